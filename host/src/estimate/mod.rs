//! The estimator: from a plan and the per-segment statistics of a recording to a calibration, its
//! uncertainty, and what the plan could not determine (`docs/model.md` §4.2–§4.4).
//!
//! Everything works on [`SegmentStats`], the sufficient statistics of each segment, so the estimator
//! never sees sample rows and costs microseconds whatever the session's length.
//!
//! - [`calibrate_session_stats`]: screening (empty, saturated, moving or mis-attituded segments, plan
//!   ↔ data mismatches), the static least squares (any number of attitudes), the joint weighted
//!   least squares of `M = K·A`, `u0` and the nine lever-arm components from all segments using the
//!   measured gyro statistics ([`Method::Joint`]), or the paper's eq. 24 ([`Method::Paper`]); the full
//!   covariance, propagated to the paper's form; a χ² check per segment; the observability of every
//!   lever-arm component.
//! - [`predict`]: the Cramér–Rao 1σ of every parameter for a plan and a noise level, before any data.
//! - `crate::sim::synth`: noise-free statistics of a plan run on a known unit (the input of [`predict`], and the tests').
//!
//! The modules, in the order a fit runs through them: `screen` (plan ↔ data, screening, the static
//! least squares), `segment` (segment kind, pooled static noise), [`model`] (one segment's mean
//! outputs, the parameter layout), `build` (segment models, mounts, the gyro's observations),
//! [`attitude`] (each mount's tilt unknowns and prior, docs/model.md §7), [`gyro`] (the gyro model,
//! §8), [`gyro_check`] (whether a fitted gyro is plausible), `solve` and `joint` (the weighted least squares), `paper` (the paper's eq. 24, for
//! comparison), `paper_angles` (θ to the paper's angles with their covariance), `uncertainty`,
//! [`plausibility`] (checks before any file is written); [`thermal`], `thermal_gyro` and
//! `thermal_misalignment` (the temperature model, §9); [`handheld_gyro`] (the gyro from hand turns);
//! [`predict`] (Cramér–Rao).

pub mod attitude;
mod build;
pub mod gyro;
pub mod gyro_check;
pub mod handheld_gyro;
mod joint;
pub mod model;
mod paper;
mod paper_angles;
pub mod plausibility;
mod predict;
mod screen;
mod segment;
mod solve;
#[cfg(test)]
mod tests;
#[cfg(test)]
mod tests_fixture;
#[cfg(test)]
mod tests_gyro;
#[cfg(test)]
mod tests_ramp;
pub mod thermal;
mod thermal_gyro;
mod thermal_misalignment;
#[cfg(test)]
mod thermal_tests;
mod uncertainty;

pub use attitude::{BodyFrame, MountTilt, StaticSplit};
pub use gyro::GyroEstimate;
pub use paper_angles::{paper_labels, paper_order, paper_values, PAPER_LEN};
pub use predict::{predict, PredictSettings, Prediction};
pub use screen::median;
pub use segment::{Noise, SegmentKind};
pub use uncertainty::Uncertainty;

use crate::session::{Plan, SegmentStats};
use model::SegModel;
use shared::linalg::{self, RowMajor3};
use shared::params::{axis_name, ParamsError};
use shared::{Calibration, FittedStatic, LeverArms, OutputUnit};
use solve::Problem;

/// Which estimator gives the result.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Method {
    /// Joint weighted least squares of all parameters from all segments (the default).
    Joint,
    /// Static least squares, then the lever arms by the paper's eq. 24 (for comparison).
    Paper,
}

impl std::fmt::Display for Method {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str(match self {
            Method::Joint => "joint least squares",
            Method::Paper => "paper eq. 24",
        })
    }
}

/// Where the reported lever arms are measured from (`docs/model.md` §4.5).
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum ReferenceChoice {
    /// The point on the table's spin axis (the paper's p = 0), or the plan's body origin when the
    /// plan gives the table centre.
    TableAxis,
    /// The centroid of the three sensing points (free of the table centre).
    Centroid,
    /// A given point, body axes, metres, relative to the frame the fit uses (the table-axis point,
    /// or the plan's body origin when the plan gives the table centre).
    BodyPoint([f64; 3]),
}

