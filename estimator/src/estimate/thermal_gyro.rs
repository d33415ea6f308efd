//! The gyro's part of the temperature model (docs/model.md §9, §8): each gyro axis's bias as a
//! polynomial in `ΔT = T − T_ref` without constant term (the constant is the main estimate's gyro
//! bias at `T_ref`), fitted to the static segments' mean rates, which at rest are the bias alone
//! (Earth's rate and g-sensitivity, below the noise of a MEMS gyro, add to the χ²).
//!
//! Each static segment gives one observation, the mean rate, whose expectation is
//! `b0 + Σ_k c_k·E[ΔT^k]` (exact for ramps too, through the segment's temperature moments); its 1σ
//! is the segment's scatter over √count. The degree (0..=3) is chosen by the same Bayesian
//! information criterion as the accelerometers' ([`super::thermal`]).

use super::note::Note;
use super::solve::invert_spd;
use super::{CalibrationOutcome, EstimateOptions, GyroEstimate, GyroModel};
use nalgebra::{DMatrix, DVector};
use recording::session::thermal::{ThermalStats, SCALE_C};
use recording::session::SegmentStats;
use shared::sensor_models::MAX_TEMPERATURE_DEGREE as DEG;

/// Segments whose mean temperatures are within this are at one temperature, °C.
const GROUP_WIDTH_C: f64 = 1.5;

/// The gyro bias fit of one session.
#[derive(Clone, Debug, PartialEq)]
pub(crate) struct GyroBiasFit {
    /// `c_k` per axis, rad/s per °C^k (0 where the degree leaves a coefficient out).
    pub per_c: [[f64; DEG]; 3],
    /// 1σ of `per_c`.
    pub sigma: [[f64; DEG]; 3],
    /// The degree each axis's data chose.
    pub degree: [usize; 3],
    /// The bias at `T_ref` this fit found, rad/s (the main estimate's agrees to noise).
    pub bias_ref_rad_s: [f64; 3],
    /// Its 1σ, rad/s (scaled by the chosen degree's χ²/dof when above 1).
    pub bias_ref_sigma_rad_s: [f64; 3],
    /// How each degree was chosen.
    pub notes: Vec<Note>,
}

/// Fits the gyro bias over temperature from the static segments `statics` (with their temperature
/// moments); `None` when the recording has no gyro readings (no scatter) or too few segments.
pub fn fit(statics: &[(&SegmentStats, &ThermalStats)], reference_c: f64) -> Option<GyroBiasFit> {
    let n = statics.len();
    if n < 2 {
        return None;
    }
    let rows: Vec<[f64; DEG + 1]> = statics
        .iter()
        .map(|(_, ts)| ts.mean_powers_about(reference_c))
        .collect();
    let mut out = GyroBiasFit {
        per_c: [[0.0; DEG]; 3],
        sigma: [[0.0; DEG]; 3],
        degree: [0; 3],
        bias_ref_rad_s: [0.0; 3],
        bias_ref_sigma_rad_s: [0.0; 3],
        notes: Vec::new(),
    };
    for axis in 0..3 {
        let y: Vec<f64> = statics
            .iter()
            .map(|(st, _)| st.mean_w_rad_s[axis])
            .collect();
        let var: Vec<f64> = statics
            .iter()
            .map(|(st, _)| st.cov_w[axis][axis] / st.count.max(1) as f64)
            .collect();
        if var.iter().any(|v| !(v.is_finite() && *v > 0.0)) {
            return None;
        }
        let temps: Vec<f64> = statics.iter().map(|(_, ts)| ts.mean_c()).collect();
        let tau2 = between_segment_variance(&temps, &y, &var);
        let var: Vec<f64> = var.iter().map(|v| v + tau2).collect();
        let max_degree = DEG.min(n - 2);
        let results: Vec<(usize, DVector<f64>, DMatrix<f64>, f64)> = (0..=max_degree)
            .filter_map(|d| {
                let (beta, cov, chi2) = weighted_ls(&rows, &y, &var, d + 1)?;
                Some((d, beta, cov, chi2))
            })
            .collect();
        let dof = |d: usize| (n - d - 1).max(1) as f64;
        let largest = results
            .last()
            .map_or(1.0, |(d, _, _, chi2)| (chi2 / dof(*d)).max(1.0));
        let bic = |(d, _, _, chi2): &(usize, DVector<f64>, DMatrix<f64>, f64)| {
            chi2 / largest + (d + 1) as f64 * (n as f64).ln()
        };
        let (d, beta, cov, chi2) = results
            .into_iter()
            .min_by(|a, b| bic(a).total_cmp(&bic(b)))?;
        let scale2 = (chi2 / dof(d)).max(1.0);
        out.degree[axis] = d;
        out.bias_ref_rad_s[axis] = beta[0];
        out.bias_ref_sigma_rad_s[axis] = (cov[(0, 0)] * scale2).sqrt();
        for k in 0..d {
            let per_c = SCALE_C.powi(k as i32 + 1);
            out.per_c[axis][k] = beta[k + 1] / per_c;
            out.sigma[axis][k] = (cov[(k + 1, k + 1)] * scale2).sqrt() / per_c;
        }
        out.notes.push(Note::ThermalGyroDegree {
            axis,
            degree: d,
            compared: max_degree + 1,
            chi2_per_dof: chi2 / dof(d),
        });
    }
    Some(out)
}

