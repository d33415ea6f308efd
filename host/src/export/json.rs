//! The calibration as one JSON document for scripts: the calibration file as it is (every table,
//! uncertainty included), the derived forms of [`super::convert`], and the fit statistics the file
//! holds. What the file does not determine is `null` and named in `undetermined`, never a zero.

use super::{convert, ExportError, ExportInput};
use serde_json::{json, Value};

/// Format version of the document.
pub const JSON_FORMAT_VERSION: u32 = 1;

/// The document.
pub fn document(input: &ExportInput<'_>) -> Result<Value, ExportError> {
    let conv = convert(&input.cal)?;
    let ser = |e: serde_json::Error| ExportError::Serialise(e.to_string());
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
    if input.unit.dynamic.is_none() {
        undetermined.push("calibration.dynamic (no lever arms in the file)".into());
    }
    // The calibration file keeps no χ²: `host calibrate --json` reports it with the fit.
    undetermined.push("fit_statistics.chi2_per_dof".into());
    Ok(json!({
        "format": "accelerometer-calibration",
        "format_version": JSON_FORMAT_VERSION,
        "calibration": serde_json::to_value(input.unit).map_err(ser)?,
        "derived": serde_json::to_value(&conv).map_err(ser)?,
        "fit_statistics": {
            "one_sigma": unc.map(serde_json::to_value).transpose().map_err(ser)?,
            "chi2_per_dof": Value::Null,
        },
        "undetermined": undetermined,
    }))
}

/// The JSON text (pretty-printed, one document).
pub fn render(input: &ExportInput<'_>) -> Result<String, ExportError> {
    let v = document(input)?;
    serde_json::to_string_pretty(&v)
        .map(|s| s + "\n")
        .map_err(|e| ExportError::Serialise(e.to_string()))
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::estimate::Uncertainty;
    use crate::export::Conversions;
    use crate::unit_file::UnitFile;

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
}
