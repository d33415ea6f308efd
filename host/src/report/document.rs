//! The calibration report a person reads (`host report`) and the paper's navigation check on its own
//! unit (`host navigation-check`), as library functions the CLI calls.
//!
//! Intended CLI (wired by `cli.rs`):
//!
//! ```text
//! host report --input SESSION_DIR --calibration calibration.toml --out-dir OUT
//!             [--static-run NAME] [--rate-run NAME] [--duration-s 60] [--no-png]
//!     → report(input, calibration, out_dir, &ReportOptions) ; prints ReportSummary::render()
//! host navigation-check [--seed 1] [--duration-s 60] [--out-dir OUT]
//!     → navigation_check(&NavigationCheckArgs) ; prints NavigationCheck::render()
//! ```
//!
//! # What the report computes
//!
//! For every segment of the session, from its mean outputs `ū` and mean gyro rate, with the given
//! calibration:
//!
//! - the true specific force at the reference point, `g·up_b − W p` (`p` = the plan's `table_centre_m`,
//!   0 when absent; `W = [ω̇×] + [ω×]²` from the measured rate);
//! - "before": bias and scale removed only, `(ū_i − u0_i)/k_i` (the paper's Tables 2 and 4 "before");
//! - "after, static": `shared::Compensator` with [`LeverMode::Off`] (paper eq. 6);
//! - "after, static + dynamic": `shared::Compensator` with [`LeverMode::RateAndAcceleration`] at the
//!   segment's mean rate and angular acceleration (paper eq. 16). On a ramp the mean of `ω ωᵀ` is not
//!   `ω̄ ω̄ᵀ`; the rate used there is `ω̄` scaled so that `|ω|²` is the segment's mean `|ω|²` less the gyro
//!   noise (seen on the static segments), which makes the compensated mean exact for a ramp about a
//!   fixed axis.
//!
//! The 1σ band of the residuals is the standard error of the segment's mean (its own noise): a
//! calibration that fits leaves residuals inside it. The calibration's own 1σ is in Tables 1 and 3.
//!
//! # The navigation check (paper Figs. 6/7 and 9/10)
//!
//! A **noise-free replay**: the recorded mean outputs of a segment (what the unit measures in that
//! attitude at that rate) are taken as a constant specific force over the whole run (60 s by default),
//! compensated three ways, gravity (the true specific force above) removed, and integrated twice in body
//! axes by [`integrate_drift`]. White noise would add a random walk that hides the error the calibration
//! leaves; replaying the means shows exactly that error, `½·e·t²`. One static run and one rotating run
//! (the fastest constant-rate segment, 200 °/s in the paper's plan) are replayed.

use crate::estimate::{calibrate_session_stats, CalibrationOutcome, EstimateOptions, SegmentKind};
use crate::report::navigation::{integrate_drift, Drift};
use crate::report::plot::{self, Figure, Formats, Panel, Series, SeriesStyle};
use crate::session::builtin::paper_plan;
use crate::session::{
    read_session, Plan, ReadOptions, RecordingError, SegmentAccumulator, SegmentStats,
};
use crate::sim::{simulate_rows, NoiseModel, SimulateError};
use crate::unit_file::{Uncertainty, UnitFile, UnitFileError};
use shared::linalg;
use shared::params::axis_name;
use shared::{BodyAngularAccel, BodyRate, Calibration, Compensator, LeverMode, SensorOutputs};
use std::fmt::Write as _;
use std::path::{Path, PathBuf};

/// File name of the Markdown page.
pub const REPORT_MD: &str = "report.md";
/// File name of the HTML page (same content).
pub const REPORT_HTML: &str = "report.html";

/// Settings of [`report`] and [`build_report`].
#[derive(Clone, Debug, PartialEq)]
pub struct ReportOptions {
    /// Estimator settings for the session's own fit (χ², excluded segments, observability).
    pub estimate: EstimateOptions,
    /// Length of the replayed navigation runs, s.
    pub navigation_duration_s: f64,
    /// Integration step of the replay, s.
    pub navigation_step_s: f64,
    /// The static segment to replay; `None`: the first static segment.
    pub static_run: Option<String>,
    /// The rotating segment to replay; `None`: the constant-rate segment with the fastest planned rate
    /// (the first of equals).
    pub rate_run: Option<String>,
    /// Which figure files to write.
    pub formats: Formats,
}

impl Default for ReportOptions {
    fn default() -> Self {
        ReportOptions {
            estimate: EstimateOptions::default(),
            navigation_duration_s: 60.0,
            navigation_step_s: 0.1,
            static_run: None,
            rate_run: None,
            formats: Formats::default(),
        }
    }
}

/// Why no report could be made.
#[derive(Debug)]
pub enum ReportError {
    /// The session could not be read.
    Recording(RecordingError),
    /// The calibration file could not be read.
    Unit(UnitFileError),
    /// The calibration cannot compensate (message says why).
    Calibration(String),
    /// A requested segment is not in the session, or the session has none to use.
    Segment(String),
    /// A figure could not be drawn.
    Figure(plot::FigureError),
    /// A file could not be written.
    Io(PathBuf, std::io::Error),
    /// The simulation of the navigation check failed.
    Simulate(SimulateError),
    /// The calibration of the navigation check failed.
    Estimate(crate::estimate::EstimateError),
}

impl std::fmt::Display for ReportError {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match self {
            ReportError::Recording(e) => e.fmt(f),
            ReportError::Unit(e) => e.fmt(f),
            ReportError::Calibration(m) => write!(f, "the calibration cannot compensate: {m}"),
            ReportError::Segment(m) => f.write_str(m),
            ReportError::Figure(e) => e.fmt(f),
            ReportError::Io(p, e) => write!(f, "cannot write {}: {e}", p.display()),
            ReportError::Simulate(e) => e.fmt(f),
            ReportError::Estimate(e) => e.fmt(f),
        }
    }
}

impl std::error::Error for ReportError {}

impl From<plot::FigureError> for ReportError {
    fn from(e: plot::FigureError) -> Self {
        ReportError::Figure(e)
    }
}

/// A compensation level.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Compensation {
    /// Bias and scale only (the paper's "before compensation").
    BiasScale,
    /// Static compensation (`K_A`, `∇_b`), no lever arms.
    Static,
    /// Static and dynamic (lever arms, ω and ω̇).
    Full,
}

impl Compensation {
    /// All three, in report order.
    pub const ALL: [Compensation; 3] = [
        Compensation::BiasScale,
        Compensation::Static,
        Compensation::Full,
    ];

    /// Short label.
    pub fn label(self) -> &'static str {
        match self {
            Compensation::BiasScale => "before (bias+scale only)",
            Compensation::Static => "after, static only",
            Compensation::Full => "after, static+dynamic",
        }
    }

    /// Palette index of its series.
    pub fn colour(self) -> usize {
        match self {
            Compensation::BiasScale => 0,
            Compensation::Static => 1,
            Compensation::Full => 2,
        }
    }
}

