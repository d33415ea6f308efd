//! `segment`, `segment_file`, `load_session` and the `Session` they give: a hand-held recording cut
//! into still positions by `host segment`'s own steps (`app::handheld`), or a recorded
//! session directory read by `host calibrate --input`'s reader.

use crate::errors::{usage, IntoPy, PyAccelErr};
use app::handheld::gyro as hand_gyro;
use app::handheld::{segment_recording, SegmentChoices, SegmentedSession};
use app::log_input::LogInput;
use estimator::estimate::gyro::GyroEstimate;
use numpy::ndarray::{ArrayView1, ArrayView2};
use numpy::{PyReadonlyArray1, PyReadonlyArray2};
use pyo3::prelude::*;
use pyo3::types::PyDict;
use recording::session::coverage::face_label;
use recording::session::from_recording::{normal_gravity_m_s2, SIX_FACE_PRIOR_DEG};
use recording::session::import::MAX_ROWS;
use recording::session::import::{read_logger, ImportError, Recording, DEFAULT_COLUMNS};
use recording::session::logs::{read_log_keeping, text_notes, DEFAULT_MAX_SAMPLES};
use recording::session::note::Note;
use recording::session::segment::{IntervalKind, SegmentOptions, StillThreshold};
use recording::session::{read_session, Plan, ReadOptions, SegmentStats};
use std::io::{BufReader, Read};
use std::path::{Path, PathBuf};

/// What a session holds.
enum Inner {
    /// Segmented in memory (`segment`, `segment_file`).
    Memory(Box<SegmentedSession>),
    /// Read from a session directory (`load_session`): what `host calibrate --input` reads.
    Read { dir: PathBuf, parts: Box<Parts> },
}

/// A calibration session: the plan (one static segment per still position), the per-segment
/// statistics, and the gyro fitted from the hand turns. Give it to `calibrate`.
#[pyclass(module = "accelcal", frozen)]
pub struct Session {
    inner: Inner,
}

/// What `calibrate` needs from a session.
#[derive(Clone)]
pub struct Parts {
    /// The plan.
    pub plan: Plan,
    /// Per segment.
    pub stats: Vec<SegmentStats>,
    /// The hand-turn gyro (`gyro.toml`), used when the plan does not estimate the gyro.
    pub gyro: Option<GyroEstimate>,
    /// The reader's warnings, which `host calibrate --input` adds to its result.
    pub reader_warnings: Vec<String>,
}

impl Session {
    /// The plan, statistics and gyro exactly as `host calibrate --input` gets them from the session
    /// directory `host segment` writes (the statistics are computed here, without the GIL).
    pub fn parts(&self) -> PyResult<Parts> {
        match &self.inner {
            Inner::Memory(s) => Ok(Parts {
                plan: s.plan.clone(),
                stats: s.stats(),
                gyro: s.gyro_estimate().py_err()?,
                reader_warnings: Vec::new(),
            }),
            Inner::Read { parts, .. } => Ok((**parts).clone()),
        }
    }

    fn plan(&self) -> &Plan {
        match &self.inner {
            Inner::Memory(s) => &s.plan,
            Inner::Read { parts, .. } => &parts.plan,
        }
    }
}

#[pymethods]
impl Session {
    /// The session's plan as `plan.toml` text.
    fn plan_toml(&self) -> String {
        self.plan().to_toml()
    }

    /// Sample rate of the plan, Hz.
    #[getter]
    fn rate_hz(&self) -> f64 {
        self.plan().sample_rate_hz
    }

