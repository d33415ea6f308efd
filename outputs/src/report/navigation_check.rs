//! What `host navigation-check` shows: the paper's navigation check on a simulated session of its
//! unit, calibrated with the joint method (`app::navigation_check` runs it): how far a navigator
//! drifts without compensation, with the static and with the static + dynamic one.

use super::data::ReportData;
use super::document::ReportSummary;
use super::navigation::{render_navigation, render_position_targets};
use estimator::estimate::CalibrationOutcome;
use std::fmt::Write as _;

/// The result of `host navigation-check`.
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