/// One segment's outputs before and after compensation (Tables 2 and 4).
#[derive(Clone, Debug, PartialEq)]
pub struct SegmentRow {
    /// Segment name.
    pub name: String,
    /// What it does.
    pub kind: SegmentKind,
    /// The plan's up.
    pub up_b: [f64; 3],
    /// Measured mean rate about `up_b`, °/s.
    pub rate_deg_s: f64,
    /// The plan's rate (at the segment's start), °/s.
    pub planned_rate_deg_s: f64,
    /// Rows.
    pub count: u64,
    /// Rate used for compensation, body axes, rad/s (see the module doc for ramps).
    pub omega_rad_s: [f64; 3],
    /// Angular acceleration used, rad/s².
    pub omega_dot_rad_s2: [f64; 3],
    /// True specific force at the reference point, g.
    pub truth_g: [f64; 3],
    /// Bias and scale removed only, g.
    pub before_g: [f64; 3],
    /// Static compensation, g.
    pub after_static_g: [f64; 3],
    /// Static and dynamic compensation, g.
    pub after_g: [f64; 3],
    /// Standard error of the segment's mean, per axis, g.
    pub sigma_g: [f64; 3],
}

impl SegmentRow {
    /// The output at a compensation level, g.
    pub fn output_g(&self, c: Compensation) -> [f64; 3] {
        match c {
            Compensation::BiasScale => self.before_g,
            Compensation::Static => self.after_static_g,
            Compensation::Full => self.after_g,
        }
    }

    /// Output minus truth, g.
    pub fn error_g(&self, c: Compensation) -> [f64; 3] {
        let o = self.output_g(c);
        std::array::from_fn(|j| o[j] - self.truth_g[j])
    }
}

/// One compensation level of a replayed run.
#[derive(Clone, Debug, PartialEq)]
pub struct NavigationCase {
    /// The level.
    pub compensation: Compensation,
    /// The constant specific-force error replayed, g.
    pub error_g: [f64; 3],
    /// Velocity and position error over the run.
    pub drift: Drift,
}

/// A replayed run (noise-free: the segment's mean outputs held for the whole run).
#[derive(Clone, Debug, PartialEq)]
pub struct NavigationRun {
    /// The segment replayed.
    pub segment: String,
    /// Its mean rate, °/s.
    pub rate_deg_s: f64,
    /// Length of the run, s.
    pub duration_s: f64,
    /// Before, static only, static + dynamic.
    pub cases: Vec<NavigationCase>,
}

impl NavigationRun {
    /// The case of a compensation level.
    pub fn case(&self, c: Compensation) -> &NavigationCase {
        self.cases
            .iter()
            .find(|k| k.compensation == c)
            .expect("every run has all three cases")
    }
}

/// Everything the report shows, computed (no files).
#[derive(Clone, Debug)]
pub struct ReportData {
    /// The calibration reported on.
    pub calibration: Calibration,
    /// Its 1σ, when the file has them.
    pub uncertainty: Option<Uncertainty>,
    /// Output unit symbol (V or LSB).
    pub unit_symbol: String,
    /// Per segment, in plan order.
    pub segments: Vec<SegmentRow>,
    /// Σ over segments and axes of ((after − truth)/σ)², for this calibration on this session.
    pub chi2: f64,
    /// Number of terms of `chi2`.
    pub chi2_terms: usize,
    /// The static and the rotating replay (either may be absent when the plan has none).
    pub navigation: Vec<NavigationRun>,
    /// The session's own fit (χ², excluded segments, observability), or why it failed.
    pub session_fit: Result<CalibrationOutcome, String>,
    /// Warnings for the reader.
    pub warnings: Vec<String>,
}

/// The true specific force, rates and the three compensated outputs of every segment.
pub fn segment_rows(
    plan: &Plan,
    stats: &[SegmentStats],
    cal: &Calibration,
) -> Result<Vec<SegmentRow>, ReportError> {
    let g = cal.gravity_m_s2;
    let stat = Compensator::new(cal, LeverMode::Off)
        .map_err(|e| ReportError::Calibration(e.to_string()))?;
    let full = Compensator::new(cal, LeverMode::RateAndAcceleration)
        .map_err(|e| ReportError::Calibration(e.to_string()))?;
    let u0 = cal.statics.zero_bias_out;
    let k = cal.statics.scale_out_per_g;
    let trace = |m: &[[f64; 3]; 3]| m[0][0] + m[1][1] + m[2][2];
    // Gyro noise variance (trace), from the static segments.
    let statics: Vec<f64> = stats
        .iter()
        .filter(|s| plan.segment(&s.name).is_some_and(|p| p.is_static()))
        .map(|s| trace(&s.cov_w))
        .collect();
    let gyro_noise = if statics.is_empty() {
        0.0
    } else {
        statics.iter().sum::<f64>() / statics.len() as f64
    };
    let mut rows = Vec::new();
    for st in stats {
        let Some(sp) = plan.segment(&st.name) else {
            continue;
        };
        let kind = if sp.is_static() {
            SegmentKind::Static
        } else if sp.rate_end_deg_s.is_some_and(|r| r != sp.rate_deg_s) {
            SegmentKind::Ramp
        } else {
            SegmentKind::ConstantRate
        };
        let mean_w = st.mean_w_rad_s;
        let w2 = linalg::dot(&mean_w, &mean_w);
        let omega = if kind == SegmentKind::Ramp && w2 > 0.0 {
            let target = (trace(&st.mean_wwt) - gyro_noise).max(w2);
            mean_w.map(|v| v * (target / w2).sqrt())
        } else {
            mean_w
        };
        let omega_dot = st.wdot_rad_s2;
        let p = sp.table_centre_m.unwrap_or([0.0; 3]);
        let wp = linalg::mat_vec(&linalg::lever_matrix(&omega, &omega_dot), &p);
        let truth_g: [f64; 3] = std::array::from_fn(|j| sp.up_b[j] - wp[j] / g);
        let u = SensorOutputs {
            raw: st.mean_u.map(|v| v as f32),
        };
        // A calibration with a temperature model is applied at the segment's mean temperature, as
        // the device applies it (docs/model.md §9).
        let (mut stat, mut full) = (stat, full);
        if let Some(ts) = &st.thermal {
            stat.refresh(ts.mean_c() as f32);
            full.refresh(ts.mean_c() as f32);
        }
        let after_static = stat.compensate_static(&u).to_f64().m_s2.map(|v| v / g);
        let after = full
            .compensate(
                &u,
                &BodyRate {
                    rad_s: omega.map(|v| v as f32),
                },
                &BodyAngularAccel {
                    rad_s2: omega_dot.map(|v| v as f32),
                },
            )
            .to_f64()
            .m_s2
            .map(|v| v / g);
        let n = st.count.max(1) as f64;
        rows.push(SegmentRow {
            name: st.name.clone(),
            kind,
            up_b: sp.up_b,
            rate_deg_s: linalg::dot(&mean_w, &sp.up_b).to_degrees(),
            planned_rate_deg_s: sp.rate_deg_s,
            count: st.count,
            omega_rad_s: omega,
            omega_dot_rad_s2: omega_dot,
            truth_g,
            before_g: std::array::from_fn(|i| (st.mean_u[i] - u0[i]) / k[i]),
            after_static_g: after_static,
            after_g: after,
            sigma_g: std::array::from_fn(|i| (st.cov_u[i][i].max(0.0) / n).sqrt() / k[i].abs()),
        });
    }
    Ok(rows)
}