/// When to scale the covariance by the reduced χ².
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum ChiSquareScaling {
    /// Never: the weights (each segment's own noise) are taken as exact.
    Never,
    /// Always by χ²/dof (also below 1).
    Always,
    /// Only when χ²/dof exceeds its 99 % point for the degrees of freedom (a model error is visible).
    WhenSignificant,
}

/// Estimator settings.
#[derive(Clone, Debug, PartialEq)]
pub struct EstimateOptions {
    /// The method whose result goes into the calibration.
    pub method: Method,
    /// Also run the other method, for the comparison in the report (when the plan allows it).
    pub compare_methods: bool,
    /// Reference point of the reported lever arms.
    pub reference: ReferenceChoice,
    /// Use the measured ω̇ (the slope of ω over each segment); `false` turns the term off (`docs/model.md` §4.6).
    pub use_omega_dot: bool,
    /// χ² scaling of the covariance.
    pub chi2_scaling: ChiSquareScaling,
    /// A lever-arm component whose 1σ exceeds this is reported as not determined, m.
    pub lever_arm_threshold_m: f64,
    /// A lever-arm component whose 1σ exceeds this (with a weak 1 m prior) is not estimable at all and is
    /// fixed at 0, m.
    pub lever_arm_structural_limit_m: f64,
    /// The outputs' valid range (rails), output unit: a segment reaching it is saturated.
    pub output_range: Option<[f64; 2]>,
    /// A segment whose measured attitude is further than this from the plan's is excluded, degrees.
    pub attitude_tolerance_deg: f64,
    /// A static segment whose mean gyro rate differs from the other static segments' by more than this
    /// is moving, rad/s.
    pub motion_rate_threshold_rad_s: f64,
    /// A static segment whose output (or gyro) standard deviation is this many times the static median
    /// is moving.
    pub motion_noise_ratio: f64,
    /// Segments in the plan but not in the data (or the reverse) are errors instead of warnings.
    pub strict_segments: bool,
    /// Fail with [`EstimateError::PlanCannotObserve`] when any lever-arm component is not determined.
    pub require_lever_arms: bool,
    /// Use the gyro's mean axis during a spin as a measurement of the mount's true up, with this
    /// floor on its 1σ (how well the gyro's axes are taken to agree with the body frame), rad;
    /// `None`: do not (docs/model.md §7).
    pub gyro_axis_sigma_rad: Option<f64>,
    /// The gyro: estimated with the accelerometers (`w = G ω + b`, docs/model.md §8) or taken as
    /// perfect.
    pub gyro_model: GyroModel,
    /// The static parameters from the rest segments alone: a spin whose mount has a rest segment
    /// enters as its difference from it (docs/model.md §7), so a misfit of the dynamic model (a gyro
    /// error, an unmodelled ω̇) cannot move them. Off by default: with the mounts' tilts shared by
    /// their rest and spin segments and the gyro modelled, the joint fit already keeps a 1 mg misfit
    /// to a third of a 1σ move (tested), and it is twice as precise on the lever arms.
    pub static_from_rest: bool,
}

/// How the estimator treats the gyro.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum GyroModel {
    /// Its readings are the body's rate (then its spin axis measures each spinning mount's up).
    Perfect,
    /// `w = G ω + b` estimated from the same session when it has spins.
    Estimate,
}

impl Default for EstimateOptions {
    fn default() -> Self {
        EstimateOptions {
            method: Method::Joint,
            compare_methods: true,
            reference: ReferenceChoice::TableAxis,
            use_omega_dot: true,
            chi2_scaling: ChiSquareScaling::WhenSignificant,
            lever_arm_threshold_m: 2e-4,
            lever_arm_structural_limit_m: 0.05,
            output_range: None,
            attitude_tolerance_deg: 3.0,
            motion_rate_threshold_rad_s: 0.5f64.to_radians(),
            motion_noise_ratio: 2.0,
            strict_segments: false,
            require_lever_arms: false,
            // 1 µrad: the gyro is taken as perfect (its axes are the body frame's), so the spin
            // axis's own noise weighs it (0.05 °/s over 60 s at 200 °/s is about 1 µrad). A gyro whose
            // axes are not calibrated should set its misalignment here, or `None`.
            gyro_axis_sigma_rad: Some(1e-6),
            gyro_model: GyroModel::Estimate,
            static_from_rest: false,
        }
    }
}

