//! Whether a fitted gyro is accepted: a least-squares fit of `w = G·ω + b` (docs/model.md §8) always
//! returns numbers, and these checks refuse the numbers no real gyro has. A real MEMS or FOG gyro's
//! `G` is the identity within a few percent (scale) and a few degrees (misalignment); a fit far from
//! it, or turns that no `G` explains, come from the recording's columns or time base, not from the
//! unit. Each refusal names the likely cause:
//!
//! - a diagonal entry ≤ 0: that axis's sign is reversed (or the accelerometer's axes are mirrored,
//!   which only the gyro can see: a reflection of every still position is still a set of positions);
//! - an off-diagonal entry larger than the diagonal one: two axes are swapped;
//! - the same scale error on all three axes by 57.3× or its inverse: the gyro's unit. The same error
//!   by any other factor within `COMMON_SCALE_RANGE` is no contradiction: the gyro's nominal
//!   scale is off (which is what a gyro calibration is for), or the time base is (the turns were
//!   integrated over the wrong durations); the two cannot be told apart from the turns, so the fit is
//!   kept and `common_scale` lets the caller name both with the figure each implies;
//! - turns that no `G` explains (a misfit far beyond the noise): a sign, a swap or a time gap.
//!
//! The table session's gyro is also refused when the screening left out spins because the gyro
//! contradicts the table (`ExclusionReason::RateContradiction`): the same causes, seen before the fit.

use super::{Exclusion, ExclusionReason};
use recording::spelling::{Spelling, UserOption};
use shared::linalg::RowMajor3;

/// Largest plausible |G_ii − 1|: MEMS gyros are within ±3 % of their nominal scale; 20 % leaves room
/// for any real part while catching a wrong unit (×57.3), a time base off by ≥ 1.25× and a sign.
pub(crate) const MAX_SCALE_ERROR: f64 = 0.2;

/// Largest plausible |G_ij| (i ≠ j): 0.1 is a 5.7° misalignment, far beyond any mounted part's
/// (≤ 1–2°) but far below a swapped axis's 1.
pub(crate) const MAX_CROSS_AXIS: f64 = 0.1;

/// Largest plausible rms misfit of hand turns, degrees. The still positions give each "up" to about
/// 0.01–0.1° and a fitted `G` leaves only that; beyond 1° the turns contradict every linear gyro model.
pub const MAX_TURN_MISFIT_DEG: f64 = 1.0;

/// Ratio of two scale errors regarded as "the same on all three axes" (a time base or unit, not a
/// part's own scale errors, which differ from axis to axis).
const COMMON_SCALE_SPREAD: f64 = 0.05;

/// The common scale factors taken for a result, not a contradiction ([`common_scale`]): a nominal
/// scale off by up to 4× (a wrong LSB per °/s, a full-scale range mixed up) or a time base as far.
pub(crate) const COMMON_SCALE_RANGE: (f64, f64) = (0.25, 4.0);

/// The factor `k` by which the gyro reads on all three axes (`G ≈ k·(I + small)`), when it is beyond
/// `MAX_SCALE_ERROR`, the same on every axis, within `COMMON_SCALE_RANGE` and not a unit's
/// 57.3×: a nominal scale or a time base, which the caller names (docs/model.md §8).
pub fn common_scale(matrix: &RowMajor3) -> Option<f64> {
    let ratio: [f64; 3] = core::array::from_fn(|i| matrix[i][i]);
    if ratio.iter().any(|r| !r.is_finite() || *r <= 0.0) {
        return None;
    }
    let k = ratio.iter().sum::<f64>() / 3.0;
    let deg = 180.0 / core::f64::consts::PI;
    let common = ratio
        .iter()
        .all(|r| (r / k - 1.0).abs() < COMMON_SCALE_SPREAD);
    let unit = (k / deg - 1.0).abs() < 0.1 || (k * deg - 1.0).abs() < 0.1;
    (common
        && !unit
        && (k - 1.0).abs() > MAX_SCALE_ERROR
        && (COMMON_SCALE_RANGE.0..=COMMON_SCALE_RANGE.1).contains(&k))
    .then_some(k)
}

