//! The short block that ends `host calibrate`: what a person wants of the result, in the units an
//! engineer reads (biases in mg, scale factors with their 1σ in ppm, each accelerometer's
//! misalignment from its body axis in mrad, lever arms in mm, the gyro's bias in °/s and scale in
//! ppm), each ± 1σ, and the verdict. The full tables stay behind `calibrate -v` and in the report.

use crate::summary::CalibrationSummary;
use std::fmt::Write as _;

/// The block, one line per quantity and the verdict last.
pub fn render_summary_block(s: &CalibrationSummary) -> String {
    let p = |name: &str| s.parameters.iter().find(|p| p.name == name);
    let axes = AXES;
    // A lever-arm component is determined to the estimator's own threshold (the full table's rule).
    let lever_determined_m = estimator::estimate::LEVER_ARM_THRESHOLD_M;
    let mut out = String::from("Result (± 1σ):\n");
    // Biases: in mg where the output has a physical zero (m/s², g); else the zero-g output in its
    // own unit with its 1σ in that unit, and the 1σ in mg on a row of its own (one unit a figure).
    let mut bias = Vec::new();
    let mut zero = Vec::new();
    let mut scale = Vec::new();
    let mut misalignment = Vec::new();
    let mut output_unit = String::new();
    for a in axes {
        let (Some(b), Some(k)) = (p(&format!("bias_{a}")), p(&format!("scale_{a}"))) else {
            continue;
        };
        let mg = |v: f64| v / k.value * 1e3;
        match b.unit.as_str() {
            "m/s2" | "g" => bias.push(format!("{a} {}", pm(mg(b.value), b.sigma.map(mg), 3))),
            unit => {
                output_unit = unit.to_string();
                zero.push(format!("{a} {}", pm_same_unit(b.value, b.sigma)));
                bias.push(format!(
                    "{a} {}",
                    b.sigma.map_or("n.d.".into(), |sd| format!("{:.3}", mg(sd)))
                ));
            }
        }
        scale.push(format!(
            "{a} {:.6} {} ± {} ppm",
            k.value,
            k.unit,
            k.sigma
                .map_or("n.d.".into(), |sd| format!("{:.0}", sd / k.value * 1e6))
        ));
        let own = format!("theta_{a}{a}");
        if let Some(t) = p(&own) {
            let mrad = |deg: f64| deg.to_radians() * 1e3;
            misalignment.push(format!("{a} {}", pm(mrad(t.value), t.sigma.map(mrad), 3)));
        }
    }
    if zero.is_empty() {
        let _ = writeln!(out, "  bias, mg         {}", bias.join("   "));
    } else {
        let _ = writeln!(out, "  zero-g output, {output_unit:<3}{}", zero.join("   "));
        let _ = writeln!(out, "  bias 1σ, mg      {}", bias.join("   "));
    }
    let _ = writeln!(out, "  scale            {}", scale.join("   "));
    let _ = writeln!(
        out,
        "  misalignment     {}  mrad (each sensing axis from its body axis)",
        misalignment.join("   ")
    );
    if let Some(frame) = s.calibration.as_ref().and_then(|c| c.frame.as_ref()) {
        let _ = writeln!(out, "  body frame       {}", frame.axes);
    }
    for (i, a) in axes.iter().enumerate() {
        let comps: Vec<String> = axes
            .iter()
            .filter_map(|c| p(&format!("r{}{c}", i + 1)))
            .map(|r| match r.sigma {
                Some(sd) if sd <= lever_determined_m => pm(r.value * 1e3, Some(sd * 1e3), 3),
                _ => "n.d.".into(),
            })
            .collect();
        if !comps.is_empty() {
            let _ = writeln!(out, "  lever arm {a}, mm  {}", comps.join(", "));
        }
    }
    write_gyro(&mut out, s);
    let failures = s.failures();
    let _ = writeln!(
        out,
        "  verdict          {}: χ²/dof {:.2}{}{}",
        if s.passed { "PASS" } else { "FAIL" },
        s.chi2_per_dof,
        s.thermal_fit.as_ref().map_or(String::new(), |t| format!(
            ", temperature fit χ²/dof {:.2}",
            t.worst_chi2_per_dof
        )),
        if failures.is_empty() {
            String::new()
        } else {
            format!("; {failures}")
        }
    );
    out
}

