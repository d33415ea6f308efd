//! `calibrate` and the `Calibration` it gives: the estimate of `host calibrate --input`, its
//! `calibration.toml` and `calibration.bin`, the exports of `host export`, and `Calibration.load`.

use crate::errors::{usage, IntoPy, PyAccelErr};
use crate::session::Session;
use app::{self, CalibrateOptions, CalibrationDocument, Recording};
use clap::ValueEnum;
use estimator::calibration_files::{
    blob_bytes, calibration_unit_file, now_unix_s, write_calibration_files,
};
use estimator::estimate::{CalibrationOutcome, EstimateOptions, Method, ReferenceChoice};
use estimator::unit_file::{UnitFile, UnitFileError};
use numpy::{PyArray1, PyArray2};
use outputs::export::{render, ExportError, ExportFormat, ExportInput, ExportOptions};
use outputs::summary::{file_parameters, CalibrationSummary, Limits, Parameter};
use pyo3::prelude::*;
use pyo3::types::{PyBytes, PyDict};
use shared::blob::ParameterBlob;
use shared::chain::Chain;
use shared::UnitId;
use std::path::PathBuf;

/// A calibration: estimated by `calibrate`, or read by `Calibration.load`.
#[pyclass(module = "accelcal", frozen)]
pub struct Calibration {
    /// The calibration file (`calibration.toml`'s contents).
    unit: UnitFile,
    /// Its parameters, as the device gets them.
    cal: shared::Calibration,
    /// The unit the blob is bound to.
    unit_id: UnitId,
    /// The estimate and its summary, for a calibration estimated here.
    fitted: Option<Box<Fitted>>,
    /// The creation time of a blob read by `load`.
    created_unix_s: Option<u64>,
}

struct Fitted {
    outcome: CalibrationOutcome,
    /// The result as `host calibrate --input --json` gives it (no files: nothing is written).
    document: CalibrationDocument,
}

impl Calibration {
    /// The device's parameters (for `apply`).
    pub fn device(&self) -> &shared::Calibration {
        &self.cal
    }

    fn fit_summary(&self) -> Option<&CalibrationSummary> {
        self.fitted.as_ref().map(|f| &f.document.summary)
    }

    /// Every value with its unit and 1σ, as `host calibrate --json` lists them: the fit's, or for a
    /// loaded calibration the same names from the file (the paper-form values, then its `[gyro]` and
    /// `[temperature]` sections), so that a calibration and the same one loaded list alike.
    fn parameters(&self) -> PyResult<Vec<Parameter>> {
        if let Some(s) = self.fit_summary() {
            return Ok(s.parameters.clone());
        }
        file_parameters(&self.unit, &self.cal)
            .map_err(ExportError::from)
            .py_err()
    }
}

/// One of `names`' values by its name, or [`crate::errors::InputError`] naming the keyword and the
/// names it takes.
pub fn choose<T: Copy>(keyword: &str, given: &str, names: &[(&str, T)]) -> PyResult<T> {
    names
        .iter()
        .find(|(n, _)| *n == given)
        .map(|(_, v)| *v)
        .ok_or_else(|| {
            let all: Vec<&str> = names.iter().map(|(n, _)| *n).collect();
            usage(format!(
                "{keyword}=\"{given}\": use one of {}",
                all.join(", ")
            ))
        })
}

/// An export format by the name `host export` gives it (the enum's own names).
fn export_format(given: &str) -> PyResult<ExportFormat> {
    let names: Vec<(String, ExportFormat)> = ExportFormat::value_variants()
        .iter()
        .filter_map(|v| {
            v.to_possible_value()
                .map(|p| (p.get_name().to_string(), *v))
        })
        .collect();
    let names: Vec<(&str, ExportFormat)> = names.iter().map(|(n, v)| (n.as_str(), *v)).collect();
    choose("format", given, &names)
}

fn json_to_py<'py>(py: Python<'py>, value: &impl serde::Serialize) -> PyResult<Bound<'py, PyAny>> {
    let text = serde_json::to_string(value)
        .map_err(|e| usage(format!("cannot write the JSON result: {}", Chain(&e))))?;
    py.import("json")?.call_method1("loads", (text,))
}