/// The likely causes of an implausible `G`, one line each (empty: `G` is plausible), the options
/// named as `sp` spells them.
pub fn matrix_problems_spelled(matrix: &RowMajor3, sp: Spelling) -> Vec<String> {
    let ax = shared::params::axis_name;
    let mut problems = Vec::new();
    if matrix.iter().flatten().any(|v| !v.is_finite()) {
        return vec![
            "the gyro fit has non-finite entries: the recording has no usable turns".into(),
        ];
    }
    for i in 0..3 {
        let (d, row) = (matrix[i][i], matrix[i]);
        if let Some(j) = (0..3).find(|&j| j != i && row[j].abs() > d.abs()) {
            problems.push(format!(
                "gyro axis {} reads body axis {} (G[{}][{}] = {:+.3}, G[{}][{}] = {:+.3}): two gyro (or \
                 accelerometer) columns are swapped; check the column order",
                ax(i),
                ax(j),
                ax(i),
                ax(j),
                row[j],
                ax(i),
                ax(i),
                d
            ));
        } else if d <= 0.0 {
            problems.push(format!(
                "gyro axis {} turns the wrong way (G[{}][{}] = {:+.3}): its sign is reversed, or one \
                 accelerometer axis is (the turns then look mirrored); negate that column",
                ax(i),
                ax(i),
                ax(i),
                d
            ));
        }
    }
    if !problems.is_empty() {
        return problems;
    }
    let scale: [f64; 3] = core::array::from_fn(|i| matrix[i][i] - 1.0);
    if common_scale(matrix).is_none() && scale.iter().any(|s| s.abs() > MAX_SCALE_ERROR) {
        problems.push(scale_cause(&scale, sp));
    }
    // Relative to the row's scale: a gyro that reads 2× has its cross-axis terms doubled too.
    for i in 0..3 {
        for j in (0..3).filter(|&j| j != i) {
            if matrix[i][j].abs() > MAX_CROSS_AXIS * matrix[i][i].abs() {
                problems.push(format!(
                    "G[{}][{}] = {:+.3}: a {:.1}° misalignment, beyond any mounted gyro's (at most \
                     {MAX_CROSS_AXIS} is plausible); check the columns and the gyro's mounting",
                    ax(i),
                    ax(j),
                    matrix[i][j],
                    matrix[i][j].asin().to_degrees()
                ));
            }
        }
    }
    problems
}

/// The cause of a scale error beyond [`MAX_SCALE_ERROR`]: a common one is the time base or unit.
fn scale_cause(scale: &[f64; 3], sp: Spelling) -> String {
    let ratio: [f64; 3] = scale.map(|s| 1.0 + s);
    let mean = ratio.iter().sum::<f64>() / 3.0;
    let common = ratio
        .iter()
        .all(|r| (r / mean - 1.0).abs() < COMMON_SCALE_SPREAD);
    let shown = format!(
        "{:+.1} %, {:+.1} %, {:+.1} %",
        scale[0] * 100.0,
        scale[1] * 100.0,
        scale[2] * 100.0
    );
    let deg = 180.0 / core::f64::consts::PI;
    if common && ((mean / deg) - 1.0).abs() < 0.1 {
        format!(
            "gyro scale errors {shown}: the rates are {deg:.1}× too large on every axis, so the gyro \
             is in °/s but was read as rad/s ({})",
            sp.given(UserOption::GyroUnit, "deg/s")
        )
    } else if common && ((mean * deg) - 1.0).abs() < 0.1 {
        format!(
            "gyro scale errors {shown}: the rates are {deg:.1}× too small on every axis, so the gyro \
             is in rad/s but was read as °/s ({})",
            sp.given(UserOption::GyroUnit, "rad/s")
        )
    } else if common {
        format!(
            "gyro scale errors {shown}, the same on all three axes: {mean:.3}×, beyond any nominal \
             scale or time base error taken for a result ({}× to {}×); check the gyro's unit, its \
             nominal scale and the time stamps",
            COMMON_SCALE_RANGE.0,
            COMMON_SCALE_RANGE.1
        )
    } else {
        format!(
            "gyro scale errors {shown}: at most {:.0} % is plausible; check the gyro's unit and the \
             columns",
            MAX_SCALE_ERROR * 100.0
        )
    }
}

/// The refusal of turns that no gyro model explains (`rms_misfit_deg` over `max_deg`: usually
/// [`MAX_TURN_MISFIT_DEG`]; a six-face session's ups are only as good as its faces, docs/model.md §7.2).
pub fn misfit_problem(rms_misfit_deg: f64, turns: usize, max_deg: f64) -> Option<String> {
    (rms_misfit_deg.is_nan() || rms_misfit_deg > max_deg).then(|| {
        format!(
            "the {turns} hand turns contradict every gyro model (rms misfit {rms_misfit_deg:.2}°, at \
             most {max_deg}° is plausible): a gyro or accelerometer axis sign is \
             reversed, two columns are swapped, or the time stamps have a gap inside a turn"
        )
    })
}