    /// The accelerometer's unit (the calibration's output unit): "m/s2", "g", "LSB" or "V".
    #[getter]
    fn acc_unit(&self) -> &'static str {
        self.plan().output_unit.symbol()
    }

    /// The segments' names, in plan order.
    #[getter]
    fn segments(&self) -> Vec<String> {
        self.plan()
            .segments
            .iter()
            .map(|s| s.name.clone())
            .collect()
    }

    /// Warnings of the reader (rows left out, a cut-short file, time jumps).
    #[getter]
    fn warnings(&self) -> Vec<String> {
        match &self.inner {
            Inner::Memory(s) => s.warnings.clone(),
            Inner::Read { parts, .. } => parts.reader_warnings.clone(),
        }
    }

    /// How to make a better session, when the positions are too few or too alike (else None).
    #[getter]
    fn advice(&self) -> Option<String> {
        match &self.inner {
            Inner::Memory(s) => s.advice.clone(),
            Inner::Read { .. } => None,
        }
    }

    /// The still intervals and spins found (a segmented session; empty for a directory read): one
    /// dict each with kind, start_s, duration_s, direction (rough up, body axes), rows.
    fn intervals<'py>(&self, py: Python<'py>) -> PyResult<Vec<Bound<'py, PyDict>>> {
        let Inner::Memory(s) = &self.inner else {
            return Ok(Vec::new());
        };
        let seg = &s.segmentation;
        seg.stills
            .iter()
            .chain(&seg.spins)
            .map(|iv| {
                let d = PyDict::new(py);
                let kind = match iv.kind {
                    IntervalKind::Still => "static",
                    IntervalKind::Spin => "spin",
                };
                d.set_item("kind", kind)?;
                d.set_item("start_s", iv.start_s)?;
                d.set_item("duration_s", iv.duration_s)?;
                d.set_item("direction", iv.direction.to_vec())?;
                d.set_item("rows", iv.end - iv.start)?;
                Ok(d)
            })
            .collect()
    }

    /// The gyro fitted from the hand turns (None without one): matrix G (w = G·ω + b), its 1σ,
    /// bias b and its 1σ in rad/s, the number of turns and the rms misfit in degrees.
    fn gyro<'py>(&self, py: Python<'py>) -> PyResult<Option<Bound<'py, PyDict>>> {
        let Inner::Memory(s) = &self.inner else {
            return Ok(None);
        };
        let Ok(fit) = &s.gyro else { return Ok(None) };
        let d = PyDict::new(py);
        let m = |a: &[[f64; 3]; 3]| a.iter().map(|r| r.to_vec()).collect::<Vec<_>>();
        d.set_item("matrix", m(&fit.matrix))?;
        d.set_item("matrix_1sigma", m(&fit.matrix_1sigma))?;
        d.set_item("bias_rad_s", fit.bias_rad_s.to_vec())?;
        d.set_item("bias_rad_s_1sigma", fit.bias_1sigma_rad_s.to_vec())?;
        d.set_item("turns", fit.turns)?;
        d.set_item("rms_residual_deg", fit.rms_residual_deg)?;
        Ok(Some(d))
    }

    /// Writes the session as `host segment` does (plan.toml, samples.csv, gyro.toml), for
    /// `host calibrate --input DIR`; refuses an existing session unless force. Returns the rows written.
    #[pyo3(signature = (dir, force = false))]
    fn write(&self, py: Python<'_>, dir: PathBuf, force: bool) -> PyResult<u64> {
        match &self.inner {
            Inner::Memory(s) => py.detach(|| s.write(&dir, force)).py_err(),
            Inner::Read { dir: from, .. } => Err(usage(format!(
                "this session was read from {}: it is already written",
                from.display()
            ))),
        }
    }

    fn __repr__(&self) -> String {
        let p = self.plan();
        format!(
            "Session({} segments, {} Hz, {})",
            p.segments.len(),
            p.sample_rate_hz,
            p.output_unit.symbol()
        )
    }
}

