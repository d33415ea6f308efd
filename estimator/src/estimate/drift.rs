//! The accelerometers' bias random walk (docs/model.md §11): generalised least squares over the
//! segments' time order.
//!
//! Each axis's bias is `u0_i + w_i(t)`, `w_i` a Wiener process of intensity `q_i²` (output unit²/s)
//! started at 0 at the session's first sample, so `u0` is the bias then. A segment's mean output
//! carries the mean of `w_i` over its span; those means are correlated across segments with the
//! closed-form covariance of [`interval_cov`]. The segments' mean outputs are then fitted with the
//! full covariance `blockdiag(se_cov) + q² C` whitened by its Cholesky factor (§11.2), which is the
//! least squares of `solve` with a dense weight in place of the per-segment one. No walk leaves
//! `solve` on its per-segment path, so a zero walk is the constant-bias fit bit for bit.
//!
//! The walk's strength is given (mg/√s) or estimated from the constant-bias fit's whole problem by
//! restricted maximum likelihood (§11.3), with the likelihood interval as its 1σ; [`track`] is each
//! segment's fitted bias over the session (§11.4).

use super::model::SegModel;
use super::solve::{self, NormalSystem, Problem};
use super::{BiasWalk, EstimateError, EstimateOptions, SessionSeg, UnitWalk};
use nalgebra::{DMatrix, DVector};
use shared::linalg::RowMajor3;

/// The random walk the fit assumes.
#[derive(Clone, Debug, PartialEq)]
pub(crate) struct Drift {
    /// Intensity per axis, output unit²/s.
    pub q2: [f64; 3],
    /// Where every axis's walk is 0 (the session's first sample), s.
    pub t0_s: f64,
}

impl Drift {
    /// A walk of `mg_sqrt_s` on every axis, turned into output units with each axis's scale factor
    /// `k` (output unit per g).
    pub(crate) fn new(mg_sqrt_s: f64, k: [f64; 3], t0_s: f64) -> Drift {
        Drift {
            q2: k.map(|k| (mg_sqrt_s * 1e-3 * k).powi(2)),
            t0_s,
        }
    }

    /// A walk per axis in output unit/√s: `q_i = K_i`.
    fn per_axis_out(out_sqrt_s: [f64; 3], t0_s: f64) -> Drift {
        Drift {
            q2: out_sqrt_s.map(|q| q * q),
            t0_s,
        }
    }

    /// Whether the walk has any strength: without, the fit takes the per-segment path.
    pub(crate) fn active(&self) -> bool {
        self.q2.iter().any(|q| *q > 0.0)
    }
}

/// `∫₀^u ∫₀^v min(x, y) dy dx` for `u, v ≥ 0` (docs/model.md §11.1).
fn g(u: f64, v: f64) -> f64 {
    let (lo, hi) = if u <= v { (u, v) } else { (v, u) };
    lo * lo * hi / 2.0 - lo * lo * lo / 6.0
}

/// `Cov(w̄_a, w̄_b) / q²`: the covariance of a unit Wiener process's means over the spans `a` and
/// `b`, the walk starting at `t0` (docs/model.md §11.1). Disjoint spans give the earlier span's mean
/// time; one span `[s, s + L]` gives `s + L/3`.
pub(crate) fn interval_cov(a: [f64; 2], b: [f64; 2], t0: f64) -> f64 {
    let [a0, a1] = a.map(|t| (t - t0).max(0.0));
    let [b0, b1] = b.map(|t| (t - t0).max(0.0));
    let (la, lb) = (a1 - a0, b1 - b0);
    if la <= 0.0 || lb <= 0.0 {
        // A single sample: the walk's value there, or its mean over the other span up to it.
        let mid_a = 0.5 * (a0 + a1);
        let mid_b = 0.5 * (b0 + b1);
        return match (la > 0.0, lb > 0.0) {
            (false, false) => mid_a.min(mid_b),
            (true, false) => mean_min(a0, a1, mid_b),
            _ => mean_min(b0, b1, mid_a),
        };
    }
    (g(a1, b1) - g(a0, b1) - g(a1, b0) + g(a0, b0)) / (la * lb)
}

