//! The report page as one document model ([`Block`]s): Tables 1 and 3, the before/after tables
//! (the paper's Tables 2 and 4), the navigation table, the figures; `super::markup` writes it as
//! Markdown and HTML.

use super::data::Theoretical;
use super::data::{Compensation, ReportData};
use super::figures::fmt_rate;
use super::format::{g_or_dash, out_digits, pm, pm_opt, reference_point};
use super::navigation::NavigationRun;
use estimator::estimate::SegmentKind;
use shared::linalg;
use shared::params::axis_name;

/// A block of the report page.
#[derive(Clone, Debug, PartialEq)]
pub enum Block {
    /// Heading of a level (1..3).
    Heading(u8, String),
    /// A paragraph.
    Para(String),
    /// A table.
    Table {
        /// Column headers.
        header: Vec<String>,
        /// Rows of cells.
        rows: Vec<Vec<String>>,
    },
    /// An image (relative path).
    Image {
        /// Relative path.
        src: String,
        /// Alternative text.
        alt: String,
    },
    /// Preformatted text.
    Pre(String),
}

/// Table 1 (zero bias, scale factor, installation angles with 1σ) as table rows.
pub(crate) fn table1(data: &ReportData) -> Block {
    let st = &data.calibration.statics;
    let u = data.uncertainty.as_ref();
    let d = out_digits(data.calibration.statics.output_unit);
    let sym = &data.unit_symbol;
    Block::Table {
        header: vec![
            "No.".into(),
            format!("Zero bias ({sym})"),
            format!("Scale factor ({sym}/g)"),
            "θ_ix (°)".into(),
            "θ_iy (°)".into(),
            "θ_iz (°)".into(),
        ],
        rows: (0..3)
            .map(|i| {
                let mut row = vec![
                    format!("{}", i + 1),
                    pm_opt(st.zero_bias_out[i], u.map(|u| u.zero_bias_1sigma[i]), d),
                    pm_opt(st.scale_out_per_g[i], u.map(|u| u.scale_per_g_1sigma[i]), d),
                ];
                for j in 0..3 {
                    row.push(pm_opt(
                        st.installation_angles_deg[i][j],
                        u.map(|u| u.installation_angles_deg_1sigma[i][j]),
                        5,
                    ));
                }
                row
            })
            .collect(),
    }
}

/// Table 3 (lever arms, mm, with 1σ; "n.d." where the plan did not determine the component).
pub(crate) fn table3(data: &ReportData) -> Block {
    let r = &data.calibration.lever_arms.r_m;
    let u = data.uncertainty.as_ref();
    Block::Table {
        header: vec!["".into(), "x (mm)".into(), "y (mm)".into(), "z (mm)".into()],
        // A single package's three rows are one point: shown once (docs/model.md §4.7).
        rows: (0..if data.single_package { 1 } else { 3 })
            .map(|i| {
                let mut row = vec![if data.single_package {
                    "r".to_string()
                } else {
                    format!("r{}", i + 1)
                }];
                for j in 0..3 {
                    let cell = pm_opt(
                        r[i][j] * 1e3,
                        u.map(|u| u.lever_arms_m_1sigma[i][j] * 1e3),
                        4,
                    );
                    let nd = u.is_some_and(|u| !u.lever_arms_observable[i][j]);
                    row.push(if nd { format!("({cell}) n.d.") } else { cell });
                }
                row
            })
            .collect(),
    }
}

/// Tables 2 and 4: per segment and axis, theoretical, before, after static, after full (g), the
/// residual and the segment's 1σ (µg). `rotating`: the rotating segments (Table 4) or the static ones.
pub(crate) fn before_after_table(data: &ReportData, rotating: bool) -> Block {
    let mut rows = Vec::new();
    for r in data
        .segments
        .iter()
        .filter(|r| (r.kind != SegmentKind::Static) == rotating)
    {
        for j in 0..3 {
            rows.push(vec![
                if j == 0 {
                    r.name.clone()
                } else {
                    String::new()
                },
                axis_name(j).to_string(),
                g_or_dash(r.truth_g[j]),
                format!("{:+.6}", r.before_g[j]),
                format!("{:+.6}", r.after_static_g[j]),
                format!("{:+.6}", r.after_g[j]),
                residual_cell(r.error_g(Compensation::Full)[j], r.sigma_g[j]),
            ]);
        }
    }
    Block::Table {
        header: [
            "segment",
            "axis",
            "theoretical (g)",
            "before: bias+scale (g)",
            "after: static (g)",
            "after: static+dynamic (g)",
            "residual ± 1σ (µg)",
        ]
        .map(String::from)
        .to_vec(),
        rows,
    }
}

/// The residual after full compensation and the segment's own 1σ, µg, through the one ± formatter
/// (to 0.1 µg, more when the 1σ needs it); "—" without a theoretical value.
fn residual_cell(e_g: f64, sigma_g: f64) -> String {
    if e_g.is_finite() {
        pm(e_g * 1e6, sigma_g * 1e6, 1)
    } else {
        "—".into()
    }
}