/// The line after the result: the command that takes the calibration to a flight stack or a
/// driver.
pub fn next_line(calibration_toml: &std::path::Path) -> String {
    format!(
        "next: host export --calibration {} --format json   (or px4, ardupilot, kalibr, c, \
         fusion: `host export --help`)\n",
        calibration_toml.display()
    )
}

/// `v ± σ` in one unit, with as many decimals as give σ two significant digits (at least five).
fn pm_same_unit(v: f64, sigma: Option<f64>) -> String {
    let digits = sigma
        .filter(|sd| *sd > 0.0)
        .map_or(5, |sd| (1.0 - sd.log10().floor()).clamp(5.0, 12.0) as usize);
    match sigma {
        Some(sd) => format!("{v:.digits$} ± {sd:.digits$}"),
        None => format!("{v:.digits$} (n.d.)"),
    }
}

/// `v ± σ` with `digits` decimals, or `v (n.d.)` when it is not determined.
fn pm(v: f64, sigma: Option<f64>, digits: usize) -> String {
    match sigma {
        Some(sd) => format!("{v:+.digits$} ± {sd:.digits$}"),
        None => format!("{v:+.digits$} (n.d.)"),
    }
}

const AXES: [&str; 3] = ["x", "y", "z"];

/// The gyro's bias (°/s) and scale (ppm) lines, where the calibration has a gyro.
fn write_gyro(out: &mut String, s: &CalibrationSummary) {
    let p = |name: &str| s.parameters.iter().find(|p| p.name == name);
    let gyro_bias: Vec<String> = AXES
        .iter()
        .filter_map(|a| p(&format!("gyro_bias_{a}")).map(|b| (a, b)))
        .map(|(a, b)| {
            format!(
                "{a} {}",
                pm(b.value.to_degrees(), b.sigma.map(f64::to_degrees), 4)
            )
        })
        .collect();
    if !gyro_bias.is_empty() {
        let _ = writeln!(out, "  gyro bias, °/s   {}", gyro_bias.join("   "));
    }
    // The scale error of docs/model.md §8 (the row's length less one), from G's entries.
    let entry = |i: usize, j: usize| p(&format!("gyro_g_{}{}", AXES[i], AXES[j]));
    let gyro_scale: Vec<String> = match entry(0, 0) {
        None => Vec::new(),
        Some(_) => {
            let g = core::array::from_fn(|i| {
                core::array::from_fn(|j| {
                    entry(i, j).map_or(if i == j { 1.0 } else { 0.0 }, |e| e.value)
                })
            });
            let sd = core::array::from_fn(|i| {
                core::array::from_fn(|j| entry(i, j).and_then(|e| e.sigma).unwrap_or(0.0))
            });
            let determined = |i: usize| entry(i, i).is_some_and(|e| e.sigma.is_some());
            estimator::estimate::gyro::scale_error(&g, &sd)
                .iter()
                .enumerate()
                .map(|(i, (e, s))| {
                    format!(
                        "{} {}",
                        AXES[i],
                        pm(e * 1e6, determined(i).then_some(s * 1e6), 0)
                    )
                })
                .collect()
        }
    };
    if !gyro_scale.is_empty() {
        let _ = writeln!(out, "  gyro scale, ppm  {}", gyro_scale.join("   "));
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::summary::Parameter;

    fn param(name: &str, unit: &str, value: f64, sigma: Option<f64>) -> Parameter {
        Parameter {
            name: name.into(),
            unit: unit.into(),
            value,
            sigma,
        }
    }

    /// A passing summary of `parameters` at χ²/dof `chi2_per_dof` (one degree of freedom), with
    /// nothing else to say.
    fn passing(parameters: Vec<Parameter>, chi2_per_dof: f64) -> CalibrationSummary {
        CalibrationSummary {
            unit_id: None,
            parameters,
            undetermined: Vec::new(),
            temperature: None,
            calibration: None,
            chi2: chi2_per_dof,
            dof: 1,
            chi2_per_dof,
            thermal_fit: None,
            checks: Vec::new(),
            passed: true,
            warnings: Vec::new(),
            in_package_size_effect: None,
            gyro_bias_walk_deg_s_sqrt_s: None,
            gyro_walk: None,
            bias_walk: None,
        }
    }

    /// A hand-worked case: 49.03 mm/s² of bias at 9.80665 m/s² per g is 5.000 mg; 1σ 2e-5 of the
    /// scale is 20 ppm; θ_xx = 0.5° is 8.727 mrad; a lever arm of 12.3 ± 0.05 mm, one
    /// of 1σ 0.5 mm is not determined.
    #[test]
    fn the_block_is_in_an_engineers_units() {
        let g = shared::STANDARD_GRAVITY_M_S2;
        let mut s = passing(Vec::new(), 1.04);
        s.parameters = vec![
            param("bias_x", "m/s2", 5e-3 * g, Some(1e-4 * g)),
            param("scale_x", "m/s2/g", g, Some(g * 2e-5)),
            param("theta_xx", "deg", 0.5, Some(0.01)),
            param("r1x", "m", 0.0123, Some(5e-5)),
            param("r1y", "m", 0.001, Some(5e-4)),
            param(
                "gyro_bias_x",
                "rad/s",
                0.01f64.to_radians(),
                Some(1e-4f64.to_radians()),
            ),
            param("gyro_g_xx", "1", 1.0 + 250e-6, Some(10e-6)),
        ];
        let b = render_summary_block(&s);
        assert!(b.contains("bias, mg         x +5.000 ± 0.100"), "{b}");
        assert!(b.contains("± 20 ppm"), "{b}");
        assert!(b.contains("x +8.727 ± 0.175  mrad"), "{b}");
        assert!(b.contains("lever arm x, mm  +12.300 ± 0.050, n.d."), "{b}");
        assert!(b.contains("gyro bias, °/s   x +0.0100 ± 0.0001"), "{b}");
        assert!(b.contains("gyro scale, ppm  x +250 ± 10"), "{b}");
        assert!(b.contains("verdict          PASS: χ²/dof 1.04"), "{b}");
    }

    /// The body frame the numbers are in, as the calibration file states it; none where the file
    /// states none.
    #[test]
    fn the_block_names_the_body_frame_the_file_states() {
        use estimator::estimate::BodyFrame;
        use estimator::unit_file::{FrameSection, UnitFile};
        let mut s = passing(Vec::new(), 1.0);
        assert!(!render_summary_block(&s).contains("body frame"));
        let mut file = UnitFile::paper_unit();
        file.frame = Some(FrameSection::of(&BodyFrame::Convention));
        s.calibration = Some(file);
        let b = render_summary_block(&s);
        assert!(
            b.contains("  body frame       the accelerometer triad's own: x along accelerometer x"),
            "{b}"
        );
    }

    /// An output in volts: the zero-g output in V with its 1σ in V, the 1σ in mg on a row of its
    /// own (4 µV of 0.4 V/g is 0.010 mg), never a figure in volts with a 1σ in mg.
    #[test]
    fn an_offset_outputs_zero_and_its_sigma_share_one_unit() {
        let s = passing(
            vec![
                param("bias_x", "V", 2.4051, Some(4e-6)),
                param("scale_x", "V/g", 0.4, Some(8e-6)),
            ],
            1.0,
        );
        let b = render_summary_block(&s);
        assert!(
            b.contains("zero-g output, V  x 2.4051000 ± 0.0000040"),
            "{b}"
        );
        assert!(b.contains("bias 1σ, mg      x 0.010"), "{b}");
        for line in b.lines().filter(|l| l.contains(" V ") || l.contains(", V")) {
            assert!(!line.contains("mg"), "two units in one figure: {line}");
        }
    }

    /// A gyro scale error is the row's length less one (docs/model.md §8), as `host segment` says
    /// it: a row (1.004772, 0.021, 0) is +4991 ppm (1.004772 · √(1 + (0.021/1.004772)²) − 1), not
    /// the diagonal's +4772.
    #[test]
    fn the_gyro_scale_is_the_rows_length() {
        let mut parameters = Vec::new();
        for (i, a) in AXES.iter().enumerate() {
            for (j, b) in AXES.iter().enumerate() {
                let v = match (i, j) {
                    (0, 0) => 1.004772,
                    (0, 1) => 0.021,
                    _ if i == j => 1.0,
                    _ => 0.0,
                };
                parameters.push(param(&format!("gyro_g_{a}{b}"), "1", v, Some(1e-5)));
            }
        }
        let s = passing(parameters, 1.0);
        let b = render_summary_block(&s);
        let want = (1.004772f64.powi(2) + 0.021f64.powi(2)).sqrt() - 1.0;
        assert_eq!(format!("{:+.0}", want * 1e6), "+4991");
        assert!(
            b.contains("gyro scale, ppm  x +4991 ± 10   y +0 ± 10"),
            "{b}"
        );
    }
}
