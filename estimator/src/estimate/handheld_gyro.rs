//! The gyro without a rate table (imu_tk's idea, Tedaldi et al. 2014): between two consecutive still
//! positions the body-rate integral of the corrected gyro must turn the first position's gravity
//! direction into the second's. Over all such turns this fixes the gyro's `G` (scale and misalignment,
//! docs/model.md §8: `w = G·ω_body + b`); the still periods fix its bias `b`. A whole turn on a table
//! about the vertical (the classic six-face bench method) leaves gravity where it was and so tells
//! nothing that way; it is used instead as a known angle: the rate integral over it is `2πk` times
//! the up direction (docs/model.md §7.2).
//!
//! The unknowns are `T = G⁻¹` (nine values, the correction is linear in it) and `b`, fitted by
//! Gauss–Newton on the hand turns, the table turns and the still bias together. The gravity
//! directions are the *calibrated* accelerometer's, so `G` is in the accelerometer calibration's body
//! frame; an uncalibrated accelerometer's percent-level errors would otherwise enter `G` directly.

use nalgebra::{DMatrix, DVector, UnitQuaternion, Vector3};
use recording::spelling::{Spelling, UserOption};
use shared::linalg::{self, RowMajor3};
use std::f64::consts::PI;

/// One turn: the rows from the end of one still position to the start of the next, with the two
/// calibrated gravity ("up") directions in body axes.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Turn {
    /// Last row of the first still position.
    pub from_row: usize,
    /// First row of the next still position.
    pub to_row: usize,
    /// Up before the turn, body axes, unit.
    pub up_before_b: [f64; 3],
    /// Up after the turn, body axes, unit.
    pub up_after_b: [f64; 3],
}

/// A whole turn on a table (docs/model.md §7.2): the unit turned `turns` times about the vertical and
/// set back against the same stop, the same face down before and after.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct TableTurn {
    /// Last row of the still position before.
    pub from_row: usize,
    /// First row of the still position after.
    pub to_row: usize,
    /// Up at that position (the turn's axis), body axes, unit.
    pub up_b: [f64; 3],
    /// Whole turns, signed: positive is right-handed about up (anticlockwise seen from above).
    pub turns: i32,
}

/// 1σ of a table turn's return to its stop, degrees (docs/model.md §7.2): the unit pushed back against
/// the same fence or corner after its whole turn repeats its heading to a few hundredths of a degree
/// (a face's edge and a straight fence, both flat to about 0.02 mm over 20–30 mm); taken with margin
/// for dust and a pushed-back rather than slid-back unit.
pub(crate) const TABLE_STOP_DEG: f64 = 0.1;
/// 1σ of a table turn's axis from the calibrated up, degrees (docs/model.md §7.2): the table's normal
/// is off the vertical by its levelling (a bench level to 0.1–0.2°), the face rocks on dust while
/// turned, and the calibrated up is itself a fraction of a milliradian off.
pub(crate) const TABLE_AXIS_DEG: f64 = 0.3;
/// A hand turn's residual 1σ per component before the turns' own misfit estimates it, degrees.
const HAND_PRIOR_DEG: f64 = 0.05;

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
    /// Hand turns used.
    pub turns: usize,
    /// Whole table turns used (docs/model.md §7.2).
    pub table_turns: usize,
    /// RMS angle between predicted and measured up after a hand turn, degrees.
    pub rms_residual_deg: f64,
    /// RMS of the table turns' angle error (the corrected rate's integral about the axis less
    /// `2πk`), degrees; 0 without table turns.
    pub table_rms_residual_deg: f64,
}

/// A `G` entry whose 1σ exceeds this is reported as not determined by the turns (0.1 % / 0.06°).
pub const DETERMINED_1SIGMA: f64 = 1e-3;

impl HandGyroFit {
    /// Scale factor error of each gyro axis, the one definition of docs/model.md §8
    /// ([`super::gyro::scale_error`]).
    pub fn scale_rel(&self) -> [f64; 3] {
        super::gyro::scale_error(&self.matrix, &self.matrix_1sigma).map(|e| e.0)
    }

