//! From the fitted parameters (θ: `M`, `u0`, `r`) to the paper's form (Table 1 and Table 3) with its
//! covariance, by the exact Jacobian of the conversion (`docs/model.md` §4.2):
//! `k_i = ‖m_i‖`, `θ_ij = acos(m_ij / k_i)`, `r'_i = r_i − c` (c = 0, the centroid or a given point).

use super::model::{idx_m, idx_r, idx_u0, NI as NP};
use super::screen::{Frame, Shift};
use super::{EstimateError, EstimateOptions, Observability, Uncertainty};
use nalgebra::DMatrix;
use shared::linalg::RowMajor3;
use shared::params::{axis_name, ParamsError};
use shared::Calibration;

/// Number of paper-form values: 3 biases, 3 scale factors, 9 angles, 9 lever-arm components.
pub const PAPER_LEN: usize = 24;

/// Names of the paper-form values, in [`paper_values`] order.
pub fn paper_labels() -> Vec<String> {
    let mut v = Vec::with_capacity(PAPER_LEN);
    for i in 0..3 {
        v.push(format!("bias {}", axis_name(i)));
    }
    for i in 0..3 {
        v.push(format!("scale {}", axis_name(i)));
    }
    for i in 0..3 {
        for j in 0..3 {
            v.push(format!("θ{}{}", axis_name(i), axis_name(j)));
        }
    }
    for i in 0..3 {
        for j in 0..3 {
            v.push(format!("r{}{}", i + 1, axis_name(j)));
        }
    }
    v
}

/// A calibration's paper-form values (angles from normalised rows, so consistent with an estimate).
pub fn paper_values(cal: &Calibration) -> Result<[f64; PAPER_LEN], ParamsError> {
    let paper = cal.statics.to_fitted()?.0.to_paper()?;
    Ok(paper_order(
        &paper.zero_bias_out,
        &paper.scale_out_per_g,
        &paper.installation_angles_deg,
        &cal.lever_arms.r_m,
    ))
}

/// Values (or their 1σ) laid out in [`paper_labels`] order: zero biases, scale factors, installation
/// angles row by row, lever arms row by row.
pub fn paper_order(
    bias: &[f64; 3],
    scale: &[f64; 3],
    angles: &RowMajor3,
    lever_arms: &RowMajor3,
) -> [f64; PAPER_LEN] {
    let mut v = [0.0; PAPER_LEN];
    for i in 0..3 {
        v[i] = bias[i];
        v[3 + i] = scale[i];
        for j in 0..3 {
            v[6 + 3 * i + j] = angles[i][j];
            v[15 + 3 * i + j] = lever_arms[i][j];
        }
    }
    v
}

/// The converted estimate.
pub(crate) struct Converted {
    pub values: [f64; PAPER_LEN],
    pub cov: DMatrix<f64>,
    /// Depends on a lever-arm component fixed at 0.
    pub undetermined: [bool; PAPER_LEN],
    pub fixed: [[bool; 3]; 3],
    pub lever_arms: RowMajor3,
    /// The calibration's reference point in the fit's frame, m: `lever_arms[i] = r_i − centre_m`.
    pub centre_m: [f64; 3],
}

