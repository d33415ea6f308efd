//! `Calibration.export(noise=…)`'s argument: a path to `host noise`'s `noise.json`, or the result
//! of `accelcal.allan` on the six still signals `host noise` analyses. Either way Kalibr's figures
//! come from `outputs::noise` (the file's, or [`outputs::noise::kalibr_figures`] of the curves'
//! terms), as `host export --noise` takes them.

use crate::errors::IntoPy;
use outputs::export::kalibr::KalibrNoise;
use outputs::noise::{kalibr_figures, AXES};
use pyo3::exceptions::{PyTypeError, PyValueError};
use pyo3::prelude::*;
use pyo3::types::{PyDict, PyList};
use std::path::PathBuf;

/// What `noise=` accepts, for the messages.
const ACCEPTED: &str = "a path to host noise's noise.json, or accelcal.allan()'s result of the \
    six still signals as columns (accel x, y, z in m/s², gyro x, y, z in rad/s)";

/// Kalibr's noise figures of `noise`.
pub fn kalibr_noise(noise: &Bound<'_, PyAny>) -> PyResult<KalibrNoise> {
    if let Ok(d) = noise.cast::<PyDict>() {
        return from_allan(d);
    }
    match noise.extract::<PathBuf>() {
        Ok(path) => outputs::noise::load_kalibr_noise(&path).py_err(),
        Err(_) => Err(PyTypeError::new_err(format!(
            "noise must be {ACCEPTED}; got {}",
            noise.get_type().name()?
        ))),
    }
}

/// The figures of `allan(x, rate_hz)` where `x` is (n, 6) in [`AXES`] order.
fn from_allan(d: &Bound<'_, PyDict>) -> PyResult<KalibrNoise> {
    let item = |key: &str| {
        d.get_item(key)?.ok_or_else(|| {
            PyTypeError::new_err(format!(
                "noise is a dict without '{key}': noise must be {ACCEPTED}"
            ))
        })
    };
    let rate_hz: f64 = item("rate_hz")?.extract()?;
    let (white, walk) = (item("white_density")?, item("random_walk")?);
    let columns = |term: &Bound<'_, PyAny>| -> PyResult<Vec<Option<f64>>> {
        let Ok(list) = term.cast::<PyList>() else {
            return Err(PyValueError::new_err(format!(
                "noise is allan()'s result of one signal: Kalibr's figures need the six still \
                 signals as columns ({}), accel in m/s² and gyro in rad/s",
                AXES.join(", ")
            )));
        };
        list.iter()
            .map(|t| t.get_item("value")?.extract())
            .collect()
    };
    let (white, walk) = (columns(&white)?, columns(&walk)?);
    if white.len() != AXES.len() || walk.len() != AXES.len() {
        return Err(PyValueError::new_err(format!(
            "noise is allan()'s result of {} signals: Kalibr's figures need the six still signals \
             as columns ({}), accel in m/s² and gyro in rad/s",
            white.len(),
            AXES.join(", ")
        )));
    }
    let pairs = std::array::from_fn(|j| (white[j], walk[j]));
    Ok(kalibr_figures(rate_hz, &pairs, true))
}
