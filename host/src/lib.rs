//! The PC calibrator: recording format, simulator, estimator, reports and the device link.
//! The binary (`src/main.rs`) is a thin clap layer over this library.

pub mod calibration_files;
pub mod cli;
pub mod compare;
pub mod convert;
pub mod device;
pub mod device_cli;
pub mod estimate;
pub mod figures;
pub mod navigation;
pub mod procedure;
pub mod recording;
pub mod report;
pub mod report_cmd;
pub mod simulate;
pub mod unit_file;
