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
    // The estimate's 1σ beside the values that `from_calibration` wrote.
    if let (Some(section), Some(g)) = (file.gyro.as_mut(), outcome.gyro.as_ref()) {
        section.bias_rad_s_1sigma = Some(g.bias_rad_s_1sigma);
        section.matrix_1sigma = Some(g.matrix_1sigma);
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

#[cfg(test)]
mod tests {
    use super::*;
    use crate::estimate::{calibrate_session_stats, EstimateOptions};
    use crate::session::builtin::builtin_plan;
    use crate::sim::testkit::{self, TableErrors};

    #[test]
    fn the_calibration_file_carries_the_estimated_gyro() {
        let plan = builtin_plan("short-oblique").unwrap().unwrap();
        let truth = testkit::paper_unit();
        let g = crate::sim::session::gyro_matrix([5e-3, -5e-3, 5e-3], 0.5f64.to_radians());
        let b = [0.008, -0.008, 0.008];
        let errors = TableErrors {
            gyro_noise_rad_s: 0.05f64.to_radians(),
            gyro: Some((g, b)),
            ..TableErrors::default()
        };
        let mut rng = testkit::Rng::new(3, 0);
        let noise = 1e-3 * truth.statics.scale_out_per_g[0];
        let stats = testkit::noisy_stats(&plan, &truth, noise, errors, &mut rng);
        let out = calibrate_session_stats(&plan, &stats, &EstimateOptions::default()).unwrap();
        let dir = tempfile::tempdir().unwrap();
        let id = UnitId::parse_hex("000102030405060708090a0b").unwrap();
        let w = write_calibration_files(dir.path(), &out, id, 0).unwrap();
        let text = std::fs::read_to_string(&w.toml_path).unwrap();
        assert!(
            text.contains("[gyro]")
                && text.contains("bias_rad_s = [")
                && text.contains("matrix = ["),
            "{text}"
        );
        let back = UnitFile::load(&w.toml_path).unwrap().gyro.unwrap();
        let sb = back.bias_rad_s_1sigma.unwrap();
        let sg = back.matrix_1sigma.unwrap();
        for i in 0..3 {
            assert!((back.bias_rad_s[i] - b[i]).abs() < 5.0 * sb[i], "b{i}");
            for j in 0..3 {
                // Within 5σ (the misalignment's 1σ includes the body frame's alignment).
                assert!(
                    (back.matrix[i][j] - g[i][j]).abs() < 5.0 * sg[i][j],
                    "G{i}{j}"
                );
            }
        }
    }
}
