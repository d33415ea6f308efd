//! Matching plan and data, screening segments (empty, saturated, moving, wrong rate, wrong attitude),
//! building the segment models and the static least squares.

use super::model::{self, idx_m, idx_u0, Mount, SegModel};
use super::note::Note;
use super::outcome::{RATE_TOLERANCE_DEG_S, RATE_TOLERANCE_FRACTION};
use super::solve::Problem;
use super::{
    solve, EstimateError, EstimateOptions, Exclusion, ExclusionReason, Noise, ReferenceChoice,
    SegmentKind, SessionSeg,
};
use recording::session::{Plan, SegmentStats};
use shared::linalg;
use shared::ReferencePoint;
use std::collections::HashMap;

/// Pairs plan segments with their statistics, in plan order.
pub(crate) fn match_plan(
    plan: &Plan,
    stats: &[SegmentStats],
    options: &EstimateOptions,
    excluded: &mut Vec<Exclusion>,
    warnings: &mut Vec<Note>,
) -> Result<Vec<SessionSeg>, EstimateError> {
    let mut by_name: HashMap<&str, &SegmentStats> = HashMap::new();
    for s in stats {
        if by_name.contains_key(s.name.as_str()) {
            excluded.push(Exclusion {
                name: s.name.clone(),
                reason: ExclusionReason::Duplicate,
            });
            continue;
        }
        by_name.insert(s.name.as_str(), s);
        if plan.segment(&s.name).is_none() {
            if options.strict_segments {
                return Err(EstimateError::UnknownSegment {
                    name: s.name.clone(),
                });
            }
            warnings.push(Note::SegmentNotInPlan {
                segment: s.name.clone(),
            });
            excluded.push(Exclusion {
                name: s.name.clone(),
                reason: ExclusionReason::NotInPlan,
            });
        }
    }
    let mut out = Vec::new();
    for (plan_idx, sp) in plan.segments.iter().enumerate() {
        match by_name.get(sp.name.as_str()) {
            Some(st) => out.push(SessionSeg {
                plan_idx,
                stats: (*st).clone(),
                kind: SegmentKind::of(sp),
                used: true,
            }),
            None => {
                if options.strict_segments {
                    return Err(EstimateError::MissingSegment {
                        name: sp.name.clone(),
                    });
                }
                warnings.push(Note::SegmentMissingFromData {
                    segment: sp.name.clone(),
                });
                excluded.push(Exclusion {
                    name: sp.name.clone(),
                    reason: ExclusionReason::MissingFromData,
                });
            }
        }
    }
    Ok(out)
}

/// The median (the mean of the two middle values for an even count); NaN when empty.
pub fn median(mut v: Vec<f64>) -> f64 {
    if v.is_empty() {
        return f64::NAN;
    }
    v.sort_by(f64::total_cmp);
    let n = v.len();
    if n % 2 == 1 {
        v[n / 2]
    } else {
        0.5 * (v[n / 2 - 1] + v[n / 2])
    }
}

fn finite_stats(s: &SegmentStats) -> bool {
    s.mean_u
        .iter()
        .chain(s.mean_w_rad_s.iter())
        .chain(s.wdot_rad_s2.iter())
        .chain(s.cov_u.iter().flatten())
        .chain(s.cov_w.iter().flatten())
        .chain(s.mean_wwt.iter().flatten())
        .all(|v| v.is_finite())
}

pub(super) fn exclude(
    segs: &mut [SessionSeg],
    k: usize,
    plan: &Plan,
    reason: ExclusionReason,
    out: &mut Vec<Exclusion>,
) {
    segs[k].used = false;
    out.push(Exclusion {
        name: plan.segments[segs[k].plan_idx].name.clone(),
        reason,
    });
}

