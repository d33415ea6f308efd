//! The temperature model in the terminal report (docs/model.md §9): the fitted coefficients with 1σ
//! in g-based units (so a bias tempco reads in mg/°C whatever the output unit), the degrees the data
//! chose, and the residual of every static segment against its temperature.

use crate::estimate::thermal::ThermalFit;
use crate::estimate::CalibrationOutcome;
use std::fmt::Write as _;

/// `c ± s` of the three coefficients, each multiplied by its unit factor.
fn coefficients(c: &[f64; 3], s: &[f64; 3], factor: [f64; 3], degree: usize) -> String {
    (0..3)
        .map(|k| {
            if k < degree {
                format!("{:+.4} ± {:.4}", c[k] * factor[k], s[k] * factor[k])
            } else {
                "—".to_string()
            }
        })
        .collect::<Vec<_>>()
        .join(", ")
}

/// Appends the temperature section to `s` when the outcome has a temperature fit.
pub fn render(s: &mut String, o: &CalibrationOutcome) {
    let Some(fit) = &o.thermal else {
        return;
    };
    let m = &fit.model;
    let k = o.calibration.statics.scale_out_per_g;
    let _ = writeln!(s);
    let _ = writeln!(
        s,
        "Temperature model (docs/model.md §9), 1σ: reference {:.2} °C, valid {:.2}..{:.2} °C",
        m.reference_c, m.valid_range_c[0], m.valid_range_c[1]
    );
    let _ = writeln!(
        s,
        "     zero bias (mg/°C, µg/°C², µg/°C³)                        relative scale (ppm/°C, ppm/°C², ppm/°C³)"
    );
    for i in 0..3 {
        let g = [1e3 / k[i], 1e6 / k[i], 1e6 / k[i]];
        let _ = writeln!(
            s,
            "{:<4} {:<60} {}",
            shared::params::axis_name(i),
            coefficients(
                &m.zero_bias_out_per_c[i],
                &fit.zero_bias_sigma[i],
                g,
                fit.zero_bias_degree[i]
            ),
            coefficients(
                &m.scale_rel_per_c[i],
                &fit.scale_sigma[i],
                [1e6; 3],
                fit.scale_degree[i]
            ),
        );
    }
    for note in &fit.notes {
        let _ = writeln!(s, "  {note}");
    }
    render_steps(s, fit, &k);
}

/// One line per static segment: its temperature and residual per axis, µg.
fn render_steps(s: &mut String, fit: &ThermalFit, k: &[f64; 3]) {
    let _ = writeln!(
        s,
        "Residuals per static segment (µg, data − model, ± 1σ of the mean):"
    );
    for step in &fit.steps {
        let cells: Vec<String> = (0..3)
            .map(|i| {
                format!(
                    "{:+7.1} ± {:.1}",
                    step.residual_out[i] / k[i] * 1e6,
                    step.sigma_out[i] / k[i] * 1e6
                )
            })
            .collect();
        let _ = writeln!(
            s,
            "  {:<14} {:+7.2} °C  {}",
            step.segment,
            step.mean_c,
            cells.join("  ")
        );
    }
}
