//! Where the unit points and where to turn it next, in words for the terminal and in numbers for the
//! live page: gravity's direction in body axes from the raw outputs (a rough calibration made from
//! the positions recorded so far), the targets still missing, the one that most shrinks the
//! predicted 1σ, and the turn that reaches it.
//!
//! The rough calibration is only for pointing: the result is the estimator's (docs/model.md §2–§7).
//! A zero-centred output (m/s², g, counts) points along gravity from the first window; an output
//! with an offset (volts) needs its zero, which a diagonal ellipsoid through [`ELLIPSOID_MIN`]
//! spread positions gives (|f| = 1 g at rest, docs/model.md §7).

use nalgebra::{DMatrix, DVector};
use recording::session::segment::FACE_COVERAGE_DEG;
use shared::linalg;

/// Positions an output with an offset needs before its rough zero and scale are known: a diagonal
/// ellipsoid has six unknowns.
pub(crate) const ELLIPSOID_MIN: usize = 6;

/// Parameters of the magnitude-only static model a free attitude determines (docs/model.md §7):
/// three biases and the six entries of the symmetric scale matrix.
const FREE_PARAMS: usize = 9;

/// A rough per-axis zero and scale: enough to say where gravity points.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct RoughScale {
    /// Output at zero specific force, output unit.
    pub zero_out: [f64; 3],
    /// Output per g, output unit.
    pub out_per_g: [f64; 3],
}

impl RoughScale {
    /// The specific force of output `u`, g.
    pub fn force_g(&self, u: &[f64; 3]) -> [f64; 3] {
        core::array::from_fn(|j| (u[j] - self.zero_out[j]) / self.out_per_g[j])
    }
}

/// The rough scale of an output from its still positions' mean outputs: zero at zero for a
/// zero-centred output (its scale the mean magnitude), else the diagonal ellipsoid through them.
pub(crate) fn rough_scale(zero_centred: bool, positions: &[[f64; 3]]) -> Option<RoughScale> {
    if positions.is_empty() {
        return None;
    }
    if zero_centred {
        let g = positions.iter().map(linalg::norm).sum::<f64>() / positions.len() as f64;
        return (g > 0.0).then_some(RoughScale {
            zero_out: [0.0; 3],
            out_per_g: [g; 3],
        });
    }
    if positions.len() < ELLIPSOID_MIN {
        return None;
    }
    // Σ_j A_j v_j² + B_j v_j + C = 0 in outputs less their mean (v), homogeneous in (A, B, C):
    // the eigenvector of the smallest eigenvalue of the normal matrix; then zero_j = −B_j / 2A_j
    // and the scale from the constant the completed squares leave.
    let n = positions.len() as f64;
    let mean: [f64; 3] = core::array::from_fn(|j| positions.iter().map(|u| u[j]).sum::<f64>() / n);
    let spread = positions
        .iter()
        .map(|u| linalg::norm(&core::array::from_fn(|j| u[j] - mean[j])))
        .fold(0.0, f64::max);
    if spread.is_nan() || spread <= 0.0 {
        return None;
    }
    let a = DMatrix::from_fn(positions.len(), 7, |r, c| {
        let v = (positions[r][c % 3] - mean[c % 3]) / spread;
        match c {
            0..=2 => v * v,
            3..=5 => v,
            _ => 1.0,
        }
    });
    let eig = (a.transpose() * &a).symmetric_eigen();
    let smallest = (0..7).min_by(|&i, &j| eig.eigenvalues[i].total_cmp(&eig.eigenvalues[j]))?;
    let mut x = eig.eigenvectors.column(smallest).clone_owned();
    if x[0] < 0.0 {
        x = -x;
    }
    if (0..3).any(|j| x[j].is_nan() || x[j] <= 0.0) {
        return None;
    }
    let centre: [f64; 3] = core::array::from_fn(|j| -x[j + 3] / (2.0 * x[j]));
    let k = -x[6] + (0..3).map(|j| x[j] * centre[j].powi(2)).sum::<f64>();
    if k.is_nan() || k <= 0.0 {
        return None;
    }
    let zero_out = core::array::from_fn(|j| mean[j] + centre[j] * spread);
    let out_per_g = core::array::from_fn(|j| (k / x[j]).sqrt() * spread);
    Some(RoughScale {
        zero_out,
        out_per_g,
    })
}

/// A direction to hold the unit in: gravity's up in body axes.
#[derive(Clone, Debug, PartialEq, serde::Serialize)]
pub struct Target {
    /// What the operator calls it ("+y up", "plan aim 07").
    pub label: String,
    /// Up in body axes (unit vector).
    pub up_b: [f64; 3],
    /// A recorded position lies within the coverage angle of it.
    pub done: bool,
}

