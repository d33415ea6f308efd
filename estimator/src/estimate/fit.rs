//! One calibration fit, in the order it runs: [`prepare`] (plan ↔ data, screening, the static fit),
//! [`setup_gyro`] (the gyro's unknowns or observations, the body frame, the starting point),
//! [`main_fit`] (the chosen method's least squares), `fit_checks::chi2_scale` (the χ² check), then the
//! conversion to the paper's form, `fit_checks::lever_arm_observability`, [`calibration_of`] and [`outcome`]
//! (the per-segment diagnostics, the mounts' tilts and the warnings drawn from the result). Each stage
//! hands the next a struct, so that what a stage produces has a name.

use super::fit_checks::{chi2_scale, lever_arm_observability, residual_warning, ChiSquare};
use super::model::{self, SegModel};
use super::note::Note;
use super::package::{self, PackageTest};
use super::paper_angles::{self, Converted};
use super::solve::{self, Problem};
use super::{attitude, build, drift, gyro, joint, paper, plausibility, screen, thermal};
use super::{gyro_drift, thermal_gyro, WalkEstimate};
use super::{
    BiasWalk, BodyFrame, CalibrationOutcome, EstimateError, EstimateOptions, Exclusion, FitSummary,
    GyroEstimate, GyroModel, Method, MethodComparison, Noise, Observability, SegmentDiagnostic,
    SegmentKind, UnitWalk,
};
use nalgebra::DMatrix;
use recording::session::{Package, Plan, SegmentStats};
use shared::linalg;
use shared::{Calibration, FittedStatic, LeverArms, OutputUnit};

mod walks;
use walks::estimate_walks;

/// A segment of the session after matching plan and data.
#[derive(Clone, Debug)]
pub(crate) struct SessionSeg {
    pub plan_idx: usize,
    pub stats: SegmentStats,
    pub kind: SegmentKind,
    pub used: bool,
}

/// Calibrates from a plan and its segments' statistics; a result that fails the plausibility checks
/// ([`plausibility`]) is an error. A session recorded over a temperature range first gets its
/// temperature model ([`thermal`]); the rest is estimated from the statistics referred to the reference
/// temperature.
pub fn calibrate_session_stats(
    plan: &Plan,
    stats: &[SegmentStats],
    options: &EstimateOptions,
) -> Result<CalibrationOutcome, EstimateError> {
    calibrate_with_hand_gyro(plan, stats, options, None).map(|(outcome, _)| outcome)
}

/// [`calibrate_session_stats`] with the gyro a hand-held session's turns determined (`gyro.toml`),
/// which the calibration takes where the session's own fit determines no `G`
/// (`thermal_gyro::settle_gyro`, docs/model.md §8, §9); and whether it took it.
pub fn calibrate_with_hand_gyro(
    plan: &Plan,
    stats: &[SegmentStats],
    options: &EstimateOptions,
    hand: Option<&GyroEstimate>,
) -> Result<(CalibrationOutcome, bool), EstimateError> {
    // A plan for a single-package unit asks for its model whatever the flags (docs/model.md §4.7).
    let options = &EstimateOptions {
        single_package: options.single_package || plan.package == Package::Single,
        ..options.clone()
    };
    let sp = options.spelling;
    let (fit, notes) = thermal::fit_session(plan, stats).map_err(EstimateError::Temperature)?;
    let mut outcome = match &fit {
        None => plausibility::check(plan, stats, fit_session(plan, stats, options), sp)?,
        Some(fit) => {
            let referred = fit.refer_to_reference(stats);
            plausibility::check(plan, &referred, fit_session(plan, &referred, options), sp)?
        }
    };
    outcome.warnings.extend(notes);
    outcome.calibration.temperature = fit.as_ref().map(|f| f.model);
    let rests = thermal_gyro::bias_from_rests(&outcome, fit.as_ref(), options);
    let from_hand = thermal_gyro::settle_gyro(&mut outcome, rests, hand);
    outcome.thermal = fit;
    Ok((outcome, from_hand))
}