/// How to read a logger's file or arrays (`host segment`'s input options, as keywords): the
/// columns, the time, the units, raw counts' offset and scale, the IMU of a binary log.
#[pyclass(module = "accelcal", frozen, get_all)]
#[derive(Clone, Debug)]
pub struct LogOptions {
    /// Accelerometer unit: "m/s2", "g", "LSB" or "V" (text files and arrays).
    pub acc_unit: Option<String>,
    /// Gyro unit: "deg/s", "rad/s" or "LSB" (with gyro_lsb_per_dps).
    pub gyro_unit: Option<String>,
    /// The six column names, acc x, y, z then gyro x, y, z (text files).
    pub columns: Option<Vec<String>>,
    /// The time column (text files; else rate_hz).
    pub time_column: Option<String>,
    /// The time column's unit: "s", "ms", "us", "ns" (default: detected).
    pub time_unit: Option<String>,
    /// The sample rate, Hz, of a text file without a time column.
    pub rate_hz: Option<f64>,
    /// Raw counts' zero force, one value or one per axis.
    pub acc_offset: Option<Vec<f64>>,
    /// A gyro in counts: counts per °/s.
    pub gyro_lsb_per_dps: Option<f64>,
    /// A gyro in counts: the counts of zero rate, one value or one per axis.
    pub gyro_offset: Option<Vec<f64>>,
    /// A text file's temperature column, °C.
    pub temp_column: Option<String>,
    /// ULog or DataFlash: which IMU.
    pub instance: Option<u8>,
    /// MCAP: which Imu topic.
    pub topic: Option<String>,
    /// Text files: lines before the header to skip (`host segment --skip-lines`).
    pub skip_lines: Option<u64>,
}

#[pymethods]
impl LogOptions {
    #[new]
    #[pyo3(signature = (*, acc_unit = None, gyro_unit = None, columns = None, time_column = None,
        time_unit = None, rate_hz = None, acc_offset = None, gyro_lsb_per_dps = None,
        gyro_offset = None, temp_column = None, instance = None, topic = None, skip_lines = None))]
    #[allow(clippy::too_many_arguments)]
    fn new(
        acc_unit: Option<String>,
        gyro_unit: Option<String>,
        columns: Option<Vec<String>>,
        time_column: Option<String>,
        time_unit: Option<String>,
        rate_hz: Option<f64>,
        acc_offset: Option<Vec<f64>>,
        gyro_lsb_per_dps: Option<f64>,
        gyro_offset: Option<Vec<f64>>,
        temp_column: Option<String>,
        instance: Option<u32>,
        topic: Option<String>,
        skip_lines: Option<u64>,
    ) -> PyResult<Self> {
        let instance = instance
            .map(u8::try_from)
            .transpose()
            .map_err(|_| usage("instance is an IMU's number in the log, 0 to 255"))?;
        Ok(LogOptions {
            acc_unit,
            gyro_unit,
            columns,
            time_column,
            time_unit,
            rate_hz,
            acc_offset,
            gyro_lsb_per_dps,
            gyro_offset,
            temp_column,
            instance,
            topic,
            skip_lines,
        })
    }

    fn __repr__(&self) -> String {
        format!("{self:?}").replacen("LogOptions {", "LogOptions(", 1)
    }
}

impl LogOptions {
    /// The application layer's options, named as keywords in its messages.
    fn input(&self) -> LogInput {
        LogInput {
            columns: self
                .columns
                .clone()
                .unwrap_or_else(|| DEFAULT_COLUMNS.map(String::from).to_vec()),
            time_column: self.time_column.clone(),
            time_unit: self.time_unit.clone(),
            rate_hz: self.rate_hz,
            acc_unit: self.acc_unit.clone(),
            acc_offset: self.acc_offset.clone(),
            gyro_unit: self.gyro_unit.clone(),
            gyro_lsb_per_dps: self.gyro_lsb_per_dps,
            gyro_offset: self.gyro_offset.clone(),
            temp_column: self.temp_column.clone(),
            skip_lines: self.skip_lines,
            instance: self.instance,
            topic: self.topic.clone(),
            spelling: crate::spelling::KEYWORDS,
        }
    }
}

