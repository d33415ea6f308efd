//! A single-package MEMS unit (counts, 2048 LSB/g, one lever arm for its three accelerometers)
//! calibrated live against the simulated device with its built-in plan: the device's virtual part
//! saturates at its own ±16 g, not at the analog part's 0–5 V (which would clamp every count), and
//! the package's lever arm comes back within 3σ of the unit file's r = (12, −7, 25) mm.

use std::path::Path;
use std::process::Command;

/// The unit file of the single-package MEMS unit.
const UNIT: &str = concat!(env!("CARGO_MANIFEST_DIR"), "/units/single-package.toml");

/// `host calibrate --port PORT --sim-unit UNIT --plan PLAN --out-dir OUT`, which must succeed: its
/// stdout and stderr.
fn calibrate_live(port: &str, plan: &str, out_dir: &Path) -> (String, String) {
    let o = Command::new(env!("CARGO_BIN_EXE_host"))
        .args(["calibrate", "-v", "--port", port, "--sim-unit", UNIT])
        .args(["--plan", plan, "--out-dir"])
        .arg(out_dir)
        .output()
        .unwrap();
    let stdout = String::from_utf8_lossy(&o.stdout).to_string();
    let stderr = String::from_utf8_lossy(&o.stderr).to_string();
    assert!(o.status.success(), "{stdout}\n{stderr}");
    (stdout, stderr)
}

#[test]
fn a_single_package_unit_calibrates_live_on_the_simulated_device() {
    let dir = tempfile::tempdir().unwrap();
    let out_dir = dir.path().join("mems");
    let (stdout, _) = calibrate_live("sim", "single-package", &out_dir);
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

/// A board whose outputs are counts (the F405's IMU) held in the hand with the `hand` plan, whose
/// unit is volts: the host records and calibrates in the device's counts, says it replaced the
/// plan's unit, and the calibration's biases come back in counts (the unit file's, within 3σ).
#[test]
fn a_device_in_counts_is_recorded_in_counts_whatever_the_plan_says() {
    let dir = tempfile::tempdir().unwrap();
    let out_dir = dir.path().join("hand");
    let (stdout, stderr) = calibrate_live("sim-hand", "hand", &out_dir);
    let said = format!("{stdout}{stderr}");
    assert!(
        said.contains("the device's outputs are in LSB: the plan's V is replaced"),
        "{said}"
    );
    let plan: toml::Table = std::fs::read_to_string(out_dir.join("recording/plan.toml"))
        .unwrap()
        .parse()
        .unwrap();
    assert_eq!(plan["output_unit"].as_str(), Some("LSB"));
    let cal: toml::Table = std::fs::read_to_string(out_dir.join("calibration.toml"))
        .unwrap()
        .parse()
        .unwrap();
    let truth: toml::Table = std::fs::read_to_string(UNIT).unwrap().parse().unwrap();
    assert_eq!(cal["output_unit"].as_str(), Some("LSB"), "{cal}");
    let floats = |t: &toml::Table, table: &str, key: &str| -> Vec<f64> {
        t[table][key]
            .as_array()
            .unwrap_or_else(|| panic!("[{table}] {key}"))
            .iter()
            .map(|v| v.as_float().unwrap())
            .collect()
    };
    let bias = floats(&cal, "static", "zero_bias_lsb");
    let sigma = floats(&cal, "uncertainty", "zero_bias_1sigma");
    let true_bias = floats(&truth, "static", "zero_bias_lsb");
    for i in 0..3 {
        let z = (bias[i] - true_bias[i]) / sigma[i];
        assert!(
            z.abs() < 3.0,
            "bias {i}: {} against {} (z = {z})",
            bias[i],
            true_bias[i]
        );
    }
}
