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

use super::drift::{interval, log_det_information, peak, search, start_time, walk_covariance};
use super::drift::{with_own_noise, Drift, Peak, Search, Z_WALK};
use super::gyro::GyroBlock;
use super::solve::{self, NormalSystem, Problem};
use super::{EstimateError, EstimateOptions, SessionSeg};
use nalgebra::{DMatrix, DVector};

/// The gyro walk of `options` (°/s/√s, the same on every axis unless given per axis), starting at
/// the first sample of `segs`; `None` for a constant gyro bias (a walk of 0).
pub(crate) fn walk(options: &EstimateOptions, segs: &[SessionSeg]) -> Option<Drift> {
    let k = options.gyro_bias_walk_deg_s_sqrt_s;
    (k > 0.0).then(|| {
        let axes = options.gyro_bias_walk_axes_deg_s_sqrt_s.unwrap_or([k; 3]);
        drift_of(axes, start_time(segs))
    })
}

/// The walk of strengths `k` (°/s/√s, per axis) started at `t0_s`.
fn drift_of(k: [f64; 3], t0_s: f64) -> Drift {
    Drift {
        q2: k.map(|k| {
            let q = k.to_radians();
            q * q
        }),
        t0_s,
    }
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

/// The gyro walk's strength, estimated from the session, with its 1σ (docs/model.md §11.6).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct GyroWalkEstimate {
    /// The strength that maximises the session's restricted likelihood, °/s/√s (one for the three
    /// axes).
    pub deg_s_sqrt_s: f64,
    /// Its 1σ (half the likelihood interval's width), °/s/√s.
    pub sigma_deg_s_sqrt_s: f64,
    /// The likelihood interval (log-likelihood within ½ of its maximum), °/s/√s.
    pub interval_deg_s_sqrt_s: [f64; 2],
    /// The strength the fit weighted the gyro's means with when used, °/s/√s: `√(K̂² + σ²)`, the
    /// walk's mean square over its likelihood, as for the accelerometers (§11.3).
    pub fit_deg_s_sqrt_s: f64,
    /// `√(2 (log L(K̂) − log L(0)))`: how far the session rules out a constant gyro bias, σ.
    pub significance: f64,
    /// Whether the fit used it (a significance of at least [`super::drift::Z_WALK`]); otherwise
    /// the gyro bias is fitted as constant.
    pub used: bool,
    /// Each axis's strength, estimated where the one strength is used (§11.6); the fit takes
    /// them in its place where they are [`GyroWalkAxes::used`]. `None` where the one strength is
    /// not used, or where the per-axis likelihood could not be evaluated.
    pub axes: Option<GyroWalkAxes>,
}

impl GyroWalkEstimate {
    /// The strength the fit weighs the gyro's means with where it is used, °/s/√s, and the
    /// per-axis strengths in its place where those are used (its value the strongest of them).
    pub(crate) fn fit_strengths(&self) -> (f64, Option<[f64; 3]>) {
        match self.axes.filter(|a| a.used) {
            Some(a) => (
                a.fit_deg_s_sqrt_s.into_iter().fold(0.0, f64::max),
                Some(a.fit_deg_s_sqrt_s),
            ),
            None => (self.fit_deg_s_sqrt_s, None),
        }
    }
}

/// The gyro walk's strength on each axis, x, y, z, estimated from the session with their 1σ
/// (docs/model.md §11.6).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct GyroWalkAxes {
    /// The strengths that maximise the session's restricted likelihood together, °/s/√s.
    pub deg_s_sqrt_s: [f64; 3],
    /// Their 1σ: half of each axis's likelihood interval, the other axes at their estimates,
    /// °/s/√s.
    pub sigma_deg_s_sqrt_s: [f64; 3],
    /// Each axis's likelihood interval (log-likelihood within ½ of its maximum), °/s/√s.
    pub interval_deg_s_sqrt_s: [[f64; 2]; 3],
    /// The strengths the fit weighted each axis's means with when used, °/s/√s: `√(K̂_i² + σ_i²)`.
    pub fit_deg_s_sqrt_s: [f64; 3],
    /// `√(2 (log L(K̂) − log L(K̂_i = 0)))` per axis: how far the session rules out a constant
    /// bias on that axis, the others walking, σ.
    pub significance: [f64; 3],
    /// `2 (log L(K̂_x, K̂_y, K̂_z) − log L(K̂))`: how much better the per-axis strengths explain the
    /// session than the one strength, a likelihood ratio with 2 degrees of freedom.
    pub likelihood_ratio: f64,
    /// Whether the fit used them: the likelihood ratio at least [`LR_AXES`] and every axis's
    /// likelihood interval closed below the grid's top (§11.6); otherwise the one strength.
    pub used: bool,
}

/// The per-axis strengths are used where they raise the restricted likelihood over the one
/// strength by a likelihood ratio of at least this: the 99 % point of χ² with 2 degrees of freedom,
/// the two strengths they add (docs/model.md §11.6).
pub const LR_AXES: f64 = 9.21;

/// The coordinate ascent over the three axes' strengths stops once a sweep raises the
/// log-likelihood by less than this, or after [`SWEEPS`] sweeps.
const CONVERGED: f64 = 0.01;
const SWEEPS: usize = 4;

