//! The calibration as one JSON document for scripts: the calibration file as it is (every table,
//! uncertainty included: the accelerometer's, the gyro's `[gyro]` with its 1σ, the temperature
//! model's `[temperature]` with its reference, valid range, degrees and 1σ), the derived forms of
//! [`super::convert`], and the fit statistics the file holds. What the file does not determine is
//! `null` or named in `undetermined` (a gyro entry whose 1σ is above 1e-3), never a silent zero;
//! `sections` names the tables the calibration has, so a script can tell "no gyro" from "dropped".

use super::{convert, ExportError, ExportInput};
use crate::summary::gyro_entry_undetermined;
use estimator::unit_file::UnitFile;
use serde_json::{json, Value};

/// Format version of the document.
pub(crate) const JSON_FORMAT_VERSION: u32 = 1;

/// The document.
pub fn document(input: &ExportInput<'_>) -> Result<Value, ExportError> {
    let conv = convert(&input.cal)?;
    let ser = ExportError::Json;
    let mut undetermined: Vec<String> = Vec::new();
    let unc = input.unit.uncertainty.as_ref();
    match unc {
        Some(u) => {
            for i in 0..3 {
                for j in 0..3 {
                    if !u.lever_arms_observable[i][j] {
                        undetermined.push(format!("calibration.dynamic.lever_arms_m[{i}][{j}]"));
                    }
                }
            }
        }
        None => undetermined.push("fit_statistics.one_sigma".into()),
    }
    undetermined.extend(gyro_and_temperature_undetermined(input.unit));
    if input.unit.dynamic.is_none() {
        undetermined.push("calibration.dynamic (no lever arms in the file)".into());
    }
    // The calibration file keeps no χ²: `host calibrate --json` reports it with the fit.
    undetermined.push("fit_statistics.chi2_per_dof".into());
    Ok(json!({
        "format": "accelerometer-calibration",
        "format_version": JSON_FORMAT_VERSION,
        "sections": sections(input.unit),
        "calibration": serde_json::to_value(input.unit).map_err(ser)?,
        "derived": serde_json::to_value(&conv).map_err(ser)?,
        "fit_statistics": {
            "one_sigma": unc.map(serde_json::to_value).transpose().map_err(ser)?,
            "chi2_per_dof": Value::Null,
        },
        "undetermined": undetermined,
    }))
}

/// The model tables the calibration file has (`static` always; `dynamic`, `uncertainty`, `gyro`,
/// `temperature` when present).
fn sections(unit: &UnitFile) -> Vec<&'static str> {
    let present = [
        ("static", true),
        ("dynamic", unit.dynamic.is_some()),
        ("uncertainty", unit.uncertainty.is_some()),
        ("gyro", unit.gyro.is_some()),
        ("temperature", unit.temperature.is_some()),
    ];
    present.iter().filter(|p| p.1).map(|p| p.0).collect()
}

/// What the gyro and temperature sections leave undetermined: each `G` entry the plan did not
/// determine, and a section's 1σ when the file has none (a simulator's truth, a hand-written file).
fn gyro_and_temperature_undetermined(unit: &UnitFile) -> Vec<String> {
    let mut v = Vec::new();
    if let Some(g) = &unit.gyro {
        match g.matrix_1sigma {
            Some(s) => {
                for (i, row) in s.iter().enumerate() {
                    for (j, sigma) in row.iter().enumerate() {
                        if gyro_entry_undetermined(*sigma) {
                            v.push(format!("calibration.gyro.matrix[{i}][{j}]"));
                        }
                    }
                }
            }
            None => v.push("calibration.gyro.matrix_1sigma".into()),
        }
        if g.bias_rad_s_1sigma.is_none() {
            v.push("calibration.gyro.bias_rad_s_1sigma".into());
        }
    }
    if let Some(t) = &unit.temperature {
        if t.zero_bias_out_per_c_1sigma.is_none() || t.scale_rel_per_c_1sigma.is_none() {
            v.push("calibration.temperature (no 1σ in the file)".into());
        }
    }
    v
}

