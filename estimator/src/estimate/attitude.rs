//! The fixture's attitude unknowns (docs/model.md §7): free attitudes from |gravity| alone, what
//! fixes the body frame, each mount's estimated tilt, and the split of the static uncertainty into
//! the intrinsic part and the body frame's alignment.

use super::model::{self, idx_m, idx_tilt, idx_u0};
use super::solve::{self, Problem};
use super::{EstimateError, SegmentKind, SessionSeg};
use nalgebra::{DMatrix, Matrix3};
use recording::session::plan::Attitude;
use recording::session::Plan;
use shared::linalg::{self, RowMajor3};

/// The entries of `M` fixed at 0 by the frame convention used when nothing else fixes the body
/// frame: body x along accelerometer x's sensing axis, body y in the plane of the x and y sensing
/// axes (`M` lower-triangular; any rotation of the body frame fits |gravity| equally well).
pub(crate) const CONVENTION_FIXED: [usize; 3] = [idx_m(0, 1), idx_m(0, 2), idx_m(1, 2)];

/// What fixes the body frame's orientation (docs/model.md §7, §7.1).
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum BodyFrame {
    /// The fixture: the mounts' nominal ups (within their prior) and, for spinning mounts, the gyro's
    /// rotation axis.
    Fixture {
        /// Mounts with a known nominal up.
        known_mounts: usize,
        /// Mounts whose spin axis the gyro measured.
        gyro_mounts: usize,
    },
    /// The faces of the unit's housing, set down on a bench (`attitude = "face"`): each body axis
    /// along a face's normal, the faces' placement errors averaging to zero within their prior.
    Faces {
        /// Positions taken as set down on a face.
        faces: usize,
        /// The widest of their priors, degrees (1σ per axis).
        prior_deg: f64,
    },
    /// No mount is known: body x along accelerometer x, body y in the x–y sensing plane.
    Convention,
}

impl BodyFrame {
    /// Its short name, as `calibration.toml`'s `[frame]` writes it: `fixture`, `faces` or
    /// `accelerometer`.
    pub fn kind(&self) -> crate::unit_file::FrameKind {
        use crate::unit_file::FrameKind;
        match self {
            BodyFrame::Fixture { .. } => FrameKind::Fixture,
            BodyFrame::Faces { .. } => FrameKind::Faces,
            BodyFrame::Convention => FrameKind::Accelerometer,
        }
    }
}

impl std::fmt::Display for BodyFrame {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match self {
            BodyFrame::Fixture {
                known_mounts,
                gyro_mounts,
            } => write!(
                f,
                "the body frame is fixed by the fixture: {known_mounts} mount(s) with a known up \
                 (within their attitude prior) and the gyro's spin axis on {gyro_mounts} mount(s)"
            ),
            BodyFrame::Faces { faces, prior_deg } => write!(
                f,
                "the body frame is the housing's: each body axis along the normal of a face the \
                 unit was set down on ({faces} position(s) on a face, each within its {prior_deg}° \
                 prior; their placement errors average to zero)"
            ),
            BodyFrame::Convention => write!(
                f,
                "no attitude is known, so the body frame is a convention: x along accelerometer x's \
                 sensing axis, y in the plane of the x and y sensing axes (M lower-triangular)"
            ),
        }
    }
}

/// The proper rotation `R` minimising Σ |R a_k − b_k|² (Kabsch): what a result in a conventional
/// body frame (`BodyFrame::Convention`) is compared through, since any rotation of that frame fits
/// the data equally well (docs/model.md §7). `None` only if the 3×3 SVD does not converge.
pub fn best_rotation(a: &[[f64; 3]], b: &[[f64; 3]]) -> Option<Matrix3<f64>> {
    let mut h = Matrix3::zeros();
    for (x, y) in a.iter().zip(b) {
        for i in 0..3 {
            for j in 0..3 {
                h[(i, j)] += y[i] * x[j];
            }
        }
    }
    let svd = h.svd(true, true);
    let (u, vt): (Matrix3<f64>, Matrix3<f64>) = (svd.u?, svd.v_t?);
    let d = (u * vt).determinant().signum();
    Some(u * Matrix3::from_diagonal(&nalgebra::Vector3::new(1.0, 1.0, d)) * vt)
}

