//! The mean-output model of one segment, and the fit's parameter layout.
//!
//! For a segment with specific force `f_O` at the origin and mean lever matrix
//! `E[W] = [E ω̇ ×] + E[ω ωᵀ] − tr(E[ω ωᵀ]) I` (paper eq. 11; the model is linear in `W`, so the mean
//! of the outputs is the model at the mean `W`), accelerometer `i` reads on average
//!
//! ```text
//! ū_i = m_i · (F + E r_i) + u0_i,      F = f_O / g,  E = E[W] / g,  f_O = g·up − E[W] p
//! ```
//!
//! with `m_i` = row `i` of `M = K·A`, `r_i` the lever arm and `p` the table centre (`docs/model.md` §4.5).
//! `up` is the mount's true up: its nominal one tilted by two small unknowns perpendicular to it,
//! shared by every segment of the mount (docs/model.md §7).
//!
//! The parameter vector θ: the 21 intrinsic entries first, 7 per accelerometer (`m_i` (3), `u0_i`,
//! `r_i` (3)), then two tilt entries per mount ([`idx_tilt`]).

use shared::linalg::{self, RowMajor3};

/// Number of intrinsic parameters (`M`, `u0`, lever arms).
pub(crate) const NI: usize = 21;

/// Index of `M[i][j]` in θ.
pub const fn idx_m(i: usize, j: usize) -> usize {
    7 * i + j
}

/// Index of `u0_i` in θ.
pub const fn idx_u0(i: usize) -> usize {
    7 * i + 3
}

/// Index of `r_i[j]` in θ.
pub const fn idx_r(i: usize, j: usize) -> usize {
    7 * i + 4 + j
}

/// Index of mount `k`'s tilt about its basis vector `c` (0, 1) in θ, radians.
pub const fn idx_tilt(k: usize, c: usize) -> usize {
    NI + 2 * k + c
}

/// Whether θ's entry `p` is a lever-arm component.
pub const fn is_lever(p: usize) -> bool {
    p < NI && p % 7 >= 4
}

/// Human name of θ's entry `k` (`mounts` names the tilt entries).
pub(crate) fn theta_label(k: usize, mounts: &[Mount]) -> String {
    if k >= NI {
        let m = (k - NI) / 2;
        let name = mounts.get(m).map_or("?", |m| m.name.as_str());
        return format!("tilt{} {name}", (k - NI) % 2 + 1);
    }
    let i = k / 7;
    let a = shared::params::axis_name(i);
    match k % 7 {
        j @ 0..=2 => format!("M[{a}][{}]", shared::params::axis_name(j)),
        3 => format!("u0_{a}"),
        j => format!("r{}{}", i + 1, shared::params::axis_name(j - 4)),
    }
}

/// θ from the fitted form and lever arms, with `n_mounts` zero tilts.
#[cfg(test)]
pub(crate) fn theta_from(m: &RowMajor3, u0: &[f64; 3], r: &RowMajor3, n_mounts: usize) -> Vec<f64> {
    let mut t = vec![0.0; NI + 2 * n_mounts];
    for i in 0..3 {
        for j in 0..3 {
            t[idx_m(i, j)] = m[i][j];
            t[idx_r(i, j)] = r[i][j];
        }
        t[idx_u0(i)] = u0[i];
    }
    t
}

/// `M` of θ.
pub(crate) fn m_of(t: &[f64]) -> RowMajor3 {
    core::array::from_fn(|i| core::array::from_fn(|j| t[idx_m(i, j)]))
}

/// `u0` of θ.
pub(crate) fn u0_of(t: &[f64]) -> [f64; 3] {
    core::array::from_fn(|i| t[idx_u0(i)])
}

/// Lever arms of θ.
pub(crate) fn r_of(t: &[f64]) -> RowMajor3 {
    core::array::from_fn(|i| core::array::from_fn(|j| t[idx_r(i, j)]))
}

