//! Single-package units (docs/model.md §4.7), against the simulator's known truth: a MEMS IMU whose
//! three accelerometers are one point (`host/units/single-package.toml`, r = (12, −7, 25) mm) run
//! on the built-in `single-package` plan through the row simulator with consumer MEMS noise, fitted
//! with one lever arm and with nine; and the paper's unit (three lever arms millimetres apart) fitted
//! with one, which the χ² test refuses.
//!
//! The figure (r's error and 1σ for both fits, over seeds):
//! `cargo test -p host --lib single_package_many_seeds -- --ignored --nocapture`.

use super::note::Note;
use super::*;
use crate::sim::testkit::{
    mems_noise, simulate_stats, single_package_fits, single_package_plan, single_package_unit,
};
use crate::sim::thermal::ThermalSim;
use crate::sim::NoiseModel;
use recording::session::Package;

/// Largest |error| / 1σ of the biases and scale factors.
fn static_z(o: &CalibrationOutcome, truth: &Calibration) -> f64 {
    let st = &o.calibration.statics;
    let u = &o.uncertainty;
    (0..3)
        .map(|i| {
            let zb = (st.zero_bias_out[i] - truth.statics.zero_bias_out[i]) / u.zero_bias_1sigma[i];
            let zk = (st.scale_out_per_g[i] - truth.statics.scale_out_per_g[i])
                / u.scale_per_g_1sigma[i];
            zb.abs().max(zk.abs())
        })
        .fold(0.0, f64::max)
}

#[test]
fn single_package_unit_gets_one_lever_arm_within_3_sigma() {
    let truth = single_package_unit();
    let r_true = truth.lever_arms.r_m[0];
    let (one, nine) = single_package_fits(&truth, 11);
    assert!(one.single_package && !nine.single_package);
    let r = one.calibration.lever_arms.r_m;
    let s = one.uncertainty.lever_arms_m_1sigma;
    for j in 0..3 {
        // The device's per-axis form: the three rows are the one point, with one 1σ.
        assert_eq!(r[1][j], r[0][j]);
        assert_eq!(r[2][j], r[0][j]);
        assert_eq!(s[1][j], s[0][j]);
        let err = r[0][j] - r_true[j];
        assert!(
            err.abs() < 3.0 * s[0][j],
            "r{j}: error {err} vs 1σ {}",
            s[0][j]
        );
        assert!(one.observability.observable[0][j]);
        // Smaller than every per-accelerometer 1σ of the nine-component fit.
        for i in 0..3 {
            let s9 = nine.uncertainty.lever_arms_m_1sigma[i][j];
            assert!(s[0][j] < s9, "r{j}: 1σ {} vs r{}{j} {s9}", s[0][j], i + 1);
        }
    }
    // The χ² test of one point against three ran, and passed.
    assert!(one.package_test.is_some_and(|t| t.dof == 6));
    // Three lever-arm parameters instead of nine: six more degrees of freedom.
    assert_eq!(one.fit.dof - nine.fit.dof, 6);
    // The static parameters as accurate as the nine-component fit's, within their 1σ.
    assert!(static_z(&one, &truth) < 3.5, "{}", static_z(&one, &truth));
    for i in 0..3 {
        let ratio = one.uncertainty.zero_bias_1sigma[i] / nine.uncertainty.zero_bias_1sigma[i];
        assert!((0.9..1.01).contains(&ratio), "bias 1σ ratio {ratio}");
    }
    // The nine-component fit of this one-point unit: its in-package differences are not
    // significant, and the warning names the fix.
    let test = nine.package_test.expect("the χ² test ran");
    assert_eq!(test.dof, 6);
    assert!(
        nine.warnings
            .iter()
            .map(ToString::to_string)
            .any(|w| w.contains("<SinglePackage>")
                && w.contains("package = \"single\"")
                && w.contains("do not differ significantly")),
        "{:#?}",
        nine.warnings
    );
    assert!(!one
        .warnings
        .iter()
        .any(|w| matches!(w, Note::LeverArmsAlike { .. })));
}

#[test]
fn separate_lever_arms_fitted_as_one_point_are_refused() {
    // The paper's unit: three lever arms millimetres apart, on the single-package plan.
    let truth = shared::params::PAPER_UNIT;
    let mut p = single_package_plan(Package::Single);
    p.output_unit = truth.statics.output_unit;
    // The paper's unit reads volts: MEMS noise without the 1 LSB step.
    let noise = NoiseModel {
        accel_quantum_out: 0.0,
        ..mems_noise()
    };
    let stats = simulate_stats(&truth, &p, &noise, &ThermalSim::default(), 5);
    let e = calibrate_session_stats(&p, &stats, &EstimateOptions::default()).unwrap_err();
    let EstimateError::SinglePackage(PackageRefusal::Contradicted {
        spread_mm,
        delta_chi2,
        limit,
        ..
    }) = &e
    else {
        panic!("{e}")
    };
    assert!(*delta_chi2 > *limit && *spread_mm > 3.0, "{e}");
    assert!(
        e.to_string().contains("calibrate without <SinglePackage>"),
        "{e}"
    );
    // Without the option the same session calibrates, and no warning suggests the option.
    p.package = Package::Separate;
    let o = calibrate_session_stats(&p, &stats, &EstimateOptions::default()).unwrap();
    assert!(!o
        .warnings
        .iter()
        .any(|w| matches!(w, Note::LeverArmsAlike { .. })));
}