/// How to cut a recording into a session (`host segment`'s options that do not name the input):
/// the shortest still position, the unit's id, the site's gravity, the gyro fit, a six-face prior.
#[pyclass(module = "accelcal", frozen, get_all)]
#[derive(Clone, Debug)]
pub struct SessionOptions {
    /// Shortest still position kept, s.
    pub min_still_s: f64,
    /// The unit's id, 24 hex digits.
    pub unit_id: Option<String>,
    /// The site's gravity, m/s².
    pub gravity: Option<f64>,
    /// The site's latitude, degrees (its normal gravity).
    pub latitude: Option<f64>,
    /// The site's height, m (with latitude).
    pub height_m: Option<f64>,
    /// Leave the gyro out.
    pub no_gyro: bool,
    /// A six-face session's prior on its faces, degrees.
    pub face_sigma_deg: f64,
    /// The faces as the user labels them, one per still position in order (`x+` … `z-`).
    pub faces: Option<Vec<String>>,
    /// Samples of each stream held in memory at once from a file (`host segment --max-samples`).
    pub max_samples: Option<usize>,
    /// Fixed limits on a still window's spread, (mg, °/s) (`host segment --still-threshold`).
    pub still_threshold: Option<(f64, f64)>,
}

#[pymethods]
impl SessionOptions {
    #[new]
    #[pyo3(signature = (*, min_still_s = 1.0, unit_id = None, gravity = None, latitude = None,
        height_m = None, no_gyro = false, face_sigma_deg = SIX_FACE_PRIOR_DEG, faces = None,
        max_samples = None, still_threshold = None))]
    // One argument per Python keyword, as LogOptions' constructor.
    #[allow(clippy::too_many_arguments)]
    fn new(
        min_still_s: f64,
        unit_id: Option<String>,
        gravity: Option<f64>,
        latitude: Option<f64>,
        height_m: Option<f64>,
        no_gyro: bool,
        face_sigma_deg: f64,
        faces: Option<Vec<String>>,
        max_samples: Option<usize>,
        still_threshold: Option<(f64, f64)>,
    ) -> Self {
        SessionOptions {
            max_samples,
            still_threshold,
            min_still_s,
            unit_id,
            gravity,
            latitude,
            height_m,
            no_gyro,
            face_sigma_deg,
            faces,
        }
    }

    fn __repr__(&self) -> String {
        format!("{self:?}").replacen("SessionOptions {", "SessionOptions(", 1)
    }
}

impl SessionOptions {
    /// The choices, checked as `host segment` checks its flags.
    fn choices(&self) -> PyResult<SegmentChoices> {
        if self.height_m.is_some() && self.latitude.is_none() {
            return Err(usage(
                "height_m needs latitude (the site's gravity comes from both)",
            ));
        }
        if self.gravity.is_some() && self.latitude.is_some() {
            return Err(usage("give gravity or latitude, not both"));
        }
        let unit_id = match &self.unit_id {
            Some(hex) if shared::UnitId::parse_hex(hex).is_none() => {
                return Err(usage(format!(
                    "unit_id {hex}: give the unit's id as 24 hex digits"
                )))
            }
            id => id.as_ref().map(|h| h.to_ascii_lowercase()),
        };
        let gravity_m_s2 = match (self.gravity, self.latitude) {
            (Some(g), _) => g,
            (None, Some(lat)) => normal_gravity_m_s2(lat, self.height_m.unwrap_or(0.0)),
            (None, None) => shared::STANDARD_GRAVITY_M_S2,
        };
        let faces = match &self.faces {
            Some(labels) => Some(
                labels
                    .iter()
                    .map(|l| {
                        face_label(l).ok_or_else(|| {
                            usage(format!(
                                "faces: '{l}' is not a face; use \"x+\", \"x-\", \"y+\", \"y-\", \"z+\" or \"z-\""
                            ))
                        })
                    })
                    .collect::<PyResult<Vec<_>>>()?,
            ),
            None => None,
        };
        let still_threshold = match self.still_threshold {
            Some((mg, dps)) if mg > 0.0 && mg <= 1000.0 && dps > 0.0 && dps <= 100.0 => {
                Some(StillThreshold {
                    acc_mg: mg,
                    gyro_deg_s: dps,
                })
            }
            Some((mg, dps)) => {
                return Err(usage(format!(
                    "still_threshold=({mg}, {dps}): give the accelerometer's limit in mg (0–1000) \
                     and the gyro's in °/s (0–100), e.g. (15, 6)"
                )))
            }
            None => None,
        };
        Ok(SegmentChoices {
            segment: SegmentOptions {
                min_still_s: self.min_still_s,
                still_threshold,
                offer_still_threshold: true,
                ..SegmentOptions::new(crate::spelling::KEYWORDS)
            },
            unit_id,
            gravity_m_s2,
            fit_gyro: !self.no_gyro,
            face_sigma_deg: self.face_sigma_deg,
            faces,
        })
    }
}

