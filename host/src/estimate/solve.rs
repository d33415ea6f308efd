//! Weighted least squares (Gauss–Newton) over the segment models, with a free-parameter mask.
//!
//! The model is bilinear (`m_i · E r_i`), so Gauss–Newton from the static solution with `r = 0`
//! converges in a few iterations. Normal equations are solved after scaling every column to unit
//! diagonal: the parameters span ten orders of magnitude (V/g against metres).

use super::model::{idx_r, SegModel, NP};
use super::EstimateError;
use nalgebra::{DMatrix, DVector};

/// A converged fit.
#[derive(Clone, Debug)]
pub struct Fit {
    /// The estimate (fixed entries keep their starting value).
    pub theta: [f64; NP],
    /// Covariance of θ from the weights alone (not scaled by χ²), 21 × 21, zero rows for fixed entries.
    pub cov: DMatrix<f64>,
    /// Σ of whitened residuals².
    pub chi2: f64,
    /// Observations − free parameters.
    pub dof: i64,
}

/// Inverse of a symmetric positive-definite matrix via Jacobi scaling and Cholesky; `None` when it
/// is not numerically positive definite.
pub fn invert_spd(n: &DMatrix<f64>, min_eigen: f64) -> Option<DMatrix<f64>> {
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

/// Information matrix `Jᵀ Σ⁻¹ J` over the free entries (plus an optional prior of 1σ = `prior_r_m`
/// on every free lever-arm component), and `Jᵀ Σ⁻¹ res`.
fn normal_equations(
    segs: &[SegModel],
    t: &[f64; NP],
    free_idx: &[usize],
    prior_r_m: Option<f64>,
) -> (DMatrix<f64>, DVector<f64>, f64) {
    let k = free_idx.len();
    let mut n = DMatrix::<f64>::zeros(k, k);
    let mut b = DVector::<f64>::zeros(k);
    let mut chi2 = 0.0;
    for s in segs {
        let jac = s.jacobian(t);
        let res = s.whitened_residual(t);
        chi2 += res.iter().map(|v| v * v).sum::<f64>();
        // Whitened Jacobian rows: L⁻¹ J, restricted to the free columns.
        let mut wj = vec![[0.0; 3]; k];
        for (c, &p) in free_idx.iter().enumerate() {
            for a in 0..3 {
                wj[c][a] = (0..3).map(|q| s.whiten[a][q] * jac[q][p]).sum();
            }
        }
        for c1 in 0..k {
            b[c1] += (0..3).map(|a| wj[c1][a] * res[a]).sum::<f64>();
            for c2 in c1..k {
                let v: f64 = (0..3).map(|a| wj[c1][a] * wj[c2][a]).sum();
                n[(c1, c2)] += v;
            }
        }
    }
    for c1 in 0..k {
        for c2 in 0..c1 {
            n[(c1, c2)] = n[(c2, c1)];
        }
    }
    if let Some(sig) = prior_r_m {
        for (c, &p) in free_idx.iter().enumerate() {
            if (p % 7) >= 4 {
                n[(c, c)] += 1.0 / (sig * sig);
                // The prior pulls towards 0.
                b[c] -= t[p] / (sig * sig);
            }
        }
    }
    (n, b, chi2)
}

fn free_indices(free: &[bool; NP]) -> Vec<usize> {
    (0..NP).filter(|&p| free[p]).collect()
}

/// Covariance (21 × 21, zeros for fixed entries) of θ at `t`, or `None` if singular.
pub fn covariance(
    segs: &[SegModel],
    t: &[f64; NP],
    free: &[bool; NP],
    prior_r_m: Option<f64>,
) -> Option<DMatrix<f64>> {
    let idx = free_indices(free);
    let (n, _, _) = normal_equations(segs, t, &idx, prior_r_m);
    // With a prior the matrix is positive definite by construction; without, reject rank deficiency.
    let min_eigen = if prior_r_m.is_some() { 0.0 } else { 1e-14 };
    let inv = invert_spd(&n, min_eigen)?;
    let mut cov = DMatrix::<f64>::zeros(NP, NP);
    for (a, &p) in idx.iter().enumerate() {
        for (b, &q) in idx.iter().enumerate() {
            cov[(p, q)] = inv[(a, b)];
        }
    }
    Some(cov)
}

/// Gauss–Newton from `t0`, estimating the entries marked in `free`.
pub fn fit(
    segs: &[SegModel],
    t0: [f64; NP],
    free: [bool; NP],
    what: &'static str,
) -> Result<Fit, EstimateError> {
    let idx = free_indices(&free);
    let mut t = t0;
    for _ in 0..30 {
        let (n, b, _) = normal_equations(segs, &t, &idx, None);
        // Cholesky alone while iterating; the rank check runs once, on the final covariance.
        let d: Vec<f64> = (0..n.nrows())
            .map(|i| 1.0 / n[(i, i)].max(1e-300).sqrt())
            .collect();
        let scaled = DMatrix::from_fn(n.nrows(), n.ncols(), |i, j| n[(i, j)] * d[i] * d[j]);
        let chol = scaled.cholesky().ok_or(EstimateError::Singular { what })?;
        let bs = DVector::from_fn(b.len(), |i, _| b[i] * d[i]);
        let x = chol.solve(&bs);
        let step = DVector::from_fn(b.len(), |i, _| x[i] * d[i]);
        let mut rel = 0.0f64;
        for (c, &p) in idx.iter().enumerate() {
            t[p] += step[c];
            let scale = if p % 7 >= 4 {
                1e-3
            } else {
                t[p].abs().max(1e-9)
            };
            rel = rel.max(step[c].abs() / scale);
        }
        if !step.iter().all(|v| v.is_finite()) {
            return Err(EstimateError::Singular { what });
        }
        if rel < 1e-10 {
            break;
        }
    }
    let cov = covariance(segs, &t, &free, None).ok_or(EstimateError::Singular { what })?;
    let chi2 = segs
        .iter()
        .map(|s| s.whitened_residual(&t).iter().map(|v| v * v).sum::<f64>())
        .sum();
    Ok(Fit {
        theta: t,
        cov,
        chi2,
        dof: 3 * segs.len() as i64 - idx.len() as i64,
    })
}

/// Lever-arm components the segments cannot determine at all (1σ above `limit_m` even with a weak
/// 1 m prior), removed one at a time, worst first: the remaining ones are estimable.
pub fn structurally_unobservable(
    segs: &[SegModel],
    t: &[f64; NP],
    free: &mut [bool; NP],
    limit_m: f64,
) -> Vec<(usize, usize)> {
    let mut fixed = Vec::new();
    while let Some(cov) = covariance(segs, t, free, Some(1.0)) {
        let worst = (0..3)
            .flat_map(|i| (0..3).map(move |j| (i, j)))
            .filter(|&(i, j)| free[idx_r(i, j)])
            .map(|(i, j)| ((i, j), cov[(idx_r(i, j), idx_r(i, j))].sqrt()))
            .max_by(|a, b| a.1.total_cmp(&b.1));
        match worst {
            Some(((i, j), s)) if s > limit_m => {
                free[idx_r(i, j)] = false;
                fixed.push((i, j));
            }
            _ => break,
        }
    }
    fixed
}