/// [`calibrate_session_stats`] for statistics at one temperature, before the plausibility checks.
fn fit_session(
    plan: &Plan,
    stats: &[SegmentStats],
    options: &EstimateOptions,
) -> Result<CalibrationOutcome, EstimateError> {
    package::preconditions(options).map_err(EstimateError::SinglePackage)?;
    if options.method == Method::Paper && options.bias_walk != BiasWalk::Off {
        return Err(EstimateError::BiasWalkWithPaperMethod);
    }
    refuse_walk_unit(plan, options)?;
    let mut prepared = prepare(plan, stats, options)?;
    let setup = setup_gyro(plan, options, &mut prepared);
    settle_gyro_walk(options, &mut prepared, setup.gyro_base.is_some())?;
    let frame = setup.frame;
    let estimate_gyro = options.gyro_bias_walk_estimate
        && options.gyro_bias_walk_deg_s_sqrt_s == 0.0
        && setup.gyro_base.is_some();
    let main = main_fit(plan, options, &mut prepared, setup)?;
    let walks = estimate_walks(options, estimate_gyro, &prepared, &main)?;
    if let Some(refit) = walks.refit(options) {
        // A walk the session determines: the fit again with it (§11.3, §11.6).
        let mut out = fit_session(plan, stats, &refit)?;
        out.bias_walk = walks.accel.or(out.bias_walk);
        out.gyro_walk = walks.gyro;
        return Ok(out);
    }
    let fitted = package::Fitted {
        theta: &main.theta,
        free: &main.free,
        chi2: main.chi2,
        dof: main.dof,
    };
    let package_test = (options.method == Method::Joint && rotates(plan))
        .then(|| package::check(&prepared.problem, &fitted, options, &mut prepared.warnings))
        .transpose()
        .map_err(EstimateError::SinglePackage)?
        .flatten();
    let chi2 = chi2_scale((main.chi2, main.dof), plan, options, &mut prepared.warnings);
    let frame_note = screen::reference_frame(plan, options, &mut prepared.warnings);
    let conv = paper_angles::convert(
        &main.theta,
        &main.cov,
        chi2.scale2,
        &main.fixed,
        options,
        &frame_note,
    )?;
    let observability = lever_arm_observability(&conv, plan, options, &mut prepared.warnings)?;
    let (fitted, calibration) = calibration_of(plan, &main, &conv, &frame_note)?;
    // The paper's eq. 24 has no single-point form: its per-accelerometer values would claim the
    // size effect the single-package model reports as not observable (docs/model.md §4.7).
    let comparison = if options.compare_methods && !options.single_package {
        compare(
            plan,
            &mut prepared.segs.clone(),
            &mut prepared.problem.clone(),
            &prepared.static_fit,
            options,
            &frame_note,
            frame,
        )
    } else {
        None
    };
    let solution = Solution {
        chi2,
        conv,
        observability,
        fitted,
        calibration,
        comparison,
        frame,
        package_test,
    };
    let mut out = outcome(plan, options, prepared, main, solution);
    // Estimated and not determined: reported, and the fit is the constant-bias one.
    out.bias_walk = walks.accel.or(out.bias_walk);
    out.gyro_walk = walks.gyro;
    Ok(out)
}

/// The session matched to its plan and screened, the mounts and segment models built, and the
/// static fit (or, without enough known attitudes, the fit with every attitude free) done.
struct Prepared {
    /// Warnings so far, in the order the user reads them.
    warnings: Vec<Note>,
    /// Segments left out so far, with the reason.
    excluded: Vec<Exclusion>,
    segs: Vec<SessionSeg>,
    /// The pooled static noise that weighs every segment.
    noise: Noise,
    /// Each segment's mount.
    seg_mount: Vec<usize>,
    problem: Problem,
    static_fit: solve::Fit,
    /// The bias random walk the fit assumes, when asked for (docs/model.md §11).
    walk: Option<WalkEstimate>,
}