/// Two unit vectors perpendicular to `up` and to each other: the axes of a mount's tilt unknowns.
pub(crate) fn tilt_basis(up: &[f64; 3]) -> [[f64; 3]; 2] {
    let pick = if up[0].abs() < 0.9 {
        [1.0, 0.0, 0.0]
    } else {
        [0.0, 1.0, 0.0]
    };
    let e1 = linalg::cross(up, &pick);
    let e1 = e1.map(|c| c / linalg::norm(&e1));
    [e1, linalg::cross(up, &e1)]
}

/// A mount's nominal up and the axes of its tilt: the true up is `normalise(up + α e₁ + β e₂)`, so
/// (α, β) are the tilt angles (radians, to first order) about `e₂` and `−e₁`.
#[derive(Clone, Copy, Debug, PartialEq)]
pub(crate) struct TiltGeometry {
    /// Nominal up, body axes (unit).
    pub up_nominal_b: [f64; 3],
    /// Tilt axes ([`tilt_basis`]).
    pub basis: [[f64; 3]; 2],
    /// θ index of α (β follows).
    pub index: usize,
}

impl TiltGeometry {
    /// Geometry of mount `k` about `up`.
    pub fn new(up: [f64; 3], k: usize) -> TiltGeometry {
        let n = linalg::norm(&up);
        let up = up.map(|c| c / n);
        TiltGeometry {
            up_nominal_b: up,
            basis: tilt_basis(&up),
            index: idx_tilt(k, 0),
        }
    }

    fn tilt(&self, t: &[f64]) -> [f64; 2] {
        [t[self.index], t[self.index + 1]]
    }

    /// The true up at θ, and its derivatives by α and β.
    pub(crate) fn up_and_derivatives(&self, t: &[f64]) -> ([f64; 3], [[f64; 3]; 2]) {
        let [a, b] = self.tilt(t);
        let e = &self.basis;
        let v: [f64; 3] =
            core::array::from_fn(|j| self.up_nominal_b[j] + a * e[0][j] + b * e[1][j]);
        let n = linalg::norm(&v);
        let up = v.map(|c| c / n);
        let d = core::array::from_fn(|c| {
            let p = linalg::dot(&up, &e[c]);
            core::array::from_fn(|j| (e[c][j] - up[j] * p) / n)
        });
        (up, d)
    }

    /// The true up at θ.
    pub fn up(&self, t: &[f64]) -> [f64; 3] {
        self.up_and_derivatives(t).0
    }
}

/// A mount: the segments sharing one attitude on the fixture (or one hand-held position).
#[derive(Clone, Debug, PartialEq)]
pub(crate) struct Mount {
    /// Name (the plan's `mount`, or derived, see `SegmentPlan::mount_name`).
    pub name: String,
    /// Geometry of its tilt unknowns.
    pub geometry: TiltGeometry,
    /// Prior 1σ of each tilt, radians; `None`: free (no prior); 0: exact (tilt fixed at 0).
    pub prior_rad: Option<f64>,
    /// Whether the plan gave an up (for a free mount, the rough guess).
    pub up_given: bool,
    /// Whether any of its segments spins.
    pub spins: bool,
}

/// `E[W]` from a segment's gyro statistics, rad/s², optionally without the ω̇ term (`docs/model.md` §4.6)
/// and with the gyro's own noise covariance removed from `E[ω ωᵀ]`.
pub(crate) fn mean_lever_matrix(
    mean_wwt: &RowMajor3,
    wdot: &[f64; 3],
    gyro_noise_cov: &RowMajor3,
    use_omega_dot: bool,
) -> RowMajor3 {
    let s: RowMajor3 =
        core::array::from_fn(|i| core::array::from_fn(|j| mean_wwt[i][j] - gyro_noise_cov[i][j]));
    let tr = s[0][0] + s[1][1] + s[2][2];
    let wd = if use_omega_dot { *wdot } else { [0.0; 3] };
    // [ω̇×] = [[0, −ω̇z, ω̇y], [ω̇z, 0, −ω̇x], [−ω̇y, ω̇x, 0]]
    let skew = [
        [0.0, -wd[2], wd[1]],
        [wd[2], 0.0, -wd[0]],
        [-wd[1], wd[0], 0.0],
    ];
    core::array::from_fn(|i| {
        core::array::from_fn(|j| skew[i][j] + s[i][j] - if i == j { tr } else { 0.0 })
    })
}

