//! The temperature fit against the simulator's known unit (docs/model.md §9): a unit with bias and
//! scale tempcos calibrated from soak steps, checked on attitudes and temperatures it never saw.

use super::{calibrate_session_stats, EstimateOptions};
use crate::session::{Plan, SegmentAccumulator, SegmentPlan, SegmentStats};
use crate::sim::thermal::{outputs_at, ThermalSim};
use crate::sim::{simulate_rows_with_temperature, NoiseModel};
use crate::unit_file::UnitFile;
use shared::forward::{ForwardModel, TableState};
use shared::sensor_models::poly_no_constant;
use shared::OutputUnit;
use shared::{Calibration, Compensator, LeverMode, SensorOutputs};

/// `host/units/thermal-mems.toml`: the paper's unit with tempcos of MEMS size (bias 0.25..0.35
/// mg/°C plus a quadratic term, scale 100..150 ppm/°C).
pub(crate) fn hot_unit_file() -> UnitFile {
    toml::from_str(include_str!("../../units/thermal-mems.toml")).unwrap()
}

/// [`hot_unit_file`] as a calibration.
pub(crate) fn hot_unit() -> Calibration {
    hot_unit_file().to_calibration().unwrap()
}

/// Six positions (±1 g per axis) at each chamber set-point, `seconds` each.
pub(crate) fn soak_plan(temps_c: &[f64], seconds: f64) -> Plan {
    let mut segments = Vec::new();
    for &t in temps_c {
        for (a, n) in ["x", "y", "z"].iter().enumerate() {
            for (sgn, s) in [(1.0, "+"), (-1.0, "-")] {
                let mut up_b = [0.0; 3];
                up_b[a] = sgn;
                segments.push(SegmentPlan {
                    name: format!("{n}{s} @{t}"),
                    up_b,
                    rate_deg_s: 0.0,
                    rate_end_deg_s: None,
                    duration_s: Some(seconds),
                    table_centre_m: None,
                    mount: Some(format!("{n}{s}")),
                    temp_c: Some(t),
                    temp_end_c: None,
                    ..Default::default()
                });
            }
        }
    }
    Plan {
        attitude_sigma_deg: None,
        table_rate_sigma_ppm: None,
        format_version: crate::session::plan::PLAN_FORMAT_VERSION_TEMPERATURE,
        output_unit: OutputUnit::Volts,
        sample_rate_hz: 1000.0,
        gravity_m_s2: shared::STANDARD_GRAVITY_M_S2,
        unit_id: None,
        package: Default::default(),
        segments,
    }
}

/// Simulates straight into per-segment statistics (what the reader would make of the CSV).
pub fn simulate_stats(
    cal: &Calibration,
    plan: &Plan,
    noise: &NoiseModel,
    thermal: &ThermalSim,
    seed: u64,
) -> Vec<SegmentStats> {
    let mut accs: Vec<SegmentAccumulator> = plan
        .segments
        .iter()
        .map(|s| SegmentAccumulator::new(s.name.clone()))
        .collect();
    let mut current = 0;
    simulate_rows_with_temperature(cal, plan, noise, thermal, seed, |seg, t, u, w, temp| {
        if plan.segments[current].name != seg {
            current = plan.segments.iter().position(|s| s.name == seg).unwrap();
        }
        accs[current].push_with_temperature(t, u, w, temp);
        Ok::<(), ()>(())
    })
    .unwrap()
    .unwrap();
    accs.iter().filter_map(SegmentAccumulator::finish).collect()
}

/// The realistic nuisances: 1 mg white noise, a 16-bit ADC's step on 5 V, a slow bias random walk,
/// a quantised and noisy temperature sensor.
pub(crate) fn nuisances() -> NoiseModel {
    NoiseModel {
        accel_quantum_out: 5.0 / 65536.0,
        accel_bias_walk_mg_sqrt_s: 2e-4,
        ..NoiseModel::default()
    }
}