/// Converts θ and its covariance (scaled by `scale2`).
pub fn convert(
    theta: &[f64],
    cov: &DMatrix<f64>,
    scale2: f64,
    fixed: &[[bool; 3]; 3],
    _options: &EstimateOptions,
    frame: &Frame,
) -> Result<Converted, EstimateError> {
    let mut g = DMatrix::<f64>::zeros(PAPER_LEN, NP);
    let mut values = [0.0; PAPER_LEN];
    let rad2deg = 180.0 / std::f64::consts::PI;
    let r: RowMajor3 = core::array::from_fn(|i| core::array::from_fn(|j| theta[idx_r(i, j)]));
    let centre = match frame.shift {
        Shift::None => [0.0; 3],
        Shift::Centroid => core::array::from_fn(|j| (r[0][j] + r[1][j] + r[2][j]) / 3.0),
        Shift::Point(o) => o,
    };
    let mut lever_arms = [[0.0; 3]; 3];
    for i in 0..3 {
        values[i] = theta[idx_u0(i)];
        g[(i, idx_u0(i))] = 1.0;
        let m: [f64; 3] = core::array::from_fn(|j| theta[idx_m(i, j)]);
        let k = shared::linalg::norm(&m);
        if !(k > 0.0 && k.is_finite()) {
            return Err(EstimateError::Params(ParamsError::DegenerateAxis {
                axis: i as u8,
            }));
        }
        values[3 + i] = k;
        let a: [f64; 3] = m.map(|v| v / k);
        for l in 0..3 {
            g[(3 + i, idx_m(i, l))] = a[l];
        }
        for j in 0..3 {
            let row = 6 + 3 * i + j;
            let aij = a[j].clamp(-1.0, 1.0);
            values[row] = aij.acos() * rad2deg;
            let s = (1.0 - aij * aij).max(1e-300).sqrt();
            for l in 0..3 {
                let da = ((j == l) as u8 as f64 - a[j] * a[l]) / k;
                g[(row, idx_m(i, l))] = -da / s * rad2deg;
            }
            let row = 15 + 3 * i + j;
            lever_arms[i][j] = r[i][j] - centre[j];
            values[row] = lever_arms[i][j];
            match frame.shift {
                Shift::Centroid => {
                    for q in 0..3 {
                        g[(row, idx_r(q, j))] = (i == q) as u8 as f64 - 1.0 / 3.0;
                    }
                }
                _ => g[(row, idx_r(i, j))] = 1.0,
            }
        }
    }
    let mut undetermined = [false; PAPER_LEN];
    for (p, u) in undetermined.iter_mut().enumerate() {
        *u = (0..3).any(|i| (0..3).any(|j| fixed[i][j] && g[(p, idx_r(i, j))] != 0.0));
    }
    let cov = cov.view((0, 0), (NP, NP));
    let mut c = &g * cov * g.transpose() * scale2;
    for (p, u) in undetermined.iter().enumerate() {
        if *u {
            c[(p, p)] = f64::INFINITY;
        }
    }
    Ok(Converted {
        values,
        cov: c,
        undetermined,
        fixed: *fixed,
        lever_arms,
        centre_m: centre,
    })
}

impl Converted {
    pub fn sigma(&self, p: usize) -> f64 {
        self.cov[(p, p)].max(0.0).sqrt()
    }

    pub(crate) fn lever_sigma(&self) -> RowMajor3 {
        core::array::from_fn(|i| core::array::from_fn(|j| self.sigma(15 + 3 * i + j)))
    }

    pub fn observability(&self, options: &EstimateOptions) -> Observability {
        let s = self.lever_sigma();
        Observability {
            lever_arm_sigma_m: s,
            observable: core::array::from_fn(|i| {
                core::array::from_fn(|j| {
                    !self.undetermined[15 + 3 * i + j] && s[i][j] <= options.lever_arm_threshold_m
                })
            }),
            fixed_at_zero: self.fixed,
            threshold_m: options.lever_arm_threshold_m,
        }
    }

    pub fn uncertainty(&self, obs: &Observability) -> Uncertainty {
        Uncertainty {
            zero_bias_1sigma: core::array::from_fn(|i| self.sigma(i)),
            scale_per_g_1sigma: core::array::from_fn(|i| self.sigma(3 + i)),
            installation_angles_deg_1sigma: core::array::from_fn(|i| {
                core::array::from_fn(|j| self.sigma(6 + 3 * i + j))
            }),
            lever_arms_m_1sigma: self.lever_sigma(),
            lever_arms_observable: obs.observable,
        }
    }

    pub(crate) fn cov_rows(&self) -> Vec<Vec<f64>> {
        (0..PAPER_LEN)
            .map(|a| (0..PAPER_LEN).map(|b| self.cov[(a, b)]).collect())
            .collect()
    }

    #[allow(dead_code)]
    pub fn value(&self, p: usize) -> f64 {
        self.values[p]
    }
}
