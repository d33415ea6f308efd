//! The estimator's time on the paper's session (the built-in `paper` plan: 15 segments of 60 s at
//! 1 kHz, 900 000 rows) with a bias random walk of 0.002 mg/√s: the constant-bias fit, the walk
//! given and the walk estimated (docs/model.md §11).
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

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let plan = paper_plan();
    let truth = shared::params::PAPER_UNIT;
    let noise = NoiseModel {
        accel_bias_walk_mg_sqrt_s: 0.002,
        ..NoiseModel::default()
    };
    let stats = simulate_stats(&truth, &plan, &noise, 1)?;
    let rows: u64 = stats.iter().map(|s| s.count).sum();
    println!(
        "paper session: {rows} rows in {} segments, walk 0.002 mg/√s",
        stats.len()
    );
    for (name, walk) in [
        ("constant bias", BiasWalk::Off),
        ("walk given 0.002 mg/√s", BiasWalk::Given(0.002)),
        ("walk estimated", BiasWalk::Estimate),
    ] {
        let options = EstimateOptions {
            bias_walk: walk,
            ..EstimateOptions::default()
        };
        let mut times = Vec::with_capacity(RUNS);
        let mut last = None;
        for _ in 0..RUNS {
            let t = Instant::now();
            let out = calibrate_session_stats(&plan, &stats, &options)?;
            times.push(t.elapsed().as_secs_f64());
            last = Some(out);
        }
        times.sort_by(f64::total_cmp);
        let walk =
            last.and_then(|o| o.bias_walk)
                .map_or(String::new(), |w| match w.sigma_mg_sqrt_s {
                    Some(s) => format!(" (walk {:.5} ± {s:.5} mg/√s)", w.mg_sqrt_s),
                    None => String::new(),
                });
        println!(
            "{name:24} {:8.2} ms median of {RUNS} ({:.2} best){walk}",
            times[RUNS / 2] * 1e3,
            times[0] * 1e3
        );
    }
    Ok(())
}
