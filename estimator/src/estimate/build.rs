//! The fit's problem from the screened segments: the mounts (one attitude each, docs/model.md §7),
//! each segment's mean-output model (with the body's rate through the gyro model when there is one,
//! §8), the gyro's observations, and the starting ups of free attitudes.

use super::model::{self, Mount, SegModel, TiltGeometry};
use super::screen::median;
use super::solve::{GyroDirection, Problem};
use super::{EstimateOptions, Noise, SegmentKind, SessionSeg};
use recording::session::Plan;
use shared::linalg::{self, RowMajor3, IDENTITY};

/// The mounts of the used segments (one attitude each, docs/model.md §7) and each session
/// segment's mount index. A mount is keyed by its name and nominal up; a free mount without an up
/// starts at +z until [`seed_free_mounts`] sets it from the data.
pub(crate) fn build_mounts(plan: &Plan, segs: &[SessionSeg]) -> (Vec<Mount>, Vec<usize>) {
    let mut mounts: Vec<Mount> = Vec::new();
    let mut keys: Vec<String> = Vec::new();
    let mut of_seg = Vec::with_capacity(segs.len());
    for s in segs {
        let sp = &plan.segments[s.plan_idx];
        let key = format!(
            "{}|{:?}",
            sp.mount_name(),
            sp.up_b.map(|v| (v * 1e4).round())
        );
        let k = match keys.iter().position(|q| *q == key) {
            Some(k) => k,
            None => {
                let up = if sp.has_up() {
                    sp.up_b
                } else {
                    [0.0, 0.0, 1.0]
                };
                keys.push(key);
                mounts.push(Mount {
                    name: sp.mount_name(),
                    geometry: TiltGeometry::new(up, mounts.len()),
                    prior_rad: plan.mount_sigma_deg(sp).map(f64::to_radians),
                    up_given: sp.has_up(),
                    spins: false,
                });
                mounts.len() - 1
            }
        };
        if s.used && s.kind != SegmentKind::Static {
            mounts[k].spins = true;
        }
        of_seg.push(k);
    }
    (mounts, of_seg)
}

/// The body's rate through the gyro model (docs/model.md §8): `(G⁻¹, b)`, and under a gyro bias
/// walk each segment's own fitted bias in place of `b` (§11.6).
pub(crate) struct RateCorrection<'a> {
    /// `G⁻¹` and `b`.
    pub gyro: (RowMajor3, [f64; 3]),
    /// `(segment, bias)`: the segments whose rate is corrected with a bias of their own.
    pub seg_bias: &'a [(usize, [f64; 3])],
}

/// Segment models of the used segments. Ramps are weighted with the static noise (their own output
/// variance includes the ramp's signal).
pub(crate) fn build_models(
    plan: &Plan,
    segs: &[SessionSeg],
    noise: &Noise,
    options: &EstimateOptions,
    mounts: &[Mount],
    seg_mount: &[usize],
    correction: Option<&RateCorrection<'_>>,
) -> Vec<SegModel> {
    let g = plan.gravity_m_s2;
    let static_bias = static_gyro(segs);
    let mut out = Vec::new();
    for (k, s) in segs.iter().enumerate() {
        if !s.used {
            continue;
        }
        let sp = &plan.segments[s.plan_idx];
        let st = &s.stats;
        // The body's rate through the gyro model when one is estimated (docs/model.md §8), else
        // through its static reading alone: a gyro's bias is no rotation, and one of hundreds of
        // °/s (raw counts of an unsigned output) would otherwise read as a centripetal term.
        let mut c = correction.map_or((IDENTITY, static_bias), |r| r.gyro);
        if let Some((_, b)) = correction.and_then(|r| r.seg_bias.iter().find(|(q, _)| *q == k)) {
            c.1 = *b;
        }
        let (wwt, wdot) = super::gyro::corrected_moments(
            &st.mean_wwt,
            &st.mean_w_rad_s,
            &st.wdot_rad_s2,
            &noise.gyro_cov,
            &c,
        );
        let ew = model::mean_lever_matrix(&wwt, &wdot, &[[0.0; 3]; 3], options.use_omega_dot);
        let p = sp.table_centre_m.unwrap_or([0.0; 3]);
        let wp = linalg::mat_vec(&ew, &p);
        let centre = core::array::from_fn(|j| -wp[j] / g);
        let e = ew.map(|row| row.map(|v| v / g));
        let per_sample = if s.kind == SegmentKind::Ramp {
            noise.out_cov
        } else {
            st.cov_u
        };
        let n = st.count as f64;
        let mut se: RowMajor3 = per_sample.map(|row| row.map(|v| v / n));
        for i in 0..3 {
            let floor = (1e-9 * st.mean_u[i].abs().max(1e-3)).powi(2);
            se[i][i] = se[i][i].max(floor);
        }
        let tilt = mounts[seg_mount[k]].geometry;
        if let Some(mut m) = SegModel::new(k, tilt, centre, e, st.mean_u, se) {
            m.span_s = [st.t_first_s, st.t_last_s];
            out.push(m);
        }
    }
    out
}

