//! Tests of the report: its numbers against the paper's and the simulator's truth, its figures against
//! its tables, its pages and files.

use super::data::*;
use super::document::*;
use super::figures::*;
use super::page::*;
use super::plot::{Formats, SeriesStyle};
use crate::report::plot::{line_width, palette_hex, png_dimensions, svg_polylines};
use estimator::estimate::{calibrate_session_stats, EstimateOptions, SegmentKind};
use estimator::sim::{simulate_stats, NoiseModel};
use recording::session::builtin::builtin_plan;
use recording::session::Plan;

fn short() -> Plan {
    builtin_plan("short").unwrap().unwrap()
}

/// The short plan on the paper unit, calibrated from its own noisy data.
fn noisy_report() -> ReportData {
    let plan = short();
    let truth = shared::params::PAPER_UNIT;
    let stats = simulate_stats(&truth, &plan, &NoiseModel::default(), 7).unwrap();
    let outcome = calibrate_session_stats(&plan, &stats, &EstimateOptions::default()).unwrap();
    build_report(
        &plan,
        &stats,
        &outcome.calibration,
        Some(&outcome.uncertainty),
        Ok(outcome.clone()),
        &ReportOptions::default(),
    )
    .unwrap()
}

/// The report of `cal` on a session, the session's own fit run as `app::report` runs it.
fn report_of(
    plan: &Plan,
    stats: &[recording::session::SegmentStats],
    cal: &shared::Calibration,
    uncertainty: Option<&estimator::estimate::Uncertainty>,
    options: &ReportOptions,
) -> Result<ReportData, ReportError> {
    let fit = calibrate_session_stats(plan, stats, &session_fit_options(cal, options));
    build_report(plan, stats, cal, uncertainty, fit, options)
}

/// Cells of a table block, parsed as numbers where they are.
fn cells(b: &Block) -> &Vec<Vec<String>> {
    match b {
        Block::Table { rows, .. } => rows,
        _ => panic!("not a table"),
    }
}

#[test]
fn noise_free_true_calibration_gives_the_papers_numbers() {
    // docs/model.md §6: x up, bias+scale only → (0.99991, 0.01300, −0.00911) g; static-only at 200 °/s
    // about x leaves (0.09, 11.2, 10.1) mg.
    let plan = short();
    let truth = shared::params::PAPER_UNIT;
    let stats = simulate_stats(&truth, &plan, &NoiseModel::none(), 1).unwrap();
    let rows = segment_rows(&plan, &stats, &truth).unwrap();
    assert_eq!(rows.len(), 15);
    let x = &rows[0];
    assert_eq!(x.name, "x+");
    for (v, want) in x.before_g.iter().zip([0.99991, 0.01300, -0.00911]) {
        assert!((v - want).abs() < 1e-5, "{:?}", x.before_g);
    }
    let x200 = rows.iter().find(|r| r.name == "x+ 200").unwrap();
    assert_eq!(x200.kind, SegmentKind::ConstantRate);
    let e = x200.error_g(Compensation::Static).map(|v| v.abs() * 1e3);
    for (v, want) in e.iter().zip([0.09, 11.2, 10.1]) {
        assert!((v - want).abs() < 0.06, "{e:?}");
    }
    // The device's f32 compensation with the true parameters leaves only rounding.
    for r in &rows {
        let e = r.error_g(Compensation::Full);
        assert!(e.iter().all(|v| v.abs() < 2e-6), "{}: {e:?}", r.name);
    }
}

