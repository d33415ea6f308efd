//! The gyro model `w = G ω_b + b` (docs/model.md §8), estimated with the accelerometers from the same
//! session: rest segments give `b`; a spin at the table's rate Ω about mount m's true up `u_m` (the
//! tilt unknowns of §7, shared with the accelerometers) gives `G u_m Ω (1 + s)`, with `s` the table's
//! rate scale error (a prior from the plan). One spin axis gives three of G's nine values; spins about
//! three non-coplanar axes give all of them. A weak prior (1σ = 1 per entry, about the identity)
//! keeps the rest finite, and the report names the entries it leaves undetermined.

use super::model::TiltGeometry;
use shared::linalg::{self, RowMajor3};

/// Entries of the gyro block of θ: `G` (9, row-major), `b` (3, rad/s), table rate scale `s`.
pub(crate) const NG: usize = 13;

/// Index of `G[i][j]` in θ.
pub const fn idx_g(base: usize, i: usize, j: usize) -> usize {
    base + 3 * i + j
}

/// Index of `b_i` in θ.
pub const fn idx_b(base: usize, i: usize) -> usize {
    base + 9 + i
}

/// Index of the table rate scale `s` in θ.
pub const fn idx_rate(base: usize) -> usize {
    base + 12
}

/// A `G` entry whose 1σ exceeds this is reported as not determined by the plan.
pub const UNDETERMINED_SIGMA: f64 = 1e-3;

/// 1σ of the weak prior on each `G` entry (about the identity).
pub(crate) const G_PRIOR_SIGMA: f64 = 1.0;

/// `G` of θ.
pub(crate) fn g_of(t: &[f64], base: usize) -> RowMajor3 {
    core::array::from_fn(|i| core::array::from_fn(|j| t[idx_g(base, i, j)]))
}

/// `b` of θ.
pub(crate) fn b_of(t: &[f64], base: usize) -> [f64; 3] {
    core::array::from_fn(|i| t[idx_b(base, i)])
}

/// One segment's mean gyro rate as the fit sees it.
#[derive(Clone, Debug)]
pub(crate) struct GyroMean {
    /// Index into the session's segment list.
    pub seg: usize,
    /// The mount's attitude unknowns (unused at rest).
    pub tilt: TiltGeometry,
    /// The table's planned mean rate, rad/s (0 at rest).
    pub rate_rad_s: f64,
    /// Measured mean rate, rad/s.
    pub mean_w_rad_s: [f64; 3],
    /// `L⁻¹` of the mean's covariance.
    pub whiten: RowMajor3,
    /// The mean's own covariance (its noise), (rad/s)²: the gyro walk's dense weighting adds the
    /// walk's share to it (docs/model.md §11.6).
    pub se_cov: RowMajor3,
    /// The segment's first and last sample, s (where the gyro walk's share is taken over).
    pub span_s: [f64; 2],
}

impl GyroMean {
    /// Builds one over the span `span_s`; `None` when the covariance is not positive definite.
    pub fn new(
        seg: usize,
        tilt: TiltGeometry,
        rate_rad_s: f64,
        mean_w_rad_s: [f64; 3],
        se_cov: RowMajor3,
        span_s: [f64; 2],
    ) -> Option<GyroMean> {
        let l = linalg::to_na(&se_cov).cholesky()?.l();
        let whiten = linalg::from_na(&l.try_inverse()?);
        Some(GyroMean {
            seg,
            tilt,
            rate_rad_s,
            mean_w_rad_s,
            whiten,
            se_cov,
            span_s,
        })
    }

    /// Predicted mean rate `G Ω (1 + s) u + b`.
    pub fn predict(&self, t: &[f64], base: usize) -> [f64; 3] {
        let g = g_of(t, base);
        let b = b_of(t, base);
        if self.rate_rad_s == 0.0 {
            return b;
        }
        let k = self.rate_rad_s * (1.0 + t[idx_rate(base)]);
        let up = self.tilt.up(t);
        let gu = linalg::mat_vec(&g, &up);
        core::array::from_fn(|i| k * gu[i] + b[i])
    }