/// Plan ↔ data, screening, the segment models and the static fit.
fn prepare(
    plan: &Plan,
    stats: &[SegmentStats],
    options: &EstimateOptions,
) -> Result<Prepared, EstimateError> {
    let mut warnings = Vec::new();
    let mut excluded = Vec::new();
    let mut segs = screen::match_plan(plan, stats, options, &mut excluded, &mut warnings)?;
    screen::screen(plan, &mut segs, options, &mut excluded);
    let planned_static = plan.segments.iter().filter(|s| s.is_static()).count();
    let noise = screen::pooled_noise(&segs);
    let (mounts, seg_mount) = build::build_mounts(plan, &segs);
    let models = build::build_models(plan, &segs, &noise, options, &mounts, &seg_mount, None);
    let mut problem = Problem::new(models, mounts);
    problem.single_package = options.single_package;
    let mut stage = |segs: &mut [SessionSeg], problem: &mut Problem| {
        let (ex, n) = (&mut excluded, planned_static);
        screen::static_stage(plan, segs, &noise, problem, options, ex, n)
    };
    let mut static_fit = stage(&mut segs, &mut problem)?;
    // The walk's strength (given, or estimated from the constant-bias fit's segments), then the
    // static fit again with it (docs/model.md §11).
    let walk = drift::apply(options, &segs, &mut problem, &static_fit);
    if problem.drift.as_ref().is_some_and(drift::Drift::active) {
        static_fit = stage(&mut segs, &mut problem)?;
    }
    Ok(Prepared {
        walk,
        warnings,
        excluded,
        segs,
        noise,
        seg_mount,
        problem,
        static_fit,
    })
}

/// A walk of raw outputs is a strength in its own output unit: one of another unit than the
/// session's is refused (docs/model.md §11.3).
fn refuse_walk_unit(plan: &Plan, options: &EstimateOptions) -> Result<(), EstimateError> {
    if let BiasWalk::FromUnit(UnitWalk::OutputPerSqrtS(_, unit)) = options.bias_walk {
        if unit != plan.output_unit {
            return Err(EstimateError::BiasWalkUnit {
                walk: unit.symbol(),
                session: plan.output_unit.symbol(),
            });
        }
    }
    Ok(())
}

/// The gyro's walk weighs the gyro model's mean rates (§11.6): without the model it would change
/// nothing, so one asked for is refused, naming why there is none, and a unit's is left out with a
/// warning.
fn settle_gyro_walk(
    options: &EstimateOptions,
    prepared: &mut Prepared,
    has_gyro_model: bool,
) -> Result<(), EstimateError> {
    if options.gyro_bias_walk_deg_s_sqrt_s <= 0.0 || has_gyro_model {
        return Ok(());
    }
    let spins = prepared
        .segs
        .iter()
        .any(|s| s.used && s.kind != SegmentKind::Static);
    let why = if options.method == Method::Paper {
        "the paper's method estimates no gyro model"
    } else if options.gyro_model != GyroModel::Estimate {
        "the gyro is taken as given, not estimated from this session"
    } else if !spins {
        "the session has no spins (every segment used is a rest), so no gyro model is estimated \
         from it"
    } else {
        "the session estimates no gyro model"
    };
    if !options.gyro_bias_walk_from_unit {
        return Err(EstimateError::GyroBiasWalkUnused { why });
    }
    prepared.warnings.push(Note::GyroWalkUnused { why });
    Ok(())
}

/// What the main fit starts from.
struct Setup {
    /// The index of the gyro's first parameter, when the gyro is estimated with the rest.
    gyro_base: Option<usize>,
    /// What fixes the body frame.
    frame: BodyFrame,
    /// Which segments are rests, when the static parameters come from the rests alone.
    rests: Option<Vec<bool>>,
    /// The starting θ: the static fit's, and a perfect gyro with the rests' mean bias.
    start: Vec<f64>,
}

