//! Single-package units (docs/model.md §4.7): whether the session tells the three accelerometers'
//! lever arms apart, tested on the residuals.
//!
//! The fit with one lever arm `r` for the three accelerometers is the fit with nine components under
//! the six linear constraints `r_i = r`, so the rise of χ² from the nine-component fit to the
//! one-point fit is χ²-distributed with (about) six degrees of freedom when the unit is one point.
//! That one statistic answers both questions: with the option, a rise above its 99.9 % point means
//! the session resolves different lever arms, and the fit is refused; without it, a rise below its
//! 95 % point means the nine components fitted noise, and a warning names the option.

use super::model::{idx_r, r_of};
use super::note::Note;
use super::solve::{self, Problem};
use super::{EstimateOptions, Method, ReferenceChoice};
use recording::spelling::{Spelling, UserOption};

/// The one line every output gives for a single-package unit's in-package size effect.
pub const IN_PACKAGE_NOT_OBSERVABLE: &str =
    "in-package size effect (each accelerometer's lever arm minus the package's, r_i − r): not \
     observable — the three sensing points lie within a millimetre of each other in one package, \
     below what a rate-table session resolves, so one lever arm r is fitted for the three \
     (docs/model.md §4.7)";

/// Why the single-package model was refused.
#[derive(Clone, Debug, PartialEq, thiserror::Error)]
pub enum PackageRefusal {
    /// The paper's eq. 24 fits each component on its own: it has no single-point form.
    #[error(
        "the paper's eq. 24 estimates each accelerometer's lever arm on its own; use {} with {}",
        .0.given(UserOption::Method, "joint"),
        .0.switch(UserOption::SinglePackage)
    )]
    PaperMethod(Spelling),
    /// Relative to the centroid every lever arm of a single-package unit is 0 by construction.
    #[error(
        "relative to the sensing points' centroid a single-package unit's lever arms are all 0 by \
         construction; use {} to get the package's position",
        .0.given(UserOption::Reference, "table-axis")
    )]
    CentroidReference(Spelling),
    /// The residuals show the three lever arms differ (χ² test).
    #[error(
        "this session resolves different lever arms for the three accelerometers (they differ by up \
         to {spread_mm:.2} mm; the one-point fit raises χ² by {delta_chi2:.1} for {dof} degrees of \
         freedom, above its 99.9 % point {limit:.1}), so they are not one point at this session's \
         precision; calibrate without {} (and without package = \"single\" in \
         plan.toml) to fit each accelerometer's lever arm",
        .spelling.switch(UserOption::SinglePackage)
    )]
    Contradicted {
        /// Largest distance of one accelerometer's lever-arm component from the three's mean in the
        /// nine-component fit, mm.
        spread_mm: f64,
        /// χ² rise from the nine-component fit to the one-point fit, divided by the nine-component
        /// fit's χ²/dof when that is above 1.
        delta_chi2: f64,
        /// Its degrees of freedom (the constraints that bind).
        dof: i64,
        /// The 99.9 % point of χ² with `dof` degrees of freedom.
        limit: f64,
        /// The caller's names of the options.
        spelling: Spelling,
    },
}

/// The χ² test of the one-point model against the nine-component one.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct PackageTest {
    /// χ² rise from the nine-component to the one-point fit, over max(1, χ²/dof of the former).
    pub delta_chi2: f64,
    /// Its degrees of freedom.
    pub dof: i64,
    /// Largest |r_i\[j\] − mean_i r_i\[j\]| of the nine-component fit, m.
    pub spread_m: f64,
}

/// The single-package model's preconditions: the joint method, a reference other than the
/// centroid.
pub(crate) fn preconditions(options: &EstimateOptions) -> Result<(), PackageRefusal> {
    if !options.single_package {
        return Ok(());
    }
    if options.method == Method::Paper {
        return Err(PackageRefusal::PaperMethod(options.spelling));
    }
    if options.reference == ReferenceChoice::Centroid {
        return Err(PackageRefusal::CentroidReference(options.spelling));
    }
    Ok(())
}

/// The χ² test of one lever arm against three on a joint fit of a session that turns: with the
/// option, a refusal when the session resolves three different lever arms (or a warning when it
/// cannot tell); without it, a warning naming the option when the three do not differ
/// significantly.
pub(crate) fn check(
    problem: &Problem,
    main: &Fitted<'_>,
    options: &EstimateOptions,
    warnings: &mut Vec<Note>,
) -> Result<Option<PackageTest>, PackageRefusal> {
    let Some(t) = test(problem, main, options) else {
        if options.single_package {
            warnings.push(Note::PackageUntested);
        }
        return Ok(None);
    };
    warnings.extend(verdict(&t, options.single_package, options.spelling)?);
    Ok(Some(t))
}

