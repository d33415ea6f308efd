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
use recording::session::{Plan, SegmentStats};
use recording::spelling::Spelling;
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
    /// The reference case: 1σ per sample `noise` (output unit) on each axis, 60 s segments, the
    /// estimator's messages spelled as the caller spells its options.
    pub fn white(noise: f64, spelling: Spelling) -> PredictSettings {
        PredictSettings {
            noise_out_per_sample_1sigma: [noise; 3],
            gyro_noise_rad_s: 0.0,
            sample_rate_hz: None,
            default_duration_s: 60.0,
            options: EstimateOptions::new(spelling),
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
    pub warnings: Vec<super::note::Note>,
    /// One lever arm for the three accelerometers (docs/model.md §4.7): `r1` is the package's.
    pub single_package: bool,
    /// The static 1σ split into intrinsic and body-frame parts (docs/model.md §7).
    pub static_split: super::StaticSplit,
    /// Each mount's attitude 1σ (tilts of the noise-free data are zero).
    pub mount_tilts: Vec<super::MountTilt>,
    /// The gyro model's 1σ (a perfect gyro's values), when the plan has spins.
    pub gyro: Option<super::GyroEstimate>,
    /// The temperature model's 1σ, when the plan's static segments span a temperature range
    /// (docs/model.md §9): the fit at the degrees the unit's own model has (linear where it has
    /// none) on the noise-free statistics, its `*_sigma` the Cramér–Rao bound.
    pub temperature: Option<super::thermal::ThermalFit>,
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
    let temperature = predict_temperature(plan, truth, stats)?;
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
        single_package: out.single_package,
        static_split: out.static_split,
        mount_tilts: out.mount_tilts,
        gyro: out.gyro,
        temperature,
    })
}

/// The degrees `(zero bias, scale)` per axis of a unit's temperature model: its highest non-zero
/// coefficient's, at least 1 (a plan is judged for at least a linear model).
fn degrees_of(truth: &Calibration) -> [(usize, usize); 3] {
    let degree = |c: &[f64]| c.iter().rposition(|v| *v != 0.0).map_or(1, |k| k + 1);
    core::array::from_fn(|i| match &truth.temperature {
        Some(t) => (
            degree(&t.zero_bias_out_per_c[i]),
            degree(&t.scale_rel_per_c[i]),
        ),
        None => (1, 1),
    })
}

/// The temperature model's predicted 1σ: each static segment with a chamber set-point gets its
/// noise-free temperature moments (a soak at `temp_c`, or a ramp to `temp_end_c`, one reading per
/// sample), and the temperature fit runs at fixed degrees. `None` for a plan without temperatures
/// or spanning too little.
fn predict_temperature(
    plan: &Plan,
    truth: &Calibration,
    stats: &[SegmentStats],
) -> Result<Option<super::thermal::ThermalFit>, EstimateError> {
    if !plan.segments.iter().any(|s| s.temp_c.is_some()) {
        return Ok(None);
    }
    let with_temperature: Vec<SegmentStats> = stats
        .iter()
        .map(|st| {
            let mut st = st.clone();
            if let Some(sp) = plan.segment(&st.name).filter(|sp| sp.is_static()) {
                if let Some(t0) = sp.temp_c {
                    let t1 = sp.temp_end_c.unwrap_or(t0);
                    let n = st.count.max(2);
                    let mut acc = recording::session::thermal::ThermalAccumulator::default();
                    // The noise as an alternating ±1σ: the per-sample variance the fit reads from
                    // a soak's scatter, or a ramp's scatter about its own cubic, is exactly the
                    // plan's, and the mean and the temperature moments are the noise-free ones.
                    let sd: [f64; 3] = core::array::from_fn(|i| st.cov_u[i][i].max(0.0).sqrt());
                    for k in 0..n {
                        let sign = if k % 2 == 0 { 1.0 } else { -1.0 };
                        let u: [f64; 3] = core::array::from_fn(|i| st.mean_u[i] + sign * sd[i]);
                        acc.push(&u, t0 + (t1 - t0) * k as f64 / (n - 1) as f64);
                    }
                    st.thermal = acc.finish();
                }
            }
            st
        })
        .collect();
    let (fit, _) =
        super::thermal::fit_session_at_degrees(plan, &with_temperature, degrees_of(truth))
            .map_err(EstimateError::Temperature)?;
    Ok(fit)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::sim::testkit::{hot_unit, simulate_stats, soak_plan};
    use crate::sim::thermal::ThermalSim;
    use crate::sim::NoiseModel;

    /// The predicted 1σ of the temperature coefficients is what a fit of a simulated session of the
    /// same plan and noise reports (its own 1σ, from that session's scatter): within 25 %.
    #[test]
    fn predicts_the_temperature_models_sigma_of_a_simulated_soak() {
        let truth = hot_unit();
        let plan = soak_plan(&[-20.0, 5.0, 25.0, 40.0, 60.0], 10.0);
        let noise = NoiseModel::default();
        let settings = PredictSettings {
            noise_out_per_sample_1sigma: truth
                .statics
                .scale_out_per_g
                .map(|k| noise.accel_white_mg * 1e-3 * k.abs()),
            ..PredictSettings::white(0.0, recording::testkit::SPELLING)
        };
        let synth = crate::sim::synth::prediction_stats(&plan, &truth, &settings).unwrap();
        let predicted = predict(&plan, &truth, &synth, &settings)
            .unwrap()
            .temperature
            .expect("a temperature prediction");
        let stats = simulate_stats(&truth, &plan, &noise, &ThermalSim::default(), 5);
        let out = calibrate_session_stats(&plan, &stats, &EstimateOptions::default()).unwrap();
        let fit = out.thermal.expect("a temperature model");
        assert_eq!(fit.zero_bias_degree, predicted.zero_bias_degree);
        assert_eq!(fit.scale_degree, predicted.scale_degree);
        for i in 0..3 {
            for k in 0..predicted.zero_bias_degree[i] {
                let r = predicted.zero_bias_sigma[i][k] / fit.zero_bias_sigma[i][k];
                assert!((0.8..1.25).contains(&r), "bias {i} c{k}: ratio {r}");
            }
            for k in 0..predicted.scale_degree[i] {
                let r = predicted.scale_sigma[i][k] / fit.scale_sigma[i][k];
                assert!((0.8..1.25).contains(&r), "scale {i} c{k}: ratio {r}");
            }
        }
    }
}
