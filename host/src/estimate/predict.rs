//! The Cramér–Rao prediction of a plan, before any data (`host plan --check FILE`): the estimator's
//! information matrix evaluated on noise-free statistics of a given unit (made by the caller, e.g.
//! `crate::sim::synth::prediction_stats`, so that the estimator does not depend on the simulator), with
//! each segment's weight from the given per-sample noise and its duration. For white noise and this
//! (nearly linear) model the weighted least squares attains the bound, so these are the 1σ values a
//! real session of this plan will report.

use super::{
    calibrate_session_stats, paper_labels, paper_values, ChiSquareScaling, EstimateError,
    EstimateOptions, ReferenceChoice, PAPER_LEN,
};
use crate::session::{Plan, SegmentStats};
use shared::{Calibration, OutputUnit};

/// Noise level and durations for [`predict`].
#[derive(Clone, Debug, PartialEq)]
pub struct PredictSettings {
    /// Accelerometer white noise, 1σ per sample, output unit, per axis.
    pub noise_out_per_sample_1sigma: [f64; 3],
    /// Gyro white noise, 1σ per sample, rad/s.
    pub gyro_noise_rad_s: f64,
    /// Sample rate, Hz (`None`: the plan's).
    pub sample_rate_hz: Option<f64>,
    /// Duration of segments whose plan gives none, s.
    pub default_duration_s: f64,
    /// Estimator options (reference, thresholds); χ² scaling and the comparison are turned off.
    pub options: EstimateOptions,
}

impl PredictSettings {
    /// The reference case: 1σ per sample `noise` (output unit) on each axis, 60 s segments.
    pub fn white(noise: f64) -> PredictSettings {
        PredictSettings {
            noise_out_per_sample_1sigma: [noise; 3],
            gyro_noise_rad_s: 0.0,
            sample_rate_hz: None,
            default_duration_s: 60.0,
            options: EstimateOptions::default(),
        }
    }
}

/// Predicted 1σ of every paper-form value.
#[derive(Clone, Debug, PartialEq)]
pub struct Prediction {
    /// Output unit of biases and scale factors.
    pub output_unit: OutputUnit,
    /// Value names ([`paper_labels`]).
    pub labels: Vec<String>,
    /// The unit's values.
    pub values: [f64; PAPER_LEN],
    /// Predicted 1σ (∞ for values the plan cannot determine at all).
    pub sigma: [f64; PAPER_LEN],
    /// Lever-arm components determined to the threshold.
    pub lever_arms_observable: [[bool; 3]; 3],
    /// Lever-arm components not estimable at all.
    pub lever_arms_fixed: [[bool; 3]; 3],
    /// The threshold, m.
    pub threshold_m: f64,
    /// Warnings from the estimator (e.g. what the plan does not determine).
    pub warnings: Vec<String>,
    /// The static 1σ split into intrinsic and body-frame parts (docs/model.md §7).
    pub static_split: super::StaticSplit,
    /// Each mount's attitude 1σ (tilts of the noise-free data are zero).
    pub mount_tilts: Vec<super::MountTilt>,
    /// The gyro model's 1σ (a perfect gyro's values), when the plan has spins.
    pub gyro: Option<super::GyroEstimate>,
}

/// The predicted 1σ of every parameter for `plan` run on `truth` with the given noise: `stats` are the
/// noise-free statistics of that run, with the noise of `settings` in their covariances.
pub fn predict(
    plan: &Plan,
    truth: &Calibration,
    stats: &[SegmentStats],
    settings: &PredictSettings,
) -> Result<Prediction, EstimateError> {
    if let Some(s) = plan.segments.iter().find(|s| !s.has_up()) {
        return Err(EstimateError::PlanCannotObserve {
            parameters: vec![format!("the prediction for segment '{}'", s.name)],
            hint: "a prediction needs every segment's up_b (for a free attitude, where it will \
                   roughly be): add it"
                .into(),
        });
    }
    let mut options = settings.options.clone();
    options.chi2_scaling = ChiSquareScaling::Never;
    options.compare_methods = false;
    options.require_lever_arms = false;
    let out = calibrate_session_stats(plan, stats, &options)?;
    let sigma = core::array::from_fn(|p| out.covariance[p][p].max(0.0).sqrt());
    let mut truth_in_frame = *truth;
    truth_in_frame.lever_arms = match options.reference {
        ReferenceChoice::TableAxis => truth.lever_arms,
        ReferenceChoice::Centroid => truth
            .lever_arms
            .re_referenced(truth.lever_arms.centroid_m()),
        ReferenceChoice::BodyPoint(o) => truth.lever_arms.re_referenced(o),
    };
    Ok(Prediction {
        output_unit: truth.statics.output_unit,
        labels: paper_labels(),
        values: paper_values(&truth_in_frame)?,
        sigma,
        lever_arms_observable: out.observability.observable,
        lever_arms_fixed: out.observability.fixed_at_zero,
        threshold_m: out.observability.threshold_m,
        warnings: out.warnings,
        static_split: out.static_split,
        mount_tilts: out.mount_tilts,
        gyro: out.gyro,
    })
}
