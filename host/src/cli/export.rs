//! `host export`: a calibration in the conventions of other tools (TOML).

use super::CliError;
use crate::export::{export_marked, ExportFormat};
use crate::unit_file::{UnitFile, UnitFileError};
use clap::Args;
use std::path::PathBuf;

/// `host export`.
#[derive(Debug, Args)]
pub struct ExportArgs {
    /// The calibration (a unit file, e.g. calibration.toml).
    #[arg(long, value_name = "FILE")]
    pub calibration: PathBuf,
    /// plain (the paper's K_A, ∇_b, lever arms), fusion, kalibr, or all.
    #[arg(long, default_value = "all")]
    pub format: ExportFormat,
    /// Where to write it (default: stdout).
    #[arg(long, value_name = "FILE")]
    pub out: Option<PathBuf>,
}

/// `host export`.
pub fn run(a: &ExportArgs) -> Result<(), CliError> {
    let (calibration, format, out) = (a.calibration.as_path(), a.format, a.out.as_deref());
    let unit = UnitFile::load(calibration)?;
    let cal = unit
        .to_calibration()
        .map_err(|m| CliError::Unit(UnitFileError::Invalid(calibration.to_path_buf(), m)))?;
    let observable = unit.uncertainty.as_ref().map(|u| &u.lever_arms_observable);
    let text = export_marked(&cal, format, observable)?;
    match out {
        Some(p) => {
            std::fs::write(p, &text).map_err(|e| {
                CliError::Output(crate::calibration_files::OutputError::Io(
                    p.to_path_buf(),
                    e,
                ))
            })?;
            crate::outln!("wrote {}", p.display())?;
        }
        None => crate::out!("{text}")?,
    }
    Ok(())
}