/// Replays one segment's mean outputs for `duration_s` (see the module doc).
pub fn replay(row: &SegmentRow, g: f64, duration_s: f64, step_s: f64) -> NavigationRun {
    let steps = (duration_s / step_s).round().max(1.0) as usize;
    let truth = row.truth_g.map(|v| v * g);
    let cases = Compensation::ALL
        .iter()
        .map(|&c| {
            let f = row.output_g(c).map(|v| v * g);
            let drift = integrate_drift(
                (0..=steps).map(|k| (k as f64 * duration_s / steps as f64, f)),
                truth,
            );
            NavigationCase {
                compensation: c,
                error_g: row.error_g(c),
                drift,
            }
        })
        .collect();
    NavigationRun {
        segment: row.name.clone(),
        rate_deg_s: row.rate_deg_s,
        duration_s,
        cases,
    }
}

/// Computes everything the report shows. `session_fit`: the session's own fit when the caller has it
/// (else it is run here with `options.estimate`).
pub fn build_report(
    plan: &Plan,
    stats: &[SegmentStats],
    cal: &Calibration,
    uncertainty: Option<&Uncertainty>,
    session_fit: Option<CalibrationOutcome>,
    options: &ReportOptions,
) -> Result<ReportData, ReportError> {
    let segments = segment_rows(plan, stats, cal)?;
    if segments.is_empty() {
        return Err(ReportError::Segment(
            "the session has no segment of its plan with data: nothing to report".into(),
        ));
    }
    let mut warnings = Vec::new();
    if plan.output_unit.symbol() != cal.statics.output_unit.symbol() {
        warnings.push(format!(
            "the session records {} but the calibration is in {}: the outputs cannot be compared",
            plan.output_unit.symbol(),
            cal.statics.output_unit.symbol()
        ));
    }
    let (mut chi2, mut terms) = (0.0, 0usize);
    for r in &segments {
        let e = r.error_g(Compensation::Full);
        for j in 0..3 {
            if r.sigma_g[j] > 0.0 && e[j].is_finite() {
                chi2 += (e[j] / r.sigma_g[j]).powi(2);
                terms += 1;
            }
        }
    }
    let find = |name: &str| {
        segments
            .iter()
            .find(|r| r.name == name)
            .ok_or_else(|| ReportError::Segment(format!("segment '{name}' is not in the session")))
    };
    let static_row = match &options.static_run {
        Some(n) => Some(find(n)?),
        None => segments.iter().find(|r| r.kind == SegmentKind::Static),
    };
    let rate_row = match &options.rate_run {
        Some(n) => Some(find(n)?),
        None => segments
            .iter()
            .filter(|r| r.kind == SegmentKind::ConstantRate)
            .fold(None::<&SegmentRow>, |best, r| match best {
                Some(b) if b.planned_rate_deg_s.abs() >= r.planned_rate_deg_s.abs() => Some(b),
                _ => Some(r),
            }),
    };
    if static_row.is_none() {
        warnings.push("no static segment: the static navigation replay is left out".into());
    }
    if rate_row.is_none() {
        warnings
            .push("no constant-rate segment: the rotating navigation replay is left out".into());
    }
    let g = cal.gravity_m_s2;
    let navigation = [static_row, rate_row]
        .into_iter()
        .flatten()
        .map(|r| {
            replay(
                r,
                g,
                options.navigation_duration_s,
                options.navigation_step_s,
            )
        })
        .collect();
    let session_fit = match session_fit {
        Some(o) => Ok(o),
        None => calibrate_session_stats(plan, stats, &options.estimate).map_err(|e| e.to_string()),
    };
    Ok(ReportData {
        calibration: *cal,
        uncertainty: uncertainty.cloned(),
        unit_symbol: cal.statics.output_unit.symbol().to_string(),
        segments,
        chi2,
        chi2_terms: terms,
        navigation,
        session_fit,
        warnings,
    })
}

// ---------------------------------------------------------------------------------------------
// Figures.

/// Figure (a), paper Figs. 5 and 8: each segment's output minus the true value, mg, before and after
/// compensation; one panel per axis.
pub fn outputs_figure(data: &ReportData) -> Figure {
    let cats: Vec<String> = data.segments.iter().map(|r| r.name.clone()).collect();
    let panels = (0..3)
        .map(|j| Panel {
            title: format!("{} output − true value", axis_name(j)),
            x_desc: "segment".into(),
            y_desc: "mg".into(),
            x_categories: Some(cats.clone()),
            log_y: false,
            series: Compensation::ALL
                .iter()
                .map(|&c| Series {
                    label: c.label().into(),
                    points: data
                        .segments
                        .iter()
                        .enumerate()
                        .map(|(k, r)| (k as f64, r.error_g(c)[j] * 1e3))
                        .collect(),
                    error: None,
                    style: SeriesStyle::LineAndMarkers,
                    colour: c.colour(),
                })
                .collect(),
        })
        .collect();
    Figure {
        stem: "outputs".into(),
        title: "Outputs before and after compensation, minus the true value (paper Figs. 5, 8)"
            .into(),
        grid: (3, 1),
        size: (1200, 1000),
        panels,
    }
}

/// Figure (b): the residual after full compensation, µg, with the segment's ±1σ (its own noise).
pub fn residuals_figure(data: &ReportData) -> Figure {
    let cats: Vec<String> = data.segments.iter().map(|r| r.name.clone()).collect();
    let panels = (0..3)
        .map(|j| Panel {
            title: format!(
                "{} residual after static+dynamic compensation",
                axis_name(j)
            ),
            x_desc: "segment".into(),
            y_desc: "µg".into(),
            x_categories: Some(cats.clone()),
            log_y: false,
            series: vec![Series {
                label: "residual ± 1σ of the segment mean".into(),
                points: data
                    .segments
                    .iter()
                    .enumerate()
                    .map(|(k, r)| (k as f64, r.error_g(Compensation::Full)[j] * 1e6))
                    .collect(),
                error: Some(data.segments.iter().map(|r| r.sigma_g[j] * 1e6).collect()),
                style: SeriesStyle::Markers,
                colour: Compensation::Full.colour(),
            }],
        })
        .collect();
    Figure {
        stem: "residuals".into(),
        title: "Residuals per segment with their 1σ band".into(),
        grid: (3, 1),
        size: (1200, 1000),
        panels,
    }
}

/// Figure (c), paper Figs. 6/7 and 9/10: velocity and position error of a replayed run (norms, log
/// scale), before and after compensation.
pub fn navigation_figure(run: &NavigationRun, stem: &str) -> Figure {
    let panel = |what: &str, unit: &str, pick: &dyn Fn(&Drift, usize) -> f64| Panel {
        title: format!("{what} error |{}|", &what[..1]),
        x_desc: "t (s)".into(),
        y_desc: unit.into(),
        x_categories: None,
        log_y: true,
        series: run
            .cases
            .iter()
            .map(|c| Series {
                label: c.compensation.label().into(),
                points: (0..c.drift.t_s.len())
                    .map(|k| (c.drift.t_s[k], pick(&c.drift, k)))
                    .collect(),
                error: None,
                style: SeriesStyle::Line,
                colour: c.compensation.colour(),
            })
            .collect(),
    };
    let norm = |v: &[f64; 3]| linalg::norm(v);
    Figure {
        stem: stem.into(),
        title: format!(
            "Navigation replay of '{}' ({}), {:.0} s",
            run.segment,
            if run.rate_deg_s.abs() < 0.5 {
                "static".to_string()
            } else {
                format!("{:.0} °/s", run.rate_deg_s)
            },
            run.duration_s
        ),
        grid: (1, 2),
        size: (1200, 500),
        panels: vec![
            panel("velocity", "m/s", &|d, k| norm(&d.velocity_m_s[k])),
            panel("position", "m", &|d, k| norm(&d.position_m[k])),
        ],
    }
}

