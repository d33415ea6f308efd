//! `host navigation-check`: the paper's navigation check on a simulated session of its unit,
//! calibrated with the joint method: how far a navigator drifts without compensation, with the static
//! and with the static + dynamic one.

use super::data::{build_report, ReportData, ReportError, ReportOptions};
use super::document::{write_report, ReportSummary};
use super::navigation::{render_navigation, render_position_targets};
use crate::estimate::{calibrate_session_stats, CalibrationOutcome};
use crate::session::builtin::paper_plan;
use crate::session::Plan;
use crate::sim::{simulate_stats, NoiseModel};
use crate::unit_file::UnitFile;
use std::fmt::Write as _;
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

impl Default for NavigationCheckArgs {
    fn default() -> Self {
        NavigationCheckArgs {
            unit: UnitFile::paper_unit(),
            plan: paper_plan(),
            noise: NoiseModel::default(),
            seed: 1,
            report: ReportOptions::default(),
            out_dir: None,
        }
    }
}

/// The result of [`navigation_check`].
#[derive(Clone, Debug)]
pub struct NavigationCheck {
    /// The calibration of the simulated session (joint method by default).
    pub outcome: CalibrationOutcome,
    /// The report on it.
    pub data: ReportData,
    /// What was written, when `out_dir` was given.
    pub written: Option<ReportSummary>,
}

impl NavigationCheck {
    /// What the CLI prints: the navigation table and the position errors against their targets.
    pub fn render(&self) -> String {
        let mut s = render_navigation(&self.data.navigation);
        for why in &self.data.navigation_left_out {
            let _ = writeln!(s, "  left out: {why}");
        }
        s.push_str(&render_position_targets(&self.data.navigation));
        if let Some(w) = &self.written {
            let _ = writeln!(s, "Report: {}", w.page.display());
        }
        s
    }
}

/// `host navigation-check`: the paper's unit simulated with its plan (1 mg white noise, fixed seed),
/// calibrated with the joint method, and the navigation replay of a static and the fastest rotating
/// segment. Prints (via [`NavigationCheck::render`]) the final position errors against their targets.
pub fn navigation_check(args: &NavigationCheckArgs) -> Result<NavigationCheck, ReportError> {
    let truth = args
        .unit
        .to_calibration()
        .map_err(ReportError::Calibration)?;
    // Only the scales can fail here: the session is simulated from this unit (the guard's table).
    crate::calibration_guard::meet(
        crate::calibration_guard::Meeting::NavigationCheck,
        &crate::calibration_guard::Mine {
            name: "the --unit file",
            cal: &truth,
            unit_id: None,
        },
        &crate::calibration_guard::Other {
            name: "its simulated session",
            unit_id: None,
            output_unit: None,
            frame: None,
            temperatures: crate::calibration_guard::Temperatures::None,
        },
    )?;
    let stats = simulate_stats(&truth, &args.plan, &args.noise, args.seed)
        .map_err(ReportError::Simulate)?;
    let outcome = calibrate_session_stats(&args.plan, &stats, &args.report.estimate)
        .map_err(ReportError::Estimate)?;
    let data = build_report(
        &args.plan,
        &stats,
        &outcome.calibration,
        Some(&outcome.uncertainty),
        Some(outcome.clone()),
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
