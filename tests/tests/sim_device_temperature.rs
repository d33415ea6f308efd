//! `host calibrate --port sim --sim-unit host/units/thermal-mems.toml --plan thermal-soak`: the host
//! drives the simulated device's chamber as it drives its table, so a temperature plan calibrates the
//! temperature model against the in-process device, and a plan without rotations is verified at rest.

use device::operator::AutomaticOperator;
use device::procedure::{self, ProcedureOptions};
use device::sim::SimDevice;
use device::DeviceClient;
use estimator::unit_file::UnitFile;
use recording::session::builtin::load_plan;
use std::path::Path;
use std::time::Duration;

/// Runs a built-in plan, `seconds` per segment, against a simulated thermal unit.
fn run_plan(
    name: &str,
    seconds: f64,
) -> (
    procedure::ProcedureOutcome,
    shared::TemperatureModel,
    tempfile::TempDir,
) {
    let unit = Path::new(env!("CARGO_MANIFEST_DIR")).join("../host/units/thermal-mems.toml");
    let truth = UnitFile::load(&unit).unwrap().to_calibration().unwrap();
    let truth_t = truth.temperature.expect("the unit has a temperature model");
    let dev = SimDevice::new(truth).unwrap();
    let mut client = DeviceClient::new(dev, Duration::from_millis(500));
    let mut plan = load_plan(name).unwrap();
    for s in &mut plan.segments {
        s.duration_s = Some(seconds);
    }
    let out = tempfile::tempdir().unwrap();
    let mut opts =
        ProcedureOptions::new(plan, out.path().to_path_buf(), recording::testkit::SPELLING);
    opts.quiet = true;
    let mut op = AutomaticOperator {
        verbose: false,
        warnings: Vec::new(),
    };
    let result = procedure::run(&mut client, &opts, &mut op).unwrap();
    (result, truth_t, out)
}

/// `(segment, temp_c)` of every row of a recording.
fn recorded_temperatures(result: &procedure::ProcedureOutcome) -> Vec<(String, f64)> {
    let csv = std::fs::read_to_string(result.recording_dir.join("samples.csv")).unwrap();
    csv.lines()
        .skip(1)
        .filter_map(|l| {
            let t = l.rsplit(',').next()?.parse().ok()?;
            Some((l.split(',').next()?.to_string(), t))
        })
        .collect()
}

#[test]
fn a_soak_plan_drives_the_virtual_chamber_and_recovers_the_temperature_model() {
    // The built-in soak plan (six positions at -20, 0, 20, 40 and 60 °C), 5 s per position.
    let (result, truth_t, _out) = run_plan("thermal-soak", 5.0);

    // The recording carries the temperatures the chamber was driven to.
    let temps = recorded_temperatures(&result);
    let (lo, hi) = temps.iter().fold((f64::MAX, f64::MIN), |(a, b), (_, t)| {
        (a.min(*t), b.max(*t))
    });
    assert!(
        (lo + 20.0).abs() < 0.5 && (hi - 60.0).abs() < 0.5,
        "{lo}..{hi} °C"
    );

    // The temperature model against the unit's truth, within 5σ of the fit's own uncertainty.
    assert_slopes_within_5_sigma(&result, &truth_t, true);

    // No rotation in the plan, so no lever arm to check: verified at the three rest positions only.
    assert!(result.passed, "verification: {:#?}", result.verification);
    assert_eq!(result.verification.len(), 3);
    assert!(result.verification.iter().all(|p| p.rate_deg_s == 0.0));
}

#[test]
fn a_ramp_plan_ramps_the_virtual_chamber_during_each_segment() {
    let (result, truth_t, _out) = run_plan("thermal-ramp", 5.0);
    let plan = load_plan("thermal-ramp").unwrap();
    let temps = recorded_temperatures(&result);
    for seg in &plan.segments {
        let (t0, t1) = (seg.temp_c.unwrap(), seg.temp_end_c.unwrap());
        let seen: Vec<f64> = temps
            .iter()
            .filter(|(name, _)| *name == seg.name)
            .map(|(_, t)| *t)
            .collect();
        assert!(seen.len() > 10, "{}: {} rows", seg.name, seen.len());
        // Each window's mean reading follows the ramp: monotone, from near t0 to near t1.
        let step = (t1 - t0) / seen.len() as f64;
        assert!(
            seen.windows(2)
                .all(|w| (w[1] - w[0]) * step.signum() >= 0.0),
            "{}",
            seg.name
        );
        let (first, last) = (seen[0], seen[seen.len() - 1]);
        assert!(
            (first - t0).abs() <= step.abs() * 1.5 + 0.01,
            "{}: starts at {first}",
            seg.name
        );
        assert!(
            (last - t1).abs() <= step.abs() * 1.5 + 0.01,
            "{}: ends at {last}",
            seg.name
        );
    }
    assert_slopes_within_5_sigma(&result, &truth_t, false);
}

/// The first-order temperature coefficients of the zero biases (and of the scales with `scales`)
/// against the unit's truth, within 5σ of the fit's own uncertainty.
fn assert_slopes_within_5_sigma(
    result: &procedure::ProcedureOutcome,
    truth: &shared::TemperatureModel,
    scales: bool,
) {
    let fit = result
        .calibrated
        .outcome
        .thermal
        .as_ref()
        .expect("a temperature model");
    for i in 0..3 {
        let (est, sigma) = (
            fit.model.zero_bias_out_per_c[i][0],
            fit.zero_bias_sigma[i][0],
        );
        let want = truth.zero_bias_out_per_c[i][0];
        assert!(
            (est - want).abs() < 5.0 * sigma,
            "u0 slope {i}: {est} vs {want} ± {sigma}"
        );
        if scales {
            let (est, sigma) = (fit.model.scale_rel_per_c[i][0], fit.scale_sigma[i][0]);
            let want = truth.scale_rel_per_c[i][0];
            assert!(
                (est - want).abs() < 5.0 * sigma,
                "scale slope {i}: {est} vs {want} ± {sigma}"
            );
        }
    }
}
