//! The report's numbers, computed before anything is drawn or written: for every segment the true
//! specific force and the outputs before and after compensation, the χ² of the residuals, and the
//! navigation replays. The one per-segment before/after table of the report is built from [`SegmentRow`].
//!
//! For every segment of the session, from its mean outputs `ū` and mean gyro rate, with the given
//! calibration:
//!
//! - the theoretical specific force at the calibration's reference point: the one the terminal shows,
//!   the session's own fit's (each segment's *fitted* attitude, [`Theoretical::Fitted`]); where the
//!   fit has no value for a segment (excluded, or the fit failed), the plan's `g·up_b − W p`
//!   ([`Theoretical::Planned`]; `p` = the plan's `table_centre_m`, 0 when absent; `W = [ω̇×] + [ω×]²`
//!   from the measured rate) for a fixture's known attitude, and nothing for a free (hand-held)
//!   attitude, whose `up_b` is only a rough guess ([`Theoretical::Unknown`]: not compared);
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

use super::navigation::{replay, NavigationRun};
use super::plot::{self, Formats};
use crate::note::Note;
use estimator::estimate::{
    CalibrationOutcome, EstimateError, EstimateOptions, Noise, SegmentKind, Uncertainty,
};
use estimator::sim::SimulateError;
use estimator::unit_file::UnitFileError;
use recording::session::{Package, Plan, RecordingError, SegmentStats};
use recording::spelling::{Spelling, UserOption};
use shared::linalg;
use shared::{BodyAngularAccel, BodyRate, Calibration, Compensator, LeverMode, SensorOutputs};
use std::path::PathBuf;

/// Settings of a report (`app::report`) and [`build_report`].
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

impl ReportOptions {
    /// The report's defaults, the fit's messages spelled as the caller spells its options.
    pub fn new(spelling: Spelling) -> ReportOptions {
        ReportOptions {
            estimate: EstimateOptions::new(spelling),
            navigation_duration_s: 60.0,
            navigation_step_s: 0.1,
            static_run: None,
            rate_run: None,
            formats: Formats::default(),
        }
    }
}

/// The tests' report options: [`ReportOptions::new`] with the neutral test spelling.
#[cfg(test)]
impl Default for ReportOptions {
    fn default() -> Self {
        ReportOptions::new(Spelling::default())
    }
}

