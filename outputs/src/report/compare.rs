//! Two calibrations of one unit side by side (`host compare`), each difference in units of its
//! combined 1σ: the accelerometer's paper-form values, the gyro's `G` and `b`, and the temperature
//! model's coefficients ([`crate::summary::section_values`]). [`compare`] reads the files,
//! [`ComparisonTable::render`] prints the table.

use crate::calibration_guard::{meet, Frame, Meeting, Mine, Other, Temperatures};
use crate::summary::section_values;
use estimator::estimate::{paper_labels, paper_order, paper_values, PAPER_LEN};
use estimator::unit_file::{UnitFile, UnitFileError};
use shared::Calibration;
use std::fmt::Write as _;
use std::path::Path;

/// One parameter of [`ComparisonTable`].
#[derive(Clone, Debug, PartialEq)]
pub struct ComparisonRow {
    /// Name, e.g. "bias x", "θxy", "r1z", "gyro_g_xy", "temp_bias_x_c1".
    pub label: String,
    /// Display unit.
    pub unit: String,
    /// Value in A (display unit).
    pub a: f64,
    /// Value in B.
    pub b: f64,
    /// 1σ of A, when A has an `[uncertainty]`.
    pub sigma_a: Option<f64>,
    /// 1σ of B.
    pub sigma_b: Option<f64>,
    /// `b − a`.
    pub diff: f64,
    /// `(b − a) / √(σa² + σb²)` (missing σ count as 0; `None` when neither has one or it is ∞).
    pub diff_sigma: Option<f64>,
    /// A lever-arm component or gyro entry that A or B did not determine, or a temperature
    /// coefficient of models about different reference temperatures: not a measured difference.
    pub undetermined: bool,
}

/// Two calibrations side by side.
#[derive(Clone, Debug, PartialEq)]
pub struct ComparisonTable {
    /// Name of A (its path).
    pub a_name: String,
    /// Name of B.
    pub b_name: String,
    /// Biases, scale factors, nine angles, nine lever arms; then the gyro's and the temperature
    /// model's values both files have.
    pub rows: Vec<ComparisonRow>,
    /// Things to know (reference points, missing σ, …).
    pub notes: Vec<Note>,
}

/// One thing to know about a comparison, with the figures its message states: a value, so that a
/// caller can tell one from another ([`Note::code`]) without matching words; its `Display` is the
/// one wording the table and the JSON document print.
#[derive(Clone, Debug, PartialEq)]
pub enum Note {
    /// Neither file has σ: differences are not in units of σ.
    NoSigma,
    /// Only one file has σ (`in_a`: A's).
    SigmaOfOne {
        /// A has it (else B).
        in_a: bool,
    },
    /// The lever arms are relative to different reference points.
    ReferencePoints {
        /// A's.
        a: shared::ReferencePoint,
        /// B's.
        b: shared::ReferencePoint,
    },
    /// Different local gravity, m/s².
    Gravity {
        /// A's.
        a: f64,
        /// B's.
        b: f64,
    },
    /// A lever-arm component one calibration did not determine (n.d.).
    LeverArmUndetermined,
    /// A section only one file has.
    SectionOfOne {
        /// The section (`[gyro]`, `[temperature]`).
        section: &'static str,
        /// A has it (else B).
        in_a: bool,
    },
    /// Temperature models about different reference temperatures, °C.
    ReferenceTemperatures {
        /// A's.
        a: f64,
        /// B's.
        b: f64,
    },
    /// A gyro entry one calibration did not determine (n.d.).
    GyroUndetermined,
}

impl Note {
    /// A stable name of the note's kind, for a program reading the notes, independent of its
    /// wording.
    pub fn code(&self) -> &'static str {
        match self {
            Note::NoSigma => "no_sigma",
            Note::SigmaOfOne { .. } => "sigma_of_one",
            Note::ReferencePoints { .. } => "reference_points",
            Note::Gravity { .. } => "gravity",
            Note::LeverArmUndetermined => "lever_arm_undetermined",
            Note::SectionOfOne { .. } => "section_of_one",
            Note::ReferenceTemperatures { .. } => "reference_temperatures",
            Note::GyroUndetermined => "gyro_undetermined",
        }
    }

    /// The notes said as text, in order (the JSON document's `notes`).
    pub fn texts(notes: &[Note]) -> Vec<String> {
        notes.iter().map(ToString::to_string).collect()
    }
}