/// Worst error, µg, of `cal` compensating the truth's noise-free outputs at `temp_c` over `ups`.
pub(crate) fn worst_error_ug(
    truth: &Calibration,
    cal: &Calibration,
    temp_c: f64,
    ups: &[[f64; 3]],
) -> f64 {
    let model = ForwardModel::new(truth).unwrap();
    let mut comp = Compensator::new(cal, LeverMode::Off).unwrap();
    comp.refresh(temp_c as f32);
    let g = truth.gravity_m_s2;
    ups.iter()
        .map(|up| {
            let n = shared::linalg::norm(up);
            let up = up.map(|v| v / n);
            let motion = TableState {
                up_b: up,
                rate_rad_s: 0.0,
                accel_rad_s2: 0.0,
                centre_m: [0.0; 3],
            }
            .motion(g);
            let mut u = model.outputs(&motion).raw;
            if let Some(th) = &truth.temperature {
                u = outputs_at(th, &model.zero_bias_out, &u, temp_c);
            }
            let f = comp.compensate_static(&SensorOutputs {
                raw: u.map(|v| v as f32),
            });
            let e: Vec<f64> = (0..3).map(|j| f.m_s2[j] as f64 / g - up[j]).collect();
            (e[0] * e[0] + e[1] * e[1] + e[2] * e[2]).sqrt() * 1e6
        })
        .fold(0.0, f64::max)
}

pub(crate) const HELD_OUT_UPS: [[f64; 3]; 4] = [
    [1.0, 1.0, 1.0],
    [-1.0, 0.5, -0.3],
    [0.2, -0.9, 0.4],
    [0.6, 0.1, -0.8],
];