/// The six faces of a cube: each body axis up and down ("x up", "x down", …).
pub fn six_faces() -> Vec<Target> {
    let names = ["x", "y", "z"];
    (0..6)
        .map(|f| {
            let mut up = [0.0; 3];
            let sign = if f % 2 == 0 { 1.0 } else { -1.0 };
            up[f / 2] = sign;
            Target {
                label: format!(
                    "{} {}",
                    names[f / 2],
                    if sign > 0.0 { "up" } else { "down" }
                ),
                up_b: up,
                done: false,
            }
        })
        .collect()
}

/// The body axis (with its sign) nearest `d`, and the angle to it, degrees.
fn nearest_axis(d: &[f64; 3]) -> (usize, f64, f64) {
    let k = (0..3)
        .max_by(|&a, &b| d[a].abs().total_cmp(&d[b].abs()))
        .unwrap_or(2);
    let sign = if d[k] >= 0.0 { 1.0 } else { -1.0 };
    let angle = (d[k].abs().clamp(-1.0, 1.0)).acos().to_degrees();
    (k, sign, angle)
}

fn axis_name(k: usize, sign: f64) -> String {
    format!(
        "{}{}",
        if sign > 0.0 { "+" } else { "−" },
        ["x", "y", "z"][k]
    )
}

/// How to reach up `target` (body axes) in the operator's words: which side of the housing goes
/// down ("tilt so that −y points down"), how far the unit leans off it and towards which side, and
/// how far it is from `now` when the current attitude is known.
pub(crate) fn turn_words(now: Option<&[f64; 3]>, target: &[f64; 3]) -> String {
    let t = linalg::unit(target);
    let (k, sign, lean) = nearest_axis(&t);
    let mut words = format!("tilt so that {} points down", axis_name(k, -sign));
    if lean >= 5.0 {
        // The side that dips besides the main one: the largest other component of up, reversed.
        let (j, side) = (0..3)
            .filter(|&j| j != k)
            .map(|j| (j, t[j]))
            .max_by(|a, b| a.1.abs().total_cmp(&b.1.abs()))
            .unwrap_or((0, 0.0));
        words.push_str(&format!(
            ", leaning {lean:.0}° so that {} dips",
            axis_name(j, if side >= 0.0 { -1.0 } else { 1.0 })
        ));
    }
    if let Some(now) = now {
        let angle = linalg::dot(&linalg::unit(now), &t).clamp(-1.0, 1.0).acos();
        words.push_str(&format!(" ({:.0}° from now)", angle.to_degrees()));
    }
    words
}

/// The row a still position at up `d` adds to the magnitude-only model's design (docs/model.md
/// §7): |f|² = 1 linearised in the biases (in g) and the symmetric scale matrix's entries.
fn free_row(d: &[f64; 3]) -> [f64; FREE_PARAMS] {
    [
        d[0],
        d[1],
        d[2],
        d[0] * d[0],
        d[1] * d[1],
        d[2] * d[2],
        2.0 * d[0] * d[1],
        2.0 * d[0] * d[2],
        2.0 * d[1] * d[2],
    ]
}

/// The predicted 1σ of a hand-held session's biases (mg) and scale factors (ppm), worst axis, from
/// the positions' ups and each one's 1σ of the mean specific force, g: the Cramér–Rao bound of the
/// magnitude-only model (docs/model.md §7). `None` until the positions determine all nine.
pub(crate) fn free_sigma(positions: &[([f64; 3], f64)]) -> Option<(f64, f64)> {
    let cov = free_covariance(positions, 0.0)?;
    Some(worst_sigma(&cov, FREE_PARAMS))
}

fn free_covariance(positions: &[([f64; 3], f64)], ridge: f64) -> Option<DMatrix<f64>> {
    if positions.len() < FREE_PARAMS && ridge == 0.0 {
        return None;
    }
    let mut info = DMatrix::<f64>::identity(FREE_PARAMS, FREE_PARAMS) * ridge;
    for (d, sigma_g) in positions {
        let r = DVector::from_row_slice(&free_row(d));
        info += &r * r.transpose() / sigma_g.max(1e-12).powi(2);
    }
    let cov = info.try_inverse()?;
    (0..cov.nrows()).all(|i| cov[(i, i)] > 0.0).then_some(cov)
}

fn worst_sigma(cov: &DMatrix<f64>, n: usize) -> (f64, f64) {
    let bias = (0..3).map(|i| cov[(i, i)]).fold(0.0, f64::max).sqrt();
    let scale = (3..n.min(6))
        .map(|i| cov[(i, i)])
        .fold(0.0, f64::max)
        .sqrt();
    (bias * 1e3, scale * 1e6)
}