/// All figures of a report: outputs, residuals, then one per navigation run.
pub fn report_figures(data: &ReportData) -> Vec<Figure> {
    let mut v = vec![outputs_figure(data), residuals_figure(data)];
    if let Some(f) = data
        .session_fit
        .as_ref()
        .ok()
        .and_then(super::thermal::figure)
    {
        v.push(f);
    }
    for (k, run) in data.navigation.iter().enumerate() {
        let stem = if k == 0 && run.rate_deg_s.abs() < 0.5 {
            "navigation_static".to_string()
        } else {
            format!("navigation_{}", stem_name(&run.segment))
        };
        v.push(navigation_figure(run, &stem));
    }
    v
}

/// A rate for display, °/s, without a "-0".
fn fmt_rate(r: f64) -> String {
    if r.abs() < 0.5 {
        "0".into()
    } else {
        format!("{r:.0}")
    }
}

fn stem_name(s: &str) -> String {
    s.chars()
        .map(|c| match c {
            '+' => 'p',
            '-' | '−' => 'm',
            c if c.is_ascii_alphanumeric() => c,
            _ => '_',
        })
        .collect()
}

// ---------------------------------------------------------------------------------------------
// The page: one document model rendered to Markdown and HTML.

/// A block of the report page.
#[derive(Clone, Debug, PartialEq)]
pub enum Block {
    /// Heading of a level (1..3).
    Heading(u8, String),
    /// A paragraph.
    Para(String),
    /// A table.
    Table {
        /// Column headers.
        header: Vec<String>,
        /// Rows of cells.
        rows: Vec<Vec<String>>,
    },
    /// An image (relative path).
    Image {
        /// Relative path.
        src: String,
        /// Alternative text.
        alt: String,
    },
    /// Preformatted text.
    Pre(String),
}

fn pm(v: f64, s: Option<f64>, digits: usize) -> String {
    match s {
        Some(s) if s.is_finite() => format!("{v:.digits$} ± {s:.digits$}"),
        Some(_) => format!("{v:.digits$} ± ∞"),
        None => format!("{v:.digits$} (no σ)"),
    }
}

/// Table 1 (zero bias, scale factor, installation angles with 1σ) as table rows.
pub fn table1(data: &ReportData) -> Block {
    let st = &data.calibration.statics;
    let u = data.uncertainty.as_ref();
    let d = if data.unit_symbol == "V" { 6 } else { 3 };
    let sym = &data.unit_symbol;
    Block::Table {
        header: vec![
            "No.".into(),
            format!("Zero bias ({sym})"),
            format!("Scale factor ({sym}/g)"),
            "θ_ix (°)".into(),
            "θ_iy (°)".into(),
            "θ_iz (°)".into(),
        ],
        rows: (0..3)
            .map(|i| {
                let mut row = vec![
                    format!("{}", i + 1),
                    pm(st.zero_bias_out[i], u.map(|u| u.zero_bias_1sigma[i]), d),
                    pm(st.scale_out_per_g[i], u.map(|u| u.scale_per_g_1sigma[i]), d),
                ];
                for j in 0..3 {
                    row.push(pm(
                        st.installation_angles_deg[i][j],
                        u.map(|u| u.installation_angles_deg_1sigma[i][j]),
                        5,
                    ));
                }
                row
            })
            .collect(),
    }
}

/// Table 3 (lever arms, mm, with 1σ; "n.d." where the plan did not determine the component).
pub fn table3(data: &ReportData) -> Block {
    let r = &data.calibration.lever_arms.r_m;
    let u = data.uncertainty.as_ref();
    Block::Table {
        header: vec!["".into(), "x (mm)".into(), "y (mm)".into(), "z (mm)".into()],
        rows: (0..3)
            .map(|i| {
                let mut row = vec![format!("r{}", i + 1)];
                for j in 0..3 {
                    let cell = pm(
                        r[i][j] * 1e3,
                        u.map(|u| u.lever_arms_m_1sigma[i][j] * 1e3),
                        4,
                    );
                    let nd = u.is_some_and(|u| !u.lever_arms_observable[i][j]);
                    row.push(if nd { format!("({cell}) n.d.") } else { cell });
                }
                row
            })
            .collect(),
    }
}

/// Tables 2 and 4: per segment and axis, theoretical, before, after static, after full (g), the
/// residual and the segment's 1σ (µg). `rotating`: the rotating segments (Table 4) or the static ones.
pub fn before_after_table(data: &ReportData, rotating: bool) -> Block {
    let mut rows = Vec::new();
    for r in data
        .segments
        .iter()
        .filter(|r| (r.kind != SegmentKind::Static) == rotating)
    {
        for j in 0..3 {
            rows.push(vec![
                if j == 0 {
                    r.name.clone()
                } else {
                    String::new()
                },
                axis_name(j).to_string(),
                format!("{:+.6}", r.truth_g[j]),
                format!("{:+.6}", r.before_g[j]),
                format!("{:+.6}", r.after_static_g[j]),
                format!("{:+.6}", r.after_g[j]),
                format!("{:+.1}", r.error_g(Compensation::Full)[j] * 1e6),
                format!("{:.1}", r.sigma_g[j] * 1e6),
            ]);
        }
    }
    Block::Table {
        header: [
            "segment",
            "axis",
            "theoretical (g)",
            "before: bias+scale (g)",
            "after: static (g)",
            "after: static+dynamic (g)",
            "residual (µg)",
            "1σ (µg)",
        ]
        .map(String::from)
        .to_vec(),
        rows,
    }
}

/// The navigation table: final velocity and position error of each replayed run and level.
pub fn navigation_table(runs: &[NavigationRun]) -> Block {
    let mut rows = Vec::new();
    for run in runs {
        for c in &run.cases {
            rows.push(vec![
                run.segment.clone(),
                format!("{}", fmt_rate(run.rate_deg_s)),
                c.compensation.label().into(),
                format!("{:.3}", linalg::norm(&c.error_g) * 1e3),
                format!("{:.4}", c.drift.final_velocity_error_m_s()),
                format!("{:.3}", c.drift.final_position_error_m()),
            ]);
        }
    }
    Block::Table {
        header: [
            "run",
            "rate (°/s)",
            "compensation",
            "|error| (mg)",
            "final |v| error (m/s)",
            "final |p| error (m)",
        ]
        .map(String::from)
        .to_vec(),
        rows,
    }
}