/// Golden-section steps and bisections that place each axis's strength and its interval's ends:
/// to 0.4 % and 0.03 % of the strength, far inside its 1σ (about 20 % on the paper's plan).
const AXIS_STEPS: usize = 12;

/// The grid the gyro walk's likelihood is first searched on, °/s/√s: 10⁻⁶ to 0.1 in quarter
/// decades.
fn grid() -> Vec<f64> {
    (0..=20)
        .map(|i| 10f64.powf(-6.0 + 0.25 * i as f64))
        .collect()
}

/// The restricted log-likelihood (docs/model.md §11.3) of `p` under a gyro walk of `k` °/s/√s per
/// axis: `−½ (χ² + log det Σ_g + log det N)` at the generalised least-squares fit, `Σ_g` the gyro
/// means' covariance under the walk (the accelerometers' and the priors' terms, which do not depend
/// on it, left out).
fn log_likelihood(p: &Problem, start: &[f64], free: &[bool], t0: f64, k: [f64; 3]) -> Option<f64> {
    let mut p = p.clone();
    let d = drift_of(k, t0);
    let blk = p.gyro_block.as_mut()?;
    let chol = covariance(blk, &d).cholesky()?;
    let l = chol.l();
    let ld_sigma: f64 = (0..l.nrows()).map(|i| 2.0 * l[(i, i)].ln()).sum();
    blk.walk = Some(d);
    let fit = solve::fit(&p, start.to_vec(), free.to_vec(), "gyro walk likelihood").ok()?;
    let ld_n = log_det_information(&p, &fit.theta, &fit.free)?;
    Some(-0.5 * (fit.chi2 + ld_sigma + ld_n))
}

/// The gyro walk's strength that maximises the restricted likelihood of the fit's problem `p`
/// (its gyro model estimated with the rest), from the constant-bias fit's `theta` and `free`
/// (docs/model.md §11.3, §11.6), then, where it is used, each axis's; `None` when the session
/// estimates no gyro model.
pub(crate) fn estimate(
    p: &Problem,
    theta: &[f64],
    free: &[bool],
    segs: &[SessionSeg],
) -> Result<Option<GyroWalkEstimate>, EstimateError> {
    if p.gyro_block.is_none() {
        return Ok(None);
    }
    let t0 = start_time(segs);
    let fail = || EstimateError::Singular {
        what: "gyro bias random walk likelihood",
    };
    let at = |k: f64| log_likelihood(p, theta, free, t0, [k; 3]).ok_or_else(fail);
    let found = search(&at, &grid(), &fail)?;
    let sigma = found.sigma();
    let used = found.significance() >= Z_WALK;
    let at_axes = |k: [f64; 3]| log_likelihood(p, theta, free, t0, k).ok_or_else(fail);
    Ok(Some(GyroWalkEstimate {
        deg_s_sqrt_s: found.q,
        sigma_deg_s_sqrt_s: sigma,
        interval_deg_s_sqrt_s: found.interval,
        fit_deg_s_sqrt_s: found.q.hypot(sigma),
        significance: found.significance(),
        used,
        axes: used
            .then(|| per_axis(&at_axes, &found, &fail).ok())
            .flatten(),
    }))
}

/// Each axis's strength by coordinate ascent of the log-likelihood `at` from the one strength's
/// maximum `one`: each axis's maximum in turn on the one strength's grid, the others held, until a
/// sweep gains less than [`CONVERGED`]; then each axis's likelihood interval there, the others at
/// their estimates (docs/model.md §11.6).
fn per_axis(
    at: &dyn Fn([f64; 3]) -> Result<f64, EstimateError>,
    one: &Search,
    fail: &dyn Fn() -> EstimateError,
) -> Result<GyroWalkAxes, EstimateError> {
    let grid = grid();
    let top = grid[grid.len() - 1];
    let along = |k: [f64; 3], a: usize| {
        move |x: f64| {
            let mut kx = k;
            kx[a] = x;
            at(kx)
        }
    };
    let mut k = [one.q; 3];
    let mut last = one.peak;
    let mut peaks: Vec<Peak> = Vec::new();
    for _ in 0..SWEEPS {
        peaks.clear();
        for a in 0..3 {
            let p = peak(&along(k, a), &grid, fail, AXIS_STEPS)?;
            k[a] = p.q;
            peaks.push(p);
        }
        let gain = peaks[2].l - last;
        last = peaks[2].l;
        if gain < CONVERGED {
            break;
        }
    }
    let mut found: Vec<Search> = Vec::new();
    for (a, p) in peaks.iter().enumerate() {
        found.push(interval(&along(k, a), p, top, AXIS_STEPS)?);
    }
    let sigma: [f64; 3] = core::array::from_fn(|a| found[a].sigma());
    let interval: [[f64; 2]; 3] = core::array::from_fn(|a| found[a].interval);
    let likelihood_ratio = 2.0 * (last - one.peak);
    Ok(GyroWalkAxes {
        deg_s_sqrt_s: k,
        sigma_deg_s_sqrt_s: sigma,
        interval_deg_s_sqrt_s: interval,
        fit_deg_s_sqrt_s: core::array::from_fn(|a| k[a].hypot(sigma[a])),
        significance: core::array::from_fn(|a| found[a].significance()),
        likelihood_ratio,
        used: likelihood_ratio >= LR_AXES && interval.iter().all(|i| i[1] < top),
    })
}
