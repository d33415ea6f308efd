//! The paper's own lever-arm identification (eq. 21–24), implemented as published, for comparison.
//!
//! With the x, y and z axes up in turn and the table spinning at a constant ω0, the bias- and
//! scale-corrected output of accelerometer `i`, minus its static value `f_i0 = g a_i·up`, is
//! (eq. 21–23, `W = −ω0² (I − n nᵀ)`):
//!
//! ```text
//! D_i^x = −ω0² (a_iy r_iy + a_iz r_iz),  D_i^y = −ω0² (a_ix r_ix + a_iz r_iz),  D_i^z = −ω0² (a_ix r_ix + a_iy r_iy)
//! ```
//!
//! and eq. 24 solves `r_ix = (D^x − D^y − D^z) / (2 ω0² cos θ_ix)` and cyclically. This module does
//! exactly that (the sign convention checks out against eq. 21–23), with the deviations and pitfalls:
//!
//! - **Division by the small cosines.** For the across-axis components (`j ≠ i`) `cos θ_ij` is ~0.01,
//!   so the noise of the three differences is amplified ~100× (`docs/model.md` §4.4); the paper tilts the
//!   table to escape it. We do not tilt: the point is to show the effect.
//! - `f_i0` is the static fit's prediction `g·a_i·up` (the paper's eq. 2), not a separate static
//!   segment; `a_i`, `k_i`, `u0_i` come from our static least squares (the exact, non-orthogonal `A`).
//! - ω0 is the plan's nominal table rate (as in the paper), not the gyro's: a table rate error goes
//!   straight into `r` (the joint method uses the measured `E[ω ωᵀ]`).
//! - The table centre is assumed on the spin axis (p = 0), as in the paper.
//! - Several rates (100/150/200 °/s) are combined by an inverse-variance weighted mean (the paper
//!   says "mean values"); only +x, +y, +z-up constant-rate segments are used.

use super::model::{self, idx_r, SegModel, NI as NP};
use super::note::Note;
use super::{solve, EstimateError, SegmentKind, SessionSeg};
use nalgebra::DMatrix;
use recording::session::Plan;
use shared::linalg;
use std::collections::BTreeMap;

pub(crate) struct PaperResult {
    pub theta: Vec<f64>,
    pub cov: DMatrix<f64>,
    pub notes: Vec<Note>,
}

/// Eq. 24 for the static parameters in `t` (its lever arms ignored): the inverse-variance weighted
/// lever arms over the rate groups, and their variance from the spin segments' noise.
fn solve_eq24(
    t: &[f64],
    g: f64,
    trios: &[(f64, [usize; 3])],
    models: &[SegModel],
) -> ([[f64; 3]; 3], [[f64; 3]; 3]) {
    let m = model::m_of(t);
    let u0 = model::u0_of(t);
    let k: [f64; 3] = core::array::from_fn(|i| linalg::norm(&m[i]));
    let a: [[f64; 3]; 3] = core::array::from_fn(|i| m[i].map(|v| v / k[i]));
    let mut num = [[0.0; 3]; 3];
    let mut wsum = [[0.0; 3]; 3];
    for (w0, q) in trios {
        for i in 0..3 {
            // D^c = f_i^c − f_i0^c (m/s²) and its variance.
            let d: [f64; 3] =
                core::array::from_fn(|c| g * ((models[q[c]].mean_u[i] - u0[i]) / k[i] - a[i][c]));
            let var: f64 = (0..3)
                .map(|c| g * g * models[q[c]].se_cov[i][i] / (k[i] * k[i]))
                .sum();
            for j in 0..3 {
                let (j1, j2) = ((j + 1) % 3, (j + 2) % 3);
                let n = d[j] - d[j1] - d[j2];
                let den = 2.0 * w0 * w0 * a[i][j];
                let vr = var / (den * den);
                num[i][j] += n / den / vr;
                wsum[i][j] += 1.0 / vr;
            }
        }
    }
    let r = core::array::from_fn(|i| core::array::from_fn(|j| num[i][j] / wsum[i][j]));
    let v = core::array::from_fn(|i| core::array::from_fn(|j| 1.0 / wsum[i][j]));
    (r, v)
}

/// The paper's lever arms (eq. 24) on top of the static fit, with their covariance: the spin
/// segments' noise plus the static fit's own errors carried through.
pub(crate) fn eq24(
    plan: &Plan,
    segs: &[SessionSeg],
    models: &[SegModel],
    static_fit: &solve::Fit,
) -> Result<PaperResult, EstimateError> {
    let m = model::m_of(&static_fit.theta);
    let k: [f64; 3] = core::array::from_fn(|i| linalg::norm(&m[i]));
    let a: [[f64; 3]; 3] = core::array::from_fn(|i| m[i].map(|v| v / k[i]));
    let g = plan.gravity_m_s2;
    let trios = rate_trios(plan, segs, models);
    let rates_used: Vec<f64> = trios.iter().map(|(w, _)| w.to_degrees()).collect();
    if trios.is_empty() {
        return Err(EstimateError::PlanCannotObserve {
            parameters: (0..9)
                .map(|p| format!("r{}{}", p / 3 + 1, shared::params::axis_name(p % 3)))
                .collect(),
            hint: "the paper's eq. 24 needs constant-rate segments with +x, +y and +z up at a common rate"
                .into(),
        });
    }
    let (r, var_noise) = solve_eq24(&static_fit.theta, g, &trios, models);
    let jac = static_jacobian(&static_fit.theta, &k, g, &trios, models);
    let (theta, cov) = with_lever_arms(static_fit, &r, &var_noise, &jac);
    let worst_cos = smallest_cross_cosine(&a);
    let notes = vec![Note::PaperEq24 {
        rates_dps: rates_used,
        worst_cos,
    }];
    Ok(PaperResult { theta, cov, notes })
}

