//! The temperature fit against the simulator's known unit (docs/model.md §9): a unit with bias and
//! scale tempcos calibrated from soak steps, checked on attitudes and temperatures it never saw.

use super::{calibrate_session_stats, EstimateOptions};
use crate::sim::testkit::{
    hot_unit, nuisances, simulate_stats, soak_plan, worst_error_ug, HELD_OUT_UPS,
};
use crate::sim::thermal::ThermalSim;
use crate::sim::NoiseModel;
use crate::unit_file::UnitFile;

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
            .any(|w| w.to_string().contains("no temperature model")),
        "{:?}",
        out.warnings
    );
}

#[test]
fn slow_ramps_at_rest_calibrate_as_well_as_soak_steps() {
    let truth = hot_unit();
    let plan = recording::session::builtin::builtin_plan("thermal-ramp")
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
    let plan = recording::session::builtin::builtin_plan("thermal-ramp")
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
        !out.warnings
            .iter()
            .any(|w| w.to_string().contains("misalignment")),
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
        !out.warnings
            .iter()
            .any(|w| w.to_string().contains("misalignment")),
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
    let flagged: Vec<String> = out
        .warnings
        .iter()
        .map(ToString::to_string)
        .filter(|w| w.contains("misalignment"))
        .collect();
    println!("{flagged:?}");
    assert_eq!(flagged.len(), 1, "{:?}", out.warnings);
    assert!(
        flagged[0].contains("accelerometer x towards y"),
        "{flagged:?}"
    );
}

/// The `hand` plan's 24 free positions, position k held at `temp(k / 23)` °C, each up given as a
/// hand-held session gives it (`host segment`): the direction of its mean output, here less the
/// true bias (the scale errors and misalignment still in it, half a degree off).
fn hand_held(
    truth: &shared::Calibration,
    temp: impl Fn(f64) -> f64,
    seed: u64,
) -> (
    recording::session::Plan,
    Vec<recording::session::SegmentStats>,
) {
    let mut plan = recording::session::builtin::builtin_plan("hand")
        .unwrap()
        .unwrap();
    plan.format_version = recording::session::plan::PLAN_FORMAT_VERSION_TEMPERATURE;
    let last = (plan.segments.len() - 1) as f64;
    for (k, s) in plan.segments.iter_mut().enumerate() {
        s.temp_c = Some(temp(k as f64 / last));
    }
    let stats = simulate_stats(truth, &plan, &nuisances(), &ThermalSim::default(), seed);
    let bias = truth.statics.to_fitted().unwrap().0.zero_bias_out;
    for (s, st) in plan.segments.iter_mut().zip(&stats) {
        let d: [f64; 3] = std::array::from_fn(|i| st.mean_u[i] - bias[i]);
        s.up_b = d.map(|c| c / shared::linalg::norm(&d));
    }
    (plan, stats)
}

/// docs/model.md §9, "When the session determines it": a unit without any temperature dependence
/// held by hand through 15 → 35 → 15 °C. Each position sees one temperature, so no attitude is seen
/// over a span and no model is fitted; the fit is the one at a constant temperature, against the
/// simulator's truth.
#[test]
fn temperatures_seen_only_between_free_attitudes_give_no_model() {
    let mut truth = hot_unit();
    truth.temperature = None;
    let swing = |x: f64| 25.0 - 10.0 * (2.0 * std::f64::consts::PI * x).cos();
    let calibrate = |temp: &dyn Fn(f64) -> f64| {
        let (plan, stats) = hand_held(&truth, temp, 7);
        calibrate_session_stats(&plan, &stats, &EstimateOptions::default()).unwrap()
    };
    let (out, constant) = (calibrate(&swing), calibrate(&|_| 25.0));
    let errors = |o: &super::CalibrationOutcome| {
        let mut rng = shared::rng::Rng::new(5, 0);
        crate::sim::montecarlo::static_errors(&truth, &o.fitted, &mut rng)
    };
    let (e, e0) = (errors(&out), errors(&constant));
    println!(
        "15 → 35 → 15 °C: χ²/dof {:.2}, held-out worst {:.1} µg, rms {:.1} µg; at 25 °C: χ²/dof \
         {:.2}, worst {:.1} µg, rms {:.1} µg",
        out.fit.reduced_chi2,
        e.worst_ug,
        e.rms_ug,
        constant.fit.reduced_chi2,
        e0.worst_ug,
        e0.rms_ug
    );
    assert!(out.thermal.is_none() && out.calibration.temperature.is_none());
    let note = out
        .warnings
        .iter()
        .map(ToString::to_string)
        .find(|w| w.contains("no temperature model"))
        .unwrap_or_else(|| panic!("{:?}", out.warnings));
    assert!(
        note.contains("no known attitude is seen over 5 °C") && note.contains("24 of 24 static"),
        "{note}"
    );
    assert!(
        out.fit.reduced_chi2 < 2.0,
        "χ²/dof {}",
        out.fit.reduced_chi2
    );
    assert!(
        e.worst_ug <= 1.5 * e0.worst_ug + 20.0,
        "{} µg vs {} µg",
        e.worst_ug,
        e0.worst_ug
    );
}