impl std::fmt::Display for Note {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        let which = |in_a: bool| if in_a { "A" } else { "B" };
        match self {
            Note::NoSigma => f.write_str(
                "neither file has an [uncertainty] table: differences are not in units of σ",
            ),
            Note::SigmaOfOne { in_a } => write!(
                f,
                "only {} has an [uncertainty] table: σ is that file's alone",
                which(*in_a)
            ),
            Note::ReferencePoints { a, b } => write!(
                f,
                "the lever arms are relative to different reference points ({} vs {}): only their \
                 differences r_i − r_j compare",
                super::format::reference_point(a),
                super::format::reference_point(b)
            ),
            Note::Gravity { a, b } => write!(
                f,
                "different local gravity: {a} vs {b} m/s² (scale factors per g differ by that ratio)"
            ),
            Note::LeverArmUndetermined => f.write_str(
                "n.d.: a lever-arm component one of the calibrations did not determine (its value is \
                 not a measurement)",
            ),
            Note::SectionOfOne { section, in_a } => write!(
                f,
                "only {} has a {section} section: it is not compared",
                which(*in_a)
            ),
            Note::ReferenceTemperatures { a, b } => write!(
                f,
                "the temperature models are about different reference temperatures ({a} vs {b} \
                 °C): their coefficients are not compared (n.d.)"
            ),
            Note::GyroUndetermined => f.write_str(
                "n.d. on a gyro entry: one of the calibrations did not determine it (1σ above 1e-3)",
            ),
        }
    }
}

impl ComparisonTable {
    /// The row with the largest |difference|/σ among the determined ones.
    pub fn worst(&self) -> Option<&ComparisonRow> {
        self.rows
            .iter()
            .filter(|r| !r.undetermined && r.diff_sigma.is_some())
            .max_by(|x, y| {
                let f = |r: &ComparisonRow| r.diff_sigma.map_or(0.0, f64::abs);
                f(x).total_cmp(&f(y))
            })
    }

    /// The terminal table.
    pub fn render(&self) -> String {
        let mut s = String::new();
        let _ = writeln!(s, "A: {}", self.a_name);
        let _ = writeln!(s, "B: {}", self.b_name);
        let w = self.rows.iter().map(|r| r.label.len()).fold(9, usize::max);
        let _ = writeln!(
            s,
            "{:<w$} {:>9} {:>15} {:>12} {:>15} {:>12} {:>13} {:>9}",
            "param", "unit", "A", "1σ A", "B", "1σ B", "B − A", "(B−A)/σ"
        );
        for r in &self.rows {
            let sig = |v: Option<f64>| match v {
                Some(v) if v.is_finite() => format!("{v:.3e}"),
                Some(_) => "∞".into(),
                None => "no σ".into(),
            };
            let ds = match r.diff_sigma {
                Some(d) => format!("{d:+.1}σ"),
                None => "no σ".into(),
            };
            let _ = writeln!(
                s,
                "{:<w$} {:>9} {:>15.7} {:>12} {:>15.7} {:>12} {:>13.3e} {:>9}{}",
                r.label,
                r.unit,
                r.a,
                sig(r.sigma_a),
                r.b,
                sig(r.sigma_b),
                r.diff,
                ds,
                if r.undetermined { "  n.d." } else { "" }
            );
        }
        if let Some(w) = self.worst() {
            let _ = writeln!(
                s,
                "Largest difference: {} at {:+.1}σ",
                w.label,
                w.diff_sigma.unwrap_or(0.0)
            );
        }
        for n in &self.notes {
            let _ = writeln!(s, "note: {n}");
        }
        s
    }
}

