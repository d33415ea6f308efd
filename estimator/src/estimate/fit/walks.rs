//! The bias random walks a fit estimates from its own session (docs/model.md §11.3, §11.6): the
//! accelerometers' and the gyro's, by coordinate ascent of the restricted likelihood, and the fit's
//! options again with those the session determines.

use super::super::{drift, gyro_drift, solve, BiasWalk, EstimateError, EstimateOptions};
use super::super::{GyroWalkEstimate, WalkEstimate};
use super::{MainFit, Prepared};

/// The walks estimated from the constant-bias fit's problem (docs/model.md §11.3, §11.6).
pub(super) struct Walks {
    pub(super) accel: Option<WalkEstimate>,
    pub(super) gyro: Option<GyroWalkEstimate>,
}

impl Walks {
    /// The options of the fit again with every walk the session determines, the others as
    /// `options` had them; `None` when it determines none (the constant-bias fit stands).
    pub(super) fn refit(&self, options: &EstimateOptions) -> Option<EstimateOptions> {
        let accel = self.accel.filter(|w| w.used);
        let gyro = self.gyro.filter(|w| w.used);
        if accel.is_none() && gyro.is_none() {
            return None;
        }
        // An estimate the session does not determine leaves that bias constant.
        let bias_walk = match (accel, options.bias_walk) {
            (Some(w), _) => BiasWalk::Given(w.fit_mg_sqrt_s),
            (None, BiasWalk::Estimate) => BiasWalk::Off,
            (None, w) => w,
        };
        let (gyro_walk, gyro_axes) = gyro.map_or(
            (
                options.gyro_bias_walk_deg_s_sqrt_s,
                options.gyro_bias_walk_axes_deg_s_sqrt_s,
            ),
            |w| w.fit_strengths(),
        );
        Some(EstimateOptions {
            bias_walk,
            gyro_bias_walk_deg_s_sqrt_s: gyro_walk,
            gyro_bias_walk_axes_deg_s_sqrt_s: gyro_axes,
            gyro_bias_walk_estimate: false,
            ..options.clone()
        })
    }
}

/// The walks asked for, by coordinate ascent of the restricted likelihood: the accelerometers'
/// with a constant gyro bias, the gyro's (one strength, then per axis) under the accelerometers'
/// where that is determined, then the accelerometers' again under the gyro's where that is (§11.3,
/// §11.6). The gyro's first, with the accelerometers' walk not yet modelled, cost the 0.05° fixture
/// of `drift_tests` under 0.005 mg/√s a fifth of its static error (61 µg against the given walk's
/// 51).
pub(super) fn estimate_walks(
    options: &EstimateOptions,
    estimate_gyro: bool,
    prepared: &Prepared,
    main: &MainFit,
) -> Result<Walks, EstimateError> {
    let (p, segs) = (&prepared.problem, &prepared.segs);
    let estimate_accel = options.bias_walk == BiasWalk::Estimate;
    let accel_of = |p: &solve::Problem| -> Result<Option<WalkEstimate>, EstimateError> {
        if !estimate_accel {
            return Ok(None);
        }
        drift::estimate(p, &main.theta, &main.free, segs).map(Some)
    };
    let first = accel_of(p)?;
    let gyro = if estimate_gyro {
        let mut q = p.clone();
        if let Some(a) = first.filter(|a| a.used) {
            let k = drift::scale_factors(&main.theta);
            let d = drift::Drift::new(a.fit_mg_sqrt_s, k, drift::start_time(segs));
            q.drift = Some(d);
        }
        gyro_drift::estimate(&q, &main.theta, &main.free, segs)?
    } else {
        None
    };
    let accel = match (gyro.filter(|g| g.used), p.gyro_block.is_some()) {
        (Some(g), true) if estimate_accel => {
            let mut q = p.clone();
            let mut o = options.clone();
            (
                o.gyro_bias_walk_deg_s_sqrt_s,
                o.gyro_bias_walk_axes_deg_s_sqrt_s,
            ) = g.fit_strengths();
            if let Some(blk) = q.gyro_block.as_mut() {
                blk.walk = gyro_drift::walk(&o, segs);
            }
            accel_of(&q)?
        }
        _ => first,
    };
    Ok(Walks { accel, gyro })
}
