//! The estimator's time on the paper's session (the built-in `paper` plan: 15 segments of 60 s at
//! 1 kHz, 900 000 rows) with an accelerometer bias random walk of 0.002 mg/√s and a gyro bias walk
//! of 3·10⁻⁴ °/s/√s: the constant-bias fit, the accelerometers' walk given, estimated, given with
//! the gyro's, and both estimated as the tools do by default (the gyro's one strength, then per
//! axis; docs/model.md §11, §11.6).
//!
//! `cargo run --release -p estimator --example fit_time`
//!
//! The estimator works on the segments' statistics, not on rows, so the rows are simulated once
//! straight into statistics (not timed) and each fit is timed on its own, median of several runs.
//! Reading the rows (`host calibrate`'s other part) is timed by `cargo bench -p host --bench
//! calibrate_rows`.

use estimator::estimate::{calibrate_session_stats, BiasWalk, EstimateOptions};
use estimator::sim::{simulate_stats, NoiseModel};
use recording::session::builtin::paper_plan;
use std::time::Instant;

const RUNS: usize = 7;
/// The simulated (and, in the last case, given) gyro bias walk, °/s/√s.
const GYRO_WALK_DEG_S_SQRT_S: f64 = 3e-4;

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let plan = paper_plan();
    let truth = shared::params::PAPER_UNIT;
    let noise = NoiseModel {
        accel_bias_walk_mg_sqrt_s: 0.002,
        gyro_bias_walk_deg_s_sqrt_s: GYRO_WALK_DEG_S_SQRT_S,
        ..NoiseModel::default()
    };
    let stats = simulate_stats(&truth, &plan, &noise, 1)?;
    let rows: u64 = stats.iter().map(|s| s.count).sum();
    println!(
        "paper session: {rows} rows in {} segments, walks 0.002 mg/√s and \
         {GYRO_WALK_DEG_S_SQRT_S} °/s/√s",
        stats.len()
    );
    let given = |walk, gyro_walk| EstimateOptions {
        bias_walk: walk,
        gyro_bias_walk_deg_s_sqrt_s: gyro_walk,
        ..EstimateOptions::new(recording::testkit::SPELLING)
    };
    for (name, options) in [
        ("constant bias", given(BiasWalk::Off, 0.0)),
        ("walk given 0.002 mg/√s", given(BiasWalk::Given(0.002), 0.0)),
        ("walk estimated", given(BiasWalk::Estimate, 0.0)),
        (
            "both walks given",
            given(BiasWalk::Given(0.002), GYRO_WALK_DEG_S_SQRT_S),
        ),
        (
            "both walks estimated",
            EstimateOptions::new(recording::testkit::SPELLING).drift_aware(),
        ),
    ] {
        let mut times = Vec::with_capacity(RUNS);
        let mut last = None;
        for _ in 0..RUNS {
            let t = Instant::now();
            let out = calibrate_session_stats(&plan, &stats, &options)?;
            times.push(t.elapsed().as_secs_f64());
            last = Some(out);
        }
        times.sort_by(f64::total_cmp);
        let gyro = last
            .as_ref()
            .and_then(|o| o.gyro_walk)
            .map_or(String::new(), |g| {
                let axes = g.axes.map_or(String::new(), |a| {
                    format!(", per axis {:.6?} used {}", a.deg_s_sqrt_s, a.used)
                });
                format!(
                    " (gyro {:.6} ± {:.6} °/s/√s{axes})",
                    g.deg_s_sqrt_s, g.sigma_deg_s_sqrt_s
                )
            });
        let walk =
            last.and_then(|o| o.bias_walk)
                .map_or(String::new(), |w| match w.sigma_mg_sqrt_s {
                    Some(s) => format!(" (walk {:.5} ± {s:.5} mg/√s)", w.mg_sqrt_s),
                    None => String::new(),
                });
        println!(
            "{name:24} {:8.2} ms median of {RUNS} ({:.2} best){walk}{gyro}",
            times[RUNS / 2] * 1e3,
            times[0] * 1e3
        );
    }
    Ok(())
}
