//! The bias walks as the tools fit them by default (docs/model.md §11.3, §11.6): the
//! accelerometers' and the gyro's both estimated from the session, reported with their 1σ and used
//! where the session determines them; against the simulator's truth.
//!
//! `WALK_SEEDS=N cargo test -p estimator --lib walks_by_default_against_the_truth -- --ignored
//! --nocapture` runs N seeds (default 12, the documented run) of the paper's 15-minute plan on a
//! MEMS unit with both walks and prints every figure: the estimated walks against the simulated
//! ones with their 1σ, χ²/dof, and the rms of error/σ of biases, scale factors and lever arms.

use super::*;
use crate::sim::montecarlo::rms;
use crate::sim::testkit;
use crate::sim::NoiseModel;
use recording::session::SegmentStats;
use shared::OutputUnit;

/// The accelerometers' walk, mg/√s, and the gyro's, °/s/√s: ordinary figures for a consumer MEMS
/// part.
const ACCEL_WALK: f64 = 0.002;
const GYRO_WALK: f64 = 0.0005;

/// The options the tools give the estimator without a walk flag.
fn by_default() -> EstimateOptions {
    EstimateOptions::default().drift_aware()
}

/// The paper's 15-minute plan (six 60 s rests, nine 60 s spins) for the MEMS unit of
/// `host/units/single-package.toml`, in LSB.
fn paper_plan() -> Plan {
    testkit::paper_plan(OutputUnit::Lsb)
}

/// `plan` simulated row by row with the walks given: consumer MEMS noise for a unit in LSB, else
/// 1 mg and 0.05 °/s of white noise.
fn simulate(plan: &Plan, truth: &Calibration, walks: [f64; 2], seed: u64) -> Vec<SegmentStats> {
    let base = if plan.output_unit == OutputUnit::Lsb {
        testkit::mems_noise()
    } else {
        NoiseModel {
            accel_white_mg: 1.0,
            gyro_white_deg_s: 0.05,
            ..NoiseModel::none()
        }
    };
    let noise = NoiseModel {
        accel_bias_walk_mg_sqrt_s: walks[0],
        gyro_bias_walk_deg_s_sqrt_s: walks[1],
        ..base
    };
    crate::sim::stats::simulate_stats(truth, plan, &noise, seed).unwrap()
}

/// The largest difference between two fits' parameter tables, relative to each value's 1σ (a
/// value without a 1σ, relative to itself).
fn largest_difference(a: &CalibrationOutcome, b: &CalibrationOutcome) -> f64 {
    assert_eq!(a.parameters.len(), b.parameters.len());
    a.parameters
        .iter()
        .zip(&b.parameters)
        .map(|((na, va, sa), (nb, vb, sb))| {
            assert_eq!(na, nb);
            let scale = if *sa > 0.0 { *sa } else { va.abs().max(1e-300) };
            ((va - vb).abs() / scale).max((sa - sb).abs() / scale)
        })
        .fold(0.0, f64::max)
}

/// Error/σ of the biases, scale factors and observable lever arms against the truth.
fn z_scores(truth: &Calibration, out: &CalibrationOutcome) -> [Vec<f64>; 3] {
    let (c, u) = (&out.calibration, &out.uncertainty);
    let mut z: [Vec<f64>; 3] = Default::default();
    for i in 0..3 {
        z[0].push(
            (c.statics.zero_bias_out[i] - truth.statics.zero_bias_out[i]) / u.zero_bias_1sigma[i],
        );
        z[1].push(
            (c.statics.scale_out_per_g[i] - truth.statics.scale_out_per_g[i])
                / u.scale_per_g_1sigma[i],
        );
        for j in 0..3 {
            if u.lever_arms_observable[i][j] {
                let e = c.lever_arms.r_m[i][j] - truth.lever_arms.r_m[i][j];
                z[2].push(e / u.lever_arms_m_1sigma[i][j]);
            }
        }
    }
    z
}

/// A session without a walk determines none, and the default fit is the constant-bias fit to the
/// last digit (every parameter and 1σ within 10⁻⁹ of its 1σ): the paper's plan on the MEMS unit
/// (both walks estimated, the gyro's from the spins) and the 16-mount static plan on the paper's
/// unit (the accelerometers' alone). Both estimates are still reported, with their 1σ.
#[test]
fn without_drift_the_default_is_the_constant_bias_fit() {
    let mems = testkit::single_package_unit();
    let paper = testkit::paper_unit();
    let many = testkit::declared(&testkit::many_mounts_plan(), 0.0, 1.0);
    let cases: [(&Plan, &Calibration, u64); 3] = [
        (&paper_plan(), &mems, 1),
        (&paper_plan(), &mems, 2),
        (&many, &paper, 3),
    ];
    for (plan, truth, seed) in cases {
        let stats = simulate(plan, truth, [0.0, 0.0], seed);
        let constant = calibrate_session_stats(plan, &stats, &EstimateOptions::default()).unwrap();
        let default = calibrate_session_stats(plan, &stats, &by_default()).unwrap();
        let accel = default.bias_walk.expect("estimated");
        println!(
            "seed {seed}: accelerometer walk {:.5} ± {:.5} mg/√s ({:.2}σ), gyro {:?}",
            accel.mg_sqrt_s,
            accel.sigma_mg_sqrt_s.unwrap(),
            accel.significance.unwrap(),
            default.gyro_walk
        );
        assert!(!accel.used && accel.sigma_mg_sqrt_s.is_some(), "{accel:?}");
        if plan.segments.len() == 15 {
            let gyro = default.gyro_walk.expect("the spins estimate a gyro model");
            assert!(!gyro.used, "{gyro:?}");
        }
        let d = largest_difference(&constant, &default);
        assert!(d <= 1e-9, "seed {seed}: {d}");
        assert_eq!(constant.calibration, default.calibration);
        assert!(default.bias_track.is_empty());
    }
}