/// The whole page.
pub fn page(
    data: &ReportData,
    session: &str,
    calibration: &str,
    figure_stems: &[String],
) -> Vec<Block> {
    let mut b = Vec::new();
    b.push(Block::Heading(1, "Calibration report".into()));
    b.push(Block::Para(format!(
        "Session `{session}`, calibration `{calibration}`. Values with their 1σ; 1σ of the \
         residuals is the standard error of each segment's mean (its own noise)."
    )));
    for w in &data.warnings {
        b.push(Block::Para(format!("**Warning:** {w}")));
    }
    b.push(Block::Heading(2, "Table 1. Static calibration".into()));
    b.push(table1(data));
    b.push(Block::Heading(2, "Table 3. Lever arms".into()));
    b.push(Block::Para(format!(
        "Reference point: {:?}. n.d. = not determined by the calibrating plan.",
        data.calibration.reference
    )));
    b.push(table3(data));
    b.push(Block::Heading(
        2,
        "Outputs before and after compensation (like Tables 2 and 4)".into(),
    ));
    b.push(Block::Heading(3, "Static segments (Table 2)".into()));
    b.push(before_after_table(data, false));
    b.push(Block::Heading(3, "Rotating segments (Table 4)".into()));
    b.push(before_after_table(data, true));
    b.push(Block::Para(format!(
        "χ² of this calibration on this session (residual after full compensation over each segment's \
         own noise): {:.1} for {} values.",
        data.chi2, data.chi2_terms
    )));
    for stem in figure_stems.iter().filter(|s| !s.starts_with("navigation")) {
        b.push(Block::Image {
            src: format!("{stem}.png"),
            alt: stem.clone(),
        });
    }
    b.push(Block::Heading(
        2,
        "Navigation check (paper Figs. 6/7, 9/10)".into(),
    ));
    b.push(Block::Para(
        "Noise-free replay: each run holds the segment's recorded mean outputs for the whole run, \
         compensates them, removes the true specific force and integrates twice in body axes."
            .into(),
    ));
    b.push(navigation_table(&data.navigation));
    for stem in figure_stems.iter().filter(|s| s.starts_with("navigation")) {
        b.push(Block::Image {
            src: format!("{stem}.png"),
            alt: stem.clone(),
        });
    }
    b.push(Block::Heading(2, "This session's own fit".into()));
    match &data.session_fit {
        Ok(o) => {
            b.push(Block::Para(format!(
                "Method: {}. χ² = {:.1}, dof = {}, χ²/dof = {:.2}. Excluded segments: {}. Lever-arm \
                 components not determined to {:.0} µm: {}.",
                o.method,
                o.fit.chi2,
                o.fit.dof,
                o.fit.reduced_chi2,
                if o.excluded.is_empty() {
                    "none".to_string()
                } else {
                    o.excluded
                        .iter()
                        .map(|e| format!("'{}' ({})", e.name, e.reason))
                        .collect::<Vec<_>>()
                        .join("; ")
                },
                o.observability.threshold_m * 1e6,
                {
                    let u = o.observability.undetermined();
                    if u.is_empty() {
                        "none".to_string()
                    } else {
                        u.join(", ")
                    }
                }
            )));
            b.push(Block::Pre(crate::report::render(o)));
        }
        Err(e) => b.push(Block::Para(format!(
            "The session alone does not calibrate: {e}"
        ))),
    }
    b
}

fn md_cell(s: &str) -> String {
    s.replace('|', "\\|")
}

/// Markdown.
pub fn to_markdown(blocks: &[Block]) -> String {
    let mut s = String::new();
    for b in blocks {
        match b {
            Block::Heading(l, t) => {
                let _ = writeln!(s, "{} {t}\n", "#".repeat(*l as usize));
            }
            Block::Para(t) => {
                let _ = writeln!(s, "{t}\n");
            }
            Block::Table { header, rows } => {
                let h: Vec<String> = header.iter().map(|c| md_cell(c)).collect();
                let _ = writeln!(s, "| {} |", h.join(" | "));
                let _ = writeln!(s, "|{}", "---|".repeat(header.len()));
                for r in rows {
                    let c: Vec<String> = r.iter().map(|c| md_cell(c)).collect();
                    let _ = writeln!(s, "| {} |", c.join(" | "));
                }
                s.push('\n');
            }
            Block::Image { src, alt } => {
                let _ = writeln!(s, "![{alt}]({src})\n");
            }
            Block::Pre(t) => {
                let _ = writeln!(s, "```text\n{}\n```\n", t.trim_end());
            }
        }
    }
    s
}

fn esc(s: &str) -> String {
    s.replace('&', "&amp;")
        .replace('<', "&lt;")
        .replace('>', "&gt;")
        .replace('"', "&quot;")
}

/// Inline Markdown of the page's paragraphs (`code`, **bold**) in HTML.
fn inline_html(s: &str) -> String {
    let mut out = String::new();
    let mut code = false;
    let mut bold = false;
    let mut rest = s;
    while let Some(c) = rest.chars().next() {
        if rest.starts_with("**") {
            out.push_str(if bold { "</strong>" } else { "<strong>" });
            bold = !bold;
            rest = &rest[2..];
        } else if c == '`' {
            out.push_str(if code { "</code>" } else { "<code>" });
            code = !code;
            rest = &rest[1..];
        } else {
            out.push_str(&esc(&c.to_string()));
            rest = &rest[c.len_utf8()..];
        }
    }
    out
}

/// Self-contained HTML (images by relative path).
pub fn to_html(blocks: &[Block], title: &str) -> String {
    let mut s = String::new();
    let _ = writeln!(
        s,
        "<!DOCTYPE html>\n<html lang=\"en\"><head><meta charset=\"utf-8\"><title>{}</title>\n<style>\
         body{{font-family:sans-serif;max-width:1250px;margin:2em auto;padding:0 1em}}\
         table{{border-collapse:collapse;margin:1em 0}}td,th{{border:1px solid #bbb;padding:3px 8px;\
         text-align:right;font-family:monospace}}th{{background:#eee}}img{{max-width:100%}}\
         pre{{background:#f6f6f6;padding:1em;overflow-x:auto}}</style></head><body>",
        esc(title)
    );
    for b in blocks {
        match b {
            Block::Heading(l, t) => {
                let _ = writeln!(s, "<h{l}>{}</h{l}>", esc(t));
            }
            Block::Para(t) => {
                let _ = writeln!(s, "<p>{}</p>", inline_html(t));
            }
            Block::Table { header, rows } => {
                s.push_str("<table>\n<tr>");
                for h in header {
                    let _ = write!(s, "<th>{}</th>", esc(h));
                }
                s.push_str("</tr>\n");
                for r in rows {
                    s.push_str("<tr>");
                    for c in r {
                        let _ = write!(s, "<td>{}</td>", esc(c));
                    }
                    s.push_str("</tr>\n");
                }
                s.push_str("</table>\n");
            }
            Block::Image { src, alt } => {
                let _ = writeln!(s, "<p><img src=\"{}\" alt=\"{}\"></p>", esc(src), esc(alt));
            }
            Block::Pre(t) => {
                let _ = writeln!(s, "<pre>{}</pre>", esc(t.trim_end()));
            }
        }
    }
    s.push_str("</body></html>\n");
    s
}

// ---------------------------------------------------------------------------------------------
// Writing, and the two entry points.

/// What [`report`] wrote.
#[derive(Clone, Debug)]
pub struct ReportSummary {
    /// The computed report.
    pub data: ReportData,
    /// The figures drawn (as data), in file order.
    pub figures: Vec<Figure>,
    /// Files written (figures, then `report.md` and `report.html`).
    pub files: Vec<PathBuf>,
    /// The HTML page: the one file to open.
    pub page: PathBuf,
    /// Warnings (no font, missing runs, …).
    pub warnings: Vec<String>,
}

