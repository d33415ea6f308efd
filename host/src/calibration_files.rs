//! Writing a calibration result: `calibration.toml` (the unit-file schema plus 1σ, so that
//! `host simulate --unit calibration.toml` round-trips) and `calibration.bin` (the device blob).

use crate::estimate::CalibrationOutcome;
use crate::unit_file::UnitFile;
use shared::blob::{BlobError, ParameterBlob};
use shared::UnitId;
use std::path::{Path, PathBuf};

/// File name of the TOML result.
pub const CALIBRATION_TOML: &str = "calibration.toml";
/// File name of the blob.
pub const CALIBRATION_BIN: &str = "calibration.bin";

/// What was written.
#[derive(Clone, Debug)]
pub struct WrittenCalibration {
    /// Path of `calibration.toml`.
    pub toml_path: PathBuf,
    /// Path of `calibration.bin`.
    pub bin_path: PathBuf,
    /// The blob's bytes.
    pub blob: Vec<u8>,
}

/// Why the result could not be written.
#[derive(Debug)]
pub enum OutputError {
    /// The calibration does not encode (it fails the device's own validation).
    Blob(BlobError),
    /// A file could not be written.
    Io(PathBuf, std::io::Error),
}

impl std::fmt::Display for OutputError {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match self {
            OutputError::Blob(e) => write!(
                f,
                "the estimated calibration cannot be stored on a device: {e}"
            ),
            OutputError::Io(p, e) => write!(f, "cannot write {}: {e}", p.display()),
        }
    }
}

impl std::error::Error for OutputError {}

/// Seconds since the Unix epoch (0 if the clock is before it).
pub fn now_unix_s() -> u64 {
    std::time::SystemTime::now()
        .duration_since(std::time::UNIX_EPOCH)
        .map_or(0, |d| d.as_secs())
}

/// The blob of an outcome for `unit_id`.
pub fn blob_bytes(
    outcome: &CalibrationOutcome,
    unit_id: UnitId,
    created_unix_s: u64,
) -> Result<Vec<u8>, BlobError> {
    let blob = ParameterBlob {
        unit_id,
        calibration: outcome.calibration,
        created_unix_s,
    };
    let (bytes, n) = blob.to_bytes()?;
    Ok(bytes[..n].to_vec())
}

/// Writes both files into `out_dir` (created if needed).
pub fn write_calibration_files(
    out_dir: &Path,
    outcome: &CalibrationOutcome,
    unit_id: UnitId,
    created_unix_s: u64,
) -> Result<WrittenCalibration, OutputError> {
    let blob = blob_bytes(outcome, unit_id, created_unix_s).map_err(OutputError::Blob)?;
    std::fs::create_dir_all(out_dir).map_err(|e| OutputError::Io(out_dir.to_path_buf(), e))?;
    let toml_path = out_dir.join(CALIBRATION_TOML);
    let mut file = UnitFile::from_calibration(
        &outcome.calibration,
        Some(unit_id),
        Some(outcome.uncertainty.clone()),
    );
    if let (Some(section), Some(fit)) = (file.temperature.as_mut(), &outcome.thermal) {
        section.zero_bias_degree = Some(fit.zero_bias_degree);
        section.scale_degree = Some(fit.scale_degree);
        section.zero_bias_out_per_c_1sigma = Some(fit.zero_bias_sigma);
        section.scale_rel_per_c_1sigma = Some(fit.scale_sigma);
    }
    let text = file.to_toml();
    std::fs::write(&toml_path, text).map_err(|e| OutputError::Io(toml_path.clone(), e))?;
    let bin_path = out_dir.join(CALIBRATION_BIN);
    std::fs::write(&bin_path, &blob).map_err(|e| OutputError::Io(bin_path.clone(), e))?;
    Ok(WrittenCalibration {
        toml_path,
        bin_path,
        blob,
    })
}
