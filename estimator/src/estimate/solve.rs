//! Weighted least squares (Gauss–Newton) over the segment models, the gyro's rotation-axis
//! directions and the mounts' attitude priors, with a free-parameter mask.
//!
//! The model is bilinear (`m_i · E r_i`) and nearly linear in the small tilts, so Gauss–Newton from
//! the static solution with `r = 0` converges in a few iterations; a step that raises χ² is halved
//! (free attitudes may start tens of degrees off). Normal equations are solved after scaling every
//! column to unit diagonal: the parameters span ten orders of magnitude (V/g against metres).

use super::drift::{self, Drift};
use super::gyro::{self, GyroBlock, NG};
use super::gyro_drift;
use super::model::{is_lever, Mount, SegModel, TiltGeometry, NI};
use super::EstimateError;
use nalgebra::{DMatrix, DVector};

/// During a spin the gyro measures the rotation axis, which is the mount's true up
/// (docs/model.md §7): the components of the measured axis on the mount's tilt axes.
#[derive(Clone, Debug)]
pub(crate) struct GyroDirection {
    /// Index into the session's segment list.
    pub seg: usize,
    /// The mount's attitude unknowns.
    pub tilt: TiltGeometry,
    /// Measured unit axis (sign of the nominal up) · each tilt axis.
    pub measured: [f64; 2],
    /// 1σ of `measured`.
    pub sigma: [f64; 2],
}

impl GyroDirection {
    /// Residuals and their derivatives by (α, β), unweighted.
    fn residual(&self, t: &[f64]) -> ([f64; 2], [[f64; 2]; 2]) {
        let (up, d) = self.tilt.up_and_derivatives(t);
        let e = &self.tilt.basis;
        let dot = shared::linalg::dot;
        (
            core::array::from_fn(|c| self.measured[c] - dot(&up, &e[c])),
            core::array::from_fn(|c| core::array::from_fn(|k| dot(&d[k], &e[c]))),
        )
    }
}

/// A mount's spinning segments as differences from its rest segment (docs/model.md §7): the mount's
/// gravity, its tilt and the biases cancel, so the spins inform the lever arms (and, weakly, `M`
/// through `M E r`) but not the static parameters, which come from the rest segments alone; a misfit
/// of the dynamic model then cannot move them. The differences share the rest's noise, so they are
/// whitened together.
#[derive(Clone, Debug)]
pub(crate) struct DiffGroup {
    /// The rest segment (also an observation of its own in [`Problem::models`]).
    pub rest: SegModel,
    /// The spins.
    pub spins: Vec<SegModel>,
    /// `L⁻¹` of the stacked differences' covariance (3k × 3k).
    pub whiten: DMatrix<f64>,
}

impl DiffGroup {
    /// Groups `spins` with `rest`, with the bias random walk's share of the differences when there
    /// is one (docs/model.md §11.2); `None` when the covariance is not positive definite.
    pub fn new(rest: SegModel, spins: Vec<SegModel>, walk: Option<&Drift>) -> Option<DiffGroup> {
        let k = spins.len();
        let mut c = DMatrix::from_fn(3 * k, 3 * k, |a, b| {
            let (i, j) = (a / 3, b / 3);
            let own = if i == j {
                spins[i].se_cov[a % 3][b % 3]
            } else {
                0.0
            };
            own + rest.se_cov[a % 3][b % 3]
        });
        if let Some(d) = walk.filter(|d| d.active()) {
            c += drift::difference_cov(&rest, &spins, d);
        }
        let whiten = c.cholesky()?.l().try_inverse()?;
        Some(DiffGroup {
            rest,
            spins,
            whiten,
        })
    }