/// The refusal of a table session whose spins contradict the gyro systematically: the exclusions
/// for `RateContradiction` of a sign or unit (a ratio of −1 or 57.3^±1, which only the gyro's columns
/// give), or of more than half of the session's `spins`. One spin that did not happen as planned is a
/// table's slip: it stays an exclusion, and the others calibrate.
pub(crate) fn contradiction_problem(excluded: &[Exclusion], spins: &[Spin]) -> Option<String> {
    let ratios: Vec<(&str, f64)> = excluded
        .iter()
        .filter_map(|e| match e.reason {
            ExclusionReason::RateContradiction {
                measured_deg_s,
                planned_deg_s,
            } => Some((e.name.as_str(), measured_deg_s / planned_deg_s)),
            _ => None,
        })
        .collect();
    let first = ratios.first()?;
    let deg = 180.0 / core::f64::consts::PI;
    let near = |r: f64, x: f64| (r / x - 1.0).abs() < 0.1;
    let mixup = column_mixup(&ratios, spins);
    let systematic = mixup.is_some()
        || ratios
            .iter()
            .all(|(_, r)| near(*r, -1.0) || near(*r, deg) || near(*r, 1.0 / deg));
    if !systematic && 2 * ratios.len() <= spins.len() {
        return None;
    }
    let names: Vec<String> = ratios.iter().map(|(n, _)| format!("'{n}'")).collect();
    let cause = if let Some(p) = mixup {
        mixup_cause(&p)
    } else if ratios.iter().all(|(_, r)| near(*r, -1.0)) {
        "the gyro axis along those spins has its sign reversed: negate that column".to_string()
    } else if ratios.iter().all(|(_, r)| near(*r, deg)) {
        "the gyro reads about 57.3× the table rate: it is in °/s, and the recording must be in rad/s \
         (docs/recording-format.md)"
            .to_string()
    } else if ratios.iter().all(|(_, r)| near(*r, 1.0 / deg)) {
        "the gyro reads about 1/57.3 of the table rate: it is in rad/s where °/s was expected"
            .into()
    } else if ratios.iter().all(|(_, r)| r.abs() < 0.2) {
        "the gyro axis along those spins does not see them: two gyro columns are swapped, or the \
         unit was mounted about another axis"
            .to_string()
    } else {
        format!(
            "the gyro reads {:.3}× the table rate on '{}': check the gyro's columns, sign and unit, \
             and the table's rate",
            first.1, first.0
        )
    };
    Some(format!(
        "the gyro contradicts the table on {} spin segment(s) ({}): {cause}",
        ratios.len(),
        names.join(", ")
    ))
}

/// A spin of the plan by its segment's name, about its `up_b` (`None`: a free attitude's spin,
/// screened on its magnitude alone).
pub(crate) struct Spin<'a> {
    pub(crate) name: &'a str,
    pub(crate) axis_b: Option<[f64; 3]>,
}

/// The signed permutation `P` of the gyro's columns (other than the identity) under which every
/// spin reads as screened: a spin about `u` reads `u·P·u` times its planned rate about `u`, so the
/// excluded spins must read that ratio and the others about 1 (the screen's 10 %). A column's sign
/// reads −1 on a spin along that axis but 0 on a spin between two axes (an oblique plan's), and
/// only such a `P` explains both. The closest to the identity wins; `None` when none explains all.
fn column_mixup(ratios: &[(&str, f64)], spins: &[Spin]) -> Option<RowMajor3> {
    let tolerance = 0.1;
    let explains = |p: &RowMajor3| {
        let excluded_known = ratios
            .iter()
            .all(|(name, _)| spins.iter().any(|s| s.name == *name));
        excluded_known
            && spins.iter().all(|s| {
                // A permutation keeps a rate's magnitude: a free spin reads its plan under any.
                let reads = s.axis_b.map_or(1.0, |u| {
                    let pu: [f64; 3] =
                        core::array::from_fn(|i| (0..3).map(|j| p[i][j] * u[j]).sum::<f64>());
                    shared::linalg::dot(&u, &pu) / shared::linalg::dot(&u, &u)
                });
                match ratios.iter().find(|(name, _)| *name == s.name) {
                    Some((_, measured)) => (measured - reads).abs() < tolerance,
                    None => (reads - 1.0).abs() < tolerance,
                }
            })
    };
    signed_permutations()
        .filter(|p| explains(p))
        .min_by_key(changed_entries)
}