/// A soak (the six positions at five temperatures) beside hand-held positions at temperatures along
/// the same range: the soak's attitudes determine the model, the free ones do not enter it, and the
/// model and held-out accuracy are the soak's own.
#[test]
fn soak_positions_determine_the_model_beside_free_ones() {
    let truth = hot_unit();
    let soak = soak_plan(&SOAK_TEMPS_C, 10.0);
    let soak_stats = simulate_stats(&truth, &soak, &nuisances(), &ThermalSim::default(), 5);
    let (lo, hi) = (SOAK_TEMPS_C[0], SOAK_TEMPS_C[4]);
    let (hand, hand_stats) = hand_held(&truth, |x| lo + (hi - lo) * x, 9);
    let mut plan = soak.clone();
    plan.segments.extend(hand.segments);
    let stats = [soak_stats.clone(), hand_stats].concat();
    let options = EstimateOptions::default();
    let both = calibrate_session_stats(&plan, &stats, &options).unwrap();
    let alone = calibrate_session_stats(&soak, &soak_stats, &options).unwrap();
    let (fit, own) = (
        both.thermal.as_ref().unwrap(),
        alone.thermal.as_ref().unwrap(),
    );
    assert_eq!(fit.steps.len(), soak.segments.len(), "{:?}", fit.notes);
    assert_eq!(
        (fit.zero_bias_degree, fit.scale_degree),
        (own.zero_bias_degree, own.scale_degree),
        "{:?}",
        fit.notes
    );
    for temp in [0.0, 45.0] {
        let with = worst_error_ug(&truth, &both.calibration, temp, &HELD_OUT_UPS);
        let soak_only = worst_error_ug(&truth, &alone.calibration, temp, &HELD_OUT_UPS);
        println!("held-out at {temp} °C: worst {with:.1} µg, the soak alone {soak_only:.1} µg");
        assert!(
            with <= 30.0_f64.max(1.5 * soak_only),
            "{temp} °C: {with} µg"
        );
    }
}

/// `d` added to output `axis` of every sample of `st`: its mean, extremes and temperature moments.
fn shift_output(st: &mut recording::session::SegmentStats, axis: usize, d: f64) {
    let ts = st.thermal.as_mut().expect("temperature moments");
    ts.sum_u2[axis] += 2.0 * d * ts.sum_u_x_pow[axis][0] + ts.count as f64 * d * d;
    for k in 0..ts.sum_u_x_pow[axis].len() {
        ts.sum_u_x_pow[axis][k] += d * ts.sum_x_pow[k];
    }
    st.mean_u[axis] += d;
    st.min_u[axis] += d;
    st.max_u[axis] += d;
}

/// docs/model.md §9, "The verdict": a misfit between soak steps reaches the main fit, which sees
/// each step's mean referred to `T_ref`, far more strongly than the temperature fit's own χ²/dof,
/// which spreads it over every sample. Planted: output x one sample-σ higher in every position at
/// 40 °C, a step no cubic through five temperatures follows.
#[test]
fn a_soak_step_off_the_model_shows_in_the_main_chi2() {
    let truth = hot_unit();
    let plan = soak_plan(&SOAK_TEMPS_C, 10.0);
    let mut stats = simulate_stats(&truth, &plan, &nuisances(), &ThermalSim::default(), 5);
    let sigma = stats[0].cov_u[0][0].sqrt();
    for st in stats.iter_mut().filter(|st| st.name.ends_with("@40")) {
        shift_output(st, 0, sigma);
    }
    let out = calibrate_session_stats(&plan, &stats, &EstimateOptions::default()).unwrap();
    let fit = out.thermal.as_ref().expect("a temperature model");
    println!(
        "a {:.3} mV step at 40 °C: main χ²/dof {:.1}, temperature fit χ²/dof {:.4?}",
        sigma * 1e3,
        out.fit.reduced_chi2,
        fit.reduced_chi2()
    );
    assert!(out.fit.reduced_chi2 > 100.0, "{}", out.fit.reduced_chi2);
    assert!(fit.worst_reduced_chi2() < 1.1, "{:?}", fit.reduced_chi2());
}
