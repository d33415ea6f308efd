//! `accelcal._accelcal`: the Python package's compiled half. Every function calls `host`'s
//! application layer and domain modules, as the command line does (no second implementation, and
//! nothing of the command line itself: typed options, not flags); the Python half
//! (`accelcal/__init__.py`) adds pandas DataFrames and keyword conveniences. `spelling` holds the
//! keyword arguments' names, handed to the crates below so that a refusal names Python's argument.

mod calibration;
mod errors;
mod noise_arg;
mod session;
mod signals;
mod spelling;

use pyo3::prelude::*;

#[pymodule]
fn _accelcal(m: &Bound<'_, PyModule>) -> PyResult<()> {
    errors::register(m)?;
    m.add_class::<session::Session>()?;
    m.add_class::<calibration::Calibration>()?;
    m.add_class::<session::LogOptions>()?;
    m.add_class::<session::SessionOptions>()?;
    m.add_function(wrap_pyfunction!(session::segment_arrays, m)?)?;
    m.add_function(wrap_pyfunction!(session::segment_file, m)?)?;
    m.add_function(wrap_pyfunction!(session::load_session, m)?)?;
    m.add_function(wrap_pyfunction!(calibration::calibrate, m)?)?;
    m.add_function(wrap_pyfunction!(signals::apply, m)?)?;
    m.add_function(wrap_pyfunction!(signals::allan, m)?)?;
    m.add_function(wrap_pyfunction!(signals::simulate_hand, m)?)?;
    m.add_function(wrap_pyfunction!(signals::simulate, m)?)?;
    Ok(())
}
