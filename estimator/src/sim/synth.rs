//! Noise-free segment statistics of a known unit on a rate table: what [`SegmentStats`] a long
//! recording converges to. Backs the Cramér–Rao prediction ([`crate::estimate::predict`]) and the tests.
//!
//! The outputs' means come from `shared::forward` (independent of the estimator's own model): the
//! model is linear in `W`, so the mean over a linear ramp `ω(t) = n (ω_a + (ω_b − ω_a) t/T)` is the
//! output at `E[ω²] = (ω_a² + ω_a ω_b + ω_b²)/3` and `ω̇ = (ω_b − ω_a)/T`. The outputs' covariance is
//! the white noise plus, for a ramp, the spread of the signal itself.

use recording::session::{Plan, SegmentPlan, SegmentStats};
use shared::forward::{ForwardModel, TableState};
use shared::linalg::RowMajor3;

/// What the table really does during a segment.
#[derive(Clone, Copy, Debug, PartialEq)]
pub(crate) struct ActualSegment {
    /// Up, body axes (unit).
    pub up_b: [f64; 3],
    /// Rate at the start, rad/s.
    pub rate_start_rad_s: f64,
    /// Rate at the end, rad/s.
    pub rate_end_rad_s: f64,
    /// Table centre relative to the body origin, body axes, m.
    pub centre_m: [f64; 3],
    /// Duration, s.
    pub duration_s: f64,
}

impl ActualSegment {
    /// The segment as planned (no table errors).
    pub(crate) fn from_plan(sp: &SegmentPlan, default_duration_s: f64) -> ActualSegment {
        let a = sp.rate_deg_s.to_radians();
        ActualSegment {
            up_b: sp.up_b,
            rate_start_rad_s: a,
            rate_end_rad_s: sp.rate_end_deg_s.map_or(a, f64::to_radians),
            centre_m: sp.table_centre_m.unwrap_or([0.0; 3]),
            duration_s: sp.duration_s.unwrap_or(default_duration_s),
        }
    }
}

/// Noise of the recorded signals, per sample.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct SynthNoise {
    /// Accelerometer white noise, 1σ per sample, output unit.
    pub out_1sigma: [f64; 3],
    /// Gyro white noise, 1σ per sample, rad/s.
    pub gyro_1sigma_rad_s: f64,
    /// Sample rate, Hz.
    pub sample_rate_hz: f64,
}

/// Noise-free statistics of one segment.
pub(crate) fn segment_stats(
    name: &str,
    seg: &ActualSegment,
    unit: &ForwardModel,
    noise: &SynthNoise,
) -> SegmentStats {
    let g = unit.gravity_m_s2;
    let (wa, wb) = (seg.rate_start_rad_s, seg.rate_end_rad_s);
    let t = seg.duration_s;
    let count = (t * noise.sample_rate_hz).round().max(1.0) as u64;
    let mean_w2 = (wa * wa + wa * wb + wb * wb) / 3.0;
    let accel = if t > 0.0 { (wb - wa) / t } else { 0.0 };
    let state = |rate: f64, accel: f64| TableState {
        up_b: seg.up_b,
        rate_rad_s: rate,
        accel_rad_s2: accel,
        centre_m: seg.centre_m,
    };
    let mean_u = unit.outputs(&state(mean_w2.sqrt(), accel).motion(g)).raw;
    // Spread of the signal over a ramp.
    let mut sig_cov = [[0.0; 3]; 3];
    let (mut lo, mut hi) = (mean_u, mean_u);
    if wa != wb {
        const K: usize = 65;
        for q in 0..K {
            let rate = wa + (wb - wa) * q as f64 / (K - 1) as f64;
            let u = unit.outputs(&state(rate, accel).motion(g)).raw;
            for i in 0..3 {
                lo[i] = lo[i].min(u[i]);
                hi[i] = hi[i].max(u[i]);
                for j in 0..3 {
                    sig_cov[i][j] += (u[i] - mean_u[i]) * (u[j] - mean_u[j]) / K as f64;
                }
            }
        }
    }
    let sg2 = noise.gyro_1sigma_rad_s * noise.gyro_1sigma_rad_s;
    let var_rate = (wb - wa) * (wb - wa) / 12.0;
    let up = seg.up_b;
    let outer = |s: f64, add: f64| -> RowMajor3 {
        core::array::from_fn(|i| {
            core::array::from_fn(|j| up[i] * up[j] * s + if i == j { add } else { 0.0 })
        })
    };
    SegmentStats {
        name: name.to_string(),
        count,
        rejected_rows: 0,
        t_first_s: 0.0,
        t_last_s: (count - 1) as f64 / noise.sample_rate_hz,
        mean_u,
        cov_u: core::array::from_fn(|i| {
            core::array::from_fn(|j| {
                sig_cov[i][j]
                    + if i == j {
                        noise.out_1sigma[i].powi(2)
                    } else {
                        0.0
                    }
            })
        }),
        min_u: core::array::from_fn(|i| lo[i] - 4.5 * noise.out_1sigma[i]),
        max_u: core::array::from_fn(|i| hi[i] + 4.5 * noise.out_1sigma[i]),
        mean_w_rad_s: up.map(|u| u * 0.5 * (wa + wb)),
        mean_wwt: outer(mean_w2, sg2),
        cov_w: outer(var_rate, sg2),
        wdot_rad_s2: up.map(|u| u * accel),
        thermal: None,
    }
}

/// Noise-free statistics of every segment of a plan run as planned on `unit`.
pub fn plan_stats(
    plan: &Plan,
    unit: &ForwardModel,
    noise: &SynthNoise,
    default_duration_s: f64,
) -> Vec<SegmentStats> {
    plan.segments
        .iter()
        .map(|sp| {
            segment_stats(
                &sp.name,
                &ActualSegment::from_plan(sp, default_duration_s),
                unit,
                noise,
            )
        })
        .collect()
}

/// The noise-free statistics of `plan` run on `truth` with the noise and durations of `settings`: the
/// input of [`crate::estimate::predict`].
pub fn prediction_stats(
    plan: &Plan,
    truth: &shared::Calibration,
    settings: &crate::estimate::PredictSettings,
) -> Result<Vec<SegmentStats>, shared::params::ParamsError> {
    let unit = ForwardModel::new(truth)?;
    let noise = SynthNoise {
        out_1sigma: settings.noise_out_per_sample_1sigma,
        gyro_1sigma_rad_s: settings.gyro_noise_rad_s,
        sample_rate_hz: settings.sample_rate_hz.unwrap_or(plan.sample_rate_hz),
    };
    let mut stats = plan_stats(plan, &unit, &noise, settings.default_duration_s);
    // One segment after the other, as a session runs them: where each sits on the bias random
    // walk (docs/model.md §11).
    let mut t = 0.0;
    for st in &mut stats {
        let length = st.t_last_s - st.t_first_s + 1.0 / noise.sample_rate_hz;
        st.t_last_s += t - st.t_first_s;
        st.t_first_s = t;
        t += length;
    }
    Ok(stats)
}