/// Output `i` of segment `k` is constant over the segment and that is a fault: the other outputs of
/// the segment vary (so the recording has noise), or another segment shows the very same constant
/// (the output does not respond to attitude). A noise-free recording (a simulation without noise, or
/// outputs averaged over long windows) is constant everywhere without being stuck.
fn stuck(segs: &[SessionSeg], k: usize, i: usize) -> bool {
    let st = &segs[k].stats;
    if st.max_u[i] != st.min_u[i] {
        return false;
    }
    let others_vary = (0..3).any(|j| st.max_u[j] != st.min_u[j]);
    let same_elsewhere = segs.iter().enumerate().any(|(m, o)| {
        m != k
            && o.stats.count >= 2
            && o.stats.max_u[i] == o.stats.min_u[i]
            && o.stats.max_u[i] == st.max_u[i]
    });
    others_vary || same_elsewhere
}

/// Leaves out empty, non-finite, saturated and moving segments and rates that contradict the plan.
pub(crate) fn screen(
    plan: &Plan,
    segs: &mut [SessionSeg],
    options: &EstimateOptions,
    excluded: &mut Vec<Exclusion>,
) {
    screen_unusable(plan, segs, options, excluded);
    super::screen_motion::screen_motion(plan, segs, options, excluded);
    screen_rates(plan, segs, excluded);
}

/// Leaves out segments with too few rows, non-finite statistics or a saturated output.
fn screen_unusable(
    plan: &Plan,
    segs: &mut [SessionSeg],
    options: &EstimateOptions,
    excluded: &mut Vec<Exclusion>,
) {
    for k in 0..segs.len() {
        let st = &segs[k].stats;
        if st.count < 2 {
            let reason = ExclusionReason::Empty {
                rows: st.count,
                rejected: st.rejected_rows,
            };
            exclude(segs, k, plan, reason, excluded);
            continue;
        }
        if !finite_stats(st) {
            exclude(segs, k, plan, ExclusionReason::NonFinite, excluded);
            continue;
        }
        if let Some((axis, detail)) = saturation(segs, k, options) {
            exclude(
                segs,
                k,
                plan,
                ExclusionReason::Saturated { axis, detail },
                excluded,
            );
        }
    }
}

/// The first output of segment `k` that is stuck or reaches the configured range, with the reason.
fn saturation(segs: &[SessionSeg], k: usize, options: &EstimateOptions) -> Option<(usize, String)> {
    let st = &segs[k].stats;
    for i in 0..3 {
        if stuck(segs, k, i) {
            return Some((
                i,
                format!(
                    "output constant at {} for all {} rows (stuck, or clipped at a rail)",
                    st.max_u[i], st.count
                ),
            ));
        }
        if let Some([lo, hi]) = options.output_range {
            if st.min_u[i] <= lo || st.max_u[i] >= hi {
                return Some((
                    i,
                    format!(
                        "output reaches the range limit [{lo}, {hi}] (min {}, max {})",
                        st.min_u[i], st.max_u[i]
                    ),
                ));
            }
        }
    }
    None
}

/// Leaves out rotating segments whose gyro contradicts the plan's rate.
fn screen_rates(plan: &Plan, segs: &mut [SessionSeg], excluded: &mut Vec<Exclusion>) {
    for k in 0..segs.len() {
        if !segs[k].used || segs[k].kind == SegmentKind::Static {
            continue;
        }
        let sp = &plan.segments[segs[k].plan_idx];
        let planned = 0.5 * (sp.rate_deg_s + sp.rate_end_deg_s.unwrap_or(sp.rate_deg_s));
        let w = &segs[k].stats.mean_w_rad_s;
        let measured = if sp.is_free() {
            // The axis is unknown: only the magnitude can contradict the plan.
            linalg::norm(w).to_degrees() * planned.signum()
        } else {
            linalg::dot(w, &sp.up_b).to_degrees()
        };
        if (measured - planned).abs()
            > RATE_TOLERANCE_FRACTION * planned.abs() + RATE_TOLERANCE_DEG_S
        {
            let reason = ExclusionReason::RateContradiction {
                measured_deg_s: measured,
                planned_deg_s: planned,
            };
            exclude(segs, k, plan, reason, excluded);
        }
    }
}