/// The main fit the test starts from.
pub(crate) struct Fitted<'a> {
    pub theta: &'a [f64],
    pub free: &'a [bool],
    pub chi2: f64,
    pub dof: i64,
}

/// The other lever-arm model fitted on the same problem from the main fit, and the test; `None`
/// when the other fit is singular or binds no constraint.
pub(crate) fn test(
    problem: &Problem,
    main: &Fitted<'_>,
    options: &EstimateOptions,
) -> Option<PackageTest> {
    let mut other = problem.clone();
    other.single_package = !problem.single_package;
    let mut t = main.theta.to_vec();
    let mut free = main.free.to_vec();
    if other.single_package {
        // Start from the mean of the free components, each component free if any axis had it.
        for j in 0..3 {
            let on: Vec<usize> = (0..3).filter(|&i| free[idx_r(i, j)]).collect();
            let mean = on.iter().map(|&i| t[idx_r(i, j)]).sum::<f64>() / on.len().max(1) as f64;
            for i in 0..3 {
                free[idx_r(i, j)] = !on.is_empty();
                t[idx_r(i, j)] = mean;
            }
        }
    }
    solve::structurally_unobservable(
        &other,
        &mut t,
        &mut free,
        options.lever_arm_structural_limit_m,
    );
    let fit = solve::fit(&other, t, free, "lever-arm model test").ok()?;
    let (one, nine) = if problem.single_package {
        ((main.chi2, main.dof), (fit.chi2, fit.dof))
    } else {
        ((fit.chi2, fit.dof), (main.chi2, main.dof))
    };
    let dof = one.1 - nine.1;
    if dof <= 0 {
        return None;
    }
    let r = if problem.single_package {
        r_of(&fit.theta)
    } else {
        r_of(main.theta)
    };
    let spread_m = (0..3)
        .flat_map(|j| {
            let mean = (r[0][j] + r[1][j] + r[2][j]) / 3.0;
            (0..3).map(move |i| (r[i][j] - mean).abs())
        })
        .fold(0.0, f64::max);
    let scale2 = if nine.1 > 0 {
        (nine.0 / nine.1 as f64).max(1.0)
    } else {
        1.0
    };
    Some(PackageTest {
        delta_chi2: (one.0 - nine.0).max(0.0) / scale2,
        dof,
        spread_m,
    })
}

/// With the option: the refusal when the test rejects one point. Without it: the warning naming the
/// option when the nine components do not differ significantly.
pub(crate) fn verdict(
    test: &PackageTest,
    single_package: bool,
    sp: Spelling,
) -> Result<Option<Note>, PackageRefusal> {
    if single_package {
        let limit = chi2_quantile(test.dof, Z_999);
        if test.delta_chi2 > limit {
            return Err(PackageRefusal::Contradicted {
                spread_mm: test.spread_m * 1e3,
                delta_chi2: test.delta_chi2,
                dof: test.dof,
                limit,
                spelling: sp,
            });
        }
        return Ok(None);
    }
    let limit = chi2_quantile(test.dof, Z_95);
    Ok((test.delta_chi2 < limit).then_some(Note::LeverArmsAlike {
        delta_chi2: test.delta_chi2,
        dof: test.dof,
        limit,
        spelling: sp,
    }))
}

/// The standard normal's 99.9 % and 95 % points.
const Z_999: f64 = 3.090_232;
const Z_95: f64 = 1.644_854;

/// The χ² distribution's point with `dof` degrees of freedom at the normal point `z`
/// (Wilson–Hilferty: (χ²/k)^(1/3) is nearly normal with mean 1 − 2/(9k), variance 2/(9k); within
/// 1 % of the exact 99.9 % point for k ≥ 3).
pub(crate) fn chi2_quantile(dof: i64, z: f64) -> f64 {
    let k = dof as f64;
    let v = 2.0 / (9.0 * k);
    k * (1.0 - v + z * v.sqrt()).powi(3)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn chi2_points_match_the_tables() {
        // Tabulated: χ²(6) 95 % 12.592, 99.9 % 22.458; χ²(3) 99.9 % 16.266.
        assert!((chi2_quantile(6, Z_95) - 12.592).abs() < 0.1);
        assert!((chi2_quantile(6, Z_999) - 22.458).abs() < 0.3);
        assert!((chi2_quantile(3, Z_999) - 16.266).abs() < 0.3);
    }
}
