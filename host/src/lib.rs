//! The command line: `host`'s subcommands, each one file of [`cli`] that parses its arguments, calls
//! the layers below and presents their results. The binary (`src/main.rs`) is a thin clap layer
//! over this library.
//!
//! # Crates below, kept there by Cargo
//!
//! - `recording`: the readers, segmentation and statistics, the input limits, the result files;
//! - `estimator`: the fit, its uncertainty, the calibration's files, the simulator;
//! - `outputs` ([`calibration_guard`], [`summary`], [`apply`], [`report`], [`export`], [`noise`]):
//!   what a calibration produces;
//! - [`app`]: the use cases, each once, with [`batch`];
//! - [`device`]: the link to a device and the live procedure.
//!
//! This crate re-exports them at its root, so that `host::report` and the like name them for the
//! tests, the examples and the fuzz targets. Its own modules: [`cli`]; [`limits`] and [`ui`], the
//! command line's bounds and stdout writes beside the recording's; `fuzz`, the parsers' fuzz
//! targets (feature `fuzz`).
#![deny(missing_docs)]

// The modules of the crates below keep their paths inside this one.
use estimator::{calibration_files, estimate, sim, unit_file};
use recording::{output_file, session};

pub use ::app;
pub use ::device;
pub use outputs::{apply, calibration_guard, export, noise, report, summary};

pub use app::batch;
pub mod cli;
/// The parsers' fuzz targets: not in the shipped library or binary (feature `fuzz`, which the `fuzz/`
/// crate and `--example fuzz` enable); the unit tests run their short seeded runs.
#[cfg(any(test, feature = "fuzz"))]
pub mod fuzz;
pub mod limits;
pub mod ui;
