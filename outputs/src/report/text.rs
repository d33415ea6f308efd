//! The terminal report of a calibration: the paper's Table 1 (zero bias, scale factor, installation
//! angles) and Table 3 (lever arms) with 1σ, the per-segment outputs before and after compensation
//! (like Tables 2 and 4, from the one table [`super::segment_rows`]) with the fit's χ² check, the excluded segments, the method comparison and the
//! warnings. Plain text, no colour, so it reads the same in a log.

use super::format::{out_digits, pm, reference_point};
use super::SegmentRow;
use estimator::estimate::{
    CalibrationOutcome, GyroEstimate, GyroWalkAxes, GyroWalkEstimate, Method, MountTilt,
    Prediction, SegmentDiagnostic, SegmentKind, StaticSplit, IN_PACKAGE_NOT_OBSERVABLE, PAPER_LEN,
};
use recording::session::{Plan, SegmentStats};
use shared::params::axis_name;
use std::fmt::Write;

/// Lever arm in mm with its 1σ, marked when not determined.
fn lever_cell(r: f64, s: f64, observable: bool, fixed: bool) -> String {
    if fixed {
        "fixed at 0 (n.o.)".to_string()
    } else if observable {
        pm(r * 1e3, s * 1e3, 4)
    } else {
        format!("({}) n.d.", pm(r * 1e3, s * 1e3, 3))
    }
}