    /// Misalignment of gyro axis i towards body axis j (i ≠ j), degrees.
    pub fn misalignment_deg(&self) -> RowMajor3 {
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
    /// Too few turns for the nine unknowns and a check of them ([`MIN_EQUATIONS`]).
    #[error(
        "{turns} turn(s) between still positions and {table_turns} whole turn(s) on the table: too \
         few to determine the gyro's scale and misalignment or to check its columns, which need at \
         least 6 turns (24 recommended), turning about different axes, or one whole table turn on \
         each face"
    )]
    TooFewTurns {
        /// Hand turns available.
        turns: usize,
        /// Whole table turns available.
        table_turns: usize,
    },
    /// The integrated gyro turns far more or far less than gravity did.
    #[error(
        "the gyro turns {ratio:.3}× as far as gravity does between positions: its unit is wrong{hint}; \
         give the right {}",
        .spelling.name(UserOption::GyroUnit)
    )]
    UnitMismatch {
        /// Median ratio of integrated to gravity angle.
        ratio: f64,
        /// A guess at the right unit.
        hint: String,
        /// The caller's names of the options.
        spelling: Spelling,
    },
    /// The turns leave `G` so loose that an implausible fitted `G` is within 3σ of a plausible one:
    /// no evidence of a wrong column or unit, and no calibration either.
    #[error(
        "not determined by these {turns} turn(s): G's entries have 1σ up to {worst_1sigma_pct:.0} %, \
         and within 3σ the fit is a plausible gyro's; turn the unit about each of its axes, both \
         ways, between the still positions (24 turns recommended)"
    )]
    NotDetermined {
        /// Hand turns used.
        turns: usize,
        /// The largest 1σ of an entry of `G`, %.
        worst_1sigma_pct: f64,
    },
    /// The user asked for no gyro fit ([`UserOption::NoGyro`]).
    #[error("not fitted (the gyro was left out); the accelerometer's axes are unchecked for a mirror image")]
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

/// The hand turns' residuals (measured minus predicted up after each turn, three per turn), rad.
fn hand_residuals(turns: &[Turn], t_s: &[f64], w: &[[f64; 3]], p: &[f64]) -> Vec<f64> {
    let (t, b) = unpack(p);
    turns
        .iter()
        .flat_map(|turn| {
            let up = predict_up(turn, t_s, w, &t, &b);
            (0..3).map(move |j| turn.up_after_b[j] - up[j])
        })
        .collect()
}

/// `T = G⁻¹` (row-major) and `b` from the parameter vector `p = [T₁₁ … T₃₃, b₁, b₂, b₃]`.
fn unpack(p: &[f64]) -> (RowMajor3, [f64; 3]) {
    (
        core::array::from_fn(|i| core::array::from_fn(|j| p[3 * i + j])),
        [p[9], p[10], p[11]],
    )
}

/// The gyro's bias from still intervals: the mean of their mean rates weighted by their lengths, with
/// 1σ from the spread between intervals (it includes the tremor's and the bias's own wander).
pub fn still_bias(means_rad_s: &[([f64; 3], usize)]) -> ([f64; 3], [f64; 3]) {
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
    sp: Spelling,
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
            hint: format!(
                " (the values look like rad/s: {})",
                sp.given(UserOption::GyroUnit, "rad/s")
            ),
            spelling: sp,
        }),
        r if r > 5.0 => Err(HandGyroError::UnitMismatch {
            ratio: r,
            hint: format!(
                " (deg/s read as rad/s gives 57×: {}; time stamps in ms instead of s give 1000×)",
                sp.given(UserOption::GyroUnit, "deg/s")
            ),
            spelling: sp,
        }),
        _ => Ok(()),
    }
}

/// Equations a hand-turn fit needs (two per hand turn, three per table turn): `G`'s nine entries and
/// three to spare. With fewer the fit neither determines `G` nor can it tell a wrong column from a
/// right one (its misfit and 1σ would rest on one or two degrees of freedom).
pub const MIN_EQUATIONS: usize = 12;