/// One segment as the fit sees it.
#[derive(Clone, Debug)]
pub(crate) struct SegModel {
    /// Index into the session's segment list.
    pub seg: usize,
    /// The mount's attitude unknowns.
    pub tilt: TiltGeometry,
    /// `−E[W] p / g`: the table centre's part of `F`, in g.
    pub centre_g: [f64; 3],
    /// `E = E[W] / g`, 1/m (so that `E r` is in g).
    pub e: RowMajor3,
    /// Mean outputs.
    pub mean_u: [f64; 3],
    /// Covariance of the mean outputs (standard error²), output unit².
    pub se_cov: RowMajor3,
    /// `L⁻¹` with `se_cov = L Lᵀ`: multiplies residuals into unit-variance ones.
    pub whiten: RowMajor3,
    /// First and last sample time, s: where the segment sits on the bias random walk
    /// (docs/model.md §11); `[0, 0]` until `build::build_models` sets it.
    pub span_s: [f64; 2],
}

impl SegModel {
    /// Builds a segment model; `None` when the covariance is not positive definite.
    pub fn new(
        seg: usize,
        tilt: TiltGeometry,
        centre_g: [f64; 3],
        e: RowMajor3,
        mean_u: [f64; 3],
        se_cov: RowMajor3,
    ) -> Option<SegModel> {
        let c = linalg::to_na(&se_cov);
        let whiten = match c.cholesky() {
            Some(ch) => {
                let l = ch.l();
                l.try_inverse().map(|li| linalg::from_na(&li))?
            }
            None => {
                // Fall back to the diagonal (correlations lost, weights kept).
                let mut w = [[0.0; 3]; 3];
                for i in 0..3 {
                    if se_cov[i][i] <= 0.0 || !se_cov[i][i].is_finite() {
                        return None;
                    }
                    w[i][i] = 1.0 / se_cov[i][i].sqrt();
                }
                w
            }
        };
        Some(SegModel {
            seg,
            tilt,
            centre_g,
            e,
            mean_u,
            se_cov,
            whiten,
            span_s: [0.0; 2],
        })
    }

    /// `F = up + centre term`, in g, at θ.
    pub fn f(&self, t: &[f64]) -> [f64; 3] {
        let up = self.tilt.up(t);
        core::array::from_fn(|j| up[j] + self.centre_g[j])
    }

    /// The specific force each sensing point sees, in g: `F + E r_i`.
    fn force_at(&self, f: &[f64; 3], r_i: &[f64; 3]) -> [f64; 3] {
        let er = linalg::mat_vec(&self.e, r_i);
        core::array::from_fn(|j| f[j] + er[j])
    }

    /// Predicted mean outputs.
    pub fn predict(&self, t: &[f64]) -> [f64; 3] {
        let m = m_of(t);
        let r = r_of(t);
        let f = self.f(t);
        core::array::from_fn(|i| linalg::dot(&m[i], &self.force_at(&f, &r[i])) + t[idx_u0(i)])
    }

    /// Jacobian of the predicted outputs as (θ index, ∂ū/∂θ) pairs: the nonzero columns only.
    pub(crate) fn jacobian(&self, t: &[f64]) -> Vec<(usize, [f64; 3])> {
        let m = m_of(t);
        let r = r_of(t);
        let (up, dup) = self.tilt.up_and_derivatives(t);
        let f: [f64; 3] = core::array::from_fn(|j| up[j] + self.centre_g[j]);
        let mut cols = Vec::with_capacity(NI + 2);
        for i in 0..3 {
            let fi = self.force_at(&f, &r[i]);
            let unit =
                |v: f64| -> [f64; 3] { core::array::from_fn(|q| if q == i { v } else { 0.0 }) };
            for j in 0..3 {
                cols.push((idx_m(i, j), unit(fi[j])));
                // ∂(m·E r)/∂r_j = (Eᵀ m)_j
                let d = self.e[0][j] * m[i][0] + self.e[1][j] * m[i][1] + self.e[2][j] * m[i][2];
                cols.push((idx_r(i, j), unit(d)));
            }
            cols.push((idx_u0(i), unit(1.0)));
        }
        for (c, d) in dup.iter().enumerate() {
            cols.push((
                self.tilt.index + c,
                core::array::from_fn(|i| linalg::dot(&m[i], d)),
            ));
        }
        cols
    }