/// Why no calibration could be made.
#[derive(Clone, Debug, PartialEq)]
pub enum EstimateError {
    /// No usable static segment.
    NoStaticSegments {
        /// How many static segments the plan has (all excluded when > 0).
        planned: usize,
        /// Why each was excluded ("'x+': …").
        reasons: Vec<String>,
    },
    /// The usable static attitudes do not span 3-D (the bias and `M` need ≥ 4 attitudes not on a plane).
    TooFewAttitudes {
        /// Usable static attitudes.
        attitudes: usize,
        /// Directions along which an attitude is missing (unit vectors, body axes).
        needed_directions: Vec<[f64; 3]>,
    },
    /// The plan cannot determine these parameters.
    PlanCannotObserve {
        /// The parameters.
        parameters: Vec<String>,
        /// What to add to the plan.
        hint: String,
    },
    /// The normal equations are singular.
    Singular {
        /// Which fit.
        what: &'static str,
    },
    /// A plan segment has no data (strict mode).
    MissingSegment {
        /// Its name.
        name: String,
    },
    /// The data have a segment the plan does not list (strict mode).
    UnknownSegment {
        /// Its name.
        name: String,
    },
    /// The estimate is not a valid calibration.
    Params(ParamsError),
    /// The fit ran but its result is not a plausible unit (see [`plausibility`]).
    Implausible {
        /// Each problem, naming the segments or axes.
        problems: Vec<String>,
    },
    /// The temperature model cannot be fitted or is implausible (the message says why).
    Temperature(String),
}

impl std::fmt::Display for EstimateError {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match self {
            EstimateError::Temperature(why) => write!(
                f,
                "temperature model: {why}; check the recording's temp_c column and the soak steps"
            ),
            EstimateError::NoStaticSegments { planned: 0, .. } => write!(
                f,
                "the plan has no static segment: add at least four static attitudes (e.g. ±1 g on each axis)"
            ),
            EstimateError::NoStaticSegments { planned, reasons } => write!(
                f,
                "all {planned} static segments were excluded; re-record them. Reasons:\n  - {}",
                reasons.join("\n  - ")
            ),
            EstimateError::TooFewAttitudes {
                attitudes,
                needed_directions,
            } => {
                write!(
                    f,
                    "the {attitudes} usable static attitude(s) do not span 3-D, so the biases and the \
                     scale/misalignment matrix are not determined; add static segments with up_b along"
                )?;
                for d in needed_directions {
                    write!(f, " ±[{:.3}, {:.3}, {:.3}]", d[0], d[1], d[2])?;
                }
                Ok(())
            }
            EstimateError::PlanCannotObserve { parameters, hint } => write!(
                f,
                "the plan cannot determine {}: {hint}",
                parameters.join(", ")
            ),
            EstimateError::Singular { what } => write!(
                f,
                "the {what} is singular: the segments do not determine the parameters"
            ),
            EstimateError::MissingSegment { name } => write!(
                f,
                "segment '{name}' is in the plan but has no rows in the data: record it or remove it from plan.toml"
            ),
            EstimateError::UnknownSegment { name } => write!(
                f,
                "segment '{name}' is in the data but not in the plan: add it to plan.toml (up_b, rate_deg_s) or drop its rows"
            ),
            EstimateError::Params(e) => write!(f, "the estimate is not a valid calibration: {e}"),
            EstimateError::Implausible { problems } => write!(
                f,
                "no calibration written: the result is not plausible:\n  - {}",
                problems.join("\n  - ")
            ),
        }
    }
}

impl std::error::Error for EstimateError {}

impl From<ParamsError> for EstimateError {
    fn from(e: ParamsError) -> Self {
        EstimateError::Params(e)
    }
}

/// Why a segment was left out.
#[derive(Clone, Debug, PartialEq)]
pub enum ExclusionReason {
    /// In the plan, no rows in the data.
    MissingFromData,
    /// Rows in the data, not in the plan.
    NotInPlan,
    /// The data have the segment twice.
    Duplicate,
    /// Fewer than two valid rows.
    Empty {
        /// Valid rows.
        rows: u64,
        /// Rows rejected for NaN/∞.
        rejected: u64,
    },
    /// A statistic is NaN or infinite.
    NonFinite,
    /// An output is stuck or at its rail.
    Saturated {
        /// Accelerometer 0..3.
        axis: usize,
        /// What was seen.
        detail: String,
    },
    /// A static segment that moved.
    Motion {
        /// What was seen.
        detail: String,
    },
    /// The measured rate contradicts the plan's.
    RateContradiction {
        /// Measured mean rate about up_b, °/s.
        measured_deg_s: f64,
        /// Planned mean rate, °/s.
        planned_deg_s: f64,
    },
    /// The measured attitude contradicts the plan's up_b.
    AttitudeContradiction {
        /// Angle between measured and planned "up", degrees.
        angle_deg: f64,
    },
}

