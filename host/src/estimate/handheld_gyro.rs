//! The gyro without a rate table (imu_tk's idea, Tedaldi et al. 2014): between two consecutive still
//! positions the body-rate integral of the corrected gyro must turn the first position's gravity
//! direction into the second's. Over all such turns this fixes the gyro's `G` (scale and misalignment,
//! docs/model.md §8: `w = G·ω_body + b`); the still periods fix its bias `b`.
//!
//! The unknown is `T = G⁻¹` (nine values, the correction is linear in it), fitted by Gauss–Newton
//! with a numerical Jacobian (central differences; the residual is a rotation of a unit vector, cheap
//! to re-integrate). The gravity directions are the *calibrated* accelerometer's, so `G` is in the
//! accelerometer calibration's body frame; an uncalibrated accelerometer's percent-level errors would
//! otherwise enter `G` directly.

use nalgebra::{DMatrix, DVector, UnitQuaternion, Vector3};
use shared::linalg::{self, RowMajor3};

/// One turn: the rows from the end of one still position to the start of the next, with the two
/// calibrated gravity ("up") directions in body axes.
#[derive(Clone, Copy, Debug, PartialEq)]
pub(crate) struct Turn {
    /// Last row of the first still position.
    pub from_row: usize,
    /// First row of the next still position.
    pub to_row: usize,
    /// Up before the turn, body axes, unit.
    pub up_before_b: [f64; 3],
    /// Up after the turn, body axes, unit.
    pub up_after_b: [f64; 3],
}

/// The fitted gyro and what the turns determined.
#[derive(Clone, Debug, PartialEq)]
pub struct HandGyroFit {
    /// `G` (row-major; row i = gyro axis i).
    pub matrix: RowMajor3,
    /// 1σ of each entry of `G`.
    pub matrix_1sigma: RowMajor3,
    /// `b`, rad/s.
    pub bias_rad_s: [f64; 3],
    /// 1σ of `b`, rad/s.
    pub bias_1sigma_rad_s: [f64; 3],
    /// Turns used.
    pub turns: usize,
    /// RMS angle between predicted and measured up after a turn, degrees.
    pub rms_residual_deg: f64,
}

/// A `G` entry whose 1σ exceeds this is reported as not determined by the turns (0.1 % / 0.06°).
pub const DETERMINED_1SIGMA: f64 = 1e-3;

impl HandGyroFit {
    /// Scale factor error of each gyro axis (row norm − 1).
    pub(crate) fn scale_rel(&self) -> [f64; 3] {
        self.matrix.map(|r| linalg::norm(&r) - 1.0)
    }

    /// Misalignment of gyro axis i towards body axis j (i ≠ j), degrees.
    pub(crate) fn misalignment_deg(&self) -> RowMajor3 {
        core::array::from_fn(|i| {
            let n = linalg::norm(&self.matrix[i]);
            core::array::from_fn(|j| {
                if i == j {
                    0.0
                } else {
                    (self.matrix[i][j] / n).asin().to_degrees()
                }
            })
        })
    }

    /// Entries of `G` not determined to [`DETERMINED_1SIGMA`], named like `G[x][y]`.
    pub fn undetermined(&self) -> Vec<String> {
        let ax = ["x", "y", "z"];
        let mut v = Vec::new();
        for i in 0..3 {
            for j in 0..3 {
                let s = self.matrix_1sigma[i][j];
                if s.is_nan() || s > DETERMINED_1SIGMA {
                    v.push(format!("G[{}][{}]", ax[i], ax[j]));
                }
            }
        }
        v
    }
}

/// Why the gyro could not be fitted.
#[derive(Debug, thiserror::Error, PartialEq)]
pub enum HandGyroError {
    /// Fewer turns than the nine unknowns need.
    #[error(
        "{turns} turn(s) between still positions: the gyro's scale and misalignment need at least 5 \
         (24 recommended), turning about different axes"
    )]
    TooFewTurns {
        /// Turns available.
        turns: usize,
    },
    /// The integrated gyro turns far more or far less than gravity did.
    #[error(
        "the gyro turns {ratio:.3}× as far as gravity does between positions: its unit is wrong{hint}; \
         give the right --gyro-unit"
    )]
    UnitMismatch {
        /// Median ratio of integrated to gravity angle.
        ratio: f64,
        /// A guess at the right unit.
        hint: &'static str,
    },
    /// The user asked for no gyro fit (`host segment --no-gyro`).
    #[error("not fitted (--no-gyro); the accelerometer's axes are unchecked for a mirror image")]
    NotAsked,
    /// The fit did not give a usable `G`.
    #[error("the gyro fit gives an implausible G (row norms {norms:?}, expected near 1): {why}")]
    Implausible {
        /// Row norms.
        norms: [f64; 3],
        /// What is wrong.
        why: &'static str,
    },
}

