//! `host compare`: two calibrations of one unit side by side, each difference in units of its combined
//! 1σ; with `--max-sigma` a production check that exits nonzero when a difference is too large.

use super::output::Output;
use super::CliError;
use clap::Args;
use outputs::report::compare::compare;
use serde_json::json;
use std::path::PathBuf;

/// `host compare`.
#[derive(Debug, Args)]
pub(crate) struct CompareArgs {
    /// First calibration.toml.
    pub a: PathBuf,
    /// Second calibration.toml.
    pub b: PathBuf,
    /// Fail (exit nonzero) when any determined parameter differs by more than this many combined σ.
    #[arg(long, value_name = "N", value_parser = recording::limits::real(recording::limits::MIN_LIMIT, recording::limits::MAX_LIMIT))]
    pub max_sigma: Option<f64>,
    /// Print the comparison as one JSON document on stdout (the table goes to stderr).
    #[arg(long)]
    pub json: bool,
}

/// Prints the comparison table (or its JSON) and checks the limit.
pub(crate) fn run(a: &CompareArgs, quiet: bool) -> Result<(), CliError> {
    if let Some(m) = a.max_sigma {
        if !(m.is_finite() && m > 0.0) {
            return Err(CliError::Usage(format!(
                "--max-sigma {m} must be a positive number"
            )));
        }
    }
    let out = Output {
        json: a.json,
        quiet,
    };
    let t = compare(&a.a, &a.b)?;
    out.human(t.render())?;
    let worst = t
        .worst()
        .and_then(|r| r.diff_sigma.map(|d| (r.label.clone(), d)));
    let passed = match (a.max_sigma, &worst) {
        (Some(limit), Some((_, d))) => d.abs() <= limit,
        (Some(_), None) => false,
        (None, _) => true,
    };
    let rows: Vec<_> = t
        .rows
        .iter()
        .map(|r| {
            json!({
                "name": r.label, "unit": r.unit, "a": r.a, "b": r.b,
                "sigma_a": r.sigma_a, "sigma_b": r.sigma_b, "diff": r.diff,
                "diff_sigma": r.diff_sigma, "undetermined": r.undetermined,
            })
        })
        .collect();
    out.document(&json!({
        "a": t.a_name,
        "b": t.b_name,
        "rows": rows,
        "worst": worst.as_ref().map(|(n, d)| json!({"name": n, "diff_sigma": d})),
        "max_sigma": a.max_sigma,
        "passed": passed,
        "notes": outputs::report::compare::Note::texts(&t.notes),
    }))?;
    match (a.max_sigma, worst) {
        (Some(limit), Some((name, d))) if d.abs() > limit => Err(CliError::ChecksFailed(format!(
            "{name} differs by {:.2} σ > {limit} σ",
            d.abs()
        ))),
        (Some(_), None) => Err(CliError::ChecksFailed(
            "no parameter has a 1σ in either file: nothing to check --max-sigma against".into(),
        )),
        _ => Ok(()),
    }
}
