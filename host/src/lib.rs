//! The command line: `host`'s subcommands, each one file of [`cli`] that parses its arguments, calls
//! the layers below and presents their results. The binary (`src/main.rs`) is a thin clap layer
//! over this library.
//!
//! # Crates below, kept there by Cargo
//!
//! - `recording`: the readers, segmentation and statistics, the input limits, the result files;
//! - `estimator`: the fit, its uncertainty, the calibration's files, the simulator;
//! - `outputs`: what a calibration produces (the guard, the summary, apply, report, export, noise);
//! - `app`: the use cases, each once, with the batch;
//! - `device`: the link to a device and the live procedure.
//!
//! The code names each of them by its crate name (`recording::session::Plan`); nothing is
//! re-exported here. This crate's own modules: [`cli`]; `limits` and `ui`, the command line's
//! bounds and stdout writes beside the recording's; `fuzz`, the parsers' fuzz targets (feature
//! `fuzz`). The tests, examples and fuzz targets depend on the crates they use.
#![deny(missing_docs)]

pub mod cli;
/// The parsers' fuzz targets: not in the shipped library or binary (feature `fuzz`, which the `fuzz/`
/// crate and `--example fuzz` enable); the unit tests run their short seeded runs.
#[cfg(any(test, feature = "fuzz"))]
pub mod fuzz;
pub(crate) mod limits;
pub(crate) mod ui;
