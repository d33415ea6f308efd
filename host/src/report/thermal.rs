//! The temperature model in the terminal report (docs/model.md §9): the fitted coefficients with 1σ
//! in g-based units (so a bias tempco reads in mg/°C whatever the output unit), the degrees the data
//! chose, and the residual of every static segment against its temperature.

use super::plot::{Figure, Panel, Series, SeriesStyle};
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

/// Points drawn per fitted curve.
const CURVE_POINTS: usize = 81;

/// The figure `temperature`: zero-bias and scale change against temperature (fitted curve and its
/// 1σ band per axis, in mg and ppm), and every static segment's residual (µg) at its temperature.
pub fn figure(o: &CalibrationOutcome) -> Option<Figure> {
    let fit = o.thermal.as_ref()?;
    let k = o.calibration.statics.scale_out_per_g;
    let [lo, hi] = fit.model.valid_range_c;
    let temps: Vec<f64> = (0..CURVE_POINTS)
        .map(|j| lo + (hi - lo) * j as f64 / (CURVE_POINTS - 1) as f64)
        .collect();
    let curves = |bias: bool| -> Vec<Series> {
        let mut v = Vec::new();
        for i in 0..3 {
            let (c, cov, unit) = if bias {
                (
                    &fit.model.zero_bias_out_per_c[i],
                    &fit.zero_bias_cov[i],
                    1e3 / k[i],
                )
            } else {
                (&fit.model.scale_rel_per_c[i], &fit.scale_cov[i], 1e6)
            };
            let pts: Vec<(f64, f64, f64)> = temps
                .iter()
                .map(|&t| {
                    let (y, s) = fit.curve(c, cov, t);
                    (t, y * unit, s * unit)
                })
                .collect();
            let name = shared::params::axis_name(i);
            v.push(line(name.to_string(), pts.iter().map(|p| (p.0, p.1)), i));
            v.push(line(
                format!("{name} +1σ"),
                pts.iter().map(|p| (p.0, p.1 + p.2)),
                i,
            ));
            v.push(line(
                format!("{name} −1σ"),
                pts.iter().map(|p| (p.0, p.1 - p.2)),
                i,
            ));
        }
        v
    };
    let residuals = (0..3)
        .map(|i| Series {
            label: shared::params::axis_name(i).to_string(),
            points: fit
                .steps
                .iter()
                .map(|s| (s.mean_c, s.residual_out[i] / k[i] * 1e6))
                .collect(),
            error: Some(
                fit.steps
                    .iter()
                    .map(|s| s.sigma_out[i] / k[i] * 1e6)
                    .collect(),
            ),
            style: SeriesStyle::Markers,
            colour: i,
        })
        .collect();
    let panel = |title: &str, y_desc: &str, series| Panel {
        title: title.into(),
        x_desc: "temperature (°C)".into(),
        y_desc: y_desc.into(),
        x_categories: None,
        log_y: false,
        series,
    };
    Some(Figure {
        stem: "temperature".into(),
        title: format!(
            "Temperature model (reference {:.1} °C): fitted change with its 1σ band, and residuals",
            fit.model.reference_c
        ),
        grid: (3, 1),
        size: (900, 1100),
        panels: vec![
            panel("Zero-bias change", "mg", curves(true)),
            panel("Relative scale change", "ppm", curves(false)),
            panel("Residual per static segment", "µg", residuals),
        ],
    })
}

fn line(label: String, points: impl Iterator<Item = (f64, f64)>, colour: usize) -> Series {
    Series {
        label,
        points: points.collect(),
        error: None,
        style: SeriesStyle::Line,
        colour,
    }
}