/// Estimates a calibration from a session, as `host calibrate --input` does (the same estimator,
/// options and hand-turn gyro), without writing files. The GIL is released during the fit.
#[pyfunction]
#[pyo3(signature = (
    session, *, method = "joint", reference = "table-axis", single_package = false, limits = None
))]
pub fn calibrate(
    py: Python<'_>,
    session: &Session,
    method: &str,
    reference: &str,
    single_package: bool,
    limits: Option<&Bound<'_, PyDict>>,
) -> PyResult<Calibration> {
    // `single_package`: host calibrate's --single-package (one lever arm for the three
    // accelerometers of one package, docs/model.md §4.7).
    let estimate = EstimateOptions {
        method: choose(
            "method",
            method,
            &[("joint", Method::Joint), ("paper", Method::Paper)],
        )?,
        reference: choose(
            "reference",
            reference,
            &[
                ("table-axis", ReferenceChoice::TableAxis),
                ("centroid", ReferenceChoice::Centroid),
            ],
        )?,
        single_package,
        ..EstimateOptions::new(crate::spelling::KEYWORDS)
    }
    .drift_aware();
    let limits: Limits = match limits {
        Some(d) => {
            let text: String = py.import("json")?.call_method1("dumps", (d,))?.extract()?;
            serde_json::from_str(&text).map_err(|e| usage(format!("limits: {}", Chain(&e))))?
        }
        None => Limits::default(),
    };
    let options = CalibrateOptions { estimate, limits };
    let parts = py.detach(|| session.parts());
    let parts = parts?;
    // The one calibrate use case, as `host calibrate --input` (the hand turns' gyro included).
    let calibrated = py.detach(|| {
        app::calibrate_recording(
            Recording {
                plan: &parts.plan,
                stats: &parts.stats,
                hand_gyro: parts.gyro.as_ref(),
                reader_warnings: &parts.reader_warnings,
            },
            &options,
        )
    });
    let calibrated = calibrated.py_err()?;
    let unit_id = match calibrated.unit_id {
        Some(id) => id,
        None => {
            pyo3::PyErr::warn(
                py,
                &py.get_type::<pyo3::exceptions::PyUserWarning>(),
                c"the session's plan has no unit_id: the blob is bound to the all-zero unit id; give \
                  segment(..., unit_id=\"<24 hex digits>\") to bind it to the unit",
                1,
            )?;
            UnitId::default()
        }
    };
    let app::Calibrated {
        outcome, document, ..
    } = calibrated;
    Ok(Calibration {
        unit: calibration_unit_file(&outcome, Some(unit_id)),
        cal: outcome.calibration,
        unit_id,
        fitted: Some(Box::new(Fitted { outcome, document })),
        created_unix_s: None,
    })
}

#[pymethods]
impl Calibration {
    /// Reads a calibration: `calibration.toml` (any unit file) or `calibration.bin` (a device blob).
    #[staticmethod]
    fn load(path: PathBuf) -> PyResult<Calibration> {
        if path.extension().is_some_and(|e| e == "bin") {
            let bytes = std::fs::read(&path)
                .map_err(|source| PyAccelErr::Io {
                    path: path.clone(),
                    source,
                })
                .py_err()?;
            let blob = shared::blob::decode(&bytes)
                .map_err(|source| PyAccelErr::Blob {
                    path: path.clone(),
                    source,
                })
                .py_err()?;
            return Ok(Calibration {
                unit: UnitFile::from_calibration(&blob.calibration, Some(blob.unit_id), None),
                cal: blob.calibration,
                unit_id: blob.unit_id,
                fitted: None,
                created_unix_s: Some(blob.created_unix_s),
            });
        }
        let unit = UnitFile::load(&path).py_err()?;
        let invalid = |m| UnitFileError::Invalid(path.clone(), m);
        let cal = unit.to_calibration().map_err(invalid).py_err()?;
        let unit_id = unit.unit_id().map_err(invalid).py_err()?;
        Ok(Calibration {
            unit,
            cal,
            unit_id: unit_id.unwrap_or_default(),
            fitted: None,
            created_unix_s: None,
        })
    }

    /// `calibration.toml` exactly as `host calibrate` writes it.
    fn to_toml(&self) -> String {
        self.unit.to_toml()
    }