/// The +x-, +y- and +z-up constant-rate segments (model indices) for each rate that has all three,
/// with the rate (rad/s), in increasing rate; the first segment of each attitude and rate is used.
fn rate_trios(plan: &Plan, segs: &[SessionSeg], models: &[SegModel]) -> Vec<(f64, [usize; 3])> {
    // rate (0.01 °/s) → model index of the x-, y-, z-up segment.
    let mut groups: BTreeMap<i64, [Option<usize>; 3]> = BTreeMap::new();
    let cos1 = 1f64.to_radians().cos();
    for (q, md) in models.iter().enumerate() {
        let s = &segs[md.seg];
        if s.kind != SegmentKind::ConstantRate {
            continue;
        }
        let sp = &plan.segments[s.plan_idx];
        let Some(axis) = (0..3).find(|&c| sp.up_b[c] > cos1 && !sp.is_free()) else {
            continue;
        };
        let key = (sp.rate_deg_s.abs() * 100.0).round() as i64;
        let e = groups.entry(key).or_insert([None; 3]);
        if e[axis].is_none() {
            e[axis] = Some(q);
        }
    }
    groups
        .iter()
        .filter_map(|(key, t)| match *t {
            [Some(x), Some(y), Some(z)] => Some(((*key as f64 / 100.0).to_radians(), [x, y, z])),
            _ => None,
        })
        .collect()
}

/// ∂r_ij/∂θ_p of eq. 24 by central differences over `M` and `u0` (eq. 24 sees them through u0, k
/// and a), zero for the lever arms; `k`, the static fit's scale factors, set the steps.
fn static_jacobian(
    theta: &[f64],
    k: &[f64; 3],
    g: f64,
    trios: &[(f64, [usize; 3])],
    models: &[SegModel],
) -> [[[f64; NP]; 3]; 3] {
    let mut jac = [[[0.0; NP]; 3]; 3];
    for p in 0..NP {
        if p % 7 >= 4 {
            continue;
        }
        let h = 1e-6 * theta[p].abs().max(1e-3 * k[p / 7]);
        let mut tp = theta.to_vec();
        let mut tm = theta.to_vec();
        tp[p] += h;
        tm[p] -= h;
        let (rp, _) = solve_eq24(&tp, g, trios, models);
        let (rm, _) = solve_eq24(&tm, g, trios, models);
        for i in 0..3 {
            for j in 0..3 {
                jac[i][j][p] = (rp[i][j] - rm[i][j]) / (2.0 * h);
            }
        }
    }
    jac
}

/// The static fit's θ and covariance with the lever arms `r` put in: their covariance is the static
/// fit's propagated through `jac` plus the spin noise `var_noise`, and their cross-covariance with
/// the static parameters is propagated the same way.
fn with_lever_arms(
    static_fit: &solve::Fit,
    r: &[[f64; 3]; 3],
    var_noise: &[[f64; 3]; 3],
    jac: &[[[f64; NP]; 3]; 3],
) -> (Vec<f64>, DMatrix<f64>) {
    let mut theta = static_fit.theta.clone();
    let mut cov = static_fit.cov.clone();
    let rows: Vec<(usize, usize)> = (0..9).map(|q| (q / 3, q % 3)).collect();
    for &(i, j) in &rows {
        theta[idx_r(i, j)] = r[i][j];
    }
    for &(i, j) in &rows {
        for &(i2, j2) in &rows {
            let mut c = 0.0;
            for p in 0..NP {
                for q in 0..NP {
                    c += jac[i][j][p] * static_fit.cov[(p, q)] * jac[i2][j2][q];
                }
            }
            if (i, j) == (i2, j2) {
                c += var_noise[i][j];
            }
            cov[(idx_r(i, j), idx_r(i2, j2))] = c;
        }
        // Cross-covariance with the static parameters.
        for p in 0..NP {
            if p % 7 < 4 {
                let c: f64 = (0..NP).map(|q| jac[i][j][q] * static_fit.cov[(q, p)]).sum();
                cov[(idx_r(i, j), p)] = c;
                cov[(p, idx_r(i, j))] = c;
            }
        }
    }
    (theta, cov)
}

/// The smallest |cos θ_ij| over the across-axis directions (`j ≠ i`): eq. 24's worst divisor.
fn smallest_cross_cosine(a: &[[f64; 3]; 3]) -> f64 {
    a.iter()
        .enumerate()
        .flat_map(|(i, row)| {
            row.iter()
                .enumerate()
                .filter(move |(j, _)| *j != i)
                .map(|(_, c)| c.abs())
        })
        .fold(f64::INFINITY, f64::min)
}
