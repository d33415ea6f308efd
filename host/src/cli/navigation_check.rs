//! `host navigation-check`: the paper's navigation check on a simulated session of its unit.

use super::CliError;
use app::navigation_check::{navigation_check, NavigationCheckArgs};
use clap::Args;
use estimator::unit_file::UnitFile;
use recording::session::builtin::load_plan;
use std::path::PathBuf;

/// `host navigation-check`.
#[derive(Debug, Args)]
pub(crate) struct NavigationCheckCliArgs {
    /// Seed of the simulated session's noise.
    #[arg(long, default_value_t = 1, value_parser = recording::limits::whole_u64(0, u64::MAX))]
    pub seed: u64,
    /// Length of the replayed navigation runs, s.
    #[arg(long, default_value_t = 60.0, value_parser = recording::limits::real(crate::limits::MIN_NAVIGATION_DURATION_S, crate::limits::MAX_NAVIGATION_DURATION_S))]
    pub duration_s: f64,
    /// Where to write the figures and pages (default: nothing written).
    #[arg(long = "out", visible_alias = "out-dir", value_name = "OUT")]
    pub out_dir: Option<PathBuf>,
    /// Unit file of the simulated unit (default: the paper's unit).
    #[arg(long, value_name = "FILE")]
    pub unit: Option<PathBuf>,
    /// Plan file or built-in name (default: paper).
    #[arg(long, value_name = "FILE|NAME")]
    pub plan: Option<String>,
}

/// `host navigation-check`.
pub(crate) fn run(a: &NavigationCheckCliArgs, quiet: bool) -> Result<(), CliError> {
    super::report::navigation_duration(a.duration_s)?;
    let mut args = NavigationCheckArgs {
        seed: a.seed,
        out_dir: a.out_dir.clone(),
        ..NavigationCheckArgs::new(super::spelling::FLAGS)
    };
    args.report.navigation_duration_s = a.duration_s;
    if let Some(p) = &a.unit {
        args.unit = UnitFile::load(p)?;
    }
    if let Some(spec) = &a.plan {
        args.plan = load_plan(spec)?;
    }
    let result = navigation_check(&args)?;
    if !quiet {
        crate::out!("{}", result.render())?;
    }
    Ok(())
}