/// Why two files cannot be compared.
#[derive(Debug, thiserror::Error)]
pub enum CompareError {
    /// A file could not be read.
    #[error(transparent)]
    Unit(UnitFileError),
    /// A file's values are not a calibration.
    #[error(transparent)]
    Invalid(estimator::unit_file::UnitFileInvalid),
    /// A calibration's values have no paper form.
    #[error(transparent)]
    Params(shared::params::ParamsError),
    /// One cannot meet the other ([`crate::calibration_guard`]).
    #[error(transparent)]
    Guard(#[from] crate::calibration_guard::GuardError),
}

/// `host compare`: reads two calibration (unit) files and compares them.
pub fn compare(a_toml: &Path, b_toml: &Path) -> Result<ComparisonTable, CompareError> {
    let a = UnitFile::load(a_toml).map_err(CompareError::Unit)?;
    let b = UnitFile::load(b_toml).map_err(CompareError::Unit)?;
    compare_units(
        &a,
        &a_toml.display().to_string(),
        &b,
        &b_toml.display().to_string(),
    )
}

/// The 1σ of a unit file in [`paper_values`] order, when it has them.
fn sigmas(u: &UnitFile) -> Option<[f64; PAPER_LEN]> {
    let s = u.uncertainty.as_ref()?;
    Some(paper_order(
        &s.zero_bias_1sigma,
        &s.scale_per_g_1sigma,
        &s.installation_angles_deg_1sigma,
        &s.lever_arms_m_1sigma,
    ))
}

/// Compares two unit files (values as [`paper_values`] gives them: angles normalised).
pub(crate) fn compare_units(
    a: &UnitFile,
    a_name: &str,
    b: &UnitFile,
    b_name: &str,
) -> Result<ComparisonTable, CompareError> {
    let (ca, cb) = comparable_calibrations(a, a_name, b, b_name)?;
    let va = paper_values(&ca).map_err(CompareError::Params)?;
    let vb = paper_values(&cb).map_err(CompareError::Params)?;
    let (sa, sb) = (sigmas(a), sigmas(b));
    let labels = paper_labels();
    let sym = ca.statics.output_unit.symbol();
    let mut rows = Vec::with_capacity(PAPER_LEN);
    for k in 0..PAPER_LEN {
        let (unit, scale) = display_unit(k, sym);
        let sig_a = sa.map(|s| s[k] * scale);
        let sig_b = sb.map(|s| s[k] * scale);
        let diff = (vb[k] - va[k]) * scale;
        rows.push(ComparisonRow {
            label: labels[k].clone(),
            unit,
            a: va[k] * scale,
            b: vb[k] * scale,
            sigma_a: sig_a,
            sigma_b: sig_b,
            diff,
            diff_sigma: diff_in_sigma(diff, sig_a, sig_b),
            undetermined: lever_undetermined(a, b, k),
        });
    }
    let mut notes = comparison_notes(sa.is_some(), sb.is_some(), &ca, &cb, &rows);
    rows.extend(section_rows(a, b, sym, &mut notes));
    Ok(ComparisonTable {
        a_name: a_name.to_string(),
        b_name: b_name.to_string(),
        rows,
        notes,
    })
}

/// The calibrations of A and B, when the guard lets them meet: usable scales, the same unit,
/// output unit and body frame.
fn comparable_calibrations(
    a: &UnitFile,
    a_name: &str,
    b: &UnitFile,
    b_name: &str,
) -> Result<(Calibration, Calibration), CompareError> {
    let ca = a.to_calibration().map_err(CompareError::Invalid)?;
    let cb = b.to_calibration().map_err(CompareError::Invalid)?;
    let (na, nb) = (format!("A ({a_name})"), format!("B ({b_name})"));
    // The guard both ways: each file's own scales, and what the two must share.
    for (x, nx, cx, y, ny, cy) in [(a, &na, &ca, b, &nb, &cb), (b, &nb, &cb, a, &na, &ca)] {
        let mine = Mine {
            name: nx,
            cal: cx,
            unit_id: x.unit_id().ok().flatten(),
        };
        let other = Other {
            name: ny,
            unit_id: y.unit_id().ok().flatten().map(|id| id.to_string()),
            output_unit: Some(cy.statics.output_unit),
            frame: Some(Frame::of_calibration(cy)),
            temperatures: Temperatures::None,
        };
        meet(Meeting::Compare, &mine, &other)?;
    }
    Ok((ca, cb))
}

/// The display unit of parameter `k` in [`paper_values`] order (`sym`: the output unit's symbol)
/// and the factor from the stored value to it (lever arms: m to mm).
fn display_unit(k: usize, sym: &str) -> (String, f64) {
    match k {
        0..=2 => (sym.to_string(), 1.0),
        3..=5 => (format!("{sym}/g"), 1.0),
        6..=14 => ("°".to_string(), 1.0),
        _ => ("mm".to_string(), 1e3),
    }
}

/// The rows of the gyro and temperature values both files have (by name), with a note for a section
/// only one of them has and for temperature models about different reference temperatures (their
/// coefficients are then not comparable and are marked n.d.).
fn section_rows(
    a: &UnitFile,
    b: &UnitFile,
    sym: &str,
    notes: &mut Vec<Note>,
) -> Vec<ComparisonRow> {
    for (what, in_a, in_b) in [
        ("[gyro]", a.gyro.is_some(), b.gyro.is_some()),
        (
            "[temperature]",
            a.temperature.is_some(),
            b.temperature.is_some(),
        ),
    ] {
        if in_a != in_b {
            notes.push(Note::SectionOfOne {
                section: what,
                in_a,
            });
        }
    }
    let refs_differ = match (&a.temperature, &b.temperature) {
        (Some(x), Some(y)) if x.reference_c != y.reference_c => {
            notes.push(Note::ReferenceTemperatures {
                a: x.reference_c,
                b: y.reference_c,
            });
            true
        }
        _ => false,
    };
    let vb = section_values(b);
    let mut rows = Vec::new();
    for x in section_values(a) {
        let Some(y) = vb.iter().find(|y| y.name == x.name) else {
            continue;
        };
        let (unit, scale) = section_display_unit(&x.name, &x.unit, sym);
        let sig_a = x.sigma.map(|s| s * scale);
        let sig_b = y.sigma.map(|s| s * scale);
        let diff = (y.value - x.value) * scale;
        rows.push(ComparisonRow {
            label: x.name.clone(),
            unit,
            a: x.value * scale,
            b: y.value * scale,
            sigma_a: sig_a,
            sigma_b: sig_b,
            diff,
            diff_sigma: diff_in_sigma(diff, sig_a, sig_b),
            undetermined: x.undetermined
                || y.undetermined
                || (refs_differ && x.name.starts_with("temp_")),
        });
    }
    if rows
        .iter()
        .any(|r| r.undetermined && r.label.starts_with("gyro_"))
    {
        notes.push(Note::GyroUndetermined);
    }
    rows
}

/// The display unit of a gyro or temperature value (`unit`: as stored, e.g. `V/degC^2`) and the
/// factor from the stored value to it: the gyro bias in °/s, temperature coefficients in µ(output
/// unit), ppm and m°/s per °C^k, so that the table's fixed decimals show them.
fn section_display_unit(name: &str, unit: &str, sym: &str) -> (String, f64) {
    let per_c = unit.split_once("/degC").map_or(String::new(), |(_, k)| {
        format!("/°C{}", k.replace("^2", "²").replace("^3", "³"))
    });
    let deg_s = 180.0 / std::f64::consts::PI;
    if name.starts_with("gyro_bias_") {
        ("°/s".into(), deg_s)
    } else if name.starts_with("temp_gyro_bias_") {
        (format!("m°/s{per_c}"), 1e3 * deg_s)
    } else if name.starts_with("temp_scale_") {
        (format!("ppm{per_c}"), 1e6)
    } else if name.starts_with("temp_bias_") {
        (format!("µ{sym}{per_c}"), 1e6)
    } else {
        (unit.to_string(), 1.0)
    }
}

/// `diff` in units of the combined 1σ of `sig_a` and `sig_b` (a missing σ counts as 0); `None` when
/// neither has one or the combination is not a usable scale.
fn diff_in_sigma(diff: f64, sig_a: Option<f64>, sig_b: Option<f64>) -> Option<f64> {
    let combined = match (sig_a, sig_b) {
        (None, None) => None,
        (x, y) => Some((x.unwrap_or(0.0).powi(2) + y.unwrap_or(0.0).powi(2)).sqrt()),
    };
    match combined {
        Some(c) if c.is_finite() && c > 0.0 => Some(diff / c),
        Some(c) if c == 0.0 && diff == 0.0 => Some(0.0),
        _ => None,
    }
}

/// Parameter `k` is a lever-arm component that A or B reports as not observable (docs/model.md
/// §4.4); a file without an `[uncertainty]` table counts as determining every component.
fn lever_undetermined(a: &UnitFile, b: &UnitFile, k: usize) -> bool {
    let obs = |u: &UnitFile, i: usize, j: usize| {
        u.uncertainty
            .as_ref()
            .is_none_or(|s| s.lever_arms_observable[i][j])
    };
    k >= 15 && {
        let (i, j) = ((k - 15) / 3, (k - 15) % 3);
        !obs(a, i, j) || !obs(b, i, j)
    }
}

/// The table's notes: which files have σ, different reference points or gravity, and what n.d.
/// means when a row has it.
fn comparison_notes(
    a_has_sigma: bool,
    b_has_sigma: bool,
    ca: &Calibration,
    cb: &Calibration,
    rows: &[ComparisonRow],
) -> Vec<Note> {
    let mut notes = Vec::new();
    match (a_has_sigma, b_has_sigma) {
        (false, false) => notes.push(Note::NoSigma),
        (true, false) | (false, true) => notes.push(Note::SigmaOfOne { in_a: a_has_sigma }),
        _ => {}
    }
    if ca.reference != cb.reference {
        notes.push(Note::ReferencePoints {
            a: ca.reference,
            b: cb.reference,
        });
    }
    if (ca.gravity_m_s2 - cb.gravity_m_s2).abs() > 1e-9 {
        notes.push(Note::Gravity {
            a: ca.gravity_m_s2,
            b: cb.gravity_m_s2,
        });
    }
    if rows.iter().any(|r| r.undetermined) {
        notes.push(Note::LeverArmUndetermined);
    }
    notes
}

#[cfg(test)]
mod tests {
    use super::*;
    use estimator::estimate::Uncertainty;

