//! Plausibility of a fitted calibration, checked before anything is written.
//!
//! A least-squares fit always returns numbers; these checks catch the numbers no real unit has, which
//! come from a plan whose labels do not match the recording (two mounts swapped, `x+` recorded as
//! `x−`), not from the unit:
//! - the sensing directions (rows of `M = K·A`, `docs/model.md` §4.2) form a right-handed triad, each
//!   within `MAX_AXIS_ANGLE_DEG` of its nominal body axis;
//! - at least one residual degree of freedom remains, so that χ²/dof is defined and the fit is checked
//!   by the data at all;
//! - the static segments read like their labels: with the nominal layout (accelerometer `i` along body
//!   axis `i`), each static segment's outputs give its "up" to within a few degrees, independently of
//!   the fit, and a segment whose data point where another label does is named ("'y+' looks like
//!   'z+'");
//! - the gyro, when the session has one: its spins agree with the table and its `G` is a real gyro's
//!   ([`super::gyro_check`]).

use super::note::Note;
use super::{gyro_check, CalibrationOutcome, EstimateError};
use recording::session::{Plan, SegmentStats};
use recording::spelling::Spelling;
use shared::linalg;

/// Largest angle between a fitted sensing axis and its nominal body axis, degrees. Real units are
/// within a few degrees (the paper's: < 1°); 30° leaves room for any deliberate mounting while
/// catching a swapped or reversed axis (90° or 180°).
pub(crate) const MAX_AXIS_ANGLE_DEG: f64 = 30.0;

/// Angle between a static segment's measured "up" and a label's `up_b` below which the data are said
/// to look like that label, and above which they contradict their own, degrees.
pub(crate) const LABEL_MATCH_DEG: f64 = 20.0;

/// Checks a fit's result (or adds the segments that contradict their labels to its error).
pub(crate) fn check(
    plan: &Plan,
    stats: &[SegmentStats],
    result: Result<CalibrationOutcome, EstimateError>,
    sp: Spelling,
) -> Result<CalibrationOutcome, EstimateError> {
    let labels = label_contradictions(plan, stats);
    let mut outcome = match result {
        Ok(o) => o,
        Err(e) if labels.is_empty() => return Err(e),
        Err(e) => {
            let mut problems = vec![shared::chain::Chain(&e).to_string()];
            problems.extend(Note::texts(&labels));
            return Err(EstimateError::Implausible { problems });
        }
    };
    let mut problems = triad_problems(&outcome.fitted.m_out_per_g);
    problems.extend(gyro_problems(plan, &outcome, sp));
    problems.extend(scale_unit_problem(plan, &outcome));
    if outcome.fit.dof < 1 {
        let excluded: Vec<String> = outcome.excluded.iter().map(|e| e.to_string()).collect();
        problems.push(format!(
            "{} residual degrees of freedom: χ²/dof is not defined, so nothing checks the fit; add \
             segments (repeat attitudes or rates) or re-record the excluded ones{}",
            outcome.fit.dof,
            if excluded.is_empty() {
                String::new()
            } else {
                format!(" (excluded: {})", excluded.join("; "))
            }
        ));
    }
    if problems.is_empty() {
        outcome.warnings.extend(labels);
        outcome.warnings.extend(common_scale_note(&outcome));
        return Ok(outcome);
    }
    problems.extend(Note::texts(&labels));
    Err(EstimateError::Implausible { problems })
}

/// The gyro's refusals (`gyro_check`): spins whose gyro contradicts the table systematically, or an
/// implausible `G`. A calibration with such a gyro is not written: its numbers would be loaded as if
/// calibrated. (`G` entries that the plan does not determine are marked by their 1σ and listed.)
fn gyro_problems(plan: &Plan, outcome: &CalibrationOutcome, sp: Spelling) -> Vec<String> {
    let spins: Vec<gyro_check::Spin> = plan
        .segments
        .iter()
        .filter(|s| !s.is_static())
        .map(|s| gyro_check::Spin {
            name: &s.name,
            axis_b: (!s.is_free()).then_some(s.up_b),
        })
        .collect();
    let mut problems: Vec<String> = gyro_check::contradiction_problem(&outcome.excluded, &spins)
        .into_iter()
        .collect();
    if let Some(g) = &outcome.gyro {
        problems.extend(gyro_check::matrix_problems_spelled(&g.matrix, sp));
    }
    problems
}

/// A gyro that reads `k`× the table's rates on every axis ([`gyro_check::common_scale`]): no
/// contradiction, since a spin's rate does not depend on the time base: the gyro's nominal scale is
/// off (which the calibration corrects), or the plan's rates are.
fn common_scale_note(outcome: &CalibrationOutcome) -> Option<Note> {
    let g = outcome.gyro.as_ref()?;
    let k = gyro_check::common_scale(&g.matrix)?;
    Some(Note::GyroCommonScale { k })
}

