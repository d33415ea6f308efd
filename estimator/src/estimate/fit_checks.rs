//! What the fit's result is read through before it becomes an outcome: the χ² check and scaling,
//! which lever-arm components the plan determined, and the warning for segments whose residuals
//! exceed their own noise (docs/model.md §4.4). Each names the error sources consistent with the
//! plan's kind.

use super::fit::rotates;
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
    warnings: &mut Vec<String>,
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
        warnings.push(
            "no residual degrees of freedom: the χ² check and scaling are not possible; \
             add segments (repeat attitudes or rates)"
                .into(),
        );
    } else if scale2 > 1.0 {
        let sources = if !rotates(plan) && plan.segments.iter().all(|s| s.is_free()) {
            "movement while held still, bias drift, a temperature change"
        } else if !rotates(plan) {
            "a mount tilted beyond its attitude prior, bias drift, a temperature change"
        } else {
            "table attitude or rate error, bias drift, a table centre off the spin axis"
        };
        warnings.push(format!(
            "χ²/dof = {reduced:.1} (dof {fit_dof}): the residuals exceed the segments' own noise, so the \
             model misses an error source it cannot see ({sources}); the 1σ values are scaled by {:.2}",
            scale2.sqrt()
        ));
    }
    ChiSquare { reduced, scale2 }
}

/// Which lever-arm components the plan determined; a warning naming the others (and those not
/// observable at all), or an error when the options require every one.
pub(super) fn lever_arm_observability(
    conv: &Converted,
    plan: &Plan,
    options: &EstimateOptions,
    warnings: &mut Vec<String>,
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
    warnings.push(format!(
        "the plan does not determine lever-arm component(s) {} to {:.0} µm{}; add rotations about \
         oblique axes (tilted mounts) and/or spin-up segments (docs/model.md §4.4)",
        undetermined.join(", "),
        options.lever_arm_threshold_m * 1e6,
        if fixed_names.is_empty() {
            String::new()
        } else {
            format!(
                " ({} not observable at all: fixed at 0)",
                fixed_names.join(", ")
            )
        }
    ));
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
pub(super) fn residual_warning(plan: &Plan, segments: &[SegmentDiagnostic]) -> Option<String> {
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
    let names: Vec<&str> = flagged.iter().map(|d| d.name.as_str()).collect();
    let mut sources = Vec::new();
    if free {
        sources.push("movement while held still or bias drift (the attitude is fitted, the bias taken as constant)");
    }
    if statics {
        sources.push("a mount tilted beyond its attitude prior, or bias drift (the bias is taken as constant)");
    }
    if rotating {
        sources.push("rate-dependent effects outside the model (table wobble, a table centre off the spin axis, gyro scale or misalignment)");
    }
    Some(format!(
        "segment(s) {} have residuals well above their own noise: {}",
        names.join(", "),
        sources.join("; ")
    ))
}