/// The mean of `min(x, p)` for `x` uniform on `[x0, x1]`.
fn mean_min(x0: f64, x1: f64, p: f64) -> f64 {
    if p >= x1 {
        return 0.5 * (x0 + x1);
    }
    if p <= x0 {
        return p;
    }
    ((p * p - x0 * x0) / 2.0 + p * (x1 - p)) / (x1 - x0)
}

/// The covariance of the stacked mean outputs of `models` (3 rows each, segment by segment):
/// each segment's own `se_cov` plus the walk's `q_a² C(s, s')` between equal axes.
fn covariance(models: &[SegModel], d: &Drift) -> DMatrix<f64> {
    with_own_noise(walk_part(models, d), models.iter().map(|m| &m.se_cov))
}

/// The walk's part of [`covariance`]: `q_a² C(s, s')` between equal axes.
fn walk_part(models: &[SegModel], d: &Drift) -> DMatrix<f64> {
    let spans: Vec<[f64; 2]> = models.iter().map(|m| m.span_s).collect();
    walk_covariance(&spans, d)
}

/// The walk's share of the covariance of stacked 3-row means taken over `spans` (in the same
/// order): `q_a² C(s, s')` between equal axes, 0 between different ones (docs/model.md §11.1).
/// The accelerometers' segment means and the gyro's mean rates (§11.6) both use it.
pub(crate) fn walk_covariance(spans: &[[f64; 2]], d: &Drift) -> DMatrix<f64> {
    let n = spans.len();
    let mut c = DMatrix::zeros(3 * n, 3 * n);
    for (s, &ss) in spans.iter().enumerate() {
        for (r, &sr) in spans.iter().enumerate().skip(s) {
            let w = interval_cov(ss, sr, d.t0_s);
            for a in 0..3 {
                let v = d.q2[a] * w;
                c[(3 * s + a, 3 * r + a)] += v;
                if r != s {
                    c[(3 * r + a, 3 * s + a)] += v;
                }
            }
        }
    }
    c
}

/// `walk` with each mean's own covariance added on its diagonal block: the means' whole
/// covariance `blockdiag(se_cov) + q² C` (docs/model.md §11.1).
pub(crate) fn with_own_noise<'a>(
    mut walk: DMatrix<f64>,
    own: impl Iterator<Item = &'a RowMajor3>,
) -> DMatrix<f64> {
    for (s, m) in own.enumerate() {
        for a in 0..3 {
            for b in 0..3 {
                walk[(3 * s + a, 3 * s + b)] += m[a][b];
            }
        }
    }
    walk
}

/// The walk's part of the covariance of a rest's spins taken as differences from it
/// (`solve::DiffGroup`): `C(j, k) − C(j, r) − C(r, k) + C(r, r)` per axis; spins and rest close in
/// time share most of their walk, so it mostly cancels.
pub(crate) fn difference_cov(rest: &SegModel, spins: &[SegModel], d: &Drift) -> DMatrix<f64> {
    let k = spins.len();
    let c = |a: &SegModel, b: &SegModel| interval_cov(a.span_s, b.span_s, d.t0_s);
    let rr = c(rest, rest);
    let mut out = DMatrix::zeros(3 * k, 3 * k);
    for (j, sj) in spins.iter().enumerate() {
        for (l, sl) in spins.iter().enumerate() {
            let w = c(sj, sl) - c(sj, rest) - c(rest, sl) + rr;
            for a in 0..3 {
                out[(3 * j + a, 3 * l + a)] = d.q2[a] * w;
            }
        }
    }
    out
}