/// The JSON text (pretty-printed, one document).
pub fn render(input: &ExportInput<'_>) -> Result<String, ExportError> {
    let v = document(input)?;
    serde_json::to_string_pretty(&v)
        .map(|s| s + "\n")
        .map_err(ExportError::Json)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::export::Conversions;
    use estimator::estimate::Uncertainty;

    #[test]
    fn json_parses_back_to_the_same_calibration_and_marks_the_undetermined() {
        let mut unit = UnitFile::paper_unit();
        let mut observable = [[true; 3]; 3];
        observable[2][1] = false;
        unit.uncertainty = Some(Uncertainty {
            zero_bias_1sigma: [1e-5, 2e-5, 3e-5],
            scale_per_g_1sigma: [4e-5, 5e-5, 6e-5],
            installation_angles_deg_1sigma: [[1e-3; 3]; 3],
            lever_arms_m_1sigma: [[2e-4; 3]; 3],
            lever_arms_observable: observable,
        });
        let cal = unit.to_calibration().unwrap();
        let input = ExportInput::for_tests(&unit, cal);
        let text = render(&input).unwrap();
        let v: Value = serde_json::from_str(&text).unwrap();
        let back: UnitFile = serde_json::from_value(v["calibration"].clone()).unwrap();
        // The `[procedure]` table and every number survive exactly.
        assert_eq!(back, unit);
        assert_eq!(back.to_calibration().unwrap(), cal);
        let derived: Conversions = serde_json::from_value(v["derived"].clone()).unwrap();
        assert_eq!(derived, convert(&cal).unwrap());
        let sigma: Uncertainty =
            serde_json::from_value(v["fit_statistics"]["one_sigma"].clone()).unwrap();
        assert_eq!(Some(sigma), unit.uncertainty);
        assert!(v["fit_statistics"]["chi2_per_dof"].is_null());
        let und: Vec<String> = serde_json::from_value(v["undetermined"].clone()).unwrap();
        assert!(
            und.contains(&"calibration.dynamic.lever_arms_m[2][1]".to_string()),
            "{und:?}"
        );
        assert!(und.contains(&"fit_statistics.chi2_per_dof".to_string()));
    }

    #[test]
    fn the_gyro_entries_a_plan_left_undetermined_are_named() {
        let mut unit = UnitFile::paper_unit();
        let mut sigma = [[1e-5; 3]; 3];
        sigma[0][2] = 2e-3;
        unit.gyro = Some(estimator::unit_file::GyroSection {
            bias_rad_s: [0.01, 0.0, 0.0],
            matrix: [[1.0, 0.0, 0.0], [0.0, 1.0, 0.0], [0.0, 0.0, 1.0]],
            bias_rad_s_1sigma: Some([1e-5; 3]),
            matrix_1sigma: Some(sigma),
        });
        let cal = unit.to_calibration().unwrap();
        let v = document(&ExportInput::for_tests(&unit, cal)).unwrap();
        let und: Vec<String> = serde_json::from_value(v["undetermined"].clone()).unwrap();
        let gyro: Vec<&String> = und.iter().filter(|u| u.contains("gyro")).collect();
        assert_eq!(gyro, ["calibration.gyro.matrix[0][2]"]);
        assert_eq!(
            v["sections"],
            serde_json::json!(["static", "dynamic", "gyro"])
        );
        assert_eq!(v["calibration"]["gyro"]["matrix_1sigma"][0][2], 2e-3);
        // A gyro without 1σ (a simulator's truth): its 1σ named as missing, not taken as exact.
        unit.gyro.as_mut().unwrap().matrix_1sigma = None;
        let v = document(&ExportInput::for_tests(&unit, cal)).unwrap();
        let und: Vec<String> = serde_json::from_value(v["undetermined"].clone()).unwrap();
        assert!(
            und.contains(&"calibration.gyro.matrix_1sigma".to_string()),
            "{und:?}"
        );
    }
}
