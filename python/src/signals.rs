//! `apply` (the device's per-sample compensation, `host apply`), `allan` (`host noise`'s Allan
//! deviation and noise terms), and the simulators of `host simulate-hand` and `host simulate`.

use crate::calibration::{choose, Calibration};
use crate::errors::{usage, IntoPy};
use crate::session::{load_session, rows_of_pair, Session};
use app::simulate::{NoiseChoices, Simulation};
use app::simulate_hand::HandSimulation;
use numpy::ndarray::{Array2, ArrayView1};
use numpy::{IntoPyArray, PyArray1, PyReadonlyArray1, PyReadonlyArray2};
use outputs::apply::Prepared;
use outputs::noise::allan::{curve_and_fit, curve_sizes, TermFit};
use outputs::noise::confidence::relative_sigma;
use pyo3::prelude::*;
use pyo3::types::PyDict;
use recording::session::import::{GyroUnit, Recording};
use shared::compensator::LeverMode;
use std::path::PathBuf;

/// The compensated specific force of each row, g, body axes: every sample through the device's
/// own f32 path (`shared::Compensator` with the firmware's ω̇ estimator, as `host apply` does), the
/// temperature model refreshed at the device's pace. A row with a non-finite value gives NaN and
/// restarts the ω̇ estimate, as on the device. The gyro is in `gyro_unit`; as `host apply` does for
/// a logger's file, the still intervals found in the rows must compensate to 1 g and, with a gyro
/// calibration, rest (a gyro in °/s declared rad/s is refused). With `with_rate`, also the corrected
/// body rate of each row, rad/s (`host apply`'s `w_*` columns).
#[pyfunction]
#[pyo3(signature = (calibration, acc, gyro, rate_hz, *, temp_c = None, lever = "full",
    gyro_unit = "rad/s", with_rate = false))]
#[allow(clippy::too_many_arguments)]
pub fn apply<'py>(
    py: Python<'py>,
    calibration: &Calibration,
    acc: PyReadonlyArray2<'py, f64>,
    gyro: PyReadonlyArray2<'py, f64>,
    rate_hz: f64,
    temp_c: Option<&Bound<'py, PyAny>>,
    lever: &str,
    gyro_unit: &str,
    with_rate: bool,
) -> PyResult<Bound<'py, PyAny>> {
    let mode = choose(
        "lever",
        lever,
        &[
            ("off", LeverMode::Off),
            ("rate", LeverMode::RateOnly),
            ("full", LeverMode::RateAndAcceleration),
        ],
    )?;
    let to_rad_s = GyroUnit::parse(gyro_unit)
        .ok_or_else(|| {
            usage(format!(
                "gyro_unit=\"{gyro_unit}\": use \"deg/s\" or \"rad/s\""
            ))
        })?
        .to_rad_s();
    if !(rate_hz.is_finite() && rate_hz > 0.0) {
        return Err(usage(format!(
            "rate_hz={rate_hz}: give the sample rate in Hz"
        )));
    }
    let (acc, gyro) = (acc.as_array(), gyro.as_array());
    let n = rows_of_pair(&acc, &gyro)?;
    // One temperature for every row, or one per row.
    let temps: Option<Vec<f64>> = match temp_c {
        None => None,
        Some(t) => match t.extract::<f64>() {
            Ok(c) => Some(vec![c; n]),
            Err(_) => Some(
                t.extract::<PyReadonlyArray1<'py, f64>>()?
                    .as_array()
                    .to_vec(),
            ),
        },
    };
    if temps.as_ref().is_some_and(|t| t.len() != n) {
        return Err(usage(format!("temp_c has the wrong length for {n} rows")));
    }
    let cal = calibration.device();
    // The rows as a recording in the calibration's unit, evenly spaced at the rate given.
    let rec = Recording {
        t_s: (0..n).map(|i| i as f64 / rate_hz).collect(),
        acc: (0..n).map(|i| [0, 1, 2].map(|j| acc[(i, j)])).collect(),
        gyro_rad_s: (0..n)
            .map(|i| [0, 1, 2].map(|j| gyro[(i, j)] * to_rad_s))
            .collect(),
        acc_unit: Some(cal.statics.output_unit),
        rate_hz,
        temp_c: temps,
        ..Recording::default()
    };
    let g = cal.gravity_m_s2;
    let done = py.detach(|| {
        let mut out = Array2::<f64>::from_elem((n, 3), f64::NAN);
        let mut rate = Array2::<f64>::from_elem((n, 3), f64::NAN);
        let prepared = Prepared::new(&rec, cal, mode, None, crate::spelling::KEYWORDS)?;
        let summary = prepared.run(&rec, cal, &mut |i, f, applier| {
            if let Some(f) = f {
                let w = applier.rate_rad_s();
                for j in 0..3 {
                    out[(i, j)] = f64::from(f[j]) / g;
                    rate[(i, j)] = f64::from(w[j]);
                }
            }
            Ok(())
        })?;
        Ok::<_, outputs::apply::ApplyError>((out, rate, summary.warnings))
    });
    let (out, rate, warnings) = done.py_err()?;
    for w in warnings {
        let text = std::ffi::CString::new(w.to_string()).unwrap_or_default();
        PyErr::warn(
            py,
            &py.get_type::<pyo3::exceptions::PyUserWarning>(),
            &text,
            1,
        )?;
    }
    let out = out.into_pyarray(py).into_any();
    if with_rate {
        Ok((out, rate.into_pyarray(py)).into_pyobject(py)?.into_any())
    } else {
        Ok(out)
    }
}