#[test]
fn replay_is_half_a_t_squared_of_the_table_error() {
    let data = noisy_report();
    assert_eq!(data.navigation.len(), 2);
    assert_eq!(data.navigation[0].segment, "x+");
    assert_eq!(data.navigation[1].segment, "x+ 200");
    let g = data.calibration.gravity_m_s2;
    for run in &data.navigation {
        let row = data
            .segments
            .iter()
            .find(|r| r.name == run.segment)
            .unwrap();
        for c in &run.cases {
            let e = row.error_g(c.compensation);
            assert_eq!(c.error_g, e);
            let p = c.drift.position_m.last().unwrap();
            let v = c.drift.velocity_m_s.last().unwrap();
            for j in 0..3 {
                assert!((p[j] - 0.5 * e[j] * g * 3600.0).abs() < 1e-9 * (1.0 + p[j].abs()));
                assert!((v[j] - e[j] * g * 60.0).abs() < 1e-9 * (1.0 + v[j].abs()));
            }
        }
    }
    // The story: static-only is fine at rest, and leaves tens of metres at 200 °/s.
    let rate = &data.navigation[1];
    assert!(
        rate.case(Compensation::Static)
            .drift
            .final_position_error_m()
            > 100.0
    );
}

#[test]
fn figures_plot_the_numbers_in_the_tables_and_render() {
    let data = noisy_report();
    let n = data.segments.len();
    // (a) The outputs figure: panel j, series c, point k = segment k's error in mg, and the
    // table's printed outputs give the same error to their printed precision.
    let fig = outputs_figure(&data);
    let statics = before_after_table(&data, false);
    let rotating = before_after_table(&data, true);
    let table_rows: Vec<&Vec<String>> = cells(&statics).iter().chain(cells(&rotating)).collect();
    assert_eq!(table_rows.len(), 3 * n);
    let mut seg_of_row = Vec::new();
    for r in &data.segments {
        let s = data.segments.iter().position(|x| x.name == r.name).unwrap();
        seg_of_row.push(s);
    }
    for (j, panel) in fig.panels.iter().enumerate() {
        assert_eq!(panel.series.len(), 3);
        for (m, (c, series)) in Compensation::ALL.iter().zip(&panel.series).enumerate() {
            assert_eq!(series.points.len(), n);
            assert_eq!(
                series.style,
                SeriesStyle::Markers,
                "segments are categories"
            );
            for (k, r) in data.segments.iter().enumerate() {
                let x = k as f64 + 0.15 * (m as f64 - 1.0);
                assert_eq!(series.points[k], (x, r.error_g(*c)[j] * 1e3));
            }
        }
    }
    // Every table row (segment, axis) against the plotted value.
    let mut current = String::new();
    for row in &table_rows {
        if !row[0].is_empty() {
            current = row[0].clone();
        }
        let k = data
            .segments
            .iter()
            .position(|r| r.name == current)
            .unwrap();
        let j = ["x", "y", "z"].iter().position(|a| *a == row[1]).unwrap();
        let num = |s: &str| s.parse::<f64>().unwrap();
        let truth = num(&row[2]);
        for (col, c) in [(3, 0usize), (4, 1), (5, 2)] {
            let plotted = fig.panels[j].series[c].points[k].1 * 1e-3;
            assert!(
                (num(&row[col]) - truth - plotted).abs() < 1.1e-6,
                "{current} {j} col {col}"
            );
        }
        // (b) The residual figure's point and band are the table's residual and 1σ (µg).
        let res = &residuals_figure(&data).panels[j].series[0];
        let (residual, sigma) = row[6].split_once(" ± ").unwrap();
        assert!((num(residual) - res.points[k].1).abs() < 0.051);
        assert!((num(sigma) - res.error.as_ref().unwrap()[k]).abs() < 0.051);
    }
    // (c) The navigation figures end at the navigation table's final errors.
    let nav = navigation_table(&data.navigation);
    let figs = report_figures(&data);
    let stems: Vec<&str> = figs.iter().map(|f| f.stem.as_str()).collect();
    assert_eq!(
        stems,
        [
            "outputs",
            "residuals",
            "navigation_static",
            "navigation_xp_200"
        ]
    );
    for (r, run) in data.navigation.iter().enumerate() {
        let f = &figs[2 + r];
        for (c, case) in run.cases.iter().enumerate() {
            let row = &cells(&nav)[3 * r + c];
            let vel_end = f.panels[0].series[c].points.last().unwrap().1;
            let pos_end = f.panels[1].series[c].points.last().unwrap().1;
            assert_eq!(pos_end, case.drift.final_position_error_m());
            assert!((row[4].parse::<f64>().unwrap() - vel_end).abs() <= 5e-5);
            assert!((row[5].parse::<f64>().unwrap() - pos_end).abs() <= 5e-4);
        }
    }

    // Rendered: valid PNGs of the figure's size, SVGs with one polyline per line series holding
    // every drawable point, and the page referring to every figure.
    let dir = tempfile::tempdir().unwrap();
    let summary = write_report(&data, dir.path(), "s", "c", Formats::default()).unwrap();
    assert!(summary.warnings.is_empty(), "{:?}", summary.warnings);
    assert_eq!(summary.files.len(), 2 * figs.len() + 2);
    for f in &figs {
        let png = std::fs::read(dir.path().join(format!("{}.png", f.stem))).unwrap();
        assert_eq!(png_dimensions(&png), Some(f.size), "{}", f.stem);
        let svg = std::fs::read_to_string(dir.path().join(format!("{}.svg", f.stem))).unwrap();
        assert!(svg.starts_with("<svg") && svg.trim_end().ends_with("</svg>"));
        let lines = svg_polylines(&svg);
        for p in &f.panels {
            let line_series: Vec<_> = p
                .series
                .iter()
                .filter(|s| s.style != SeriesStyle::Markers)
                .collect();
            for (i, s) in line_series.iter().enumerate() {
                let width = line_width(i, line_series.len()).to_string();
                let drawable = s
                    .points
                    .iter()
                    .filter(|(_, y)| !p.log_y || *y > 0.0)
                    .count();
                assert!(
                    lines.iter().any(|l| l.stroke == palette_hex(s.colour)
                        && l.width == width
                        && l.points == drawable),
                    "{}: '{}' with {drawable} points not drawn",
                    f.stem,
                    s.label
                );
            }
        }
        if f.stem == "residuals" {
            // One marker per segment and axis, and each panel's legend sample.
            assert_eq!(svg.matches("<circle").count(), 3 * n + 3);
        }
    }
    let md = std::fs::read_to_string(dir.path().join(REPORT_MD)).unwrap();
    let html = std::fs::read_to_string(&summary.page).unwrap();
    for f in &figs {
        assert!(md.contains(&format!("]({}.png)", f.stem)));
        assert!(html.contains(&format!("src=\"{}.png\"", f.stem)));
    }
    assert!(md.contains("Table 1. Static calibration") && md.contains("χ²"));
    assert!(html.starts_with("<!DOCTYPE html>") && html.contains("<table>"));
}

