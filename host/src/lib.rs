//! The PC calibrator: recording format, simulator, estimator, reports and the device link. The binary
//! (`src/main.rs`) is a thin clap layer over this library.
//!
//! # Module map
//!
//! Each subcommand is one file of [`cli`]; it calls the domain modules below, which never call back
//! up (no cycles: `estimate` knows nothing of `report`). The recording (its readers, segmentation
//! and statistics, the input limits, the result files) is the crate `recording`, below this one.
//!
//! - [`app`]: the use cases, each once (calibrate from a recording), called by the command line,
//!   `host batch`, the live procedure and the Python package alike.
//! - [`cli`]: one file per subcommand (its argument struct and `run`), the one [`cli::CliError`].
//! - [`estimate`]: from a plan and segment statistics to a calibration, its [`estimate::Uncertainty`]
//!   and what the plan could not determine; the Cramér–Rao prediction of a plan (`docs/model.md`
//!   §2–§4).
//! - [`sim`]: the virtual unit on a virtual rate table (`host simulate`), its noise-free statistics,
//!   and the one random number generator.
//! - [`device`]: the protocol client, its transports (serial port, in-process simulated device), and
//!   the live procedure with its operator prompts (`host calibrate --port`).
//! - [`report`]: what a person reads — terminal text, the HTML/Markdown report with its figures and
//!   tables, the navigation replay, the comparison of two calibrations.
//! - [`export`]: a calibration in other tools' formats (Kalibr YAML, Fusion and plain C headers with a
//!   C blob decoder, JSON, PX4, ArduPilot, the TOML conversions).
//! - [`apply`]: a calibration applied to a recording with the device's own code (`host apply`);
//!   [`noise`]: Allan deviation and noise terms (`host noise`); [`batch`]: a lot calibrated in
//!   parallel (`host batch`); [`summary`]: the machine-readable result with pass/fail limits.
//! - [`unit_file`]: a unit's parameters as TOML (the simulator's truth, the calibrator's result);
//!   [`calibration_files`]: writing `calibration.toml` and `calibration.bin`;
//!   [`calibration_guard`]: what a calibration must be before it meets a recording, a device or a
//!   tool.
#![deny(missing_docs)]

// The recording layer is its own crate; its modules keep their paths inside this one.
use recording::{output_file, session};

pub mod app;
pub mod apply;
pub mod batch;
pub mod calibration_files;
pub mod calibration_guard;
pub mod cli;
pub mod device;
pub mod estimate;
pub mod export;
/// The parsers' fuzz targets: not in the shipped library or binary (feature `fuzz`, which the `fuzz/`
/// crate and `--example fuzz` enable); the unit tests run their short seeded runs.
#[cfg(any(test, feature = "fuzz"))]
pub mod fuzz;
pub mod limits;
pub mod noise;
pub mod report;
pub mod sim;
pub mod summary;
pub mod ui;
pub mod unit_file;
