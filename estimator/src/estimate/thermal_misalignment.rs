//! Whether the misalignment the temperature model holds constant (docs/model.md §9) moves with
//! temperature: at each soak temperature with enough attitudes, each accelerometer's row of `M`
//! is fitted on its own (gain and bias free, so the bias and scale tempcos do not enter), and each
//! off-diagonal ratio `m_ij/m_ii` (the misalignment angle of axis `i` towards `j`, rad) is compared
//! across the temperatures by a χ² test at 99.9 %.

use super::note::Note;
use super::solve::invert_spd;
use nalgebra::{DMatrix, DVector};
use recording::session::thermal::ThermalStats;
use recording::session::SegmentStats;

/// Soak segments within this of a group's first mean temperature belong to its group, °C.
const GROUP_WIDTH_C: f64 = 1.5;
/// Standard normal quantile of 99.9 %.
const Z_999: f64 = 3.090_232;

/// One temperature group's misalignment ratios and their 1σ, `[i][j]`, rad.
struct Group {
    mean_c: f64,
    ratio: [[f64; 3]; 3],
    sigma: [[f64; 3]; 3],
}

/// Warnings naming each axis pair whose misalignment changes significantly with temperature, with
/// its slope, µrad/°C. `soaks` are the static soak segments with their attitudes (`up_b`).
pub fn check(soaks: &[(&SegmentStats, &ThermalStats, [f64; 3])]) -> Vec<Note> {
    let mut groups: Vec<Vec<usize>> = Vec::new();
    for (k, (_, ts, _)) in soaks.iter().enumerate() {
        let t = ts.mean_c();
        match groups
            .iter_mut()
            .find(|g| (soaks[g[0]].1.mean_c() - t).abs() < GROUP_WIDTH_C)
        {
            Some(g) => g.push(k),
            None => groups.push(vec![k]),
        }
    }
    let fitted: Vec<Group> = groups
        .iter()
        .filter(|g| g.len() >= 5)
        .filter_map(|g| fit_group(soaks, g))
        .collect();
    let mut warnings = Vec::new();
    if fitted.len() < 2 {
        return warnings;
    }
    for i in 0..3 {
        for j in (0..3).filter(|&j| j != i) {
            let w: Vec<f64> = fitted.iter().map(|g| g.sigma[i][j].powi(-2)).collect();
            let sw: f64 = w.iter().sum();
            let mean = fitted
                .iter()
                .zip(&w)
                .map(|(g, w)| g.ratio[i][j] * w)
                .sum::<f64>()
                / sw;
            let chi2: f64 = fitted
                .iter()
                .zip(&w)
                .map(|(g, w)| (g.ratio[i][j] - mean).powi(2) * w)
                .sum();
            let dof = (fitted.len() - 1) as f64;
            let bound = chi2_quantile_999(dof);
            if chi2 <= bound {
                continue;
            }
            // Weighted slope of the ratio against temperature.
            let tm = fitted
                .iter()
                .zip(&w)
                .map(|(g, w)| g.mean_c * w)
                .sum::<f64>()
                / sw;
            let sxx: f64 = fitted
                .iter()
                .zip(&w)
                .map(|(g, w)| w * (g.mean_c - tm).powi(2))
                .sum();
            let sxy: f64 = fitted
                .iter()
                .zip(&w)
                .map(|(g, w)| w * (g.mean_c - tm) * (g.ratio[i][j] - mean))
                .sum();
            let (slope, sd) = if sxx > 0.0 {
                (sxy / sxx, sxx.powf(-0.5))
            } else {
                (0.0, f64::INFINITY)
            };
            warnings.push(Note::MisalignmentDrift {
                axis: i,
                towards: j,
                slope_urad_per_c: slope * 1e6,
                sigma_urad_per_c: sd * 1e6,
                chi2,
                dof,
                soaks: fitted.len(),
                bound,
            });
        }
    }
    warnings
}

/// Rows of `M` (with their own biases) from one group's segments, as ratios `m_ij/m_ii`.
fn fit_group(soaks: &[(&SegmentStats, &ThermalStats, [f64; 3])], idx: &[usize]) -> Option<Group> {
    let mut ratio = [[0.0; 3]; 3];
    let mut sigma = [[0.0; 3]; 3];
    for i in 0..3 {
        let mut n = DMatrix::zeros(4, 4);
        let mut g = DVector::zeros(4);
        for &k in idx {
            let (st, _, up) = &soaks[k];
            let v = st.cov_u[i][i] / st.count.max(1) as f64;
            if !(v.is_finite() && v > 0.0) {
                return None;
            }
            let a = DVector::from_row_slice(&[up[0], up[1], up[2], 1.0]);
            n += &a * a.transpose() / v;
            g += &a * st.mean_u[i] / v;
        }
        let cov = invert_spd(&n, 1e-9)?;
        let m = &cov * g;
        for j in (0..3).filter(|&j| j != i) {
            let r = m[j] / m[i];
            // Delta method: ∂r/∂m_ij = 1/m_ii, ∂r/∂m_ii = −r/m_ii.
            let (a, b) = (1.0 / m[i], -r / m[i]);
            let var = a * a * cov[(j, j)] + b * b * cov[(i, i)] + 2.0 * a * b * cov[(i, j)];
            ratio[i][j] = r;
            sigma[i][j] = var.max(f64::MIN_POSITIVE).sqrt();
        }
    }
    let mean_c = idx.iter().map(|&k| soaks[k].1.mean_c()).sum::<f64>() / idx.len() as f64;
    Some(Group {
        mean_c,
        ratio,
        sigma,
    })
}

/// The χ² quantile of 99.9 % by the Wilson–Hilferty approximation (3 % high at 1 dof, better
/// above: ample for a warning's threshold).
fn chi2_quantile_999(dof: f64) -> f64 {
    let h = 2.0 / (9.0 * dof);
    dof * (1.0 - h + Z_999 * h.sqrt()).powi(3)
}
