//! What the estimator returns: the calibration with its uncertainty, the fit's summary, each segment's
//! diagnostic, the segments left out and why, and what the plan could not determine.

use super::note::Note;
use super::{thermal, GyroEstimate, Method, MountTilt, SegmentKind, StaticSplit, Uncertainty};
use shared::linalg::RowMajor3;
use shared::params::axis_name;
use shared::{Calibration, FittedStatic, LeverArms};

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
        /// The figure that failed, against its limit.
        figure: ScreenFigure,
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
        /// The segment's attitude prior (1σ, degrees), where the plan gives one (a hand-held
        /// session's faces).
        prior_sigma_deg: Option<f64>,
        /// The angle allowed, degrees.
        limit_deg: f64,
    },
}

/// The figure a screen measured on a segment and the limit it failed, so that a user sees how far
/// off the segment was, not only that it was left out.
#[derive(Clone, Debug, PartialEq)]
pub struct ScreenFigure {
    /// What was measured ("mean gyro rate", "gyro x noise ratio").
    pub what: String,
    /// The measured value, in `unit`.
    pub value: f64,
    /// The limit, in `unit`.
    pub limit: f64,
    /// The unit of both ("°/s", "×", "°", "rows").
    pub unit: &'static str,
    /// The limit is a most (else a least).
    pub at_most: bool,
}

impl std::fmt::Display for ScreenFigure {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        let (op, word) = if self.at_most {
            (">", "at most")
        } else {
            ("<", "at least")
        };
        let sep = if self.unit == "×" { "" } else { " " };
        write!(
            f,
            "{} {}{sep}{} {op} limit {}{sep}{} ({word})",
            self.what,
            fmt_figure(self.value, self.unit),
            self.unit,
            fmt_figure(self.limit, self.unit),
            self.unit
        )
    }
}

/// A figure with the digits a screen's comparison needs (rows are counted).
fn fmt_figure(v: f64, unit: &str) -> String {
    if unit == "rows" {
        format!("{v:.0}")
    } else if v.abs() >= 100.0 {
        format!("{v:.1}")
    } else {
        format!("{v:.3}")
    }
}

impl ExclusionReason {
    /// The figure that failed and its limit, for the reasons a number decides; `None` for a
    /// segment missing, unplanned, doubled, non-finite or stuck (the reason's text says what).
    pub fn figure(&self) -> Option<ScreenFigure> {
        match self {
            ExclusionReason::Empty { rows, .. } => Some(ScreenFigure {
                what: "valid rows".into(),
                value: *rows as f64,
                limit: 2.0,
                unit: "rows",
                at_most: false,
            }),
            ExclusionReason::Motion { figure, .. } => Some(figure.clone()),
            ExclusionReason::RateContradiction {
                measured_deg_s,
                planned_deg_s,
            } => Some(ScreenFigure {
                what: "gyro rate off the plan's".into(),
                value: (measured_deg_s - planned_deg_s).abs(),
                limit: RATE_TOLERANCE_FRACTION * planned_deg_s.abs() + RATE_TOLERANCE_DEG_S,
                unit: "°/s",
                at_most: true,
            }),
            ExclusionReason::AttitudeContradiction {
                angle_deg,
                limit_deg,
                ..
            } => Some(ScreenFigure {
                what: "attitude off the plan's up_b".into(),
                value: *angle_deg,
                limit: *limit_deg,
                unit: "°",
                at_most: true,
            }),
            _ => None,
        }
    }
}