/// Why no report could be made.
#[derive(Debug, thiserror::Error)]
pub enum ReportError {
    /// The session could not be read.
    #[error(transparent)]
    Recording(RecordingError),
    /// The calibration file could not be read.
    #[error(transparent)]
    Unit(UnitFileError),
    /// The calibration file's values are not a calibration (the unit file says why).
    #[error("the calibration cannot compensate")]
    Calibration(#[source] estimator::unit_file::UnitFileInvalid),
    /// The calibration cannot compensate.
    #[error("the calibration cannot compensate")]
    Compensator(#[source] shared::compensator::CompensatorError),
    /// The calibration's gyro correction cannot be inverted.
    #[error("the calibration cannot compensate")]
    Gyro(#[source] shared::sensor_models::GyroError),
    /// The calibration cannot meet this recording ([`crate::calibration_guard`]).
    #[error(transparent)]
    Meeting(#[from] crate::calibration_guard::GuardError),
    /// The session has no segment of its plan with data.
    #[error("the session has no segment of its plan with data: nothing to report")]
    NothingToReport,
    /// A segment named for a replay ([`ReportOptions::static_run`], [`ReportOptions::rate_run`]) is
    /// not in the session.
    #[error("segment '{name}' is not in the session")]
    RunNotInSession {
        /// The name given.
        name: String,
    },
    /// A segment named for a replay is not of the replay's kind: it names the segments that are.
    #[error(
        "segment '{name}' is not {}: {} needs one ({})",
        .run.wanted(),
        .spelling.name(.run.option()),
        match .examples.is_empty() {
            true => "this session has none".to_string(),
            false => format!("e.g. '{}'", .examples.join("', '")),
        }
    )]
    RunOfOtherKind {
        /// The name given.
        name: String,
        /// Which replay it was named for.
        run: NamedRun,
        /// Up to three segments of the replay's kind.
        examples: Vec<String>,
        /// The caller's names of the options.
        spelling: Spelling,
    },
    /// The navigation check has no segment to replay (the reasons, one per replay).
    #[error("nothing to replay: {}", Note::texts(.0).join("; "))]
    NothingToReplay(Vec<Note>),
    /// A figure could not be drawn.
    #[error(transparent)]
    Figure(#[from] plot::FigureError),
    /// A file could not be written.
    #[error("cannot write {}", .0.display())]
    Io(PathBuf, #[source] std::io::Error),
    /// A page of the report could not be written.
    #[error(transparent)]
    Written(#[from] recording::output_file::OutputFileError),
    /// The simulation of the navigation check failed.
    #[error(transparent)]
    Simulate(SimulateError),
    /// The calibration of the navigation check failed.
    #[error(transparent)]
    Estimate(estimator::estimate::EstimateError),
    /// The navigation check's calibration misfits its own simulated session far beyond the
    /// simulated noise: its navigation figures would describe a fit, not the unit.
    #[error(
        "the calibration of the simulated session misfits it: {what} = {value:.4e}, above \
         {limit} (a fit to the simulated noise gives about 1), so the navigation figures would \
         describe the misfit, not the unit"
    )]
    Misfit {
        /// The figure ("χ²/dof", "the temperature fit's χ²/dof").
        what: &'static str,
        /// Its value.
        value: f64,
        /// The limit it exceeds.
        limit: f64,
    },
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
    pub(crate) fn colour(self) -> usize {
        match self {
            Compensation::BiasScale => 0,
            Compensation::Static => 1,
            Compensation::Full => 2,
        }
    }
}

/// Where a row's theoretical specific force comes from (see the module doc).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Theoretical {
    /// The session's own fit: the segment's fitted attitude, at the calibration's reference point
    /// (what the terminal's "Outputs per segment" shows).
    Fitted,
    /// The plan's nominal attitude (a fixture segment the fit has no value for).
    Planned,
    /// A free attitude the fit has no value for: nothing to compare against (NaN).
    Unknown,
}

/// One segment's outputs before and after compensation (Tables 2 and 4).
#[derive(Clone, Debug, PartialEq)]
pub struct SegmentRow {
    /// Segment name.
    pub name: String,
    /// What it does.
    pub kind: SegmentKind,
    /// The plan's up (the fitted up once [`Theoretical::Fitted`]).
    pub up_b: [f64; 3],
    /// Whether the plan gives the attitude only as a rough guess (hand-held).
    pub free: bool,
    /// Where `truth_g` comes from.
    pub theoretical: Theoretical,
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
    /// Theoretical specific force at the reference point, g (NaN when [`Theoretical::Unknown`]).
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
    pub(crate) fn output_g(&self, c: Compensation) -> [f64; 3] {
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
    /// Why a replay is left out, one line each (also among the warnings).
    pub navigation_left_out: Vec<Note>,
    /// The session's own fit (χ², excluded segments, observability), or why it failed.
    pub session_fit: Result<CalibrationOutcome, estimator::estimate::EstimateError>,
    /// The session's segments through the session fit's own calibration (empty when it failed or its
    /// compensator cannot be built: the text then shows the fit's values only).
    pub session_fit_segments: Vec<SegmentRow>,
    /// The temperature figure, for a session whose own fit has a temperature model.
    pub temperature_figure: Option<super::plot::Figure>,
    /// Each segment's fitted bias over the session's time, for a session fit under a bias random
    /// walk (docs/model.md §11.4).
    pub bias_walk_figure: Option<super::plot::Figure>,
    /// Warnings for the reader.
    pub warnings: Vec<Note>,
    /// The calibration's three lever arms are one package's (docs/model.md §4.7): Table 3 shows the
    /// one lever arm and says the in-package size effect is not observable.
    pub single_package: bool,
}

/// The true specific force, rates and the three compensated outputs of every segment.
pub fn segment_rows(
    plan: &Plan,
    stats: &[SegmentStats],
    cal: &Calibration,
) -> Result<Vec<SegmentRow>, ReportError> {
    let g = cal.gravity_m_s2;
    let stat = Compensator::new(cal, LeverMode::Off).map_err(ReportError::Compensator)?;
    let full =
        Compensator::new(cal, LeverMode::RateAndAcceleration).map_err(ReportError::Compensator)?;
    let gyro_inv = cal
        .gyro
        .unwrap_or(shared::GyroCorrection::PERFECT)
        .checked_inverse()
        .map_err(ReportError::Gyro)?;
    let u0 = cal.statics.zero_bias_out;
    let k = cal.statics.scale_out_per_g;
    let trace = |m: &[[f64; 3]; 3]| m[0][0] + m[1][1] + m[2][2];
    // Gyro noise variance (trace), from the static segments.
    let gyro_noise = trace(
        &Noise::pooled(
            stats
                .iter()
                .filter(|s| plan.segment(&s.name).is_some_and(|p| p.is_static())),
        )
        .gyro_cov,
    );
    let mut rows = Vec::new();
    for st in stats {
        let Some(sp) = plan.segment(&st.name) else {
            continue;
        };
        let kind = SegmentKind::of(sp);
        let mean_w = st.mean_w_rad_s;
        let w2 = linalg::dot(&mean_w, &mean_w);
        let omega = if kind == SegmentKind::Ramp && w2 > 0.0 {
            let target = (trace(&st.mean_wwt) - gyro_noise).max(w2);
            mean_w.map(|v| v * (target / w2).sqrt())
        } else {
            mean_w
        };
        // A calibration with a temperature model is applied at the segment's mean temperature, as
        // the device applies it (docs/model.md §9).
        let (mut stat, mut full) = (stat, full);
        if let Some(ts) = &st.thermal {
            stat.refresh(ts.mean_c() as f32);
            full.refresh(ts.mean_c() as f32);
        }
        // The body's rate and angular acceleration through the calibration's gyro correction, as the
        // device computes them (docs/model.md §8): `ω = G⁻¹(w − b(T))`, `ω̇ = G⁻¹ẇ`.
        let omega = full
            .correct_rate(&omega.map(|v| v as f32))
            .rad_s
            .map(f64::from);
        let omega_dot = linalg::mat_vec(&gyro_inv, &st.wdot_rad_s2);
        let (truth_g, theoretical) = planned_theoretical(sp, &omega, &omega_dot, g);
        let u = SensorOutputs {
            raw: st.mean_u.map(|v| v as f32),
        };
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
            free: sp.is_free(),
            theoretical,
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

/// The plan's specific force at the reference point, `g·up_b − W p` in g, for a fixture's known
/// attitude; nothing (NaN) for a free one, whose `up_b` is only a rough guess.
fn planned_theoretical(
    sp: &recording::session::SegmentPlan,
    omega: &[f64; 3],
    omega_dot: &[f64; 3],
    g: f64,
) -> ([f64; 3], Theoretical) {
    if sp.is_free() {
        return ([f64::NAN; 3], Theoretical::Unknown);
    }
    let p = sp.table_centre_m.unwrap_or([0.0; 3]);
    let wp = linalg::mat_vec(&linalg::lever_matrix(omega, omega_dot), &p);
    (
        std::array::from_fn(|j| sp.up_b[j] - wp[j] / g),
        Theoretical::Planned,
    )
}

/// The replay a segment is named for ([`ReportOptions::static_run`], [`ReportOptions::rate_run`]).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum NamedRun {
    /// The static replay.
    Static,
    /// The rotating replay, at a constant rate.
    Rate,
}

impl NamedRun {
    /// The kind of segment it replays.
    fn kind(self) -> SegmentKind {
        match self {
            NamedRun::Static => SegmentKind::Static,
            NamedRun::Rate => SegmentKind::ConstantRate,
        }
    }

    /// That kind in words.
    fn wanted(self) -> &'static str {
        match self {
            NamedRun::Static => "static",
            NamedRun::Rate => "at a constant rate",
        }
    }

    /// The option that names it.
    fn option(self) -> UserOption {
        match self {
            NamedRun::Static => UserOption::StaticRun,
            NamedRun::Rate => UserOption::RateRun,
        }
    }
}

/// Computes everything the report shows, beside `session_fit`: the session's own fit, received
/// from the caller (`app::report` runs it with [`session_fit_options`]), or why the session alone
/// does not calibrate.
pub fn build_report(
    plan: &Plan,
    stats: &[SegmentStats],
    cal: &Calibration,
    uncertainty: Option<&Uncertainty>,
    session_fit: Result<CalibrationOutcome, EstimateError>,
    options: &ReportOptions,
) -> Result<ReportData, ReportError> {
    let mut segments = segment_rows(plan, stats, cal)?;
    if segments.is_empty() {
        return Err(ReportError::NothingToReport);
    }
    let mut warnings = Vec::new();
    match &session_fit {
        Ok(o) => refer_to_fit(&mut segments, o),
        Err(e) => warnings.push(Note::SessionDoesNotCalibrate(e.clone())),
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
    let mut navigation_left_out = Vec::new();
    let navigation = navigation_runs(
        &segments,
        cal.gravity_m_s2,
        options,
        &mut navigation_left_out,
    )?;
    warnings.extend(navigation_left_out.iter().cloned());
    let session_fit_segments = match &session_fit {
        Ok(o) => segment_rows(plan, stats, &o.calibration).unwrap_or_default(),
        Err(_) => Vec::new(),
    };
    let temperature_figure = session_fit.as_ref().ok().and_then(|o| {
        super::thermal::figure(o, Some(&super::thermal::soak_points(o, plan, stats)))
    });
    let bias_walk_figure = session_fit
        .as_ref()
        .ok()
        .and_then(super::figures::bias_walk_figure);
    let r = &cal.lever_arms.r_m;
    let single_package = (plan.package == Package::Single
        || session_fit.as_ref().is_ok_and(|o| o.single_package))
        && r[1] == r[0]
        && r[2] == r[0];
    Ok(ReportData {
        single_package,
        temperature_figure,
        bias_walk_figure,
        calibration: *cal,
        uncertainty: uncertainty.cloned(),
        unit_symbol: cal.statics.output_unit.symbol().to_string(),
        segments,
        chi2,
        chi2_terms: terms,
        navigation,
        navigation_left_out,
        session_fit,
        session_fit_segments,
        warnings,
    })
}

/// The options of the session's own fit that a report of `cal` sets beside it: the report's
/// estimator options with the reference point `cal`'s lever arms are referred to, so that the fit
/// gives its specific force where this calibration's output is.
pub fn session_fit_options(cal: &Calibration, options: &ReportOptions) -> EstimateOptions {
    use estimator::estimate::ReferenceChoice;
    let reference = match cal.reference {
        shared::ReferencePoint::TableAxis => ReferenceChoice::TableAxis,
        shared::ReferencePoint::Centroid => ReferenceChoice::Centroid,
        shared::ReferencePoint::BodyPoint { offset_m } => ReferenceChoice::BodyPoint(offset_m),
    };
    EstimateOptions {
        reference,
        ..options.estimate.clone()
    }
}

/// Every row the fit used takes the fit's theoretical specific force and fitted up: the one meaning
/// of "theoretical" the terminal shows too (docs/model.md §7: a mount's attitude is estimated).
fn refer_to_fit(rows: &mut [SegmentRow], fit: &CalibrationOutcome) {
    for r in rows.iter_mut() {
        let Some(d) = fit
            .segments
            .iter()
            .find(|d| d.name == r.name && d.used && d.theoretical_g.iter().all(|v| v.is_finite()))
        else {
            continue;
        };
        r.truth_g = d.theoretical_g;
        r.up_b = d.up_b;
        r.theoretical = Theoretical::Fitted;
    }
}

/// The static and the rotating replay, where they mean something. A free (hand-held) position's
/// attitude is fitted from the same outputs the replay would judge: its error after compensation is
/// the fit's own residual along gravity only, so it is not replayed (and the reader is told why).
fn navigation_runs(
    segments: &[SegmentRow],
    g: f64,
    options: &ReportOptions,
    warnings: &mut Vec<Note>,
) -> Result<Vec<NavigationRun>, ReportError> {
    let find = |name: &str| {
        segments
            .iter()
            .find(|r| r.name == name)
            .ok_or_else(|| ReportError::RunNotInSession { name: name.into() })
    };
    let known = |r: &&SegmentRow| !r.free && r.theoretical != Theoretical::Unknown;
    // A named run of the other kind would replay the wrong case under the right heading.
    let of_kind = |name: &str, run: NamedRun| {
        let row = find(name)?;
        let kind = run.kind();
        if row.kind != kind {
            let examples = (segments.iter())
                .filter(|r| r.kind == kind)
                .take(3)
                .map(|r| r.name.clone())
                .collect();
            return Err(ReportError::RunOfOtherKind {
                name: name.into(),
                run,
                examples,
                spelling: options.estimate.spelling,
            });
        }
        Ok(row)
    };
    let static_row = match &options.static_run {
        Some(n) => Some(of_kind(n, NamedRun::Static)?).filter(known),
        None => segments
            .iter()
            .filter(known)
            .find(|r| r.kind == SegmentKind::Static),
    };
    let rate_row = match &options.rate_run {
        Some(n) => Some(of_kind(n, NamedRun::Rate)?).filter(known),
        None => segments
            .iter()
            .filter(known)
            .filter(|r| r.kind == SegmentKind::ConstantRate)
            .fold(None::<&SegmentRow>, |best, r| match best {
                Some(b) if b.planned_rate_deg_s.abs() >= r.planned_rate_deg_s.abs() => Some(b),
                _ => Some(r),
            }),
    };
    let free = segments.iter().any(|r| r.free);
    if static_row.is_none() {
        warnings.push(if free {
            Note::ReplayHandHeld
        } else {
            Note::NoStaticReplay
        });
    }
    if rate_row.is_none() && !free {
        warnings.push(Note::NoRateReplay);
    }
    Ok([static_row, rate_row]
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
        .collect())
}