/// Per-sample noise seen on the used static segments.
pub(crate) fn pooled_noise(segs: &[SessionSeg]) -> Noise {
    Noise::pooled(
        segs.iter()
            .filter(|s| s.used && s.kind == SegmentKind::Static)
            .map(|s| &s.stats),
    )
}

/// Directions along which the attitudes `ups` do not spread (empty when they span 3-D affinely).
pub(crate) fn missing_directions(ups: &[[f64; 3]]) -> Vec<[f64; 3]> {
    let n = ups.len() as f64;
    let mean: [f64; 3] =
        core::array::from_fn(|j| ups.iter().map(|u| u[j]).sum::<f64>() / n.max(1.0));
    let scatter = nalgebra::Matrix3::from_fn(|a, b| {
        ups.iter()
            .map(|u| (u[a] - mean[a]) * (u[b] - mean[b]))
            .sum::<f64>()
            / n.max(1.0)
    });
    let eig = scatter.symmetric_eigen();
    (0..3)
        .filter(|&c| eig.eigenvalues[c] < 0.02)
        .map(|c| {
            let v = eig.eigenvectors.column(c);
            [v[0], v[1], v[2]]
        })
        .collect()
}

pub(crate) fn static_free(n_params: usize) -> Vec<bool> {
    let mut free = vec![false; n_params];
    for i in 0..3 {
        for j in 0..3 {
            free[idx_m(i, j)] = true;
        }
        free[idx_u0(i)] = true;
    }
    free
}

fn static_start(models: &[&SegModel], n_params: usize) -> Vec<f64> {
    // Any non-degenerate start: the static model is linear, Gauss–Newton solves it in one step.
    let mut t = vec![0.0; n_params];
    for i in 0..3 {
        let mean: f64 =
            models.iter().map(|m| m.mean_u[i]).sum::<f64>() / models.len().max(1) as f64;
        t[idx_u0(i)] = mean;
        t[idx_m(i, i)] = 1.0;
    }
    t
}

/// Static least squares on the given models (lever arms fixed at 0: static segments do not see them).
pub(crate) fn static_fit(
    models: &[&SegModel],
    mounts: &[Mount],
    drift: Option<&super::drift::Drift>,
) -> Result<solve::Fit, EstimateError> {
    let mut problem = Problem::new(
        models.iter().map(|m| (*m).clone()).collect(),
        mounts.to_vec(),
    );
    problem.drift = drift.cloned();
    let n = problem.n_params();
    solve::fit(
        &problem,
        static_start(models, n),
        static_free(n),
        "static least squares",
    )
}

/// The static fit: on the fixture's (known-attitude) static segments, or, without enough known
/// attitudes, with every attitude free (docs/model.md §7); free mounts then start from it.
pub(crate) fn static_stage(
    plan: &Plan,
    segs: &mut [SessionSeg],
    noise: &Noise,
    problem: &mut Problem,
    options: &EstimateOptions,
    excluded: &mut Vec<Exclusion>,
    planned_static: usize,
) -> Result<solve::Fit, EstimateError> {
    match static_fit_with_attitude_check(plan, segs, problem, options, excluded, planned_static) {
        Ok(fit) => {
            super::build::seed_free_mounts(plan, segs, noise, problem, &fit.theta);
            Ok(fit)
        }
        Err(
            e @ (EstimateError::NoStaticSegments { .. } | EstimateError::TooFewAttitudes { .. }),
        ) => {
            if let Some(refusal) = too_few_positions(plan, segs, problem, excluded) {
                return Err(refusal);
            }
            Ok(super::attitude::free_static_fit(plan, segs, noise, problem, e)?.0)
        }
        Err(e) => Err(e),
    }
}

