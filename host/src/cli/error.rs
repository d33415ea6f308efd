//! The one error type of the command line: every command's failure, each message naming the problem
//! and, where there is one, the fix.

use crate::calibration_files::OutputError;
use crate::device::procedure::ProcedureError;
use crate::device::LinkError;
use crate::estimate::EstimateError;
use crate::export::ExportError;
use crate::report::compare::CompareError;
use crate::report::document::ReportError;
use crate::session::{PlanError, RecordingError};
use crate::sim::SimulateError;
use crate::unit_file::UnitFileError;
use shared::blob::BlobError;
use std::path::PathBuf;

/// Why a command failed.
#[derive(Debug)]
pub enum CliError {
    /// Reading or writing a session.
    Recording(RecordingError),
    /// A plan.
    Plan(PlanError),
    /// A unit file.
    Unit(UnitFileError),
    /// The simulator.
    Simulate(SimulateError),
    /// The estimator.
    Estimate(EstimateError),
    /// Writing the result.
    Output(OutputError),
    /// `host report` / `host navigation-check`.
    Report(ReportError),
    /// `host compare`.
    Compare(CompareError),
    /// `host export`.
    Export(ExportError),
    /// The link to a device.
    Link(LinkError),
    /// The live procedure.
    Procedure(ProcedureError),
    /// A blob file.
    Blob(PathBuf, BlobError),
    /// A blob made for another unit.
    WrongUnit {
        /// The blob's unit.
        blob: String,
        /// The device's unit.
        device: String,
    },
    /// A file.
    Io(PathBuf, std::io::Error),
    /// The live procedure ran but the verification failed.
    VerificationFailed,
    /// `host apply`.
    Apply(crate::apply::ApplyError),
    /// `host noise`.
    Noise(crate::noise::NoiseError),
    /// A result file could not be written.
    Written(crate::output_file::OutputFileError),
    /// `host batch` could not run.
    Batch(crate::batch::BatchError),
    /// A result failed its pass/fail limits (the failed checks, one line).
    ChecksFailed(String),
    /// The command line is incomplete or an option is unusable.
    Usage(String),
}

impl std::fmt::Display for CliError {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match self {
            CliError::Recording(e) => e.fmt(f),
            CliError::Plan(e) => e.fmt(f),
            CliError::Unit(e) => e.fmt(f),
            CliError::Simulate(e) => e.fmt(f),
            CliError::Estimate(e) => e.fmt(f),
            CliError::Output(e) => e.fmt(f),
            CliError::Report(e) => e.fmt(f),
            CliError::Compare(e) => e.fmt(f),
            CliError::Export(e) => e.fmt(f),
            CliError::Apply(e) => e.fmt(f),
            CliError::ChecksFailed(m) => write!(f, "FAIL: {m}"),
            CliError::Batch(e) => e.fmt(f),
            CliError::Noise(e) => e.fmt(f),
            CliError::Written(e) => e.fmt(f),
            CliError::Link(e) => e.fmt(f),
            CliError::Procedure(e) => e.fmt(f),
            CliError::Blob(p, e) => write!(f, "{}: {e}", p.display()),
            CliError::WrongUnit { blob, device } => write!(
                f,
                "this calibration was made for unit {blob}, the device is unit {device}: calibrate this \
                 unit, or flash its own calibration"
            ),
            CliError::Io(p, e) => write!(f, "{}: {e}", p.display()),
            CliError::VerificationFailed => f.write_str(
                "FAIL: the calibration is on the device but its compensated output is outside the tolerance \
                 at some verification positions (see above)",
            ),
            CliError::Usage(m) => f.write_str(m),
        }
    }
}

impl std::error::Error for CliError {}

/// `From` for each wrapped error, so that commands can use `?`.
macro_rules! from_error {
    ($($variant:ident($ty:ty)),* $(,)?) => {
        $(impl From<$ty> for CliError {
            fn from(e: $ty) -> Self {
                CliError::$variant(e)
            }
        })*
    };
}

from_error!(
    Recording(RecordingError),
    Plan(PlanError),
    Unit(UnitFileError),
    Simulate(SimulateError),
    Estimate(EstimateError),
    Output(OutputError),
    Report(ReportError),
    Compare(CompareError),
    Export(ExportError),
    Link(LinkError),
    Procedure(ProcedureError),
    Apply(crate::apply::ApplyError),
    Noise(crate::noise::NoiseError),
    Written(crate::output_file::OutputFileError),
);