#[test]
fn soak_steps_calibrate_bias_and_scale_over_temperature() {
    let truth = hot_unit();
    let plan = soak_plan(&[-20.0, 5.0, 25.0, 40.0, 60.0], 10.0);
    let stats = simulate_stats(&truth, &plan, &nuisances(), &ThermalSim::default(), 7);
    let out = calibrate_session_stats(&plan, &stats, &EstimateOptions::default()).unwrap();
    let fit = out.thermal.as_ref().expect("a temperature model");
    let th = truth.temperature.unwrap();
    // The data chose the true degrees: quadratic bias, linear scale.
    assert_eq!(fit.zero_bias_degree, [2; 3], "{:?}", fit.notes);
    assert_eq!(fit.scale_degree, [1; 3], "{:?}", fit.notes);
    // Every fitted coefficient within 4σ of the truth, and its 1σ small against it.
    for i in 0..3 {
        for k in 0..2 {
            let (est, sd) = (
                fit.model.zero_bias_out_per_c[i][k],
                fit.zero_bias_sigma[i][k],
            );
            let t = th.zero_bias_out_per_c[i][k];
            assert!(
                (est - t).abs() < 4.0 * sd,
                "P[{i}][{k}] {est} ± {sd} vs {t}"
            );
            assert!(sd < 0.05 * t.abs(), "P[{i}][{k}] 1σ {sd} vs {t}");
        }
        let (est, sd) = (fit.model.scale_rel_per_c[i][0], fit.scale_sigma[i][0]);
        let t = th.scale_rel_per_c[i][0];
        assert!((est - t).abs() < 4.0 * sd, "S[{i}] {est} ± {sd} vs {t}");
    }
    assert_eq!(fit.model.reference_c, 25.0);
    let [lo, hi] = fit.model.valid_range_c;
    assert!(
        (lo + 20.0).abs() < 0.2 && (hi - 60.0).abs() < 0.2,
        "{lo} {hi}"
    );

    // Held-out attitudes at held-out temperatures: the intrinsic error with and without the model.
    let mut without = out.calibration;
    without.temperature = None;
    for temp in [0.0, 45.0] {
        let with = worst_error_ug(&truth, &out.calibration, temp, &HELD_OUT_UPS);
        let plain = worst_error_ug(&truth, &without, temp, &HELD_OUT_UPS);
        println!(
            "held-out at {temp} °C: worst error {with:.1} µg with the model, {plain:.0} µg without"
        );
        assert!(with <= 30.0, "{temp} °C: {with} µg");
        assert!(plain > 3000.0, "{temp} °C: {plain} µg without the model");
    }
    // The fitted curves' 1σ bands hold the truth, and the figure draws them.
    for i in 0..3 {
        for temp in [0.0, 45.0] {
            let dt = temp - th.reference_c;
            for (c, cov, truth) in [
                (
                    &fit.model.zero_bias_out_per_c[i],
                    &fit.zero_bias_cov[i],
                    poly_no_constant(&th.zero_bias_out_per_c[i], dt),
                ),
                (
                    &fit.model.scale_rel_per_c[i],
                    &fit.scale_cov[i],
                    poly_no_constant(&th.scale_rel_per_c[i], dt),
                ),
            ] {
                let (y, sd) = fit.curve(c, cov, temp);
                assert!(
                    sd > 0.0 && (y - truth).abs() < 4.0 * sd,
                    "{i} {temp}: {y} ± {sd} vs {truth}"
                );
            }
        }
    }
    let soaks = crate::report::thermal::soak_points(&out, &plan, &stats);
    let fig = crate::report::thermal::figure(&out, Some(&soaks)).unwrap();
    assert_eq!(fig.panels.len(), 9);
    assert_eq!(fig.panels[6].series[0].points.len(), plan.segments.len());
    // Each soak's measured bias lies on the true curve within its own noise and the misalignment's
    // share (independent truth: the simulated unit's tempco).
    for i in 0..3 {
        assert!(!soaks.bias_mg[i].is_empty(), "axis {i}: no soak pair");
        for &(t, mg, sigma) in &soaks.bias_mg[i] {
            let truth = poly_no_constant(&th.zero_bias_out_per_c[i], t - fit.model.reference_c)
                / out.calibration.statics.scale_out_per_g[i]
                * 1e3;
            assert!(
                (mg - truth).abs() < 5.0 * sigma + 0.02,
                "axis {i} {t} °C: {mg} vs {truth} mg"
            );
        }
    }
    let dir = tempfile::tempdir().unwrap();
    let formats = crate::report::plot::Formats {
        png: false,
        svg: true,
    };
    let drawn = crate::report::plot::render(&fig, dir.path(), formats).unwrap();
    assert!(dir.path().join("temperature.svg").exists(), "{drawn:?}");

    // Outside the range: clamped and flagged.
    let mut comp = Compensator::new(&out.calibration, LeverMode::Off).unwrap();
    assert!(comp.refresh(70.0).is_flagged());
    assert!(!comp.refresh(45.0).is_flagged());
}

#[test]
fn a_session_at_one_temperature_gets_no_model() {
    let truth = hot_unit();
    let plan = soak_plan(&[25.0], 2.0);
    let stats = simulate_stats(&truth, &plan, &nuisances(), &ThermalSim::default(), 3);
    let out = calibrate_session_stats(&plan, &stats, &EstimateOptions::default()).unwrap();
    assert!(out.thermal.is_none() && out.calibration.temperature.is_none());
    assert!(
        out.warnings
            .iter()
            .any(|w| w.contains("no temperature model")),
        "{:?}",
        out.warnings
    );
}

#[test]
fn slow_ramps_at_rest_calibrate_as_well_as_soak_steps() {
    let truth = hot_unit();
    let plan = crate::session::builtin::builtin_plan("thermal-ramp")
        .unwrap()
        .unwrap();
    let stats = simulate_stats(&truth, &plan, &nuisances(), &ThermalSim::default(), 11);
    let out = calibrate_session_stats(&plan, &stats, &EstimateOptions::default()).unwrap();
    let fit = out.thermal.as_ref().expect("a temperature model");
    assert_eq!(fit.scale_degree, [1; 3], "{:?}", fit.notes);
    for temp in [0.0, 45.0] {
        let with = worst_error_ug(&truth, &out.calibration, temp, &HELD_OUT_UPS);
        println!("ramps, held-out at {temp} °C: worst error {with:.1} µg");
        assert!(with <= 30.0, "{temp} °C: {with} µg");
    }
}