    fn with_sigma() -> UnitFile {
        let mut u = UnitFile::paper_unit();
        u.uncertainty = Some(Uncertainty {
            zero_bias_1sigma: [1e-4; 3],
            scale_per_g_1sigma: [2e-5; 3],
            installation_angles_deg_1sigma: [[1e-3; 3]; 3],
            lever_arms_m_1sigma: [[5e-6; 3]; 3],
            lever_arms_observable: [[true; 3]; 3],
        });
        u
    }

    #[test]
    fn identical_files_differ_by_zero_sigma() {
        let u = with_sigma();
        let t = compare_units(&u, "a", &u, "b").unwrap();
        assert_eq!(t.rows.len(), 24);
        assert!(t.rows.iter().all(|r| r.diff_sigma == Some(0.0)), "{t:?}");
        assert!(t.render().contains("+0.0σ"));
    }

    #[test]
    fn a_bias_shifted_by_three_sigma_shows_three_sigma() {
        let a = with_sigma();
        let mut b = a.clone();
        // Combined σ = √2·1e-4 V: shift by 3 of those.
        let shift = 3.0 * (2.0f64).sqrt() * 1e-4;
        b.statics.zero_bias_v.as_mut().unwrap()[1] += shift;
        let t = compare_units(&a, "a", &b, "b").unwrap();
        let row = t.rows.iter().find(|r| r.label == "bias y").unwrap();
        assert!((row.diff_sigma.unwrap() - 3.0).abs() < 1e-9, "{row:?}");
        assert_eq!(t.worst().unwrap().label, "bias y");
        assert!(t.render().contains("+3.0σ"), "{}", t.render());
        // The other parameters did not move.
        assert!(t
            .rows
            .iter()
            .filter(|r| r.label != "bias y")
            .all(|r| r.diff_sigma == Some(0.0)));
    }