/// The paper's plan on the MEMS unit with both walks passes by default: both walks are determined
/// and used, χ²/dof is near 1 (where the constant-bias fit is far above), and each estimated walk
/// is within 4σ of the simulated one. Two seeds here; [`walks_by_default_against_the_truth`] runs
/// the documented twelve.
#[test]
fn the_paper_plan_with_both_walks_passes_by_default() {
    let truth = testkit::single_package_unit();
    let plan = paper_plan();
    for seed in 0..2 {
        let stats = simulate(&plan, &truth, [ACCEL_WALK, GYRO_WALK], 40 + seed);
        let constant = calibrate_session_stats(&plan, &stats, &EstimateOptions::default());
        let out = calibrate_session_stats(&plan, &stats, &by_default()).unwrap();
        let (a, g) = (out.bias_walk.unwrap(), out.gyro_walk.unwrap());
        println!(
            "seed {seed}: χ²/dof {:.2} (constant bias: {:?}); accelerometer walk {:.5} ± {:.5} \
             mg/√s (simulated {ACCEL_WALK}); gyro walk {:.6} ± {:.6} °/s/√s (simulated {GYRO_WALK})",
            out.fit.reduced_chi2,
            constant.as_ref().map(|c| c.fit.reduced_chi2),
            a.mg_sqrt_s,
            a.sigma_mg_sqrt_s.unwrap(),
            g.deg_s_sqrt_s,
            g.sigma_deg_s_sqrt_s
        );
        assert!(g.used, "{g:?}");
        assert!(out.fit.reduced_chi2 < 2.0, "{:?}", out.fit);
        assert!((g.deg_s_sqrt_s - GYRO_WALK).abs() < 4.0 * g.sigma_deg_s_sqrt_s);
        assert!((a.mg_sqrt_s - ACCEL_WALK).abs() < 4.0 * a.sigma_mg_sqrt_s.unwrap());
        assert_eq!(out.gyro_bias_walk_deg_s_sqrt_s, Some(g.fit_deg_s_sqrt_s));
    }
}

fn seeds() -> u64 {
    std::env::var("WALK_SEEDS")
        .ok()
        .and_then(|s| s.parse().ok())
        .unwrap_or(12)
}

/// Over the seeds (12 by default): the paper's plan on the MEMS unit with both walks passes by
/// default with honest 1σ (rms error/σ of the biases, scale factors and lever arms each within
/// 30 % of 1), and the estimated walks against the simulated ones, with their 1σ (rms of
/// (estimated − simulated)/σ within 30 % of 1 for the gyro's, which the spins determine well).
#[test]
#[ignore]
fn walks_by_default_against_the_truth() {
    let truth = testkit::single_package_unit();
    let plan = paper_plan();
    let mut z: [Vec<f64>; 3] = Default::default();
    let (mut za, mut zg) = (Vec::new(), Vec::new());
    for seed in 0..seeds() {
        let stats = simulate(&plan, &truth, [ACCEL_WALK, GYRO_WALK], 1000 + seed);
        let out = calibrate_session_stats(&plan, &stats, &by_default()).unwrap();
        let (a, g) = (out.bias_walk.unwrap(), out.gyro_walk.unwrap());
        let s = a.sigma_mg_sqrt_s.unwrap();
        println!(
            "seed {seed}: χ²/dof {:.2}; accelerometer walk {:.5} ± {s:.5} mg/√s ({:.1}σ, used \
             {}); gyro walk {:.6} ± {:.6} °/s/√s ({:.1}σ, used {})",
            out.fit.reduced_chi2,
            a.mg_sqrt_s,
            a.significance.unwrap(),
            a.used,
            g.deg_s_sqrt_s,
            g.sigma_deg_s_sqrt_s,
            g.significance,
            g.used
        );
        assert!(out.fit.reduced_chi2 < 2.0, "seed {seed}: {:?}", out.fit);
        za.push((a.mg_sqrt_s - ACCEL_WALK) / s);
        zg.push((g.deg_s_sqrt_s - GYRO_WALK) / g.sigma_deg_s_sqrt_s);
        for (all, one) in z.iter_mut().zip(z_scores(&truth, &out)) {
            all.extend(one);
        }
    }
    let (ra, rg) = (rms(za.into_iter()), rms(zg.into_iter()));
    println!(
        "estimated − simulated walk over its 1σ, rms: accelerometers {ra:.2}, gyro {rg:.2} \
         (simulated {ACCEL_WALK} mg/√s, {GYRO_WALK} °/s/√s)"
    );
    assert!((rg - 1.0).abs() < 0.3, "gyro walk: {rg}");
    for (what, v) in ["biases", "scale factors", "lever arms"].iter().zip(z) {
        let r = rms(v.into_iter());
        println!("rms error/σ of the {what}: {r:.2}");
        assert!((r - 1.0).abs() < 0.3, "{what}: {r}");
    }
}
