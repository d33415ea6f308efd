//! `host report`: the report of a session judged by a calibration (figures, `report.html`, `report.md`).

use super::CliError;
use app::report::report;
use clap::Args;
use outputs::report::ReportOptions;
use std::path::PathBuf;

/// `host report`.
#[derive(Debug, Args)]
pub(crate) struct ReportArgs {
    /// Session directory (plan.toml + samples.csv).
    #[arg(long, value_name = "DIR")]
    pub input: PathBuf,
    /// The calibration to judge (default: DIR/calibration.toml, else DIR/../calibration.toml, where
    /// `calibrate --port` writes it next to its OUT/recording).
    #[arg(long, value_name = "FILE")]
    pub calibration: Option<PathBuf>,
    /// Where to write the figures and pages (default: DIR/report).
    #[arg(long = "out", visible_alias = "out-dir", value_name = "OUT")]
    pub out_dir: Option<PathBuf>,
    /// The static segment to replay for the navigation check (default: the first static one).
    #[arg(long, value_name = "NAME")]
    pub static_run: Option<String>,
    /// The rotating segment to replay (default: the fastest constant-rate one).
    #[arg(long, value_name = "NAME")]
    pub rate_run: Option<String>,
    /// Length of the replayed navigation runs, s.
    #[arg(long, default_value_t = 60.0, value_parser = recording::limits::real(crate::limits::MIN_NAVIGATION_DURATION_S, crate::limits::MAX_NAVIGATION_DURATION_S))]
    pub duration_s: f64,
    /// No PNG figures (SVG only).
    #[arg(long)]
    pub no_png: bool,
    /// The session's own fit under a bias random walk (its strength and each segment's fitted bias
    /// over the session in the report, docs/model.md §11).
    #[command(flatten)]
    pub walk: super::calibrate::BiasWalkArgs,
}

/// `host report`.
pub(crate) fn run(a: &ReportArgs, quiet: bool) -> Result<(), CliError> {
    navigation_duration(a.duration_s)?;
    let calibration = match &a.calibration {
        Some(c) => c.clone(),
        None => default_calibration(&a.input),
    };
    let out_dir = a.out_dir.clone().unwrap_or_else(|| a.input.join("report"));
    let mut options = ReportOptions {
        navigation_duration_s: a.duration_s,
        static_run: a.static_run.clone(),
        rate_run: a.rate_run.clone(),
        ..ReportOptions::new(super::spelling::FLAGS)
    };
    a.walk.set(&mut options.estimate)?;
    options.formats.png = !a.no_png;
    let summary = report(&a.input, &calibration, &out_dir, &options)?;
    let out = super::output::Output { json: false, quiet };
    out.human(summary.render())?;
    for w in &summary.warnings {
        out.warn(w);
    }
    Ok(())
}

/// `--duration-s` sizes the navigation replay (samples = duration ÷ step): checked before any work.
pub(crate) fn navigation_duration(duration_s: f64) -> Result<f64, CliError> {
    Ok(recording::limits::positive_at_most(
        "--duration-s",
        duration_s,
        crate::limits::MAX_NAVIGATION_DURATION_S,
    )?)
}

/// `DIR/calibration.toml` when it exists, else the one beside the recording (`DIR/..`), else
/// `DIR/calibration.toml` (so that the error names the expected place).
pub(crate) fn default_calibration(input: &std::path::Path) -> PathBuf {
    let own = input.join(estimator::calibration_files::CALIBRATION_TOML);
    if own.exists() {
        return own;
    }
    match input.parent() {
        Some(parent)
            if parent
                .join(estimator::calibration_files::CALIBRATION_TOML)
                .exists() =>
        {
            parent.join(estimator::calibration_files::CALIBRATION_TOML)
        }
        _ => own,
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn finds_the_calibration_beside_a_live_recording() {
        let dir = tempfile::tempdir().unwrap();
        let rec = dir.path().join("recording");
        std::fs::create_dir_all(&rec).unwrap();
        assert_eq!(default_calibration(&rec), rec.join("calibration.toml"));
        std::fs::write(dir.path().join("calibration.toml"), "x").unwrap();
        assert_eq!(
            default_calibration(&rec),
            dir.path().join("calibration.toml")
        );
        std::fs::write(rec.join("calibration.toml"), "x").unwrap();
        assert_eq!(default_calibration(&rec), rec.join("calibration.toml"));
    }
}
