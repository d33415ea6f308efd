//! The application layer: each use case written once, called alike by the command line
//! ([`crate::cli`]), `host batch` ([`crate::batch`]), the live procedure
//! ([`crate::device::procedure`]) and the Python package.
//!
//! A use case takes typed inputs and returns a typed result; it prints nothing and parses no command
//! line. Presenting the result (the terminal text, `--json`, a Python object) is the caller's.
//!
//! - `calibrate`: from a recording (its statistics, or its directory) to a calibration, its checks
//!   and its files.
//! - `document`: the result's one JSON shape ([`CalibrationDocument`]), a live run's verification
//!   included.
//! - `error`: why a use case failed ([`CalibrateError`]), each cause kept as its source.

pub mod calibrate;
pub mod document;
pub mod error;

pub use calibrate::{
    calibrate_recording, calibrate_session_dir, mark_failed, settle_files, write_result,
    CalibrateOptions, Calibrated, Recording,
};
pub use document::{CalibrationDocument, ResultFiles, VerificationSummary};
pub use error::CalibrateError;