#[test]
fn a_sensor_lagging_the_die_shows_in_the_ramp_residuals() {
    // Up and down sweeps with a sensor 5 s behind the die: the same reading means different die
    // temperatures on the way up and down, which the χ² sees (the soak steps do not suffer this).
    let truth = hot_unit();
    let plan = crate::session::builtin::builtin_plan("thermal-ramp")
        .unwrap()
        .unwrap();
    let lagging = ThermalSim {
        sensor_lag_s: 5.0,
        ..ThermalSim::default()
    };
    let chi2 = |sim: &ThermalSim| {
        let stats = simulate_stats(&truth, &plan, &nuisances(), sim, 11);
        let out = calibrate_session_stats(&plan, &stats, &EstimateOptions::default()).unwrap();
        let fit = out.thermal.unwrap();
        fit.chi2.map(|(c, dof)| c / dof as f64)
    };
    // χ²/dof of 360 000 rows has a spread of √(2/dof) ≈ 0.0024: settled data sit within 8 of those
    // of 1, the lag lifts it by far more than that.
    let settled = chi2(&ThermalSim::default());
    let lagged = chi2(&lagging);
    println!("χ²/dof of the ramp fit: settled {settled:.4?}, sensor lagging by 5 s {lagged:.4?}");
    for i in 0..3 {
        assert!((settled[i] - 1.0).abs() < 0.02, "{settled:?}");
        assert!(lagged[i] > 1.05, "{lagged:?}");
    }
}

/// The nuisances with a gyro: a constant bias per axis and a slow bias random walk.
fn gyro_nuisances() -> NoiseModel {
    NoiseModel {
        gyro_bias_deg_s: [0.1, -0.2, 0.3],
        gyro_bias_walk_deg_s_sqrt_s: 2e-5,
        ..nuisances()
    }
}

const SOAK_TEMPS_C: [f64; 5] = [-20.0, 5.0, 25.0, 40.0, 60.0];

#[test]
fn soak_steps_calibrate_the_gyro_bias_over_temperature() {
    let mut truth = hot_unit();
    let typical = firmware::paper_unit::typical_thermal_model();
    let true_gyro = typical.gyro_bias_rad_s_per_c.unwrap();
    truth.temperature.as_mut().unwrap().gyro_bias_rad_s_per_c = Some(true_gyro);
    let plan = soak_plan(&SOAK_TEMPS_C, 10.0);
    let stats = simulate_stats(&truth, &plan, &gyro_nuisances(), &ThermalSim::default(), 5);
    let out = calibrate_session_stats(&plan, &stats, &EstimateOptions::default()).unwrap();
    let fit = out.thermal.as_ref().expect("a temperature model");
    assert_eq!(fit.gyro_bias_degree, Some([1; 3]), "{:?}", fit.notes);
    let model = out.calibration.temperature.unwrap();
    let got = model.gyro_bias_rad_s_per_c.expect("a gyro bias model");
    for i in 0..3 {
        let (est, sd, t) = (got[i][0], fit.gyro_bias_sigma[i][0], true_gyro[i][0]);
        println!(
            "gyro {i}: bias tempco {:.6e} ± {:.1e} °/s/°C, truth {:.6e}",
            est.to_degrees(),
            sd.to_degrees(),
            t.to_degrees()
        );
        assert!(
            sd > 0.0 && (est - t).abs() < 3.0 * sd,
            "{est} ± {sd} vs {t}"
        );
        assert!(sd < 0.05 * t.abs(), "1σ {sd} vs {t}");
    }
    // The calibration file carries the polynomial, its degrees and 1σ, and reads back.
    let dir = tempfile::tempdir().unwrap();
    crate::calibration_files::write_calibration_files(
        dir.path(),
        &out,
        Default::default(),
        0,
        false,
    )
    .unwrap();
    let back =
        UnitFile::load(&dir.path().join(crate::calibration_files::CALIBRATION_TOML)).unwrap();
    let section = back.temperature.expect("a [temperature] section");
    assert_eq!(section.gyro_bias_rad_s_per_c, Some(got));
    assert_eq!(section.gyro_bias_degree, Some([1; 3]));
    assert_eq!(
        section.gyro_bias_rad_s_per_c_1sigma,
        Some(fit.gyro_bias_sigma)
    );
    // Referred to T_ref, every soak's mean rate is the constant bias (the bias walk, ~4e-4 °/s
    // over the session, and 5e-4 °/s of noise per mean aside); unreferred they span 0.8 °/s.
    let bias = gyro_nuisances().gyro_bias_deg_s;
    let referred = fit.refer_to_reference(&stats);
    for (raw, st) in stats.iter().zip(&referred) {
        for i in 0..3 {
            let (r, w) = (
                raw.mean_w_rad_s[i].to_degrees(),
                st.mean_w_rad_s[i].to_degrees(),
            );
            assert!(
                (w - bias[i]).abs() < 5e-3,
                "{}: {w} vs {}",
                st.name,
                bias[i]
            );
            if st.name.contains("@60") {
                assert!((r - bias[i]).abs() > 0.15, "{}: {r}", st.name);
            }
        }
    }
    assert!(
        !out.warnings.iter().any(|w| w.contains("misalignment")),
        "{:?}",
        out.warnings
    );
}