/// The gyro's unknowns (estimated with the rest, when the session has spins) or its observations
/// (taken as perfect), the body frame, the spins grouped with their rests, and the starting θ.
fn setup_gyro(plan: &Plan, options: &EstimateOptions, p: &mut Prepared) -> Setup {
    let segs = &p.segs;
    let spins = segs.iter().any(|s| s.used && s.kind != SegmentKind::Static);
    let gyro_on =
        options.gyro_model == GyroModel::Estimate && spins && options.method == Method::Joint;
    let gyro_base = p.problem.n_params();
    if gyro_on {
        let mut blk = build::build_gyro_block(
            plan,
            segs,
            &p.noise,
            &p.problem.mounts,
            &p.seg_mount,
            gyro_base,
        );
        // The gyro bias's random walk, when given (docs/model.md §11.6).
        blk.walk = gyro_drift::walk(options, segs);
        p.problem.gyro_block = Some(blk);
    } else {
        p.problem.gyro = build::build_gyro(
            plan,
            segs,
            &p.noise,
            options,
            &p.problem.mounts,
            &p.seg_mount,
        );
    }
    let frame = attitude::body_frame(&p.problem, plan);
    let group = options.static_from_rest && options.method == Method::Joint;
    let rests: Vec<bool> = segs.iter().map(|s| s.kind == SegmentKind::Static).collect();
    if group {
        p.problem.group_spins(&|seg| rests[seg]);
    }
    let mut start = p.static_fit.theta.clone();
    if gyro_on {
        start.resize(p.problem.n_params(), 0.0);
        let b = build::static_gyro(segs);
        for i in 0..3 {
            start[gyro::idx_g(gyro_base, i, i)] = 1.0;
            start[gyro::idx_b(gyro_base, i)] = b[i];
        }
    }
    Setup {
        gyro_base: gyro_on.then_some(gyro_base),
        frame,
        rests: group.then_some(rests),
        start,
    }
}

/// The chosen method's estimate of every parameter.
struct MainFit {
    theta: Vec<f64>,
    /// Covariance of θ from the weights alone (before χ² scaling).
    cov: DMatrix<f64>,
    /// Which entries of θ were estimated.
    free: Vec<bool>,
    /// Lever-arm components not estimable at all, fixed at 0.
    fixed: [[bool; 3]; 3],
    chi2: f64,
    dof: i64,
    /// The gyro, when estimated with the rest.
    gyro: Option<GyroEstimate>,
}

/// The joint least squares (with the gyro when set up) or the paper's eq. 24, whose notes become
/// warnings.
fn main_fit(
    plan: &Plan,
    options: &EstimateOptions,
    p: &mut Prepared,
    setup: Setup,
) -> Result<MainFit, EstimateError> {
    match options.method {
        Method::Joint => {
            let ctx = joint::Context {
                plan,
                noise: &p.noise,
                options,
                seg_mount: &p.seg_mount,
                rests: setup.rests.as_deref(),
            };
            let (j, gyro) = joint::with_gyro(
                &ctx,
                &mut p.segs,
                &mut p.problem,
                setup.start,
                &mut p.excluded,
                setup.frame,
                setup.gyro_base,
            )?;
            Ok(MainFit {
                theta: j.theta,
                cov: j.cov,
                free: j.free,
                fixed: j.fixed,
                chi2: j.chi2,
                dof: j.dof,
                gyro,
            })
        }
        Method::Paper => {
            let e = paper::eq24(plan, &p.segs, &p.problem.models, &p.static_fit)?;
            let (chi2, dof) = chi2_of(&p.problem.models, &e.theta, 12 + 9);
            p.warnings.extend(e.notes);
            Ok(MainFit {
                theta: e.theta,
                cov: e.cov,
                free: p.static_fit.free.clone(),
                fixed: [[false; 3]; 3],
                chi2,
                dof,
                gyro: None,
            })
        }
    }
}

/// The fitted static form and the calibration the device stores.
fn calibration_of(
    plan: &Plan,
    main: &MainFit,
    conv: &Converted,
    frame_note: &screen::Frame,
) -> Result<(FittedStatic, Calibration), EstimateError> {
    let output_unit: OutputUnit = plan.output_unit;
    let fitted = FittedStatic {
        output_unit,
        m_out_per_g: model::m_of(&main.theta),
        zero_bias_out: model::u0_of(&main.theta),
    };
    let calibration = Calibration {
        statics: fitted.to_paper()?,
        lever_arms: LeverArms {
            r_m: conv.lever_arms,
        },
        reference: frame_note.reference,
        gravity_m_s2: plan.gravity_m_s2,
        // The device corrects its rate with the estimated gyro (docs/model.md §8); a session that did
        // not estimate it leaves the device's gyro taken as perfect.
        gyro: main.gyro.as_ref().map(GyroEstimate::device_correction),
        temperature: None,
    };
    Ok((fitted, calibration))
}