impl ReportSummary {
    /// What the CLI prints.
    pub fn render(&self) -> String {
        let mut s = String::new();
        let _ = writeln!(s, "Report: {}", self.page.display());
        let _ = writeln!(s, "{}", render_navigation(&self.data.navigation));
        for w in &self.warnings {
            let _ = writeln!(s, "warning: {w}");
        }
        s
    }
}

/// Writes the figures and the page of `data` into `out_dir`.
pub fn write_report(
    data: &ReportData,
    out_dir: &Path,
    session: &str,
    calibration: &str,
    formats: Formats,
) -> Result<ReportSummary, ReportError> {
    std::fs::create_dir_all(out_dir).map_err(|e| ReportError::Io(out_dir.to_path_buf(), e))?;
    let figs = report_figures(data);
    let mut files = Vec::new();
    let mut warnings = data.warnings.clone();
    let mut png = formats.png;
    for f in &figs {
        let out = plot::render(f, out_dir, formats)?;
        files.extend(out.files);
        png &= out.warnings.is_empty();
        for w in out.warnings {
            if !warnings.contains(&w) {
                warnings.push(w);
            }
        }
    }
    let stems: Vec<String> = figs.iter().map(|f| f.stem.clone()).collect();
    let mut blocks = page(data, session, calibration, &stems);
    if !png {
        // Point the page at the SVGs when no PNG was written.
        for b in &mut blocks {
            if let Block::Image { src, .. } = b {
                *src = src.replace(".png", ".svg");
            }
        }
    }
    let md = out_dir.join(REPORT_MD);
    std::fs::write(&md, to_markdown(&blocks)).map_err(|e| ReportError::Io(md.clone(), e))?;
    let html = out_dir.join(REPORT_HTML);
    std::fs::write(&html, to_html(&blocks, "Calibration report"))
        .map_err(|e| ReportError::Io(html.clone(), e))?;
    files.push(md);
    files.push(html.clone());
    Ok(ReportSummary {
        data: data.clone(),
        figures: figs,
        files,
        page: html,
        warnings,
    })
}

/// `host report`: reads the session in `input_dir` and the calibration file, computes the outputs
/// before and after compensation, the residuals and the navigation replay, and writes the figures
/// (PNG and SVG) and `report.html` / `report.md` into `out_dir`.
pub fn report(
    input_dir: &Path,
    calibration_file: &Path,
    out_dir: &Path,
    options: &ReportOptions,
) -> Result<ReportSummary, ReportError> {
    let session =
        read_session(input_dir, &ReadOptions { quiet: true }).map_err(ReportError::Recording)?;
    let unit = UnitFile::load(calibration_file).map_err(ReportError::Unit)?;
    let cal = unit.to_calibration().map_err(ReportError::Calibration)?;
    let mut data = build_report(
        &session.plan,
        &session.stats,
        &cal,
        unit.uncertainty.as_ref(),
        None,
        options,
    )?;
    data.warnings
        .extend(session.report.warnings.iter().cloned());
    write_report(
        &data,
        out_dir,
        &input_dir.display().to_string(),
        &calibration_file.display().to_string(),
        options.formats,
    )
}

/// Settings of [`navigation_check`]: the paper's unit and plan, 1 mg white noise, a fixed seed.
#[derive(Clone, Debug)]
pub struct NavigationCheckArgs {
    /// The unit simulated (default: the paper's, `reference/paper-unit.toml`).
    pub unit: UnitFile,
    /// The plan (default: the paper's).
    pub plan: Plan,
    /// Noise (default: 1 mg accelerometer white noise, 0.05 °/s gyro white noise).
    pub noise: NoiseModel,
    /// Seed.
    pub seed: u64,
    /// Report settings (navigation run length, …).
    pub report: ReportOptions,
    /// Where to write the figures and the page; `None`: nothing written.
    pub out_dir: Option<PathBuf>,
}

impl Default for NavigationCheckArgs {
    fn default() -> Self {
        NavigationCheckArgs {
            unit: UnitFile::paper_unit(),
            plan: paper_plan(),
            noise: NoiseModel::default(),
            seed: 1,
            report: ReportOptions::default(),
            out_dir: None,
        }
    }
}

/// The result of [`navigation_check`].
#[derive(Clone, Debug)]
pub struct NavigationCheck {
    /// The calibration of the simulated session (joint method by default).
    pub outcome: CalibrationOutcome,
    /// The report on it.
    pub data: ReportData,
    /// What was written, when `out_dir` was given.
    pub written: Option<ReportSummary>,
}

impl NavigationCheck {
    /// What the CLI prints: the navigation table and the position errors against their targets.
    pub fn render(&self) -> String {
        let mut s = render_navigation(&self.data.navigation);
        s.push_str(&render_position_targets(&self.data.navigation));
        if let Some(w) = &self.written {
            let _ = writeln!(s, "Report: {}", w.page.display());
        }
        s
    }
}

/// The final position errors of the static and the rotating run against their targets (tens of metres uncompensated, under 0.3 m after static calibration, under 1 m after static + dynamic), one line per run.
pub fn render_position_targets(runs: &[NavigationRun]) -> String {
    let mut s = String::new();
    let pos = |run: &NavigationRun, c| run.case(c).drift.final_position_error_m();
    if let Some(st) = runs.iter().find(|r| r.rate_deg_s.abs() < 0.5) {
        let _ = writeln!(
            s,
            "static run '{}', {:.0} s: without compensation {:.1} m (target: tens of metres or more; \
             paper: about 100 m); after static calibration {:.3} m (target: under 0.3 m)",
            st.segment,
            st.duration_s,
            pos(st, Compensation::BiasScale),
            pos(st, Compensation::Static)
        );
    }
    if let Some(rt) = runs.iter().find(|r| r.rate_deg_s.abs() >= 0.5) {
        let _ = writeln!(
            s,
            "{:.0} °/s run '{}', {:.0} s: static-only {:.1} m (target: tens of metres); static+dynamic \
             {:.3} m (target: under 1 m)",
            rt.rate_deg_s,
            rt.segment,
            rt.duration_s,
            pos(rt, Compensation::Static),
            pos(rt, Compensation::Full)
        );
    }
    s
}

/// The navigation table as plain text.
pub fn render_navigation(runs: &[NavigationRun]) -> String {
    let mut s = String::new();
    let _ = writeln!(
        s,
        "Navigation check (noise-free replay of each segment's mean outputs):"
    );
    let _ = writeln!(
        s,
        "  {:<10} {:>8}  {:<26} {:>12} {:>14} {:>12}",
        "run", "°/s", "compensation", "|error| mg", "|v| end m/s", "|p| end m"
    );
    for run in runs {
        for c in &run.cases {
            let _ = writeln!(
                s,
                "  {:<10} {:>8}  {:<26} {:>12.4} {:>14.4} {:>12.3}",
                run.segment,
                fmt_rate(run.rate_deg_s),
                c.compensation.label(),
                linalg::norm(&c.error_g) * 1e3,
                c.drift.final_velocity_error_m_s(),
                c.drift.final_position_error_m()
            );
        }
    }
    s
}