#[test]
fn a_ramp_is_compensated_at_its_rms_rate() {
    // 0 → 200 °/s in 2 s about x: the mean of ω² is not ω̄² (the difference is ~0.8 mg of
    // centripetal term on 8 mm lever arms), so the rate used must be the RMS one.
    let plan = Plan::parse(
        "output_unit = \"V\"\nsample_rate_hz = 1000\n\
             [[segment]]\nname = \"x+\"\nup_b = [1, 0, 0]\nduration_s = 1\n\
             [[segment]]\nname = \"ramp\"\nup_b = [1, 0, 0]\nrate_deg_s = 0\n\
             rate_end_deg_s = 200\nduration_s = 2\n",
    )
    .unwrap();
    let truth = shared::params::PAPER_UNIT;
    let stats = simulate_stats(&truth, &plan, &NoiseModel::none(), 1).unwrap();
    let rows = segment_rows(&plan, &stats, &truth).unwrap();
    let ramp = &rows[1];
    assert_eq!(ramp.kind, SegmentKind::Ramp);
    assert!(ramp.omega_rad_s[0] > 1.05 * stats[1].mean_w_rad_s[0]);
    let e = ramp.error_g(Compensation::Full);
    assert!(e.iter().all(|v| v.abs() < 3e-6), "{e:?}");
    assert!(ramp.error_g(Compensation::Static)[1].abs() > 1e-3);
}

