//! `host report`: the report of a session judged by a calibration (figures, `report.html`, `report.md`).

use super::CliError;
use crate::report::document::{report, ReportOptions};
use clap::Args;
use std::path::PathBuf;

/// `host report`.
#[derive(Debug, Args)]
pub struct ReportArgs {
    /// Session directory (plan.toml + samples.csv).
    #[arg(long, value_name = "DIR")]
    pub input: PathBuf,
    /// The calibration to judge (calibration.toml; default: DIR/calibration.toml).
    #[arg(long, value_name = "FILE")]
    pub calibration: Option<PathBuf>,
    /// Where to write the figures and pages (default: DIR/report).
    #[arg(long, value_name = "OUT")]
    pub out_dir: Option<PathBuf>,
    /// The static segment to replay for the navigation check (default: the first static one).
    #[arg(long, value_name = "NAME")]
    pub static_run: Option<String>,
    /// The rotating segment to replay (default: the fastest constant-rate one).
    #[arg(long, value_name = "NAME")]
    pub rate_run: Option<String>,
    /// Length of the replayed navigation runs, s.
    #[arg(long, default_value_t = 60.0)]
    pub duration_s: f64,
    /// No PNG figures (SVG only).
    #[arg(long)]
    pub no_png: bool,
}

/// `host report`.
pub fn run(a: &ReportArgs) -> Result<(), CliError> {
    let calibration = a
        .calibration
        .clone()
        .unwrap_or_else(|| a.input.join(crate::calibration_files::CALIBRATION_TOML));
    let out_dir = a.out_dir.clone().unwrap_or_else(|| a.input.join("report"));
    let mut options = ReportOptions {
        navigation_duration_s: a.duration_s,
        static_run: a.static_run.clone(),
        rate_run: a.rate_run.clone(),
        ..ReportOptions::default()
    };
    options.formats.png = !a.no_png;
    let summary = report(&a.input, &calibration, &out_dir, &options)?;
    print!("{}", summary.render());
    Ok(())
}
