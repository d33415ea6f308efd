//! The terminal report of a calibration: the paper's Table 1 (zero bias, scale factor, installation
//! angles) and Table 3 (lever arms) with 1σ, the per-segment residuals before and after compensation
//! (like Tables 2 and 4) with the χ² check, the excluded segments, the method comparison and the
//! warnings. Plain text, no colour, so it reads the same in a log.

use crate::estimate::{
    CalibrationOutcome, Method, Prediction, SegmentDiagnostic, SegmentKind, PAPER_LEN,
};
use shared::params::axis_name;
use shared::OutputUnit;
use std::fmt::Write;

fn out_digits(unit: OutputUnit) -> usize {
    match unit {
        OutputUnit::Volts => 6,
        OutputUnit::Lsb => 3,
    }
}

/// `v ± s` with at least `digits` decimals, and more when needed to show two significant digits of
/// the 1σ (a bias known to 0.1 µV must not print as "± 0.000000").
fn pm(v: f64, s: f64, digits: usize) -> String {
    if s.is_finite() {
        let needed = if s > 0.0 {
            (1.0 - s.log10().floor()).max(0.0) as usize
        } else {
            0
        };
        let digits = digits.max(needed).min(10);
        format!("{v:.digits$} ± {s:.digits$}")
    } else {
        format!("{v:.digits$} ± ∞")
    }
}

/// Lever arm in mm with its 1σ, marked when not determined.
fn lever_cell(r: f64, s: f64, observable: bool, fixed: bool) -> String {
    if fixed {
        "fixed at 0 (n.o.)".to_string()
    } else if observable {
        format!("{:+.4} ± {:.4}", r * 1e3, s * 1e3)
    } else {
        format!("({:+.3} ± {:.3}) n.d.", r * 1e3, s * 1e3)
    }
}

