//! The PC calibrator: recording format, simulator, estimator, reports and the device link.
//! The binary (`src/main.rs`) is a thin clap layer over this library.

pub mod apply;
pub mod batch;
pub mod calibration_files;
pub mod cli;
pub mod device;
pub mod estimate;
pub mod export;
pub mod noise;
pub mod output_file;
pub mod report;
pub mod session;
pub mod sim;
pub mod summary;
pub mod ui;
pub mod unit_file;
