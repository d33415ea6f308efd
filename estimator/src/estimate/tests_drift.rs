//! The fit under an accelerometer bias random walk (docs/model.md §11), against the simulator's
//! truth and against an oracle: the generalised least squares given the true attitudes and the true
//! walk.
//!
//! `DRIFT_SEEDS=N cargo test -p estimator --lib drift_against_the_oracle -- --nocapture` runs N seeds
//! per walk strength (default 2) and prints every figure; `DRIFT_SEEDS=12` is the documented run.

use super::*;
use crate::session::{SegmentAccumulator, SegmentStats};
use crate::sim::montecarlo::{rms, static_errors};
use crate::sim::testkit::{self, Rng};
use crate::sim::{simulate_rows, NoiseModel};
use std::collections::BTreeMap;

/// The paper's unit on the 16-mount plan (27 segments of 30 s, 810 s) with a 0.05° fixture declared
/// as such.
fn plan() -> Plan {
    testkit::declared(&testkit::many_mounts_plan(), 0.05, 1.0)
}

/// A simulated session's statistics and the true up of every mount.
struct Session {
    stats: Vec<SegmentStats>,
    ups: BTreeMap<String, [f64; 3]>,
}

/// `plan` simulated row by row with 1 mg white noise, a 0.05° fixture and a bias walk of
/// `walk_mg` mg/√s.
fn simulate(plan: &Plan, truth: &Calibration, walk_mg: f64, seed: u64) -> Session {
    let noise = NoiseModel {
        accel_white_mg: 1.0,
        gyro_white_deg_s: 0.05,
        table_tilt_deg: 0.05,
        accel_bias_walk_mg_sqrt_s: walk_mg,
        ..NoiseModel::none()
    };
    let mut accs: Vec<SegmentAccumulator> = plan
        .segments
        .iter()
        .map(|s| SegmentAccumulator::new(s.name.clone()))
        .collect();
    let mut current = 0;
    let summary = simulate_rows(truth, plan, &noise, seed, |seg, t, u, w| {
        if plan.segments[current].name != seg {
            current += 1;
        }
        accs[current].push(t, u, w);
        Ok::<(), ()>(())
    })
    .unwrap()
    .unwrap();
    Session {
        stats: accs.iter().filter_map(SegmentAccumulator::finish).collect(),
        ups: summary.mount_up_b,
    }
}

/// `plan` with every mount at its true up, exactly (the oracle's attitudes).
fn true_attitudes(plan: &Plan, ups: &BTreeMap<String, [f64; 3]>) -> Plan {
    let mut p = plan.clone();
    p.attitude_sigma_deg = Some(0.0);
    for s in &mut p.segments {
        let name = s.mount_name();
        s.up_b = ups[&name];
        s.mount = Some(name);
    }
    p
}

fn fit(plan: &Plan, stats: &[SegmentStats], walk: BiasWalk) -> CalibrationOutcome {
    let options = EstimateOptions {
        bias_walk: walk,
        ..EstimateOptions::default()
    };
    calibrate_session_stats(plan, stats, &options).unwrap()
}

/// One fit's figures against the truth.
#[derive(Clone, Copy, Debug, Default)]
struct Figures {
    /// Worst static error on held-out attitudes after the best common rotation, µg.
    static_ug: f64,
    /// RMS lever-arm error, µm.
    lever_um: f64,
    /// Σ (error/σ)² and the count, for biases, scale factors, lever arms.
    z2: [(f64, usize); 3],
}

fn figures(truth: &Calibration, out: &CalibrationOutcome, seed: u64) -> Figures {
    let st = static_errors(truth, &out.fitted, &mut Rng::new(77 + seed, 0));
    let (c, u) = (&out.calibration, &out.uncertainty);
    let mut z2 = [(0.0, 0); 3];
    let mut lever = Vec::new();
    for i in 0..3 {
        let zb = (c.statics.zero_bias_out[i] - truth.statics.zero_bias_out[i])
            / u.zero_bias_1sigma[i];
        let zk = (c.statics.scale_out_per_g[i] - truth.statics.scale_out_per_g[i])
            / u.scale_per_g_1sigma[i];
        z2[0] = (z2[0].0 + zb * zb, z2[0].1 + 1);
        z2[1] = (z2[1].0 + zk * zk, z2[1].1 + 1);
        for j in 0..3 {
            let e = c.lever_arms.r_m[i][j] - truth.lever_arms.r_m[i][j];
            lever.push(e * 1e6);
            if u.lever_arms_observable[i][j] {
                let z = e / u.lever_arms_m_1sigma[i][j];
                z2[2] = (z2[2].0 + z * z, z2[2].1 + 1);
            }
        }
    }
    Figures {
        static_ug: st.worst_ug,
        lever_um: rms(lever.into_iter()),
        z2,
    }
}

fn seeds() -> u64 {
    std::env::var("DRIFT_SEEDS")
        .ok()
        .and_then(|s| s.parse().ok())
        .unwrap_or(2)
}

#[test]
fn drift_against_the_oracle() {
    let truth = testkit::paper_unit();
    let plan = plan();
    let n = seeds();
    for walk in [0.0, 0.001, 0.002, 0.005] {
        let mut rows: Vec<[Figures; 4]> = Vec::new();
        let mut estimated = Vec::new();
        for seed in 0..n {
            let s = simulate(&plan, &truth, walk, 500 + seed);
            let today = fit(&plan, &s.stats, BiasWalk::Off);
            let given = fit(&plan, &s.stats, BiasWalk::Given(walk));
            let est = fit(&plan, &s.stats, BiasWalk::Estimate);
            let oracle = fit(&true_attitudes(&plan, &s.ups), &s.stats, BiasWalk::Given(walk));
            estimated.push(est.bias_walk.unwrap());
            rows.push([today, given, est, oracle].map(|o| figures(&truth, &o, seed)));
        }
        println!("walk {walk} mg/√s, {n} seeds: static µg (worst, rotation removed) | lever µm rms | rms z bias, scale, lever");
        for (k, name) in ["today", "given", "estimated", "oracle"].iter().enumerate() {
            let st = rms(rows.iter().map(|r| r[k].static_ug));
            let lv = rms(rows.iter().map(|r| r[k].lever_um));
            let z: Vec<f64> = (0..3)
                .map(|c| {
                    let (s, m) = rows.iter().fold((0.0, 0), |a, r| {
                        (a.0 + r[k].z2[c].0, a.1 + r[k].z2[c].1)
                    });
                    (s / m.max(1) as f64).sqrt()
                })
                .collect();
            println!("  {name:10} {st:7.1} {lv:7.1}   {:.2} {:.2} {:.2}", z[0], z[1], z[2]);
        }
        for e in &estimated {
            println!(
                "  estimated walk {:.5} ± {:.5} mg/√s (simulated {walk})",
                e.mg_sqrt_s,
                e.sigma_mg_sqrt_s.unwrap_or(f64::NAN)
            );
        }
    }
}