    /// Residuals (measured − predicted differences) and the Jacobian columns, both unwhitened.
    fn residual(&self, t: &[f64]) -> (DVector<f64>, Vec<(usize, DVector<f64>)>) {
        let k = self.spins.len();
        let pr = self.rest.predict(t);
        let mut r = DVector::zeros(3 * k);
        let mut cols: Vec<(usize, DVector<f64>)> = Vec::new();
        let add = |q: usize, row: usize, v: f64, cols: &mut Vec<(usize, DVector<f64>)>| match cols
            .iter_mut()
            .find(|(p, _)| *p == q)
        {
            Some((_, c)) => c[row] += v,
            None => {
                let mut c = DVector::zeros(3 * k);
                c[row] = v;
                cols.push((q, c));
            }
        };
        let jr = self.rest.jacobian(t);
        for (j, s) in self.spins.iter().enumerate() {
            let ps = s.predict(t);
            for a in 0..3 {
                r[3 * j + a] = (s.mean_u[a] - self.rest.mean_u[a]) - (ps[a] - pr[a]);
            }
            for (q, d) in s.jacobian(t) {
                for a in 0..3 {
                    add(q, 3 * j + a, d[a], &mut cols);
                }
            }
            for (q, d) in &jr {
                for a in 0..3 {
                    add(*q, 3 * j + a, -d[a], &mut cols);
                }
            }
        }
        (r, cols)
    }
}

/// Everything the fit sees.
#[derive(Clone, Debug)]
pub(crate) struct Problem {
    /// Mean outputs of the used segments.
    pub models: Vec<SegModel>,
    /// The mounts (tilt unknowns and priors), in θ order.
    pub mounts: Vec<Mount>,
    /// Gyro axis directions of the used spinning segments (a gyro taken as perfect).
    pub gyro: Vec<GyroDirection>,
    /// The gyro model `w = G ω + b`, when estimated (docs/model.md §8).
    pub gyro_block: Option<GyroBlock>,
    /// Spins taken as differences from their mount's rest segment.
    pub groups: Vec<DiffGroup>,
    /// The segments at rest when the spins were grouped (to regroup after a removal).
    pub rest_segments: Vec<usize>,
    /// The three accelerometers share one package: one lever arm `r` for all three
    /// (docs/model.md §4.7), fitted as one column per component of the normal equations.
    pub single_package: bool,
    /// The accelerometers' bias random walk the outputs are weighted with (docs/model.md §11);
    /// `None` (or a zero walk): a constant bias, each segment weighted by its own noise.
    pub drift: Option<Drift>,
}

impl Problem {
    /// The accelerometers' problem alone: these segment models and mounts, the gyro taken as perfect
    /// and not observed, no spin taken as a difference (the static fit and the first joint pass).
    pub fn new(models: Vec<SegModel>, mounts: Vec<Mount>) -> Problem {
        Problem {
            models,
            mounts,
            gyro: Vec::new(),
            gyro_block: None,
            groups: Vec::new(),
            rest_segments: Vec::new(),
            single_package: false,
            drift: None,
        }
    }

    /// Length of θ.
    pub(crate) fn n_params(&self) -> usize {
        NI + 2 * self.mounts.len() + if self.gyro_block.is_some() { NG } else { 0 }
    }

    /// Every segment model: the plain ones and the grouped spins.
    pub(crate) fn all_models(&self) -> Vec<SegModel> {
        let mut v = self.models.clone();
        v.extend(self.groups.iter().flat_map(|g| g.spins.iter().cloned()));
        v
    }

    /// Moves every spin whose mount has a used rest segment into a [`DiffGroup`] with it (`is_rest`
    /// says which segments are at rest).
    pub(crate) fn group_spins(&mut self, is_rest: &dyn Fn(usize) -> bool) {
        self.ungroup();
        let mut keep = Vec::new();
        let mut spins: Vec<SegModel> = Vec::new();
        self.rest_segments.clear();
        for m in std::mem::take(&mut self.models) {
            if is_rest(m.seg) {
                self.rest_segments.push(m.seg);
                keep.push(m);
            } else {
                spins.push(m);
            }
        }
        let mut loose = Vec::new();
        let mut by_rest: Vec<(usize, Vec<SegModel>)> = Vec::new();
        for s in spins {
            match keep.iter().position(|r| r.tilt.index == s.tilt.index) {
                Some(r) => match by_rest.iter_mut().find(|(q, _)| *q == r) {
                    Some((_, v)) => v.push(s),
                    None => by_rest.push((r, vec![s])),
                },
                None => loose.push(s),
            }
        }
        for (r, v) in by_rest {
            match DiffGroup::new(keep[r].clone(), v.clone(), self.drift.as_ref()) {
                Some(g) => self.groups.push(g),
                None => loose.extend(v),
            }
        }
        keep.extend(loose);
        self.models = keep;
    }