/// A rotating segment's measured rate may differ from the plan's by this fraction of it …
pub(crate) const RATE_TOLERANCE_FRACTION: f64 = 0.1;
/// … plus this much, °/s.
pub(crate) const RATE_TOLERANCE_DEG_S: f64 = 1.0;

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
            ExclusionReason::Motion { detail, .. } => {
                write!(f, "planned static but moved: {detail}")
            }
            ExclusionReason::RateContradiction {
                measured_deg_s,
                planned_deg_s,
            } => write!(
                f,
                "gyro reads {measured_deg_s:.2} °/s about up_b, the plan says {planned_deg_s:.2} °/s"
            ),
            ExclusionReason::AttitudeContradiction {
                angle_deg,
                prior_sigma_deg: Some(s),
                ..
            } => write!(
                f,
                "measured attitude is {angle_deg:.2}° from the plan's up_b, beyond three times its \
                 {s}° placement prior: the unit sat farther off that face than the prior allows \
                 (`host segment --face-sigma-deg` sets it), or on another face"
            ),
            ExclusionReason::AttitudeContradiction {
                angle_deg,
                prior_sigma_deg: None,
                ..
            } => write!(
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

impl std::fmt::Display for Exclusion {
    /// "'name': reason; figure > limit (at most)": the line every listing of left-out segments uses.
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        write!(f, "'{}': {}", self.name, self.reason)?;
        if let Some(fig) = self.reason.figure() {
            write!(f, "; {fig}")?;
        }
        Ok(())
    }
}

/// The fit's view of one segment: its fitted up, the specific force the fitted model predicts and
/// the χ² check. The outputs before and after compensation (the paper's Tables 2 and 4) are the one
/// table of the report's `segment_rows` (crate `host`), which the terminal text shows beside these.
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
        self.names(|i, j| !self.observable[i][j])
    }

    /// Names of the components not determined because they are not estimable at all (fixed at 0),
    /// in the order of [`Observability::undetermined`].
    pub(crate) fn undetermined_fixed(&self) -> Vec<String> {
        self.names(|i, j| !self.observable[i][j] && self.fixed_at_zero[i][j])
    }

    /// Names ("r1y") of the components `pick(accelerometer, axis)` selects, accelerometer by
    /// accelerometer.
    fn names(&self, pick: impl Fn(usize, usize) -> bool) -> Vec<String> {
        let mut v = Vec::new();
        for i in 0..3 {
            for j in 0..3 {
                if pick(i, j) {
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
    pub notes: Vec<Note>,
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
    /// Covariance of the paper-form values ([`super::paper_labels`] order), after χ² scaling; ∞ on the
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
    /// Warnings for the user, and what the fit chose beside its numbers.
    pub warnings: Vec<super::note::Note>,
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
    /// One lever arm for the three accelerometers (a single package, docs/model.md §4.7): every
    /// `r_i` of the calibration is the package's `r`, and the in-package size effect is not
    /// observable ([`super::package::IN_PACKAGE_NOT_OBSERVABLE`]).
    pub single_package: bool,
    /// The χ² test of one lever arm against three, when the session turns.
    pub package_test: Option<super::package::PackageTest>,
    /// The accelerometers' bias random walk the fit assumed (docs/model.md §11), when asked for.
    pub bias_walk: Option<super::WalkEstimate>,
    /// Under a bias walk, each segment's fitted bias over the session (its wander from `u0`), in
    /// time order; empty without a walk (docs/model.md §11.4).
    pub bias_track: Vec<super::WalkPoint>,
    /// The gyro's bias random walk the gyro model's mean rates were weighted with, °/s/√s
    /// (docs/model.md §11.6), the strongest axis's where they were weighted per axis
    /// ([`super::GyroWalkAxes::used`]); `None` with a constant gyro bias or without a gyro model.
    pub gyro_bias_walk_deg_s_sqrt_s: Option<f64>,
    /// The counts of zero force subtracted when the session's logger's file was read (its plan's
    /// `acc_offset`): the biases are of the logger's own counts and hold them; written to the
    /// calibration file for `apply`. `None`: none was subtracted.
    pub acc_offset: Option<[f64; 3]>,
    /// The gyro's bias random walk estimated from the session, when asked for and the session
    /// estimates a gyro model (used only where it determines it; docs/model.md §11.6).
    pub gyro_walk: Option<super::GyroWalkEstimate>,
}
