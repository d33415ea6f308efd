//! `host export`: a calibration in another tool's format.

use super::CliError;
use crate::export::kalibr::KalibrNoise;
use crate::export::{render, ExportFormat, ExportInput};
use crate::output_file::write_atomic;
use crate::unit_file::{UnitFile, UnitFileError};
use clap::Args;
use std::path::PathBuf;

/// `host export`.
#[derive(Debug, Args)]
pub struct ExportArgs {
    /// The calibration (a unit file, e.g. calibration.toml).
    #[arg(long, value_name = "FILE")]
    pub calibration: PathBuf,
    /// The format.
    #[arg(long, value_enum, default_value_t = ExportFormat::All)]
    pub format: ExportFormat,
    /// Where to write it (default: stdout).
    #[arg(long, value_name = "FILE")]
    pub out: Option<PathBuf>,
    /// Replace an existing --out file.
    #[arg(long)]
    pub force: bool,
    /// The noise figures for Kalibr: noise.json written by `host noise`.
    #[arg(long, value_name = "NOISE.json")]
    pub noise: Option<PathBuf>,
    /// Kalibr's rostopic of the IMU.
    #[arg(long, default_value = "/imu0")]
    pub rostopic: String,
    /// For kalibr, px4, ardupilot: m/s² per output unit of the driver's reading (default: g / mean
    /// scale factor).
    #[arg(long, value_name = "M_S2_PER_UNIT", value_parser = crate::limits::real(1e-9, crate::limits::MAX_LIMIT))]
    pub driver_scale: Option<f64>,
}

/// Runs `host export`.
pub fn run(a: &ExportArgs, quiet: bool) -> Result<(), CliError> {
    let unit = UnitFile::load(&a.calibration)?;
    let invalid = |m| CliError::Unit(UnitFileError::Invalid(a.calibration.clone(), m));
    let cal = unit.to_calibration().map_err(invalid)?;
    if let Some(c) = a.driver_scale {
        if !(c.is_finite() && c > 0.0) {
            return Err(CliError::Usage(format!(
                "--driver-scale {c} must be a positive number of m/s² per output unit"
            )));
        }
    }
    let noise: Option<KalibrNoise> = match &a.noise {
        Some(p) => Some(crate::noise::load_kalibr_noise(p).map_err(CliError::Noise)?),
        None => None,
    };
    if a.format == ExportFormat::Kalibr && noise.is_none() {
        eprintln!(
            "warning: no --noise NOISE.json: Kalibr's noise densities and random walks are written as \
             .nan (undetermined); run `host noise --input SESSION --out DIR` first"
        );
    }
    let input = ExportInput {
        unit: &unit,
        cal,
        noise: noise.as_ref(),
        rostopic: &a.rostopic,
        driver_scale_m_s2_per_out: a.driver_scale,
    };
    let text = render(&input, a.format)?;
    match &a.out {
        Some(p) => {
            write_atomic(p, text.as_bytes(), a.force).map_err(CliError::Written)?;
            if !quiet {
                eprintln!("wrote {}", p.display());
            }
        }
        None => crate::out!("{text}")?,
    }
    Ok(())
}