    /// Returns grouped spins to the plain models.
    pub(crate) fn ungroup(&mut self) {
        for g in std::mem::take(&mut self.groups) {
            self.models.extend(g.spins);
        }
    }

    /// Removes the segment `seg` (its outputs and gyro axis).
    pub(crate) fn remove_segment(&mut self, seg: usize) {
        let grouped = !self.groups.is_empty();
        if grouped {
            self.ungroup();
        }
        self.models.retain(|m| m.seg != seg);
        self.gyro.retain(|g| g.seg != seg);
        if let Some(b) = &mut self.gyro_block {
            b.means.retain(|m| m.seg != seg);
        }
        if grouped {
            let rests: Vec<usize> = self.rest_segments.clone();
            self.group_spins(&|s| rests.contains(&s));
        }
    }

    /// Moves mount `k`'s nominal up (a free attitude's starting guess) and its tilt axes.
    pub(crate) fn set_nominal(&mut self, k: usize, up: [f64; 3]) {
        let g = TiltGeometry::new(up, k);
        self.mounts[k].geometry = g;
        for m in self.models.iter_mut().filter(|m| m.tilt.index == g.index) {
            m.tilt = g;
        }
        for o in self.gyro.iter_mut().filter(|o| o.tilt.index == g.index) {
            o.tilt = g;
        }
        for grp in &mut self.groups {
            for m in std::iter::once(&mut grp.rest)
                .chain(grp.spins.iter_mut())
                .filter(|m| m.tilt.index == g.index)
            {
                m.tilt = g;
            }
        }
        if let Some(b) = &mut self.gyro_block {
            for o in b.means.iter_mut().filter(|o| o.tilt.index == g.index) {
                o.tilt = g;
            }
        }
    }

    /// Number of observations: 3 per segment, 2 per gyro axis, 2 per mount prior.
    fn observations(&self, free: &[bool]) -> i64 {
        let priors = self
            .mounts
            .iter()
            .filter(|m| matches!(m.prior_rad, Some(s) if s > 0.0) && free[m.geometry.index])
            .count();
        let gyro = self
            .gyro_block
            .as_ref()
            .map_or(0, |b| 3 * b.means.len() as i64 + 10);
        let spins: usize = self.groups.iter().map(|g| g.spins.len()).sum();
        3 * (self.models.len() + spins) as i64
            + 2 * self.gyro.len() as i64
            + 2 * priors as i64
            + gyro
    }

    /// χ² at θ (outputs, gyro axes and priors).
    pub(crate) fn chi2(&self, t: &[f64], free: &[bool]) -> f64 {
        normal_equations(self, t, &Columns::new(free, self.single_package), None).2
    }
}

/// A converged fit.
#[derive(Clone, Debug)]
pub(crate) struct Fit {
    /// The estimate (fixed entries keep their starting value).
    pub theta: Vec<f64>,
    /// Covariance of θ from the weights alone (not scaled by χ²), zero rows for fixed entries.
    pub cov: DMatrix<f64>,
    /// Σ of whitened residuals² (priors included).
    pub chi2: f64,
    /// Observations − free parameters.
    pub dof: i64,
    /// Which entries were estimated.
    pub free: Vec<bool>,
}