/// The 47 signed permutation matrices other than the identity.
fn signed_permutations() -> impl Iterator<Item = RowMajor3> {
    const ORDERS: [[usize; 3]; 6] = [
        [0, 1, 2],
        [0, 2, 1],
        [1, 0, 2],
        [1, 2, 0],
        [2, 0, 1],
        [2, 1, 0],
    ];
    ORDERS.into_iter().flat_map(|order| {
        (0..8u8).filter_map(move |signs| {
            let mut p = [[0.0; 3]; 3];
            for (i, &j) in order.iter().enumerate() {
                p[i][j] = if signs & (1 << i) != 0 { -1.0 } else { 1.0 };
            }
            (changed_entries(&p) > 0).then_some(p)
        })
    })
}

fn changed_entries(p: &RowMajor3) -> usize {
    (0..3)
        .flat_map(|i| (0..3).map(move |j| (i, j)))
        .filter(|&(i, j)| p[i][j] != if i == j { 1.0 } else { 0.0 })
        .count()
}

/// What the gyro's columns would have to be to read as `p` says, in the recording's terms.
fn mixup_cause(p: &RowMajor3) -> String {
    let ax = shared::params::axis_name;
    let diagonal = (0..3).all(|i| p[i][i] != 0.0);
    if diagonal {
        let negated: Vec<String> = (0..3)
            .filter(|&i| p[i][i] < 0.0)
            .map(|i| ax(i).to_string())
            .collect();
        return format!(
            "the gyro's {} column has its sign reversed (every spin reads as that sign predicts, \
             the oblique ones too): negate that column",
            negated.join(" and ")
        );
    }
    let reads: Vec<String> = (0..3)
        .filter_map(|i| {
            let j = (0..3).find(|&j| p[i][j] != 0.0)?;
            (i != j || p[i][j] < 0.0).then(|| {
                let sign = if p[i][j] < 0.0 { "−" } else { "" };
                format!("gyro {} reads {sign}body {}", ax(i), ax(j))
            })
        })
        .collect();
    format!(
        "the gyro's columns are swapped or reversed ({}; every spin reads as that predicts): \
         reorder the columns",
        reads.join(", ")
    )
}

#[cfg(test)]
mod tests {
    use super::*;
    use recording::testkit::SPELLING;

    const I: RowMajor3 = [[1.0, 0.0, 0.0], [0.0, 1.0, 0.0], [0.0, 0.0, 1.0]];

    #[test]
    fn a_real_gyro_passes() {
        let g = [
            [1.005, 0.01, -0.008],
            [0.009, 0.995, 0.008],
            [0.008, 0.004, 1.004],
        ];
        assert!(matrix_problems_spelled(&g, SPELLING).is_empty());
        assert!(matrix_problems_spelled(&I, SPELLING).is_empty());
    }

    #[test]
    fn a_reversed_axis_is_named() {
        let mut g = I;
        g[2][2] = -1.0;
        let p = matrix_problems_spelled(&g, SPELLING);
        assert_eq!(p.len(), 1, "{p:?}");
        assert!(p[0].contains("gyro axis z turns the wrong way"), "{p:?}");
    }

    #[test]
    fn swapped_axes_are_named() {
        let g = [[0.0, 1.0, 0.0], [1.0, 0.0, 0.0], [0.0, 0.0, 1.0]];
        let p = matrix_problems_spelled(&g, SPELLING);
        assert!(p[0].contains("swapped"), "{p:?}");
    }

    #[test]
    fn the_same_scale_on_every_axis_is_a_result_a_unit_or_beyond_range() {
        // 0.667× on every axis, a 2 % misalignment scaled with it: kept, the factor given.
        let g = [
            [2.0 / 3.0, 0.013, 0.0],
            [0.0, 0.668, 0.0],
            [0.0, 0.0, 0.665],
        ];
        assert!(
            matrix_problems_spelled(&g, SPELLING).is_empty(),
            "{:?}",
            matrix_problems_spelled(&g, SPELLING)
        );
        let k = common_scale(&g).unwrap();
        assert!((k - 0.6667).abs() < 1e-3, "{k}");
        assert_eq!(common_scale(&I), None);
        let g = I.map(|r| r.map(|v| v * 57.3));
        assert!(matrix_problems_spelled(&g, SPELLING)[0].contains("<GyroUnit> deg/s"));
        assert_eq!(common_scale(&g), None);
        let g = I.map(|r| r.map(|v| v * 6.0));
        assert!(matrix_problems_spelled(&g, SPELLING)[0].contains("beyond any nominal scale"));
        // Different errors per axis: no common factor, refused as a scale error.
        let g = [[1.3, 0.0, 0.0], [0.0, 1.0, 0.0], [0.0, 0.0, 1.0]];
        let p = matrix_problems_spelled(&g, SPELLING);
        assert!(p[0].contains("at most 20 % is plausible"), "{p:?}");
        assert_eq!(common_scale(&g), None);
    }