impl std::fmt::Display for ExclusionReason {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match self {
            ExclusionReason::MissingFromData => write!(
                f,
                "in the plan but no rows in the data (record it, or remove it from plan.toml)"
            ),
            ExclusionReason::NotInPlan => write!(
                f,
                "rows in the data but not in the plan (add it to plan.toml, or drop its rows)"
            ),
            ExclusionReason::Duplicate => write!(f, "appears twice in the data; the first is used"),
            ExclusionReason::Empty { rows, rejected } => write!(
                f,
                "only {rows} valid row(s) ({rejected} rejected as NaN/∞): re-record it"
            ),
            ExclusionReason::NonFinite => write!(f, "its statistics are not finite"),
            ExclusionReason::Saturated { axis, detail } => {
                write!(f, "accelerometer {} saturated or stuck: {detail}", axis_name(*axis))
            }
            ExclusionReason::Motion { detail } => {
                write!(f, "planned static but moved: {detail}")
            }
            ExclusionReason::RateContradiction {
                measured_deg_s,
                planned_deg_s,
            } => write!(
                f,
                "gyro reads {measured_deg_s:.2} °/s about up_b, the plan says {planned_deg_s:.2} °/s"
            ),
            ExclusionReason::AttitudeContradiction { angle_deg } => write!(
                f,
                "measured attitude is {angle_deg:.2}° from the plan's up_b (wrong mount, or the plan's up_b is wrong)"
            ),
        }
    }
}

/// A segment left out, with the reason.
#[derive(Clone, Debug, PartialEq)]
pub struct Exclusion {
    /// Segment name.
    pub name: String,
    /// Why.
    pub reason: ExclusionReason,
}

/// The fit's view of one segment: its fitted up, the specific force the fitted model predicts and
/// the χ² check. The outputs before and after compensation (the paper's Tables 2 and 4) are the one
/// table of [`crate::report::segment_rows`], which the terminal text shows beside these.
#[derive(Clone, Debug, PartialEq)]
pub struct SegmentDiagnostic {
    /// Segment name.
    pub name: String,
    /// What it does.
    pub kind: SegmentKind,
    /// Rows.
    pub count: u64,
    /// The plan's up.
    pub up_b: [f64; 3],
    /// Measured mean rate about up_b, °/s.
    pub rate_deg_s: f64,
    /// Whether the fit used it.
    pub used: bool,
    /// The specific force the fitted model gives at the calibration's reference point, g.
    pub theoretical_g: [f64; 3],
    /// Standard error of the segment's means, g.
    pub noise_g: [f64; 3],
    /// Whitened residual² (3 outputs); `None` when not used.
    pub chi2: Option<f64>,
    /// χ² above its 99.9 % point.
    pub chi2_flagged: bool,
}

/// Goodness of fit.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct FitSummary {
    /// Σ whitened residual².
    pub chi2: f64,
    /// Degrees of freedom.
    pub dof: i64,
    /// χ²/dof (NaN when dof ≤ 0).
    pub reduced_chi2: f64,
    /// The factor the 1σ values were multiplied by (√(χ²/dof) or 1).
    pub sigma_scale: f64,
}

/// What the plan determined.
#[derive(Clone, Debug, PartialEq)]
pub struct Observability {
    /// 1σ of each lever-arm component (∞ when fixed), m.
    pub lever_arm_sigma_m: RowMajor3,
    /// Determined to better than the threshold.
    pub observable: [[bool; 3]; 3],
    /// Not estimable at all: fixed at 0 in the fit.
    pub fixed_at_zero: [[bool; 3]; 3],
    /// The threshold used, m.
    pub threshold_m: f64,
}

impl Observability {
    /// Names of the components not determined, e.g. "r1y".
    pub fn undetermined(&self) -> Vec<String> {
        let mut v = Vec::new();
        for i in 0..3 {
            for j in 0..3 {
                if !self.observable[i][j] {
                    v.push(format!("r{}{}", i + 1, axis_name(j)));
                }
            }
        }
        v
    }
}