/// Whether the calibration carries lever arms at all (a session without rotations fixes them at 0).
fn lever_arms_calibrated(data: &ReportData) -> bool {
    match &data.uncertainty {
        Some(u) => u
            .lever_arms_m_1sigma
            .iter()
            .flatten()
            .any(|s| s.is_finite()),
        None => data
            .calibration
            .lever_arms
            .r_m
            .iter()
            .flatten()
            .any(|r| *r != 0.0),
    }
}

/// What "theoretical" means in the tables and figures below.
fn theoretical_note(data: &ReportData) -> String {
    let count = |t| data.segments.iter().filter(|r| r.theoretical == t).count();
    let mut s = "Theoretical: the specific force at the calibration's reference point that this \
                 session's own fit gives, with each segment's fitted attitude (the terminal's \
                 \"Outputs per segment\" shows the same)."
        .to_string();
    let planned = count(Theoretical::Planned);
    if planned > 0 {
        s.push_str(&format!(
            " {planned} segment(s) the fit has no value for are compared against the plan's nominal \
             attitude."
        ));
    }
    let unknown = count(Theoretical::Unknown);
    if unknown > 0 {
        s.push_str(&format!(
            " {unknown} hand-held position(s) the fit has no value for have no theoretical value \
             (their planned attitude is only a rough guess): shown as —."
        ));
    }
    s
}

/// The navigation table: final velocity and position error of each replayed run and level.
pub(crate) fn navigation_table(runs: &[NavigationRun]) -> Block {
    let mut rows = Vec::new();
    for run in runs {
        for c in &run.cases {
            rows.push(vec![
                run.segment.clone(),
                format!("{}", fmt_rate(run.rate_deg_s)),
                c.compensation.label().into(),
                format!("{:.3}", linalg::norm(&c.error_g) * 1e3),
                format!("{:.4}", c.drift.final_velocity_error_m_s()),
                format!("{:.3}", c.drift.final_position_error_m()),
            ]);
        }
    }
    Block::Table {
        header: [
            "run",
            "rate (°/s)",
            "compensation",
            "|error| (mg)",
            "final |v| error (m/s)",
            "final |p| error (m)",
        ]
        .map(String::from)
        .to_vec(),
        rows,
    }
}

/// What Table 2 says in place of its rows when the session has no static segment.
pub(crate) const NO_STATIC_ROW: &str = "No row: every segment of this session with data rotates \
     (its plan has no static segment), so there is no static output to compare.";

/// The whole page.
pub fn page(
    data: &ReportData,
    session: &str,
    calibration: &str,
    figure_stems: &[String],
) -> Vec<Block> {
    let mut b = Vec::new();
    b.push(Block::Heading(1, "Calibration report".into()));
    b.push(Block::Para(format!(
        "Session `{session}`, calibration `{calibration}`. Values with their 1σ; 1σ of the \
         residuals is the standard error of each segment's mean (its own noise)."
    )));
    for w in &data.warnings {
        b.push(Block::Para(format!("**Warning:** {w}")));
    }
    b.push(Block::Heading(2, "Table 1. Static calibration".into()));
    b.push(table1(data));
    if lever_arms_calibrated(data) && data.single_package {
        b.push(Block::Heading(
            2,
            "Table 3. Lever arm of the package".into(),
        ));
        b.push(Block::Para(format!(
            "One lever arm for the three accelerometers, which share one package. Reference point: \
             {}. n.d. = not determined by the calibrating plan.",
            reference_point(&data.calibration.reference)
        )));
        b.push(table3(data));
        b.push(Block::Para(format!(
            "{}.",
            estimator::estimate::IN_PACKAGE_NOT_OBSERVABLE
        )));
    } else if lever_arms_calibrated(data) {
        b.push(Block::Heading(2, "Table 3. Lever arms".into()));
        b.push(Block::Para(format!(
            "Reference point: {}. n.d. = not determined by the calibrating plan.",
            reference_point(&data.calibration.reference)
        )));
        b.push(table3(data));
    } else {
        b.push(Block::Heading(2, "Lever arms".into()));
        b.push(Block::Para(
            "Not calibrated: the calibrating session has no rotation, so the lever arms are 0 and \
             the device applies no size-effect correction (static compensation only)."
                .into(),
        ));
    }
    b.push(Block::Heading(
        2,
        "Outputs before and after compensation (like Tables 2 and 4)".into(),
    ));
    b.push(Block::Para(theoretical_note(data)));
    b.push(Block::Heading(3, "Static segments (Table 2)".into()));
    if data.segments.iter().any(|r| r.kind == SegmentKind::Static) {
        b.push(before_after_table(data, false));
    } else {
        b.push(Block::Para(NO_STATIC_ROW.into()));
    }
    if data.segments.iter().any(|r| r.kind != SegmentKind::Static) {
        b.push(Block::Heading(3, "Rotating segments (Table 4)".into()));
        b.push(before_after_table(data, true));
    }
    b.push(Block::Para(format!(
        "χ² of this calibration on this session (residual after full compensation over each segment's \
         own noise): {:.1} for {} values.",
        data.chi2, data.chi2_terms
    )));
    for stem in figure_stems.iter().filter(|s| !s.starts_with("navigation")) {
        b.push(Block::Image {
            src: format!("{stem}.png"),
            alt: stem.clone(),
        });
    }
    navigation_section(&mut b, data, figure_stems);
    b.extend(super::gyro_section::gyro_section(data));
    session_fit_section(&mut b, data);
    b
}

