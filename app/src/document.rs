//! The one JSON shape of a calibration's result, whichever way it was made: from a recording
//! (`host calibrate --input`, `host batch`, Python) or live from a device (`host calibrate --port`),
//! which adds its verification.

use estimator::estimate::Exclusion;
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
    /// Every segment the calibration left out, with why and (where a number decided) the figure
    /// that failed against its limit; empty when every segment was used.
    #[serde(default)]
    pub excluded_segments: Vec<ExcludedSegment>,
}

/// A segment the calibration left out.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct ExcludedSegment {
    /// The segment's name in the plan (or in the data, for one the plan does not have).
    pub segment: String,
    /// Why, as the text output says it.
    pub reason: String,
    /// The figure that failed and its limit; `null` where no number decided (missing, unplanned,
    /// doubled, non-finite or stuck).
    pub figure: Option<FailedFigure>,
}

/// The figure a screen measured and the limit it failed.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct FailedFigure {
    /// What was measured, e.g. "mean gyro rate off the static segments' median".
    pub name: String,
    /// The measured value, in `unit`.
    pub value: f64,
    /// The limit, in `unit`.
    pub limit: f64,
    /// The unit of both: "°/s", "°", "×" (a ratio), "rows".
    pub unit: String,
    /// `"at_most"` (the value exceeded its limit) or `"at_least"` (it fell short).
    pub bound: String,
}

impl ExcludedSegment {
    /// The document's entry for an estimator's exclusion.
    pub fn of(e: &Exclusion) -> ExcludedSegment {
        ExcludedSegment {
            segment: e.name.clone(),
            reason: e.reason.to_string(),
            figure: e.reason.figure().map(|f| FailedFigure {
                name: f.what,
                value: f.value,
                limit: f.limit,
                unit: f.unit.into(),
                bound: if f.at_most { "at_most" } else { "at_least" }.into(),
            }),
        }
    }
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
            excluded_segments: Vec::new(),
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

    /// Lists the segments the estimate left out.
    pub(crate) fn set_excluded(&mut self, excluded: &[Exclusion]) {
        self.excluded_segments = excluded.iter().map(ExcludedSegment::of).collect();
    }

    /// Adds the device's verification; the result passes only if it passed too.
    pub fn set_verification(&mut self, verification: VerificationSummary) {
        self.summary.passed &= verification.passed;
        self.verification = Some(verification);
    }
}

#[cfg(test)]
mod tests {
    use crate::calibrate::{calibrate_recording, CalibrateOptions, Recording};
    use estimator::sim::testkit::{self, clean_session};
    use shared::OutputUnit;

    /// The paper's plan plus six oblique static attitudes, so that the fit survives two bad
    /// statics.
    fn plan_with_obliques() -> recording::session::Plan {
        let mut plan = testkit::paper_plan(OutputUnit::Volts);
        let s3 = 1.0 / 3f64.sqrt();
        for (k, sx, sy, sz) in [
            (0, 1.0, 1.0, 1.0),
            (1, -1.0, 1.0, 1.0),
            (2, 1.0, -1.0, 1.0),
            (3, 1.0, 1.0, -1.0),
            (4, -1.0, -1.0, 1.0),
            (5, -1.0, 1.0, -1.0),
        ] {
            let mut seg = plan.segments[0].clone();
            seg.name = format!("oblique {k}");
            seg.up_b = [sx * s3, sy * s3, sz * s3];
            plan.segments.push(seg);
        }
        plan
    }

    #[test]
    fn the_document_lists_every_segment_left_out_with_figure_and_limit() {
        let plan = plan_with_obliques();
        let (_, clean) = clean_session(&plan, 2);
        let calibrate = |stats: &[recording::session::SegmentStats]| {
            let recording = Recording {
                plan: &plan,
                stats,
                hand_gyro: None,
                reader_warnings: &[],
            };
            let c = calibrate_recording(recording, &CalibrateOptions::default()).unwrap();
            serde_json::to_value(&c.document).unwrap()
        };
        // Every segment used: the list is there, and empty.
        assert_eq!(
            calibrate(&clean)["excluded_segments"],
            serde_json::json!([])
        );
        // Planted: a 2 °/s turn on one static segment, accelerometer x five times noisier on another.
        let mut stats = clean.clone();
        stats[2].mean_w_rad_s = [0.0, 0.0, 2f64.to_radians()];
        stats[3].cov_u[0][0] *= 25.0;
        let doc = calibrate(&stats);
        let list = doc["excluded_segments"].as_array().unwrap();
        assert_eq!(list.len(), 2, "{list:?}");
        let entry = |name: &str| {
            list.iter()
                .find(|e| e["segment"] == name)
                .unwrap_or_else(|| panic!("{name} not in {list:?}"))
        };
        let turned = entry(&plan.segments[2].name);
        assert!(
            turned["reason"].as_str().unwrap().contains("moved"),
            "{turned}"
        );
        let fig = &turned["figure"];
        assert!((fig["value"].as_f64().unwrap() - 2.0).abs() < 0.01, "{fig}");
        assert_eq!(
            fig["limit"].as_f64().unwrap(),
            0.5f64.to_radians().to_degrees()
        );
        assert_eq!(fig["unit"], "°/s");
        assert_eq!(fig["bound"], "at_most");
        let shaken = entry(&plan.segments[3].name);
        let fig = &shaken["figure"];
        assert!((fig["value"].as_f64().unwrap() - 5.0).abs() < 0.5, "{fig}");
        assert_eq!(fig["limit"].as_f64().unwrap(), 2.0);
        assert_eq!(fig["unit"], "×");
        assert!(
            fig["name"].as_str().unwrap().contains("accelerometer x"),
            "{fig}"
        );
    }
}