/// The other method's lever arms, for the report's comparison.
#[derive(Clone, Debug, PartialEq)]
pub struct MethodComparison {
    /// Which method.
    pub method: Method,
    /// Its lever arms (same reference as the main result).
    pub lever_arms: LeverArms,
    /// Their 1σ, m.
    pub lever_arm_sigma_m: RowMajor3,
    /// Notes (pitfalls, what was used).
    pub notes: Vec<String>,
}

/// Everything `host calibrate` needs.
#[derive(Clone, Debug, PartialEq)]
pub struct CalibrationOutcome {
    /// The method of the result.
    pub method: Method,
    /// The calibration.
    pub calibration: Calibration,
    /// 1σ of every value (after χ² scaling, see `fit.sigma_scale`).
    pub uncertainty: Uncertainty,
    /// Covariance of the paper-form values ([`paper_labels`] order), after χ² scaling; ∞ on the
    /// diagonal of values that depend on a fixed lever-arm component.
    pub covariance: Vec<Vec<f64>>,
    /// Goodness of fit.
    pub fit: FitSummary,
    /// Per segment, in plan order (missing ones left out).
    pub segments: Vec<SegmentDiagnostic>,
    /// Excluded segments with reasons.
    pub excluded: Vec<Exclusion>,
    /// Lever-arm observability.
    pub observability: Observability,
    /// The other method, when run.
    pub comparison: Option<MethodComparison>,
    /// Warnings for the user.
    pub warnings: Vec<String>,
    /// The fitted form and lever arms in the fit's frame (before re-referencing).
    pub fitted: FittedStatic,
    /// Each mount's estimated attitude (docs/model.md §7).
    pub mount_tilts: Vec<MountTilt>,
    /// The static 1σ split into intrinsic and body-frame alignment parts, and what fixes the frame.
    pub static_split: StaticSplit,
    /// Every fitted parameter (intrinsic, then two tilts per mount): name, value, 1σ (0 when fixed).
    pub parameters: Vec<(String, f64, f64)>,
    /// The gyro model, when estimated.
    pub gyro: Option<GyroEstimate>,
    /// The temperature fit, when the session was recorded over a temperature range.
    pub thermal: Option<thermal::ThermalFit>,
}

/// A segment of the session after matching plan and data.
#[derive(Clone, Debug)]
pub(crate) struct SessionSeg {
    pub plan_idx: usize,
    pub stats: SegmentStats,
    pub kind: SegmentKind,
    pub used: bool,
}

/// Calibrates from a plan and its segments' statistics; a result that fails the plausibility checks
/// ([`plausibility`]) is an error. A session recorded over a temperature range first gets its
/// temperature model ([`thermal`]); the rest is estimated from the statistics referred to the reference
/// temperature.
pub fn calibrate_session_stats(
    plan: &Plan,
    stats: &[SegmentStats],
    options: &EstimateOptions,
) -> Result<CalibrationOutcome, EstimateError> {
    let (fit, notes) = thermal::fit_session(plan, stats).map_err(EstimateError::Temperature)?;
    let mut outcome = match &fit {
        None => plausibility::check(plan, stats, fit_session(plan, stats, options))?,
        Some(fit) => {
            let referred = fit.refer_to_reference(stats);
            plausibility::check(plan, &referred, fit_session(plan, &referred, options))?
        }
    };
    outcome.warnings.extend(notes);
    outcome.calibration.temperature = fit.as_ref().map(|f| f.model);
    outcome.thermal = fit;
    Ok(outcome)
}

