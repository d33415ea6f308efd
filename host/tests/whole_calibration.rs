//! The machine-readable results carry the whole calibration, and `compare` judges every section: a
//! simulated unit with a known gyro and temperature model, calibrated, exported and compared.

mod common;
use common::{host, thermal_gyro_session};
use estimator::unit_file::UnitFile;
use outputs::summary::section_values;
use serde_json::Value;
use std::path::Path;

/// A result's value and 1σ by parameter name.
type Lookup<'a> = dyn Fn(&str) -> Option<(f64, Option<f64>)> + 'a;

/// Every gyro and temperature value of the simulator's truth (`truth.toml` of `session`) is in
/// `found` (name → value, 1σ) and within 5σ of truth; a coefficient with no 1σ (above the degree
/// the data chose) is the model's 0 and the truth's is below what the data could show. Returns how
/// many values were checked.
fn check_against_truth(session: &Path, found: &Lookup) -> usize {
    let truth = UnitFile::load(&session.join("truth.toml")).unwrap();
    let values = section_values(&truth);
    assert!(
        values.iter().any(|v| v.name.starts_with("gyro_g_"))
            && values.iter().any(|v| v.name.starts_with("temp_gyro_bias_")),
        "the truth has both sections"
    );
    for t in &values {
        let (v, sigma) =
            found(&t.name).unwrap_or_else(|| panic!("{} is missing from the result", t.name));
        match sigma {
            Some(s) => assert!(
                s > 0.0 && (v - t.value).abs() < 5.0 * s,
                "{}: {v} ± {s}, truth {}",
                t.name,
                t.value
            ),
            None => assert!(
                v == 0.0 && t.value.abs() < 1e-9,
                "{}: {v} without 1σ, truth {}",
                t.name,
                t.value
            ),
        }
    }
    values.len()
}

#[test]
fn calibrate_and_export_json_carry_the_gyro_and_the_temperature_model_within_sigma_of_truth() {
    let dir = tempfile::tempdir().unwrap();
    let s = thermal_gyro_session(dir.path(), "unit", 1);
    let ss = s.to_str().unwrap();
    let (ok, stdout, stderr) = host(&["calibrate", "--input", ss, "--json"]);
    assert!(ok, "{stderr}");
    let v: Value = serde_json::from_str(&stdout).unwrap();
    let params = v["parameters"].as_array().unwrap();
    let found = |name: &str| {
        let p = params.iter().find(|p| p["name"] == name)?;
        Some((p["value"].as_f64().unwrap(), p["sigma"].as_f64()))
    };
    let n = check_against_truth(&s, &found);
    assert_eq!(n, 12 + 27, "G, b and 27 temperature coefficients");
    assert_eq!(params.len(), 24 + 12 + 27);
    assert_eq!(v["temperature"]["reference_c"], 25.0);
    let range = &v["temperature"]["valid_range_c"];
    assert!(range[0].as_f64().unwrap() < -19.0 && range[1].as_f64().unwrap() > 59.0);
    assert!(v["undetermined"].as_array().unwrap().is_empty(), "{v}");
    // And the calibration file itself, table for table (the session has no unit id: the file's is
    // the all-zero one, the summary's none).
    let cal = s.join("calibration.toml");
    let file = UnitFile::load(&cal).unwrap();
    let mut carried: UnitFile = serde_json::from_value(v["calibration"].clone()).unwrap();
    assert_eq!(carried.unit_id, None);
    carried.unit_id = file.unit_id.clone();
    assert_eq!(carried, file);

    // The export of the file calibrate wrote: the same sections, value for value.
    let (ok, stdout, stderr) = host(&[
        "export",
        "--calibration",
        cal.to_str().unwrap(),
        "--format",
        "json",
    ]);
    assert!(ok, "{stderr}");
    let e: Value = serde_json::from_str(&stdout).unwrap();
    let sections: Vec<&str> = e["sections"]
        .as_array()
        .unwrap()
        .iter()
        .map(|x| x.as_str().unwrap())
        .collect();
    assert_eq!(
        sections,
        ["static", "dynamic", "uncertainty", "gyro", "temperature"]
    );
    let back: UnitFile = serde_json::from_value(e["calibration"].clone()).unwrap();
    assert_eq!(back.gyro, file.gyro);
    assert_eq!(back.temperature, file.temperature);
    let exported = section_values(&back);
    let found = |name: &str| {
        let p = exported.iter().find(|p| p.name == name)?;
        Some((p.value, p.sigma))
    };
    assert_eq!(check_against_truth(&s, &found), n);
}

#[test]
fn compare_judges_the_gyro_and_fails_a_34_percent_difference() {
    let dir = tempfile::tempdir().unwrap();
    let mut cals = Vec::new();
    for seed in [1, 2] {
        let s = thermal_gyro_session(dir.path(), &format!("seed{seed}"), seed);
        let (ok, _, e) = host(&["-q", "calibrate", "--input", s.to_str().unwrap()]);
        assert!(ok, "{e}");
        cals.push(s.join("calibration.toml").to_str().unwrap().to_string());
    }
    // Two sessions of one unit: every section within a few σ (63 values: 6σ, as for the others).
    let (ok, stdout, stderr) = host(&["compare", &cals[0], &cals[1], "--json", "--max-sigma", "6"]);
    assert!(ok, "{stderr}");
    let v: Value = serde_json::from_str(&stdout).unwrap();
    let rows = v["rows"].as_array().unwrap();
    let row = |name: &str| rows.iter().find(|r| r["name"] == name).unwrap().clone();
    for name in [
        "gyro_g_xx",
        "gyro_bias_y",
        "temp_bias_x_c1",
        "temp_scale_z_c1",
    ] {
        assert!(row(name)["diff_sigma"].as_f64().is_some(), "{name}");
    }
    assert!(
        stderr.contains("gyro_g_xx"),
        "the table shows the gyro: {stderr}"
    );

    // B's gyro scale 34 % larger: a FAIL naming the gyro, in the table and the JSON.
    let text = std::fs::read_to_string(&cals[1]).unwrap();
    let mut b = UnitFile::parse(&text).unwrap();
    for row in &mut b.gyro.as_mut().unwrap().matrix {
        for g in row.iter_mut() {
            *g *= 1.34;
        }
    }
    let planted = dir.path().join("planted.toml");
    std::fs::write(&planted, b.to_toml()).unwrap();
    let (ok, stdout, stderr) = host(&[
        "compare",
        &cals[0],
        planted.to_str().unwrap(),
        "--json",
        "--max-sigma",
        "3",
    ]);
    assert!(!ok, "{stderr}");
    assert!(stderr.contains("FAIL: gyro_g_"), "{stderr}");
    let v: Value = serde_json::from_str(&stdout).unwrap();
    assert_eq!(v["passed"], false);
    assert!(v["worst"]["name"].as_str().unwrap().starts_with("gyro_g_"));
    let xx = v["rows"]
        .as_array()
        .unwrap()
        .iter()
        .find(|r| r["name"] == "gyro_g_xx")
        .unwrap();
    assert!(xx["diff_sigma"].as_f64().unwrap() > 1000.0, "{xx}");
}