/// Fits `G` and `b` from the hand `turns`, the whole `table` turns and the still intervals' bias
/// `bias` (from [`still_bias`], with its 1σ), with the gyro's angle random walk `arw_rad_per_sqrt_s`
/// (from the still intervals' noise) in the table turns' weights. A refusal names the options as
/// `spelling` does.
pub fn fit_handheld_gyro(
    turns: &[Turn],
    table: &[TableTurn],
    t_s: &[f64],
    w_rad_s: &[[f64; 3]],
    bias: ([f64; 3], [f64; 3]),
    arw_rad_per_sqrt_s: f64,
    spelling: Spelling,
) -> Result<HandGyroFit, HandGyroError> {
    if 2 * turns.len() + 3 * table.len() < MIN_EQUATIONS {
        return Err(HandGyroError::TooFewTurns {
            turns: turns.len(),
            table_turns: table.len(),
        });
    }
    check_unit(turns, t_s, w_rad_s, &bias.0, spelling)?;
    let problem = Problem::new(turns, table, t_s, w_rad_s, bias, arw_rad_per_sqrt_s);
    let mut p = vec![1.0, 0.0, 0.0, 0.0, 1.0, 0.0, 0.0, 0.0, 1.0];
    p.extend_from_slice(&bias.0);
    // The hand turns' 1σ is not known beforehand (tremor, the six faces' frame, the accelerometer's
    // own errors): it is estimated from their misfit, with their share of the redundancy
    // (variance component estimation), and the fit repeated with it; the table turns' and the still
    // bias's 1σ are stated (docs/model.md §7.2).
    let mut sigma_hand = HAND_PRIOR_DEG.to_radians();
    for _ in 0..3 {
        p = problem.solve(p, sigma_hand)?;
        match problem.hand_sigma(&p, sigma_hand) {
            Some(s) => sigma_hand = s,
            None => break,
        }
    }
    let jac = problem.jacobian(&p, sigma_hand);
    let (t, b) = unpack(&p);
    let g = linalg::inverse(&t).ok_or(HandGyroError::Implausible {
        norms: [f64::NAN; 3],
        why: "singular",
    })?;
    let norms = g.map(|r| linalg::norm(&r));
    let (lo, hi) = super::gyro_check::COMMON_SCALE_RANGE;
    if norms.iter().any(|n| !(lo..=hi).contains(n)) {
        return Err(HandGyroError::Implausible {
            norms,
            why: "a gyro in the stated unit reads within a factor of four of the true rate",
        });
    }
    let cov = (jac.transpose() * &jac)
        .try_inverse()
        .unwrap_or_else(|| DMatrix::from_element(12, 12, f64::INFINITY));
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
    let cov_g = &a * cov.view((0, 0), (9, 9)) * a.transpose();
    let matrix_1sigma = core::array::from_fn(|i| {
        core::array::from_fn(|j| cov_g[(3 * i + j, 3 * i + j)].max(0.0).sqrt())
    });
    let r = hand_residuals(turns, t_s, w_rad_s, &p);
    let ssr: f64 = r.iter().map(|x| x * x).sum();
    Ok(HandGyroFit {
        matrix: g,
        matrix_1sigma,
        bias_rad_s: b,
        bias_1sigma_rad_s: core::array::from_fn(|j| cov[(9 + j, 9 + j)].max(0.0).sqrt()),
        turns: turns.len(),
        table_turns: table.len(),
        rms_residual_deg: (ssr / turns.len().max(1) as f64).sqrt().to_degrees(),
        table_rms_residual_deg: problem.table_rms_deg(&p),
    })
}

/// A whole turn's data that do not change in the fit: `S = ∫w dt` (the raw rate, midpoint rule as in
/// [`integrate`]), the duration and the weight `W` whitening its residual.
struct TableData {
    turn: TableTurn,
    integral: [f64; 3],
    duration_s: f64,
    weight: RowMajor3,
}

/// The whole least squares: the parameters `p = [T, b]` (twelve), the residuals whitened.
struct Problem<'a> {
    turns: &'a [Turn],
    table: Vec<TableData>,
    t_s: &'a [f64],
    w: &'a [[f64; 3]],
    bias: ([f64; 3], [f64; 3]),
}