/// Adds the segments' mean outputs to the normal equations with the full covariance of
/// [`covariance`], whitened by its Cholesky factor `L` (`L⁻¹ r`, `L⁻¹ J`); a covariance that is not
/// positive definite falls back to the per-segment weights.
pub(crate) fn add_models(ne: &mut NormalSystem, models: &[SegModel], d: &Drift, t: &[f64]) {
    let Some(chol) = covariance(models, d).cholesky() else {
        ne.add_models(models, t);
        return;
    };
    let k = ne.n.nrows();
    let rows = 3 * models.len();
    let mut r = DVector::zeros(rows);
    let mut jac = DMatrix::zeros(rows, k);
    for (s, m) in models.iter().enumerate() {
        let p = m.predict(t);
        for a in 0..3 {
            r[3 * s + a] = m.mean_u[a] - p[a];
        }
        for (q, dv) in m.jacobian(t) {
            let c = ne.col_of[q];
            if c == usize::MAX {
                continue;
            }
            for a in 0..3 {
                jac[(3 * s + a, c)] += dv[a];
            }
        }
    }
    let l = chol.l();
    let (Some(rw), Some(jw)) = (l.solve_lower_triangular(&r), l.solve_lower_triangular(&jac))
    else {
        ne.add_models(models, t);
        return;
    };
    ne.chi2 += rw.norm_squared();
    ne.n += jw.transpose() * &jw;
    ne.b += jw.transpose() * rw;
}

/// `log det` of the mean outputs' covariance under `d` (the restricted likelihood's term, §11.3).
fn log_det(models: &[SegModel], d: &Drift) -> Option<f64> {
    let chol = covariance(models, d).cholesky()?;
    let l = chol.l();
    Some((0..l.nrows()).map(|i| 2.0 * l[(i, i)].ln()).sum())
}

/// Where the walk's strength came from (docs/model.md §11.3).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum WalkOrigin {
    /// Given on the command line.
    Given,
    /// Taken from the unit's noise figures (a unit file's `[noise]`, or `host noise`'s Allan K).
    Unit,
    /// Estimated from the session by restricted maximum likelihood.
    Estimated,
}

impl WalkOrigin {
    /// The word reports use: `given`, `unit` or `estimated`.
    pub fn word(self) -> &'static str {
        match self {
            WalkOrigin::Given => "given",
            WalkOrigin::Unit => "unit",
            WalkOrigin::Estimated => "estimated",
        }
    }
}

/// The walk's strength, given or estimated from the session with its 1σ, and the strength the
/// segments were weighted with.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct WalkEstimate {
    /// Where it came from.
    pub origin: WalkOrigin,
    /// The strength given or estimated, mg/√s; taken from the unit, the strongest axis's.
    pub mg_sqrt_s: f64,
    /// Each axis's strength, mg/√s (the three equal unless taken from the unit per axis).
    pub axes_mg_sqrt_s: [f64; 3],
    /// Its 1σ (half the width of the likelihood interval), mg/√s; `None` when given, not estimated.
    pub sigma_mg_sqrt_s: Option<f64>,
    /// The likelihood interval (log-likelihood within ½ of its maximum), mg/√s: not symmetric about
    /// the estimate when the session holds little of the walk.
    pub interval_mg_sqrt_s: Option<[f64; 2]>,
    /// The strength the fit weighted the segments with, mg/√s: the given one, or for an estimate
    /// `√(K̂² + σ²)`, the walk's mean square over its likelihood (docs/model.md §11.3).
    pub fit_mg_sqrt_s: f64,
    /// For an estimate, how far the session's likelihood rules out no walk at all:
    /// `√(2 (log L(K̂) − log L(0)))`, in σ (docs/model.md §11.3).
    pub significance: Option<f64>,
    /// Whether the fit weighted the segments with it: always when given or taken from the unit;
    /// an estimate only where the session determines it (a significance of at least
    /// [`Z_WALK`]); otherwise the bias is fitted as constant.
    pub used: bool,
}

/// An estimated walk is used when the session's likelihood rules out no walk by at least this
/// many σ (a likelihood ratio `2 Δlog L ≥ 4`; on a session without a walk, about one in 44 crosses
/// it, and then at a strength too weak to move the fit much).
pub const Z_WALK: f64 = 2.0;

