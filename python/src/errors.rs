//! The package's exceptions, in the manner of py-polars' `error.rs`: every failure is one typed
//! [`PyAccelErr`] (the domain errors of `host` as they are, and the package's own checks of its
//! arguments); `From<PyAccelErr> for PyErr` picks the exception type the stubs promise by the
//! domain error's kind, and hangs the error's causes on `__cause__` (an operating-system error as
//! Python's own `OSError` subclass, e.g. `FileNotFoundError`).
//!
//! Messages name Python's keyword arguments: the readers' and the export's checks are given the
//! keyword spelling (`crate::spelling::KEYWORDS`); the few refusals whose text is
//! the command line's own are said here in Python's words ([`PyAccelErr::python_message`]).

use app::handheld::gyro::HandGyroFileError;
use app::handheld::{InMemoryError, WriteError};
use app::log_input::LogInputError;
use app::simulate::SimulationError;
use app::CalibrateError;
use estimator::calibration_files::OutputError;
use estimator::estimate::EstimateError;
use estimator::unit_file::UnitFileError;
use outputs::apply::ApplyError;
use outputs::calibration_guard::GuardError;
use outputs::export::ExportError;
use outputs::noise::NoiseError;
use pyo3::exceptions::PyException;
use pyo3::prelude::*;
use recording::output_file::OutputFileError;
use recording::session::import::ImportError;
use recording::session::logs::LogError;
use recording::session::segment::SegmentError;
use recording::session::RecordingError;
use shared::chain::Chain;
use std::path::PathBuf;

pyo3::create_exception!(
    accelcal,
    Error,
    PyException,
    "Every error of accelcal. `__cause__` holds what caused it, where something did (an OSError \
     for a file the system could not read)."
);
pyo3::create_exception!(
    accelcal,
    InputError,
    Error,
    "The input cannot be used as given: an argument, an array's shape or unit, a logger file's \
     contents."
);
pyo3::create_exception!(
    accelcal,
    CalibrationError,
    Error,
    "The data were read but give no calibration: too few positions, a refused gyro fit, an \
     estimate that fails its plausibility checks."
);
pyo3::create_exception!(
    accelcal,
    FileError,
    Error,
    "A file could not be read or written (or would be replaced without force=True)."
);

/// Adds the exception types to the module.
pub fn register(m: &Bound<'_, PyModule>) -> PyResult<()> {
    let py = m.py();
    m.add("Error", py.get_type::<Error>())?;
    m.add("InputError", py.get_type::<InputError>())?;
    m.add("CalibrationError", py.get_type::<CalibrationError>())?;
    m.add("FileError", py.get_type::<FileError>())?;
    Ok(())
}