    #[test]
    fn without_uncertainty_says_no_sigma() {
        let a = UnitFile::paper_unit();
        let t = compare_units(&a, "a", &a, "b").unwrap();
        assert!(t.rows.iter().all(|r| r.diff_sigma.is_none()));
        assert!(t.render().contains("no σ"));
        assert!(t.notes[0].to_string().contains("neither file"));
    }

    /// A with a gyro and a temperature model, each value with a 1σ (hand-set, so that a shift of a
    /// known number of combined σ is known exactly).
    fn with_sections() -> UnitFile {
        let mut u = with_sigma();
        u.gyro = Some(estimator::unit_file::GyroSection {
            bias_rad_s: [0.01, -0.02, 0.015],
            matrix: [[1.0, 0.0, 0.0], [0.0, 1.0, 0.0], [0.0, 0.0, 1.0]],
            bias_rad_s_1sigma: Some([1e-5; 3]),
            matrix_1sigma: Some([[1e-5, 2e-3, 1e-4], [1e-4, 1e-5, 1e-4], [1e-4, 1e-4, 1e-5]]),
        });
        let mut t = estimator::unit_file::TemperatureSection::from_model(
            &shared::sensor_models::TemperatureModel {
                reference_c: 25.0,
                valid_range_c: [-20.0, 60.0],
                zero_bias_out_per_c: [[1e-4, 4e-7, 0.0]; 3],
                scale_rel_per_c: [[1.5e-4, 0.0, 0.0]; 3],
                gyro_bias_rad_s_per_c: None,
            },
        );
        t.zero_bias_degree = Some([2; 3]);
        t.scale_degree = Some([1; 3]);
        t.zero_bias_out_per_c_1sigma = Some([[6e-8, 2e-9, 0.0]; 3]);
        t.scale_rel_per_c_1sigma = Some([[2.5e-7, 0.0, 0.0]; 3]);
        u.temperature = Some(t);
        u
    }

