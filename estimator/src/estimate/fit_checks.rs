//! What the fit's result is read through before it becomes an outcome: the χ² check and scaling,
//! which lever-arm components the plan determined, and the warning for segments whose residuals
//! exceed their own noise (docs/model.md §4.4). Each names the error sources consistent with the
//! plan's kind.

use super::fit::rotates;
use super::note::{MisfitSources, Note};
use super::paper_angles::Converted;
use super::{
    ChiSquareScaling, EstimateError, EstimateOptions, Method, Observability, SegmentDiagnostic,
    SegmentKind,
};
use recording::session::Plan;

/// The fit's χ²/dof and the factor the covariance is multiplied by.
pub(super) struct ChiSquare {
    /// χ²/dof (NaN when dof ≤ 0).
    pub(super) reduced: f64,
    /// The covariance's factor (χ²/dof or 1).
    pub(super) scale2: f64,
}

/// χ²/dof, whether to scale by it ([`ChiSquareScaling`]), and a warning when it cannot be checked or
/// is well above 1.
pub(super) fn chi2_scale(
    (fit_chi2, fit_dof): (f64, i64),
    plan: &Plan,
    options: &EstimateOptions,
    warnings: &mut Vec<Note>,
) -> ChiSquare {
    let reduced = if fit_dof > 0 {
        fit_chi2 / fit_dof as f64
    } else {
        f64::NAN
    };
    let scale2 = match options.chi2_scaling {
        ChiSquareScaling::Never => 1.0,
        ChiSquareScaling::Always if reduced.is_finite() => reduced,
        ChiSquareScaling::WhenSignificant
            if reduced.is_finite() && reduced > 1.0 + 2.33 * (2.0 / fit_dof as f64).sqrt() =>
        {
            reduced
        }
        _ => 1.0,
    };
    if fit_dof <= 0 {
        warnings.push(Note::NoResidualDof);
    } else if scale2 > 1.0 {
        let sources = if !rotates(plan) && plan.segments.iter().all(|s| s.is_free()) {
            MisfitSources::HeldStill
        } else if !rotates(plan) {
            MisfitSources::Fixture
        } else {
            MisfitSources::Table
        };
        warnings.push(Note::ChiSquareScaled {
            reduced,
            dof: fit_dof,
            sources,
            sigma_scale: scale2.sqrt(),
        });
    }
    ChiSquare { reduced, scale2 }
}

/// Which lever-arm components the plan determined; a warning naming the others (and those not
/// observable at all), or an error when the options require every one.
pub(super) fn lever_arm_observability(
    conv: &Converted,
    plan: &Plan,
    options: &EstimateOptions,
    warnings: &mut Vec<Note>,
) -> Result<Observability, EstimateError> {
    let mut observability = conv.observability(options);
    if options.method == Method::Paper {
        observability.fixed_at_zero = [[false; 3]; 3];
    }
    let undetermined = observability.undetermined();
    if undetermined.is_empty() {
        return Ok(observability);
    }
    let fixed_names = observability.undetermined_fixed();
    if !rotates(plan) {
        // Without rotation there is nothing to add but a table: the terminal says the lever arms are
        // not calibrated, and a plan that needs them refuses below.
        if options.require_lever_arms {
            return Err(EstimateError::PlanCannotObserve {
                parameters: undetermined,
                hint: "lever arms need rotations on a rate table (docs/model.md §4.4)".into(),
            });
        }
        return Ok(observability);
    }
    warnings.push(Note::LeverArmsUndetermined {
        components: undetermined.clone(),
        threshold_m: options.lever_arm_threshold_m,
        fixed_at_zero: fixed_names,
    });
    if options.require_lever_arms {
        return Err(EstimateError::PlanCannotObserve {
            parameters: undetermined,
            hint: "add rotations about oblique axes and/or spin-up segments".into(),
        });
    }
    Ok(observability)
}

/// The warning for segments whose residuals are well above their own noise, naming the error
/// sources their kind points to.
pub(super) fn residual_warning(plan: &Plan, segments: &[SegmentDiagnostic]) -> Option<Note> {
    let flagged: Vec<&SegmentDiagnostic> = segments.iter().filter(|d| d.chi2_flagged).collect();
    if flagged.is_empty() {
        return None;
    }
    let is_free = |d: &&&SegmentDiagnostic| plan.segment(&d.name).is_some_and(|p| p.is_free());
    let free = flagged.iter().filter(is_free).count() > 0;
    let statics = flagged
        .iter()
        .any(|d| d.kind == SegmentKind::Static && !is_free(&d));
    let rotating = flagged.iter().any(|d| d.kind != SegmentKind::Static);
    Some(Note::SegmentResidualsHigh {
        segments: flagged.iter().map(|d| d.name.clone()).collect(),
        free,
        statics,
        rotating,
    })
}