#[test]
fn the_option_is_refused_with_the_paper_method_or_the_centroid() {
    let truth = single_package_unit();
    let stats = simulate_stats(
        &truth,
        &single_package_plan(Package::Single),
        &mems_noise(),
        &ThermalSim::default(),
        2,
    );
    for (options, want) in [
        (
            EstimateOptions {
                method: Method::Paper,
                ..EstimateOptions::default()
            },
            PackageRefusal::PaperMethod(Default::default()),
        ),
        (
            EstimateOptions {
                reference: ReferenceChoice::Centroid,
                ..EstimateOptions::default()
            },
            PackageRefusal::CentroidReference(Default::default()),
        ),
    ] {
        let e = calibrate_session_stats(&single_package_plan(Package::Single), &stats, &options)
            .unwrap_err();
        assert_eq!(e, EstimateError::SinglePackage(want));
    }
}

/// The figure: r's error and 1σ of both fits over 20 seeds, and how often each fit's r is within its
/// 3σ.
#[test]
#[ignore = "20 simulated sessions (minutes in a debug build): run with --ignored --nocapture"]
fn single_package_many_seeds() {
    let truth = single_package_unit();
    let r_true = truth.lever_arms.r_m[0];
    let seeds = 20;
    let (mut err1, mut err9) = ([0.0f64; 3], [[0.0f64; 3]; 3]);
    let mut mean1 = [0.0f64; 3];
    // Σ (error / own 1σ)² of the one-point fit over components and seeds.
    let mut z2 = 0.0;
    let (mut sig1, mut sig9) = ([0.0f64; 3], [[0.0f64; 3]; 3]);
    let (mut warned, mut static_worst) = (0, 0.0f64);
    for seed in 0..seeds {
        let (one, nine) = single_package_fits(&truth, 100 + seed);
        for j in 0..3 {
            err1[j] += (one.calibration.lever_arms.r_m[0][j] - r_true[j]).powi(2);
            mean1[j] += (one.calibration.lever_arms.r_m[0][j] - r_true[j]) / seeds as f64;
            z2 += ((one.calibration.lever_arms.r_m[0][j] - r_true[j])
                / one.uncertainty.lever_arms_m_1sigma[0][j])
                .powi(2);
            sig1[j] += one.uncertainty.lever_arms_m_1sigma[0][j].powi(2);
            for i in 0..3 {
                err9[i][j] += (nine.calibration.lever_arms.r_m[i][j] - r_true[j]).powi(2);
                sig9[i][j] += nine.uncertainty.lever_arms_m_1sigma[i][j].powi(2);
            }
        }
        warned += nine
            .warnings
            .iter()
            .any(|w| matches!(w, Note::LeverArmsAlike { .. })) as usize;
        static_worst = static_worst.max(static_z(&one, &truth));
    }
    let rms = |v: f64| (v / seeds as f64).sqrt() * 1e6;
    println!("single-package unit, r = (12, -7, 25) mm, {seeds} seeds, 1.4 mg noise, µm:");
    println!("  component   one-point fit: rms error | mean 1σ    nine-component fit r1 | r2 | r3: rms error (mean 1σ)");
    for j in 0..3 {
        println!(
            "  r{}          {:>8.2} | {:>8.2}        {}",
            shared::params::axis_name(j),
            rms(err1[j]),
            rms(sig1[j]),
            (0..3)
                .map(|i| format!("{:.2} ({:.2})", rms(err9[i][j]), rms(sig9[i][j])))
                .collect::<Vec<_>>()
                .join(" | ")
        );
    }
    println!(
        "  one-point fit's mean error (µm): {:.2}, {:.2}, {:.2}",
        mean1[0] * 1e6,
        mean1[1] * 1e6,
        mean1[2] * 1e6
    );
    println!("  nine-component fits warned to use the option: {warned}/{seeds}; one-point fit's worst static |error|/1σ {static_worst:.2}");
    let z2_per = z2 / (3 * seeds) as f64;
    println!(
        "  one-point fit: mean (error/1σ)² over components and seeds {z2_per:.2} (1 expected)"
    );
    // 60 terms: the mean of χ²(60)/60 is above 1.5 with probability below 0.5 %.
    assert!(z2_per < 1.5, "{z2_per}");
}
