//! The package's exceptions: `accelcal.Error` and three kinds under it, each carrying the message
//! `host` prints for the same failure (the error enums' `Display`, through the one `CliError`).

use host::cli::CliError;
use pyo3::exceptions::PyException;
use pyo3::prelude::*;

pyo3::create_exception!(
    accelcal,
    Error,
    PyException,
    "Every error of accelcal: the message is the one the `host` command line prints."
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

/// The Python exception of a command-line error, with its message.
pub fn to_py(e: CliError) -> PyErr {
    let text = e.to_string();
    match e {
        CliError::Usage(_) | CliError::Failed(_) | CliError::Plan(_) | CliError::Apply(_) => {
            InputError::new_err(text)
        }
        CliError::Estimate(_)
        | CliError::GyroRefused(_)
        | CliError::HandGyro(_)
        | CliError::ChecksFailed(_)
        | CliError::Export(_)
        | CliError::Noise(_) => CalibrationError::new_err(text),
        CliError::Recording(_)
        | CliError::Unit(_)
        | CliError::Output(_)
        | CliError::Written(_)
        | CliError::Io(..)
        | CliError::Blob(..) => FileError::new_err(text),
        _ => Error::new_err(text),
    }
}

/// `?` for anything the command line turns into a `CliError`.
pub trait IntoPy<T> {
    /// The value, or the Python exception of its error.
    fn py_err(self) -> PyResult<T>;
}

impl<T, E: Into<CliError>> IntoPy<T> for Result<T, E> {
    fn py_err(self) -> PyResult<T> {
        self.map_err(|e| to_py(e.into()))
    }
}

/// An argument the command line would refuse: [`InputError`] with `text`.
pub fn usage(text: impl Into<String>) -> PyErr {
    to_py(CliError::Usage(text.into()))
}