#[test]
fn a_named_run_must_exist() {
    let plan = short();
    let truth = shared::params::PAPER_UNIT;
    let stats = simulate_stats(&truth, &plan, &NoiseModel::none(), 1).unwrap();
    let options = ReportOptions {
        rate_run: Some("x+ 999".into()),
        ..ReportOptions::default()
    };
    let e = report_of(&plan, &stats, &truth, None, &options).unwrap_err();
    assert!(e.to_string().contains("'x+ 999'"));
    let options = ReportOptions {
        rate_run: Some("y+ 100".into()),
        ..ReportOptions::default()
    };
    let d = report_of(&plan, &stats, &truth, None, &options).unwrap();
    assert_eq!(d.navigation[1].segment, "y+ 100");
    // Without [uncertainty], Table 1 says so.
    assert!(cells(&table1(&d))[0][1].contains("no σ"));
}

/// The table's outputs correct the gyro's rate before the lever-arm terms, as the device does
/// (docs/model.md §8): a noise-free session whose gyro reads 0.5 % high, 0.5° misaligned and 0.5 °/s
/// off, compensated with the true unit and that gyro, gives every segment's true specific force; the
/// same unit with its gyro taken as perfect misses on the spinning segments.
#[test]
fn segment_rows_correct_the_rate_with_the_calibrations_gyro() {
    use estimator::sim::session::gyro_matrix;
    use estimator::sim::testkit::{self, TableErrors};
    let plan = builtin_plan("short-oblique").unwrap().unwrap();
    let unit = testkit::paper_unit();
    let gyro = shared::GyroCorrection {
        matrix: gyro_matrix([5e-3, -5e-3, 5e-3], 0.5f64.to_radians()),
        bias_rad_s: [
            0.5f64.to_radians(),
            -0.5f64.to_radians(),
            0.5f64.to_radians(),
        ],
    };
    let errors = TableErrors {
        gyro: Some((gyro.matrix, gyro.bias_rad_s)),
        ..TableErrors::default()
    };
    let stats = testkit::noisy_stats(&plan, &unit, 0.0, errors, &mut shared::rng::Rng::new(1, 0));
    let worst = |cal: &shared::Calibration| {
        let rows = segment_rows(&plan, &stats, cal).unwrap();
        assert_eq!(rows.len(), plan.segments.len());
        rows.iter()
            .flat_map(|r| r.error_g(Compensation::Full))
            .fold(0.0f64, |m, e| m.max(e.abs()))
    };
    let with_gyro = shared::Calibration {
        gyro: Some(gyro),
        ..unit
    };
    let corrected = worst(&with_gyro);
    let ignored = worst(&unit);
    eprintln!("worst |after − truth|: gyro corrected {corrected:.2e} g, ignored {ignored:.2e} g");
    // f32 arithmetic on outputs of ~2.4 V: a few 10⁻⁷ g.
    assert!(corrected < 2e-6, "{corrected:e}");
    assert!(ignored > 20.0 * corrected.max(1e-6), "{ignored:e}");
}

/// The terminal text puts the fit's specific force beside this table's outputs: both must be at the
/// calibration's reference point. Lever arms referred to the centroid move the output away from the
/// fit's own origin by millig at 200 °/s; on a noise-free session the two still agree to f32 rounding.
#[test]
fn the_fits_specific_force_is_at_the_calibrations_reference_point() {
    use estimator::estimate::ReferenceChoice;
    let plan = builtin_plan("short-oblique").unwrap().unwrap();
    let truth = shared::params::PAPER_UNIT;
    let stats = simulate_stats(&truth, &plan, &NoiseModel::none(), 3).unwrap();
    for reference in [
        ReferenceChoice::TableAxis,
        ReferenceChoice::Centroid,
        ReferenceChoice::BodyPoint([0.01, -0.02, 0.005]),
    ] {
        let options = EstimateOptions {
            reference,
            ..EstimateOptions::default()
        };
        let out = calibrate_session_stats(&plan, &stats, &options).unwrap();
        let rows = segment_rows(&plan, &stats, &out.calibration).unwrap();
        let mut worst = 0.0f64;
        for d in out.segments.iter().filter(|d| d.used) {
            let row = rows.iter().find(|r| r.name == d.name).unwrap();
            for j in 0..3 {
                worst = worst.max((d.theoretical_g[j] - row.after_g[j]).abs());
            }
        }
        assert!(worst < 2e-6, "{reference:?}: {worst:e} g");
    }
}