/// [`calibrate_session_stats`] for statistics at one temperature, before the plausibility checks.
fn fit_session(
    plan: &Plan,
    stats: &[SegmentStats],
    options: &EstimateOptions,
) -> Result<CalibrationOutcome, EstimateError> {
    let mut warnings = Vec::new();
    let mut excluded = Vec::new();
    let mut segs = screen::match_plan(plan, stats, options, &mut excluded, &mut warnings)?;
    screen::screen(plan, &mut segs, options, &mut excluded);
    let planned_static = plan.segments.iter().filter(|s| s.is_static()).count();
    let noise = screen::pooled_noise(&segs);
    let (mounts, seg_mount) = build::build_mounts(plan, &segs);
    let models = build::build_models(plan, &segs, &noise, options, &mounts, &seg_mount, None);
    let mut problem = Problem::new(models, mounts);
    let static_fit = match screen::static_fit_with_attitude_check(
        plan,
        &mut segs,
        &mut problem,
        options,
        &mut excluded,
        planned_static,
    ) {
        Ok(fit) => {
            build::seed_free_mounts(plan, &segs, &noise, &mut problem, &fit.theta);
            fit
        }
        Err(
            e @ (EstimateError::NoStaticSegments { .. } | EstimateError::TooFewAttitudes { .. }),
        ) => attitude::free_static_fit(plan, &segs, &noise, &mut problem, e)?.0,
        Err(e) => return Err(e),
    };
    let spins = segs.iter().any(|s| s.used && s.kind != SegmentKind::Static);
    let gyro_on =
        options.gyro_model == GyroModel::Estimate && spins && options.method == Method::Joint;
    let gyro_base = problem.n_params();
    if gyro_on {
        problem.gyro_block = Some(build::build_gyro_block(
            plan,
            &segs,
            &noise,
            &problem.mounts,
            &seg_mount,
            gyro_base,
        ));
    } else {
        problem.gyro = build::build_gyro(plan, &segs, &noise, options, &problem.mounts, &seg_mount);
    }
    let frame = attitude::body_frame(&problem);
    let group = options.static_from_rest && options.method == Method::Joint;
    let is_rest = |seg: usize| segs[seg].kind == SegmentKind::Static;
    let rests: Vec<bool> = (0..segs.len()).map(is_rest).collect();
    if group {
        problem.group_spins(&|seg| rests[seg]);
    }
    let mut start = static_fit.theta.clone();
    if gyro_on {
        start.resize(problem.n_params(), 0.0);
        let b = build::static_gyro(&segs);
        for i in 0..3 {
            start[gyro::idx_g(gyro_base, i, i)] = 1.0;
            start[gyro::idx_b(gyro_base, i)] = b[i];
        }
    }
    let mut gyro_estimate = None;

    let (main_theta, main_cov, main_free, fixed, fit_chi2, fit_dof, notes_main) =
        match options.method {
            Method::Joint => {
                let ctx = joint::Context {
                    plan,
                    noise: &noise,
                    options,
                    seg_mount: &seg_mount,
                    rests: group.then_some(rests.as_slice()),
                };
                let (j, g) = joint::with_gyro(
                    &ctx,
                    &mut segs,
                    &mut problem,
                    start,
                    &mut excluded,
                    frame,
                    gyro_on.then_some(gyro_base),
                )?;
                gyro_estimate = g;
                (j.theta, j.cov, j.free, j.fixed, j.chi2, j.dof, Vec::new())
            }
            Method::Paper => {
                let p = paper::eq24(plan, &segs, &problem.models, &static_fit)?;
                let (chi2, dof) = chi2_of(&problem.models, &p.theta, 12 + 9);
                let free = static_fit.free.clone();
                (p.theta, p.cov, free, [[false; 3]; 3], chi2, dof, p.notes)
            }
        };
    warnings.extend(notes_main);

    // χ² and its scaling.
    let reduced = if fit_dof > 0 {
        fit_chi2 / fit_dof as f64
    } else {
        f64::NAN
    };
    let scale2 = match options.chi2_scaling {
        ChiSquareScaling::Never => 1.0,
        ChiSquareScaling::Always if reduced.is_finite() => reduced,
        ChiSquareScaling::WhenSignificant
            if reduced.is_finite() && reduced > 1.0 + 2.33 * (2.0 / fit_dof as f64).sqrt() =>
        {
            reduced
        }
        _ => 1.0,
    };
    if fit_dof <= 0 {
        warnings.push(
            "no residual degrees of freedom: the χ² check and scaling are not possible; \
             add segments (repeat attitudes or rates)"
                .into(),
        );
    } else if scale2 > 1.0 {
        warnings.push(format!(
            "χ²/dof = {reduced:.1} (dof {fit_dof}): the residuals exceed the segments' own noise, so the \
             model misses an error source it cannot see (table attitude or rate error, bias drift, \
             a table centre off the spin axis); the 1σ values are scaled by {:.2}",
            scale2.sqrt()
        ));
    }

    let frame_note = screen::reference_frame(plan, options, &mut warnings);
    let conv = paper_angles::convert(&main_theta, &main_cov, scale2, &fixed, options, &frame_note)?;
    let mut observability = conv.observability(options);
    if options.method == Method::Paper {
        observability.fixed_at_zero = [[false; 3]; 3];
    }
    let undetermined = observability.undetermined();
    if !undetermined.is_empty() {
        let fixed_names: Vec<String> = undetermined
            .iter()
            .filter(|n| {
                let b = n.as_bytes();
                let i = (b[1] - b'1') as usize;
                let j = (b[2] - b'x') as usize;
                observability.fixed_at_zero[i][j]
            })
            .cloned()
            .collect();
        warnings.push(format!(
            "the plan does not determine lever-arm component(s) {} to {:.0} µm{}; add rotations about \
             oblique axes (tilted mounts) and/or spin-up segments (docs/model.md §4.4)",
            undetermined.join(", "),
            options.lever_arm_threshold_m * 1e6,
            if fixed_names.is_empty() {
                String::new()
            } else {
                format!(" ({} not observable at all: fixed at 0)", fixed_names.join(", "))
            }
        ));
        if options.require_lever_arms {
            return Err(EstimateError::PlanCannotObserve {
                parameters: undetermined,
                hint: "add rotations about oblique axes and/or spin-up segments".into(),
            });
        }
    }

    let output_unit: OutputUnit = plan.output_unit;
    let fitted = FittedStatic {
        output_unit,
        m_out_per_g: model::m_of(&main_theta),
        zero_bias_out: model::u0_of(&main_theta),
    };
    let calibration = Calibration {
        statics: fitted.to_paper()?,
        lever_arms: LeverArms {
            r_m: conv.lever_arms,
        },
        reference: frame_note.reference,
        gravity_m_s2: plan.gravity_m_s2,
        // The device corrects its rate with the estimated gyro (docs/model.md §8); a session that did
        // not estimate it leaves the device's gyro taken as perfect.
        gyro: gyro_estimate.as_ref().map(GyroEstimate::device_correction),
        temperature: None,
    };
    let segments = diagnostics(
        plan,
        &segs,
        &problem.all_models(),
        &main_theta,
        &conv.centre_m,
    );
    let comparison = if options.compare_methods {
        compare(
            plan,
            &mut segs.clone(),
            &mut problem.clone(),
            &static_fit,
            options,
            &frame_note,
            frame,
        )
    } else {
        None
    };
    let scaled_cov = &main_cov * scale2;
    let mount_tilts = attitude::mount_tilts(&problem, &main_theta, &scaled_cov, &main_free);
    warnings.extend(attitude::tilt_warnings(&mount_tilts));
    if frame == BodyFrame::Convention {
        warnings.push(format!("{frame}"));
    }
    let static_split = attitude::static_split(&main_theta, &scaled_cov, frame);
    let parameters = (0..main_theta.len())
        .map(|p| {
            (
                model::theta_label(p, &problem.mounts),
                main_theta[p],
                scaled_cov[(p, p)].max(0.0).sqrt(),
            )
        })
        .collect();
    let flagged: Vec<&SegmentDiagnostic> = segments.iter().filter(|d| d.chi2_flagged).collect();
    if !flagged.is_empty() {
        let statics = flagged.iter().any(|d| d.kind == SegmentKind::Static);
        let rotating = flagged.iter().any(|d| d.kind != SegmentKind::Static);
        let names: Vec<&str> = flagged.iter().map(|d| d.name.as_str()).collect();
        let mut sources = Vec::new();
        if statics {
            sources.push("table attitude error or bias drift (the model takes up_b as exact and the bias as constant)");
        }
        if rotating {
            sources.push("rate-dependent effects outside the model (table wobble, a table centre off the spin axis, gyro scale or misalignment)");
        }
        warnings.push(format!(
            "segment(s) {} have residuals well above their own noise: {}",
            names.join(", "),
            sources.join("; ")
        ));
    }
    Ok(CalibrationOutcome {
        method: options.method,
        calibration,
        uncertainty: conv.uncertainty(&observability),
        covariance: conv.cov_rows(),
        fit: FitSummary {
            chi2: fit_chi2,
            dof: fit_dof,
            reduced_chi2: reduced,
            sigma_scale: scale2.sqrt(),
        },
        segments,
        excluded,
        observability,
        comparison,
        warnings,
        fitted,
        mount_tilts,
        static_split,
        parameters,
        gyro: gyro_estimate,
        thermal: None,
    })
}

