//! `host compare`: two calibrations of one unit side by side, each difference in units of its combined
//! 1σ.

use super::CliError;
use crate::report::compare::compare;
use clap::Args;
use std::path::PathBuf;

/// `host compare`.
#[derive(Debug, Args)]
pub struct CompareArgs {
    /// First calibration.toml.
    pub a: PathBuf,
    /// Second calibration.toml.
    pub b: PathBuf,
}

/// Prints the comparison table.
pub fn run(a: &CompareArgs) -> Result<(), CliError> {
    print!("{}", compare(&a.a, &a.b)?.render());
    Ok(())
}
