//! The estimator layer of the PC calibrator, above the recording (crate `recording`) and below the
//! use cases, reports and the device link (crate `host`): see `ARCHITECTURE.md`.
//!
//! - [`estimate`]: from a plan and segment statistics to a calibration, its
//!   [`estimate::Uncertainty`] and what the plan could not determine; the Cramér–Rao prediction of
//!   a plan (`docs/model.md` §2–§9).
//! - [`sim`]: the virtual unit on a virtual rate table (`host simulate`), its noise-free statistics,
//!   and the one random number generator.
//! - [`unit_file`]: a unit's parameters as TOML (the simulator's truth, the calibrator's result);
//!   [`calibration_files`]: writing `calibration.toml` and `calibration.bin`;
//!   [`calibration_guard`]: what a calibration must be before it meets a recording, a device or a
//!   tool.
#![deny(missing_docs)]

// The recording's modules keep their paths inside this crate too.

pub mod calibration_files;
pub mod calibration_guard;
pub mod estimate;
pub mod sim;
pub mod unit_file;