/// The angle between two unit vectors `chord` apart (|a − b| = 2 sin(θ/2)), degrees.
pub(crate) fn chord_to_angle_deg(chord: f64) -> f64 {
    (2.0 * (0.5 * chord).min(1.0).asin()).to_degrees()
}

/// χ² of all models at θ, and dof for `n_params` parameters.
fn chi2_of(models: &[SegModel], theta: &[f64], n_params: usize) -> (f64, i64) {
    let chi2 = models
        .iter()
        .map(|m| {
            m.whitened_residual(theta)
                .iter()
                .map(|v| v * v)
                .sum::<f64>()
        })
        .sum();
    (chi2, 3 * models.len() as i64 - n_params as i64)
}

/// The other method's lever arms, when it can run.
fn compare(
    plan: &Plan,
    segs: &mut [SessionSeg],
    problem: &mut Problem,
    static_fit: &solve::Fit,
    options: &EstimateOptions,
    frame: &screen::Frame,
    body: BodyFrame,
) -> Option<MethodComparison> {
    let (method, theta, cov, fixed, notes) = match options.method {
        Method::Joint => {
            let p = paper::eq24(plan, segs, &problem.all_models(), static_fit).ok()?;
            (Method::Paper, p.theta, p.cov, [[false; 3]; 3], p.notes)
        }
        Method::Paper => {
            let mut ex = Vec::new();
            let j = joint::joint(
                plan,
                segs,
                problem,
                static_fit.theta.clone(),
                options,
                &mut ex,
                body,
            )
            .ok()?;
            (Method::Joint, j.theta, j.cov, j.fixed, Vec::new())
        }
    };
    let conv = paper_angles::convert(&theta, &cov, 1.0, &fixed, options, frame).ok()?;
    Some(MethodComparison {
        method,
        lever_arms: LeverArms {
            r_m: conv.lever_arms,
        },
        lever_arm_sigma_m: conv.lever_sigma(),
        notes,
    })
}