    /// `calibration.bin` exactly as `host calibrate` writes it, stamped `created_unix_s` (default:
    /// now, as the command does; a loaded blob keeps its own).
    #[pyo3(signature = (created_unix_s = None))]
    fn to_blob<'py>(
        &self,
        py: Python<'py>,
        created_unix_s: Option<u64>,
    ) -> PyResult<Bound<'py, PyBytes>> {
        let created = created_unix_s
            .or(self.created_unix_s)
            .unwrap_or_else(now_unix_s);
        let bytes = match &self.fitted {
            Some(f) => blob_bytes(&f.outcome, self.unit_id, created),
            None => ParameterBlob {
                unit_id: self.unit_id,
                calibration: self.cal,
                created_unix_s: created,
            }
            .to_bytes()
            .map(|(b, n)| b[..n].to_vec()),
        };
        let bytes = bytes
            .map_err(estimator::calibration_files::OutputError::Blob)
            .py_err()?;
        Ok(PyBytes::new(py, &bytes))
    }

    /// Writes `calibration.toml` and `calibration.bin` into `dir` as `host calibrate` does (as a pair,
    /// atomically; an existing pair is replaced only with force). Returns their paths.
    #[pyo3(signature = (dir, force = false))]
    fn save(&self, dir: PathBuf, force: bool) -> PyResult<(PathBuf, PathBuf)> {
        let Some(f) = &self.fitted else {
            return Err(usage(
                "save() writes an estimated calibration; a loaded one is already in its file",
            ));
        };
        let w = write_calibration_files(&dir, &f.outcome, self.unit_id, now_unix_s(), force)
            .py_err()?;
        Ok((w.toml_path, w.bin_path))
    }

    /// The calibration in another tool's format, as `host export --format FORMAT` writes it (the
    /// same keyword options as its flags). `c` gives a dict of file name → text (the package), `c-header` its header alone.
    /// `noise` is `--noise`'s noise.json, or `allan()`'s result of the same six still signals.
    #[pyo3(signature = (format, *, noise = None, rostopic = "/imu0", driver_scale = None,
        device_id = None, gyro_device_id = None, sysid = 1, compid = 1,
        allow_out_of_range = false, allow_undetermined = false))]
    #[allow(clippy::too_many_arguments)]
    fn export<'py>(
        &self,
        py: Python<'py>,
        format: &str,
        noise: Option<Bound<'py, PyAny>>,
        rostopic: &str,
        driver_scale: Option<f64>,
        device_id: Option<u32>,
        gyro_device_id: Option<u32>,
        sysid: u8,
        compid: u8,
        allow_out_of_range: bool,
        allow_undetermined: bool,
    ) -> PyResult<Bound<'py, PyAny>> {
        let format = export_format(format)?;
        let noise = noise
            .as_ref()
            .map(crate::noise_arg::kalibr_noise)
            .transpose()?;
        let input = ExportInput {
            unit: &self.unit,
            cal: self.cal,
            noise: noise.as_ref(),
            rostopic,
            driver_scale_m_s2_per_out: driver_scale,
            options: ExportOptions {
                allow_out_of_range,
                allow_undetermined,
                device_id,
                gyro_device_id,
                slot: None,
                gyro_slot: None,
                sysid,
                compid,
                spelling: crate::spelling::KEYWORDS,
            },
        };
        if format == ExportFormat::C {
            let files = outputs::export::c::package(&input).py_err()?;
            let d = PyDict::new(py);
            for (name, text) in files {
                d.set_item(name, text)?;
            }
            return Ok(d.into_any());
        }
        Ok(render(&input, format)
            .py_err()?
            .into_pyobject(py)?
            .into_any())
    }

    /// `host calibrate --json`'s document (parameters with 1σ, the calibration file, χ², checks,
    /// warnings) as a dict; None for a loaded calibration.
    #[getter]
    fn summary<'py>(&self, py: Python<'py>) -> PyResult<Option<Bound<'py, PyAny>>> {
        self.fitted
            .as_ref()
            .map(|f| json_to_py(py, &f.document))
            .transpose()
    }

    /// The calibration file's tables (`calibration.toml` as a dict).
    #[getter]
    fn file<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyAny>> {
        json_to_py(py, &self.unit)
    }

    /// Names of the paper-form parameters: bias_x…, scale_x…, theta_xx…, r1x…, then the gyro's and
    /// the temperature model's when the calibration has them (estimated or loaded alike).
    #[getter]
    fn names(&self) -> PyResult<Vec<String>> {
        Ok(self.parameters()?.into_iter().map(|p| p.name).collect())
    }

    /// The values, in `names` order.
    #[getter]
    fn values<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyArray1<f64>>> {
        let v = self.parameters()?.into_iter().map(|p| p.value).collect();
        Ok(PyArray1::from_vec(py, v))
    }

    /// 1σ of each value (NaN: not determined; for a loaded calibration, the paper-form values'
    /// 1σ, which need the fit's covariance, are NaN, and the sections' are the file's).
    #[getter]
    fn sigmas<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyArray1<f64>>> {
        let v = self
            .parameters()?
            .into_iter()
            .map(|p| p.sigma.unwrap_or(f64::NAN))
            .collect();
        Ok(PyArray1::from_vec(py, v))
    }

    /// Units of the values.
    #[getter]
    fn units(&self) -> PyResult<Vec<String>> {
        Ok(self.parameters()?.into_iter().map(|p| p.unit).collect())
    }

    /// The gyro's G (w = G·ω + b), or None.
    #[getter]
    fn gyro_matrix<'py>(&self, py: Python<'py>) -> PyResult<Option<Bound<'py, PyArray2<f64>>>> {
        self.unit
            .gyro
            .as_ref()
            .map(|g| rows(py, &g.matrix))
            .transpose()
    }

    /// 1σ of G, or None.
    #[getter]
    fn gyro_matrix_1sigma<'py>(
        &self,
        py: Python<'py>,
    ) -> PyResult<Option<Bound<'py, PyArray2<f64>>>> {
        self.unit
            .gyro
            .as_ref()
            .and_then(|g| g.matrix_1sigma)
            .map(|m| rows(py, &m))
            .transpose()
    }

    /// The gyro's bias b, rad/s, or None.
    #[getter]
    fn gyro_bias_rad_s<'py>(&self, py: Python<'py>) -> Option<Bound<'py, PyArray1<f64>>> {
        self.unit
            .gyro
            .as_ref()
            .map(|g| PyArray1::from_slice(py, &g.bias_rad_s))
    }

    /// 1σ of b, rad/s, or None.
    #[getter]
    fn gyro_bias_rad_s_1sigma<'py>(&self, py: Python<'py>) -> Option<Bound<'py, PyArray1<f64>>> {
        self.unit
            .gyro
            .as_ref()
            .and_then(|g| g.bias_rad_s_1sigma)
            .map(|b| PyArray1::from_slice(py, &b))
    }

    /// The temperature model (`[temperature]` of the file as a dict), or None.
    #[getter]
    fn temperature<'py>(&self, py: Python<'py>) -> PyResult<Option<Bound<'py, PyAny>>> {
        self.unit
            .temperature
            .as_ref()
            .map(|t| json_to_py(py, t))
            .transpose()
    }

    /// The estimator's warnings (and the reader's), as `host calibrate` lists them.
    #[getter]
    fn warnings(&self) -> Vec<String> {
        self.fit_summary()
            .map(|s| s.warnings.clone())
            .unwrap_or_default()
    }

    /// The parameters the session did not determine.
    #[getter]
    fn undetermined(&self) -> Vec<String> {
        self.fit_summary()
            .map(|s| s.undetermined.clone())
            .unwrap_or_default()
    }

    /// Σ whitened residual² of the fit (None for a loaded calibration).
    #[getter]
    fn chi2(&self) -> Option<f64> {
        self.fit_summary().map(|s| s.chi2)
    }

    /// Degrees of freedom of the fit.
    #[getter]
    fn dof(&self) -> Option<i64> {
        self.fit_summary().map(|s| s.dof)
    }

    /// χ²/dof.
    #[getter]
    fn chi2_per_dof(&self) -> Option<f64> {
        self.fit_summary().map(|s| s.chi2_per_dof)
    }

    /// The temperature fit's χ²/dof per axis (x, y, z), over every sample of the segments that
    /// determine the model (docs/model.md §9); the largest is checked against the same limit as
    /// `chi2_per_dof`. None without a temperature model, and for a loaded calibration.
    #[getter]
    fn thermal_chi2_per_dof(&self) -> Option<(f64, f64, f64)> {
        let t = self.fit_summary()?.thermal_fit.as_ref()?;
        let [x, y, z] = t.chi2_per_dof;
        Some((x, y, z))
    }

    /// The pass/fail checks passed (all, when no limits were given).
    #[getter]
    fn passed(&self) -> Option<bool> {
        self.fit_summary().map(|s| s.passed)
    }

    /// The unit id the blob is bound to (24 hex digits).
    #[getter]
    fn unit_id(&self) -> String {
        self.unit_id.to_string()
    }

    /// The creation time of a loaded blob, s since the Unix epoch (else None).
    #[getter]
    fn created_unix_s(&self) -> Option<u64> {
        self.created_unix_s
    }

    fn __repr__(&self) -> String {
        match self.fit_summary() {
            Some(s) => format!(
                "Calibration(unit {}, {}, χ²/dof = {:.3}, {} warning(s))",
                self.unit_id,
                self.cal.statics.output_unit.symbol(),
                s.chi2_per_dof,
                s.warnings.len()
            ),
            None => format!(
                "Calibration(unit {}, {}, loaded)",
                self.unit_id,
                self.cal.statics.output_unit.symbol()
            ),
        }
    }
}

fn rows<'py>(py: Python<'py>, m: &[[f64; 3]; 3]) -> PyResult<Bound<'py, PyArray2<f64>>> {
    let v: Vec<Vec<f64>> = m.iter().map(|r| r.to_vec()).collect();
    PyArray2::from_vec2(py, &v).map_err(|e| usage(Chain(&e).to_string()))
}