/// Inverse of a symmetric positive-definite matrix via Jacobi scaling and Cholesky; `None` when it
/// is not numerically positive definite.
pub(crate) fn invert_spd(n: &DMatrix<f64>, min_eigen: f64) -> Option<DMatrix<f64>> {
    let k = n.nrows();
    let d: Vec<f64> = (0..k).map(|i| n[(i, i)]).collect();
    if d.iter().any(|v| !(v.is_finite() && *v > 0.0)) {
        return None;
    }
    let s: Vec<f64> = d.iter().map(|v| 1.0 / v.sqrt()).collect();
    let scaled = DMatrix::from_fn(k, k, |i, j| n[(i, j)] * s[i] * s[j]);
    // Reject near-singular systems: the smallest eigenvalue of the scaled matrix is a conditioning
    // measure independent of units.
    if min_eigen > 0.0 {
        let eig = scaled.clone().symmetric_eigen();
        let min = eig
            .eigenvalues
            .iter()
            .copied()
            .fold(f64::INFINITY, f64::min);
        if min.is_nan() || min <= min_eigen {
            return None;
        }
    }
    let inv = scaled.cholesky()?.inverse();
    Some(DMatrix::from_fn(k, k, |i, j| inv[(i, j)] * s[i] * s[j]))
}

/// Information matrix `Jᵀ Σ⁻¹ J` over the free entries (with the mounts' attitude priors, and an
/// optional prior of 1σ = `prior_r_m` on every free lever-arm component), `Jᵀ Σ⁻¹ res`, and χ².
///
/// The blocks are accumulated in a fixed order (outputs, grouped spins, gyro axes, gyro model, mount
/// priors, lever-arm prior): the sums, and so the fit's numbers, depend on it.
pub(crate) fn normal_equations(
    p: &Problem,
    t: &[f64],
    cols: &Columns,
    prior_r_m: Option<f64>,
) -> (DMatrix<f64>, DVector<f64>, f64) {
    let mut ne = NormalSystem::new(cols);
    match p.drift.as_ref().filter(|d| d.active()) {
        Some(d) => drift::add_models(&mut ne, &p.models, d, t),
        None => ne.add_models(&p.models, t),
    }
    ne.add_groups(&p.groups, t);
    ne.add_gyro_directions(&p.gyro, t);
    if let Some(blk) = &p.gyro_block {
        ne.add_gyro_block(blk, t);
    }
    ne.add_mount_priors(&p.mounts, t);
    if let Some(sig) = prior_r_m {
        ne.add_lever_prior(sig, t, &cols.first);
    }
    (ne.n, ne.b, ne.chi2)
}

/// The normal equations being accumulated, one block of observations at a time.
pub(crate) struct NormalSystem {
    /// Column of each θ entry in `n` and `b` (`usize::MAX` for a fixed entry).
    pub(crate) col_of: Vec<usize>,
    /// `Jᵀ Σ⁻¹ J` so far.
    pub(crate) n: DMatrix<f64>,
    /// `Jᵀ Σ⁻¹ res` so far.
    pub(crate) b: DVector<f64>,
    /// Σ of whitened residuals² so far.
    pub(crate) chi2: f64,
}

impl NormalSystem {
    /// Empty normal equations over the columns `cols`.
    fn new(cols: &Columns) -> NormalSystem {
        let k = cols.first.len();
        NormalSystem {
            col_of: cols.col_of.clone(),
            n: DMatrix::<f64>::zeros(k, k),
            b: DVector::<f64>::zeros(k),
            chi2: 0.0,
        }
    }

    /// Adds one whitened row: its free columns `(column, value)` and its residual.
    fn add_row(&mut self, cols: &[(usize, f64)], res: f64) {
        for &(c1, v1) in cols {
            self.b[c1] += v1 * res;
            for &(c2, v2) in cols {
                self.n[(c1, c2)] += v1 * v2;
            }
        }
    }

    /// The segments' mean outputs (docs/model.md §4), each weighted by its own noise.
    pub(crate) fn add_models(&mut self, models: &[SegModel], t: &[f64]) {
        for s in models {
            let jac = s.jacobian(t);
            let res = s.whitened_residual(t);
            self.chi2 += res.iter().map(|v| v * v).sum::<f64>();
            // Whitened Jacobian rows: L⁻¹ J, restricted to the free columns.
            for a in 0..3 {
                let mut cols: Vec<(usize, f64)> = Vec::with_capacity(jac.len());
                for (q, d) in &jac {
                    let c = self.col_of[*q];
                    if c == usize::MAX {
                        continue;
                    }
                    let v: f64 = (0..3).map(|r| s.whiten[a][r] * d[r]).sum();
                    if v != 0.0 {
                        cols.push((c, v));
                    }
                }
                self.add_row(&cols, res[a]);
            }
        }
    }