fn term_dict<'py>(
    py: Python<'py>,
    value: Option<f64>,
    fit: &TermFit,
) -> PyResult<Bound<'py, PyDict>> {
    let d = PyDict::new(py);
    d.set_item("value", value)?;
    d.set_item("sigma", fit.sigma)?;
    d.set_item("significance", fit.significance)?;
    d.set_item("upper_bound_2sigma", fit.upper_bound_2sigma)?;
    d.set_item("needs_recording_s", fit.needs_recording_s)?;
    Ok(d)
}

/// The overlapping Allan deviation of one signal at octave-spaced τ, its 1σ bounds, and the fitted
/// white noise density N, bias instability B and random walk K, each with its 1σ or, when this
/// recording does not determine it, its 2σ upper bound (`host noise`'s analysis of one axis).
#[pyfunction]
pub fn allan<'py>(
    py: Python<'py>,
    x: PyReadonlyArray1<'py, f64>,
    rate_hz: f64,
) -> PyResult<Bound<'py, PyDict>> {
    if !(rate_hz.is_finite() && rate_hz > 0.0) {
        return Err(usage(format!(
            "rate_hz {rate_hz}: give the sample rate in Hz"
        )));
    }
    let view: ArrayView1<'_, f64> = x.as_array();
    let n = view.len();
    // One NaN would make every τ's deviation NaN: refused, with where it is.
    let bad = view.iter().filter(|v| !v.is_finite()).count();
    if let Some(first) = view.iter().position(|v| !v.is_finite()) {
        return Err(usage(format!(
            "x has {bad} non-finite value(s) (the first at index {first}): the Allan deviation \
             needs an unbroken record; analyse a stretch without them (e.g. the longest run of \
             finite values)"
        )));
    }
    if n < outputs::noise::MIN_SAMPLES {
        return Err(usage(format!(
            "{n} samples: at least {} are needed (record a long still segment)",
            outputs::noise::MIN_SAMPLES
        )));
    }
    // The array itself when it is contiguous; a strided view is copied once.
    let copied;
    let y: &[f64] = match x.as_slice() {
        Ok(s) => s,
        Err(_) => {
            copied = view.to_vec();
            &copied
        }
    };
    let (points, sizes, terms) = py.detach(|| {
        let (points, terms) = curve_and_fit(y, rate_hz);
        (points, curve_sizes(n), terms)
    });
    let rel: Vec<f64> = sizes
        .iter()
        .map(|&m| relative_sigma(n, m).unwrap_or(f64::NAN))
        .collect();
    let adev: Vec<f64> = points.iter().map(|p| p.adev).collect();
    let d = PyDict::new(py);
    d.set_item("rate_hz", rate_hz)?;
    d.set_item(
        "tau_s",
        PyArray1::from_iter(py, points.iter().map(|p| p.tau_s)),
    )?;
    d.set_item("adev", PyArray1::from_slice(py, &adev))?;
    let bound =
        |k: f64| PyArray1::from_iter(py, adev.iter().zip(&rel).map(|(a, r)| a * (1.0 + k * r)));
    d.set_item("adev_low", bound(-1.0))?;
    d.set_item("adev_high", bound(1.0))?;
    d.set_item(
        "terms",
        PyArray1::from_iter(py, points.iter().map(|p| p.terms)),
    )?;
    d.set_item(
        "fit_adev",
        PyArray1::from_iter(py, points.iter().map(|p| terms.adev(p.tau_s))),
    )?;
    d.set_item(
        "white_density",
        term_dict(py, terms.white_density, &terms.fits[0])?,
    )?;
    d.set_item(
        "bias_instability",
        term_dict(py, terms.bias_instability, &terms.fits[1])?,
    )?;
    d.set_item(
        "random_walk",
        term_dict(py, terms.random_walk, &terms.fits[2])?,
    )?;
    Ok(d)
}

