//! Why a calibration use case failed.

use crate::handheld::gyro::HandGyroFileError;
use estimator::estimate::EstimateError;
use recording::session::RecordingError;

/// Why [`super::calibrate_session_dir`] produced no calibration; each keeps its cause.
#[derive(Debug, thiserror::Error)]
pub enum CalibrateError {
    /// The session could not be read.
    #[error(transparent)]
    Recording(#[from] RecordingError),
    /// The session's hand-turn gyro (`gyro.toml`) could not be read.
    #[error(transparent)]
    HandGyro(#[from] HandGyroFileError),
    /// The estimator refused the session.
    #[error(transparent)]
    Estimate(#[from] EstimateError),
}