/// A thermal session without spins still determines the gyro's bias at `T_ref` from its rests (the
/// temperature model holds only its drift about `T_ref`): that bias, for the calibration's gyro
/// correction where the session's own fit gives no gyro ([`settle_gyro`]). Without it the device and
/// every export would keep the whole bias in the rate.
pub(crate) fn bias_from_rests(
    outcome: &CalibrationOutcome,
    fit: Option<&super::thermal::ThermalFit>,
    options: &EstimateOptions,
) -> Option<GyroEstimate> {
    if outcome.gyro.is_some() || options.gyro_model != GyroModel::Estimate {
        return None;
    }
    let (bias, sigma) = fit.and_then(|f| f.gyro_bias_ref_rad_s)?;
    Some(GyroEstimate::bias_only(bias, sigma))
}

/// The calibration's gyro, decided once from what the session gives: its own fit's where that
/// determines `G`; else the gyro a hand-held session's turns determined (`gyro.toml`, §8), whole
/// when the session gives no gyro, and beside a temperature model its `G` (scale factors and axis
/// alignment) with the rests' bias at `T_ref`, since the model's gyro polynomial holds the bias's
/// change about that value and the turns' bias is the stills' average over their temperatures
/// (§9); else the rests' bias alone. A warning says which part came from where. Whether the hand
/// turns' gyro was taken.
pub(crate) fn settle_gyro(
    outcome: &mut CalibrationOutcome,
    rests: Option<GyroEstimate>,
    hand: Option<&GyroEstimate>,
) -> bool {
    let own = outcome.gyro.take();
    let (gyro, from_hand, warning) = match (own, rests, hand) {
        (Some(own), _, _) if own.determines_matrix() => {
            outcome.gyro = Some(own);
            return false;
        }
        (Some(own), _, None) => {
            outcome.gyro = Some(own);
            return false;
        }
        (Some(bias), _, Some(hand)) | (None, Some(bias), Some(hand)) => {
            let warning = Note::GyroTurnsAndRests {
                bias_rad_s: bias.bias_rad_s,
            };
            let gyro = GyroEstimate {
                bias_rad_s: bias.bias_rad_s,
                bias_rad_s_1sigma: bias.bias_rad_s_1sigma,
                ..hand.clone()
            };
            (gyro, true, Some(warning))
        }
        (None, Some(rests), None) => {
            let warning = Note::GyroFromRests {
                bias_rad_s: rests.bias_rad_s,
                sigma_rad_s: rests.bias_rad_s_1sigma,
            };
            (rests, false, Some(warning))
        }
        (None, None, Some(hand)) => (hand.clone(), true, None),
        (None, None, None) => return false,
    };
    outcome.warnings.extend(warning);
    outcome.calibration.gyro = Some(gyro.device_correction());
    outcome.gyro = Some(gyro);
    from_hand
}

/// The scatter of segment means at one temperature beyond their own noise (the bias wandering
/// between segments), by the method of moments (DerSimonian–Laird) over the groups of segments
/// within [`GROUP_WIDTH_C`] of each other, rad²/s²: without it a wandering bias that happens to
/// follow the temperature steps would be taken for a tempco.
fn between_segment_variance(temps: &[f64], y: &[f64], var: &[f64]) -> f64 {
    let mut groups: Vec<Vec<usize>> = Vec::new();
    for (k, &t) in temps.iter().enumerate() {
        match groups
            .iter_mut()
            .find(|g| (temps[g[0]] - t).abs() < GROUP_WIDTH_C)
        {
            Some(g) => g.push(k),
            None => groups.push(vec![k]),
        }
    }
    let (mut q, mut dof, mut c) = (0.0, 0.0, 0.0);
    for g in groups.iter().filter(|g| g.len() >= 2) {
        let w: Vec<f64> = g.iter().map(|&k| 1.0 / var[k]).collect();
        let sw: f64 = w.iter().sum();
        let mean = g.iter().zip(&w).map(|(&k, w)| y[k] * w).sum::<f64>() / sw;
        q += g
            .iter()
            .zip(&w)
            .map(|(&k, w)| w * (y[k] - mean).powi(2))
            .sum::<f64>();
        dof += (g.len() - 1) as f64;
        c += sw - w.iter().map(|w| w * w).sum::<f64>() / sw;
    }
    if c > 0.0 {
        ((q - dof) / c).max(0.0)
    } else {
        0.0
    }
}

/// Weighted least squares of `y` on the first `p` columns of `rows`: coefficients, covariance, χ².
fn weighted_ls(
    rows: &[[f64; DEG + 1]],
    y: &[f64],
    var: &[f64],
    p: usize,
) -> Option<(DVector<f64>, DMatrix<f64>, f64)> {
    let mut n = DMatrix::zeros(p, p);
    let mut g = DVector::zeros(p);
    for ((r, &yi), &v) in rows.iter().zip(y).zip(var) {
        let a = DVector::from_fn(p, |j, _| r[j]);
        n += &a * a.transpose() / v;
        g += &a * yi / v;
    }
    let cov = invert_spd(&n, 1e-13)?;
    let beta = &cov * g;
    let chi2 = rows
        .iter()
        .zip(y)
        .zip(var)
        .map(|((r, &yi), &v)| {
            let m: f64 = (0..p).map(|j| r[j] * beta[j]).sum();
            (yi - m).powi(2) / v
        })
        .sum();
    Some((beta, cov, chi2))
}