/// Each mount's estimated attitude.
#[derive(Clone, Debug, PartialEq)]
pub struct MountTilt {
    /// Mount name.
    pub name: String,
    /// Prior 1σ per axis, degrees; `None`: free attitude.
    pub prior_deg: Option<f64>,
    /// Estimated true up, body axes.
    pub up_b: [f64; 3],
    /// The nominal (or, free, the starting) up.
    pub nominal_up_b: [f64; 3],
    /// Angle from the nominal up, degrees.
    pub tilt_deg: f64,
    /// 1σ of the estimated up's direction, per axis (rms of the two), degrees.
    pub sigma_deg: f64,
    /// Whether its tilt was estimated (false: exact fixture, or no data).
    pub estimated: bool,
}

/// The static calibration's uncertainty split in two (docs/model.md §7): the intrinsic part (what a
/// perfect fixture could not improve on: biases, scale factors, non-orthogonality) and the rotation
/// of the body frame (which cannot be better than what fixes the frame).
#[derive(Clone, Debug, PartialEq)]
pub struct StaticSplit {
    /// What fixes the body frame.
    pub frame: BodyFrame,
    /// 1σ of the biases, g.
    pub bias_1sigma_g: [f64; 3],
    /// 1σ of the scale factors, relative.
    pub scale_1sigma_rel: [f64; 3],
    /// 1σ of the three non-orthogonality angles (y from x, z from x, z from y), rad.
    pub nonorthogonality_1sigma_rad: [f64; 3],
    /// 1σ of the body frame's alignment, small rotations about body x, y, z, rad.
    pub alignment_1sigma_rad: [f64; 3],
}

/// `M = L Q`: `L` lower-triangular with a positive diagonal, `Q` orthogonal (the rotation from the
/// body frame to the accelerometers' own frame).
pub(crate) fn lq(m: &RowMajor3) -> (RowMajor3, RowMajor3) {
    let mt = Matrix3::from_fn(|i, j| m[j][i]);
    let qr = mt.qr();
    let (q, r) = (qr.q(), qr.r());
    // Mᵀ = q r  ⇒  M = rᵀ qᵀ; flip signs so that diag(L) > 0.
    let s: [f64; 3] = core::array::from_fn(|i| if r[(i, i)] < 0.0 { -1.0 } else { 1.0 });
    let l = core::array::from_fn(|i| core::array::from_fn(|j| r[(j, i)] * s[j]));
    let qq = core::array::from_fn(|i| core::array::from_fn(|j| q[(j, i)] * s[i]));
    (l, qq)
}

/// The small rotation vector of an orthogonal matrix close to the identity.
pub(crate) fn rotation_vector(q: &RowMajor3) -> [f64; 3] {
    [
        0.5 * (q[2][1] - q[1][2]),
        0.5 * (q[0][2] - q[2][0]),
        0.5 * (q[1][0] - q[0][1]),
    ]
}

/// The split's values of `(M, u0)`: biases (g, as the zero-g output error `δu0_i / k_i` at the
/// estimate's scale `k0`), log scale factors, non-orthogonality (rad) and the alignment rotation
/// (rad), 12 in all.
fn split_values(m: &RowMajor3, u0: &[f64; 3], k0: &[f64; 3]) -> [f64; 12] {
    let (l, q) = lq(m);
    let k: [f64; 3] = core::array::from_fn(|i| linalg::norm(&l[i]));
    let rot = rotation_vector(&q);
    let mut v = [0.0; 12];
    for i in 0..3 {
        v[i] = u0[i] / k0[i];
        v[3 + i] = k[i].ln();
        v[9 + i] = rot[i];
    }
    v[6] = l[1][0] / k[1];
    v[7] = l[2][0] / k[2];
    v[8] = l[2][1] / k[2];
    v
}

