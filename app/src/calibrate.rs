//! The calibrate use case: from a recording's statistics to a calibration, its summary and its
//! files, the same for `host calibrate --input`, `host batch`, the live procedure (which estimates
//! from the recording it has just saved) and Python's `calibrate`.

use super::document::CalibrationDocument;
use super::error::CalibrateError;
use estimator::calibration_files::{self, OutputError, WrittenCalibration};
use estimator::estimate::GyroEstimate;
use estimator::estimate::{
    calibrate_with_hand_gyro, CalibrationOutcome, EstimateError, EstimateOptions,
};
use outputs::summary::{CalibrationSummary, Limits};
use recording::session::note::Note;
use recording::session::{self, Plan, ReadOptions, SegmentStats, Session};
use recording::spelling::Spelling;
use shared::UnitId;
use std::path::{Path, PathBuf};

/// What a calibration is asked for: the estimator's settings and the pass/fail limits. Its default
/// is the tests' (feature `testkit`, the neutral test spelling): a caller builds its own.
#[derive(Clone, Debug)]
#[cfg_attr(any(test, feature = "testkit"), derive(Default))]
pub struct CalibrateOptions {
    /// The estimator's settings (`--method`, `--reference`, `--single-package`).
    pub estimate: EstimateOptions,
    /// The limits the result is checked against.
    pub limits: Limits,
}

impl CalibrateOptions {
    /// The estimator's defaults and the default limits, the messages spelled as the caller
    /// spells its options.
    pub fn new(spelling: Spelling) -> CalibrateOptions {
        CalibrateOptions {
            estimate: EstimateOptions::new(spelling),
            limits: Limits::default(),
        }
    }
}

/// A recording as the estimator takes it: its plan, its per-segment statistics, the gyro its hand
/// turns determined (a hand-held session's `gyro.toml`), and what its reader flagged.
#[derive(Clone, Copy, Debug)]
pub struct Recording<'a> {
    /// The plan.
    pub plan: &'a Plan,
    /// The per-segment statistics, in plan order.
    pub stats: &'a [SegmentStats],
    /// The gyro from the hand turns, used when the plan itself determines none.
    pub hand_gyro: Option<&'a GyroEstimate>,
    /// What the reader flagged (rows left out, gaps): part of the result, not only of the terminal.
    pub reader_warnings: &'a [String],
}

/// A calibration and everything said about it.
#[derive(Debug)]
pub struct Calibrated {
    /// The estimate.
    pub outcome: CalibrationOutcome,
    /// The result with its checks, as every caller presents it (one JSON shape).
    pub document: CalibrationDocument,
    /// The unit the recording names (`plan.toml`'s `unit_id`); `None`: the blob is bound to the
    /// all-zero id, which each caller tells its user in its own terms.
    pub unit_id: Option<UnitId>,
    /// The gyro came from the hand turns, not from the plan's own spins: its `G`, and its bias too
    /// unless a temperature model's rests give the bias at `T_ref` (docs/model.md §9).
    pub gyro_from_hand_turns: bool,
}

impl Calibrated {
    /// The id the blob is bound to.
    pub fn bound_unit_id(&self) -> UnitId {
        self.unit_id.unwrap_or_default()
    }
}

/// Estimates a calibration from a recording (docs/model.md §2–§4), takes the hand turns' gyro
/// where the plan determines no `G` ([`calibrate_with_hand_gyro`]: beside a temperature model, with
/// the rests' bias, §9), and checks the result against the limits.
pub fn calibrate_recording(
    recording: Recording<'_>,
    options: &CalibrateOptions,
) -> Result<Calibrated, EstimateError> {
    let (outcome, gyro_from_hand_turns) = calibrate_with_hand_gyro(
        recording.plan,
        recording.stats,
        &options.estimate,
        recording.hand_gyro,
    )?;
    let plan_id = recording.plan.unit_id.clone();
    let unit_id = plan_id
        .as_deref()
        .map(|hex| UnitId::parse_hex(hex).unwrap_or_default());
    let mut summary = CalibrationSummary::new(&outcome, plan_id, &options.limits);
    summary
        .warnings
        .extend(recording.reader_warnings.iter().cloned());
    let mut document = CalibrationDocument::new(summary);
    document.set_excluded(&outcome.excluded);
    Ok(Calibrated {
        outcome,
        document,
        unit_id,
        gyro_from_hand_turns,
    })
}

/// Reads the session in `dir` (`plan.toml`, `samples.csv` and a hand-held session's `gyro.toml`)
/// and calibrates it ([`calibrate_recording`]). The session is returned for its report.
pub fn calibrate_session_dir(
    dir: &Path,
    options: &CalibrateOptions,
    read: &ReadOptions,
) -> Result<(Session, Calibrated), CalibrateError> {
    let session = session::read_session(dir, read)?;
    let hand_gyro = crate::handheld::gyro::read(dir)?;
    let reader_warnings = Note::texts(&session.report.warnings);
    let calibrated = calibrate_recording(
        Recording {
            plan: &session.plan,
            stats: &session.stats,
            hand_gyro: hand_gyro.as_ref(),
            reader_warnings: &reader_warnings,
        },
        options,
    )?;
    Ok((session, calibrated))
}

/// Writes `calibration.toml` and `calibration.bin` into `out_dir` (atomically, as a pair; an
/// existing pair replaced only with `force`), and records where in the result's document.
pub fn write_result(
    out_dir: &Path,
    calibrated: &mut Calibrated,
    created_unix_s: u64,
    force: bool,
) -> Result<WrittenCalibration, OutputError> {
    let written = calibration_files::write_calibration_files(
        out_dir,
        &calibrated.outcome,
        calibrated.bound_unit_id(),
        created_unix_s,
        force,
    )?;
    calibrated
        .document
        .set_files(&written.toml_path, &written.bin_path);
    Ok(written)
}

/// Renames the written pair to `calibration.FAILED.*` when the result did not pass (its checks, or
/// the device's verification), so that nothing that looks for an accepted calibration picks it up;
/// the document names the files as they now are. A passing result removes an earlier failed pair
/// (`force`): the directory holds one result.
pub fn settle_files(
    calibrated: &mut Calibrated,
    written: WrittenCalibration,
    force: bool,
) -> Result<WrittenCalibration, OutputError> {
    if calibrated.document.summary.passed {
        // Without `force` an earlier result was refused before any work: only a forced run can
        // find a failed pair here.
        if force {
            let dir = written.bin_path.parent().unwrap_or(Path::new("."));
            calibration_files::remove_failed_in(dir)?;
        }
        return Ok(written);
    }
    let dir = written.bin_path.parent().unwrap_or(Path::new("."));
    let (toml_path, bin_path) = mark_failed(&mut calibrated.document, dir, force)?;
    Ok(WrittenCalibration {
        toml_path,
        bin_path,
        blob: written.blob,
    })
}

/// Renames the pair in `dir` to `calibration.FAILED.*` (an existing failed pair replaced only with
/// `force`) and names the new files in `document`: for a result that failed its checks, or (in
/// `host batch`) a unit that is an outlier of its lot.
pub(crate) fn mark_failed(
    document: &mut CalibrationDocument,
    dir: &Path,
    force: bool,
) -> Result<(PathBuf, PathBuf), OutputError> {
    let (toml, bin) = calibration_files::mark_failed_in(dir, force)?;
    document.set_files(&toml, &bin);
    Ok((toml, bin))
}