/// The report and the terminal give one "theoretical": the session fit's specific force with each
/// segment's fitted attitude. On a noisy table session the report, running its own fit, shows the
/// terminal's value for every segment, and its residuals are the segments' own noise (χ² per value
/// near 1, an independent check: the simulator's noise).
#[test]
fn the_report_compares_against_the_same_fitted_attitudes_as_the_terminal() {
    let plan = short();
    let truth = shared::params::PAPER_UNIT;
    let stats = simulate_stats(&truth, &plan, &NoiseModel::default(), 11).unwrap();
    let outcome = calibrate_session_stats(&plan, &stats, &EstimateOptions::default()).unwrap();
    let data = report_of(
        &plan,
        &stats,
        &outcome.calibration,
        Some(&outcome.uncertainty),
        &ReportOptions::default(),
    )
    .unwrap();
    for d in outcome.segments.iter().filter(|d| d.used) {
        let row = data.segments.iter().find(|r| r.name == d.name).unwrap();
        assert_eq!(row.theoretical, crate::report::data::Theoretical::Fitted);
        for j in 0..3 {
            assert!(
                (row.truth_g[j] - d.theoretical_g[j]).abs() < 1e-12,
                "{} {j}: report {} terminal {}",
                d.name,
                row.truth_g[j],
                d.theoretical_g[j]
            );
        }
    }
    let per_value = data.chi2 / data.chi2_terms as f64;
    assert!(per_value < 2.0, "χ²/value {per_value}");
}

/// A session of spins only has no static row: the page says so in place of an empty Table 2,
/// and still shows Table 4.
#[test]
fn an_empty_static_table_says_why() {
    let mut plan = short();
    plan.segments.retain(|s| !s.is_static());
    assert!(!plan.segments.is_empty());
    let truth = shared::params::PAPER_UNIT;
    let stats = simulate_stats(&truth, &plan, &NoiseModel::none(), 1).unwrap();
    let data = report_of(&plan, &stats, &truth, None, &ReportOptions::default()).unwrap();
    let blocks = page(&data, "spins", "cal.toml", &[]);
    let at = blocks
        .iter()
        .position(|b| matches!(b, Block::Heading(3, h) if h.starts_with("Static segments")))
        .unwrap();
    assert!(
        matches!(&blocks[at + 1], Block::Para(p) if p == NO_STATIC_ROW),
        "{:?}",
        blocks[at + 1]
    );
    assert!(blocks
        .iter()
        .any(|b| matches!(b, Block::Heading(3, h) if h.starts_with("Rotating segments"))));
}

