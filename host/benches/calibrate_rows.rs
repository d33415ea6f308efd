//! Rows per second of `host calibrate`'s input path: `cargo bench -p host --bench calibrate_rows`.
//!
//! Simulates a 10⁶-row session (the paper's plan, segments shortened to 10⁶ rows in all, the paper's
//! unit, 1 mg white noise) into a temporary directory, then times reading `samples.csv` into the
//! per-segment statistics (parse + accumulate, one core) a few times and prints rows per second.
//! The file is read from the page cache after the first pass, so this is the parser's speed, which
//! is what limits `calibrate` (the estimator works on 15 segment summaries, not on rows); the whole
//! `calibrate` path (read + statistics + joint estimate with the paper-method comparison) is timed too.

use estimator::estimate::{calibrate_session_stats, EstimateOptions};
use estimator::sim::{simulate_to_dir, NoiseModel};
use estimator::unit_file::UnitFile;
use recording::session::builtin::paper_plan;
use recording::session::{read_session, ReadOptions, SAMPLES_FILE};
use std::time::Instant;

const ROWS: f64 = 1e6;

fn main() {
    let dir = tempfile::tempdir().expect("a temporary directory");
    let mut plan = paper_plan();
    let per_segment_s = ROWS / plan.segments.len() as f64 / plan.sample_rate_hz;
    for s in &mut plan.segments {
        s.duration_s = Some(per_segment_s);
    }
    let t = Instant::now();
    let summary = simulate_to_dir(
        dir.path(),
        &UnitFile::paper_unit(),
        &plan,
        &NoiseModel::default(),
        1,
        true,
    )
    .expect("simulation");
    let sim_s = t.elapsed().as_secs_f64();
    let bytes = std::fs::metadata(dir.path().join(SAMPLES_FILE))
        .expect("samples.csv")
        .len();
    println!(
        "simulated {} rows ({:.1} MB) in {:.2} s: {:.2} M rows/s written",
        summary.rows,
        bytes as f64 / 1e6,
        sim_s,
        summary.rows as f64 / sim_s / 1e6
    );

    let mut times = Vec::new();
    for _ in 0..5 {
        let t = Instant::now();
        let session = read_session(dir.path(), &ReadOptions { quiet: true }).expect("read");
        times.push(t.elapsed().as_secs_f64());
        assert_eq!(session.report.rows, summary.rows);
        std::hint::black_box(session);
    }
    times.sort_by(f64::total_cmp);
    let (best, median) = (times[0], times[times.len() / 2]);
    println!(
        "read + statistics: {:.3} s median, {:.3} s best of {}: {:.2} M rows/s median ({:.2} best), {:.0} MB/s",
        median,
        best,
        times.len(),
        summary.rows as f64 / median / 1e6,
        summary.rows as f64 / best / 1e6,
        bytes as f64 / median / 1e6
    );
    println!(
        "rows per second (read + statistics, median): {:.0}",
        summary.rows as f64 / median
    );

    let mut times = Vec::new();
    for _ in 0..3 {
        let t = Instant::now();
        let session = read_session(dir.path(), &ReadOptions { quiet: true }).expect("read");
        let outcome =
            calibrate_session_stats(&session.plan, &session.stats, &EstimateOptions::default())
                .expect("estimate");
        times.push(t.elapsed().as_secs_f64());
        std::hint::black_box(outcome);
    }
    times.sort_by(f64::total_cmp);
    println!(
        "rows per second (whole calibrate: read + statistics + estimate, median of {}): {:.0}",
        times.len(),
        summary.rows as f64 / times[times.len() / 2]
    );
}