/// The navigation check: its table and figures, or why it is left out.
fn navigation_section(b: &mut Vec<Block>, data: &ReportData, figure_stems: &[String]) {
    b.push(Block::Heading(
        2,
        "Navigation check: velocity and position error of an integrated run, before and after \
         compensation"
            .into(),
    ));
    if data.navigation.is_empty() {
        b.push(Block::Para(
            "Left out (see the warnings above for why).".into(),
        ));
    } else {
        b.push(Block::Para(
            "Noise-free replay: each run holds the segment's recorded mean outputs for the whole \
             run, compensates them, removes the theoretical specific force and integrates twice in \
             body axes."
                .into(),
        ));
        b.push(navigation_table(&data.navigation));
    }
    for stem in figure_stems.iter().filter(|s| s.starts_with("navigation")) {
        b.push(Block::Image {
            src: format!("{stem}.png"),
            alt: stem.clone(),
        });
    }
}

/// The session's own fit: its χ², exclusions and what it did not determine, and its terminal text.
fn session_fit_section(b: &mut Vec<Block>, data: &ReportData) {
    b.push(Block::Heading(2, "This session's own fit".into()));
    match &data.session_fit {
        Ok(o) => {
            b.push(Block::Para(format!(
                "Method: {}. χ² = {:.1}, dof = {}, χ²/dof = {:.2}. Excluded segments: {}. Lever-arm \
                 components not determined to {:.0} µm: {}.",
                o.method,
                o.fit.chi2,
                o.fit.dof,
                o.fit.reduced_chi2,
                if o.excluded.is_empty() {
                    "none".to_string()
                } else {
                    o.excluded
                        .iter()
                        .map(|e| e.to_string())
                        .collect::<Vec<_>>()
                        .join("; ")
                },
                o.observability.threshold_m * 1e6,
                {
                    let u = o.observability.undetermined();
                    if u.is_empty() {
                        "none".to_string()
                    } else {
                        u.join(", ")
                    }
                }
            )));
            if let Some(t) = &o.thermal {
                let [x, y, z] = t.reduced_chi2();
                b.push(Block::Para(format!(
                    "Temperature fit: χ²/dof x {x:.2}, y {y:.2}, z {z:.2} over every sample of the \
                     segments that determine it; the largest is checked against the same limit as \
                     the fit's χ²/dof, since a misfit within a ramp leaves the segment means the \
                     main fit sees (docs/model.md §9)."
                )));
            }
            if let Some(w) = &o.bias_walk {
                b.push(Block::Para(bias_walk_note(w)));
            }
            b.push(Block::Pre(crate::report::render(
                o,
                &data.session_fit_segments,
            )));
        }
        Err(e) => b.push(Block::Para(format!(
            "The session alone does not calibrate: {}",
            shared::chain::Chain(e)
        ))),
    }
}

/// The walk the session fit assumed (docs/model.md §11.3): its strength, where it came from, and
/// the strength the segments were weighted with.
fn bias_walk_note(w: &estimator::estimate::WalkEstimate) -> String {
    let [x, y, z] = w.axes_mg_sqrt_s;
    let source = match (w.origin, w.sigma_mg_sqrt_s) {
        (_, Some(sd)) => format!(
            "estimated from the session, {:.5} ± {sd:.5} mg/√s (1σ)",
            w.mg_sqrt_s
        ),
        (estimator::estimate::WalkOrigin::Unit, None) => {
            format!("from the unit's noise figures, x {x:.5}, y {y:.5}, z {z:.5} mg/√s")
        }
        _ => format!("given, {:.5} mg/√s", w.mg_sqrt_s),
    };
    if !w.used {
        return format!(
            "Bias random walk (docs/model.md §11): {source}, {:.1}σ from none: not determined by \
             the session (under {}σ), so the bias is fitted as constant.",
            w.significance.unwrap_or(0.0),
            estimator::estimate::Z_WALK
        );
    }
    format!(
        "Bias random walk (docs/model.md §11): {source}; the segments weighted with {:.5} mg/√s. \
         The figure bias_walk shows each segment's fitted bias over the session with its 1σ.",
        w.fit_mg_sqrt_s
    )
}