/// The session fit under a walk (docs/model.md §11.4): the report's `bias_walk` figure is the fit's
/// own bias track, point for point with its 1σ as the bars, and the page names the walk's strength
/// and source; the same session without a walk has no such figure, note or file, and its other
/// figures are the same.
#[test]
fn the_bias_walk_figure_is_the_fits_track() {
    let plan = short();
    let truth = shared::params::PAPER_UNIT;
    let noise = NoiseModel {
        accel_bias_walk_mg_sqrt_s: 0.005,
        ..NoiseModel::default()
    };
    let stats = simulate_stats(&truth, &plan, &noise, 5).unwrap();
    let build = |walk: estimator::estimate::BiasWalk| {
        let options = ReportOptions {
            estimate: EstimateOptions::default().with_bias_walk(walk),
            ..ReportOptions::default()
        };
        report_of(&plan, &stats, &truth, None, &options).unwrap()
    };
    let with = build(estimator::estimate::BiasWalk::Given(0.005));
    let o = with.session_fit.as_ref().unwrap();
    assert!(!o.bias_track.is_empty());
    let fig = with
        .bias_walk_figure
        .as_ref()
        .expect("a walk gives the figure");
    assert_eq!(fig.panels.len(), 3);
    for (j, panel) in fig.panels.iter().enumerate() {
        let s = &panel.series[0];
        assert_eq!(s.style, SeriesStyle::Markers);
        assert_eq!(s.points.len(), o.bias_track.len());
        for (k, p) in o.bias_track.iter().enumerate() {
            assert_eq!(s.points[k], (p.t_mid_s, p.bias_mg[j]));
            assert_eq!(s.error.as_ref().unwrap()[k], p.sigma_mg[j]);
        }
    }
    // The segments are in time order over the session (the short plan runs 15 segments).
    let t: Vec<f64> = o.bias_track.iter().map(|p| p.t_mid_s).collect();
    assert!(t.windows(2).all(|w| w[0] < w[1]), "{t:?}");
    let stems: Vec<String> = report_figures(&with)
        .iter()
        .map(|f| f.stem.clone())
        .collect();
    assert!(stems.contains(&"bias_walk".to_string()), "{stems:?}");
    let md = super::markup::to_markdown(&page(&with, "s", "c", &stems));
    assert!(
        md.contains("Bias random walk (docs/model.md §11): given, 0.00500 mg/√s")
            && md.contains("bias_walk.png"),
        "{md}"
    );
    let without = build(estimator::estimate::BiasWalk::Off);
    assert!(without.bias_walk_figure.is_none());
    let plain: Vec<String> = report_figures(&without)
        .iter()
        .map(|f| f.stem.clone())
        .collect();
    assert_eq!(
        plain,
        stems
            .iter()
            .filter(|s| *s != "bias_walk")
            .cloned()
            .collect::<Vec<_>>()
    );
    let md = super::markup::to_markdown(&page(&without, "s", "c", &plain));
    assert!(
        !md.contains("Bias random walk") && !md.contains("bias_walk"),
        "{md}"
    );
}

/// A session with a temperature model: the page's own-fit section gives the temperature fit's
/// χ²/dof per axis, the figure the verdict checks; a session without one says nothing of it.
#[test]
fn the_session_fit_section_gives_the_temperature_fits_chi2() {
    let truth = estimator::sim::testkit::hot_unit();
    let para = |plan_name: &str| -> (Option<String>, Option<[f64; 3]>) {
        let plan = builtin_plan(plan_name).unwrap().unwrap();
        let thermal = estimator::sim::thermal::ThermalSim::default();
        let stats = estimator::sim::testkit::simulate_stats(
            &truth,
            &plan,
            &NoiseModel::default(),
            &thermal,
            5,
        );
        let data = report_of(&plan, &stats, &truth, None, &ReportOptions::default()).unwrap();
        let fit = data.session_fit.as_ref().unwrap();
        let chi2 = fit.thermal.as_ref().map(|t| t.reduced_chi2());
        let text = page(&data, plan_name, "cal.toml", &[])
            .into_iter()
            .find_map(|b| match b {
                Block::Para(p) if p.starts_with("Temperature fit") => Some(p),
                _ => None,
            });
        (text, chi2)
    };
    let (text, chi2) = para("thermal-ramp");
    let [x, y, z] = chi2.expect("the ramp fits a temperature model");
    let text = text.expect("the paragraph");
    assert!(
        text.contains(&format!("x {x:.2}, y {y:.2}, z {z:.2}")),
        "{text}"
    );
    // White noise about a model that fits: χ²/dof is 1 to within a few √(2/dof).
    assert!([x, y, z].iter().all(|c| (c - 1.0).abs() < 0.05), "{text}");
    let (text, chi2) = para("short");
    assert_eq!((text, chi2), (None, None));
}