/// `host simulate-hand`'s session as arrays (`app::simulate_hand`): t (s), acc (the unit asked,
/// its offset added), gyro (deg/s, rad/s or counts), and the simulated unit's truth as unit-file
/// TOML with its `[gyro]`.
#[pyfunction]
#[pyo3(signature = (seed = 1, rate_hz = 200.0, acc_unit = "m/s2", gyro_unit = "deg/s", *,
    acc_offset = None, gyro_lsb_per_dps = None))]
pub fn simulate_hand<'py>(
    py: Python<'py>,
    seed: u64,
    rate_hz: f64,
    acc_unit: &str,
    gyro_unit: &str,
    acc_offset: Option<f64>,
    gyro_lsb_per_dps: Option<f64>,
) -> PyResult<Bound<'py, PyDict>> {
    let request = HandSimulation {
        seed,
        rate_hz,
        acc_unit: acc_unit.into(),
        acc_offset,
        gyro_unit: gyro_unit.into(),
        gyro_lsb_per_dps,
        six_face_rounds: None,
        table_turns: false,
        spelling: crate::spelling::KEYWORDS,
    };
    let sim = py
        .detach(|| request.run())
        .map_err(|e| usage(shared::chain::Chain(&e).to_string()))?;
    let rows = &sim.session.rows;
    let written: Vec<([f64; 3], [f64; 3])> = rows.iter().map(|r| sim.layout.written(r)).collect();
    let n = rows.len();
    let t = PyArray1::from_iter(py, rows.iter().map(|r| r.0));
    let acc = Array2::from_shape_fn((n, 3), |(i, j)| written[i].0[j]);
    let gyro = Array2::from_shape_fn((n, 3), |(i, j)| written[i].1[j]);
    let d = PyDict::new(py);
    d.set_item("t", t)?;
    d.set_item("acc", acc.into_pyarray(py))?;
    d.set_item("gyro", gyro.into_pyarray(py))?;
    d.set_item("truth_toml", sim.truth_toml())?;
    Ok(d)
}

/// A session on the virtual rate table (`host simulate`: plan.toml, samples.csv, truth.toml in
/// `out`), read back. The keywords are the simulation's typed options.
#[pyfunction]
#[pyo3(signature = (out, *, plan = None, unit = None, seed = 1, force = false, no_noise = false,
    noise_mg = None, lsb = None, drift_mg_sqrt_s = None, tilt_deg = None, rate_scale = None,
    rate_offset_deg_s = None, gyro_noise_deg_s = None, gyro_bias_deg_s = None,
    gyro_scale_ppm = None, gyro_misalignment_deg = None, flicker_mg = None,
    gyro_drift_deg_s_sqrt_s = None, gyro_flicker_deg_s = None))]
#[allow(clippy::too_many_arguments)]
pub fn simulate(
    py: Python<'_>,
    out: PathBuf,
    plan: Option<String>,
    unit: Option<PathBuf>,
    seed: u64,
    force: bool,
    no_noise: bool,
    noise_mg: Option<f64>,
    lsb: Option<f64>,
    drift_mg_sqrt_s: Option<f64>,
    tilt_deg: Option<f64>,
    rate_scale: Option<f64>,
    rate_offset_deg_s: Option<f64>,
    gyro_noise_deg_s: Option<f64>,
    gyro_bias_deg_s: Option<[f64; 3]>,
    gyro_scale_ppm: Option<[f64; 3]>,
    gyro_misalignment_deg: Option<f64>,
    flicker_mg: Option<f64>,
    gyro_drift_deg_s_sqrt_s: Option<f64>,
    gyro_flicker_deg_s: Option<f64>,
) -> PyResult<Session> {
    let simulation = Simulation {
        out: out.clone(),
        unit,
        plan,
        seed,
        force,
        noise: NoiseChoices {
            no_noise,
            noise_mg,
            lsb,
            drift_mg_sqrt_s,
            tilt_deg,
            rate_scale,
            rate_offset_deg_s,
            gyro_noise_deg_s,
            gyro_bias_deg_s,
            gyro_scale_ppm,
            gyro_misalignment_deg,
            flicker_mg,
            gyro_drift_deg_s_sqrt_s,
            gyro_flicker_deg_s,
        },
    };
    py.detach(|| app::simulate::simulate(&simulation, None))
        .py_err()?;
    load_session(py, out)
}