/// The maximum of a walk strength's restricted log-likelihood (docs/model.md §11.3): the strength,
/// the interval where the log-likelihood is within ½ of its maximum, and the maximum's height above
/// no walk.
pub(crate) struct Search {
    pub q: f64,
    pub interval: [f64; 2],
    pub gain: f64,
    /// The log-likelihood at `q`.
    pub peak: f64,
}

impl Search {
    /// Half the likelihood interval's width: the 1σ.
    pub(crate) fn sigma(&self) -> f64 {
        0.5 * (self.interval[1] - self.interval[0])
    }

    /// `√(2 Δlog L)` against no walk, σ.
    pub(crate) fn significance(&self) -> f64 {
        (2.0 * self.gain.max(0.0)).sqrt()
    }
}

/// Golden-section steps and bisections that place a strength and its interval's ends (the first
/// leave 10⁻⁵ of their bracket, the second 6·10⁻⁸).
const REFINE: usize = 24;

/// The walk strength on `grid` (then refined by golden section) that maximises the log-likelihood
/// `at`, with its likelihood interval (docs/model.md §11.3).
pub(crate) fn search(
    at: &dyn Fn(f64) -> Result<f64, EstimateError>,
    grid: &[f64],
    fail: &dyn Fn() -> EstimateError,
) -> Result<Search, EstimateError> {
    let top = peak(at, grid, fail, REFINE)?;
    interval(at, &top, grid[grid.len() - 1], REFINE)
}

/// The maximum of a log-likelihood over a grid of strengths and 0: every point evaluated, the
/// best, and the log-likelihood at 0.
pub(crate) struct Peak {
    pts: Vec<(f64, f64)>,
    pub q: f64,
    pub l: f64,
    l0: f64,
}

/// The strength on `grid` or 0 that maximises `at`, refined by `steps` of golden section between
/// the best grid point's neighbours.
pub(crate) fn peak(
    at: &dyn Fn(f64) -> Result<f64, EstimateError>,
    grid: &[f64],
    fail: &dyn Fn() -> EstimateError,
    steps: usize,
) -> Result<Peak, EstimateError> {
    let l0 = at(0.0)?;
    let mut pts: Vec<(f64, f64)> = vec![(0.0, l0)];
    for &q in grid {
        pts.push((q, at(q)?));
    }
    let best = (0..pts.len())
        .max_by(|&a, &b| pts[a].1.total_cmp(&pts[b].1))
        .ok_or_else(fail)?;
    let (mut q, mut l) = pts[best];
    if best > 0 && best + 1 < pts.len() {
        let floor = grid[0] / 10.0;
        (q, l) = golden(at, pts[best - 1].0.max(floor), pts[best + 1].0, steps)?;
        if l < pts[best].1 {
            (q, l) = pts[best];
        }
    }
    Ok(Peak { pts, q, l, l0 })
}

/// The likelihood interval about `top` (where `at` is within ½ of its maximum), its ends placed by
/// `steps` bisections; `grid_top` the grid's strongest, above which an upper end is looked for
/// up to ten times it.
pub(crate) fn interval(
    at: &dyn Fn(f64) -> Result<f64, EstimateError>,
    top: &Peak,
    grid_top: f64,
    steps: usize,
) -> Result<Search, EstimateError> {
    let (q, l) = (top.q, top.l);
    let target = l - 0.5;
    let lower = if q == 0.0 || top.l0 >= target {
        0.0
    } else {
        crossing(at, 0.0, q, target, steps)?
    };
    let hi = top
        .pts
        .iter()
        .find(|(x, v)| *x > q && *v < target)
        .map_or(10.0 * q.max(grid_top), |p| p.0);
    let upper = crossing(at, q, hi, target, steps)?;
    Ok(Search {
        q,
        interval: [lower, upper],
        gain: l - top.l0,
        peak: l,
    })
}