#[test]
fn a_gyro_without_tempco_gets_no_gyro_bias_model() {
    let truth = hot_unit();
    assert!(truth.temperature.unwrap().gyro_bias_rad_s_per_c.is_none());
    let plan = soak_plan(&SOAK_TEMPS_C, 10.0);
    // Without the bias walk: a walk that drifts along the monotone soak sequence is
    // indistinguishable from a tempco in these data (with 2e-5 °/s/√s the x gyro was given degree
    // 1); interleaving the soak temperatures is what separates the two.
    let noise = NoiseModel {
        gyro_bias_walk_deg_s_sqrt_s: 0.0,
        ..gyro_nuisances()
    };
    let stats = simulate_stats(&truth, &plan, &noise, &ThermalSim::default(), 9);
    let out = calibrate_session_stats(&plan, &stats, &EstimateOptions::default()).unwrap();
    let fit = out.thermal.as_ref().expect("a temperature model");
    assert_eq!(fit.gyro_bias_degree, Some([0; 3]), "{:?}", fit.notes);
    assert!(out
        .calibration
        .temperature
        .unwrap()
        .gyro_bias_rad_s_per_c
        .is_none());
    // A constant misalignment raises no warning.
    assert!(
        !out.warnings.iter().any(|w| w.contains("misalignment")),
        "{:?}",
        out.warnings
    );
}

#[test]
fn a_misalignment_drifting_with_temperature_is_flagged() {
    // Each soak temperature simulated with its own truth: axis x tilts towards y by 5 µrad/°C.
    let drift_rad_per_c = 5e-6;
    let base = hot_unit();
    let mut stats = Vec::new();
    let mut plan = soak_plan(&SOAK_TEMPS_C, 10.0);
    plan.segments.clear();
    for (k, &t) in SOAK_TEMPS_C.iter().enumerate() {
        let mut truth = base;
        truth.statics.installation_angles_deg[0][1] -= (drift_rad_per_c * (t - 25.0)).to_degrees();
        let part = soak_plan(&[t], 10.0);
        stats.extend(simulate_stats(
            &truth,
            &part,
            &nuisances(),
            &ThermalSim::default(),
            20 + k as u64,
        ));
        plan.segments.extend(part.segments);
    }
    let out = calibrate_session_stats(&plan, &stats, &EstimateOptions::default()).unwrap();
    let flagged: Vec<&String> = out
        .warnings
        .iter()
        .filter(|w| w.contains("misalignment"))
        .collect();
    println!("{flagged:?}");
    assert_eq!(flagged.len(), 1, "{:?}", out.warnings);
    assert!(
        flagged[0].contains("accelerometer x towards y"),
        "{flagged:?}"
    );
}
