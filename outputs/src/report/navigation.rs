//! The navigation check of the paper (Figures 6/7 and 9/10): integrate the specific-force error of a
//! run twice and see how far a navigator would drift.
//!
//! As in the paper's ground experiment, the integration is done in body axes with the plan's known
//! attitude: on a table spinning about the vertical, gravity is constant in body axes (`g·up_b`), and
//! so is the true specific force at the reference point, so `a = f − g·up_b` is the acceleration error
//! a strap-down navigator would integrate before attitude rotation. This is the error budget the paper
//! plots; a full mechanisation would additionally rotate the across-axis part of the error and average it
//! out over each turn, which hides exactly the lever-arm error this check is meant to show.
//!
//! # The replay (paper Figs. 6/7 and 9/10)
//!
//! A **noise-free replay**: the recorded mean outputs of a segment (what the unit measures in that
//! attitude at that rate) are taken as a constant specific force over the whole run (60 s by default),
//! compensated three ways, gravity (the true specific force above) removed, and integrated twice in body
//! axes by `integrate_drift`. White noise would add a random walk that hides the error the calibration
//! leaves; replaying the means shows exactly that error, `½·e·t²`. One static run and one rotating run

use super::data::{Compensation, SegmentRow};
use super::figures::fmt_rate;
use shared::linalg;
use std::fmt::Write as _;

/// Velocity and position error of one run, sampled at the integration steps.
#[derive(Clone, Debug, PartialEq)]
pub struct Drift {
    /// Time since the start of the run, s.
    pub t_s: Vec<f64>,
    /// Velocity error, body axes, m/s.
    pub velocity_m_s: Vec<[f64; 3]>,
    /// Position error, body axes, m.
    pub position_m: Vec<[f64; 3]>,
}

impl Drift {
    /// Norm of the final position error, m.
    pub(crate) fn final_position_error_m(&self) -> f64 {
        self.position_m.last().map_or(0.0, norm)
    }

    /// Norm of the final velocity error, m/s.
    pub(crate) fn final_velocity_error_m_s(&self) -> f64 {
        self.velocity_m_s.last().map_or(0.0, norm)
    }
}

fn norm(v: &[f64; 3]) -> f64 {
    (v[0] * v[0] + v[1] * v[1] + v[2] * v[2]).sqrt()
}

/// Integrates `(t, f)` samples (f: specific force at the reference point, body axes, m/s²) minus the
/// true specific force `g·up_b`, with the trapezoidal rule, starting at rest.
pub(crate) fn integrate_drift(
    samples: impl IntoIterator<Item = (f64, [f64; 3])>,
    true_f_m_s2: [f64; 3],
) -> Drift {
    let mut d = Drift {
        t_s: Vec::new(),
        velocity_m_s: Vec::new(),
        position_m: Vec::new(),
    };
    let mut prev: Option<(f64, [f64; 3])> = None;
    let mut v = [0.0; 3];
    let mut p = [0.0; 3];
    let mut t0 = 0.0;
    for (t, f) in samples {
        let a: [f64; 3] = std::array::from_fn(|j| f[j] - true_f_m_s2[j]);
        match prev {
            None => t0 = t,
            Some((tp, ap)) => {
                let dt = t - tp;
                for j in 0..3 {
                    let v_new = v[j] + 0.5 * (a[j] + ap[j]) * dt;
                    p[j] += 0.5 * (v[j] + v_new) * dt;
                    v[j] = v_new;
                }
            }
        }
        d.t_s.push(t - t0);
        d.velocity_m_s.push(v);
        d.position_m.push(p);
        prev = Some((t, a));
    }
    d
}

/// One compensation level of a replayed run.
#[derive(Clone, Debug, PartialEq)]
pub struct NavigationCase {
    /// The level.
    pub compensation: Compensation,
    /// The constant specific-force error replayed, g.
    pub error_g: [f64; 3],
    /// Velocity and position error over the run.
    pub drift: Drift,
}

/// A replayed run (noise-free: the segment's mean outputs held for the whole run).
#[derive(Clone, Debug, PartialEq)]
pub struct NavigationRun {
    /// The segment replayed.
    pub segment: String,
    /// Its mean rate, °/s.
    pub rate_deg_s: f64,
    /// Length of the run, s.
    pub duration_s: f64,
    /// Before, static only, static + dynamic.
    pub cases: Vec<NavigationCase>,
}