/// The gyro's static reading (its bias as the static majority shows it), rad/s.
pub(crate) fn static_gyro(segs: &[SessionSeg]) -> [f64; 3] {
    let statics: Vec<&SessionSeg> = segs
        .iter()
        .filter(|s| s.used && s.kind == SegmentKind::Static)
        .collect();
    core::array::from_fn(|j| median(statics.iter().map(|s| s.stats.mean_w_rad_s[j]).collect()))
        .map(|v: f64| if v.is_finite() { v } else { 0.0 })
}

/// The measured rotation axis of a spinning segment (bias removed), signed as the planned rate, and
/// its per-axis 1σ of the mean (rad/s): `None` below 1 °/s.
fn spin_axis(
    s: &SessionSeg,
    sp: &recording::session::SegmentPlan,
    noise: &Noise,
    bias: &[f64; 3],
) -> Option<([f64; 3], f64, RowMajor3)> {
    let w: [f64; 3] = core::array::from_fn(|j| s.stats.mean_w_rad_s[j] - bias[j]);
    let n = linalg::norm(&w);
    if n < 1f64.to_radians() {
        return None;
    }
    let planned = sp.rate_deg_s + sp.rate_end_deg_s.unwrap_or(sp.rate_deg_s);
    let sign = if sp.has_up() && !sp.is_free() {
        linalg::dot(&w, &sp.up_b).signum()
    } else {
        planned.signum()
    };
    let cov = if s.kind == SegmentKind::Ramp {
        noise.gyro_cov
    } else {
        s.stats.cov_w
    };
    Some((w.map(|v| v * sign / n), n, cov))
}

/// The gyro axis directions of the used spinning segments (docs/model.md §7): each mean axis,
/// weighted by its noise with a floor of `options.gyro_axis_sigma_rad` (how well the gyro's axes are
/// taken to agree with the body frame).
pub(crate) fn build_gyro(
    plan: &Plan,
    segs: &[SessionSeg],
    noise: &Noise,
    options: &EstimateOptions,
    mounts: &[Mount],
    seg_mount: &[usize],
) -> Vec<GyroDirection> {
    let Some(floor) = options.gyro_axis_sigma_rad else {
        return Vec::new();
    };
    let bias = static_gyro(segs);
    let mut out = Vec::new();
    for (k, s) in segs.iter().enumerate() {
        if !s.used || s.kind == SegmentKind::Static {
            continue;
        }
        let sp = &plan.segments[s.plan_idx];
        let Some((axis, rate, cov)) = spin_axis(s, sp, noise, &bias) else {
            continue;
        };
        let tilt = mounts[seg_mount[k]].geometry;
        let n = s.stats.count.max(1) as f64;
        let e = tilt.basis;
        out.push(GyroDirection {
            seg: k,
            tilt,
            measured: core::array::from_fn(|c| linalg::dot(&axis, &e[c])),
            sigma: core::array::from_fn(|c| {
                let v = linalg::dot(&e[c], &linalg::mat_vec(&cov, &e[c])) / n;
                (v / (rate * rate) + floor * floor).sqrt()
            }),
        });
    }
    out
}