/// The refusal of a session whose static positions have free attitudes (a hand-held or six-face
/// session) when fewer are left than the free-attitude fit needs (docs/model.md §7): the positions
/// left against those needed, and every segment left out with its figure and limit.
fn too_few_positions(
    plan: &Plan,
    segs: &[SessionSeg],
    problem: &Problem,
    excluded: &[Exclusion],
) -> Option<EstimateError> {
    let free_static = |sp: &recording::session::SegmentPlan| sp.is_static() && sp.is_free();
    if !plan.segments.iter().any(free_static) {
        return None;
    }
    let left: std::collections::HashSet<usize> = problem
        .models
        .iter()
        .filter(|m| segs[m.seg].kind == SegmentKind::Static)
        .map(|m| m.tilt.index)
        .collect();
    let needed = super::attitude::FREE_POSITIONS_NEEDED;
    (left.len() < needed).then(|| EstimateError::TooFewPositions {
        left: left.len(),
        needed,
        planned: plan.segments.iter().filter(|s| s.is_static()).count(),
        dropped: excluded.iter().map(|e| e.to_string()).collect(),
    })
}

/// |M⁻¹(ū − u0) − up| of each static segment under a fit, g.
fn attitude_errors(fit: &solve::Fit, models: &[&SegModel], ups: &[[f64; 3]]) -> Vec<f64> {
    let m = model::m_of(&fit.theta);
    let u0 = model::u0_of(&fit.theta);
    let Some(minv) = linalg::inverse(&m) else {
        return vec![f64::INFINITY; models.len()];
    };
    models
        .iter()
        .zip(ups)
        .map(|(md, up)| {
            let du: [f64; 3] = core::array::from_fn(|i| md.mean_u[i] - u0[i]);
            let d = linalg::mat_vec(&minv, &du);
            linalg::norm(&core::array::from_fn(|j| d[j] - up[j]))
        })
        .collect()
}

/// The static fit on the fixture's (known-attitude) static segments, after leaving out those whose
/// attitude contradicts the plan (leave-one-out: each static segment is predicted from the others).
pub(crate) fn static_fit_with_attitude_check(
    plan: &Plan,
    segs: &mut [SessionSeg],
    problem: &mut Problem,
    options: &EstimateOptions,
    excluded: &mut Vec<Exclusion>,
    planned_static: usize,
) -> Result<solve::Fit, EstimateError> {
    let tol_g = 2.0 * (0.5 * options.attitude_tolerance_deg.to_radians()).sin();
    let mounts = problem.mounts.clone();
    loop {
        let models = &problem.models;
        let statics: Vec<usize> = (0..models.len())
            .filter(|&k| {
                let sp = &plan.segments[segs[models[k].seg].plan_idx];
                segs[models[k].seg].kind == SegmentKind::Static && !sp.is_free()
            })
            .collect();
        if statics.is_empty() {
            return Err(EstimateError::NoStaticSegments {
                planned: planned_static,
                reasons: excluded.iter().map(|e| e.to_string()).collect(),
            });
        }
        let ups: Vec<[f64; 3]> = statics
            .iter()
            .map(|&k| plan.segments[segs[models[k].seg].plan_idx].up_b)
            .collect();
        let missing = missing_directions(&ups);
        if !missing.is_empty() || ups.len() < 4 {
            return Err(EstimateError::TooFewAttitudes {
                attitudes: ups.len(),
                needed_directions: missing,
                dropped: excluded.iter().map(|e| e.to_string()).collect(),
            });
        }
        // Fast path: when the fit on all static segments leaves every one within a tenth of the
        // tolerance, no segment can hide a wrong attitude (its leverage is < 1 − 1/10).
        let refs: Vec<&SegModel> = statics.iter().map(|&k| &models[k]).collect();
        let all = static_fit(&refs, &mounts, problem.drift.as_ref())?;
        let all_err = attitude_errors(&all, &refs, &ups);
        if all_err.iter().all(|e| *e < 0.1 * tol_g) {
            return Ok(all);
        }
        // Leave one out: the segment whose removal makes the others consistent is the suspect; it is
        // excluded when the others' fit puts it further than the tolerance from its planned attitude.
        let mut best: Option<(usize, f64, f64)> = None; // (model index, rest's worst error, its own error)
        if statics.len() >= 5 {
            for (a, &k) in statics.iter().enumerate() {
                let mut rest_ups = ups.clone();
                rest_ups.remove(a);
                if !missing_directions(&rest_ups).is_empty() {
                    continue;
                }
                let rest: Vec<&SegModel> = statics
                    .iter()
                    .filter(|&&q| q != k)
                    .map(|&q| &models[q])
                    .collect();
                let Ok(fit) = static_fit(&rest, &mounts, problem.drift.as_ref()) else {
                    continue;
                };
                let rest_worst = attitude_errors(&fit, &rest, &rest_ups)
                    .into_iter()
                    .fold(0.0, f64::max);
                let own = attitude_errors(&fit, &[&models[k]], &[ups[a]])[0];
                if best.is_none_or(|b| rest_worst < b.1) {
                    best = Some((k, rest_worst, own));
                }
            }
        }
        let worst = best.map(|(k, _, own)| (k, own));
        // A segment whose plan gives its attitude a prior (a six-face session's faces, placed by
        // hand) contradicts it only beyond three of that prior's σ (docs/model.md §7.1).
        let tol_of = |k: usize| {
            let prior = plan.segments[segs[models[k].seg].plan_idx].attitude_sigma_deg;
            let deg = options
                .attitude_tolerance_deg
                .max(3.0 * prior.unwrap_or(0.0));
            tol_g.max(2.0 * (0.5 * deg.to_radians()).sin())
        };
        match worst {
            Some((k, err)) if err > tol_of(k) => {
                let seg = models[k].seg;
                let limit_deg = super::chord_to_angle_deg(tol_of(k));
                segs[seg].used = false;
                excluded.push(Exclusion {
                    name: plan.segments[segs[seg].plan_idx].name.clone(),
                    reason: ExclusionReason::AttitudeContradiction {
                        angle_deg: super::chord_to_angle_deg(err),
                        prior_sigma_deg: plan.segments[segs[seg].plan_idx].attitude_sigma_deg,
                        limit_deg,
                    },
                });
                problem.remove_segment(seg);
            }
            _ => return Ok(all),
        }
    }
}