/// The split of the static 1σ, by the numerical Jacobian of the split values through θ's covariance.
pub(crate) fn static_split(theta: &[f64], cov: &DMatrix<f64>, frame: BodyFrame) -> StaticSplit {
    let idx: Vec<usize> = (0..3)
        .flat_map(|i| [idx_m(i, 0), idx_m(i, 1), idx_m(i, 2), idx_u0(i)])
        .collect();
    let m0 = model::m_of(theta);
    let k0: [f64; 3] = core::array::from_fn(|i| linalg::norm(&m0[i]));
    let base = |t: &[f64]| split_values(&model::m_of(t), &model::u0_of(t), &k0);
    let mut jac = DMatrix::<f64>::zeros(12, idx.len());
    for (c, &p) in idx.iter().enumerate() {
        let h = 1e-7 * theta[p].abs().max(1e-6 * theta[idx_m(p / 7, p / 7)].abs());
        let mut tp = theta.to_vec();
        let mut tm = theta.to_vec();
        tp[p] += h;
        tm[p] -= h;
        let (a, b) = (base(&tp), base(&tm));
        for r in 0..12 {
            jac[(r, c)] = (a[r] - b[r]) / (2.0 * h);
        }
    }
    let sub = DMatrix::from_fn(idx.len(), idx.len(), |a, b| cov[(idx[a], idx[b])]);
    let c = &jac * sub * jac.transpose();
    let s = |r: usize| c[(r, r)].max(0.0).sqrt();
    StaticSplit {
        frame,
        bias_1sigma_g: core::array::from_fn(s),
        scale_1sigma_rel: core::array::from_fn(|i| s(3 + i)),
        nonorthogonality_1sigma_rad: core::array::from_fn(|i| s(6 + i)),
        alignment_1sigma_rad: core::array::from_fn(|i| s(9 + i)),
    }
}

/// Which tilt entries the joint fit estimates: a mount's, unless it is exact (prior 0) or no used
/// segment sees it.
pub(crate) fn tilt_free(problem: &Problem, free: &mut [bool]) {
    for (k, m) in problem.mounts.iter().enumerate() {
        let idx = m.geometry.index;
        let seen = problem.models.iter().any(|s| s.tilt.index == idx)
            || problem.gyro.iter().any(|g| g.tilt.index == idx)
            || problem.gyro_block.as_ref().is_some_and(|b| {
                b.means
                    .iter()
                    .any(|g| g.rate_rad_s != 0.0 && g.tilt.index == idx)
            });
        let on = seen && m.prior_rad != Some(0.0);
        free[idx_tilt(k, 0)] = on;
        free[idx_tilt(k, 1)] = on;
    }
}

/// What fixes the body frame: the known mounts and gyro axes when they give two directions that are
/// not parallel, else the convention. Known mounts that are all faces of the housing (`plan`'s
/// `attitude = "face"`, no fixture mount, no spin) make it the housing's frame.
pub(crate) fn body_frame(problem: &Problem, plan: &Plan) -> BodyFrame {
    let mut dirs: Vec<[f64; 3]> = Vec::new();
    let (mut known, mut gyro) = (0, 0);
    let mut widest_rad: f64 = 0.0;
    for m in &problem.mounts {
        let idx = m.geometry.index;
        let seen = problem.models.iter().any(|s| s.tilt.index == idx);
        let spun = problem.gyro.iter().any(|g| g.tilt.index == idx);
        if let (true, Some(prior)) = (seen, m.prior_rad) {
            known += 1;
            widest_rad = widest_rad.max(prior);
        }
        if spun {
            gyro += 1;
        }
        if (seen && m.prior_rad.is_some()) || spun {
            dirs.push(m.geometry.up_nominal_b);
        }
    }
    let spread = dirs.iter().any(|a| {
        dirs.iter()
            .any(|b| linalg::norm(&linalg::cross(a, b)) > 0.2)
    });
    let faces = plan
        .segments
        .iter()
        .filter(|s| s.attitude != Attitude::Free)
        .all(|s| s.attitude == Attitude::Face);
    match (spread, faces && gyro == 0) {
        (false, _) => BodyFrame::Convention,
        (true, true) => BodyFrame::Faces {
            faces: known,
            prior_deg: (widest_rad.to_degrees() * 1e3).round() / 1e3,
        },
        (true, false) => BodyFrame::Fixture {
            known_mounts: known,
            gyro_mounts: gyro,
        },
    }
}

/// Moves each free mount's nominal up to its estimate and zeroes its tilt, so that later fits
/// linearise about the estimate.
pub(crate) fn recentre_free(problem: &mut Problem, theta: &mut [f64]) {
    for k in 0..problem.mounts.len() {
        if problem.mounts[k].prior_rad.is_some() {
            continue;
        }
        let up = problem.mounts[k].geometry.up(theta);
        problem.set_nominal(k, up);
        theta[idx_tilt(k, 0)] = 0.0;
        theta[idx_tilt(k, 1)] = 0.0;
    }
}