/// A scale factor that contradicts the plan's `output_unit`: an output declared in g must measure
/// about 1 g per g, one in m/s² about 9.8 per g (within [`MAX_UNIT_SCALE_ERROR`]); volts and counts
/// have no nominal scale. Volt data declared as g calibrate to 0.4 "g per g" otherwise.
fn scale_unit_problem(plan: &Plan, outcome: &CalibrationOutcome) -> Option<String> {
    let nominal = match plan.output_unit {
        shared::OutputUnit::StandardGravity => 1.0,
        shared::OutputUnit::MetresPerSecondSquared => plan.gravity_m_s2,
        _ => return None,
    };
    let k = outcome.calibration.statics.scale_out_per_g;
    k.iter()
        .any(|v| v.is_nan() || (v / nominal - 1.0).abs() > MAX_UNIT_SCALE_ERROR)
        .then(|| {
            format!(
                "the scale factors are {:.4}, {:.4}, {:.4} {} per g, but an output in {} is about {} \
                 per g: the recording is not in the plan's output_unit; set output_unit to the data's \
                 unit",
                k[0],
                k[1],
                k[2],
                plan.output_unit.symbol(),
                plan.output_unit.symbol(),
                nominal
            )
        })
}

/// Largest relative difference of a scale factor from its output unit's nominal one (a MEMS part's
/// scale is within a few percent of its data sheet's).
pub(crate) const MAX_UNIT_SCALE_ERROR: f64 = 0.2;

/// Handedness and per-axis angle of the fitted sensing directions.
fn triad_problems(m: &linalg::RowMajor3) -> Vec<String> {
    let mut problems = Vec::new();
    let det = linalg::to_na(m).determinant();
    // NaN (a degenerate fit) fails too.
    if det.is_nan() || det <= 0.0 {
        problems.push(format!(
            "the fitted sensing axes form a left-handed (or degenerate) triad (det M = {det:.3e}): \
             a segment pair is probably recorded under each other's label (e.g. x+ and x−)"
        ));
    }
    for (i, row) in m.iter().enumerate() {
        let n = linalg::norm(row);
        let cos = if n > 0.0 { row[i] / n } else { f64::NAN };
        let angle = cos.clamp(-1.0, 1.0).acos().to_degrees();
        if angle.is_nan() || angle > MAX_AXIS_ANGLE_DEG {
            problems.push(format!(
                "accelerometer {} senses {angle:.1}° away from body axis {} (at most \
                 {MAX_AXIS_ANGLE_DEG}° is plausible): the plan's labels do not match the recording",
                i + 1,
                shared::params::axis_name(i)
            ));
        }
    }
    problems
}

/// Static segments whose outputs point where another label does, or nowhere near their own.
///
/// Independent of the fit: the bias and scale of each output are taken from the extremes of the
/// static means (`u0 ≈ (max + min)/2`, `k ≈ (max − min)/2`), valid when the plan has `±1 g` on every
/// body axis; with another plan the check is skipped (the fit's own checks remain).
pub(crate) fn label_contradictions(plan: &Plan, stats: &[SegmentStats]) -> Vec<Note> {
    let near = |a: &[f64; 3], b: &[f64; 3]| angle_deg(a, b) < 10.0;
    let statics: Vec<(&str, [f64; 3], [f64; 3])> = stats
        .iter()
        .filter(|s| s.count >= 2 && s.mean_u.iter().all(|v| v.is_finite()))
        .filter_map(|s| {
            let sp = plan.segment(&s.name)?;
            sp.is_static()
                .then_some((sp.name.as_str(), sp.up_b, s.mean_u))
        })
        .collect();
    let covers_both_signs = (0..3).all(|i| {
        [1.0, -1.0].iter().all(|sign| {
            let mut e = [0.0; 3];
            e[i] = *sign;
            statics.iter().any(|(_, up, _)| near(up, &e))
        })
    });
    if !covers_both_signs {
        return Vec::new();
    }
    let mut u0 = [0.0; 3];
    let mut k = [0.0; 3];
    for i in 0..3 {
        let hi = statics.iter().map(|s| s.2[i]).fold(f64::MIN, f64::max);
        let lo = statics.iter().map(|s| s.2[i]).fold(f64::MAX, f64::min);
        u0[i] = 0.5 * (hi + lo);
        k[i] = 0.5 * (hi - lo);
    }
    if k.iter().any(|v| v.is_nan() || *v <= 0.0) {
        return Vec::new();
    }
    let mut out = Vec::new();
    for (name, up, u) in &statics {
        let measured: [f64; 3] = core::array::from_fn(|i| (u[i] - u0[i]) / k[i]);
        if angle_deg(&measured, up) <= LABEL_MATCH_DEG {
            continue;
        }
        let alike: Vec<String> = statics
            .iter()
            .filter(|(other, o_up, _)| {
                other != name && angle_deg(&measured, o_up) < LABEL_MATCH_DEG
            })
            .map(|(other, _, _)| other.to_string())
            .collect();
        let n = linalg::norm(&measured);
        if alike.is_empty() {
            out.push(Note::LabelNotRecorded {
                segment: name.to_string(),
                up_b: measured.map(|v| v / n),
                angle_deg: angle_deg(&measured, up),
            });
        } else {
            out.push(Note::LabelLooksLike {
                segment: name.to_string(),
                alike,
            });
        }
    }
    out
}

fn angle_deg(a: &[f64; 3], b: &[f64; 3]) -> f64 {
    let (na, nb) = (linalg::norm(a), linalg::norm(b));
    let c = linalg::dot(a, b) / (na * nb);
    if c.is_finite() {
        c.clamp(-1.0, 1.0).acos().to_degrees()
    } else {
        180.0
    }
}