/// The gyro means of the used segments for the gyro model (docs/model.md §8): rest segments at
/// rate 0, spins at the plan's mean table rate. A ramp's own gyro spread is its signal, so it is
/// weighted with the static noise.
pub(crate) fn build_gyro_block(
    plan: &Plan,
    segs: &[SessionSeg],
    noise: &Noise,
    mounts: &[Mount],
    seg_mount: &[usize],
    base: usize,
) -> super::gyro::GyroBlock {
    let mut means = Vec::new();
    for (k, s) in segs.iter().enumerate() {
        if !s.used {
            continue;
        }
        let sp = &plan.segments[s.plan_idx];
        let rate = if s.kind == SegmentKind::Static {
            0.0
        } else {
            (0.5 * (sp.rate_deg_s + sp.rate_end_deg_s.unwrap_or(sp.rate_deg_s))).to_radians()
        };
        let per_sample = if s.kind == SegmentKind::Ramp {
            noise.gyro_cov
        } else {
            s.stats.cov_w
        };
        let n = s.stats.count.max(1) as f64;
        // A floor of 0.1 µrad/s keeps a noise-free (predicted) session's weights finite.
        let se: RowMajor3 = core::array::from_fn(|i| {
            core::array::from_fn(|j| per_sample[i][j] / n + if i == j { 1e-14 } else { 0.0 })
        });
        let tilt = mounts[seg_mount[k]].geometry;
        let span = [s.stats.t_first_s, s.stats.t_last_s];
        let mean = s.stats.mean_w_rad_s;
        if let Some(m) = super::gyro::GyroMean::new(k, tilt, rate, mean, se, span) {
            means.push(m);
        }
    }
    super::gyro::GyroBlock {
        base,
        means,
        rate_sigma_rel: plan.table_rate_sigma_ppm() * 1e-6,
        walk: None,
    }
}

/// Starting ups of free mounts given without one (or with a rough one): from the static fit's
/// compensated mean output of their first static segment, else from the gyro's axis.
pub(crate) fn seed_free_mounts(
    plan: &Plan,
    segs: &[SessionSeg],
    noise: &Noise,
    problem: &mut Problem,
    theta: &[f64],
) {
    let m = model::m_of(theta);
    let u0 = model::u0_of(theta);
    let minv = linalg::inverse(&m);
    let bias = static_gyro(segs);
    for k in 0..problem.mounts.len() {
        if problem.mounts[k].prior_rad.is_some() {
            continue;
        }
        let idx = problem.mounts[k].geometry.index;
        let from_static = problem
            .models
            .iter()
            .find(|md| md.tilt.index == idx && segs[md.seg].kind == SegmentKind::Static)
            .and_then(|md| {
                let du: [f64; 3] = core::array::from_fn(|i| md.mean_u[i] - u0[i]);
                minv.map(|mi| linalg::mat_vec(&mi, &du))
            });
        let from_gyro = || {
            problem
                .models
                .iter()
                .find(|md| md.tilt.index == idx && segs[md.seg].kind != SegmentKind::Static)
                .and_then(|md| {
                    let s = &segs[md.seg];
                    spin_axis(s, &plan.segments[s.plan_idx], noise, &bias).map(|a| a.0)
                })
        };
        if let Some(up) = from_static.or_else(from_gyro) {
            if linalg::norm(&up) > 0.1 {
                problem.set_nominal(k, up);
            }
        }
    }
}