impl<'a> Problem<'a> {
    fn new(
        turns: &'a [Turn],
        table: &[TableTurn],
        t_s: &'a [f64],
        w: &'a [[f64; 3]],
        bias: ([f64; 3], [f64; 3]),
        arw: f64,
    ) -> Problem<'a> {
        let table = table
            .iter()
            .map(|tt| {
                let mut integral = [0.0; 3];
                for i in tt.from_row..tt.to_row {
                    let dt = t_s[i + 1] - t_s[i];
                    for (j, s) in integral.iter_mut().enumerate() {
                        *s += 0.5 * (w[i][j] + w[i + 1][j]) * dt;
                    }
                }
                let duration_s = t_s[tt.to_row] - t_s[tt.from_row];
                let (along, across) = table_sigmas(arw, duration_s, tt.turns);
                let u = tt.up_b;
                let weight = core::array::from_fn(|i| {
                    core::array::from_fn(|j| {
                        let uu = u[i] * u[j];
                        let delta = f64::from(u8::from(i == j));
                        uu / along + (delta - uu) / across
                    })
                });
                TableData {
                    turn: *tt,
                    integral,
                    duration_s,
                    weight,
                }
            })
            .collect();
        Problem {
            turns,
            table,
            t_s,
            w,
            bias,
        }
    }

    /// Number of whitened residuals: three per hand turn, three per table turn, three for the bias.
    fn rows(&self) -> usize {
        3 * self.turns.len() + 3 * self.table.len() + 3
    }

    /// The known-angle residual of a table turn, rad, before whitening (docs/model.md §7.2):
    /// `T·(S − b·D) − 2πk·u`.
    fn table_residual(d: &TableData, t: &RowMajor3, b: &[f64; 3]) -> [f64; 3] {
        let s: [f64; 3] = core::array::from_fn(|j| d.integral[j] - b[j] * d.duration_s);
        let ts = linalg::mat_vec(t, &s);
        let k = 2.0 * PI * f64::from(d.turn.turns);
        core::array::from_fn(|i| ts[i] - k * d.turn.up_b[i])
    }

    /// All residuals, whitened: the hand turns' by `sigma_hand`, the table turns' by their `W`, the
    /// bias's by the still intervals' 1σ.
    fn residuals(&self, p: &[f64], sigma_hand: f64) -> Vec<f64> {
        let (t, b) = unpack(p);
        let mut r: Vec<f64> = hand_residuals(self.turns, self.t_s, self.w, p)
            .into_iter()
            .map(|x| x / sigma_hand)
            .collect();
        for d in &self.table {
            r.extend(linalg::mat_vec(&d.weight, &Self::table_residual(d, &t, &b)));
        }
        r.extend((0..3).map(|j| (b[j] - self.bias.0[j]) / bias_sigma(self.bias.1[j])));
        r
    }

    /// The Jacobian of [`Self::residuals`]: the hand turns' by central differences (the residual is a
    /// rotation of a unit vector, cheap to re-integrate), the table turns' and the bias's exactly
    /// (they are linear in `T` and `b`: `∂r/∂T_ij = W·e_i·(S − b·D)_j`, `∂r/∂b = −W·T·D`).
    fn jacobian(&self, p: &[f64], sigma_hand: f64) -> DMatrix<f64> {
        let mut jac = DMatrix::zeros(self.rows(), 12);
        let hand_rows = 3 * self.turns.len();
        let h = 1e-6;
        for c in 0..12 {
            let (mut a, mut z) = (p.to_vec(), p.to_vec());
            a[c] += h;
            z[c] -= h;
            let ra = hand_residuals(self.turns, self.t_s, self.w, &a);
            let rz = hand_residuals(self.turns, self.t_s, self.w, &z);
            for r in 0..hand_rows {
                jac[(r, c)] = (ra[r] - rz[r]) / (2.0 * h * sigma_hand);
            }
        }
        let (t, b) = unpack(p);
        for (n, d) in self.table.iter().enumerate() {
            let row = hand_rows + 3 * n;
            let s: [f64; 3] = core::array::from_fn(|j| d.integral[j] - b[j] * d.duration_s);
            for r in 0..3 {
                for i in 0..3 {
                    for j in 0..3 {
                        jac[(row + r, 3 * i + j)] = d.weight[r][i] * s[j];
                    }
                }
                for j in 0..3 {
                    let wt: f64 = (0..3).map(|i| d.weight[r][i] * t[i][j]).sum();
                    jac[(row + r, 9 + j)] = -wt * d.duration_s;
                }
            }
        }
        let row = hand_rows + 3 * self.table.len();
        for j in 0..3 {
            jac[(row + j, 9 + j)] = 1.0 / bias_sigma(self.bias.1[j]);
        }
        jac
    }

    /// Gauss–Newton from `p`: each step minimises `|r + J·δ|²`.
    fn solve(&self, mut p: Vec<f64>, sigma_hand: f64) -> Result<Vec<f64>, HandGyroError> {
        for _ in 0..20 {
            let jac = self.jacobian(&p, sigma_hand);
            let r = DVector::from_vec(self.residuals(&p, sigma_hand));
            let step = (jac.transpose() * &jac)
                .try_inverse()
                .map(|inv| -(inv * jac.transpose() * r))
                .ok_or(HandGyroError::Implausible {
                    norms: [f64::NAN; 3],
                    why: "the turns do not determine it (all about one axis?)",
                })?;
            for (c, s) in step.iter().enumerate() {
                p[c] += s;
            }
            if step.norm() < 1e-10 {
                break;
            }
        }
        Ok(p)
    }

    /// The hand turns' 1σ from their misfit at `p`: their whitened sum of squares over their share of
    /// the redundancy (two equations per turn, less the trace of their block of the hat matrix), at
    /// least one as the χ²/dof of a fit without table turns had; `None` without hand turns or misfit.
    fn hand_sigma(&self, p: &[f64], sigma_hand: f64) -> Option<f64> {
        let n = 3 * self.turns.len();
        if n == 0 {
            return None;
        }
        let jac = self.jacobian(p, sigma_hand);
        let inv = (jac.transpose() * &jac).try_inverse()?;
        let hand = jac.rows(0, n);
        let trace = (hand * inv * hand.transpose()).trace();
        let redundancy = (2.0 * self.turns.len() as f64 - trace).max(1.0);
        let ssr: f64 = self.residuals(p, sigma_hand)[..n]
            .iter()
            .map(|x| x * x)
            .sum();
        (ssr > 0.0).then(|| sigma_hand * (ssr / redundancy).sqrt())
    }

    /// RMS of the table turns' residual along their axis (the whole turn's angle error), degrees.
    fn table_rms_deg(&self, p: &[f64]) -> f64 {
        if self.table.is_empty() {
            return 0.0;
        }
        let (t, b) = unpack(p);
        let ssr: f64 = self
            .table
            .iter()
            .map(|d| linalg::dot(&Self::table_residual(d, &t, &b), &d.turn.up_b).powi(2))
            .sum();
        (ssr / self.table.len() as f64).sqrt().to_degrees()
    }
}

