//! A single-package MEMS unit (counts, 2048 LSB/g, one lever arm for its three accelerometers)
//! calibrated live against the simulated device with its built-in plan: the device's virtual part
//! saturates at its own ±16 g, not at the analog part's 0–5 V (which would clamp every count), and
//! the package's lever arm comes back within 3σ of the unit file's r = (12, −7, 25) mm.

use std::process::Command;

#[test]
fn a_single_package_unit_calibrates_live_on_the_simulated_device() {
    let dir = tempfile::tempdir().unwrap();
    let out_dir = dir.path().join("mems");
    let unit = concat!(env!("CARGO_MANIFEST_DIR"), "/units/single-package.toml");
    let o = Command::new(env!("CARGO_BIN_EXE_host"))
        .args(["calibrate", "--port", "sim", "--sim-unit", unit])
        .args(["--plan", "single-package", "--out-dir"])
        .arg(&out_dir)
        .output()
        .unwrap();
    let stdout = String::from_utf8_lossy(&o.stdout);
    let stderr = String::from_utf8_lossy(&o.stderr);
    assert!(o.status.success(), "{stdout}\n{stderr}");
    assert!(stdout.contains("in-package size effect"), "{stdout}");
    let text = std::fs::read_to_string(out_dir.join("calibration.toml")).unwrap();
    let doc: toml::Table = text.parse().unwrap();
    let rows = |table: &str, key: &str| -> Vec<Vec<f64>> {
        doc[table][key]
            .as_array()
            .unwrap()
            .iter()
            .map(|r| {
                r.as_array()
                    .unwrap()
                    .iter()
                    .map(|v| v.as_float().unwrap())
                    .collect()
            })
            .collect()
    };
    let r = rows("dynamic", "lever_arms_m");
    let sigma = rows("uncertainty", "lever_arms_m_1sigma");
    assert_eq!(doc["dynamic"]["package"].as_str(), Some("single"));
    let truth = [0.012, -0.007, 0.025];
    for i in 0..3 {
        assert_eq!(r[i], r[0], "one point for the three accelerometers");
        for j in 0..3 {
            let z = (r[i][j] - truth[j]) / sigma[i][j];
            assert!(sigma[i][j] < 2e-5 && z.abs() < 3.0, "r{i}{j}: z = {z}");
        }
    }
}