    /// Whitened residual `L⁻¹ (ū − prediction)`.
    pub(crate) fn whitened_residual(&self, t: &[f64]) -> [f64; 3] {
        let p = self.predict(t);
        let res: [f64; 3] = core::array::from_fn(|i| self.mean_u[i] - p[i]);
        linalg::mat_vec(&self.whiten, &res)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use shared::forward::{ForwardModel, TableState};

    #[test]
    fn model_matches_the_shared_forward_model() {
        let cal = shared::params::PAPER_UNIT;
        let fm = ForwardModel::new(&cal).unwrap();
        let g = cal.gravity_m_s2;
        let st = TableState {
            up_b: [0.6, 0.0, 0.8],
            rate_rad_s: 3.0,
            accel_rad_s2: 1.5,
            centre_m: [0.01, -0.02, 0.005],
        };
        let motion = st.motion(g);
        let u = fm.outputs(&motion).raw;
        let w = motion.omega.rad_s;
        let wwt: RowMajor3 = core::array::from_fn(|i| core::array::from_fn(|j| w[i] * w[j]));
        let ew = mean_lever_matrix(&wwt, &motion.omega_dot.rad_s2, &[[0.0; 3]; 3], true);
        let wp = linalg::mat_vec(&ew, &st.centre_m);
        let centre = core::array::from_fn(|j| -wp[j] / g);
        let e = ew.map(|row| row.map(|v| v / g));
        // The nominal up is 2° away from the true one; the tilt entries of θ bring it back.
        let nominal = [0.6, 0.03, 0.8];
        let geom = TiltGeometry::new(nominal, 1);
        let seg = SegModel::new(
            0,
            geom,
            centre,
            e,
            u,
            [[1.0, 0.0, 0.0], [0.0, 1.0, 0.0], [0.0, 0.0, 1.0]],
        )
        .unwrap();
        let (fitted, _) = cal.statics.to_fitted().unwrap();
        let mut t = theta_from(
            &fitted.m_out_per_g,
            &fitted.zero_bias_out,
            &cal.lever_arms.r_m,
            2,
        );
        // Solve the tilt for the true up: up_true ∝ nominal + α e1 + β e2.
        let n = linalg::norm(&nominal);
        let nom = nominal.map(|c| c / n);
        let up = st.up_b;
        let s = linalg::dot(&up, &nom);
        t[idx_tilt(1, 0)] = linalg::dot(&up, &geom.basis[0]) / s;
        t[idx_tilt(1, 1)] = linalg::dot(&up, &geom.basis[1]) / s;
        let p = seg.predict(&t);
        for i in 0..3 {
            assert!((p[i] - u[i]).abs() < 1e-12, "{p:?} vs {u:?}");
        }
        // Jacobian by central differences, every column (absent ones are zero).
        let cols = seg.jacobian(&t);
        for k in 0..t.len() {
            let h = 1e-6;
            let mut tp = t.clone();
            let mut tm = t.clone();
            tp[k] += h;
            tm[k] -= h;
            let (a, b) = (seg.predict(&tp), seg.predict(&tm));
            let col = cols
                .iter()
                .filter(|(p, _)| *p == k)
                .fold([0.0; 3], |acc, (_, d)| {
                    core::array::from_fn(|i| acc[i] + d[i])
                });
            for i in 0..3 {
                let d = (a[i] - b[i]) / (2.0 * h);
                assert!((d - col[i]).abs() < 1e-6, "{} {i}", theta_label(k, &[]));
            }
        }
    }
}
