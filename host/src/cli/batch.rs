//! `host batch`: a production lot calibrated in parallel, with a lot summary (CSV and JSON).

use super::calibrate::EstimatorArgs;
use super::output::Output;
use super::CliError;
use app::batch::{find_sessions, run_batch, to_csv, BatchOptions, MAX_JOBS};
use clap::Args;
use outputs::summary::Limits;
use recording::output_file::{write_atomic, OutputDir};
use std::path::PathBuf;

/// `host batch`.
#[derive(Debug, Args)]
#[command(mut_args(outputs::summary::pass_fail_limits))]
pub(crate) struct BatchArgs {
    /// Directory whose subdirectories are sessions (plan.toml + samples.csv), one per unit.
    #[arg(long, value_name = "DIR_OF_SESSIONS")]
    pub input: PathBuf,
    /// Output directory: one subdirectory of calibration files per unit, summary.csv, summary.json.
    /// Built beside it and moved into place whole at the end.
    #[arg(long, value_name = "DIR")]
    pub out: PathBuf,
    /// Replace an earlier batch's result in --out (a directory with summary.json), whole.
    #[arg(long)]
    pub force: bool,
    /// Worker threads, 1 to 256 (default: one per core; never more than there are sessions).
    #[arg(long, value_name = "N")]
    pub jobs: Option<usize>,
    /// Robust z-score above which a parameter makes a unit an outlier of the lot.
    #[arg(long, value_name = "Z", default_value_t = 5.0, value_parser = recording::limits::real(recording::limits::MIN_LIMIT, recording::limits::MAX_LIMIT))]
    pub outlier_z: f64,
    /// The estimator of each unit: --method, --reference, --single-package.
    #[command(flatten)]
    pub estimator: EstimatorArgs,
    /// Pass/fail limits of each unit.
    #[command(flatten)]
    pub limits: Limits,
    /// Print the lot summary as one JSON document on stdout.
    #[arg(long)]
    pub json: bool,
}

/// The lot summary's CSV file in `--out`.
pub(crate) const SUMMARY_CSV: &str = "summary.csv";
/// The lot summary's JSON file in `--out`: its presence marks a directory as a batch result, which
/// `--force` may replace.
pub(crate) const SUMMARY_JSON: &str = "summary.json";

/// Runs `host batch`; exits nonzero when any unit failed, is outside the limits or is an outlier.
pub(crate) fn run(a: &BatchArgs, quiet: bool) -> Result<(), CliError> {
    // Checked before anything is read, created or started.
    a.estimator.refuse()?;
    let estimate = a.estimator.options()?;
    if let Some(j) = a.jobs {
        if !(1..=MAX_JOBS).contains(&j) {
            return Err(CliError::Usage(format!(
                "--jobs {j}: use 1 to {MAX_JOBS} worker threads (default: one per core; a lot never \
                 uses more threads than it has sessions)"
            )));
        }
    }
    if !(a.outlier_z.is_finite() && a.outlier_z > 0.0) {
        return Err(CliError::Usage(format!(
            "--outlier-z {} must be a positive number",
            a.outlier_z
        )));
    }
    let out = Output {
        json: a.json,
        quiet,
    };
    // Refused here, before anything is read, when --out holds something --force may not replace.
    let staged = OutputDir::create(&a.out, a.force, SUMMARY_JSON)?;
    let sessions = find_sessions(&a.input).map_err(CliError::Batch)?;
    let opts = BatchOptions {
        estimate,
        limits: a.limits,
        outlier_z: a.outlier_z,
        jobs: a.jobs,
    };
    let bar = recording::ui::progress_bar(sessions.len() as u64, "calibrating", quiet);
    let mut lot = run_batch(&sessions, staged.path(), &opts, &bar).map_err(CliError::Batch)?;
    // The units' documents name their files where they will be once the result is in place.
    for d in lot.units.iter_mut().filter_map(|u| u.summary.as_mut()) {
        d.files_moved(staged.path(), &a.out);
    }
    let json = serde_json::to_string_pretty(&lot).map_err(|source| CliError::Json {
        what: "the lot summary",
        source,
    })?;
    write_atomic(
        &staged.path().join(SUMMARY_CSV),
        to_csv(&lot).as_bytes(),
        false,
    )?;
    write_atomic(&staged.path().join(SUMMARY_JSON), json.as_bytes(), false)?;
    staged.commit()?;
    out.document(&lot)?;
    for w in &lot.warnings {
        out.warn(w);
    }
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
        out.line(format_args!("  FAIL {}: {}", u.session, u.why_failed()))?;
    }
    out.line(format_args!("wrote {}", a.out.join(SUMMARY_CSV).display()))?;
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