/// A figure that cannot be written is a typed error naming its file, with plotters' or the file
/// system's error as its source, not a message.
#[test]
fn a_figure_that_cannot_be_written_keeps_its_cause() {
    let data = noisy_report();
    let fig = outputs_figure(&data);
    let tmp = tempfile::tempdir().unwrap();
    let missing = tmp.path().join("no-such-dir");
    let svg_only = Formats {
        png: false,
        svg: true,
    };
    let e = super::plot::render(&fig, &missing, svg_only).unwrap_err();
    let text = e.to_string();
    assert!(text.starts_with("cannot draw "), "{text}");
    assert!(text.contains("no-such-dir"), "{text}");
    let source = std::error::Error::source(&e).map(ToString::to_string);
    assert!(source.is_some(), "{e:?}");
    match e {
        super::plot::FigureError::Draw { path, .. }
        | super::plot::FigureError::Write { path, .. } => {
            assert!(path.starts_with(&missing), "{}", path.display());
        }
    }
}

/// Figure titles and headings say what they show in the user's terms: nothing that needs the paper
/// at hand ("paper Figs. 5, 8").
#[test]
fn figure_titles_and_headings_need_no_paper() {
    let data = noisy_report();
    let mut titles: Vec<String> = report_figures(&data)
        .iter()
        .flat_map(|f| {
            std::iter::once(f.title.clone()).chain(f.panels.iter().map(|p| p.title.clone()))
        })
        .collect();
    titles.extend(
        page(&data, "s", "c", &[])
            .into_iter()
            .filter_map(|b| match b {
                Block::Heading(_, h) => Some(h),
                _ => None,
            }),
    );
    assert!(titles.len() > 3, "{titles:?}");
    for t in &titles {
        assert!(
            !t.contains("paper") && !t.contains("Fig"),
            "'{t}' needs the paper"
        );
    }
}

/// The report has the gyro: G and b as the calibration holds them, the scale error as the row's
/// length less one, and each spin's corrected rate against the table's.
#[test]
fn the_report_has_a_gyro_section() {
    let data = noisy_report();
    let g = data
        .calibration
        .gyro
        .expect("the short plan's spins fit the gyro");
    let blocks = page(&data, "s", "c", &[]);
    let at = blocks
        .iter()
        .position(|b| *b == Block::Heading(2, "Gyro".into()))
        .expect("a gyro section");
    let table = blocks[at + 1..]
        .iter()
        .find(|b| matches!(b, Block::Table { .. }))
        .unwrap();
    let rows = cells(table);
    for i in 0..3 {
        for j in 0..3 {
            let shown: f64 = rows[i][1 + 2 * j].parse().unwrap();
            assert!(
                (shown - g.matrix[i][j]).abs() <= 5e-7,
                "G[{i}][{j}] {shown}"
            );
        }
        let norm = g.matrix[i].iter().map(|v| v * v).sum::<f64>().sqrt();
        assert_eq!(rows[i][7], format!("{:+.0}", (norm - 1.0) * 1e6));
        let b: f64 = rows[i][9].parse().unwrap();
        assert!((b - g.bias_rad_s[i].to_degrees()).abs() <= 5e-6);
        assert_ne!(rows[i][2], "—", "the session's fit gives G's 1σ");
    }
    let spins = blocks[at + 1..]
        .iter()
        .filter(|b| matches!(b, Block::Table { .. }))
        .nth(1)
        .expect("the spins' residuals");
    let n_spins = data
        .segments
        .iter()
        .filter(|r| r.kind != SegmentKind::Static && r.planned_rate_deg_s != 0.0)
        .count();
    assert!(n_spins > 0);
    assert_eq!(cells(spins).len(), n_spins);
    for row in cells(spins) {
        for v in &row[2..5] {
            let r: f64 = v.parse().unwrap();
            assert!(
                r.abs() < 0.05,
                "{row:?}: the corrected gyro reads the table's rate"
            );
        }
    }
}