/// How the fit's lever arms map to the reported ones.
#[derive(Clone, Copy, Debug, PartialEq)]
pub(crate) enum Shift {
    None,
    Centroid,
    Point([f64; 3]),
}

/// The reported reference point.
#[derive(Clone, Copy, Debug, PartialEq)]
pub(crate) struct Frame {
    pub reference: ReferencePoint,
    pub shift: Shift,
}

/// The frame of the reported lever arms (`docs/model.md` §4.5).
pub(crate) fn reference_frame(
    plan: &Plan,
    options: &EstimateOptions,
    warnings: &mut Vec<Note>,
) -> Frame {
    let centres: Vec<[f64; 3]> = plan
        .segments
        .iter()
        .filter_map(|s| s.table_centre_m)
        .collect();
    let common = centres.first().copied();
    if centres.is_empty() {
        // Without rotation no lever arm is calibrated, so their reference point says nothing.
        if options.reference == ReferenceChoice::TableAxis && super::fit::rotates(plan) {
            warnings.push(Note::NoTableCentre {
                single_package: options.single_package,
            });
        }
    } else if centres.iter().any(|c| Some(*c) != common) || centres.len() < plan.segments.len() {
        warnings.push(Note::TableCentreDiffers);
    }
    let p = common.unwrap_or([0.0; 3]);
    let neg = |o: [f64; 3]| -> [f64; 3] { core::array::from_fn(|j| o[j] - p[j]) };
    match options.reference {
        ReferenceChoice::TableAxis if centres.is_empty() => Frame {
            reference: ReferencePoint::TableAxis,
            shift: Shift::None,
        },
        ReferenceChoice::TableAxis => Frame {
            reference: ReferencePoint::BodyPoint {
                offset_m: neg([0.0; 3]),
            },
            shift: Shift::None,
        },
        ReferenceChoice::Centroid => Frame {
            reference: ReferencePoint::Centroid,
            shift: Shift::Centroid,
        },
        ReferenceChoice::BodyPoint(o) => Frame {
            reference: ReferencePoint::BodyPoint { offset_m: neg(o) },
            shift: Shift::Point(o),
        },
    }
}
