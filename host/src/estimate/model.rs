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
//! with `m_i` = row `i` of `M = K·A`, `r_i` the lever arm and `p` the table centre (`docs/model.md` §5).
//! The parameter vector θ has 21 entries, 7 per accelerometer: `m_i` (3), `u0_i`, `r_i` (3).

use shared::linalg::{self, RowMajor3};

/// Number of fitted parameters.
pub const NP: usize = 21;

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

/// Human name of θ's entry `k`.
pub fn theta_label(k: usize) -> String {
    let i = k / 7;
    let a = shared::params::axis_name(i);
    match k % 7 {
        j @ 0..=2 => format!("M[{a}][{}]", shared::params::axis_name(j)),
        3 => format!("u0_{a}"),
        j => format!("r{}{}", i + 1, shared::params::axis_name(j - 4)),
    }
}

/// θ from the fitted form and lever arms.
pub fn theta_from(m: &RowMajor3, u0: &[f64; 3], r: &RowMajor3) -> [f64; NP] {
    let mut t = [0.0; NP];
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
pub fn m_of(t: &[f64; NP]) -> RowMajor3 {
    core::array::from_fn(|i| core::array::from_fn(|j| t[idx_m(i, j)]))
}

/// `u0` of θ.
pub fn u0_of(t: &[f64; NP]) -> [f64; 3] {
    core::array::from_fn(|i| t[idx_u0(i)])
}

/// Lever arms of θ.
pub fn r_of(t: &[f64; NP]) -> RowMajor3 {
    core::array::from_fn(|i| core::array::from_fn(|j| t[idx_r(i, j)]))
}

/// `E[W]` from a segment's gyro statistics, rad/s², optionally without the ω̇ term (`docs/model.md` §6)
/// and with the gyro's own noise covariance removed from `E[ω ωᵀ]`.
pub fn mean_lever_matrix(
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
pub struct SegModel {
    /// Index into the session's segment list.
    pub seg: usize,
    /// `F = f_O / g` (plan's attitude, table centre and the measured `E[W]`), in g.
    pub f: [f64; 3],
    /// `E = E[W] / g`, 1/m (so that `E r` is in g).
    pub e: RowMajor3,
    /// Mean outputs.
    pub mean_u: [f64; 3],
    /// Covariance of the mean outputs (standard error²), output unit².
    pub se_cov: RowMajor3,
    /// `L⁻¹` with `se_cov = L Lᵀ`: multiplies residuals into unit-variance ones.
    pub whiten: RowMajor3,
}

impl SegModel {
    /// Builds a segment model; `None` when the covariance is not positive definite.
    pub fn new(
        seg: usize,
        f: [f64; 3],
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
            f,
            e,
            mean_u,
            se_cov,
            whiten,
        })
    }

    /// The specific force each sensing point sees, in g: `F + E r_i`.
    pub fn force_at(&self, r_i: &[f64; 3]) -> [f64; 3] {
        let er = linalg::mat_vec(&self.e, r_i);
        core::array::from_fn(|j| self.f[j] + er[j])
    }

    /// Predicted mean outputs.
    pub fn predict(&self, t: &[f64; NP]) -> [f64; 3] {
        let m = m_of(t);
        let r = r_of(t);
        core::array::from_fn(|i| linalg::dot(&m[i], &self.force_at(&r[i])) + t[idx_u0(i)])
    }

    /// Lever term `m_i · E r_i` of each output (output unit).
    pub fn lever_term(&self, t: &[f64; NP]) -> [f64; 3] {
        let m = m_of(t);
        let r = r_of(t);
        core::array::from_fn(|i| linalg::dot(&m[i], &linalg::mat_vec(&self.e, &r[i])))
    }

    /// Jacobian of the predicted outputs, 3 × 21 (row `i` nonzero only in block `i`).
    pub fn jacobian(&self, t: &[f64; NP]) -> [[f64; NP]; 3] {
        let m = m_of(t);
        let r = r_of(t);
        let mut jac = [[0.0; NP]; 3];
        for i in 0..3 {
            let fi = self.force_at(&r[i]);
            for j in 0..3 {
                jac[i][idx_m(i, j)] = fi[j];
                // ∂(m·E r)/∂r_j = (Eᵀ m)_j
                jac[i][idx_r(i, j)] =
                    self.e[0][j] * m[i][0] + self.e[1][j] * m[i][1] + self.e[2][j] * m[i][2];
            }
            jac[i][idx_u0(i)] = 1.0;
        }
        jac
    }

    /// Whitened residual `L⁻¹ (ū − prediction)`.
    pub fn whitened_residual(&self, t: &[f64; NP]) -> [f64; 3] {
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
        let f = core::array::from_fn(|j| st.up_b[j] - wp[j] / g);
        let e = ew.map(|row| row.map(|v| v / g));
        let seg = SegModel::new(
            0,
            f,
            e,
            u,
            [[1.0, 0.0, 0.0], [0.0, 1.0, 0.0], [0.0, 0.0, 1.0]],
        )
        .unwrap();
        let (fitted, _) = cal.statics.to_fitted().unwrap();
        let t = theta_from(
            &fitted.m_out_per_g,
            &fitted.zero_bias_out,
            &cal.lever_arms.r_m,
        );
        let p = seg.predict(&t);
        for i in 0..3 {
            assert!((p[i] - u[i]).abs() < 1e-12, "{p:?} vs {u:?}");
        }
        // Jacobian by central differences.
        let jac = seg.jacobian(&t);
        for k in 0..NP {
            let h = 1e-6;
            let mut tp = t;
            let mut tm = t;
            tp[k] += h;
            tm[k] -= h;
            let (a, b) = (seg.predict(&tp), seg.predict(&tm));
            for i in 0..3 {
                let d = (a[i] - b[i]) / (2.0 * h);
                assert!((d - jac[i][k]).abs() < 1e-6, "{} {i}", theta_label(k));
            }
        }
    }
}