/// The predicted 1σ of a table session's biases (mg) and scale factors (ppm), worst axis: each
/// axis's output is linear in the known up (bias and a row of the scale matrix, docs/model.md §2).
/// `None` until four positions not in one plane.
pub(crate) fn table_sigma(positions: &[([f64; 3], f64)]) -> Option<(f64, f64)> {
    let mut info = DMatrix::<f64>::zeros(4, 4);
    for (d, sigma_g) in positions {
        let r = DVector::from_row_slice(&[1.0, d[0], d[1], d[2]]);
        info += &r * r.transpose() / sigma_g.max(1e-12).powi(2);
    }
    let cov = info.try_inverse()?;
    if !(0..4).all(|i| cov[(i, i)] > 0.0) {
        return None;
    }
    let scale = (1..4).map(|i| cov[(i, i)]).fold(0.0, f64::max).sqrt();
    Some((cov[(0, 0)].sqrt() * 1e3, scale * 1e6))
}

/// The targets not yet done, best first: the one whose position most lowers the summed variance of
/// the biases and scale factors (A-optimal) given the positions so far; ties in plan order.
pub(crate) fn rank_targets(positions: &[([f64; 3], f64)], targets: &[Target]) -> Vec<usize> {
    let sigma = positions.iter().map(|p| p.1).fold(f64::INFINITY, f64::min);
    let sigma = if sigma.is_finite() { sigma } else { 1e-3 };
    let score = |t: &Target| {
        let mut with = positions.to_vec();
        with.push((t.up_b, sigma));
        // A small ridge ranks candidates before nine positions determine everything.
        free_covariance(&with, 1e-6 / sigma.powi(2))
            .map_or(f64::INFINITY, |c| (0..6).map(|i| c[(i, i)]).sum::<f64>())
    };
    let mut open: Vec<(usize, f64)> = targets
        .iter()
        .enumerate()
        .filter(|(_, t)| !t.done)
        .map(|(k, t)| (k, score(t)))
        .collect();
    open.sort_by(|a, b| a.1.total_cmp(&b.1).then(a.0.cmp(&b.0)));
    open.into_iter().map(|(k, _)| k).collect()
}

/// Marks the targets that a position at one of `ups` covers (within `within_deg`).
pub(crate) fn mark_done(targets: &mut [Target], ups: &[[f64; 3]], within_deg: f64) {
    let cos = within_deg.to_radians().cos();
    for t in targets.iter_mut() {
        t.done = ups
            .iter()
            .any(|u| linalg::dot(&linalg::unit(u), &linalg::unit(&t.up_b)) >= cos);
    }
}

/// A hand-held session's coverage: the positions recorded (mean outputs and their 1σ), the rough
/// scale they give, and the targets (the six faces, then the plan's aims) with the best next.
#[derive(Clone, Debug, Default)]
pub struct Coverage {
    /// The output is zero at zero force (not volts).
    pub zero_centred: bool,
    /// A position covers a plan's aim within this angle, degrees (a face within
    /// `FACE_COVERAGE_DEG`).
    pub within_deg: f64,
    /// Each position's mean output, output unit.
    pub outputs: Vec<[f64; 3]>,
    /// Each position's 1σ of the mean output per axis, output unit.
    pub sigma_out: Vec<[f64; 3]>,
    /// The six faces and the plan's aims, `done` where a position covers them.
    pub targets: Vec<Target>,
}

impl Coverage {
    /// Coverage of the six faces and `aims` (the plan's free ups).
    pub fn new(zero_centred: bool, within_deg: f64, aims: &[[f64; 3]]) -> Coverage {
        let mut targets = six_faces();
        targets.extend(aims.iter().enumerate().map(|(k, up)| Target {
            label: format!("aim {:02}", k + 1),
            up_b: linalg::unit(up),
            done: false,
        }));
        Coverage {
            zero_centred,
            within_deg,
            targets,
            ..Coverage::default()
        }
    }

    /// Adds a recorded position.
    pub fn add(&mut self, mean_out: [f64; 3], sigma_out: [f64; 3]) {
        self.outputs.push(mean_out);
        self.sigma_out.push(sigma_out);
        if let Some(ups) = self.ups() {
            let (faces, aims) = self.targets.split_at_mut(6);
            mark_done(faces, &ups, FACE_COVERAGE_DEG);
            mark_done(aims, &ups, self.within_deg);
        }
    }

    /// The rough scale the positions give (`None` before an offset output has six).
    pub fn rough(&self) -> Option<RoughScale> {
        rough_scale(self.zero_centred, &self.outputs)
    }