/// `host segment`'s steps after the options: the recording `read` gives (the import's checks and
/// messages), then the intervals, plan and gyro; the GIL released meanwhile.
fn segmented<F, E>(py: Python<'_>, site: &SessionOptions, read: F) -> PyResult<Session>
where
    F: FnOnce() -> Result<(Recording, Vec<Note>), E> + Send,
    E: Into<PyAccelErr> + Send,
{
    let choices = site.choices()?;
    let (rec, reader_warnings) = py.detach(read).py_err()?;
    let s = py.detach(|| segment_recording(rec, &choices));
    let mut s = s.py_err()?;
    s.warnings.splice(0..0, Note::texts(&reader_warnings));
    Ok(Session {
        inner: Inner::Memory(Box::new(s)),
    })
}

/// The arrays as the rows of a logger's CSV, made one line at a time as the import reads them: the
/// import's every check and message apply unchanged, and ryu's shortest form parses back to the
/// same f64, so the recording holds exactly the arrays' values.
struct ArrayLines<'a> {
    acc: ArrayView2<'a, f64>,
    gyro: ArrayView2<'a, f64>,
    t: Option<ArrayView1<'a, f64>>,
    row: usize,
    line: Vec<u8>,
    pos: usize,
}

impl ArrayLines<'_> {
    fn next_line(&mut self) -> bool {
        let mut fmt = ryu::Buffer::new();
        self.line.clear();
        self.pos = 0;
        if self.row == 0 {
            let mut names: Vec<&str> = self.t.iter().map(|_| "t").collect();
            names.extend(DEFAULT_COLUMNS);
            self.line.extend_from_slice(names.join(",").as_bytes());
        } else {
            let i = self.row - 1;
            if i >= self.acc.nrows() {
                return false;
            }
            let mut values = Vec::with_capacity(7);
            if let Some(t) = &self.t {
                values.push(t[i]);
            }
            values.extend((0..3).map(|j| self.acc[(i, j)]));
            values.extend((0..3).map(|j| self.gyro[(i, j)]));
            for (k, v) in values.into_iter().enumerate() {
                if k > 0 {
                    self.line.push(b',');
                }
                self.line.extend_from_slice(fmt.format(v).as_bytes());
            }
        }
        self.line.push(b'\n');
        self.row += 1;
        true
    }
}

impl Read for ArrayLines<'_> {
    fn read(&mut self, out: &mut [u8]) -> std::io::Result<usize> {
        if self.pos == self.line.len() && !self.next_line() {
            return Ok(0);
        }
        let n = out.len().min(self.line.len() - self.pos);
        out[..n].copy_from_slice(&self.line[self.pos..self.pos + n]);
        self.pos += n;
        Ok(n)
    }
}

/// The number of rows of an accelerometer and a gyro array, both (n, 3).
pub fn rows_of_pair(acc: &ArrayView2<'_, f64>, gyro: &ArrayView2<'_, f64>) -> PyResult<usize> {
    let n = acc.nrows();
    if acc.ncols() != 3 || gyro.ncols() != 3 || gyro.nrows() != n {
        return Err(usage(format!(
            "acc and gyro must be arrays of shape (n, 3) with the same n (got {:?} and {:?})",
            acc.shape(),
            gyro.shape()
        )));
    }
    Ok(n)
}

