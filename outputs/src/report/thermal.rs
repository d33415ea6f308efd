//! The temperature model in the terminal report (docs/model.md §9): the fitted coefficients with 1σ
//! in g-based units (so a bias tempco reads in mg/°C whatever the output unit), the degrees the data
//! chose, and the residual of every static segment against its temperature.

use super::plot::{Figure, Panel, Series, SeriesStyle};
use estimator::estimate::thermal::ThermalFit;
use estimator::estimate::CalibrationOutcome;
use recording::session::{Plan, SegmentStats};
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

/// The predicted 1σ of the temperature model's coefficients (`host plan --check`), in the units of
/// [`render`]; `values` are the prediction's paper-form values (scale factors at 3..6).
pub fn render_prediction(s: &mut String, fit: &ThermalFit, values: &[f64]) {
    let m = &fit.model;
    let _ = writeln!(
        s,
        "Temperature model (docs/model.md §9), predicted 1σ over {:.1}..{:.1} °C, reference {:.1} °C:",
        m.valid_range_c[0], m.valid_range_c[1], m.reference_c
    );
    let _ = writeln!(
        s,
        "     zero bias 1σ (mg/°C, µg/°C², µg/°C³)          relative scale 1σ (ppm/°C, ppm/°C², ppm/°C³)"
    );
    for i in 0..3 {
        let k = values[3 + i].abs();
        let g = [1e3 / k, 1e6 / k, 1e6 / k];
        let cells = |sig: &[f64; 3], factor: [f64; 3], degree: usize| {
            (0..3)
                .map(|c| {
                    if c < degree {
                        format!("{:.2e}", sig[c] * factor[c])
                    } else {
                        "—".into()
                    }
                })
                .collect::<Vec<_>>()
                .join(", ")
        };
        let _ = writeln!(
            s,
            "{:<4} {:<45} {}   (degrees {}, {})",
            shared::params::axis_name(i),
            cells(&fit.zero_bias_sigma[i], g, fit.zero_bias_degree[i]),
            cells(&fit.scale_sigma[i], [1e6; 3], fit.scale_degree[i]),
            fit.zero_bias_degree[i],
            fit.scale_degree[i]
        );
    }
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

/// Each soak's measured zero bias and scale per axis, from the pair of static segments with that
/// axis up and down at one temperature: `bias = (u₊ + u₋)/2`, `1 + S = (u₊ − u₋)/(2 M_ii)` (the
/// specific force cancels in the sum; docs/model.md §9), as changes from the reference: mg and ppm.
pub struct SoakPoints {
    /// Per axis, (°C, zero-bias change mg, its 1σ).
    pub bias_mg: [Vec<(f64, f64, f64)>; 3],
    /// Per axis, (°C, relative scale change ppm, its 1σ).
    pub scale_ppm: [Vec<(f64, f64, f64)>; 3],
}

/// [`SoakPoints`] of a session (empty where it has no axis-up/axis-down pair at one temperature).
pub(crate) fn soak_points(
    o: &CalibrationOutcome,
    plan: &Plan,
    stats: &[SegmentStats],
) -> SoakPoints {
    let mut p = SoakPoints {
        bias_mg: Default::default(),
        scale_ppm: Default::default(),
    };
    let (Some(fit), Ok((fitted, _))) = (&o.thermal, o.calibration.statics.to_fitted()) else {
        return p;
    };
    let k = o.calibration.statics.scale_out_per_g;
    let along = |st: &SegmentStats, i: usize, sign: f64| {
        plan.segment(&st.name)
            .is_some_and(|sp| sp.is_static() && !sp.is_free() && sp.up_b[i] * sign > 0.999)
            && st.thermal.is_some()
    };
    let temp = |st: &SegmentStats| st.thermal.as_ref().map_or(f64::NAN, |t| t.mean_c());
    for i in 0..3 {
        for up in stats.iter().filter(|st| along(st, i, 1.0)) {
            let Some(down) = stats
                .iter()
                .filter(|st| along(st, i, -1.0) && (temp(st) - temp(up)).abs() < 2.0)
                .min_by(|a, b| {
                    (temp(a) - temp(up))
                        .abs()
                        .total_cmp(&(temp(b) - temp(up)).abs())
                })
            else {
                continue;
            };
            let t = 0.5 * (temp(up) + temp(down));
            let var = |st: &SegmentStats| st.cov_u[i][i].max(0.0) / st.count.max(1) as f64;
            let sigma = 0.5 * (var(up) + var(down)).sqrt();
            let bias = 0.5 * (up.mean_u[i] + down.mean_u[i]) - fit.zero_bias_ref_out[i];
            let m_ii = fitted.m_out_per_g[i][i];
            let scale = 0.5 * (up.mean_u[i] - down.mean_u[i]) / m_ii - 1.0;
            p.bias_mg[i].push((t, bias / k[i] * 1e3, sigma / k[i] * 1e3));
            p.scale_ppm[i].push((t, scale * 1e6, sigma / m_ii.abs() * 1e6));
        }
    }
    p
}

/// The figure `temperature`: each temperature parameter against temperature, one panel per
/// parameter and axis: the fitted curve, its 1σ band (dashed), each soak's measured value
/// ([`SoakPoints`], markers with ±1σ) when given, and every static segment's residual (µg).
pub fn figure(o: &CalibrationOutcome, soaks: Option<&SoakPoints>) -> Option<Figure> {
    let fit = o.thermal.as_ref()?;
    let k = o.calibration.statics.scale_out_per_g;
    let [lo, hi] = fit.model.valid_range_c;
    let temps: Vec<f64> = (0..CURVE_POINTS)
        .map(|j| lo + (hi - lo) * j as f64 / (CURVE_POINTS - 1) as f64)
        .collect();
    let curve = |i: usize, bias: bool| parameter_series(fit, &k, &temps, i, bias, soaks);
    let residual = |i: usize| Series {
        label: "data − model ± 1σ".into(),
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
    };
    let panel = |title: String, y_desc: &str, series| Panel {
        title,
        x_desc: "temperature (°C)".into(),
        y_desc: y_desc.into(),
        x_categories: None,
        log_x: false,
        log_y: false,
        series,
    };
    let mut panels = Vec::new();
    for i in 0..3 {
        let a = shared::params::axis_name(i);
        panels.push(panel(
            format!("{a}: zero-bias change"),
            "mg",
            curve(i, true),
        ));
    }
    for i in 0..3 {
        let a = shared::params::axis_name(i);
        panels.push(panel(
            format!("{a}: relative scale change"),
            "ppm",
            curve(i, false),
        ));
    }
    for i in 0..3 {
        let a = shared::params::axis_name(i);
        panels.push(panel(
            format!("{a}: residual per static segment"),
            "µg",
            vec![residual(i)],
        ));
    }
    Some(Figure {
        stem: "temperature".into(),
        title: format!(
            "Temperature model (reference {:.1} °C): each parameter against temperature, its fit and 1σ band",
            fit.model.reference_c
        ),
        grid: (3, 3),
        size: (1800, 1100),
        panels,
    })
}

/// One temperature parameter of axis `i` (the zero bias, or the scale): its fitted curve over
/// `temps`, the curve ± 1σ (dashed), and each soak's measured value when given.
fn parameter_series(
    fit: &ThermalFit,
    k: &[f64; 3],
    temps: &[f64],
    i: usize,
    bias: bool,
    soaks: Option<&SoakPoints>,
) -> Vec<Series> {
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
    let band = |sign: f64| Series {
        label: "fit ± 1σ".into(),
        points: pts.iter().map(|p| (p.0, p.1 + sign * p.2)).collect(),
        error: None,
        style: SeriesStyle::Dashed,
        colour: i,
    };
    let mut v = vec![
        line("fit".into(), pts.iter().map(|p| (p.0, p.1)), i),
        band(1.0),
        band(-1.0),
    ];
    if let Some(sk) = soaks {
        let data = if bias {
            &sk.bias_mg[i]
        } else {
            &sk.scale_ppm[i]
        };
        if !data.is_empty() {
            v.push(Series {
                label: "each soak (axis up/down pair)".into(),
                points: data.iter().map(|d| (d.0, d.1)).collect(),
                error: Some(data.iter().map(|d| d.2).collect()),
                style: SeriesStyle::Markers,
                colour: 3,
            });
        }
    }
    v
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