/// Per segment: the fitted up, the model's specific force at the calibration's reference point
/// `centre_m` (where the device's compensated output is), the noise and the χ² (docs/model.md §6).
fn diagnostics(
    plan: &Plan,
    segs: &[SessionSeg],
    models: &[SegModel],
    theta: &[f64],
    centre_m: &[f64; 3],
) -> Vec<SegmentDiagnostic> {
    let m = model::m_of(theta);
    let k: [f64; 3] = core::array::from_fn(|i| linalg::norm(&m[i]));
    let models_by_seg: std::collections::HashMap<usize, &SegModel> =
        models.iter().map(|s| (s.seg, s)).collect();
    // 99.9 % point of χ² with 3 degrees of freedom.
    const CHI2_3_999: f64 = 16.27;
    segs.iter()
        .enumerate()
        .map(|(idx, s)| {
            let sp = &plan.segments[s.plan_idx];
            let st = &s.stats;
            let up = models_by_seg
                .get(&idx)
                .map_or(sp.up_b, |md| md.tilt.up(theta));
            let rate = linalg::dot(&st.mean_w_rad_s, &up).to_degrees();
            let (theoretical, noise, chi2) = match models_by_seg.get(&idx) {
                Some(md) => {
                    let noise = core::array::from_fn(|i| md.se_cov[i][i].sqrt() / k[i]);
                    let c2: f64 = md.whitened_residual(theta).iter().map(|v| v * v).sum();
                    let f = md.f(theta);
                    let at_reference = linalg::mat_vec(&md.e, centre_m);
                    (
                        core::array::from_fn(|j| f[j] + at_reference[j]),
                        noise,
                        Some(c2),
                    )
                }
                None => (up, [f64::NAN; 3], None),
            };
            SegmentDiagnostic {
                name: sp.name.clone(),
                kind: s.kind,
                count: st.count,
                up_b: up,
                rate_deg_s: rate,
                used: s.used,
                theoretical_g: theoretical,
                noise_g: noise,
                chi2,
                chi2_flagged: chi2.is_some_and(|c| c > CHI2_3_999),
            }
        })
        .collect()
}
