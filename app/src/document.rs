//! The one JSON shape of a calibration's result, whichever way it was made: from a recording
//! (`host calibrate --input`, `host batch`, Python) or live from a device (`host calibrate --port`),
//! which adds its verification.

use outputs::summary::CalibrationSummary;
use serde::{Deserialize, Serialize};
use std::path::Path;

/// A calibration's result: its summary (parameters, 1σ, χ², checks), the files written and, for a
/// live calibration, the device's verification. `passed` (in the summary) is every check and the
/// verification together.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct CalibrationDocument {
    /// Parameters, 1σ, χ², the checks against the limits, warnings.
    #[serde(flatten)]
    pub summary: CalibrationSummary,
    /// Where the result was written; `null` when nothing was (Python's `calibrate`).
    pub files: Option<ResultFiles>,
    /// The stored calibration's verification on the device; `null` for a recording.
    pub verification: Option<VerificationSummary>,
}

/// The files of a result.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct ResultFiles {
    /// `calibration.toml` (or `calibration.FAILED.toml`).
    pub calibration_toml: String,
    /// `calibration.bin` (or `calibration.FAILED.bin`).
    pub calibration_bin: String,
    /// The directory holding them (and, for a live calibration, its `recording/`).
    pub results_dir: String,
}

/// The verification of a calibration stored on a device: the compensated output at held-out
/// positions against the tolerance.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct VerificationSummary {
    /// Largest compensated error at a position, mg.
    pub worst_error_mg: f64,
    /// The tolerance, mg.
    pub tolerance_mg: f64,
    /// Every position within the tolerance.
    pub passed: bool,
}

impl CalibrationDocument {
    /// A result with no files written yet and no verification.
    pub fn new(summary: CalibrationSummary) -> Self {
        CalibrationDocument {
            summary,
            files: None,
            verification: None,
        }
    }

    /// Records the files' paths as written (or renamed to `calibration.FAILED.*`); the results
    /// directory is the one holding them.
    pub(crate) fn set_files(&mut self, toml: &Path, bin: &Path) {
        self.files = Some(ResultFiles {
            calibration_toml: toml.display().to_string(),
            calibration_bin: bin.display().to_string(),
            results_dir: bin.parent().unwrap_or(Path::new(".")).display().to_string(),
        });
    }

    /// Names the files where they are after their directory `from` was moved to `to` (a result
    /// built beside its destination and renamed into place whole, as `host batch` does).
    pub fn files_moved(&mut self, from: &Path, to: &Path) {
        let moved = |p: &mut String| {
            if let Ok(rest) = Path::new(p.as_str()).strip_prefix(from) {
                *p = to.join(rest).display().to_string();
            }
        };
        if let Some(f) = self.files.as_mut() {
            moved(&mut f.calibration_toml);
            moved(&mut f.calibration_bin);
            moved(&mut f.results_dir);
        }
    }

    /// Adds the device's verification; the result passes only if it passed too.
    pub fn set_verification(&mut self, verification: VerificationSummary) {
        self.summary.passed &= verification.passed;
        self.verification = Some(verification);
    }
}