    /// Nonzero Jacobian columns.
    pub(crate) fn jacobian(&self, t: &[f64], base: usize) -> Vec<(usize, [f64; 3])> {
        let mut cols = Vec::with_capacity(19);
        let unit = |i: usize, v: f64| -> [f64; 3] {
            core::array::from_fn(|q| if q == i { v } else { 0.0 })
        };
        for i in 0..3 {
            cols.push((idx_b(base, i), unit(i, 1.0)));
        }
        if self.rate_rad_s == 0.0 {
            return cols;
        }
        let g = g_of(t, base);
        let s = t[idx_rate(base)];
        let k = self.rate_rad_s * (1.0 + s);
        let (up, dup) = self.tilt.up_and_derivatives(t);
        for i in 0..3 {
            for j in 0..3 {
                cols.push((idx_g(base, i, j), unit(i, k * up[j])));
            }
        }
        let gu = linalg::mat_vec(&g, &up);
        cols.push((idx_rate(base), gu.map(|v| v * self.rate_rad_s)));
        for (c, d) in dup.iter().enumerate() {
            let gd = linalg::mat_vec(&g, d);
            cols.push((self.tilt.index + c, gd.map(|v| v * k)));
        }
        cols
    }

    /// Whitened residual.
    pub(crate) fn whitened_residual(&self, t: &[f64], base: usize) -> [f64; 3] {
        let p = self.predict(t, base);
        let r: [f64; 3] = core::array::from_fn(|i| self.mean_w_rad_s[i] - p[i]);
        linalg::mat_vec(&self.whiten, &r)
    }
}

/// The gyro part of the session's fit.
#[derive(Clone, Debug)]
pub(crate) struct GyroBlock {
    /// Index of the block in θ.
    pub base: usize,
    /// The segments' gyro means.
    pub means: Vec<GyroMean>,
    /// 1σ of the table's relative rate error.
    pub rate_sigma_rel: f64,
    /// The gyro bias's random walk the means are weighted with (docs/model.md §11.6), intensity
    /// in (rad/s)²/s per gyro axis; `None` (or a zero walk): a constant bias, each mean weighted by
    /// its own noise.
    pub walk: Option<super::drift::Drift>,
}

/// Each gyro axis's scale error, `|G_i·| − 1` (docs/model.md §8): its gain along its own sensing
/// direction, whatever that direction's misalignment; the 1σ from the row's entries' 1σ.
pub fn scale_error(matrix: &RowMajor3, matrix_1sigma: &RowMajor3) -> [(f64, f64); 3] {
    core::array::from_fn(|i| {
        let n = linalg::norm(&matrix[i]);
        let var: f64 = (0..3)
            .map(|j| (matrix[i][j] / n * matrix_1sigma[i][j]).powi(2))
            .sum();
        (n - 1.0, var.sqrt())
    })
}

/// The estimated gyro correction, with 1σ, for the calibration file and the report.
#[derive(Clone, Debug, PartialEq)]
pub struct GyroEstimate {
    /// `G` (w = G ω_b + b).
    pub matrix: RowMajor3,
    /// Its 1σ (entries above [`UNDETERMINED_SIGMA`] are not determined by the plan).
    pub matrix_1sigma: RowMajor3,
    /// `b`, rad/s.
    pub bias_rad_s: [f64; 3],
    /// Its 1σ, rad/s.
    pub bias_rad_s_1sigma: [f64; 3],
    /// The table's rate scale error, and its 1σ; `None` for a gyro fitted from hand turns (no table).
    pub table_rate_scale: Option<(f64, f64)>,
    /// Names of the `G` entries the plan does not determine (e.g. `G[x][z]`).
    pub undetermined: Vec<String>,
}

