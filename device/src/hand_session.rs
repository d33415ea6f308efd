//! A live hand-held session's recording, whole: every raw window is logged
//! (`window_log`, `stream.csv`) while the operator is guided, and at the end the log goes
//! through `host segment`'s use case (`app::handheld::segment_recording`) into a session directory
//! (`segmented/`) that `host calibrate --input` reads. The accelerometer fit and the gyro fit from
//! the hand's turns (docs/model.md §8) are then those of the offline path on the same samples:
//! one document for one recording, whichever way it came.

use super::window_log::{WindowLog, WindowLogError, STREAM_FILE};
use app::handheld::{InMemoryError, SegmentChoices, WriteError};
use app::log_input::{LogInput, LogInputError};
use recording::session::from_recording::SIX_FACE_PRIOR_DEG;
use recording::session::logs::{read_log_keeping, LogError, DEFAULT_MAX_SAMPLES};
use recording::session::segment::SegmentOptions;
use recording::session::Plan;
use recording::spelling::Spelling;
use std::path::{Path, PathBuf};

/// The session directory segmented from the window log, in the output directory.
pub(crate) const SEGMENTED_DIR: &str = "segmented";

/// The gyro's unit in the window log (its `--gyro-unit`).
const LOG_GYRO_UNIT: &str = "deg/s";

/// The window log's time column, seconds (its `--time-column`).
pub(crate) const LOG_TIME_COLUMN: &str = "t";

/// Why a hand-held session's window log gave no session.
#[derive(Debug, thiserror::Error)]
pub enum HandSessionError {
    /// The log could not be written.
    #[error(transparent)]
    WindowLog(#[from] WindowLogError),
    /// The log's reading options (a unit the reader does not know).
    #[error(transparent)]
    LogInput(#[from] LogInputError),
    /// The log could not be read back.
    #[error(transparent)]
    Log(#[from] LogError),
    /// The log gives no session (too few positions, a gyro fit no real gyro gives).
    #[error(transparent)]
    Segment(#[from] InMemoryError),
    /// The session directory could not be written.
    #[error(transparent)]
    Write(#[from] WriteError),
}

/// Opens the window log of a session recorded into `out_dir` at `sample_rate_hz` in windows of
/// `window_samples` (the directory is made if missing).
pub(crate) fn open_log(
    out_dir: &Path,
    sample_rate_hz: f64,
    window_samples: u32,
    force: bool,
) -> Result<WindowLog, WindowLogError> {
    let path = out_dir.join(STREAM_FILE);
    std::fs::create_dir_all(out_dir).map_err(|source| WindowLogError::at(&path, source))?;
    WindowLog::create(&path, sample_rate_hz, window_samples, force)
}

/// The `host segment` options that read the log as this function does.
pub(crate) fn segment_command(stream: &Path, plan: &Plan, out: &Path) -> String {
    let mut cmd = format!(
        "host segment --input {} --time-column {LOG_TIME_COLUMN} --acc-unit {} \
         --gyro-unit {LOG_GYRO_UNIT}",
        stream.display(),
        plan.output_unit.symbol()
    );
    if let Some(id) = &plan.unit_id {
        cmd.push_str(&format!(" --unit-id {id}"));
    }
    if plan.gravity_m_s2 != shared::STANDARD_GRAVITY_M_S2 {
        cmd.push_str(&format!(" --gravity {}", plan.gravity_m_s2));
    }
    cmd.push_str(&format!(" --out {}", out.display()));
    cmd
}

/// Segments the window log at `stream` (of a session recorded with `plan`) as
/// [`segment_command`] would, into `out_dir/segmented`; that directory.
pub(crate) fn segment_log(
    stream: &Path,
    plan: &Plan,
    out_dir: &Path,
    force: bool,
    spelling: Spelling,
) -> Result<PathBuf, HandSessionError> {
    let input = LogInput {
        time_column: Some(LOG_TIME_COLUMN.into()),
        acc_unit: Some(plan.output_unit.symbol().into()),
        gyro_unit: Some(LOG_GYRO_UNIT.into()),
        ..LogInput::new(spelling)
    };
    let source = input.source()?;
    let log = read_log_keeping(stream, &source, DEFAULT_MAX_SAMPLES)?;
    let choices = SegmentChoices {
        // `host segment`'s defaults; no --still-threshold to offer here.
        segment: SegmentOptions::new(spelling),
        unit_id: plan.unit_id.clone(),
        gravity_m_s2: plan.gravity_m_s2,
        fit_gyro: true,
        face_sigma_deg: SIX_FACE_PRIOR_DEG,
        faces: None,
    };
    let session = app::handheld::segment_recording(log.recording, &choices)?;
    let dir = out_dir.join(SEGMENTED_DIR);
    session.write(&dir, force)?;
    Ok(dir)
}