/// A given walk (or one taken from the unit) set on `problem`, its scale factors from the
/// constant-bias `static_fit`; `None` when the bias is constant, or when the walk is to be estimated
/// (the constant-bias fit comes first, docs/model.md §11.3).
pub(crate) fn apply(
    options: &EstimateOptions,
    segs: &[SessionSeg],
    problem: &mut Problem,
    static_fit: &solve::Fit,
) -> Option<WalkEstimate> {
    let k = scale_factors(&static_fit.theta);
    let t0 = start_time(segs);
    let (drift, origin, axes) = match options.bias_walk {
        BiasWalk::Given(mg) => (Drift::new(mg, k, t0), WalkOrigin::Given, [mg; 3]),
        BiasWalk::FromUnit(UnitWalk::MgSqrtS(mg)) => {
            let d = Drift {
                q2: core::array::from_fn(|a| (mg[a] * 1e-3 * k[a]).powi(2)),
                t0_s: t0,
            };
            (d, WalkOrigin::Unit, mg)
        }
        BiasWalk::FromUnit(UnitWalk::OutputPerSqrtS(out, _)) => {
            // K_i output unit/√s over k_i output unit/g is g/√s; ×10³ mg.
            let mg = core::array::from_fn(|a| out[a] / k[a] * 1e3);
            (Drift::per_axis_out(out, t0), WalkOrigin::Unit, mg)
        }
        BiasWalk::Off | BiasWalk::Estimate => return None,
    };
    problem.drift = Some(drift);
    let strongest = axes.iter().copied().fold(0.0, f64::max);
    Some(WalkEstimate {
        origin,
        mg_sqrt_s: strongest,
        axes_mg_sqrt_s: axes,
        sigma_mg_sqrt_s: None,
        interval_mg_sqrt_s: None,
        fit_mg_sqrt_s: strongest,
        significance: None,
        used: true,
    })
}

/// One segment's fitted wander of the bias from `u0` (docs/model.md §11.4).
#[derive(Clone, Debug, PartialEq)]
pub struct WalkPoint {
    /// The segment's name.
    pub name: String,
    /// The middle of its span, s from the session's first sample.
    pub t_mid_s: f64,
    /// The walk's mean over the segment per axis, mg.
    pub bias_mg: [f64; 3],
    /// Its 1σ per axis, mg: the spread of the true wander about the fitted one (docs/model.md §11.4).
    pub sigma_mg: [f64; 3],
}

/// Each plain segment's fitted walk, `Σ_walk Σ⁻¹ r` at `theta` (the walk's conditional mean given
/// the residuals, docs/model.md §11.4), with its 1σ from `cov` (θ's covariance), in time order;
/// empty without a walk.
pub(crate) fn track(
    problem: &Problem,
    theta: &[f64],
    cov: &DMatrix<f64>,
    segs: &[SessionSeg],
) -> Vec<WalkPoint> {
    let Some(d) = problem.drift.as_ref().filter(|d| d.active()) else {
        return Vec::new();
    };
    let models = &problem.models;
    let walk = walk_part(models, d);
    let sigma = with_own_noise(walk.clone(), models.iter().map(|m| &m.se_cov));
    let rows = 3 * models.len();
    let r = DVector::from_iterator(
        rows,
        models.iter().flat_map(|m| {
            let p = m.predict(theta);
            (0..3).map(move |a| m.mean_u[a] - p[a])
        }),
    );
    let mut jac = DMatrix::zeros(rows, theta.len());
    for (s, m) in models.iter().enumerate() {
        for (q, dv) in m.jacobian(theta) {
            for a in 0..3 {
                jac[(3 * s + a, q)] += dv[a];
            }
        }
    }
    let Some(chol) = sigma.cholesky() else {
        return Vec::new();
    };
    // A = Σ_walk Σ⁻¹ (both symmetric): the prediction, and its error's covariance
    // Σ_walk − A Σ_walk + (A J) cov (A J)ᵀ (the second term the residuals' share of θ's error).
    let a_mat = chol.solve(&walk).transpose();
    let w = &a_mat * r;
    let aj = &a_mat * jac;
    let from_theta = (&aj * cov).component_mul(&aj).column_sum();
    let shrunk = (&a_mat * &walk).diagonal();
    let k = scale_factors(theta);
    let t0 = start_time(segs);
    let sd = |i: usize, a: usize| {
        (walk[(i, i)] - shrunk[i] + from_theta[i]).max(0.0).sqrt() / k[a] * 1e3
    };
    let mut out: Vec<WalkPoint> = models
        .iter()
        .enumerate()
        .map(|(s, m)| WalkPoint {
            name: segs[m.seg].stats.name.clone(),
            t_mid_s: 0.5 * (m.span_s[0] + m.span_s[1]) - t0,
            bias_mg: core::array::from_fn(|a| w[3 * s + a] / k[a] * 1e3),
            sigma_mg: core::array::from_fn(|a| sd(3 * s + a, a)),
        })
        .collect();
    out.sort_by(|a, b| a.t_mid_s.total_cmp(&b.t_mid_s));
    out
}