    /// Gravity's up at each position, body axes, once the rough scale is known.
    pub fn ups(&self) -> Option<Vec<[f64; 3]>> {
        let r = self.rough()?;
        Some(
            self.outputs
                .iter()
                .map(|u| linalg::unit(&r.force_g(u)))
                .collect(),
        )
    }

    /// Each position's up and 1σ of its mean specific force (worst axis), g.
    fn weighted(&self) -> Option<Vec<([f64; 3], f64)>> {
        let r = self.rough()?;
        let ups = self.ups()?;
        Some(
            ups.into_iter()
                .zip(&self.sigma_out)
                .map(|(d, s)| {
                    let g = (0..3)
                        .map(|j| s[j] / r.out_per_g[j].abs())
                        .fold(0.0, f64::max);
                    (d, g)
                })
                .collect(),
        )
    }

    /// Predicted 1σ (bias mg, scale ppm; worst axis) of the positions so far.
    pub fn sigma(&self) -> Option<(f64, f64)> {
        free_sigma(&self.weighted()?)
    }

    /// The open targets, best first; in plan order (faces first) before the directions are known.
    pub fn best(&self) -> Vec<usize> {
        match self.weighted() {
            Some(w) => rank_targets(&w, &self.targets),
            None => (0..self.targets.len())
                .filter(|&k| !self.targets[k].done)
                .collect(),
        }
    }

    /// The best open target and the turn that reaches it from the last position, in words.
    pub fn next_step(&self) -> Option<(Target, String)> {
        let k = *self.best().first()?;
        let t = self.targets[k].clone();
        let now = self.ups().and_then(|u| u.last().copied());
        let words = turn_words(now.as_ref(), &t.up_b);
        Some((t, words))
    }

    /// The faces no position is near yet ("x up", "x down", …); empty before the directions are
    /// known.
    pub fn missing_faces(&self) -> Vec<&str> {
        if self.ups().is_none() {
            return Vec::new();
        }
        self.targets[..6]
            .iter()
            .filter(|t| !t.done)
            .map(|t| t.label.as_str())
            .collect()
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn an_offset_output_gets_its_zero_and_scale_from_six_spread_positions() {
        let zero = [2.4, 2.5, 2.45];
        let scale = [0.4, 0.38, 0.42];
        let ups = six_faces().into_iter().map(|t| t.up_b).collect::<Vec<_>>();
        let outs: Vec<[f64; 3]> = ups
            .iter()
            .map(|d| core::array::from_fn(|j| zero[j] + scale[j] * d[j]))
            .collect();
        assert_eq!(rough_scale(false, &outs[..5]), None);
        let r = rough_scale(false, &outs).unwrap();
        for j in 0..3 {
            assert!((r.zero_out[j] - zero[j]).abs() < 1e-9, "{r:?}");
            assert!((r.out_per_g[j] - scale[j]).abs() < 1e-9, "{r:?}");
        }
        let f = r.force_g(&outs[3]);
        assert!((f[1] + 1.0).abs() < 1e-9 && f[0].abs() < 1e-9, "{f:?}");
    }

    #[test]
    fn the_words_name_the_side_that_goes_down_and_the_lean() {
        assert_eq!(
            turn_words(None, &[0.0, 1.0, 0.0]),
            "tilt so that −y points down"
        );
        let w = turn_words(Some(&[0.0, 0.0, 1.0]), &[0.285652, 0.0, 0.958333]);
        assert_eq!(
            w,
            "tilt so that −z points down, leaning 17° so that −x dips (17° from now)"
        );
    }

    #[test]
    fn nine_spread_positions_determine_the_free_model_and_a_missing_face_ranks_first() {
        let faces = six_faces();
        let mut pos: Vec<([f64; 3], f64)> = faces.iter().take(5).map(|t| (t.up_b, 1e-4)).collect();
        assert_eq!(free_sigma(&pos), None);
        // The six faces alone leave the cross terms undetermined; three diagonals fix them.
        let s = 1.0 / 3f64.sqrt();
        pos.extend([[s, s, s], [s, -s, s], [-s, s, s]].map(|d| (d, 1e-4)));
        assert_eq!(pos.len(), 8);
        let mut targets = six_faces();
        mark_done(
            &mut targets,
            &pos.iter().map(|p| p.0).collect::<Vec<_>>(),
            10.0,
        );
        assert_eq!(targets.iter().filter(|t| !t.done).count(), 1);
        let best = rank_targets(&pos, &targets);
        assert_eq!(targets[best[0]].label, "z down");
        pos.push((targets[best[0]].up_b, 1e-4));
        let (bias_mg, scale_ppm) = free_sigma(&pos).unwrap();
        assert!(
            bias_mg > 0.0 && bias_mg < 1.0 && scale_ppm > 0.0,
            "{bias_mg} {scale_ppm}"
        );
    }
}
