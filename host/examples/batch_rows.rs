//! Rows per second of `host batch` with one worker thread and with all cores.
//!
//! ```text
//! cargo run --release -p host --example batch_rows -- [UNITS] [PLAN]
//! ```
//!
//! Simulates UNITS (default 50) sessions of the paper's unit (PLAN, default `short`: 30 000 rows each)
//! into a temporary directory, then calibrates the lot twice through `app::batch::run_batch`: with
//! one thread and with one per core. Prints rows, seconds and rows/s of each run. The rows are read
//! from disk each time (the second run reads from the page cache, like the first after simulation).

use app::batch::{find_sessions, run_batch, BatchOptions};
use estimator::sim::{simulate_to_dir, NoiseModel};
use estimator::unit_file::UnitFile;
use indicatif::ProgressBar;
use outputs::summary::Limits;
use recording::session::builtin::load_plan;

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let mut args = std::env::args().skip(1);
    let units: u64 = args.next().map_or(Ok(50), |s| s.parse())?;
    let plan = load_plan(&args.next().unwrap_or_else(|| "short".into()))?;
    let dir = tempfile::tempdir()?;
    let input = dir.path().join("lot");
    let unit = UnitFile::paper_unit();
    for i in 0..units {
        simulate_to_dir(
            &input.join(format!("unit{i:03}")),
            &unit,
            &plan,
            &NoiseModel::default(),
            i,
            false,
        )?;
    }
    let sessions = find_sessions(&input)?;
    for (label, jobs) in [("1 thread", Some(1)), ("all cores", None)] {
        let opts = BatchOptions {
            estimate: Default::default(),
            limits: Limits::default(),
            outlier_z: 5.0,
            jobs,
        };
        let lot = run_batch(
            &sessions,
            // A fresh directory each run: results are never written over earlier ones.
            &dir.path().join(format!("out-{}", jobs.unwrap_or(0))),
            &opts,
            &ProgressBar::hidden(),
        )?;
        println!(
            "{label:>9} ({} threads): {} units, {} rows in {:.3} s = {:.0} rows/s",
            lot.threads,
            lot.units.len(),
            lot.rows,
            lot.seconds,
            lot.rows as f64 / lot.seconds
        );
    }
    Ok(())
}