/// Each axis's scale factor (output unit per g) from a fit's `M`: what turns mg/√s into output units.
pub(crate) fn scale_factors(theta: &[f64]) -> [f64; 3] {
    let m = super::model::m_of(theta);
    core::array::from_fn(|i| shared::linalg::norm(&m[i]))
}

/// The session's first sample, s: where the walk starts.
pub(crate) fn start_time(segs: &[SessionSeg]) -> f64 {
    segs.iter()
        .map(|s| s.stats.t_first_s)
        .fold(f64::INFINITY, f64::min)
}

/// The restricted log-likelihood (docs/model.md §11.3) of the fit's problem `p` under a walk of
/// `mg` mg/√s: `−½ (χ² + log det Σ + log det N)` at the generalised least-squares fit (the terms
/// that do not depend on the walk, the gyro's and the priors' own, left out).
struct Likelihood<'a> {
    p: &'a Problem,
    start: &'a [f64],
    free: &'a [bool],
    k: [f64; 3],
    t0: f64,
}

impl Likelihood<'_> {
    fn at(&self, mg: f64) -> Option<f64> {
        let mut p = self.p.clone();
        let d = Drift::new(mg, self.k, self.t0);
        let ld_sigma = log_det(&p.models, &d)?;
        p.drift = Some(d);
        if !p.groups.is_empty() {
            // The differences' covariance holds the walk: group them again under it.
            let rests = p.rest_segments.clone();
            p.group_spins(&|s| rests.contains(&s));
        }
        // `whiten` is `L⁻¹`, lower triangular: its diagonal is `1 / L_ii`.
        let ld_groups: f64 = p
            .groups
            .iter()
            .map(|g| {
                (0..g.whiten.nrows())
                    .map(|i| -2.0 * g.whiten[(i, i)].ln())
                    .sum::<f64>()
            })
            .sum();
        let fit = solve::fit(
            &p,
            self.start.to_vec(),
            self.free.to_vec(),
            "walk likelihood",
        )
        .ok()?;
        let ld_n = log_det_information(&p, &fit.theta, &fit.free)?;
        Some(-0.5 * (fit.chi2 + ld_sigma + ld_groups + ld_n))
    }
}

/// `log det` of the information matrix over the free columns at `t` (the restricted likelihood's
/// term), or `None` when it is not positive definite.
pub(crate) fn log_det_information(p: &Problem, t: &[f64], free: &[bool]) -> Option<f64> {
    let cols = solve::Columns::new(free, p.single_package);
    let (n, _, _) = solve::normal_equations(p, t, &cols, None);
    let chol = n.cholesky()?;
    let l = chol.l();
    Some((0..l.nrows()).map(|i| 2.0 * l[(i, i)].ln()).sum())
}

/// The grid the likelihood is first searched on, mg/√s: 10⁻⁵ to 1 in quarter decades.
fn grid() -> impl Iterator<Item = f64> {
    (0..=20).map(|i| 10f64.powf(-5.0 + 0.25 * i as f64))
}

