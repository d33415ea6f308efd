//! The PC calibrator above the estimator: the use cases, reports, exports, the device link and the
//! command line. The binary (`src/main.rs`) is a thin clap layer over this library.
//!
//! # Module map
//!
//! Each subcommand is one file of [`cli`]; it calls the domain modules below, which never call back
//! up. Below this crate, and kept there by Cargo: the crate `recording` (the readers, segmentation
//! and statistics, the input limits, the result files) and the crate `estimator` (the fit, its
//! uncertainty, the calibration's files, the simulator).
//!
//! - [`app`]: the use cases, each once (calibrate from a recording), called by the command line,
//!   `host batch`, the live procedure and the Python package alike.
//! - [`cli`]: one file per subcommand (its argument struct and `run`), the one [`cli::CliError`].
//! - [`device`]: the protocol client, its transports (serial port, in-process simulated device), and
//!   the live procedure with its operator prompts (`host calibrate --port`).
//! - [`report`]: what a person reads — terminal text, the HTML/Markdown report with its figures and
//!   tables, the navigation replay, the comparison of two calibrations.
//! - [`export`]: a calibration in other tools' formats (Kalibr YAML, Fusion and plain C headers with a
//!   C blob decoder, JSON, PX4, ArduPilot, the TOML conversions).
//! - [`calibration_guard`]: the one guard wherever a calibration meets a recording, a device or
//!   another calibration, with its table of checks.
//! - [`apply`]: a calibration applied to a recording with the device's own code (`host apply`);
//!   [`noise`]: Allan deviation and noise terms (`host noise`); [`batch`]: a lot calibrated in
//!   parallel (`host batch`); [`summary`]: the machine-readable result with pass/fail limits.
#![deny(missing_docs)]

// The recording and the estimator are crates of their own, below this one; their modules keep
// their paths inside this one.
use estimator::{calibration_files, estimate, sim, unit_file};
use recording::{output_file, session};

pub use outputs::{apply, calibration_guard, export, noise, report, summary};

pub mod app;
pub mod batch;
pub mod cli;
pub mod device;
/// The parsers' fuzz targets: not in the shipped library or binary (feature `fuzz`, which the `fuzz/`
/// crate and `--example fuzz` enable); the unit tests run their short seeded runs.
#[cfg(any(test, feature = "fuzz"))]
pub mod fuzz;
pub mod limits;
pub mod ui;