impl NavigationRun {
    /// The case of a compensation level.
    pub fn case(&self, c: Compensation) -> &NavigationCase {
        self.cases
            .iter()
            .find(|k| k.compensation == c)
            .expect("every run has all three cases")
    }
}

/// Replays one segment's mean outputs for `duration_s` (see the module doc).
pub(crate) fn replay(row: &SegmentRow, g: f64, duration_s: f64, step_s: f64) -> NavigationRun {
    let steps = (duration_s / step_s).round().max(1.0) as usize;
    let truth = row.truth_g.map(|v| v * g);
    let cases = Compensation::ALL
        .iter()
        .map(|&c| {
            let f = row.output_g(c).map(|v| v * g);
            let drift = integrate_drift(
                (0..=steps).map(|k| (k as f64 * duration_s / steps as f64, f)),
                truth,
            );
            NavigationCase {
                compensation: c,
                error_g: row.error_g(c),
                drift,
            }
        })
        .collect();
    NavigationRun {
        segment: row.name.clone(),
        rate_deg_s: row.rate_deg_s,
        duration_s,
        cases,
    }
}

/// The final position errors of the static and the rotating run against their targets (tens of metres uncompensated, under 0.3 m after static calibration, under 1 m after static + dynamic), one line per run.
pub fn render_position_targets(runs: &[NavigationRun]) -> String {
    let mut s = String::new();
    let pos = |run: &NavigationRun, c| run.case(c).drift.final_position_error_m();
    if let Some(st) = runs.iter().find(|r| r.rate_deg_s.abs() < 0.5) {
        let _ = writeln!(
            s,
            "static run '{}', {:.0} s: without compensation {:.1} m (target: tens of metres or more; \
             paper: about 100 m); after static calibration {:.3} m (target: under 0.3 m)",
            st.segment,
            st.duration_s,
            pos(st, Compensation::BiasScale),
            pos(st, Compensation::Static)
        );
    }
    if let Some(rt) = runs.iter().find(|r| r.rate_deg_s.abs() >= 0.5) {
        let _ = writeln!(
            s,
            "{:.0} °/s run '{}', {:.0} s: static-only {:.1} m (target: tens of metres); static+dynamic \
             {:.3} m (target: under 1 m)",
            rt.rate_deg_s,
            rt.segment,
            rt.duration_s,
            pos(rt, Compensation::Static),
            pos(rt, Compensation::Full)
        );
    }
    s
}

/// The navigation table as plain text.
pub(crate) fn render_navigation(runs: &[NavigationRun]) -> String {
    let mut s = String::new();
    let _ = writeln!(
        s,
        "Navigation check (noise-free replay of each segment's mean outputs):"
    );
    let _ = writeln!(
        s,
        "  {:<10} {:>8}  {:<26} {:>12} {:>14} {:>12}",
        "run", "°/s", "compensation", "|error| mg", "|v| end m/s", "|p| end m"
    );
    for run in runs {
        for c in &run.cases {
            let _ = writeln!(
                s,
                "  {:<10} {:>8}  {:<26} {:>12.4} {:>14.4} {:>12.3}",
                run.segment,
                fmt_rate(run.rate_deg_s),
                c.compensation.label(),
                linalg::norm(&c.error_g) * 1e3,
                c.drift.final_velocity_error_m_s(),
                c.drift.final_position_error_m()
            );
        }
    }
    s
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn constant_error_drifts_as_half_a_t_squared() {
        // A 1 mg error for 60 s: v = a t = 0.588 m/s, p = a t²/2 = 17.65 m (hand-derived).
        let a = 1e-3 * 9.80665;
        let samples = (0..=6000).map(|k| (k as f64 * 0.01, [a, 0.0, 9.80665]));
        let d = integrate_drift(samples, [0.0, 0.0, 9.80665]);
        assert!((d.final_velocity_error_m_s() - a * 60.0).abs() < 1e-9);
        assert!((d.final_position_error_m() - 0.5 * a * 3600.0).abs() < 1e-6);
        assert_eq!(d.t_s.len(), 6001);
    }
}
