//! `host batch`: a production lot calibrated in parallel, with a lot summary (CSV and JSON).

use super::calibrate::{estimate_options_of, MethodArg, ReferenceArg};
use super::output::Output;
use super::CliError;
use crate::batch::{find_sessions, run_batch, to_csv, BatchError, BatchOptions};
use crate::output_file::write_atomic;
use crate::summary::Limits;
use clap::Args;
use std::path::PathBuf;

/// `host batch`.
#[derive(Debug, Args)]
#[command(mut_args(crate::limits::pass_fail_limits))]
pub struct BatchArgs {
    /// Directory whose subdirectories are sessions (plan.toml + samples.csv), one per unit.
    #[arg(long, value_name = "DIR_OF_SESSIONS")]
    pub input: PathBuf,
    /// Output directory: one subdirectory of calibration files per unit, summary.csv, summary.json.
    #[arg(long, value_name = "DIR")]
    pub out: PathBuf,
    /// Replace existing results in --out.
    #[arg(long)]
    pub force: bool,
    /// Worker threads (default: one per core).
    #[arg(long, value_name = "N")]
    pub jobs: Option<usize>,
    /// Robust z-score above which a parameter makes a unit an outlier of the lot.
    #[arg(long, value_name = "Z", default_value_t = 5.0, value_parser = crate::limits::real(crate::limits::MIN_LIMIT, crate::limits::MAX_LIMIT))]
    pub outlier_z: f64,
    /// Estimator: joint (default) or paper.
    #[arg(long, value_enum, default_value_t = MethodArg::Joint)]
    pub method: MethodArg,
    /// Point the lever arms are given relative to.
    #[arg(long, value_enum, default_value_t = ReferenceArg::TableAxis)]
    pub reference: ReferenceArg,
    /// Pass/fail limits of each unit.
    #[command(flatten)]
    pub limits: Limits,
    /// Print the lot summary as one JSON document on stdout.
    #[arg(long)]
    pub json: bool,
}

/// Runs `host batch`; exits nonzero when any unit failed, is outside the limits or is an outlier.
pub fn run(a: &BatchArgs, quiet: bool) -> Result<(), CliError> {
    if a.jobs == Some(0) || !(a.outlier_z.is_finite() && a.outlier_z > 0.0) {
        return Err(CliError::Usage(
            "--jobs must be at least 1 and --outlier-z a positive number".into(),
        ));
    }
    let out = Output {
        json: a.json,
        quiet,
    };
    let sessions = find_sessions(&a.input).map_err(CliError::Batch)?;
    std::fs::create_dir_all(&a.out).map_err(|e| CliError::Io(a.out.clone(), e))?;
    let opts = BatchOptions {
        estimate: estimate_options_of(a.method, a.reference),
        limits: a.limits,
        outlier_z: a.outlier_z,
        jobs: a.jobs,
        force: a.force,
    };
    let bar = crate::ui::progress_bar(sessions.len() as u64, "calibrating", quiet);
    let lot = run_batch(&sessions, &a.out, &opts, &bar).map_err(CliError::Batch)?;
    let json = serde_json::to_string_pretty(&lot)
        .map_err(|e| CliError::Batch(BatchError::Threads(e.to_string())))?;
    write_atomic(&a.out.join("summary.csv"), to_csv(&lot).as_bytes(), a.force)?;
    write_atomic(&a.out.join("summary.json"), json.as_bytes(), a.force)?;
    out.document(&lot)?;
    let failed = lot.failed();
    out.line(format_args!(
        "{} units, {} rows in {:.2} s on {} threads ({:.0} rows/s); {} passed, {} not",
        lot.units.len(),
        lot.rows,
        lot.seconds,
        lot.threads,
        lot.rows as f64 / lot.seconds.max(1e-9),
        lot.units.len() - failed.len(),
        failed.len()
    ))?;
    for u in &failed {
        let why = match (&u.error, &u.summary) {
            (Some(e), _) => e.clone(),
            (None, Some(s)) if !s.passed => s.failures(),
            _ => {
                let o: Vec<String> = u
                    .outliers
                    .iter()
                    .map(|(n, z)| format!("{n} z = {z:.1}"))
                    .collect();
                format!("outlier of the lot: {}", o.join(", "))
            }
        };
        out.line(format_args!("  FAIL {}: {why}", u.session))?;
    }
    out.line(format_args!(
        "wrote {}",
        a.out.join("summary.csv").display()
    ))?;
    if failed.is_empty() {
        Ok(())
    } else {
        Err(CliError::ChecksFailed(format!(
            "{} of {} units: {}",
            failed.len(),
            lot.units.len(),
            failed
                .iter()
                .map(|u| u.session.as_str())
                .collect::<Vec<_>>()
                .join(", ")
        )))
    }
}