/// The full report.
pub fn render(o: &CalibrationOutcome) -> String {
    let mut s = String::new();
    let unit = o.calibration.statics.output_unit;
    let sym = unit.symbol();
    let d = out_digits(unit);
    let st = &o.calibration.statics;
    let u = &o.uncertainty;
    let _ = writeln!(s, "Calibration ({}), 1σ{}", o.method, sigma_note(o));
    let _ = writeln!(s);
    let _ = writeln!(s, "Table 1. Static calibration");
    let _ = writeln!(
        s,
        "{:<4} {:>26} {:>26}   Installation angles θ_ix, θ_iy, θ_iz (°)",
        "No.",
        format!("Zero bias ({sym})"),
        format!("Scale factor ({sym}/g)"),
    );
    for i in 0..3 {
        let angles: Vec<String> = (0..3)
            .map(|j| {
                pm(
                    st.installation_angles_deg[i][j],
                    u.installation_angles_deg_1sigma[i][j],
                    5,
                )
            })
            .collect();
        let _ = writeln!(
            s,
            "{:<4} {:>26} {:>26}   ({})",
            i + 1,
            pm(st.zero_bias_out[i], u.zero_bias_1sigma[i], d),
            pm(st.scale_out_per_g[i], u.scale_per_g_1sigma[i], d),
            angles.join(", ")
        );
    }
    let _ = writeln!(s);
    let _ = writeln!(
        s,
        "Table 3. Lever arms (mm), reference: {:?}; n.d. = not determined to {:.0} µm, n.o. = not observable",
        o.calibration.reference,
        o.observability.threshold_m * 1e6
    );
    let _ = writeln!(s, "{:<4} {:>24} {:>24} {:>24}", "", "x", "y", "z");
    for i in 0..3 {
        let cells: Vec<String> = (0..3)
            .map(|j| {
                lever_cell(
                    o.calibration.lever_arms.r_m[i][j],
                    u.lever_arms_m_1sigma[i][j],
                    o.observability.observable[i][j],
                    o.observability.fixed_at_zero[i][j],
                )
            })
            .collect();
        let _ = writeln!(
            s,
            "{:<4} {:>24} {:>24} {:>24}",
            format!("r{}", i + 1),
            cells[0],
            cells[1],
            cells[2]
        );
    }
    if let Some(c) = &o.comparison {
        let _ = writeln!(s);
        let _ = writeln!(s, "Lever arms by method (mm): {} | {}", o.method, c.method);
        for i in 0..3 {
            for j in 0..3 {
                let _ = writeln!(
                    s,
                    "  r{}{}  {:>22} | {:>22}",
                    i + 1,
                    axis_name(j),
                    pm(
                        o.calibration.lever_arms.r_m[i][j] * 1e3,
                        u.lever_arms_m_1sigma[i][j] * 1e3,
                        4
                    ),
                    pm(
                        c.lever_arms.r_m[i][j] * 1e3,
                        c.lever_arm_sigma_m[i][j] * 1e3,
                        4
                    ),
                );
            }
        }
        for n in &c.notes {
            let _ = writeln!(s, "  note: {n}");
        }
        if c.method == Method::Paper || o.method == Method::Paper {
            let _ = writeln!(
                s,
                "  (eq. 24 divides the across-axis components by cos θ_ij ≈ 0.01: expect them to be poor)"
            );
        }
    }
    let _ = writeln!(s);
    let _ = writeln!(
        s,
        "Residuals per segment (g), like Tables 2 and 4: theoretical | bias+scale only | static compensation | full compensation; χ² of 3 outputs against the segment's own noise (* = above the 99.9 % point 16.3)"
    );
    for dgn in &o.segments {
        render_segment(&mut s, dgn);
    }
    let _ = writeln!(
        s,
        "Fit: χ² = {:.1}, dof = {}, χ²/dof = {:.2}, 1σ scaled by {:.2}",
        o.fit.chi2, o.fit.dof, o.fit.reduced_chi2, o.fit.sigma_scale
    );
    super::thermal::render(&mut s, o);
    if !o.excluded.is_empty() {
        let _ = writeln!(s);
        let _ = writeln!(s, "Excluded segments:");
        for e in &o.excluded {
            let _ = writeln!(s, "  '{}': {}", e.name, e.reason);
        }
    }
    if !o.warnings.is_empty() {
        let _ = writeln!(s);
        let _ = writeln!(s, "Warnings:");
        for w in &o.warnings {
            let _ = writeln!(s, "  - {w}");
        }
    }
    s
}

fn sigma_note(o: &CalibrationOutcome) -> String {
    if o.fit.sigma_scale > 1.0 {
        format!(" (scaled by √(χ²/dof) = {:.2})", o.fit.sigma_scale)
    } else {
        String::new()
    }
}

fn render_segment(s: &mut String, d: &SegmentDiagnostic) {
    let kind = match d.kind {
        SegmentKind::Static => "static".to_string(),
        SegmentKind::ConstantRate => format!("{:+.1} °/s", d.rate_deg_s),
        SegmentKind::Ramp => format!("ramp, mean {:+.1} °/s", d.rate_deg_s),
    };
    let chi = match d.chi2 {
        Some(c) => format!("χ² {c:.1}{}", if d.chi2_flagged { " *" } else { "" }),
        None => "excluded".to_string(),
    };
    let _ = writeln!(
        s,
        "  {} — up [{:+.3}, {:+.3}, {:+.3}], {kind}, {} rows, {chi}",
        d.name, d.up_b[0], d.up_b[1], d.up_b[2], d.count
    );
    for i in 0..3 {
        let _ = writeln!(
            s,
            "    {}  {:+.6} | {:+.6} | {:+.6} | {:+.6}   (σ {:.1} µg)",
            axis_name(i),
            d.theoretical_g[i],
            d.before_g[i],
            d.after_static_g[i],
            d.after_g[i],
            d.noise_g[i] * 1e6
        );
    }
}