    #[test]
    fn gyro_and_temperature_differences_are_in_combined_sigma() {
        let a = with_sections();
        let t = compare_units(&a, "a", &a, "b").unwrap();
        // 24 + G and b + 9 zero-bias and 9 scale coefficients (no gyro bias polynomial).
        assert_eq!(t.rows.len(), 24 + 12 + 18);
        let mut b = a.clone();
        // G yy by 4 combined σ (√2·1e-5), the y zero bias's ΔT² coefficient by −3.
        b.gyro.as_mut().unwrap().matrix[1][1] += 4.0 * 2f64.sqrt() * 1e-5;
        b.temperature.as_mut().unwrap().zero_bias_out_per_c[1][1] -= 3.0 * 2f64.sqrt() * 2e-9;
        let t = compare_units(&a, "a", &b, "b").unwrap();
        let row = |n: &str| t.rows.iter().find(|r| r.label == n).unwrap();
        assert!((row("gyro_g_yy").diff_sigma.unwrap() - 4.0).abs() < 1e-6);
        assert!((row("temp_bias_y_c2").diff_sigma.unwrap() + 3.0).abs() < 1e-6);
        assert_eq!(t.worst().unwrap().label, "gyro_g_yy");
        // The table shows them in display units: µV/°C², the bias in °/s.
        assert_eq!(row("temp_bias_y_c2").unit, "µV/°C²");
        assert!((row("gyro_bias_x").a - 0.01f64.to_degrees()).abs() < 1e-12);
        assert!(t.render().contains("gyro_g_yy"), "{}", t.render());
        // G xy's 1σ of 2e-3 is not determined: n.d., never the worst however far it moves.
        b.gyro.as_mut().unwrap().matrix[0][1] += 1.0;
        let t = compare_units(&a, "a", &b, "b").unwrap();
        assert!(
            t.rows
                .iter()
                .find(|r| r.label == "gyro_g_xy")
                .unwrap()
                .undetermined
        );
        assert_eq!(t.worst().unwrap().label, "gyro_g_yy");
        // Models about different reference temperatures: coefficients not compared, and said so.
        b.temperature.as_mut().unwrap().reference_c = 30.0;
        let t = compare_units(&a, "a", &b, "b").unwrap();
        assert!(t
            .rows
            .iter()
            .filter(|r| r.label.starts_with("temp_"))
            .all(|r| r.undetermined));
        assert!(t
            .notes
            .iter()
            .any(|n| n.to_string().contains("reference temperatures")));
        // A section only one file has is named in a note.
        let t = compare_units(&a, "a", &with_sigma(), "b").unwrap();
        assert_eq!(t.rows.len(), 24);
        assert!(
            t.notes
                .iter()
                .any(|n| n.to_string().contains("only A has a [gyro]")),
            "{:?}",
            t.notes
        );
    }
}
