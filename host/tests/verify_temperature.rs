//! The live procedure verifies at the temperature it ran at and, asked, at a second one: against the
//! simulated device with a temperature-dependent unit and the soak plan, every verification line
//! names the device's temperature reading, and `--verify-temp-c 45` verifies again at 45 °C within
//! the tolerance (the unit's bias moves about 0.3 mg/°C: without its temperature model the
//! compensated output would be mg off there).

use std::process::Command;

#[test]
fn verifies_at_the_recorded_and_at_a_second_temperature() {
    let dir = tempfile::tempdir().unwrap();
    let out_dir = dir.path().join("soak-sim");
    let unit = concat!(env!("CARGO_MANIFEST_DIR"), "/units/thermal-mems.toml");
    let o = Command::new(env!("CARGO_BIN_EXE_host"))
        .args([
            "calibrate",
            "--port",
            "sim",
            "--sim-unit",
            unit,
            "--plan",
            "thermal-soak",
        ])
        .args([
            "--verify-temp-c",
            "45",
            "--out-dir",
            out_dir.to_str().unwrap(),
        ])
        .output()
        .unwrap();
    let stdout = String::from_utf8_lossy(&o.stdout);
    let stderr = String::from_utf8_lossy(&o.stderr);
    assert!(o.status.success(), "{stdout}\n{stderr}");
    assert!(stderr.contains("virtual chamber is set to it"), "{stderr}");
    let lines: Vec<&str> = stdout
        .lines()
        .filter(|l| l.starts_with("verify "))
        .collect();
    let temp = |l: &str| -> f64 {
        let before = &l[..l.find(" °C  error").expect(l)];
        before.split_whitespace().last().unwrap().parse().expect(l)
    };
    let (second, first): (Vec<&str>, Vec<&str>) = lines.iter().partition(|l| l.contains(", 45 °C"));
    assert_eq!((first.len(), second.len()), (3, 3), "{stdout}");
    // The soak plan ends at its hottest step, 60 °C: the first verification runs there.
    for l in &first {
        assert!((temp(l) - 60.0).abs() < 0.5 && l.ends_with("ok"), "{l}");
    }
    for l in &second {
        assert!((temp(l) - 45.0).abs() < 0.5 && l.ends_with("ok"), "{l}");
    }
}

/// `--verify-temp-c` where nothing verifies at a second temperature is a usage error (exit 2)
/// saying why, not a run that silently skips it: a recorded session (no device), and the hand-held
/// procedure (it verifies |f| = 1 g in the hand's positions, at the room's temperature).
#[test]
fn verify_temp_c_is_refused_where_it_cannot_apply() {
    let dir = tempfile::tempdir().unwrap();
    let run = |args: &[&str]| {
        Command::new(env!("CARGO_BIN_EXE_host"))
            .args(args)
            .output()
            .unwrap()
    };
    let session = dir.path().join("s");
    let s = session.to_str().unwrap();
    assert!(run(&["-q", "simulate", "--out", s, "--plan", "short"])
        .status
        .success());
    let out = dir.path().join("hand").to_str().unwrap().to_string();
    for (args, needle) in [
        (
            vec!["calibrate", "--input", s, "--verify-temp-c", "45"],
            "a recorded session has no device to verify",
        ),
        (
            vec![
                "calibrate",
                "--port",
                "sim-hand",
                "--out-dir",
                &out,
                "--verify-temp-c",
                "45",
            ],
            "the hand-held procedure verifies",
        ),
    ] {
        let o = run(&args);
        let stderr = String::from_utf8_lossy(&o.stderr);
        assert_eq!(o.status.code(), Some(2), "{args:?}: {stderr}");
        assert!(
            stderr.contains("--verify-temp-c") && stderr.contains(needle),
            "{stderr}"
        );
    }
    // Nothing was calibrated or recorded on the way to the refusal.
    assert!(!session.join("calibration.toml").exists());
    assert!(!dir.path().join("hand").exists());
}
