//! What a calibration produces once it exists: the checks it passes wherever it is used, its
//! compensation of a recording, its reports and other tools' formats, and the noise figures of a
//! still recording. Above the estimator, below the use cases (`app`) and the command line.
//!
//! # Module map
//!
//! - [`calibration_guard`]: the one guard wherever a calibration meets a recording, a device or
//!   another calibration, with its table of checks.
//! - [`summary`]: the machine-readable result with pass/fail limits.
//! - [`apply`]: a calibration applied to a recording with the device's own code (`host apply`).
//! - [`report`]: what a person reads — terminal text, the HTML/Markdown report with its figures and
//!   tables, the navigation replay, the comparison of two calibrations.
//! - [`export`]: a calibration in other tools' formats (Kalibr YAML, Fusion and plain C headers with a
//!   C blob decoder, JSON, PX4, ArduPilot, the TOML conversions).
//! - [`noise`]: Allan deviation and noise terms (`host noise`).
//! - [`note`]: what a report tells its reader besides its numbers, as values.
#![deny(missing_docs)]

pub mod apply;
pub mod calibration_guard;
pub mod export;
pub mod noise;
pub mod note;
pub mod report;
pub mod summary;
