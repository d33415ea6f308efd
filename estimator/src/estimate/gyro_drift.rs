//! The gyro's bias random walk (docs/model.md §11.6): the gyro model's mean rates weighted with the
//! covariance a random walk of the gyro bias gives them across the session.
//!
//! Each gyro axis reads its bias as `b_i + w_i(t)`, `w_i` a Wiener process of intensity `q²`
//! ((rad/s)²/s) that is 0 at the session's first sample, so `b` is the bias then. Every used
//! segment's mean rate (a rest's `b + w̄`, a spin's `Ω (1 + s) G u + b + w̄`, §8) carries the walk's
//! mean over its span, correlated across segments by the closed form of §11.1
//! ([`super::drift::interval_cov`]). The means are fitted with the full covariance
//! `blockdiag(se_cov) + q² C`, whitened by its Cholesky factor, in place of each mean's own
//! whitening. No walk leaves the per-mean path, so a zero walk is the constant-bias fit bit for bit.

use super::drift::{start_time, walk_covariance, with_own_noise, Drift};
use super::gyro::GyroBlock;
use super::solve::NormalSystem;
use super::{EstimateOptions, SessionSeg};
use nalgebra::{DMatrix, DVector};

/// The gyro walk of `options` (°/s/√s, the same on every axis), starting at the first sample of
/// `segs`; `None` for a constant gyro bias (a walk of 0).
pub(crate) fn walk(options: &EstimateOptions, segs: &[SessionSeg]) -> Option<Drift> {
    let k = options.gyro_bias_walk_deg_s_sqrt_s;
    (k > 0.0).then(|| {
        let q = k.to_radians();
        Drift {
            q2: [q * q; 3],
            t0_s: start_time(segs),
        }
    })
}

/// The covariance of the stacked gyro means of `blk` (3 rows each, mean by mean): each mean's own
/// `se_cov` plus the walk's `q_a² C(s, s')` between equal axes (docs/model.md §11.1, §11.6).
fn covariance(blk: &GyroBlock, d: &Drift) -> DMatrix<f64> {
    with_own_noise(walk_part(blk, d), blk.means.iter().map(|m| &m.se_cov))
}

/// The walk's part of [`covariance`].
fn walk_part(blk: &GyroBlock, d: &Drift) -> DMatrix<f64> {
    let spans: Vec<[f64; 2]> = blk.means.iter().map(|m| m.span_s).collect();
    walk_covariance(&spans, d)
}

/// The residuals (measured − predicted mean rates) and the Jacobian over every θ entry, stacked.
fn residuals(blk: &GyroBlock, t: &[f64]) -> (DVector<f64>, DMatrix<f64>) {
    let rows = 3 * blk.means.len();
    let mut r = DVector::zeros(rows);
    let mut jac = DMatrix::zeros(rows, t.len());
    for (s, g) in blk.means.iter().enumerate() {
        let p = g.predict(t, blk.base);
        for a in 0..3 {
            r[3 * s + a] = g.mean_w_rad_s[a] - p[a];
        }
        for (q, dv) in g.jacobian(t, blk.base) {
            for a in 0..3 {
                jac[(3 * s + a, q)] += dv[a];
            }
        }
    }
    (r, jac)
}

/// Adds the gyro means of `blk` to the normal equations with the full covariance of
/// [`covariance`] under its walk, whitened by its Cholesky factor `L` (`L⁻¹ r`, `L⁻¹ J`); `false`
/// (and nothing added) without a walk or when that covariance is not positive definite, so that
/// the caller weights each mean by its own noise.
pub(crate) fn add_means(ne: &mut NormalSystem, blk: &GyroBlock, t: &[f64]) -> bool {
    let Some(d) = blk.walk.as_ref().filter(|d| d.active()) else {
        return false;
    };
    let Some(chol) = covariance(blk, d).cholesky() else {
        return false;
    };
    let (r, full) = residuals(blk, t);
    let k = ne.n.nrows();
    let mut jac = DMatrix::zeros(r.len(), k);
    for q in 0..t.len() {
        let c = ne.col_of[q];
        if c == usize::MAX {
            continue;
        }
        for row in 0..r.len() {
            jac[(row, c)] += full[(row, q)];
        }
    }
    let l = chol.l();
    let (Some(rw), Some(jw)) = (l.solve_lower_triangular(&r), l.solve_lower_triangular(&jac))
    else {
        return false;
    };
    ne.chi2 += rw.norm_squared();
    ne.n += jw.transpose() * &jw;
    ne.b += jw.transpose() * rw;
    true
}

/// Each gyro mean's segment and its fitted bias `b + ŵ`, `ŵ = Σ_walk Σ⁻¹ r` at `t` (the walk's
/// conditional mean over the segment given the residuals, as docs/model.md §11.4 does for the
/// accelerometers): the bias the segment's body rate is corrected with (§11.6). Empty without a
/// walk.
pub(crate) fn segment_biases(blk: &GyroBlock, t: &[f64]) -> Vec<(usize, [f64; 3])> {
    let Some(d) = blk.walk.as_ref().filter(|d| d.active()) else {
        return Vec::new();
    };
    let walk = walk_part(blk, d);
    let sigma = with_own_noise(walk.clone(), blk.means.iter().map(|m| &m.se_cov));
    let Some(chol) = sigma.cholesky() else {
        return Vec::new();
    };
    let (r, _) = residuals(blk, t);
    // Σ_walk Σ⁻¹ r, both symmetric.
    let w = &walk * chol.solve(&r);
    let b = super::gyro::b_of(t, blk.base);
    blk.means
        .iter()
        .enumerate()
        .map(|(s, m)| (m.seg, core::array::from_fn(|a| b[a] + w[3 * s + a])))
        .collect()
}
