//! What each figure of the report shows, as data ([`Figure`]: panels of named series), so that the
//! plotted values can be checked against the tables; [`super::plot`] draws them.

use super::data::{Compensation, ReportData};
use super::navigation::{Drift, NavigationRun};
use super::plot::{Figure, Panel, Series, SeriesStyle};
use estimator::estimate::CalibrationOutcome;
use shared::linalg;
use shared::params::axis_name;

/// Figure (a), paper Figs. 5 and 8: each segment's output minus the theoretical value (the session
/// fit's, as in the tables), mg, before and after
/// compensation; one panel per axis.
pub(crate) fn outputs_figure(data: &ReportData) -> Figure {
    let cats: Vec<String> = data.segments.iter().map(|r| r.name.clone()).collect();
    let panels = (0..3)
        .map(|j| Panel {
            title: format!("{} output − theoretical", axis_name(j)),
            x_desc: "segment".into(),
            y_desc: "mg".into(),
            x_categories: Some(cats.clone()),
            log_x: false,
            log_y: false,
            // Segments are categories: markers only (a line between them would suggest an order
            // in between), each compensation shifted a little so that none hides another.
            series: Compensation::ALL
                .iter()
                .enumerate()
                .map(|(n, &c)| Series {
                    label: c.label().into(),
                    points: data
                        .segments
                        .iter()
                        .enumerate()
                        .map(|(k, r)| (k as f64 + 0.15 * (n as f64 - 1.0), r.error_g(c)[j] * 1e3))
                        .collect(),
                    error: None,
                    style: SeriesStyle::Markers,
                    colour: c.colour(),
                })
                .collect(),
        })
        .collect();
    Figure {
        stem: "outputs".into(),
        title: "Each segment's error (measured less expected specific force): raw, after the \
                static calibration, after static + lever arms"
            .into(),
        grid: (3, 1),
        size: (1200, 1000),
        panels,
    }
}

/// Figure (b): the residual after full compensation, µg, with the segment's ±1σ (its own noise).
pub(crate) fn residuals_figure(data: &ReportData) -> Figure {
    let cats: Vec<String> = data.segments.iter().map(|r| r.name.clone()).collect();
    let panels = (0..3)
        .map(|j| Panel {
            title: format!(
                "{} residual after static+dynamic compensation",
                axis_name(j)
            ),
            x_desc: "segment".into(),
            y_desc: "µg".into(),
            x_categories: Some(cats.clone()),
            log_x: false,
            log_y: false,
            series: vec![Series {
                label: "residual ± 1σ of the segment mean".into(),
                points: data
                    .segments
                    .iter()
                    .enumerate()
                    .map(|(k, r)| (k as f64, r.error_g(Compensation::Full)[j] * 1e6))
                    .collect(),
                error: Some(data.segments.iter().map(|r| r.sigma_g[j] * 1e6).collect()),
                style: SeriesStyle::Markers,
                colour: Compensation::Full.colour(),
            }],
        })
        .collect();
    Figure {
        stem: "residuals".into(),
        title: "Residuals per segment with their 1σ band".into(),
        grid: (3, 1),
        size: (1200, 1000),
        panels,
    }
}

/// Figure (c), paper Figs. 6/7 and 9/10: velocity and position error of a replayed run (norms, log
/// scale), before and after compensation.
pub(crate) fn navigation_figure(run: &NavigationRun, stem: &str) -> Figure {
    let panel = |what: &str, unit: &str, pick: &dyn Fn(&Drift, usize) -> f64| Panel {
        title: format!("{what} error |{}|", &what[..1]),
        x_desc: "t (s)".into(),
        y_desc: unit.into(),
        x_categories: None,
        log_x: false,
        log_y: true,
        series: run
            .cases
            .iter()
            .map(|c| Series {
                label: c.compensation.label().into(),
                points: (0..c.drift.t_s.len())
                    .map(|k| (c.drift.t_s[k], pick(&c.drift, k)))
                    .collect(),
                error: None,
                style: SeriesStyle::Line,
                colour: c.compensation.colour(),
            })
            .collect(),
    };
    let norm = |v: &[f64; 3]| linalg::norm(v);
    Figure {
        stem: stem.into(),
        title: format!(
            "Navigation replay of '{}' ({}), {:.0} s",
            run.segment,
            if run.rate_deg_s.abs() < 0.5 {
                "static".to_string()
            } else {
                format!("{:.0} °/s", run.rate_deg_s)
            },
            run.duration_s
        ),
        grid: (1, 2),
        size: (1200, 500),
        panels: vec![
            panel("velocity", "m/s", &|d, k| norm(&d.velocity_m_s[k])),
            panel("position", "m", &|d, k| norm(&d.position_m[k])),
        ],
    }
}

/// The session fit's bias over the session (docs/model.md §11.4): each segment's fitted wander of
/// the bias from the session's start against the middle of its span, mg, with its 1σ, one panel per
/// axis; `None` when the fit assumed no walk.
pub(crate) fn bias_walk_figure(o: &CalibrationOutcome) -> Option<Figure> {
    let w = o.bias_walk.as_ref()?;
    if o.bias_track.is_empty() {
        return None;
    }
    let panels = (0..3)
        .map(|j| Panel {
            title: format!("{} bias wander from the start", axis_name(j)),
            x_desc: "t (s)".into(),
            y_desc: "mg".into(),
            x_categories: None,
            log_x: false,
            log_y: false,
            series: vec![Series {
                label: "bias ± 1σ".into(),
                points: o
                    .bias_track
                    .iter()
                    .map(|p| (p.t_mid_s, p.bias_mg[j]))
                    .collect(),
                error: Some(o.bias_track.iter().map(|p| p.sigma_mg[j]).collect()),
                style: SeriesStyle::Markers,
                colour: 0,
            }],
        })
        .collect();
    let how = match w.sigma_mg_sqrt_s {
        Some(sd) => format!("{:.5} ± {sd:.5} mg/√s, estimated", w.mg_sqrt_s),
        None => format!("{:.5} mg/√s, {}", w.mg_sqrt_s, w.origin.word()),
    };
    Some(Figure {
        stem: "bias_walk".into(),
        title: format!("Bias over the session under a random walk of {how}"),
        grid: (3, 1),
        size: (1200, 1000),
        panels,
    })
}

/// All figures of a report: outputs, residuals, then one per navigation run.
pub(crate) fn report_figures(data: &ReportData) -> Vec<Figure> {
    let mut v = vec![outputs_figure(data), residuals_figure(data)];
    v.extend(data.temperature_figure.clone());
    v.extend(data.bias_walk_figure.clone());
    for (k, run) in data.navigation.iter().enumerate() {
        let stem = if k == 0 && run.rate_deg_s.abs() < 0.5 {
            "navigation_static".to_string()
        } else {
            format!("navigation_{}", stem_name(&run.segment))
        };
        v.push(navigation_figure(run, &stem));
    }
    v
}

/// A rate for display, °/s, without a "-0".
pub(crate) fn fmt_rate(r: f64) -> String {
    if r.abs() < 0.5 {
        "0".into()
    } else {
        format!("{r:.0}")
    }
}

pub(crate) fn stem_name(s: &str) -> String {
    s.chars()
        .map(|c| match c {
            '+' => 'p',
            '-' | '−' => 'm',
            c if c.is_ascii_alphanumeric() => c,
            _ => '_',
        })
        .collect()
}