/// What the main fit became: its χ² scaling, the paper's form, the observability, the calibration,
/// the other method's lever arms and the body frame.
struct Solution {
    chi2: ChiSquare,
    conv: Converted,
    observability: Observability,
    fitted: FittedStatic,
    calibration: Calibration,
    comparison: Option<MethodComparison>,
    frame: BodyFrame,
    package_test: Option<PackageTest>,
}

/// The outcome: the per-segment diagnostics, each mount's tilt, the static 1σ split, the parameter
/// table, and the warnings they give (tilts, the body frame's convention, segments whose residuals
/// exceed their noise).
fn outcome(
    plan: &Plan,
    options: &EstimateOptions,
    p: Prepared,
    main: MainFit,
    s: Solution,
) -> CalibrationOutcome {
    let Prepared {
        mut warnings,
        excluded,
        segs,
        problem,
        walk,
        ..
    } = p;
    let segments = diagnostics(
        plan,
        &segs,
        &problem.all_models(),
        &main.theta,
        &s.conv.centre_m,
    );
    let scaled_cov = &main.cov * s.chi2.scale2;
    let mount_tilts = attitude::mount_tilts(&problem, &main.theta, &scaled_cov, &main.free);
    warnings.extend(attitude::tilt_warning(&mount_tilts));
    if s.frame == BodyFrame::Convention {
        warnings.push(Note::BodyFrame(s.frame));
    }
    let static_split = attitude::static_split(&main.theta, &scaled_cov, s.frame);
    let parameters = parameter_table(&problem, &main.theta, &scaled_cov);
    warnings.extend(residual_warning(plan, &segments));
    CalibrationOutcome {
        method: options.method,
        calibration: s.calibration,
        uncertainty: s.conv.uncertainty(&s.observability),
        covariance: s.conv.cov_rows(),
        fit: FitSummary {
            chi2: main.chi2,
            dof: main.dof,
            reduced_chi2: s.chi2.reduced,
            sigma_scale: s.chi2.scale2.sqrt(),
        },
        segments,
        excluded,
        observability: s.observability,
        comparison: s.comparison,
        warnings,
        fitted: s.fitted,
        mount_tilts,
        static_split,
        parameters,
        gyro: main.gyro,
        thermal: None,
        single_package: options.single_package,
        package_test: s.package_test,
        bias_track: drift::track(&problem, &main.theta, &main.cov, &segs),
        gyro_bias_walk_deg_s_sqrt_s: problem
            .gyro_block
            .as_ref()
            .and_then(|b| b.walk.as_ref())
            .filter(|d| d.active())
            .map(|_| options.gyro_bias_walk_deg_s_sqrt_s),
        acc_offset: plan.acc_offset,
        bias_walk: walk,
        gyro_walk: None,
    }
}

/// Every fitted parameter (intrinsic, then two tilts per mount): name, value and 1σ from the
/// scaled covariance (0 when fixed).
fn parameter_table(
    problem: &Problem,
    theta: &[f64],
    scaled_cov: &DMatrix<f64>,
) -> Vec<(String, f64, f64)> {
    (0..theta.len())
        .map(|k| {
            (
                model::theta_label(k, &problem.mounts),
                theta[k],
                scaled_cov[(k, k)].max(0.0).sqrt(),
            )
        })
        .collect()
}

/// Whether the session turns at all (rotations or ramps): only then do lever arms, a table centre
/// and a table's rate enter the model.
pub(crate) fn rotates(plan: &Plan) -> bool {
    plan.segments.iter().any(|s| !s.is_static())
}