    #[test]
    fn a_large_misfit_is_refused() {
        assert!(misfit_problem(0.02, 23, MAX_TURN_MISFIT_DEG).is_none());
        assert!(misfit_problem(32.9, 23, MAX_TURN_MISFIT_DEG)
            .unwrap()
            .contains("sign is reversed"));
        assert!(misfit_problem(f64::NAN, 23, MAX_TURN_MISFIT_DEG).is_some());
    }

    fn ex(name: &str, measured: f64, planned: f64) -> Exclusion {
        Exclusion {
            name: name.into(),
            reason: ExclusionReason::RateContradiction {
                measured_deg_s: measured,
                planned_deg_s: planned,
            },
        }
    }

    /// Spins about each body axis, `per_axis` of them each, named "x 1", "x 2", …
    fn axis_spins(per_axis: usize) -> Vec<(String, [f64; 3])> {
        (0..3)
            .flat_map(|i| {
                (1..=per_axis).map(move |k| {
                    let mut u = [0.0; 3];
                    u[i] = 1.0;
                    (format!("{} {k}", shared::params::axis_name(i)), u)
                })
            })
            .collect()
    }

    fn spins(list: &[(String, [f64; 3])]) -> Vec<Spin<'_>> {
        list.iter()
            .map(|(name, u)| Spin {
                name,
                axis_b: Some(*u),
            })
            .collect()
    }

    #[test]
    fn rate_contradictions_name_their_cause() {
        let plan = axis_spins(3);
        let plan = spins(&plan);
        assert!(contradiction_problem(&[], &plan).is_none());
        let z = [
            ex("z 1", -100.0, 100.0),
            ex("z 2", -200.0, 200.0),
            ex("z 3", -300.0, 300.0),
        ];
        let p = contradiction_problem(&z, &plan).unwrap();
        assert!(p.contains("z column has its sign reversed"), "{p}");
        let p = contradiction_problem(&[ex("x 1", 5729.6, 100.0)], &plan).unwrap();
        assert!(p.contains("57.3×"), "{p}");
        // One spin that did not happen is the table's slip; most of them, the gyro's columns.
        let still = |n: &str| ex(n, 0.0, 100.0);
        assert!(contradiction_problem(&[still("x 1")], &plan).is_none());
        let many: Vec<Exclusion> = ["x 1", "x 2", "x 3", "y 1", "y 2"].map(still).into();
        let p = contradiction_problem(&many, &plan).unwrap();
        assert!(p.contains("swapped"), "{p}");
    }

    /// A negated z column reads −1 on a z spin but 0 on a spin halfway between y and z: the
    /// oblique plan's spins are explained by the same sign, so the gyro is refused, not half kept.
    #[test]
    fn a_negated_column_is_refused_on_oblique_spins_too() {
        let h = core::f64::consts::FRAC_1_SQRT_2;
        let mut plan = axis_spins(1);
        plan.push(("yz".into(), [0.0, h, h]));
        plan.push(("zx".into(), [h, 0.0, h]));
        plan.push(("xy".into(), [h, h, 0.0]));
        let plan = spins(&plan);
        let excluded = [
            ex("z 1", -200.0, 200.0),
            ex("yz", -0.01, 200.0),
            ex("zx", 0.02, -200.0),
        ];
        let p = contradiction_problem(&excluded, &plan).unwrap();
        assert!(p.contains("z column has its sign reversed"), "{p}");
        // Swapped y and z: the xy and zx spins read half their rate, the y, z and yz spins in full.
        let swapped = [
            ex("y 1", 0.0, 100.0),
            ex("z 1", 0.0, 100.0),
            ex("zx", 50.0, 100.0),
            ex("xy", 50.0, 100.0),
        ];
        let p = contradiction_problem(&swapped, &plan).unwrap();
        assert!(
            p.contains("gyro y reads body z, gyro z reads body y"),
            "{p}"
        );
        // One oblique spin that read nothing is a slip, not a column: no signed permutation gives 0
        // on yz alone while every axis spin reads in full.
        assert!(contradiction_problem(&[ex("yz", 0.0, 200.0)], &plan).is_none());
    }
}