    /// The spins taken as differences from their rest segment (docs/model.md §7).
    fn add_groups(&mut self, groups: &[DiffGroup], t: &[f64]) {
        for grp in groups {
            let (r, cols) = grp.residual(t);
            let rw = &grp.whiten * r;
            self.chi2 += rw.norm_squared();
            let wcols: Vec<(usize, DVector<f64>)> = cols
                .into_iter()
                .filter(|(q, _)| self.col_of[*q] != usize::MAX)
                .map(|(q, c)| (self.col_of[q], &grp.whiten * c))
                .collect();
            for row in 0..rw.len() {
                let cs: Vec<(usize, f64)> = wcols
                    .iter()
                    .filter(|(_, c)| c[row] != 0.0)
                    .map(|(q, c)| (*q, c[row]))
                    .collect();
                self.add_row(&cs, rw[row]);
            }
        }
    }

    /// The gyro's rotation-axis directions of the spins (docs/model.md §7).
    fn add_gyro_directions(&mut self, gyro: &[GyroDirection], t: &[f64]) {
        for g in gyro {
            let (res, d) = g.residual(t);
            for c in 0..2 {
                let w = 1.0 / g.sigma[c];
                self.chi2 += (res[c] * w).powi(2);
                let cols: Vec<(usize, f64)> = (0..2)
                    .filter(|&q| self.col_of[g.tilt.index + q] != usize::MAX)
                    .map(|q| (self.col_of[g.tilt.index + q], d[c][q] * w))
                    .collect();
                self.add_row(&cols, res[c] * w);
            }
        }
    }

    /// The gyro model's mean rates and its priors (docs/model.md §8); with a gyro bias walk the
    /// means are weighted with its covariance across the session (§11.6).
    fn add_gyro_block(&mut self, blk: &GyroBlock, t: &[f64]) {
        let dense = gyro_drift::add_means(self, blk, t);
        for g in if dense { &[][..] } else { &blk.means[..] } {
            let jac = g.jacobian(t, blk.base);
            let res = g.whitened_residual(t, blk.base);
            self.chi2 += res.iter().map(|v| v * v).sum::<f64>();
            for a in 0..3 {
                let cols: Vec<(usize, f64)> = jac
                    .iter()
                    .filter(|(q, _)| self.col_of[*q] != usize::MAX)
                    .map(|(q, d)| (self.col_of[*q], (0..3).map(|r| g.whiten[a][r] * d[r]).sum()))
                    .collect();
                self.add_row(&cols, res[a]);
            }
        }
        // Priors: each G entry about the identity (weak), the table's rate scale about 0.
        let mut priors: Vec<(usize, f64, f64)> = (0..9)
            .map(|k| {
                let q = gyro::idx_g(blk.base, k / 3, k % 3);
                (q, if k % 4 == 0 { 1.0 } else { 0.0 }, gyro::G_PRIOR_SIGMA)
            })
            .collect();
        priors.push((gyro::idx_rate(blk.base), 0.0, blk.rate_sigma_rel));
        for (q, mean, sig) in priors {
            if self.col_of[q] == usize::MAX {
                continue;
            }
            let r = (mean - t[q]) / sig;
            self.chi2 += r * r;
            let col = self.col_of[q];
            self.n[(col, col)] += 1.0 / (sig * sig);
            self.b[col] += r / sig;
        }
    }

    /// The mounts' attitude priors, which pull each free tilt towards the nominal up.
    fn add_mount_priors(&mut self, mounts: &[Mount], t: &[f64]) {
        for m in mounts {
            let Some(sig) = m.prior_rad.filter(|s| *s > 0.0) else {
                continue;
            };
            for c in 0..2 {
                let q = m.geometry.index + c;
                if self.col_of[q] == usize::MAX {
                    continue;
                }
                self.chi2 += (t[q] / sig).powi(2);
                let col = self.col_of[q];
                self.n[(col, col)] += 1.0 / (sig * sig);
                self.b[col] -= t[q] / (sig * sig);
            }
        }
    }