/// The walk's strength that maximises the restricted likelihood of the fit's problem (every used
/// segment, the gyro's observations and model, the attitude priors; docs/model.md §11.3), and half
/// the width of the interval where the log-likelihood is within ½ of its maximum as its 1σ.
/// `theta` and `free` are the constant-bias fit's, which it starts from.
pub(crate) fn estimate(
    problem: &Problem,
    theta: &[f64],
    free: &[bool],
    segs: &[SessionSeg],
) -> Result<WalkEstimate, EstimateError> {
    let lik = Likelihood {
        p: problem,
        start: theta,
        free,
        k: scale_factors(theta),
        t0: start_time(segs),
    };
    let fail = || EstimateError::Singular {
        what: "bias random walk likelihood",
    };
    let at = |mg: f64| lik.at(mg).ok_or_else(fail);
    let grid: Vec<f64> = grid().collect();
    let found = search(&at, &grid, &fail)?;
    let (q, sigma) = (found.q, found.sigma());
    Ok(WalkEstimate {
        origin: WalkOrigin::Estimated,
        mg_sqrt_s: q,
        axes_mg_sqrt_s: [q; 3],
        sigma_mg_sqrt_s: Some(sigma),
        interval_mg_sqrt_s: Some(found.interval),
        fit_mg_sqrt_s: q.hypot(sigma),
        significance: Some(found.significance()),
        used: found.significance() >= Z_WALK,
    })
}

/// The maximum of `f` on `[a, b]` by `steps` of golden section in `ln q`.
fn golden(
    f: &dyn Fn(f64) -> Result<f64, EstimateError>,
    a: f64,
    b: f64,
    steps: usize,
) -> Result<(f64, f64), EstimateError> {
    let r = (5f64.sqrt() - 1.0) / 2.0;
    let (mut lo, mut hi) = (a.ln(), b.ln());
    let mut x1 = hi - r * (hi - lo);
    let mut x2 = lo + r * (hi - lo);
    let (mut f1, mut f2) = (f(x1.exp())?, f(x2.exp())?);
    for _ in 0..steps {
        if f1 >= f2 {
            hi = x2;
            (x2, f2) = (x1, f1);
            x1 = hi - r * (hi - lo);
            f1 = f(x1.exp())?;
        } else {
            lo = x1;
            (x1, f1) = (x2, f2);
            x2 = lo + r * (hi - lo);
            f2 = f(x2.exp())?;
        }
    }
    Ok(if f1 >= f2 {
        (x1.exp(), f1)
    } else {
        (x2.exp(), f2)
    })
}