/// Static positions (distinct mounts) a fit with every attitude free needs: three equations per
/// position against two tilts per position and the nine intrinsic parameters the frame leaves free
/// (3n ≥ 2n + 9, docs/model.md §7).
pub(crate) const FREE_POSITIONS_NEEDED: usize = 9;

/// The static fit when the fixture's static attitudes do not determine `M` and `u0` but at least
/// nine static mounts (free or not) do: |gravity| fixes the intrinsic parameters; the known mounts
/// (or the convention) fix the frame. Starts from the per-axis output range (`u0` at its middle,
/// scale from its half-width), the free ups from that start.
pub(crate) fn free_static_fit(
    plan: &Plan,
    segs: &[SessionSeg],
    noise: &super::Noise,
    problem: &mut Problem,
    fallback: EstimateError,
) -> Result<(solve::Fit, BodyFrame), EstimateError> {
    let is_static = |seg: usize| segs[seg].kind == SegmentKind::Static;
    let statics: Vec<usize> = (0..problem.models.len())
        .filter(|&k| is_static(problem.models[k].seg))
        .collect();
    let static_mounts: std::collections::HashSet<usize> = statics
        .iter()
        .map(|&k| problem.models[k].tilt.index)
        .collect();
    if static_mounts.len() < FREE_POSITIONS_NEEDED
        || problem.mounts.iter().all(|m| m.prior_rad.is_some())
    {
        return Err(fallback);
    }
    let n = problem.n_params();
    let mut t = vec![0.0; n];
    for i in 0..3 {
        let (lo, hi) = statics
            .iter()
            .map(|&k| problem.models[k].mean_u[i])
            .fold((f64::INFINITY, f64::NEG_INFINITY), |(a, b), v| {
                (a.min(v), b.max(v))
            });
        t[idx_u0(i)] = 0.5 * (lo + hi);
        t[idx_m(i, i)] = 0.5 * (hi - lo);
    }
    let mut sub = Problem::new(
        statics.iter().map(|&k| problem.models[k].clone()).collect(),
        problem.mounts.clone(),
    );
    sub.drift = problem.drift.clone();
    super::build::seed_free_mounts(plan, segs, noise, &mut sub, &t);
    let frame = body_frame(&sub, plan);
    let mut free = super::screen::static_free(n);
    tilt_free(&sub, &mut free);
    if frame == BodyFrame::Convention {
        for p in CONVENTION_FIXED {
            free[p] = false;
        }
    }
    let mut fit = solve::fit(&sub, t, free.clone(), "free-attitude static fit")?;
    // A second pass about the estimated ups (the first may have started tens of degrees off).
    recentre_free(&mut sub, &mut fit.theta);
    let fit = solve::fit(&sub, fit.theta, free, "free-attitude static fit")?;
    for k in 0..problem.mounts.len() {
        problem.set_nominal(k, sub.mounts[k].geometry.up_nominal_b);
    }
    Ok((fit, frame))
}

/// Each mount's estimated attitude at θ with its 1σ.
pub(crate) fn mount_tilts(
    problem: &Problem,
    theta: &[f64],
    cov: &DMatrix<f64>,
    free: &[bool],
) -> Vec<MountTilt> {
    problem
        .mounts
        .iter()
        .map(|m| {
            let g = &m.geometry;
            let up = g.up(theta);
            let cos = linalg::dot(&up, &g.up_nominal_b).clamp(-1.0, 1.0);
            let (i, j) = (g.index, g.index + 1);
            let var = 0.5 * (cov[(i, i)] + cov[(j, j)]);
            MountTilt {
                name: m.name.clone(),
                prior_deg: m.prior_rad.map(f64::to_degrees),
                up_b: up,
                nominal_up_b: g.up_nominal_b,
                tilt_deg: cos.acos().to_degrees(),
                sigma_deg: var.max(0.0).sqrt().to_degrees(),
                estimated: free[i],
            }
        })
        .collect()
}

/// A warning for mounts tilted more than 3× their declared prior.
pub(crate) fn tilt_warning(tilts: &[MountTilt]) -> Option<super::note::Note> {
    let mounts: Vec<MountTilt> = tilts
        .iter()
        .filter(|t| t.estimated && t.prior_deg.is_some_and(|p| p > 0.0 && t.tilt_deg > 3.0 * p))
        .cloned()
        .collect();
    (!mounts.is_empty()).then_some(super::note::Note::MountsTilted { mounts })
}
