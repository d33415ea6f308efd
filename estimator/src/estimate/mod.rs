//! The estimator: from a plan and the per-segment statistics of a recording to a calibration, its
//! uncertainty, and what the plan could not determine (`docs/model.md` §4.2–§4.4).
//!
//! Everything works on [`recording::session::SegmentStats`], the sufficient statistics of each segment,
//! so the estimator never sees sample rows and costs microseconds whatever the session's length.
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
//! The estimator's types: [`options`] (its settings), [`outcome`] (what it returns), [`error`] (why
//! it made no calibration), [`note`] (how a fit chose its model and what it warns of, as values with one wording each;
//! `note_text` words the warnings). The modules, in the order a fit runs through them: `fit` (the fit's
//! stages, from plan and statistics to the outcome), `fit_checks` (the χ² check, the lever arms'
//! observability, the residual warning), `screen` (plan ↔ data, screening, the static least
//! squares; `screen_motion` for the static segments that moved), `segment` (segment kind, pooled
//! static noise), [`model`] (one segment's mean outputs, the parameter layout), `build` (segment models, mounts, the gyro's observations),
//! [`attitude`] (each mount's tilt unknowns and prior, docs/model.md §7), [`gyro`] (the gyro model,
//! §8), [`gyro_check`] (whether a fitted gyro is plausible), `solve` and `joint` (the weighted least squares), `paper` (the paper's eq. 24, for
//! comparison), `paper_angles` (θ to the paper's angles with their covariance), `uncertainty`,
//! [`plausibility`] (checks before any file is written); [`thermal`], `thermal_gyro` and
//! `thermal_misalignment` (the temperature model, §9); [`handheld_gyro`] (the gyro from hand turns);
//! [`package`] (a single-package unit's one lever arm: its preconditions and χ² test, §4.7);
//! `drift` (the accelerometers' bias random walk: generalised least squares over the segments'
//! time order, its strength by restricted maximum likelihood, §11); `gyro_drift` (the gyro's bias
//! random walk: the gyro model's mean rates by generalised least squares, §11.6);
//! [`predict`] (Cramér–Rao).

pub mod attitude;
mod build;
mod drift;
#[cfg(test)]
mod drift_tests;
pub mod error;
mod fit;
mod fit_checks;
#[cfg(test)]
mod fixture_tests;
pub mod gyro;
pub mod gyro_check;
mod gyro_drift;
#[cfg(test)]
mod gyro_drift_tests;
#[cfg(test)]
mod gyro_tests;
#[cfg(test)]
mod gyro_walk_axes_tests;
pub mod handheld_gyro;
mod joint;
pub mod model;
pub mod note;
mod note_text;
pub mod options;
pub mod outcome;
pub mod package;
#[cfg(test)]
mod package_tests;
mod paper;
mod paper_angles;
pub mod plausibility;
mod predict;
#[cfg(test)]
mod ramp_tests;
mod screen;
mod screen_motion;
#[cfg(test)]
mod screen_tests;
mod segment;
mod solve;
#[cfg(test)]
mod tests;
pub mod thermal;
mod thermal_gyro;
mod thermal_misalignment;
#[cfg(test)]
mod thermal_tests;
mod uncertainty;
#[cfg(test)]
mod walk_default_tests;

pub use attitude::{BodyFrame, MountTilt, StaticSplit};
pub use drift::{WalkEstimate, WalkOrigin, WalkPoint, Z_WALK};
pub use error::EstimateError;
pub use fit::{calibrate_session_stats, calibrate_with_hand_gyro};
pub(crate) use fit::{chord_to_angle_deg, SessionSeg};
pub use gyro::GyroEstimate;
pub use gyro_drift::{GyroWalkAxes, GyroWalkEstimate, LR_AXES};
pub use options::{
    BiasWalk, ChiSquareScaling, EstimateOptions, GyroModel, Method, ReferenceChoice, UnitWalk,
    LEVER_ARM_THRESHOLD_M,
};
pub use outcome::{
    CalibrationOutcome, Exclusion, ExclusionReason, FitSummary, MethodComparison, Observability,
    ScreenFigure, SegmentDiagnostic,
};
pub use package::{PackageRefusal, PackageTest, IN_PACKAGE_NOT_OBSERVABLE};
pub use paper_angles::{paper_labels, paper_order, paper_values, PAPER_LEN};
pub use predict::{predict, PredictSettings, Prediction};
pub use screen::median;
pub use segment::{Noise, SegmentKind};
pub use uncertainty::Uncertainty;

// The tests (`tests.rs` and its siblings) take this module's names with `use super::*`.
#[cfg(test)]
use recording::session::Plan;
#[cfg(test)]
use shared::{Calibration, FittedStatic};