    /// A prior of 1σ = `sig` about 0 on every free lever-arm column (not counted in χ²); `first`
    /// is each column's first θ entry ([`Columns::first`]).
    fn add_lever_prior(&mut self, sig: f64, t: &[f64], first: &[usize]) {
        for (c, &q) in first.iter().enumerate() {
            if is_lever(q) {
                self.n[(c, c)] += 1.0 / (sig * sig);
                self.b[c] -= t[q] / (sig * sig);
            }
        }
    }
}

/// The normal equations' columns: which column of `n` and `b` each θ entry moves with.
///
/// A free entry has a column of its own, except for a single-package unit's lever arms
/// (docs/model.md §4.7): `r_2[j]` and `r_3[j]` move with `r_1[j]`, which is the exact constraint
/// `r_1 = r_2 = r_3 = r` written as θ = T φ. A row's entries that share a column add up in it
/// ([`NormalSystem::add_row`] sums every pair), so the normal matrix is `Tᵀ Jᵀ Σ⁻¹ J T` and the
/// covariance `T (Tᵀ Jᵀ Σ⁻¹ J T)⁻¹ Tᵀ`: the 1σ of `r` from three parameters, given to each `r_i`.
/// In a tied problem `r_1[j]`'s `free` entry speaks for the three.
#[derive(Clone, Debug)]
pub(crate) struct Columns {
    /// Column of each θ entry (`usize::MAX`: fixed).
    col_of: Vec<usize>,
    /// Each column's first θ entry (the one whose step and value stand for the column).
    first: Vec<usize>,
}

impl Columns {
    pub(crate) fn new(free: &[bool], single_package: bool) -> Columns {
        use super::model::idx_r;
        let mut col_of = vec![usize::MAX; free.len()];
        let mut first = Vec::new();
        for q in 0..free.len() {
            let tied = single_package && is_lever(q) && q >= idx_r(1, 0);
            if tied {
                // r_i[j] with i > 0: the column of r_1[j], when that one is free.
                col_of[q] = col_of[idx_r(0, (q % 7) - 4)];
            } else if free[q] {
                col_of[q] = first.len();
                first.push(q);
            }
        }
        Columns { col_of, first }
    }

    /// Number of columns (the fitted parameters).
    pub(crate) fn len(&self) -> usize {
        self.first.len()
    }

    /// θ moved by the step `s` (one value per column) times `h`.
    fn stepped(&self, t: &[f64], s: &DVector<f64>, h: f64) -> Vec<f64> {
        let mut out = t.to_vec();
        for (q, &c) in self.col_of.iter().enumerate() {
            if c != usize::MAX {
                out[q] = t[q] + h * s[c];
            }
        }
        out
    }

    /// θ with every tied entry set to its column's first entry (a start that satisfies the tie).
    fn tie(&self, t: &mut [f64]) {
        for (q, &c) in self.col_of.iter().enumerate() {
            if c != usize::MAX {
                t[q] = t[self.first[c]];
            }
        }
    }
}

/// Covariance (zeros for fixed entries) of θ at `t`, or `None` if singular.
pub(crate) fn covariance(
    p: &Problem,
    t: &[f64],
    free: &[bool],
    prior_r_m: Option<f64>,
) -> Option<DMatrix<f64>> {
    let cols = Columns::new(free, p.single_package);
    let (n, _, _) = normal_equations(p, t, &cols, prior_r_m);
    // With a prior the matrix is positive definite by construction; without, reject rank deficiency.
    let min_eigen = if prior_r_m.is_some() { 0.0 } else { 1e-14 };
    let inv = invert_spd(&n, min_eigen)?;
    let np = t.len();
    // T (Tᵀ N T)⁻¹ Tᵀ: entries sharing a column share its variance and are fully correlated.
    Some(DMatrix::from_fn(np, np, |q, r| {
        match (cols.col_of[q], cols.col_of[r]) {
            (a, b) if a != usize::MAX && b != usize::MAX => inv[(a, b)],
            _ => 0.0,
        }
    }))
}