/// The full report: Tables 1 and 3, the methods compared, the per-segment outputs, the fit, the
/// excluded segments and the warnings. `segments`: the outputs of the session's segments through
/// this calibration ([`super::segment_rows`]); a segment without a row shows the fit's values only.
pub fn render(o: &CalibrationOutcome, segments: &[SegmentRow]) -> String {
    let mut s = String::new();
    let _ = writeln!(s, "Calibration ({}), 1σ{}", o.method, sigma_note(o));
    let _ = writeln!(s);
    render_table1(&mut s, o);
    render_table3(&mut s, o);
    render_comparison(&mut s, o);
    let _ = writeln!(s);
    render_attitudes(&mut s, &o.static_split, &o.mount_tilts);
    render_gyro(&mut s, o.gyro.as_ref());
    let _ = writeln!(s);
    let _ = writeln!(
        s,
        "Outputs per segment (g), like Tables 2 and 4: theoretical (the fitted specific force at the reference point) | bias+scale only | static compensation | full compensation; χ² of 3 outputs against the segment's own noise (* = above the 99.9 % point 16.3)"
    );
    for dgn in &o.segments {
        render_segment(&mut s, dgn, segments.iter().find(|r| r.name == dgn.name));
    }
    let _ = writeln!(
        s,
        "Fit: χ² = {:.1}, dof = {}, χ²/dof = {:.2}, 1σ scaled by {:.2}",
        o.fit.chi2, o.fit.dof, o.fit.reduced_chi2, o.fit.sigma_scale
    );
    if let Some(t) = &o.thermal {
        let [x, y, z] = t.reduced_chi2();
        let _ = writeln!(
            s,
            "Temperature fit: χ²/dof x {x:.2}, y {y:.2}, z {z:.2} over every sample (the largest is \
             checked against the same limit as the fit's; docs/model.md §9)"
        );
    }
    render_walks(&mut s, o);
    if !o.bias_track.is_empty() {
        let _ = writeln!(s, "Fitted bias wander from u0 per segment, mg (x, y, z):");
        for p in &o.bias_track {
            let [x, y, z] = p.bias_mg;
            let _ = writeln!(
                s,
                "  {:8.1} s  {x:+.4} {y:+.4} {z:+.4}  {}",
                p.t_mid_s, p.name
            );
        }
    }
    super::thermal::render(&mut s, o);
    if !o.excluded.is_empty() {
        let _ = writeln!(s);
        s.push_str(&render_excluded(&o.excluded));
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

/// The accelerometers' and the gyro's bias random walks the fit used or estimated, with how each
/// came (docs/model.md §11, §11.6).
fn render_walks(s: &mut String, o: &CalibrationOutcome) {
    if let Some(w) = &o.bias_walk {
        let how = match (w.sigma_mg_sqrt_s, w.origin) {
            (Some(sd), _) if !w.used => format!(
                " ± {sd:.5} (1σ), estimated from the session, {:.1}σ from none: not determined \
                 (under {}σ), the bias fitted as constant",
                w.significance.unwrap_or(0.0),
                estimator::estimate::Z_WALK
            ),
            (Some(sd), _) => format!(
                " ± {sd:.5} (1σ), estimated from the session ({:.1}σ from none); the segments \
                 weighted with √(K² + σ²) = {:.5}",
                w.significance.unwrap_or(0.0),
                w.fit_mg_sqrt_s
            ),
            (None, estimator::estimate::WalkOrigin::Unit) => {
                let [x, y, z] = w.axes_mg_sqrt_s;
                format!(" (the strongest axis; from the unit's noise figures: x {x:.5}, y {y:.5}, z {z:.5})")
            }
            (None, _) => " (given)".into(),
        };
        let _ = writeln!(
            s,
            "Bias random walk: {:.5} mg/√s{how} (docs/model.md §11)",
            w.mg_sqrt_s
        );
    }
    let per_axis = o
        .gyro_walk
        .and_then(|g| Some((g, g.axes.filter(|a| a.used)?)));
    if let Some((g, a)) = per_axis {
        render_gyro_axes(s, &g, &a);
        return;
    }
    match (&o.gyro_walk, o.gyro_bias_walk_deg_s_sqrt_s) {
        (Some(g), _) => {
            let how = if g.used {
                format!(
                    "the gyro's mean rates weighted with √(K² + σ²) = {:.6}, its bias b at the \
                     session's start",
                    g.fit_deg_s_sqrt_s
                )
            } else {
                format!(
                    "not determined (under {}σ), the gyro bias fitted as constant",
                    estimator::estimate::Z_WALK
                )
            };
            let _ = writeln!(
                s,
                "Gyro bias random walk: {:.6} ± {:.6} °/s/√s (1σ), estimated from the session, \
                 {:.1}σ from none; {how} (docs/model.md §11.6)",
                g.deg_s_sqrt_s, g.sigma_deg_s_sqrt_s, g.significance
            );
        }
        (None, Some(k)) => {
            let _ = writeln!(
                s,
                "Gyro bias random walk: {k:.5} °/s/√s (given; the gyro's mean rates weighted with \
                 it, its bias b at the session's start; docs/model.md §11.6)"
            );
        }
        (None, None) => {}
    }
}

/// The gyro walk's line where the fit weighted each axis with its own strength (docs/model.md
/// §11.6).
fn render_gyro_axes(s: &mut String, g: &GyroWalkEstimate, a: &GyroWalkAxes) {
    let axes = |v: [f64; 3], sd: Option<[f64; 3]>| -> String {
        let each: Vec<String> = (0..3)
            .map(|i| match sd {
                Some(sd) => format!("{} {:.6} ± {:.6}", axis_name(i), v[i], sd[i]),
                None => format!("{} {:.6}", axis_name(i), v[i]),
            })
            .collect();
        each.join(", ")
    };
    let _ = writeln!(
        s,
        "Gyro bias random walk: {:.6} ± {:.6} °/s/√s (1σ), estimated from the session, {:.1}σ \
         from none; per axis {} °/s/√s (1σ), determined apart (2Δlog L = {:.1} over the one \
         strength, at least {}): the gyro's mean rates weighted per axis with √(K² + σ²) = {}, \
         its bias b at the session's start (docs/model.md §11.6)",
        g.deg_s_sqrt_s,
        g.sigma_deg_s_sqrt_s,
        g.significance,
        axes(a.deg_s_sqrt_s, Some(a.sigma_deg_s_sqrt_s)),
        a.likelihood_ratio,
        estimator::estimate::LR_AXES,
        axes(a.fit_deg_s_sqrt_s, None),
    );
}

/// The segments a calibration left out, one line each with why and the figure that failed
/// against its limit; empty when none was.
pub fn render_excluded(excluded: &[estimator::estimate::Exclusion]) -> String {
    let mut s = String::new();
    if !excluded.is_empty() {
        let _ = writeln!(s, "Excluded segments ({}):", excluded.len());
        for e in excluded {
            let _ = writeln!(s, "  {e}");
        }
    }
    s
}

/// Table 1: zero bias, scale factor and installation angles with their 1σ.
fn render_table1(s: &mut String, o: &CalibrationOutcome) {
    let unit = o.calibration.statics.output_unit;
    let sym = unit.symbol();
    let d = out_digits(unit);
    let st = &o.calibration.statics;
    let u = &o.uncertainty;
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
}

/// Table 3: the lever arms in mm, marked where the plan did not determine them; one line instead when
/// the session has no rotation and so fixes every one at 0.
fn render_table3(s: &mut String, o: &CalibrationOutcome) {
    let u = &o.uncertainty;
    let _ = writeln!(s);
    if o.observability.fixed_at_zero.iter().flatten().all(|f| *f) {
        let _ = writeln!(
            s,
            "Lever arms: not calibrated (the session has no rotation): 0, so the device applies no size-effect correction"
        );
        return;
    }
    if o.single_package {
        render_package_lever_arm(s, o);
        return;
    }
    let _ = writeln!(
        s,
        "Table 3. Lever arms (mm), reference: {}; n.d. = not determined to {:.0} µm, n.o. = not observable",
        reference_point(&o.calibration.reference),
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
}

/// A single-package unit's Table 3: the package's one lever arm `r` with its 1σ, and the in-package
/// size effect in words, not numbers (docs/model.md §4.7).
fn render_package_lever_arm(s: &mut String, o: &CalibrationOutcome) {
    let u = &o.uncertainty;
    let _ = writeln!(
        s,
        "Table 3. Lever arm of the package (mm), one for the three accelerometers, reference: {}; \
         n.d. = not determined to {:.0} µm, n.o. = not observable",
        reference_point(&o.calibration.reference),
        o.observability.threshold_m * 1e6
    );
    let _ = writeln!(s, "{:<4} {:>24} {:>24} {:>24}", "", "x", "y", "z");
    let cells: Vec<String> = (0..3)
        .map(|j| {
            lever_cell(
                o.calibration.lever_arms.r_m[0][j],
                u.lever_arms_m_1sigma[0][j],
                o.observability.observable[0][j],
                o.observability.fixed_at_zero[0][j],
            )
        })
        .collect();
    let _ = writeln!(
        s,
        "{:<4} {:>24} {:>24} {:>24}",
        "r", cells[0], cells[1], cells[2]
    );
    let _ = writeln!(s, "{IN_PACKAGE_NOT_OBSERVABLE}");
}

/// The lever arms of both methods side by side, when the other method was run too.
fn render_comparison(s: &mut String, o: &CalibrationOutcome) {
    let u = &o.uncertainty;
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
}

/// [`render`] with the session's segments through the outcome's own calibration.
pub fn render_session(o: &CalibrationOutcome, plan: &Plan, stats: &[SegmentStats]) -> String {
    match super::segment_rows(plan, stats, &o.calibration) {
        Ok(rows) => render(o, &rows),
        Err(e) => format!(
            "{}(the outputs after compensation cannot be shown: {})\n",
            render(o, &[]),
            shared::chain::Chain(&e)
        ),
    }
}

fn sigma_note(o: &CalibrationOutcome) -> String {
    if o.fit.sigma_scale > 1.0 {
        format!(" (scaled by √(χ²/dof) = {:.2})", o.fit.sigma_scale)
    } else {
        String::new()
    }
}

fn render_segment(s: &mut String, d: &SegmentDiagnostic, row: Option<&SegmentRow>) {
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
    let cell = |v: Option<f64>| v.map_or("        —".to_string(), |v| format!("{v:+.6}"));
    for i in 0..3 {
        let _ = writeln!(
            s,
            "    {}  {:+.6} | {} | {} | {}   (σ {:.1} µg)",
            axis_name(i),
            d.theoretical_g[i],
            cell(row.map(|r| r.before_g[i])),
            cell(row.map(|r| r.after_static_g[i])),
            cell(row.map(|r| r.after_g[i])),
            d.noise_g[i] * 1e6
        );
    }
}

/// The static 1σ split into intrinsic and body-frame parts, what fixes the frame, and each mount's
/// estimated attitude (docs/model.md §7).
fn render_attitudes(s: &mut String, split: &StaticSplit, tilts: &[MountTilt]) {
    let ug = |v: [f64; 3]| v.map(|x| format!("{:.2}", x * 1e6)).join(", ");
    let _ = writeln!(
        s,
        "Static 1σ, intrinsic part and body-frame alignment part:"
    );
    let _ = writeln!(
        s,
        "  biases (µg)                          {}",
        ug(split.bias_1sigma_g)
    );
    let _ = writeln!(
        s,
        "  scale factors (ppm)                  {}",
        ug(split.scale_1sigma_rel)
    );
    let _ = writeln!(
        s,
        "  non-orthogonality y|x, z|x, z|y (µrad) {}",
        ug(split.nonorthogonality_1sigma_rad)
    );
    let _ = writeln!(
        s,
        "  body-frame alignment about x, y, z (µrad) {}",
        ug(split.alignment_1sigma_rad)
    );
    let _ = writeln!(s, "  {}", split.frame);
    if tilts.iter().all(|t| !t.estimated) {
        return;
    }
    let fixture: Vec<&MountTilt> = tilts
        .iter()
        .filter(|t| t.estimated && t.prior_deg.is_some())
        .collect();
    if !fixture.is_empty() {
        let _ = writeln!(
            s,
            "Mount attitudes: angle of the estimated up from the nominal, 1σ per axis"
        );
    }
    for t in fixture {
        let p = t.prior_deg.unwrap_or(0.0);
        let flag = if t.tilt_deg > 3.0 * p {
            "  > 3× prior"
        } else {
            ""
        };
        let _ = writeln!(
            s,
            "  {:<22} up [{:+.5}, {:+.5}, {:+.5}]  tilt {}°  (prior {p:.3}°){flag}",
            t.name,
            t.up_b[0],
            t.up_b[1],
            t.up_b[2],
            pm(t.tilt_deg, t.sigma_deg, 4)
        );
    }
    let free: Vec<&MountTilt> = tilts
        .iter()
        .filter(|t| t.estimated && t.prior_deg.is_none())
        .collect();
    if !free.is_empty() {
        let _ = writeln!(
            s,
            "Free positions (no known attitude): the fitted up, and its 1σ per axis"
        );
    }
    for t in free {
        let _ = writeln!(
            s,
            "  {:<22} up [{:+.5}, {:+.5}, {:+.5}]  ± {:.4}°",
            t.name, t.up_b[0], t.up_b[1], t.up_b[2], t.sigma_deg
        );
    }
}

/// The gyro model with 1σ, and what the plan leaves undetermined (docs/model.md §8).
fn render_gyro(s: &mut String, g: Option<&GyroEstimate>) {
    let Some(g) = g else {
        return;
    };
    let _ = writeln!(s, "Gyro, w = G·ω + b (1σ):");
    for i in 0..3 {
        let row: Vec<String> = (0..3)
            .map(|j| {
                if g.matrix_1sigma[i][j] > estimator::estimate::gyro::UNDETERMINED_SIGMA {
                    format!("{:>24}", "n.d.")
                } else {
                    format!(
                        "{:>24}",
                        format!("{:+.6} ± {:.6}", g.matrix[i][j], g.matrix_1sigma[i][j])
                    )
                }
            })
            .collect();
        let _ = writeln!(
            s,
            "  G[{}]  {}   b {:+.5} ± {:.5} °/s",
            axis_name(i),
            row.join(" "),
            g.bias_rad_s[i].to_degrees(),
            g.bias_rad_s_1sigma[i].to_degrees()
        );
    }
    if let Some((scale, sigma)) = g.table_rate_scale {
        let _ = writeln!(
            s,
            "  table rate scale error {} ppm (its prior is the plan's table_rate_sigma_ppm: the gyro's scale cannot be better)",
            pm(scale * 1e6, sigma * 1e6, 1)
        );
    }
    if !g.undetermined.is_empty() {
        let how = if g.table_rate_scale.is_some() {
            "spin about at least three non-coplanar axes"
        } else {
            "turn the unit by hand about each of its three axes"
        };
        let _ = writeln!(
            s,
            "  not determined by this plan: {} ({how} to determine all of G)",
            g.undetermined.join(", ")
        );
    }
}

/// A single-package plan's verdict on the package's lever arm `r`, and the in-package size effect
/// in words (docs/model.md §4.7).
fn render_package_prediction(s: &mut String, p: &Prediction) {
    let worst = (0..3).map(|j| p.sigma[15 + j]).fold(0.0, f64::max);
    if (0..3).all(|j| p.lever_arms_observable[0][j]) {
        let _ = writeln!(
            s,
            "Common lever arm r (the package's position, one for the three accelerometers): \
             observable, every component to {:.4} mm (1σ) or better",
            worst * 1e3
        );
    } else {
        let _ = writeln!(
            s,
            "Common lever arm r (the package's position): NOT determined on every axis; add spins \
             about each body axis (docs/model.md §4.4)"
        );
    }
    let _ = writeln!(s, "{IN_PACKAGE_NOT_OBSERVABLE}");
}

/// The Cramér–Rao prediction of a plan (the check of `host plan`).
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
            if p.single_package && i > 0 {
                // One lever arm for the three: r1 is the package's r (docs/model.md §4.7).
                continue;
            }
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
        let label = match (p.single_package, k) {
            (true, 15..) => format!("r{}", axis_name(k - 15)),
            _ => label.clone(),
        };
        let _ = writeln!(s, "  {label:<10} {value:>14} ± {sigma} {unit}{mark}");
    }
    let _ = writeln!(s, "Lever-arm threshold: {:.0} µm", p.threshold_m * 1e6);
    if p.single_package {
        render_package_prediction(&mut s, p);
    }
    render_attitudes(&mut s, &p.static_split, &p.mount_tilts);
    render_gyro(&mut s, p.gyro.as_ref());
    if let Some(t) = &p.temperature {
        super::thermal::render_prediction(&mut s, t, &p.values);
    }
    for w in &p.warnings {
        let _ = writeln!(s, "  - {w}");
    }
    s
}

#[cfg(test)]
mod tests {
    use estimator::estimate::{calibrate_session_stats, EstimateOptions};
    use estimator::sim::synth::{self, SynthNoise};
    use recording::session::Plan;

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
        let truth = shared::params::PAPER_UNIT;
        let unit = shared::forward::ForwardModel::new(&truth).unwrap();
        let noise = SynthNoise {
            out_1sigma: [4e-4; 3],
            gyro_1sigma_rad_s: 0.0,
            sample_rate_hz: 1000.0,
        };
        let stats = synth::plan_stats(&plan, &unit, &noise, 60.0);
        let out = calibrate_session_stats(&plan, &stats, &EstimateOptions::default()).unwrap();
        let text = super::render_session(&out, &plan, &stats);
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