/// The Cramér–Rao prediction of a plan (`host plan --check`).
pub fn render_prediction(p: &Prediction) -> String {
    let mut s = String::new();
    let sym = p.output_unit.symbol();
    let d = out_digits(p.output_unit) + 1;
    let _ = writeln!(s, "Predicted 1σ (Cramér–Rao bound) for this plan:");
    for k in 0..PAPER_LEN {
        let label = &p.labels[k];
        let (value, sigma, unit, mark) = if k < 6 {
            (
                format!("{:.d$}", p.values[k]),
                format!("{:.d$}", p.sigma[k]),
                if k < 3 {
                    sym.to_string()
                } else {
                    format!("{sym}/g")
                },
                "",
            )
        } else if k < 15 {
            (
                format!("{:.5}", p.values[k]),
                format!("{:.6}", p.sigma[k]),
                "°".to_string(),
                "",
            )
        } else {
            let (i, j) = ((k - 15) / 3, (k - 15) % 3);
            let mark = if p.lever_arms_fixed[i][j] {
                "  NOT OBSERVABLE (fixed at 0)"
            } else if !p.lever_arms_observable[i][j] {
                "  not determined"
            } else {
                ""
            };
            (
                format!("{:+.4}", p.values[k] * 1e3),
                if p.sigma[k].is_finite() {
                    format!("{:.4}", p.sigma[k] * 1e3)
                } else {
                    "∞".to_string()
                },
                "mm".to_string(),
                mark,
            )
        };
        let _ = writeln!(s, "  {label:<10} {value:>14} ± {sigma} {unit}{mark}");
    }
    let _ = writeln!(s, "Lever-arm threshold: {:.0} µm", p.threshold_m * 1e6);
    for w in &p.warnings {
        let _ = writeln!(s, "  - {w}");
    }
    s
}

#[cfg(test)]
mod tests {
    use crate::estimate::{calibrate_session_stats, EstimateOptions};
    use crate::session::Plan;
    use crate::sim::synth::{self, SynthNoise};

    const PLAN: &str = r#"
output_unit = "V"
sample_rate_hz = 1000
[[segment]]
name = "x+"
up_b = [1, 0, 0]
[[segment]]
name = "x-"
up_b = [-1, 0, 0]
[[segment]]
name = "y+"
up_b = [0, 1, 0]
[[segment]]
name = "y-"
up_b = [0, -1, 0]
[[segment]]
name = "z+"
up_b = [0, 0, 1]
[[segment]]
name = "z-"
up_b = [0, 0, -1]
[[segment]]
name = "x+ 200"
up_b = [1, 0, 0]
rate_deg_s = 200
[[segment]]
name = "y+ 200"
up_b = [0, 1, 0]
rate_deg_s = 200
[[segment]]
name = "z+ 200"
up_b = [0, 0, 1]
rate_deg_s = 200
"#;

    #[test]
    fn report_has_the_paper_tables_and_the_comparison() {
        let plan = Plan::parse(PLAN).unwrap();
        let truth = crate::unit_file::UnitFile::paper_unit()
            .to_calibration()
            .unwrap();
        let unit = shared::forward::ForwardModel::new(&truth).unwrap();
        let noise = SynthNoise {
            out_1sigma: [4e-4; 3],
            gyro_1sigma_rad_s: 0.0,
            sample_rate_hz: 1000.0,
        };
        let stats = synth::plan_stats(&plan, &unit, &noise, 60.0);
        let out = calibrate_session_stats(&plan, &stats, &EstimateOptions::default()).unwrap();
        let text = super::render(&out);
        eprintln!("{text}");
        for want in [
            "Table 1",
            "Zero bias (V)",
            "Table 3",
            "n.d.",
            "Lever arms by method",
            "paper eq. 24",
            "x+ 200",
            "χ²",
            "Warnings",
        ] {
            assert!(text.contains(want), "missing {want}");
        }
    }
}

#[cfg(test)]
mod pm_tests {
    #[test]
    fn sigma_keeps_two_significant_digits() {
        assert_eq!(super::pm(2.405098123, 1.3e-7, 6), "2.40509812 ± 0.00000013");
        assert_eq!(super::pm(0.39496, 2.0e-3, 6), "0.394960 ± 0.002000");
        assert_eq!(super::pm(1.0, f64::INFINITY, 3), "1.000 ± ∞");
    }
}