/// Simulates `plan` on `cal` straight into segment statistics (no files).
pub fn simulate_stats(
    cal: &Calibration,
    plan: &Plan,
    noise: &NoiseModel,
    seed: u64,
) -> Result<Vec<SegmentStats>, SimulateError> {
    let mut accs: Vec<SegmentAccumulator> = Vec::new();
    let r = simulate_rows(cal, plan, noise, seed, |seg, t, u, w| {
        if accs.last().is_none_or(|a| a.name() != seg) {
            accs.push(SegmentAccumulator::new(seg));
        }
        if let Some(a) = accs.last_mut() {
            a.push(t, u, w);
        }
        Ok::<(), std::convert::Infallible>(())
    })?;
    let _ = r;
    Ok(accs.iter().filter_map(|a| a.finish()).collect())
}

/// `host navigation-check`: the paper's unit simulated with its plan (1 mg white noise, fixed seed),
/// calibrated with the joint method, and the navigation replay of a static and the fastest rotating
/// segment. Prints (via [`NavigationCheck::render`]) the final position errors against their targets.
pub fn navigation_check(args: &NavigationCheckArgs) -> Result<NavigationCheck, ReportError> {
    let truth = args
        .unit
        .to_calibration()
        .map_err(ReportError::Calibration)?;
    let stats = simulate_stats(&truth, &args.plan, &args.noise, args.seed)
        .map_err(ReportError::Simulate)?;
    let outcome = calibrate_session_stats(&args.plan, &stats, &args.report.estimate)
        .map_err(ReportError::Estimate)?;
    let data = build_report(
        &args.plan,
        &stats,
        &outcome.calibration,
        Some(&outcome.uncertainty),
        Some(outcome.clone()),
        &args.report,
    )?;
    let written = match &args.out_dir {
        Some(dir) => Some(write_report(
            &data,
            dir,
            &format!(
                "simulated: paper unit, {} plan, {} mg white noise, seed {}",
                if args.plan == paper_plan() {
                    "paper"
                } else {
                    "given"
                },
                args.noise.accel_white_mg,
                args.seed
            ),
            "estimated from it (joint method)",
            args.report.formats,
        )?),
        None => None,
    };
    Ok(NavigationCheck {
        outcome,
        data,
        written,
    })
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::report::plot::{palette_hex, png_dimensions, svg_polylines};
    use crate::session::builtin::builtin_plan;

    fn short() -> Plan {
        builtin_plan("short").unwrap().unwrap()
    }

    /// The short plan on the paper unit, calibrated from its own noisy data.
    fn noisy_report() -> ReportData {
        let plan = short();
        let truth = UnitFile::paper_unit().to_calibration().unwrap();
        let stats = simulate_stats(&truth, &plan, &NoiseModel::default(), 7).unwrap();
        let outcome = calibrate_session_stats(&plan, &stats, &EstimateOptions::default()).unwrap();
        build_report(
            &plan,
            &stats,
            &outcome.calibration,
            Some(&outcome.uncertainty),
            Some(outcome.clone()),
            &ReportOptions::default(),
        )
        .unwrap()
    }

    /// Cells of a table block, parsed as numbers where they are.
    fn cells(b: &Block) -> &Vec<Vec<String>> {
        match b {
            Block::Table { rows, .. } => rows,
            _ => panic!("not a table"),
        }
    }

    #[test]
    fn noise_free_true_calibration_gives_the_papers_numbers() {
        // docs/model.md §6: x up, bias+scale only → (0.99991, 0.01300, −0.00911) g; static-only at 200 °/s
        // about x leaves (0.09, 11.2, 10.1) mg.
        let plan = short();
        let truth = UnitFile::paper_unit().to_calibration().unwrap();
        let stats = simulate_stats(&truth, &plan, &NoiseModel::none(), 1).unwrap();
        let rows = segment_rows(&plan, &stats, &truth).unwrap();
        assert_eq!(rows.len(), 15);
        let x = &rows[0];
        assert_eq!(x.name, "x+");
        for (v, want) in x.before_g.iter().zip([0.99991, 0.01300, -0.00911]) {
            assert!((v - want).abs() < 1e-5, "{:?}", x.before_g);
        }
        let x200 = rows.iter().find(|r| r.name == "x+ 200").unwrap();
        assert_eq!(x200.kind, SegmentKind::ConstantRate);
        let e = x200.error_g(Compensation::Static).map(|v| v.abs() * 1e3);
        for (v, want) in e.iter().zip([0.09, 11.2, 10.1]) {
            assert!((v - want).abs() < 0.06, "{e:?}");
        }
        // The device's f32 compensation with the true parameters leaves only rounding.
        for r in &rows {
            let e = r.error_g(Compensation::Full);
            assert!(e.iter().all(|v| v.abs() < 2e-6), "{}: {e:?}", r.name);
        }
    }

    #[test]
    fn replay_is_half_a_t_squared_of_the_table_error() {
        let data = noisy_report();
        assert_eq!(data.navigation.len(), 2);
        assert_eq!(data.navigation[0].segment, "x+");
        assert_eq!(data.navigation[1].segment, "x+ 200");
        let g = data.calibration.gravity_m_s2;
        for run in &data.navigation {
            let row = data
                .segments
                .iter()
                .find(|r| r.name == run.segment)
                .unwrap();
            for c in &run.cases {
                let e = row.error_g(c.compensation);
                assert_eq!(c.error_g, e);
                let p = c.drift.position_m.last().unwrap();
                let v = c.drift.velocity_m_s.last().unwrap();
                for j in 0..3 {
                    assert!((p[j] - 0.5 * e[j] * g * 3600.0).abs() < 1e-9 * (1.0 + p[j].abs()));
                    assert!((v[j] - e[j] * g * 60.0).abs() < 1e-9 * (1.0 + v[j].abs()));
                }
            }
        }
        // The story: static-only is fine at rest, and leaves tens of metres at 200 °/s.
        let rate = &data.navigation[1];
        assert!(
            rate.case(Compensation::Static)
                .drift
                .final_position_error_m()
                > 100.0
        );
    }

    #[test]
    fn figures_plot_the_numbers_in_the_tables_and_render() {
        let data = noisy_report();
        let n = data.segments.len();
        // (a) The outputs figure: panel j, series c, point k = segment k's error in mg, and the
        // table's printed outputs give the same error to their printed precision.
        let fig = outputs_figure(&data);
        let statics = before_after_table(&data, false);
        let rotating = before_after_table(&data, true);
        let table_rows: Vec<&Vec<String>> =
            cells(&statics).iter().chain(cells(&rotating)).collect();
        assert_eq!(table_rows.len(), 3 * n);
        let mut seg_of_row = Vec::new();
        for r in &data.segments {
            let s = data.segments.iter().position(|x| x.name == r.name).unwrap();
            seg_of_row.push(s);
        }
        for (j, panel) in fig.panels.iter().enumerate() {
            assert_eq!(panel.series.len(), 3);
            for (c, series) in Compensation::ALL.iter().zip(&panel.series) {
                assert_eq!(series.points.len(), n);
                for (k, r) in data.segments.iter().enumerate() {
                    assert_eq!(series.points[k], (k as f64, r.error_g(*c)[j] * 1e3));
                }
            }
        }
        // Every table row (segment, axis) against the plotted value.
        let mut current = String::new();
        for row in &table_rows {
            if !row[0].is_empty() {
                current = row[0].clone();
            }
            let k = data
                .segments
                .iter()
                .position(|r| r.name == current)
                .unwrap();
            let j = ["x", "y", "z"].iter().position(|a| *a == row[1]).unwrap();
            let num = |s: &str| s.parse::<f64>().unwrap();
            let truth = num(&row[2]);
            for (col, c) in [(3, 0usize), (4, 1), (5, 2)] {
                let plotted = fig.panels[j].series[c].points[k].1 * 1e-3;
                assert!(
                    (num(&row[col]) - truth - plotted).abs() < 1.1e-6,
                    "{current} {j} col {col}"
                );
            }
            // (b) The residual figure's point and band are the table's residual and 1σ (µg).
            let res = &residuals_figure(&data).panels[j].series[0];
            assert!((num(&row[6]) - res.points[k].1).abs() < 0.051);
            assert!((num(&row[7]) - res.error.as_ref().unwrap()[k]).abs() < 0.051);
        }
        // (c) The navigation figures end at the navigation table's final errors.
        let nav = navigation_table(&data.navigation);
        let figs = report_figures(&data);
        let stems: Vec<&str> = figs.iter().map(|f| f.stem.as_str()).collect();
        assert_eq!(
            stems,
            [
                "outputs",
                "residuals",
                "navigation_static",
                "navigation_xp_200"
            ]
        );
        for (r, run) in data.navigation.iter().enumerate() {
            let f = &figs[2 + r];
            for (c, case) in run.cases.iter().enumerate() {
                let row = &cells(&nav)[3 * r + c];
                let vel_end = f.panels[0].series[c].points.last().unwrap().1;
                let pos_end = f.panels[1].series[c].points.last().unwrap().1;
                assert_eq!(pos_end, case.drift.final_position_error_m());
                assert!((row[4].parse::<f64>().unwrap() - vel_end).abs() <= 5e-5);
                assert!((row[5].parse::<f64>().unwrap() - pos_end).abs() <= 5e-4);
            }
        }

        // Rendered: valid PNGs of the figure's size, SVGs with one polyline per line series holding
        // every drawable point, and the page referring to every figure.
        let dir = tempfile::tempdir().unwrap();
        let summary = write_report(&data, dir.path(), "s", "c", Formats::default()).unwrap();
        assert!(summary.warnings.is_empty(), "{:?}", summary.warnings);
        assert_eq!(summary.files.len(), 2 * figs.len() + 2);
        for f in &figs {
            let png = std::fs::read(dir.path().join(format!("{}.png", f.stem))).unwrap();
            assert_eq!(png_dimensions(&png), Some(f.size), "{}", f.stem);
            let svg = std::fs::read_to_string(dir.path().join(format!("{}.svg", f.stem))).unwrap();
            assert!(svg.starts_with("<svg") && svg.trim_end().ends_with("</svg>"));
            let lines = svg_polylines(&svg);
            for p in &f.panels {
                for s in p.series.iter().filter(|s| s.style != SeriesStyle::Markers) {
                    let drawable = s
                        .points
                        .iter()
                        .filter(|(_, y)| !p.log_y || *y > 0.0)
                        .count();
                    assert!(
                        lines.iter().any(|l| l.stroke == palette_hex(s.colour)
                            && l.width == "2"
                            && l.points == drawable),
                        "{}: '{}' with {drawable} points not drawn",
                        f.stem,
                        s.label
                    );
                }
            }
            if f.stem == "residuals" {
                assert_eq!(svg.matches("<circle").count(), 3 * n);
            }
        }
        let md = std::fs::read_to_string(dir.path().join(REPORT_MD)).unwrap();
        let html = std::fs::read_to_string(&summary.page).unwrap();
        for f in &figs {
            assert!(md.contains(&format!("]({}.png)", f.stem)));
            assert!(html.contains(&format!("src=\"{}.png\"", f.stem)));
        }
        assert!(md.contains("Table 1. Static calibration") && md.contains("χ²"));
        assert!(html.starts_with("<!DOCTYPE html>") && html.contains("<table>"));
    }

    #[test]
    fn a_ramp_is_compensated_at_its_rms_rate() {
        // 0 → 200 °/s in 2 s about x: the mean of ω² is not ω̄² (the difference is ~0.8 mg of
        // centripetal term on 8 mm lever arms), so the rate used must be the RMS one.
        let plan = Plan::parse(
            "output_unit = \"V\"\nsample_rate_hz = 1000\n\
             [[segment]]\nname = \"x+\"\nup_b = [1, 0, 0]\nduration_s = 1\n\
             [[segment]]\nname = \"ramp\"\nup_b = [1, 0, 0]\nrate_deg_s = 0\n\
             rate_end_deg_s = 200\nduration_s = 2\n",
        )
        .unwrap();
        let truth = UnitFile::paper_unit().to_calibration().unwrap();
        let stats = simulate_stats(&truth, &plan, &NoiseModel::none(), 1).unwrap();
        let rows = segment_rows(&plan, &stats, &truth).unwrap();
        let ramp = &rows[1];
        assert_eq!(ramp.kind, SegmentKind::Ramp);
        assert!(ramp.omega_rad_s[0] > 1.05 * stats[1].mean_w_rad_s[0]);
        let e = ramp.error_g(Compensation::Full);
        assert!(e.iter().all(|v| v.abs() < 3e-6), "{e:?}");
        assert!(ramp.error_g(Compensation::Static)[1].abs() > 1e-3);
    }

    #[test]
    fn navigation_check_prints_the_position_errors_against_targets() {
        // The short plan keeps this fast; the paper's plan is what the command runs by default.
        let dir = tempfile::tempdir().unwrap();
        let check = navigation_check(&NavigationCheckArgs {
            plan: short(),
            out_dir: Some(dir.path().to_path_buf()),
            ..NavigationCheckArgs::default()
        })
        .unwrap();
        let text = check.render();
        assert!(
            text.contains("static run 'x+', 60 s: without compensation"),
            "{text}"
        );
        assert!(
            text.contains("200 °/s run 'x+ 200', 60 s: static-only"),
            "{text}"
        );
        assert!(dir.path().join(REPORT_HTML).exists());
    }

    #[test]
    fn a_named_run_must_exist() {
        let plan = short();
        let truth = UnitFile::paper_unit().to_calibration().unwrap();
        let stats = simulate_stats(&truth, &plan, &NoiseModel::none(), 1).unwrap();
        let options = ReportOptions {
            rate_run: Some("x+ 999".into()),
            ..ReportOptions::default()
        };
        let e = build_report(&plan, &stats, &truth, None, None, &options).unwrap_err();
        assert!(e.to_string().contains("'x+ 999'"));
        let options = ReportOptions {
            rate_run: Some("y+ 100".into()),
            ..ReportOptions::default()
        };
        let d = build_report(&plan, &stats, &truth, None, None, &options).unwrap();
        assert_eq!(d.navigation[1].segment, "y+ 100");
        // Without [uncertainty], Table 1 says so.
        assert!(cells(&table1(&d))[0][1].contains("no σ"));
    }
}