/// Cuts a hand-held recording held in arrays into a session, with `host segment`'s input options
/// (units, raw counts' offset and gyro scale, the time unit) checked as for a file.
#[pyfunction]
#[pyo3(signature = (acc, gyro, t, rate_hz, log, site))]
pub fn segment_arrays(
    py: Python<'_>,
    acc: PyReadonlyArray2<'_, f64>,
    gyro: PyReadonlyArray2<'_, f64>,
    t: Option<PyReadonlyArray1<'_, f64>>,
    rate_hz: Option<f64>,
    log: &LogOptions,
    site: &SessionOptions,
) -> PyResult<Session> {
    let (acc, gyro) = (acc.as_array(), gyro.as_array());
    let t = t.as_ref().map(|t| t.as_array());
    let n = rows_of_pair(&acc, &gyro)?;
    if t.as_ref().is_some_and(|t| t.len() != n) {
        return Err(usage(format!(
            "t has {} values for {n} rows",
            t.map_or(0, |t| t.len())
        )));
    }
    if t.is_some() == rate_hz.is_some() {
        return Err(usage("give exactly one of t (seconds) or rate_hz (Hz)"));
    }
    if log.columns.is_some()
        || log.instance.is_some()
        || log.topic.is_some()
        || log.temp_column.is_some()
    {
        return Err(usage(
            "arrays have no columns, instances or topics: give columns, temp_column, instance \
             and topic to segment_file",
        ));
    }
    if site.max_samples.is_some() {
        return Err(usage(
            "max_samples bounds what is read from a file; arrays are in memory already: leave it \
             out, or give it to segment_file",
        ));
    }
    let input = LogInput {
        time_column: t.map(|_| "t".to_string()),
        rate_hz,
        ..log.input()
    };
    let options = input.import_options().py_err()?;
    let lines = ArrayLines {
        acc,
        gyro,
        t,
        row: 0,
        line: Vec::new(),
        pos: 0,
    };
    segmented(py, site, || {
        let mut rec = read_logger(BufReader::new(lines), Path::new("(arrays)"), &options)?;
        let notes = text_notes(&mut rec, &options);
        Ok::<_, ImportError>((rec, notes))
    })
}

/// Cuts a logger's file into a session: every format `host segment` reads (text, PX4 ULog,
/// ArduPilot DataFlash, ROS 2 MCAP, told by its first bytes), read as `log` says and cut as `site`
/// says.
#[pyfunction]
#[pyo3(signature = (path, log, site))]
pub fn segment_file(
    py: Python<'_>,
    path: PathBuf,
    log: &LogOptions,
    site: &SessionOptions,
) -> PyResult<Session> {
    let source = log.input().source().py_err()?;
    let max = match site.max_samples {
        Some(n) if !(1000..=MAX_ROWS).contains(&n) => {
            return Err(usage(format!("max_samples {n}: give 1000 to {MAX_ROWS}")))
        }
        Some(n) => n,
        None => DEFAULT_MAX_SAMPLES,
    };
    segmented(py, site, || {
        read_log_keeping(&path, &source, max).map(|log| (log.recording, log.warnings))
    })
}

/// Reads a session directory (plan.toml + samples.csv, and gyro.toml when `host segment` wrote
/// one), as `host calibrate --input DIR` does.
#[pyfunction]
pub fn load_session(py: Python<'_>, dir: PathBuf) -> PyResult<Session> {
    let read = py.detach(|| -> Result<_, PyAccelErr> {
        let s = read_session(&dir, &ReadOptions { quiet: true })?;
        let gyro = hand_gyro::read(&dir)?;
        Ok((s, gyro))
    });
    let (s, gyro) = read.py_err()?;
    Ok(Session {
        inner: Inner::Read {
            dir,
            parts: Box::new(Parts {
                plan: s.plan,
                stats: s.stats,
                gyro,
                reader_warnings: Note::texts(&s.report.warnings),
            }),
        },
    })
}