/// The still bias's 1σ, kept above a floor so that one still interval (no spread) does not fix `b`
/// exactly.
fn bias_sigma(s: f64) -> f64 {
    s.max(1e-6)
}

/// 1σ of a table turn's residual along its axis and across it, rad (docs/model.md §7.2): the angle
/// random walk over the turn's duration, and along the axis the return to the same stop
/// ([`TABLE_STOP_DEG`]), across it the axis's offset from the measured up ([`TABLE_AXIS_DEG`]) times
/// the angle turned.
pub(crate) fn table_sigmas(arw_rad_per_sqrt_s: f64, duration_s: f64, turns: i32) -> (f64, f64) {
    let walk = arw_rad_per_sqrt_s.powi(2) * duration_s;
    let along = (walk + TABLE_STOP_DEG.to_radians().powi(2)).sqrt();
    let across = 2.0 * PI * f64::from(turns.abs()) * TABLE_AXIS_DEG.to_radians();
    (along, (walk + across * across).sqrt())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_table_turns_jacobian_is_the_derivative_of_their_residual() {
        // Two turns of 2 s at 200 Hz about a tilted up, a rate with some wobble across it.
        let n = 401;
        let t_s: Vec<f64> = (0..n).map(|i| i as f64 / 200.0).collect();
        let w: Vec<[f64; 3]> = t_s
            .iter()
            .map(|t| [0.1 * (3.0 * t).sin(), 0.05, PI + 0.2 * t])
            .collect();
        let up = [0.1, -0.2, 0.97];
        let table = [TableTurn {
            from_row: 0,
            to_row: n - 1,
            up_b: up.map(|c| c / linalg::norm(&up)),
            turns: 1,
        }];
        let bias = ([0.01, -0.02, 0.005], [1e-4; 3]);
        let problem = Problem::new(&[], &table, &t_s, &w, bias, 1e-4);
        let p = [
            1.01, 0.02, -0.01, 0.005, 0.99, 0.03, -0.02, 0.01, 1.02, 0.012, -0.018, 0.004,
        ];
        let jac = problem.jacobian(&p, 1.0);
        for c in 0..12 {
            let (mut a, mut z) = (p.to_vec(), p.to_vec());
            a[c] += 1e-6;
            z[c] -= 1e-6;
            let (ra, rz) = (problem.residuals(&a, 1.0), problem.residuals(&z, 1.0));
            for r in 0..problem.rows() {
                let numeric = (ra[r] - rz[r]) / 2e-6;
                let scale = jac[(r, c)].abs().max(1.0);
                assert!(
                    (jac[(r, c)] - numeric).abs() < 1e-6 * scale,
                    "row {r} column {c}: {} against {numeric}",
                    jac[(r, c)]
                );
            }
        }
    }

    #[test]
    fn a_table_turns_noise_is_the_stop_along_its_axis_and_the_axis_across() {
        // No random walk: the stated stop and axis 1σ (docs/model.md §7.2); two turns: twice across.
        let (along, across) = table_sigmas(0.0, 5.0, -2);
        assert!((along - TABLE_STOP_DEG.to_radians()).abs() < 1e-15);
        assert!((across - 4.0 * PI * TABLE_AXIS_DEG.to_radians()).abs() < 1e-15);
        // 0.01 °/s/√Hz over 4 s adds 0.02° in quadrature.
        let (along, _) = table_sigmas(0.01f64.to_radians(), 4.0, 1);
        assert!((along.to_degrees() - 0.1f64.hypot(0.02)).abs() < 1e-12);
    }
}