/// One Gauss–Newton step over the free columns, or `None` when the normal equations are singular.
fn step(n: &DMatrix<f64>, b: &DVector<f64>) -> Option<DVector<f64>> {
    let d: Vec<f64> = (0..n.nrows())
        .map(|i| 1.0 / n[(i, i)].max(1e-300).sqrt())
        .collect();
    let scaled = DMatrix::from_fn(n.nrows(), n.ncols(), |i, j| n[(i, j)] * d[i] * d[j]);
    let chol = scaled.cholesky()?;
    let bs = DVector::from_fn(b.len(), |i, _| b[i] * d[i]);
    let x = chol.solve(&bs);
    let s = DVector::from_fn(b.len(), |i, _| x[i] * d[i]);
    s.iter().all(|v| v.is_finite()).then_some(s)
}

/// Gauss–Newton from `t0`, estimating the entries marked in `free`.
pub fn fit(
    p: &Problem,
    t0: Vec<f64>,
    free: Vec<bool>,
    what: &'static str,
) -> Result<Fit, EstimateError> {
    let cols = Columns::new(&free, p.single_package);
    let mut t = t0;
    cols.tie(&mut t);
    for _ in 0..60 {
        let (n, b, chi2) = normal_equations(p, &t, &cols, None);
        let s = step(&n, &b).ok_or(EstimateError::Singular { what })?;
        let mut h = 1.0;
        let mut trial = cols.stepped(&t, &s, h);
        for _ in 0..12 {
            if p.chi2(&trial, &free) <= chi2 * (1.0 + 1e-12) + 1e-9 {
                break;
            }
            h *= 0.5;
            trial = cols.stepped(&t, &s, h);
        }
        let mut rel = 0.0f64;
        for (c, &q) in cols.first.iter().enumerate() {
            let scale = if is_lever(q) || q >= NI {
                1e-3
            } else {
                t[q].abs().max(1e-9)
            };
            rel = rel.max((h * s[c]).abs() / scale);
        }
        t = trial;
        if rel < 1e-10 {
            break;
        }
    }
    let cov = covariance(p, &t, &free, None).ok_or(EstimateError::Singular { what })?;
    let chi2 = p.chi2(&t, &free);
    Ok(Fit {
        dof: p.observations(&free) - cols.len() as i64,
        theta: t,
        cov,
        chi2,
        free,
    })
}

/// Lever-arm components the segments cannot determine at all (1σ above `limit_m` even with a weak
/// 1 m prior), removed one at a time, worst first: the remaining ones are estimable. Each one
/// removed is also set to 0 in `t`, the fit's start.
///
/// A fixed entry keeps its start value in every term of the model (`E r_i` holds the ω̇ term
/// `[ω̇×] r_i` beside the centripetal one, docs/model.md §4.4, §4.6), and the start of a later
/// joint pass is the previous pass's estimate, in which the component may still have been free:
/// without the reset a component reported "fixed at 0" would enter the fit, and the report, at
/// that value.
pub(crate) fn structurally_unobservable(
    p: &Problem,
    t: &mut [f64],
    free: &mut [bool],
    limit_m: f64,
) -> Vec<(usize, usize)> {
    use super::model::idx_r;
    let mut fixed = Vec::new();
    while let Some(cov) = covariance(p, t, free, Some(1.0)) {
        // A single-package unit's component j is one column: r_1[j] speaks for the three.
        let rows = if p.single_package { 1 } else { 3 };
        let worst = (0..rows)
            .flat_map(|i| (0..3).map(move |j| (i, j)))
            .filter(|&(i, j)| free[idx_r(i, j)])
            .map(|(i, j)| ((i, j), cov[(idx_r(i, j), idx_r(i, j))].sqrt()))
            .max_by(|a, b| a.1.total_cmp(&b.1));
        match worst {
            Some(((i, j), s)) if s > limit_m => {
                let tied = if p.single_package { 0..3 } else { i..i + 1 };
                for i in tied {
                    free[idx_r(i, j)] = false;
                    t[idx_r(i, j)] = 0.0;
                    fixed.push((i, j));
                }
            }
            _ => break,
        }
    }
    fixed
}