/// The angle between two unit vectors `chord` apart (|a − b| = 2 sin(θ/2)), degrees.
pub(crate) fn chord_to_angle_deg(chord: f64) -> f64 {
    (2.0 * (0.5 * chord).min(1.0).asin()).to_degrees()
}

/// χ² of all models at θ, and dof for `n_params` parameters.
fn chi2_of(models: &[SegModel], theta: &[f64], n_params: usize) -> (f64, i64) {
    let chi2 = models
        .iter()
        .map(|m| {
            m.whitened_residual(theta)
                .iter()
                .map(|v| v * v)
                .sum::<f64>()
        })
        .sum();
    (chi2, 3 * models.len() as i64 - n_params as i64)
}

/// The other method's lever arms, when it can run.
fn compare(
    plan: &Plan,
    segs: &mut [SessionSeg],
    problem: &mut Problem,
    static_fit: &solve::Fit,
    options: &EstimateOptions,
    frame: &screen::Frame,
    body: BodyFrame,
) -> Option<MethodComparison> {
    let (method, theta, cov, fixed, notes) = match options.method {
        Method::Joint => {
            let p = paper::eq24(plan, segs, &problem.all_models(), static_fit).ok()?;
            (Method::Paper, p.theta, p.cov, [[false; 3]; 3], p.notes)
        }
        Method::Paper => {
            let mut ex = Vec::new();
            let j = joint::joint(
                plan,
                segs,
                problem,
                static_fit.theta.clone(),
                options,
                &mut ex,
                body,
            )
            .ok()?;
            (Method::Joint, j.theta, j.cov, j.fixed, Vec::new())
        }
    };
    let conv = paper_angles::convert(&theta, &cov, 1.0, &fixed, options, frame).ok()?;
    Some(MethodComparison {
        method,
        lever_arms: LeverArms {
            r_m: conv.lever_arms,
        },
        lever_arm_sigma_m: conv.lever_sigma(),
        notes,
    })
}

/// Per segment: the fitted up, the model's specific force at the calibration's reference point
/// `centre_m` (where the device's compensated output is), the noise and the χ² (docs/model.md §6).
fn diagnostics(
    plan: &Plan,
    segs: &[SessionSeg],
    models: &[SegModel],
    theta: &[f64],
    centre_m: &[f64; 3],
) -> Vec<SegmentDiagnostic> {
    let m = model::m_of(theta);
    let k: [f64; 3] = core::array::from_fn(|i| linalg::norm(&m[i]));
    let models_by_seg: std::collections::HashMap<usize, &SegModel> =
        models.iter().map(|s| (s.seg, s)).collect();
    // 99.9 % point of χ² with 3 degrees of freedom.
    const CHI2_3_999: f64 = 16.27;
    segs.iter()
        .enumerate()
        .map(|(idx, s)| {
            let sp = &plan.segments[s.plan_idx];
            let st = &s.stats;
            let up = models_by_seg
                .get(&idx)
                .map_or(sp.up_b, |md| md.tilt.up(theta));
            let rate = linalg::dot(&st.mean_w_rad_s, &up).to_degrees();
            let (theoretical, noise, chi2) = match models_by_seg.get(&idx) {
                Some(md) => {
                    let noise = core::array::from_fn(|i| md.se_cov[i][i].sqrt() / k[i]);
                    let c2: f64 = md.whitened_residual(theta).iter().map(|v| v * v).sum();
                    let f = md.f(theta);
                    let at_reference = linalg::mat_vec(&md.e, centre_m);
                    (
                        core::array::from_fn(|j| f[j] + at_reference[j]),
                        noise,
                        Some(c2),
                    )
                }
                None => (up, [f64::NAN; 3], None),
            };
            SegmentDiagnostic {
                name: sp.name.clone(),
                kind: s.kind,
                count: st.count,
                up_b: up,
                rate_deg_s: rate,
                used: s.used,
                theoretical_g: theoretical,
                noise_g: noise,
                chi2,
                chi2_flagged: chi2.is_some_and(|c| c > CHI2_3_999),
            }
        })
        .collect()
}