/// Up after `turn`, predicted by integrating `T·(w − b)` (midpoint rule per sample step).
fn predict_up(turn: &Turn, t_s: &[f64], w: &[[f64; 3]], t: &RowMajor3, b: &[f64; 3]) -> [f64; 3] {
    let q = integrate(turn, t_s, w, t, b);
    let v = q.inverse_transform_vector(&Vector3::from(turn.up_before_b));
    [v.x, v.y, v.z]
}

/// Body rotation over the turn (body-before to body-after).
fn integrate(
    turn: &Turn,
    t_s: &[f64],
    w: &[[f64; 3]],
    t: &RowMajor3,
    b: &[f64; 3],
) -> UnitQuaternion<f64> {
    let mut q = UnitQuaternion::identity();
    for i in turn.from_row..turn.to_row {
        let dt = t_s[i + 1] - t_s[i];
        let mid: [f64; 3] = core::array::from_fn(|j| 0.5 * (w[i][j] + w[i + 1][j]) - b[j]);
        let om = linalg::mat_vec(t, &mid);
        q *= UnitQuaternion::from_scaled_axis(Vector3::from(om) * dt);
    }
    q
}

fn residuals(turns: &[Turn], t_s: &[f64], w: &[[f64; 3]], p: &[f64], b: &[f64; 3]) -> Vec<f64> {
    let t: RowMajor3 = core::array::from_fn(|i| core::array::from_fn(|j| p[3 * i + j]));
    turns
        .iter()
        .flat_map(|turn| {
            let up = predict_up(turn, t_s, w, &t, b);
            (0..3).map(move |j| turn.up_after_b[j] - up[j])
        })
        .collect()
}

/// The gyro's bias from still intervals: the mean of their mean rates weighted by their lengths, with
/// 1σ from the spread between intervals (it includes the tremor's and the bias's own wander).
pub(crate) fn still_bias(means_rad_s: &[([f64; 3], usize)]) -> ([f64; 3], [f64; 3]) {
    let n: usize = means_rad_s.iter().map(|m| m.1).sum();
    let b: [f64; 3] = core::array::from_fn(|j| {
        means_rad_s
            .iter()
            .map(|(m, c)| m[j] * *c as f64)
            .sum::<f64>()
            / n.max(1) as f64
    });
    let k = means_rad_s.len() as f64;
    let s = core::array::from_fn(|j| {
        let var = means_rad_s
            .iter()
            .map(|(m, _)| (m[j] - b[j]).powi(2))
            .sum::<f64>()
            / (k - 1.0).max(1.0);
        (var / k).sqrt()
    });
    (b, s)
}

/// Checks that the integrated turns are of gravity's size before fitting (a wrong gyro unit makes the
/// integrated angle 57× too large or too small).
fn check_unit(
    turns: &[Turn],
    t_s: &[f64],
    w: &[[f64; 3]],
    b: &[f64; 3],
) -> Result<(), HandGyroError> {
    let path = |turn: &Turn| {
        (turn.from_row..turn.to_row)
            .map(|i| {
                let d: [f64; 3] = core::array::from_fn(|j| w[i][j] - b[j]);
                linalg::norm(&d) * (t_s[i + 1] - t_s[i])
            })
            .sum::<f64>()
    };
    let mut ratios: Vec<f64> = turns
        .iter()
        .filter_map(|turn| {
            let gravity = linalg::dot(&turn.up_before_b, &turn.up_after_b)
                .clamp(-1.0, 1.0)
                .acos();
            (gravity > 20f64.to_radians()).then(|| path(turn) / gravity)
        })
        .collect();
    if ratios.is_empty() {
        return Ok(());
    }
    ratios.sort_by(f64::total_cmp);
    let ratio = ratios[ratios.len() / 2];
    // The angle turned (the path, |ω| integrated, which never wraps) is at least gravity's and, for
    // hand turns, rarely above a few times it; a wrong unit is off by 57×.
    match ratio {
        r if r < 0.3 => Err(HandGyroError::UnitMismatch {
            ratio: r,
            hint: " (the values look like rad/s: --gyro-unit rad/s)",
        }),
        r if r > 5.0 => Err(HandGyroError::UnitMismatch {
            ratio: r,
            hint: " (deg/s read as rad/s gives 57×: --gyro-unit deg/s; time stamps in ms instead of s \
                   give 1000×)",
        }),
        _ => Ok(()),
    }
}