/// Where `f` crosses `target` between `a` and `b` (one side above it, the other below), by
/// `steps` bisections.
fn crossing(
    f: &dyn Fn(f64) -> Result<f64, EstimateError>,
    a: f64,
    b: f64,
    target: f64,
    steps: usize,
) -> Result<f64, EstimateError> {
    let above_at_a = f(a)? >= target;
    let (mut lo, mut hi) = (a, b);
    for _ in 0..steps {
        let mid = 0.5 * (lo + hi);
        if (f(mid)? >= target) == above_at_a {
            lo = mid;
        } else {
            hi = mid;
        }
    }
    Ok(0.5 * (lo + hi))
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::estimate::attitude;
    use crate::estimate::model::{idx_m, idx_u0, Mount, TiltGeometry};

    /// The dense path with a walk too weak to matter is the per-segment path: the same χ² and the
    /// same covariance of θ at the same θ, to rounding (no iteration in between to differ by).
    #[test]
    fn the_dense_path_without_a_walk_is_the_per_segment_path() {
        let mut rng = shared::rng::Rng::new(3, 0);
        let ups = [
            [1.0, 0.0, 0.0],
            [-1.0, 0.0, 0.0],
            [0.0, 1.0, 0.0],
            [0.0, -1.0, 0.0],
            [0.0, 0.0, 1.0],
            [0.0, 0.0, -1.0],
            [0.6, 0.0, 0.8],
        ];
        let mut mounts = Vec::new();
        let mut models = Vec::new();
        for (k, up) in ups.iter().enumerate() {
            let geometry = TiltGeometry::new(*up, k);
            mounts.push(Mount {
                name: format!("m{k}"),
                geometry,
                prior_rad: Some(1e-3),
                up_given: true,
                spins: false,
            });
            let mean_u = core::array::from_fn(|i| 2.4 + 0.4 * up[i] + 1e-4 * rng.normal());
            let c = 1e-8 * (1.0 + rng.range(0.0, 1.0));
            let se = [[c, 0.2 * c, 0.0], [0.2 * c, c, 0.1 * c], [0.0, 0.1 * c, c]];
            let mut m = SegModel::new(k, geometry, [0.0; 3], [[0.0; 3]; 3], mean_u, se).unwrap();
            m.span_s = [40.0 * k as f64, 40.0 * k as f64 + 30.0];
            models.push(m);
        }
        let mut p = Problem::new(models, mounts);
        let mut t = vec![0.0; p.n_params()];
        let mut free = crate::estimate::screen::static_free(t.len());
        attitude::tilt_free(&p, &mut free);
        for i in 0..3 {
            t[idx_m(i, i)] = 0.4;
            t[idx_u0(i)] = 2.4;
        }
        let plain = (
            p.chi2(&t, &free),
            solve::covariance(&p, &t, &free, None).unwrap(),
        );
        p.drift = Some(Drift {
            q2: [1e-300; 3],
            t0_s: 0.0,
        });
        assert!(p.drift.as_ref().unwrap().active());
        let dense = (
            p.chi2(&t, &free),
            solve::covariance(&p, &t, &free, None).unwrap(),
        );
        assert!(
            (plain.0 - dense.0).abs() <= 1e-12 * plain.0,
            "{plain:?} {dense:?}"
        );
        let worst = (0..t.len())
            .flat_map(|a| (0..t.len()).map(move |b| (a, b)))
            .filter(|&(a, b)| plain.1[(a, a)] > 0.0 && plain.1[(b, b)] > 0.0)
            .map(|(a, b)| {
                (plain.1[(a, b)] - dense.1[(a, b)]).abs()
                    / (plain.1[(a, a)] * plain.1[(b, b)]).sqrt()
            })
            .fold(0.0, f64::max);
        assert!(worst < 1e-12, "{worst}");
    }

    /// The closed forms against a direct double sum over a fine grid.
    #[test]
    fn interval_covariance_matches_a_direct_sum() {
        let direct = |a: [f64; 2], b: [f64; 2]| {
            let n = 400;
            let (ha, hb) = ((a[1] - a[0]) / n as f64, (b[1] - b[0]) / n as f64);
            let mut s = 0.0;
            for i in 0..n {
                for j in 0..n {
                    let x = a[0] + (i as f64 + 0.5) * ha;
                    let y = b[0] + (j as f64 + 0.5) * hb;
                    s += x.min(y);
                }
            }
            s / (n * n) as f64
        };
        for (a, b) in [
            ([2.0, 32.0], [40.0, 70.0]),
            ([40.0, 70.0], [2.0, 32.0]),
            ([5.0, 35.0], [5.0, 35.0]),
            ([0.0, 10.0], [5.0, 20.0]),
        ] {
            let c = interval_cov(a, b, 0.0);
            assert!((c - direct(a, b)).abs() < 1e-3, "{a:?} {b:?}: {c}");
        }
        // The two named forms: disjoint spans, and one span.
        assert!((interval_cov([2.0, 32.0], [40.0, 70.0], 0.0) - 17.0).abs() < 1e-9);
        assert!((interval_cov([5.0, 35.0], [5.0, 35.0], 0.0) - 15.0).abs() < 1e-9);
        // Shifting time and the start together changes nothing.
        let shifted = interval_cov([1e6 + 2.0, 1e6 + 32.0], [1e6 + 40.0, 1e6 + 70.0], 1e6);
        assert!((shifted - 17.0).abs() < 1e-6);
    }
}
