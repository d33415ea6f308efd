//! `host navigation-check`: the paper's navigation check on a simulated session of its unit,
//! calibrated with the joint method: how far a navigator drifts without compensation, with the
//! static and with the static + dynamic one. The session is simulated and fitted here, and the
//! report (`outputs::report`) is built from the fit and written.

use estimator::estimate::{calibrate_session_stats, CalibrationOutcome};
use estimator::sim::{simulate_unit_stats, NoiseModel};
use estimator::unit_file::UnitFile;
use outputs::calibration_guard::{meet, Meeting, Mine, Other, Temperatures};
use outputs::report::{build_report, write_report, NavigationCheck, ReportError, ReportOptions};
use recording::session::builtin::paper_plan;
use recording::session::Plan;
use recording::spelling::{Spelling, UserOption};
use std::path::PathBuf;

/// Settings of [`navigation_check`]: the paper's unit and plan, 1 mg white noise, a fixed seed.
#[derive(Clone, Debug)]
pub struct NavigationCheckArgs {
    /// The unit simulated (default: the paper's, `reference/paper-unit.toml`).
    pub unit: UnitFile,
    /// The plan (default: the paper's).
    pub plan: Plan,
    /// Noise (default: 1 mg accelerometer white noise, 0.05 °/s gyro white noise).
    pub noise: NoiseModel,
    /// Seed.
    pub seed: u64,
    /// Report settings (navigation run length, …).
    pub report: ReportOptions,
    /// Where to write the figures and the page; `None`: nothing written.
    pub out_dir: Option<PathBuf>,
}

impl NavigationCheckArgs {
    /// The paper's unit and plan, the default noise and report, the fit's messages spelled as the
    /// caller spells its options.
    pub fn new(spelling: Spelling) -> NavigationCheckArgs {
        NavigationCheckArgs {
            unit: UnitFile::paper_unit(),
            plan: paper_plan(),
            noise: NoiseModel::default(),
            seed: 1,
            report: ReportOptions::new(spelling),
            out_dir: None,
        }
    }
}

/// A fit of a simulated session is held to the calibration's own χ²/dof limit, the main fit's and
/// the temperature fit's ([`outputs::summary::DEFAULT_MAX_CHI2_PER_DOF`]).
fn refuse_misfit(outcome: &CalibrationOutcome) -> Result<(), ReportError> {
    let limit = outputs::summary::DEFAULT_MAX_CHI2_PER_DOF;
    let thermal = outcome.thermal.as_ref().map(|t| t.worst_reduced_chi2());
    let figures = [
        ("χ²/dof", Some(outcome.fit.reduced_chi2)),
        ("the temperature fit's χ²/dof", thermal),
    ];
    for (what, value) in figures {
        // NaN is a misfit too.
        if let Some(value) = value.filter(|v| v.is_nan() || *v > limit) {
            return Err(ReportError::Misfit { what, value, limit });
        }
    }
    Ok(())
}

/// `host navigation-check`: the paper's unit simulated with its plan (1 mg white noise, fixed seed),
/// calibrated with the joint method, and the navigation replay of a static and the fastest rotating
/// segment; its `render` gives the final position errors against their targets.
pub fn navigation_check(args: &NavigationCheckArgs) -> Result<NavigationCheck, ReportError> {
    let truth = args
        .unit
        .to_calibration()
        .map_err(ReportError::Calibration)?;
    // Only the scales can fail here: the session is simulated from this unit (the guard's table).
    let name = format!(
        "the {} file",
        args.report.estimate.spelling.name(UserOption::Unit)
    );
    meet(
        Meeting::NavigationCheck,
        &Mine {
            name: &name,
            cal: &truth,
            unit_id: None,
        },
        &Other {
            name: "its simulated session",
            unit_id: None,
            output_unit: None,
            frame: None,
            temperatures: Temperatures::None,
        },
    )?;
    // The unit as `host simulate` records it: with its temperatures where the plan has them.
    let stats = simulate_unit_stats(&args.unit, &args.plan, &args.noise, args.seed)
        .map_err(ReportError::Simulate)?;
    let outcome = calibrate_session_stats(&args.plan, &stats, &args.report.estimate)
        .map_err(ReportError::Estimate)?;
    refuse_misfit(&outcome)?;
    let data = build_report(
        &args.plan,
        &stats,
        &outcome.calibration,
        Some(&outcome.uncertainty),
        Ok(outcome.clone()),
        &args.report,
    )?;
    if data.navigation.is_empty() {
        return Err(ReportError::NothingToReplay(data.navigation_left_out));
    }
    let written = match &args.out_dir {
        Some(dir) => Some(write_report(
            &data,
            dir,
            &format!(
                "simulated: paper unit, {} plan, {} mg white noise, seed {}",
                if args.plan == paper_plan() {
                    "paper"
                } else {
                    "given"
                },
                args.noise.accel_white_mg,
                args.seed
            ),
            "estimated from it (joint method)",
            args.report.formats,
        )?),
        None => None,
    };
    Ok(NavigationCheck {
        outcome,
        data,
        written,
    })
}

#[cfg(test)]
mod tests {
    use super::*;
    use recording::session::builtin::builtin_plan;

    #[test]
    fn navigation_check_prints_the_position_errors_against_targets() {
        // The short plan keeps this fast; the paper's plan is what the command runs by default.
        let dir = tempfile::tempdir().unwrap();
        let check = navigation_check(&NavigationCheckArgs {
            plan: builtin_plan("short").unwrap().unwrap(),
            out_dir: Some(dir.path().to_path_buf()),
            ..NavigationCheckArgs::new(recording::testkit::SPELLING)
        })
        .unwrap();
        let text = check.render();
        assert!(
            text.contains("static run 'x+', 60 s: without compensation"),
            "{text}"
        );
        assert!(
            text.contains("200 °/s run 'x+ 200', 60 s: static-only"),
            "{text}"
        );
        assert!(dir.path().join(outputs::report::REPORT_HTML).exists());
    }

    /// A fit far beyond its noise (χ²/dof 1.6·10⁶, what a thermal unit simulated without its
    /// temperatures gave) is refused, naming the figure and the limit; the fit of the simulated
    /// session itself passes.
    #[test]
    fn a_misfit_far_beyond_the_noise_is_refused() {
        let unit = UnitFile::paper_unit();
        let plan = builtin_plan("quick-oblique").unwrap().unwrap();
        let stats = simulate_unit_stats(&unit, &plan, &NoiseModel::default(), 3).unwrap();
        let mut outcome = calibrate_session_stats(&plan, &stats, &Default::default()).unwrap();
        refuse_misfit(&outcome).unwrap();
        outcome.fit.reduced_chi2 = 1.6e6;
        let e = refuse_misfit(&outcome).unwrap_err().to_string();
        assert!(
            e.contains("χ²/dof = 1.6000e6") && e.contains("above 100"),
            "{e}"
        );
        outcome.fit.reduced_chi2 = f64::NAN;
        assert!(refuse_misfit(&outcome).is_err());
    }
}