/// Fits `G` from `turns` with the bias `b` (from [`still_bias`]).
pub(crate) fn fit_handheld_gyro(
    turns: &[Turn],
    t_s: &[f64],
    w_rad_s: &[[f64; 3]],
    bias: ([f64; 3], [f64; 3]),
) -> Result<HandGyroFit, HandGyroError> {
    if turns.len() < 5 {
        return Err(HandGyroError::TooFewTurns { turns: turns.len() });
    }
    let b = bias.0;
    check_unit(turns, t_s, w_rad_s, &b)?;
    let mut p = vec![1.0, 0.0, 0.0, 0.0, 1.0, 0.0, 0.0, 0.0, 1.0];
    let jacobian = |p: &[f64]| {
        let h = 1e-6;
        let m = 3 * turns.len();
        let mut j = DMatrix::zeros(m, 9);
        for c in 0..9 {
            let (mut a, mut z) = (p.to_vec(), p.to_vec());
            a[c] += h;
            z[c] -= h;
            let (ra, rz) = (
                residuals(turns, t_s, w_rad_s, &a, &b),
                residuals(turns, t_s, w_rad_s, &z, &b),
            );
            for r in 0..m {
                j[(r, c)] = (ra[r] - rz[r]) / (2.0 * h);
            }
        }
        j
    };
    let mut jac = jacobian(&p);
    for _ in 0..20 {
        let r = DVector::from_vec(residuals(turns, t_s, w_rad_s, &p, &b));
        // J is the derivative of r itself: the step minimises |r + J·δ|².
        let step = (jac.transpose() * &jac)
            .try_inverse()
            .map(|inv| -(inv * jac.transpose() * r))
            .ok_or(HandGyroError::Implausible {
                norms: [f64::NAN; 3],
                why: "the turns do not determine it (all about one axis?)",
            })?;
        for c in 0..9 {
            p[c] += step[c];
        }
        jac = jacobian(&p);
        if step.norm() < 1e-10 {
            break;
        }
    }
    let r = residuals(turns, t_s, w_rad_s, &p, &b);
    let ssr: f64 = r.iter().map(|x| x * x).sum();
    let dof = (2 * turns.len()).saturating_sub(9).max(1) as f64;
    let sigma2 = ssr / dof;
    let t: RowMajor3 = core::array::from_fn(|i| core::array::from_fn(|j| p[3 * i + j]));
    let g = linalg::inverse(&t).ok_or(HandGyroError::Implausible {
        norms: [f64::NAN; 3],
        why: "singular",
    })?;
    let norms = g.map(|r| linalg::norm(&r));
    if norms.iter().any(|n| !(0.5..=2.0).contains(n)) {
        return Err(HandGyroError::Implausible {
            norms,
            why: "a gyro in the stated unit reads within a factor of two of the true rate",
        });
    }
    let cov_t = (jac.transpose() * &jac)
        .try_inverse()
        .unwrap_or_else(|| DMatrix::from_element(9, 9, f64::INFINITY))
        * sigma2;
    // dG = −G·dT·G: the linear map from T's entries to G's.
    let mut a = DMatrix::zeros(9, 9);
    for i in 0..3 {
        for j in 0..3 {
            for k in 0..3 {
                for l in 0..3 {
                    a[(3 * i + j, 3 * k + l)] = -g[i][k] * g[l][j];
                }
            }
        }
    }
    let cov_g = &a * cov_t * a.transpose();
    let matrix_1sigma = core::array::from_fn(|i| {
        core::array::from_fn(|j| cov_g[(3 * i + j, 3 * i + j)].max(0.0).sqrt())
    });
    Ok(HandGyroFit {
        matrix: g,
        matrix_1sigma,
        bias_rad_s: b,
        bias_1sigma_rad_s: bias.1,
        turns: turns.len(),
        rms_residual_deg: (ssr / turns.len() as f64).sqrt().to_degrees(),
    })
}