/// Every failure of the package, typed; each domain error kept whole (its `source()` chain too).
#[derive(Debug, thiserror::Error)]
pub enum PyAccelErr {
    /// The options that say how to read a log.
    #[error(transparent)]
    LogInput(#[from] LogInputError),
    /// A logger's file (any format).
    #[error(transparent)]
    Log(#[from] LogError),
    /// Arrays read as a logger's rows.
    #[error(transparent)]
    Import(#[from] ImportError),
    /// Cutting a recording into a session.
    #[error(transparent)]
    Segment(#[from] InMemoryError),
    /// Writing a session.
    #[error(transparent)]
    Write(#[from] WriteError),
    /// The calibrate use case.
    #[error(transparent)]
    Calibrate(#[from] CalibrateError),
    /// The estimator.
    #[error(transparent)]
    Estimate(#[from] EstimateError),
    /// A session directory.
    #[error(transparent)]
    Recording(#[from] RecordingError),
    /// A session's `gyro.toml`.
    #[error(transparent)]
    HandGyro(#[from] HandGyroFileError),
    /// A unit file (`calibration.toml`).
    #[error(transparent)]
    Unit(#[from] UnitFileError),
    /// Writing the calibration files.
    #[error(transparent)]
    Output(#[from] OutputError),
    /// Another tool's format.
    #[error(transparent)]
    Export(#[from] ExportError),
    /// A noise analysis (`noise.json`).
    #[error(transparent)]
    Noise(#[from] NoiseError),
    /// The device's compensation over arrays.
    #[error(transparent)]
    Apply(#[from] ApplyError),
    /// The virtual rate table.
    #[error(transparent)]
    Simulation(#[from] SimulationError),
    /// A file.
    #[error("{}", .path.display())]
    Io {
        /// The file.
        path: PathBuf,
        /// The cause.
        source: std::io::Error,
    },
    /// A `calibration.bin`.
    #[error("{}", .path.display())]
    Blob {
        /// The file.
        path: PathBuf,
        /// The cause.
        source: shared::blob::BlobError,
    },
    /// An argument of the package's own functions that cannot be used (no cause below it).
    #[error("{0}")]
    Argument(String),
}

/// Which of the package's exceptions an error is.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
enum Kind {
    Input,
    Calibration,
    File,
}

impl PyAccelErr {
    fn kind(&self) -> Kind {
        use PyAccelErr as E;
        match self {
            E::LogInput(_) | E::Apply(_) | E::Argument(_) => Kind::Input,
            // A gyro whose turns are 57× (or 1/57 of) gravity's is read in the wrong unit.
            E::Segment(InMemoryError::HandGyro(HandGyroFileError::Unit(_)))
            | E::HandGyro(HandGyroFileError::Unit(_)) => Kind::Input,
            E::Log(LogError::Io { .. }) | E::Import(ImportError::Io { .. }) => Kind::File,
            E::Log(_) | E::Import(_) => Kind::Input,
            // A vehicle's corrected samples, or face labels the data contradict, are the wrong
            // input; every other refusal of the segmentation (no still position, too few
            // positions) is data that give no calibration.
            E::Segment(InMemoryError::Segment(
                SegmentError::AlreadyCorrected(_)
                | SegmentError::FaceLabelCount { .. }
                | SegmentError::FaceMissing(_)
                | SegmentError::FaceLabelContradicted { .. },
            )) => Kind::Input,
            E::Segment(_) | E::HandGyro(_) | E::Estimate(_) | E::Export(_) | E::Noise(_) => {
                Kind::Calibration
            }
            E::Calibrate(CalibrateError::Recording(_)) => Kind::File,
            E::Calibrate(_) => Kind::Calibration,
            E::Simulation(SimulationError::Unit(_)) => Kind::File,
            E::Simulation(_) => Kind::Input,
            E::Write(_) | E::Recording(_) | E::Unit(_) | E::Output(_) => Kind::File,
            E::Io { .. } | E::Blob { .. } => Kind::File,
        }
    }

    /// The message in Python's words where the domain error's own names a command-line flag.
    fn python_message(&self) -> String {
        match self {
            PyAccelErr::Segment(InMemoryError::GyroRefused(problems)) => format!(
                "the gyro fit is refused, nothing returned:\n  - {}\nfix the columns, signs, unit \
                 or time base named above; to use the accelerometer alone, give no_gyro=True",
                problems.join("\n  - ")
            ),
            PyAccelErr::Apply(ApplyError::Guard(GuardError::NoTemperature { .. })) => {
                "the calibration has a temperature \
                 model but no temperature was given: give temp_c=C (one temperature, or one per \
                 row; the model's error grows with the distance from the real temperature)"
                    .to_string()
            }
            PyAccelErr::Apply(
                e @ (ApplyError::Guard(GuardError::RestRate { .. })
                | ApplyError::GyroNeverAtRest { .. }),
            ) => {
                format!(
                    "{}; give the gyro's unit with gyro_unit=\"deg/s\" or gyro_unit=\"rad/s\"",
                    Chain(e)
                )
            }
            PyAccelErr::Output(OutputError::Exists(path))
            | PyAccelErr::Recording(RecordingError::Exists(path))
            | PyAccelErr::Write(WriteError::Session(RecordingError::Exists(path)))
            | PyAccelErr::Write(WriteError::Gyro(OutputFileError::Exists(path))) => format!(
                "{} already exists: choose another directory or replace it (force=True)",
                path.display()
            ),
            e => Chain(e).to_string(),
        }
    }
}

/// The Python exception of one cause: Python's own `OSError` subclass for an operating-system
/// error, else [`Error`].
fn cause_to_py(e: &(dyn std::error::Error + 'static)) -> PyErr {
    match e.downcast_ref::<std::io::Error>() {
        Some(io) => PyErr::from(std::io::Error::new(io.kind(), Chain(io).to_string())),
        None => Error::new_err(Chain(e).to_string()),
    }
}

impl From<PyAccelErr> for PyErr {
    fn from(e: PyAccelErr) -> PyErr {
        let message = e.python_message();
        let top = match e.kind() {
            Kind::Input => InputError::new_err(message),
            Kind::Calibration => CalibrationError::new_err(message),
            Kind::File => FileError::new_err(message),
        };
        Python::attach(|py| {
            // Each cause below the error, innermost last, as the `__cause__` of the one above it.
            let mut causes = Vec::new();
            let mut next = std::error::Error::source(&e);
            while let Some(s) = next {
                causes.push(cause_to_py(s));
                next = s.source();
            }
            let mut below: Option<PyErr> = None;
            for cause in causes.into_iter().rev() {
                cause.set_cause(py, below.take());
                below = Some(cause);
            }
            top.set_cause(py, below);
        });
        top
    }
}

/// `?` for any error of the package: the value, or the Python exception of its error.
pub trait IntoPy<T> {
    /// The value, or the Python exception of its error.
    fn py_err(self) -> PyResult<T>;
}

impl<T, E: Into<PyAccelErr>> IntoPy<T> for Result<T, E> {
    fn py_err(self) -> PyResult<T> {
        self.map_err(|e| PyErr::from(e.into()))
    }
}

/// An argument the package refuses: [`InputError`] with `text`.
pub fn usage(text: impl Into<String>) -> PyErr {
    PyAccelErr::Argument(text.into()).into()
}