impl GyroEstimate {
    /// From θ and its covariance.
    pub(crate) fn from_fit(t: &[f64], cov: &nalgebra::DMatrix<f64>, base: usize) -> GyroEstimate {
        let s = |p: usize| cov[(p, p)].max(0.0).sqrt();
        let matrix_1sigma: RowMajor3 =
            core::array::from_fn(|i| core::array::from_fn(|j| s(idx_g(base, i, j))));
        let mut undetermined = Vec::new();
        for i in 0..3 {
            for j in 0..3 {
                if matrix_1sigma[i][j] > UNDETERMINED_SIGMA {
                    undetermined.push(format!(
                        "G[{}][{}]",
                        shared::params::axis_name(i),
                        shared::params::axis_name(j)
                    ));
                }
            }
        }
        GyroEstimate {
            matrix: g_of(t, base),
            matrix_1sigma,
            bias_rad_s: b_of(t, base),
            bias_rad_s_1sigma: core::array::from_fn(|i| s(idx_b(base, i))),
            table_rate_scale: Some((t[idx_rate(base)], s(idx_rate(base)))),
            undetermined,
        }
    }

    /// The estimate as the calibration the device applies (`ω = G⁻¹ (w − b)`, docs/model.md §8).
    pub fn device_correction(&self) -> shared::GyroCorrection {
        shared::GyroCorrection {
            matrix: self.matrix,
            bias_rad_s: self.bias_rad_s,
        }
    }

    /// The bias alone, from rests (a session without spins): `G` is the identity, none of its
    /// entries determined (1σ infinite), and `b` with its 1σ (docs/model.md §8).
    pub(crate) fn bias_only(bias_rad_s: [f64; 3], bias_rad_s_1sigma: [f64; 3]) -> GyroEstimate {
        let mut undetermined = Vec::new();
        for i in 0..3 {
            for j in 0..3 {
                undetermined.push(format!(
                    "G[{}][{}]",
                    shared::params::axis_name(i),
                    shared::params::axis_name(j)
                ));
            }
        }
        GyroEstimate {
            matrix: core::array::from_fn(|i| core::array::from_fn(|j| f64::from(u8::from(i == j)))),
            matrix_1sigma: [[f64::INFINITY; 3]; 3],
            bias_rad_s,
            bias_rad_s_1sigma,
            table_rate_scale: None,
            undetermined,
        }
    }

    /// Whether any entry of `G` is determined ([`UNDETERMINED_SIGMA`]): not for the rests' bias
    /// alone (`GyroEstimate::bias_only`), whose `G` is the identity taken as perfect.
    pub fn determines_matrix(&self) -> bool {
        self.matrix_1sigma
            .iter()
            .flatten()
            .any(|&s| s <= UNDETERMINED_SIGMA)
    }

    /// `(G⁻¹, b)`: what turns a gyro reading into the body rate.
    pub(crate) fn correction(&self) -> Option<(RowMajor3, [f64; 3])> {
        linalg::inverse(&self.matrix).map(|gi| (gi, self.bias_rad_s))
    }
}

/// `E[ω ωᵀ]` and `ω̇` of the body from a segment's gyro statistics through a correction
/// `ω = G⁻¹ (w − b)`, the gyro's own noise `noise_cov` (gyro axes) removed.
pub(crate) fn corrected_moments(
    mean_wwt: &RowMajor3,
    mean_w: &[f64; 3],
    wdot: &[f64; 3],
    noise_cov: &RowMajor3,
    correction: &(RowMajor3, [f64; 3]),
) -> (RowMajor3, [f64; 3]) {
    let (gi, b) = correction;
    // E[(w − b)(w − b)ᵀ] − C = E[w wᵀ] − b w̄ᵀ − w̄ bᵀ + b bᵀ − C
    let c: RowMajor3 = core::array::from_fn(|i| {
        core::array::from_fn(|j| {
            mean_wwt[i][j] - b[i] * mean_w[j] - mean_w[i] * b[j] + b[i] * b[j] - noise_cov[i][j]
        })
    });
    let gc: RowMajor3 = core::array::from_fn(|i| {
        core::array::from_fn(|j| (0..3).map(|k| gi[i][k] * c[k][j]).sum())
    });
    let wwt = core::array::from_fn(|i| {
        core::array::from_fn(|j| (0..3).map(|k| gc[i][k] * gi[j][k]).sum())
    });
    (wwt, linalg::mat_vec(gi, wdot))
}
