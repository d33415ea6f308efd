//! The one error type of the command line: every command's failure, each message naming the problem
//! and, where there is one, the fix (the wrapped errors' own messages, unchanged).

use device::procedure::ProcedureError;
use device::LinkError;
use estimator::calibration_files::OutputError;
use estimator::estimate::EstimateError;
use estimator::sim::SimulateError;
use estimator::unit_file::UnitFileError;
use outputs::export::ExportError;
use outputs::report::compare::CompareError;
use outputs::report::ReportError;
use recording::session::{PlanError, RecordingError};
use shared::blob::BlobError;
use std::path::PathBuf;

/// Why a command failed.
#[derive(Debug, thiserror::Error)]
pub(crate) enum CliError {
    /// Reading or writing a session.
    #[error(transparent)]
    Recording(#[from] RecordingError),
    /// A plan.
    #[error(transparent)]
    Plan(#[from] PlanError),
    /// A unit file.
    #[error(transparent)]
    Unit(#[from] UnitFileError),
    /// The simulator.
    #[error(transparent)]
    Simulate(#[from] SimulateError),
    /// The estimator.
    #[error(transparent)]
    Estimate(EstimateError),
    /// An option the estimator refuses, named by its flag (the estimator names no caller's
    /// options): the flag, then the estimator's reason as the cause.
    #[error("{flag}")]
    EstimateOption {
        /// The flag.
        flag: &'static str,
        /// The estimator's reason.
        source: EstimateError,
    },
    /// Writing the result.
    #[error(transparent)]
    Output(#[from] OutputError),
    /// A logger's file could not be read.
    #[error(transparent)]
    Log(recording::session::logs::LogError),
    /// `host report` / `host navigation-check`.
    #[error(transparent)]
    Report(#[from] ReportError),
    /// `host compare`.
    #[error(transparent)]
    Compare(#[from] CompareError),
    /// `host export`.
    #[error(transparent)]
    Export(#[from] ExportError),
    /// The link to a device.
    #[error(transparent)]
    Link(#[from] LinkError),
    /// The live procedure.
    #[error(transparent)]
    Procedure(#[from] ProcedureError),
    /// A blob file.
    #[error("{}", .0.display())]
    Blob(PathBuf, #[source] BlobError),
    /// A calibration that cannot meet what it meets ([`outputs::calibration_guard`]).
    #[error(transparent)]
    Guard(#[from] outputs::calibration_guard::GuardError),
    /// A calibration no device or tool can use ([`outputs::calibration_guard`]).
    #[error(transparent)]
    Scale(#[from] outputs::calibration_guard::ScaleError),
    /// A file.
    #[error("{}", .0.display())]
    Io(PathBuf, #[source] std::io::Error),
    /// The live procedure ran but the verification failed.
    #[error(
        "FAIL: the calibration is on the device but its compensated output is outside the tolerance \
         at some verification positions (see above); its files are kept as calibration.FAILED.toml \
         and calibration.FAILED.bin: flash an accepted calibration to replace it on the device"
    )]
    VerificationFailed,
    /// `host apply`.
    #[error(transparent)]
    Apply(#[from] outputs::apply::ApplyError),
    /// `host noise`.
    #[error(transparent)]
    Noise(#[from] outputs::noise::NoiseError),
    /// A result file could not be written.
    #[error(transparent)]
    Written(#[from] recording::output_file::OutputFileError),
    /// `host batch` could not run.
    #[error(transparent)]
    Batch(app::batch::BatchError),
    /// `host bringup` could not run its checks.
    #[error(transparent)]
    Bringup(#[from] device::bringup::BringupError),
    /// A result failed its pass/fail limits (the failed checks, one line).
    #[error("FAIL: {0}")]
    ChecksFailed(String),
    /// A gyro fit that no real gyro gives ([`estimator::estimate::gyro_check`]): nothing was written.
    #[error(
        "the gyro fit is refused, nothing written:\n  - {}\nfix the columns, signs, unit or time \
         base named above; to use the accelerometer alone, add --no-gyro",
        .0.join("\n  - ")
    )]
    GyroRefused(Vec<String>),
    /// The hand-held session's gyro.
    #[error(transparent)]
    HandGyro(#[from] app::handheld::gyro::HandGyroFileError),
    /// The options that say how to read a logger's file do not fit together.
    #[error(transparent)]
    LogInput(#[from] app::log_input::LogInputError),
    /// A vehicle's log gives no ids, slots or calibrations.
    #[error(transparent)]
    Autopilot(#[from] app::autopilot::AutopilotError),
    /// `--bias-walk-from`: the walk could not be taken from the file.
    #[error(transparent)]
    WalkSource(#[from] app::walk_source::WalkSourceError),
    /// The recording gives no session: no still interval, too few positions, face labels the
    /// data contradict.
    #[error(transparent)]
    Segment(#[from] recording::session::segment::SegmentError),
    /// The command line is incomplete or an option is unusable.
    #[error("{0}")]
    Usage(String),
    /// An option's value is out of its range.
    #[error(transparent)]
    Range(#[from] recording::limits::RangeError),
    /// The simulated device cannot hold the unit given (`--sim-unit`).
    #[error(transparent)]
    SimDevice(#[from] device::sim::SimError),
    /// A result could not be written as JSON (`what` names it).
    #[error("cannot write {what} as JSON")]
    Json {
        /// The result.
        what: &'static str,
        /// Why.
        #[source]
        source: serde_json::Error,
    },
    /// A file could not be written.
    #[error("cannot write {}", .0.display())]
    Write(PathBuf, #[source] std::io::Error),
    /// Standard output is closed or full (`| head`, `> /dev/full`); files and devices were written
    /// before it. The I/O error is said in parentheses inside the message, so it is shown there and
    /// not also returned as `source()`.
    #[error(
        "cannot write to standard output ({}); any files (and a device) were written before this",
        shared::chain::Chain(.0)
    )]
    Stdout(std::io::Error),
}

/// The estimator's refusal, led by the flag it refuses where one is refused.
impl From<EstimateError> for CliError {
    fn from(e: EstimateError) -> Self {
        let flag = match e {
            EstimateError::GyroBiasWalkUnused { .. } => "--gyro-bias-walk",
            EstimateError::BiasWalkUnit { .. } => "--bias-walk-from",
            _ => return CliError::Estimate(e),
        };
        CliError::EstimateOption { flag, source: e }
    }
}

impl From<std::io::Error> for CliError {
    fn from(e: std::io::Error) -> Self {
        CliError::Stdout(e)
    }
}

/// Exit status of a command that failed (bad input, I/O, a device, an estimate refused).
pub(crate) const EXIT_ERROR: i32 = 1;
/// Exit status of a command line that cannot be run as given (clap's own usage errors exit 2 too).
pub(crate) const EXIT_USAGE: i32 = 2;
/// Exit status of a command that ran to the end but whose result failed a check (pass/fail limits,
/// the device's verification): its files are written, marked as failed.
pub(crate) const EXIT_CHECK_FAILED: i32 = 3;

impl CliError {
    /// The process exit status for this error: `EXIT_USAGE`, `EXIT_CHECK_FAILED` or
    /// `EXIT_ERROR`, so that scripts tell a typo, a failed unit and a broken run apart.
    pub fn exit_code(&self) -> i32 {
        match self {
            CliError::Usage(_) | CliError::LogInput(_) => EXIT_USAGE,
            CliError::ChecksFailed(_) | CliError::VerificationFailed => EXIT_CHECK_FAILED,
            CliError::WalkSource(e) if e.is_usage() => EXIT_USAGE,
            _ if self.is_option_not_for_input() => EXIT_USAGE,
            _ => EXIT_ERROR,
        }
    }

    /// An option that does not apply to the input it was given with, found only once the input
    /// was opened (a log's format, a session's segments): a usage error like any other.
    fn is_option_not_for_input(&self) -> bool {
        use outputs::apply::ApplyError;
        use outputs::calibration_guard::GuardError;
        use recording::session::logs::LogError;
        matches!(
            self,
            CliError::Report(
                ReportError::RunNotInSession { .. } | ReportError::RunOfOtherKind { .. }
            ) | CliError::Range(_)
                | CliError::SimDevice(_)
                | CliError::Apply(
                    ApplyError::Guard(GuardError::TemperatureNotUsed { .. })
                        | ApplyError::RawOffset { given: Some(_), .. }
                )
                | CliError::Log(
                    LogError::OptionNotForFormat { .. } | LogError::TextOptionOnBinary { .. }
                )
                | CliError::EstimateOption { .. }
        )
    }
}

impl From<app::handheld::InMemoryError> for CliError {
    fn from(e: app::handheld::InMemoryError) -> Self {
        use app::handheld::InMemoryError;
        match e {
            InMemoryError::GyroRefused(problems) => CliError::GyroRefused(problems),
            InMemoryError::HandGyro(e) => CliError::HandGyro(e),
            InMemoryError::Segment(e) => CliError::Segment(e),
        }
    }
}

impl From<app::handheld::WriteError> for CliError {
    fn from(e: app::handheld::WriteError) -> Self {
        use app::handheld::WriteError;
        match e {
            WriteError::Session(e) => e.into(),
            WriteError::Gyro(e) => e.into(),
        }
    }
}

impl From<app::CalibrateError> for CliError {
    fn from(e: app::CalibrateError) -> Self {
        use app::CalibrateError;
        match e {
            CalibrateError::Recording(e) => e.into(),
            CalibrateError::HandGyro(e) => e.into(),
            CalibrateError::Estimate(e) => e.into(),
        }
    }
}

impl From<app::simulate::SimulationError> for CliError {
    fn from(e: app::simulate::SimulationError) -> Self {
        use app::simulate::SimulationError;
        match e {
            SimulationError::Unit(e) => e.into(),
            SimulationError::Plan(e) => e.into(),
            SimulationError::Simulate(e) => e.into(),
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use device::procedure::ProcedureError;
    use recording::session::{builtin::paper_plan, read_session, ReadOptions, PLAN_FILE};
    use shared::chain::Chain;
    use shared::params::ParamsError;
    use std::error::Error;

    /// Every error below `e`, outermost first (`source()` followed to its end).
    fn chain(e: &dyn Error) -> Vec<String> {
        let mut below = Vec::new();
        let mut next = e.source();
        while let Some(s) = next {
            below.push(s.to_string());
            next = s.source();
        }
        below
    }

    /// A session whose `samples.csv` is missing: the command's error keeps its one-line message and
    /// hands the operating system's error to anyone who walks `source()` (a logger, `anyhow`).
    #[test]
    fn a_session_read_failure_keeps_its_io_error_as_source() {
        let dir = tempfile::tempdir().unwrap();
        std::fs::write(dir.path().join(PLAN_FILE), paper_plan().to_toml()).unwrap();
        let e = CliError::from(read_session(dir.path(), &ReadOptions { quiet: true }).unwrap_err());
        let below = chain(&e);
        assert_eq!(below.len(), 1, "{below:?}");
        let io = e
            .source()
            .unwrap()
            .downcast_ref::<std::io::Error>()
            .unwrap();
        assert_eq!(io.kind(), std::io::ErrorKind::NotFound);
        let samples = dir.path().join("samples.csv");
        assert_eq!(e.to_string(), samples.display().to_string());
        assert_eq!(
            Chain(&e).to_string(),
            format!("{}: {io}", samples.display())
        );
    }

    /// A missing plan: three layers (command, recording, plan) down to the I/O error.
    #[test]
    fn a_missing_plan_reaches_its_io_error_through_three_layers() {
        let dir = tempfile::tempdir().unwrap();
        let e = CliError::from(read_session(dir.path(), &ReadOptions { quiet: true }).unwrap_err());
        assert!(e.to_string().starts_with("cannot read plan "), "{e}");
        let io = e.source().and_then(|s| s.downcast_ref::<std::io::Error>());
        assert_eq!(
            io.map(|io| io.kind()),
            Some(std::io::ErrorKind::NotFound),
            "{e:?}"
        );
    }

    /// The procedure's estimate failure leads with its reason and says where the recording is
    /// after it: the reason, with its own cause, is said in the message once and not returned as
    /// `source()`.
    #[test]
    fn a_procedure_failure_says_its_reason_and_the_reasons_cause_once() {
        let e = CliError::from(ProcedureError::Estimate {
            cause: EstimateError::Params(ParamsError::NonFinite).into(),
            recording: PathBuf::from("rec"),
        });
        assert!(chain(&e).is_empty(), "{:?}", chain(&e));
        let reason = EstimateError::Params(ParamsError::NonFinite);
        assert_eq!(
            chain(&reason),
            [ParamsError::NonFinite.to_string()],
            "the estimator's error exposes its cause"
        );
        assert_eq!(
            Chain(&e).to_string(),
            format!(
                "the estimate is not a valid calibration: {}\n(the recording is saved in rec)",
                ParamsError::NonFinite
            )
        );
    }
}
