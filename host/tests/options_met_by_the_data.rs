//! An option either acts or is refused, and an explicit choice the data already satisfy is
//! honoured: `apply --lever off` with a calibration without lever arms gives the static
//! compensation every mode gives there (a note says so); `apply --temp-column` with a calibration
//! without a temperature model and `calibrate --gyro-bias-walk` on a session without a gyro model
//! would change nothing, and are usage errors naming why. And `navigation-check` simulates a thermal
//! unit with its temperatures.

mod common;
use std::process::Command;

/// Runs `host ARGS`: the exit status, stdout, stderr.
fn host(args: &[&str]) -> (i32, String, String) {
    let out = Command::new(env!("CARGO_BIN_EXE_host"))
        .args(args)
        .output()
        .unwrap();
    (
        out.status.code().unwrap_or(-1),
        String::from_utf8_lossy(&out.stdout).into_owned(),
        String::from_utf8_lossy(&out.stderr).into_owned(),
    )
}

fn ok(args: &[&str]) -> String {
    let (code, stdout, stderr) = host(args);
    assert_eq!(code, 0, "{args:?}: {stderr}");
    stdout
}

/// A static plan's calibration has no lever arms: `--lever off` (or any mode) is what it does
/// anyway, so it is honoured, with a note, and the output is the output without `--lever`.
#[test]
fn a_lever_mode_the_calibration_already_satisfies_is_honoured() {
    let dir = tempfile::tempdir().unwrap();
    let session = dir.path().join("thermal");
    let session = session.to_str().unwrap();
    ok(&["-q", "simulate", "--plan", "thermal-soak", "--out", session]);
    ok(&["-q", "calibrate", "--input", session]);
    let cal = format!("{session}/calibration.toml");
    let plain = ok(&["apply", "--calibration", &cal, "--input", session]);
    for mode in ["off", "rate", "full"] {
        let (code, stdout, stderr) = host(&[
            "apply",
            "--calibration",
            &cal,
            "--input",
            session,
            "--lever",
            mode,
        ]);
        assert_eq!(code, 0, "--lever {mode}: {stderr}");
        assert!(
            stderr.contains("all zero") && stderr.contains(&format!("--lever {mode}")),
            "{stderr}"
        );
        assert!(stdout == plain, "--lever {mode}: another output");
    }
}

/// `--temp-column` feeds a temperature model: with a calibration that has none it would change
/// nothing, and is refused before the log is read.
#[test]
fn a_temperature_column_without_a_temperature_model_is_refused() {
    let dir = tempfile::tempdir().unwrap();
    let session = dir.path().join("s");
    let session = session.to_str().unwrap();
    let csv = dir.path().join("hand.csv");
    let csv = csv.to_str().unwrap();
    ok(&["-q", "simulate", "--plan", "short", "--out", session]);
    ok(&["-q", "calibrate", "--input", session]);
    ok(&["-q", "simulate-hand", "--out", csv]);
    let cal = format!("{session}/calibration.toml");
    let mut args = vec!["apply", "--calibration", &cal, "--input", csv];
    args.extend(common::HAND_CSV_READING);
    args.extend(["--temp-column", "temp_c"]);
    let (code, stdout, stderr) = host(&args);
    assert_eq!(code, 2, "{stderr}");
    assert!(stdout.is_empty());
    assert!(
        stderr.contains("--temp-column does not apply") && stderr.contains("no temperature model"),
        "{stderr}"
    );
}

/// The gyro's bias walk weighs a gyro model's mean rates: a thermal soak (rests only) and a
/// hand-held session (its gyro from the hand turns) have none, so it is refused, naming why.
#[test]
fn a_gyro_walk_without_a_gyro_model_is_refused() {
    let dir = tempfile::tempdir().unwrap();
    let thermal = dir.path().join("thermal");
    let thermal = thermal.to_str().unwrap();
    ok(&["-q", "simulate", "--plan", "thermal-soak", "--out", thermal]);
    let csv = dir.path().join("hand.csv");
    let csv = csv.to_str().unwrap();
    let hand = dir.path().join("hand");
    let hand = hand.to_str().unwrap();
    ok(&["-q", "simulate-hand", "--out", csv]);
    let mut seg = vec!["-q"];
    seg.extend(common::hand_segment_args(csv, hand));
    ok(&seg);
    for (k, session) in [thermal, hand].into_iter().enumerate() {
        let out = format!("{}/walk{k}", dir.path().display());
        let (code, _, stderr) = host(&[
            "calibrate",
            "--input",
            session,
            "--out-dir",
            &out,
            "--gyro-bias-walk",
            "0.001",
        ]);
        assert_eq!(code, 2, "{session}: {stderr}");
        assert!(
            stderr.contains("gyro bias random walk does not apply"),
            "{session}: {stderr}"
        );
        assert!(!std::path::Path::new(&out).join("calibration.toml").exists());
        // Without it the session calibrates.
        ok(&["-q", "calibrate", "--input", session, "--out-dir", &out]);
    }
}

/// A gyro walk that comes with the unit's noise figures (`--bias-walk-from`, whose accelerometer
/// walk is used) is not asked for by itself: on a session without a gyro model it is left out with a
/// warning, and the calibration is made.
#[test]
fn a_units_gyro_walk_is_left_out_where_there_is_no_gyro_model() {
    let dir = tempfile::tempdir().unwrap();
    let thermal = dir.path().join("thermal");
    let thermal = thermal.to_str().unwrap();
    ok(&[
        "-q",
        "simulate",
        "--plan",
        "thermal-soak",
        "--out",
        thermal,
        "--drift-mg-sqrt-s",
        "0.003",
        "--gyro-drift-deg-s-sqrt-s",
        "0.0004",
    ]);
    let truth = format!("{thermal}/truth.toml");
    let (code, stdout, stderr) = host(&[
        "calibrate",
        "--input",
        thermal,
        "--bias-walk-from",
        &truth,
        "--json",
    ]);
    assert_eq!(code, 0, "{stderr}");
    let doc: serde_json::Value = serde_json::from_str(&stdout).unwrap();
    let warnings = doc["warnings"].to_string();
    assert!(
        warnings.contains("gyro bias random walk is left out") && warnings.contains("no spins"),
        "{warnings}"
    );
    assert!(doc["gyro_bias_walk_deg_s_sqrt_s"].is_null(), "{doc}");
}

/// The thermal unit on the thermal-soak plan: the simulation carries the unit's temperatures, so
/// the check's calibration has its temperature model and fits within the noise, and the static
/// calibration's navigation error is the calibration's, not a misfit's hundreds of metres.
#[test]
fn navigation_check_simulates_a_thermal_unit_with_its_temperatures() {
    let unit = concat!(env!("CARGO_MANIFEST_DIR"), "/units/thermal-mems.toml");
    let (code, stdout, stderr) =
        host(&["navigation-check", "--unit", unit, "--plan", "thermal-soak"]);
    assert_eq!(code, 0, "{stderr}");
    println!("{stdout}");
    let line = stdout
        .lines()
        .find(|l| l.contains("after static calibration"))
        .unwrap_or_else(|| panic!("{stdout}"));
    let after = line.split("after static calibration ").nth(1).unwrap();
    let metres: f64 = after.split_whitespace().next().unwrap().parse().unwrap();
    // Without its temperatures the simulation gave a misfit (χ²/dof 1.6·10⁶) and 434 m here.
    assert!(metres < 0.3, "{line}");
}
