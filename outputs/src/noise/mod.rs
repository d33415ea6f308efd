//! Noise characterisation (`host noise`): the overlapping Allan deviation of each accelerometer and
//! gyro axis over the longest still segment of a recording, the fitted white noise density, bias
//! instability and random walk ([`allan`]), a table, a log-log figure, and the figures Kalibr needs.
//! Each point's 1σ, for error bars, is [`confidence`]'s (the Python package's `allan`); `kalibr`
//! turns the fitted terms into Kalibr's figures; `accel` turns the accelerometer's outputs into
//! m/s².
//!
//! Input: a session directory (the longest static segment of its plan is used), a bare
//! `samples.csv` (its longest run of rows of one segment is used, assumed still), or a logger's file
//! in any format `host segment` reads (`log`: its longest still interval). Accelerometer
//! outputs are turned into m/s² when a calibration is given (`f = g·K_A·(U − u0)`, paper eq. 6);
//! otherwise they stay in the output unit and Kalibr's accelerometer figures are undetermined.
//!
//! Memory: two passes over the file, each line bounded by [`MAX_LINE_BYTES`] (an endless line is an
//! error after a few kilobytes); the first keeps the segment names (at most [`MAX_SEGMENTS`]), the
//! second only the rows of the segment being read and of the longest so far, at most [`MAX_SAMPLES`]
//! of each (6 × 8 bytes a row, ≤ 2 × 100 MB) — a longer segment is cut, with a warning.

mod accel;
pub mod allan;
pub mod confidence;
mod kalibr;
mod log;

pub use kalibr::{kalibr_figures, load_kalibr_noise, WhiteAndWalk};
pub use log::{analyse_log, is_samples_csv};

use crate::export::kalibr::KalibrNoise;
use crate::export::PlainMatrices;
use crate::note::Note;
use crate::report::plot::{Figure, Panel, Series, SeriesStyle};
use allan::{curve_and_fit, AllanPoint, NoiseTerms};
use recording::limits::{MAX_LINE_BYTES, MAX_SEGMENTS};
use recording::session::{read_samples_each, read_session, Plan, ReadOptions, RecordingError};
use recording::session::{PLAN_FILE, SAMPLES_FILE};
use recording::spelling::Spelling;
use serde::{Deserialize, Serialize};
use shared::OutputUnit;
use std::collections::HashSet;
use std::io::BufReader;
use std::path::{Path, PathBuf};

/// Largest number of rows analysed (2²¹: 35 min at 1 kHz, 100 MB).
pub const MAX_SAMPLES: usize = 1 << 21;
/// Fewest rows that give an Allan curve worth fitting.
pub const MIN_SAMPLES: usize = 64;

/// The axes, in the order of [`NoiseReport::axes`].
pub const AXES: [&str; 6] = [
    "accel_x", "accel_y", "accel_z", "gyro_x", "gyro_y", "gyro_z",
];

