//! The joint fit (docs/model.md §7–8): all used segments, the gyro's observations and the mounts'
//! attitude priors, excluding segments whose residual shows a wrong attitude; with the gyro model,
//! the lever terms rerun on the body's rate through the estimated `G`, `b`.

use super::gyro::GyroEstimate;
use super::gyro_drift;
use super::solve::{self, Problem};
use super::{
    attitude, build, chord_to_angle_deg, model, BodyFrame, EstimateError, EstimateOptions,
    Exclusion, ExclusionReason, Noise, SegmentKind, SessionSeg,
};
use recording::session::Plan;
use shared::linalg;

/// What rebuilding the segment models needs.
pub(crate) struct Context<'a> {
    pub plan: &'a Plan,
    pub noise: &'a Noise,
    pub options: &'a EstimateOptions,
    pub seg_mount: &'a [usize],
    /// Which segments are at rest, when spins enter as differences from their rest.
    pub rests: Option<&'a [bool]>,
}

impl Context<'_> {
    /// The segment models again, the lever terms on the body's rate through `correction`; under a
    /// gyro bias walk each segment's rate through its own fitted bias at `theta` (docs/model.md
    /// §11.6).
    fn rebuild(
        &self,
        segs: &[SessionSeg],
        problem: &mut Problem,
        correction: &(shared::linalg::RowMajor3, [f64; 3]),
        theta: &[f64],
    ) {
        let seg_bias = problem
            .gyro_block
            .as_ref()
            .map_or_else(Vec::new, |b| gyro_drift::segment_biases(b, theta));
        problem.models = build::build_models(
            self.plan,
            segs,
            self.noise,
            self.options,
            &problem.mounts,
            self.seg_mount,
            Some(&build::RateCorrection {
                gyro: *correction,
                seg_bias: &seg_bias,
            }),
        );
        problem.groups.clear();
        if let Some(r) = self.rests {
            problem.group_spins(&|seg| r[seg]);
        }
    }
}

/// The joint fit, and with `gyro_base` the gyro model: first from the gyro alone (nominal ups within
/// their priors) so that the first joint pass already runs on corrected rates, then twice more with
/// the joint estimate (G is then known to ppm).
pub(crate) fn with_gyro(
    ctx: &Context<'_>,
    segs: &mut [SessionSeg],
    problem: &mut Problem,
    mut start: Vec<f64>,
    excluded: &mut Vec<Exclusion>,
    frame: BodyFrame,
    gyro_base: Option<usize>,
) -> Result<(JointFit, Option<GyroEstimate>), EstimateError> {
    let Some(base) = gyro_base else {
        let j = joint(ctx.plan, segs, problem, start, ctx.options, excluded, frame)?;
        return Ok((j, None));
    };
    let gyro_only = Problem {
        models: Vec::new(),
        groups: Vec::new(),
        ..problem.clone()
    };
    let mut free = vec![false; start.len()];
    free[base..].fill(true);
    attitude::tilt_free(&gyro_only, &mut free);
    let f = solve::fit(&gyro_only, start.clone(), free, "gyro model")?;
    if let Some(c) = GyroEstimate::from_fit(&f.theta, &f.cov, base).correction() {
        ctx.rebuild(segs, problem, &c, &f.theta);
        start[base..].copy_from_slice(&f.theta[base..]);
    }
    let mut j = joint(ctx.plan, segs, problem, start, ctx.options, excluded, frame)?;
    for _ in 0..2 {
        let Some(c) = GyroEstimate::from_fit(&j.theta, &j.cov, base).correction() else {
            break;
        };
        ctx.rebuild(segs, problem, &c, &j.theta);
        j = joint(
            ctx.plan,
            segs,
            problem,
            j.theta.clone(),
            ctx.options,
            excluded,
            frame,
        )?;
    }
    let g = GyroEstimate::from_fit(&j.theta, &j.cov, base);
    Ok((j, Some(g)))
}

/// The joint fit's result.
pub(crate) struct JointFit {
    pub theta: Vec<f64>,
    pub cov: nalgebra::DMatrix<f64>,
    pub free: Vec<bool>,
    pub fixed: [[bool; 3]; 3],
    pub chi2: f64,
    pub dof: i64,
}

/// Joint fit over all used segments, the gyro's spin axes and the mounts' attitude priors,
/// excluding segments whose residual shows a wrong attitude.
pub(crate) fn joint(
    plan: &Plan,
    segs: &mut [SessionSeg],
    problem: &mut Problem,
    start: Vec<f64>,
    options: &EstimateOptions,
    excluded: &mut Vec<Exclusion>,
    frame: BodyFrame,
) -> Result<JointFit, EstimateError> {
    loop {
        let n = problem.n_params();
        let mut free = vec![true; n];
        attitude::tilt_free(problem, &mut free);
        if frame == BodyFrame::Convention {
            for p in attitude::CONVENTION_FIXED {
                free[p] = false;
            }
        }
        let mut t0 = start.clone();
        let fixed_list = solve::structurally_unobservable(
            problem,
            &mut t0,
            &mut free,
            options.lever_arm_structural_limit_m,
        );
        let fit = solve::fit(problem, t0, free, "joint least squares")?;
        // A residual of more than the attitude tolerance (in g) means the segment is not what the plan says.
        let m = model::m_of(&fit.theta);
        let Some(minv) = linalg::inverse(&m) else {
            return Err(EstimateError::Singular {
                what: "scale/misalignment matrix",
            });
        };
        let tol_g = 2.0 * (0.5 * options.attitude_tolerance_deg.to_radians()).sin();
        let models = &problem.all_models();
        let worst = models
            .iter()
            .enumerate()
            .filter(|(_, s)| !plan.segments[segs[s.seg].plan_idx].is_free())
            .map(|(k, s)| {
                let p = s.predict(&fit.theta);
                let res: [f64; 3] = core::array::from_fn(|i| s.mean_u[i] - p[i]);
                (k, linalg::norm(&linalg::mat_vec(&minv, &res)))
            })
            .max_by(|a, b| a.1.total_cmp(&b.1));
        if let Some((k, err)) = worst {
            let is_static = segs[models[k].seg].kind == SegmentKind::Static;
            let statics_left = models
                .iter()
                .filter(|s| segs[s.seg].kind == SegmentKind::Static)
                .count();
            if err > tol_g && (!is_static || statics_left > 4) {
                let seg = models[k].seg;
                segs[seg].used = false;
                excluded.push(Exclusion {
                    name: plan.segments[segs[seg].plan_idx].name.clone(),
                    reason: ExclusionReason::AttitudeContradiction {
                        angle_deg: chord_to_angle_deg(err),
                        prior_sigma_deg: plan.segments[segs[seg].plan_idx].attitude_sigma_deg,
                        limit_deg: chord_to_angle_deg(tol_g),
                    },
                });
                problem.remove_segment(seg);
                continue;
            }
        }
        let mut fixed = [[false; 3]; 3];
        for (i, j) in fixed_list {
            fixed[i][j] = true;
        }
        return Ok(JointFit {
            theta: fit.theta,
            cov: fit.cov,
            free: fit.free,
            fixed,
            chi2: fit.chi2,
            dof: fit.dof,
        });
    }
}
