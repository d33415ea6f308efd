//! The application layer: each use case written once, called alike by the command line (`host`'s
//! `cli`), `host batch` ([`batch`]), the live procedure (the `device` crate's `procedure`) and the
//! Python package.
//!
//! A use case takes typed inputs and returns a typed result; it prints nothing and parses no command
//! line. Presenting the result (the terminal text, `--json`, a Python object) is the caller's.
//!
//! - `calibrate`: from a recording (its statistics, or its directory) to a calibration, its checks
//!   and its files.
//! - `document`: the result's one JSON shape ([`CalibrationDocument`]), a live run's verification
//!   included.
//! - `error`: why a use case failed ([`CalibrateError`]), each cause kept as its source.
//! - [`handheld`]: `host segment` (a logger's recording to a session) without writing files until
//!   asked: the positions and spins found, their coverage, the plan and statistics, and the gyro
//!   fit from the hand turns or the table turns ([`handheld::gyro`], [`handheld::table_turn`]).
//! - [`log_input`]: how to read a logger's file ([`log_input::LogInput`]), the options named as the
//!   caller spells them.
//! - [`navigation_check`]: `host navigation-check`, the paper's unit simulated, fitted and
//!   replayed by a navigator.
//! - [`report`]: `host report`, a session judged by a calibration: the session's own fit run once
//!   here and handed to the report.
//! - [`simulate`]: a virtual unit on a virtual rate table written as a session
//!   ([`simulate::Simulation`]).
//! - [`simulate_hand`]: a simulated hand-held or six-face session as a logger writes it, with the
//!   unit's truth ([`simulate_hand::HandSimulation`]).
//! - [`walk_source`]: the accelerometers' bias random walk taken from the unit's noise figures
//!   (`--bias-walk-from`: `host noise`'s `noise.json` or a unit file's `[noise]`).
//! - [`segment_order`]: which order of a plan's segments lowers the predicted 1σ under a walk
//!   (`host plan --check --bias-walk`).
//! - [`autopilot`]: a vehicle's log to its IMUs' ids, slots and calibrations (`host export --log`).
//! - [`batch`]: a lot of recordings calibrated in parallel (`host batch`), each through
//!   [`calibrate_recording`], with the lot's screen and summary.
#![deny(missing_docs)]

pub mod autopilot;
pub mod batch;
pub mod calibrate;
pub mod document;
pub mod error;
pub mod handheld;
pub mod log_input;
pub mod navigation_check;
pub mod report;
pub mod segment_order;
pub mod simulate;
pub mod simulate_hand;
pub mod walk_source;

pub use calibrate::{
    calibrate_recording, calibrate_session_dir, settle_files, write_result, CalibrateOptions,
    Calibrated, Recording,
};
pub use document::{CalibrationDocument, ResultFiles, VerificationSummary};
pub use error::CalibrateError;
