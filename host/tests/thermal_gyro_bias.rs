//! A thermal session without spins keeps the gyro's bias: a unit with a 0.57 °/s gyro bias (and a
//! drift of 2e-5 rad/s per °C on x) recorded on the `thermal-soak` plan. The calibration's `[gyro]`
//! bias is the simulated one within 3σ, `apply` takes it out of the rate at rest, and the PX4 and
//! ArduPilot files carry it (`CAL_GYRO0_*OFF`, `INS_GYROFFS_*`), against the simulator's truth.

mod common;

use common::host;
use std::path::Path;

/// The simulated gyro bias at the thermal model's 25 °C reference, °/s.
const BIAS_DEG_S: [f64; 3] = [0.57, -0.3, 0.2];

/// The unit of `host/units/thermal-mems.toml` with a perfect-scale gyro of bias [`BIAS_DEG_S`].
fn unit_file(dir: &Path) -> std::path::PathBuf {
    let root = Path::new(env!("CARGO_MANIFEST_DIR"));
    let b = BIAS_DEG_S.map(f64::to_radians);
    let gyro = format!(
        "[gyro]\nbias_rad_s = [{:?}, {:?}, {:?}]\nmatrix = [[1.0, 0.0, 0.0], [0.0, 1.0, 0.0], [0.0, 0.0, 1.0]]\n",
        b[0], b[1], b[2]
    );
    let unit = std::fs::read_to_string(root.join("units/thermal-mems.toml"))
        .unwrap()
        .replace("[temperature]", &format!("{gyro}\n[temperature]"))
        .replace(
            "[thermal]",
            "gyro_bias_rad_s_per_c = [[2e-5, 0.0, 0.0], [0.0, 0.0, 0.0], [0.0, 0.0, 0.0]]\n\n[thermal]",
        );
    let path = dir.join("unit.toml");
    std::fs::write(&path, unit).unwrap();
    path
}

/// `thermal-soak` with 2 s a segment: six rests at each of five temperatures, no spins.
fn soak_plan(dir: &Path) -> std::path::PathBuf {
    let root = Path::new(env!("CARGO_MANIFEST_DIR"));
    let plan = std::fs::read_to_string(root.join("../recording/plans/thermal-soak.toml"))
        .unwrap()
        .replace("duration_s = 20", "duration_s = 2");
    assert!(!plan.contains("rate_deg_s"), "the soak plan has no spins");
    let path = dir.join("plan.toml");
    std::fs::write(&path, plan).unwrap();
    path
}

fn run(args: &[&str]) -> String {
    let (ok, stdout, stderr) = host(args);
    assert!(ok, "host {args:?}\n{stdout}\n{stderr}");
    format!("{stdout}\n{stderr}")
}

/// The numbers on the parameter file's line that starts with `key`.
fn numbers_after(text: &str, key: &str) -> Vec<f64> {
    let line = text
        .lines()
        .find(|l| l.trim_start().starts_with(key))
        .unwrap_or_else(|| panic!("no {key} in\n{text}"));
    line[key.len()..]
        .split(|c: char| !(c.is_ascii_digit() || "+-.eE".contains(c)))
        .filter_map(|t| t.parse().ok())
        .collect()
}

#[test]
fn a_thermal_session_without_spins_keeps_the_gyro_bias() {
    let dir = tempfile::tempdir().unwrap();
    let unit = unit_file(dir.path());
    let plan = soak_plan(dir.path());
    let session = dir.path().join("session");
    let cal_dir = dir.path().join("cal");
    let p = |p: &Path| p.to_str().unwrap().to_string();
    run(&[
        "-q",
        "simulate",
        "--out",
        &p(&session),
        "--unit",
        &p(&unit),
        "--plan",
        &p(&plan),
        "--seed",
        "3",
    ]);
    let printed = run(&[
        "calibrate",
        "-v",
        "--input",
        &p(&session),
        "--out-dir",
        &p(&cal_dir),
    ]);
    assert!(
        printed.contains("bias at the reference temperature from the rests")
            && printed.contains("not determined"),
        "{printed}"
    );
    let toml = std::fs::read_to_string(cal_dir.join("calibration.toml")).unwrap();
    let file: toml::Value = toml::from_str(&toml).unwrap();
    let gyro = file.get("gyro").expect("a [gyro] section");
    let three = |key: &str| -> Vec<f64> {
        gyro[key]
            .as_array()
            .unwrap_or_else(|| panic!("no {key} in\n{toml}"))
            .iter()
            .map(|v| v.as_float().unwrap())
            .collect()
    };
    let (bias, sigma) = (three("bias_rad_s"), three("bias_rad_s_1sigma"));
    assert!(toml.contains("reference_c = 25.0"), "{toml}");
    for i in 0..3 {
        let truth = BIAS_DEG_S[i].to_radians();
        assert!(
            sigma[i] > 0.0 && (bias[i] - truth).abs() < 3.0 * sigma[i],
            "axis {i}: {} ± {} vs {truth} rad/s",
            bias[i],
            sigma[i]
        );
    }

    // `apply`: the rate at rest is the bias's residual and the drift's, not the 0.57 °/s.
    let applied = dir.path().join("applied.csv");
    run(&[
        "apply",
        "--input",
        &p(&session),
        "--calibration",
        &p(&cal_dir.join("calibration.toml")),
        "--out",
        &p(&applied),
    ]);
    let text = std::fs::read_to_string(&applied).unwrap();
    let mut header = text.lines().next().unwrap().split(',');
    let wx = header.position(|c| c == "w_x_rad_s").unwrap();
    let mut rates: Vec<f64> = text
        .lines()
        .skip(1)
        .map(|l| {
            l.split(',')
                .nth(wx)
                .unwrap()
                .parse::<f64>()
                .unwrap()
                .to_degrees()
        })
        .collect();
    rates.sort_by(f64::total_cmp);
    let median = rates[rates.len() / 2];
    assert!(median.abs() < 0.02, "median w_x at rest {median} °/s");

    // The autopilots' files: the offsets are the calibrated bias (PX4 and ArduPilot subtract them).
    // The accelerometers' driver scale is irrelevant to the gyro; ArduPilot's accelerometer ranges
    // are for a real driver's, hence --allow-out-of-range.
    let cal = p(&cal_dir.join("calibration.toml"));
    let px4 = run(&[
        "export",
        "--calibration",
        &cal,
        "--format",
        "px4",
        "--device-id",
        "1310988",
        "--gyro-device-id",
        "2359306",
        "--driver-scale",
        "24.8",
    ]);
    let ardupilot = run(&[
        "export",
        "--calibration",
        &cal,
        "--format",
        "ardupilot",
        "--device-id",
        "1310988",
        "--gyro-device-id",
        "2359306",
        "--driver-scale",
        "24.8",
        "--allow-out-of-range",
    ]);
    for (i, axis) in ["X", "Y", "Z"].iter().enumerate() {
        let truth = BIAS_DEG_S[i].to_radians();
        for (text, name) in [
            (&px4, format!("1\t1\tCAL_GYRO0_{axis}OFF")),
            (&ardupilot, format!("INS_GYROFFS_{axis},")),
        ] {
            let v = *numbers_after(text, &name).first().unwrap_or(&f64::NAN);
            assert!(
                (v - bias[i]).abs() < 1e-6 && (v - truth).abs() < 3.0 * sigma[i],
                "{name}: {v} vs {} (truth {truth})\n{text}",
                bias[i]
            );
        }
    }
}