/// Why the analysis failed.
#[derive(Debug, thiserror::Error)]
pub enum NoiseError {
    /// The recording could not be read.
    #[error(transparent)]
    Recording(#[from] RecordingError),
    /// No still segment with enough rows.
    #[error("no noise analysis possible: {0}")]
    NoStillData(String),
    /// The logger's file could not be read.
    #[error(transparent)]
    Log(#[from] recording::session::logs::LogError),
    /// The logger's file has no still interval to analyse.
    #[error("no noise analysis possible")]
    NoStill(#[source] recording::session::segment::SegmentError),
    /// A noise file could not be read.
    #[error("cannot use noise file {}", .0.display())]
    File(PathBuf, #[source] std::io::Error),
    /// A noise file is not `host noise`'s `noise.json`.
    #[error("cannot use noise file {}: not a noise.json of host noise", .0.display())]
    NotNoiseJson(PathBuf, #[source] serde_json::Error),
    /// The Allan figure could not be drawn.
    #[error(transparent)]
    Figure(#[from] crate::report::plot::FigureError),
    /// The calibration does not turn this still recording into 1 g: it is not this recording's.
    #[error(
        "the calibration turns this still recording into |f| = {f_g:.4} g, not 1 g: it is \
         not this recording's calibration (another unit, output unit or scale), and its \
         noise figures would be off by the same factor; give the recording's own calibration"
    )]
    NotOneG {
        /// Mean |f| of the still data after the calibration, g.
        f_g: f64,
    },
    /// The calibration cannot meet the recording ([`crate::calibration_guard`]).
    #[error(transparent)]
    Guard(#[from] crate::calibration_guard::GuardError),
}

/// One axis's analysis.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct AxisNoise {
    /// `accel_x` … `gyro_z`.
    pub axis: String,
    /// Unit of the signal (`m/s^2`, `V`, `LSB`, `rad/s`); N is in unit/√Hz, K in unit/√s.
    pub unit: String,
    /// The Allan deviation curve.
    pub points: Vec<AllanPoint>,
    /// The fitted terms.
    pub terms: NoiseTerms,
}

/// The result of `host noise`.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct NoiseReport {
    /// What was read.
    pub source: String,
    /// The segment analysed.
    pub segment: String,
    /// Sample rate, Hz.
    pub sample_rate_hz: f64,
    /// Rows analysed.
    pub samples: u64,
    /// Per axis, in [`AXES`] order.
    pub axes: Vec<AxisNoise>,
    /// The figures for Kalibr (worst axis of each sensor).
    pub kalibr: KalibrNoise,
    /// Warnings (segment cut, accelerometer not in m/s², …), as `noise.json` keeps them: the
    /// analysis's notes ([`Note`]) and the reader's, said.
    pub warnings: Vec<String>,
    /// The recording's accelerometer output unit (`V`, `LSB`, `m/s2`, `g`): what the accelerometer
    /// axes' figures are in where their unit is `output unit`, so that a consumer can check it
    /// against its own recording's. Absent where the input states none (a bare samples.csv) and in
    /// a noise.json written before it was recorded.
    #[serde(default)]
    pub output_unit: Option<OutputUnit>,
}

/// The rows of one segment as six signals.
struct Signals {
    segment: String,
    rate_hz: f64,
    data: [Vec<f64>; 6],
    cut: bool,
    /// The accelerometer's unit as the input states it (`None`: a bare samples.csv states none).
    acc_unit: Option<OutputUnit>,
}

fn collect_session(dir: &Path, quiet: bool) -> Result<Signals, NoiseError> {
    let session = read_session(dir, &ReadOptions { quiet })?;
    let plan: &Plan = &session.plan;
    let best = session
        .stats
        .iter()
        .filter(|s| {
            plan.segments
                .iter()
                .any(|p| p.name == s.name && p.is_static())
        })
        .max_by_key(|s| s.count)
        .ok_or_else(|| {
            NoiseError::NoStillData(format!("{} has no static segment", dir.display()))
        })?;
    let index = plan
        .segments
        .iter()
        .position(|p| p.name == best.name)
        .unwrap_or(0);
    let mut data: [Vec<f64>; 6] = Default::default();
    let mut cut = false;
    let path = dir.join(SAMPLES_FILE);
    let file = std::fs::File::open(&path).map_err(|source| RecordingError::Io {
        path: path.clone(),
        source,
    })?;
    read_samples_each(
        BufReader::with_capacity(1 << 20, file),
        plan,
        &path,
        |row| {
            let finite = row.u.iter().chain(&row.w_rad_s).all(|v| v.is_finite());
            if row.segment_index == index && finite {
                if data[0].len() >= MAX_SAMPLES {
                    cut = true;
                } else {
                    for j in 0..3 {
                        data[j].push(row.u[j]);
                        data[3 + j].push(row.w_rad_s[j]);
                    }
                }
            }
            Ok(())
        },
    )?;
    Ok(Signals {
        segment: best.name.clone(),
        rate_hz: plan.sample_rate_hz,
        data,
        cut,
        acc_unit: Some(plan.output_unit),
    })
}

/// A bare samples.csv: the longest run of one segment's rows; the rate from the time stamps. It is
/// read by the session reader (same parser, same checks) with a plan made of the segment names the
/// file uses (a first pass over the names only).
fn collect_csv(path: &Path) -> Result<Signals, NoiseError> {
    let open = || {
        std::fs::File::open(path)
            .map(|f| BufReader::with_capacity(1 << 20, f))
            .map_err(|source| RecordingError::Io {
                path: path.to_path_buf(),
                source,
            })
    };
    collect_csv_from(open()?, open()?, path)
}

/// [`collect_csv`] on two readers of the same text, one per pass (`path` only names it in messages).
fn collect_csv_from<R: std::io::BufRead>(
    first_pass: R,
    second_pass: R,
    path: &Path,
) -> Result<Signals, NoiseError> {
    let names = segment_names(first_pass, path)?;
    let plan = Plan {
        attitude_sigma_deg: None,
        table_rate_sigma_ppm: None,
        format_version: recording::session::plan::PLAN_FORMAT_VERSION,
        output_unit: shared::OutputUnit::Volts,
        sample_rate_hz: 1.0,
        gravity_m_s2: shared::STANDARD_GRAVITY_M_S2,
        unit_id: None,
        package: Default::default(),
        acc_offset: None,
        segments: names
            .iter()
            .map(|n| recording::session::SegmentPlan {
                attitude: Default::default(),
                attitude_sigma_deg: None,
                name: n.clone(),
                up_b: [0.0, 0.0, 1.0],
                rate_deg_s: 0.0,
                rate_end_deg_s: None,
                duration_s: None,
                table_centre_m: None,
                mount: None,
                ..Default::default()
            })
            .collect(),
    };
    type Run = (Signals, usize, f64, f64);
    let finish = |run: Option<Run>, best: &mut Option<Signals>| {
        if let Some((mut s, _, t0, t1)) = run {
            let n = s.data[0].len();
            if n > 1 {
                s.rate_hz = (n - 1) as f64 / (t1 - t0);
            }
            if best.as_ref().is_none_or(|b| b.data[0].len() < n) {
                *best = Some(s);
            }
        }
    };
    let (mut best, mut cur): (Option<Signals>, Option<Run>) = (None, None);
    read_samples_each(second_pass, &plan, path, |row| {
        if cur.as_ref().is_none_or(|c| c.1 != row.segment_index) {
            finish(cur.take(), &mut best);
            let s = Signals {
                segment: row.segment.to_string(),
                rate_hz: 0.0,
                data: Default::default(),
                cut: false,
                acc_unit: None,
            };
            cur = Some((s, row.segment_index, row.t_s, row.t_s));
        }
        if let Some((s, _, _, t1)) = cur.as_mut() {
            let finite = row.u.iter().chain(&row.w_rad_s).all(|v| v.is_finite());
            if s.data[0].len() >= MAX_SAMPLES {
                s.cut = true;
            } else if finite && row.t_s.is_finite() {
                for j in 0..3 {
                    s.data[j].push(row.u[j]);
                    s.data[3 + j].push(row.w_rad_s[j]);
                }
                *t1 = row.t_s;
            }
        }
        Ok(())
    })?;
    finish(cur.take(), &mut best);
    best.ok_or_else(|| NoiseError::NoStillData(format!("{} has no rows", path.display())))
}

/// The segment names a bare samples.csv uses, in the order they first appear: the first field of
/// every line after the header. Each line is read with the session reader's bound
/// ([`MAX_LINE_BYTES`]) and at most [`MAX_SEGMENTS`] names are kept, so an endless line
/// (`/dev/zero`, a file without line ends) or endless names are an error naming the limit after a
/// few kilobytes, never an unbounded allocation.
fn segment_names<R: std::io::BufRead>(
    mut reader: R,
    path: &Path,
) -> Result<Vec<String>, NoiseError> {
    use std::io::{BufRead as _, Read as _};
    let io = |source| RecordingError::Io {
        path: path.to_path_buf(),
        source,
    };
    let (mut names, mut known): (Vec<String>, HashSet<String>) = Default::default();
    let mut line = Vec::with_capacity(256);
    for number in 1u64.. {
        line.clear();
        let n = (&mut reader)
            .take(MAX_LINE_BYTES as u64 + 1)
            .read_until(b'\n', &mut line)
            .map_err(io)?;
        if n == 0 {
            break;
        }
        if n > MAX_LINE_BYTES {
            return Err(RecordingError::LineTooLong {
                path: path.to_path_buf(),
                line: number,
            }
            .into());
        }
        if number == 1 {
            continue;
        }
        let field = line.split(|&b| b == b',').next().unwrap_or_default();
        let name = String::from_utf8_lossy(field.trim_ascii());
        let name = name.trim_matches('"');
        if name.is_empty() || names.last().is_some_and(|l| l == name) || known.contains(name) {
            continue;
        }
        if names.len() >= MAX_SEGMENTS {
            return Err(NoiseError::NoStillData(format!(
                "{} names more than {MAX_SEGMENTS} segments (line {number}): not a samples.csv",
                path.display()
            )));
        }
        known.insert(name.to_string());
        names.push(name.to_string());
    }
    Ok(names)
}

/// Analyses `input` (session directory or samples.csv); `calibration` turns the accelerometer
/// outputs into m/s²; `spelling` names the options its warnings ask for.
pub fn analyse(
    input: &Path,
    calibration: Option<&PlainMatrices>,
    spelling: Spelling,
    quiet: bool,
) -> Result<NoiseReport, NoiseError> {
    let s = if input.is_dir() {
        if !input.join(PLAN_FILE).exists() {
            return Err(NoiseError::NoStillData(format!(
                "{} has no {PLAN_FILE}; give a session directory or a samples.csv",
                input.display()
            )));
        }
        collect_session(input, quiet)?
    } else {
        collect_csv(input)?
    };
    analyse_signals(s, input.display().to_string(), calibration, spelling, quiet)
}

/// [`analyse`] of a bare samples.csv held in memory (`host::fuzz`'s `noise_csv` target).
#[cfg(any(test, feature = "fuzz"))]
pub fn analyse_csv_bytes(
    data: &[u8],
    calibration: Option<&PlainMatrices>,
    spelling: Spelling,
) -> Result<NoiseReport, NoiseError> {
    let s = collect_csv_from(data, data, Path::new(SAMPLES_FILE))?;
    analyse_signals(s, SAMPLES_FILE.into(), calibration, spelling, true)
}

/// The Allan curves, fitted terms and Kalibr figures of one segment's signals.
fn analyse_signals(
    mut s: Signals,
    source: String,
    calibration: Option<&PlainMatrices>,
    spelling: Spelling,
    quiet: bool,
) -> Result<NoiseReport, NoiseError> {
    let n = s.data[0].len();
    if n < MIN_SAMPLES || !(s.rate_hz.is_finite() && s.rate_hz > 0.0) {
        return Err(NoiseError::NoStillData(format!(
            "the longest still segment ('{}') has {n} usable rows at {} Hz; at least {MIN_SAMPLES} \
             are needed (record a long still segment)",
            s.segment, s.rate_hz
        )));
    }
    let mut warnings = Vec::new();
    if s.cut {
        warnings.push(Note::NoiseSegmentCut {
            segment: s.segment.clone(),
            max_samples: MAX_SAMPLES,
        });
    }
    let accel_unit = accel::accel_to_m_s2(&mut s, calibration, spelling, &mut warnings)?;
    // The Allan curve and the fit's bootstrap take seconds per axis on a long recording.
    let bar = recording::ui::progress_bar(
        AXES.len() as u64,
        "Allan deviation and fit, per axis",
        quiet,
    );
    let axes: Vec<AxisNoise> = AXES
        .iter()
        .enumerate()
        .map(|(j, name)| {
            let (points, terms) = curve_and_fit(&s.data[j], s.rate_hz);
            bar.inc(1);
            AxisNoise {
                axis: (*name).into(),
                unit: if j < 3 {
                    accel_unit.into()
                } else {
                    "rad/s".into()
                },
                terms,
                points,
            }
        })
        .collect();
    bar.finish_and_clear();
    let kalibr = kalibr_figures(
        s.rate_hz,
        &std::array::from_fn(|j| (axes[j].terms.white_density, axes[j].terms.random_walk)),
        accel_unit == "m/s^2",
    );
    Ok(NoiseReport {
        source,
        segment: s.segment,
        sample_rate_hz: s.rate_hz,
        samples: n as u64,
        axes,
        kalibr,
        warnings: Note::texts(&warnings),
        output_unit: s.acc_unit,
    })
}

fn opt(v: Option<f64>) -> String {
    v.map_or("n.d.".into(), |v| format!("{v:.4e}"))
}

/// The terms' names in the order of [`NoiseTerms::fits`].
const TERM_NAMES: [&str; 3] = ["N", "B", "K"];

/// One line per term a recording does not determine: its bound and the recording it would need.
fn undetermined_lines(axes: &[AxisNoise], seconds: f64) -> String {
    let mut s = String::new();
    for a in axes {
        for (name, (value, fit)) in TERM_NAMES
            .iter()
            .zip(a.terms.values().iter().zip(&a.terms.fits))
        {
            if value.is_some() {
                continue;
            }
            let bound = fit
                .upper_bound_2sigma
                .map_or(String::new(), |b| format!(", ≤ {b:.2e} at 2σ"));
            let needs = match fit.needs_recording_s {
                Some(t) => format!(
                    "; a still recording of at least {t:.0} s (this one: {seconds:.0} s) would determine a term that large"
                ),
                None => format!("; not even {:.0} s of recording would determine a term that large", seconds * 65536.0),
            };
            s += &format!(
                "  {} {name}: not determined by this recording ({:.1}σ{bound}){needs}\n",
                a.axis, fit.significance
            );
        }
    }
    s
}

impl NoiseReport {
    /// The human table.
    pub fn render(&self) -> String {
        let mut s = format!(
            "Allan deviation of '{}' ({} rows at {} Hz)\n{:<8} {:>12} {:>12} {:>12} {:>12}  unit\n",
            self.segment,
            self.samples,
            self.sample_rate_hz,
            "axis",
            "N (/√Hz)",
            "B",
            "K (/√s)",
            "min σ"
        );
        for a in &self.axes {
            let min = a
                .points
                .iter()
                .map(|p| p.adev)
                .fold(f64::INFINITY, f64::min);
            s += &format!(
                "{:<8} {:>12} {:>12} {:>12} {:>12.4e}  {}\n",
                a.axis,
                opt(a.terms.white_density),
                opt(a.terms.bias_instability),
                opt(a.terms.random_walk),
                min,
                a.unit
            );
        }
        let lines = undetermined_lines(&self.axes, self.samples as f64 / self.sample_rate_hz);
        if !lines.is_empty() {
            s += &format!(
                "n.d.: a term counts only where it is at least {}× its 1σ (from the Allan points' \
                 equivalent degrees of freedom) and the curve reaches the τ that shows it\n{lines}",
                allan::Z_DETERMINED
            );
        }
        for line in self.axes.iter().flat_map(|a| a.terms.notes(&a.axis)) {
            s += &format!("note: {line}\n");
        }
        s
    }

    /// The Allan figure as engineers draw it: one log–log panel per axis with the measured curve
    /// and its 1σ bars (IEEE 952's cluster count, [`confidence::relative_sigma`]), the fitted model,
    /// and each determined term as its own line: N on the −½ slope (read at τ = 1 s), B flat at
    /// 0.664 B, K on the +½ slope (read at τ = 3 s), labelled with its value.
    pub fn figure(&self) -> Figure {
        let accel_unit = self
            .axes
            .first()
            .map_or("m/s^2".to_string(), |a| a.unit.clone());
        let panels = self
            .axes
            .iter()
            .enumerate()
            .map(|(j, a)| {
                let unit = if j < 3 { accel_unit.as_str() } else { "rad/s" };
                self.axis_panel(a, unit)
            })
            .collect();
        Figure {
            stem: "allan".into(),
            title: "Allan deviation".into(),
            grid: (2, 3),
            size: (1800, 1100),
            panels,
        }
    }

    /// One axis's panel of [`Self::figure`].
    fn axis_panel(&self, a: &AxisNoise, unit: &str) -> Panel {
        let n = usize::try_from(self.samples).unwrap_or(usize::MAX);
        let sigma = |tau: f64| {
            let m = (tau * self.sample_rate_hz).round() as usize;
            confidence::relative_sigma(n, m.max(1)).unwrap_or(0.0)
        };
        let mut series = vec![
            Series {
                label: format!("{} (±1σ), {unit}", a.axis),
                points: a.points.iter().map(|p| (p.tau_s, p.adev)).collect(),
                error: Some(a.points.iter().map(|p| p.adev * sigma(p.tau_s)).collect()),
                style: SeriesStyle::Markers,
                colour: 0,
            },
            Series {
                label: "fit".into(),
                points: a
                    .points
                    .iter()
                    .map(|p| (p.tau_s, a.terms.adev(p.tau_s)))
                    .collect(),
                error: None,
                style: SeriesStyle::Line,
                colour: 1,
            },
        ];
        let (Some(first), Some(last)) = (a.points.first(), a.points.last()) else {
            return axis_panel_of(a, unit, series);
        };
        let span = [first.tau_s, last.tau_s];
        let t = &a.terms;
        // Each term in its unit (N in unit/√Hz, B in the unit, K in unit/√s) and its slope.
        let lines: [TermLine; 3] = [
            (t.white_density, "N", "/√Hz (slope −½)", |v, tau| {
                v / tau.sqrt()
            }),
            (t.bias_instability, "B", " (flat)", |v, _| {
                allan::FLICKER_FACTOR.sqrt() * v
            }),
            (t.random_walk, "K", "/√s (slope +½)", |v, tau| {
                v * (tau / 3.0).sqrt()
            }),
        ];
        for (k, (value, name, rest, adev)) in lines.into_iter().enumerate() {
            // A term the record does not determine is said in the legend, not left out silently.
            let (label, points) = match value {
                Some(v) => (
                    format!("{name} = {v:.3e} {unit}{rest}"),
                    span.iter().map(|&tau| (tau, adev(v, tau))).collect(),
                ),
                None => (format!("{name}: not determined by this record"), Vec::new()),
            };
            series.push(Series {
                label,
                points,
                error: None,
                style: SeriesStyle::Dashed,
                colour: 2 + k,
            });
        }
        axis_panel_of(a, unit, series)
    }

    /// `axis,tau_s,adev,fit_adev,terms,sigma` rows (`sigma`: the 1σ of `adev` from the equivalent
    /// degrees of freedom under the fitted terms, [`allan::NoiseTerms::adev_sigma`]).
    pub fn csv(&self) -> String {
        let mut s = String::from("axis,tau_s,adev,fit_adev,terms,sigma\n");
        for a in &self.axes {
            for p in &a.points {
                s += &format!(
                    "{},{:e},{:e},{:e},{},{:e}\n",
                    a.axis,
                    p.tau_s,
                    p.adev,
                    a.terms.adev(p.tau_s),
                    p.terms,
                    a.terms.adev_sigma(p, 1.0 / self.sample_rate_hz)
                );
            }
        }
        s
    }
}

/// A term's line in the Allan figure: its value, name, unit suffix and slope, and its Allan
/// deviation at τ.
type TermLine = (Option<f64>, &'static str, &'static str, fn(f64, f64) -> f64);

/// A log–log panel of one axis's `series`.
fn axis_panel_of(a: &AxisNoise, unit: &str, series: Vec<Series>) -> Panel {
    Panel {
        title: a.axis.clone(),
        x_desc: "τ (s)".into(),
        y_desc: format!("Allan deviation [{unit}]"),
        x_categories: None,
        log_x: true,
        log_y: true,
        series,
    }
}

#[cfg(test)]
mod tests;
