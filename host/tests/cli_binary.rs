//! The `host` binary itself: errors go to stderr as `error: ...` with a non-zero exit status, results
//! to stdout.

mod common;
use common::host;

#[test]
fn simulate_and_calibrate_through_the_binary() {
    let dir = tempfile::tempdir().unwrap();
    let session = dir.path().join("s");
    let s = session.to_str().unwrap();
    let (ok, stdout, stderr) = host(&["simulate", "--out", s, "--plan", "short", "--seed", "4"]);
    assert!(ok, "{stderr}");
    assert!(stdout.contains("simulated 30000 rows"), "{stdout}");
    // Simulating again into the same directory is refused, not silently overwritten.
    let (ok, _, stderr) = host(&["simulate", "--out", s, "--plan", "short"]);
    assert!(
        !ok && stderr.starts_with("error: ") && stderr.contains("--force"),
        "{stderr}"
    );
    let (ok, stdout, stderr) = host(&["calibrate", "--input", s]);
    assert!(ok, "{stderr}");
    assert!(
        stdout.contains("Table 1") && stdout.contains("calibration.bin"),
        "{stdout}"
    );
    assert!(stderr.contains("no unit_id"), "{stderr}");
    assert!(session.join("calibration.toml").exists());
}

#[test]
fn bad_input_is_an_error_line_and_a_failure_status() {
    let dir = tempfile::tempdir().unwrap();
    let session = dir.path().join("s");
    let s = session.to_str().unwrap();
    let (ok, _, stderr) = host(&["calibrate", "--input", s]);
    assert!(
        !ok && stderr.starts_with("error: ") && stderr.contains("plan.toml"),
        "{stderr}"
    );
    assert!(host(&["simulate", "--out", s, "--plan", "short"]).0);
    let csv = session.join("samples.csv");
    let text = std::fs::read_to_string(&csv).unwrap();
    std::fs::write(&csv, text.replacen("x+,0.001,", "x+,0.001x,", 1)).unwrap();
    let (ok, _, stderr) = host(&["calibrate", "--input", s]);
    assert!(!ok, "{stderr}");
    assert!(stderr.contains("line 3, column 2 (t_s)"), "{stderr}");
}

#[test]
fn calibrate_live_against_the_simulated_device() {
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("live");
    let (ok, stdout, stderr) = host(&[
        "-q",
        "calibrate",
        "--port",
        "sim",
        "--plan",
        "short-oblique",
        "--out-dir",
        out.to_str().unwrap(),
    ]);
    assert!(ok, "{stdout}\n{stderr}");
    // -q: only errors and a --json document are printed; success is the exit status.
    assert!(stdout.is_empty(), "{stdout}");
    assert!(out.join("calibration.bin").exists());
    // --input and --port are exclusive; port-only flags need --port.
    let (ok, _, stderr) = host(&["calibrate", "--input", "x", "--port", "sim"]);
    assert!(!ok && stderr.contains("cannot be used with"), "{stderr}");
}

/// `--port sim-hand`: no table, so the hand-held procedure (the default plan for it is `hand`), the
/// operator's steps on stderr, the result and the three magnitude checks on stdout.
#[test]
fn calibrate_live_hand_held_against_the_simulated_hand() {
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("hand");
    let (ok, stdout, stderr) = host(&[
        "calibrate",
        "--port",
        "sim-hand",
        "--out-dir",
        out.to_str().unwrap(),
    ]);
    assert!(ok, "{stdout}\n{stderr}");
    assert!(
        stderr.contains("[hand 24] still at a new position: recording")
            && stderr.contains("24 positions recorded: enough"),
        "{stderr}"
    );
    // The simulated hand brings the unit back to where it was every seventh turn: refused each
    // time, and turned again.
    assert_eq!(stderr.matches("again (0° away)").count(), 3, "{stderr}");
    assert_eq!(stdout.matches("hand-held check").count(), 3, "{stdout}");
    assert!(stdout.contains("PASS: unit"), "{stdout}");
    assert!(out.join("calibration.bin").exists());
}

#[test]
fn a_soak_session_calibrates_over_temperature_through_the_binary() {
    let dir = tempfile::tempdir().unwrap();
    let session = dir.path().join("soak");
    let s = session.to_str().unwrap();
    let unit = concat!(env!("CARGO_MANIFEST_DIR"), "/units/thermal-mems.toml");
    let (ok, _, stderr) = host(&[
        "-q",
        "simulate",
        "--out",
        s,
        "--unit",
        unit,
        "--plan",
        "thermal-soak",
        "--seed",
        "5",
    ]);
    assert!(ok, "{stderr}");
    let csv = std::fs::read_to_string(session.join("samples.csv")).unwrap();
    assert!(csv.starts_with("segment,t_s,u_x,u_y,u_z,w_x,w_y,w_z,temp_c\nx+ @-20,"));
    let (ok, stdout, stderr) = host(&["calibrate", "--input", s]);
    assert!(ok, "{stderr}");
    assert!(
        stdout.contains("Temperature model") && stdout.contains("x+ @60"),
        "{stdout}"
    );
    let toml = std::fs::read_to_string(session.join("calibration.toml")).unwrap();
    let cal: estimator::unit_file::UnitFile = toml::from_str(&toml).unwrap();
    let t = cal.temperature.expect("a [temperature] section");
    assert_eq!(t.zero_bias_degree, Some([2; 3]), "{toml}");
    assert_eq!(t.scale_degree, Some([1; 3]), "{toml}");
    assert!(t.zero_bias_out_per_c_1sigma.is_some());
    // The blob carries the model to the device.
    let blob = std::fs::read(session.join("calibration.bin")).unwrap();
    let decoded = shared::blob::decode(&blob).unwrap();
    assert_eq!(decoded.calibration.temperature, Some(t.model()));
}

#[test]
fn a_live_recording_with_format_version_3_carries_the_device_temperature() {
    let dir = tempfile::tempdir().unwrap();
    let plan = dir.path().join("plan.toml");
    let text = include_str!("../../recording/plans/quick-oblique.toml");
    std::fs::write(
        &plan,
        text.replace("format_version = 1", "format_version = 3"),
    )
    .unwrap();
    let out = dir.path().join("live");
    let (ok, stdout, stderr) = host(&[
        "-q",
        "calibrate",
        "--port",
        "sim",
        "--plan",
        plan.to_str().unwrap(),
        "--out-dir",
        out.to_str().unwrap(),
    ]);
    assert!(ok, "{stdout}\n{stderr}");
    let csv = std::fs::read_to_string(out.join("recording/samples.csv")).unwrap();
    let mut lines = csv.lines();
    assert_eq!(
        lines.next(),
        Some("segment,t_s,u_x,u_y,u_z,w_x,w_y,w_z,temp_c")
    );
    // The simulated device's chamber stays at 25 °C: every window's mean reading.
    assert!(lines.all(|l| l.ends_with(",25.0")), "{csv}");
}

/// Every command that writes names its output `--out`; the older `--out-dir` stays an alias.
#[test]
fn every_output_is_named_out() {
    use clap::CommandFactory;
    for sub in host::cli::Cli::command().get_subcommands() {
        for arg in sub.get_arguments() {
            assert_ne!(
                arg.get_long(),
                Some("out-dir"),
                "{} names its output --out-dir",
                sub.get_name()
            );
        }
    }
    let dir = tempfile::tempdir().unwrap();
    let s = dir.path().join("s");
    let s = s.to_str().unwrap();
    assert!(host(&["-q", "simulate", "--out", s, "--plan", "short"]).0);
    for (flag, name) in [("--out", "a"), ("--out-dir", "b")] {
        let cal = dir.path().join(format!("cal-{name}"));
        let (ok, _, e) = host(&["-q", "calibrate", "--input", s, flag, cal.to_str().unwrap()]);
        assert!(ok && cal.join("calibration.toml").exists(), "{flag}: {e}");
        let rep = dir.path().join(format!("report-{name}"));
        let cal = cal.join("calibration.toml");
        let line = [
            "-q",
            "report",
            "--input",
            s,
            "--calibration",
            cal.to_str().unwrap(),
        ];
        let (ok, _, e) = host(&[&line[..], &[flag, rep.to_str().unwrap()]].concat());
        assert!(ok && rep.is_dir(), "{flag}: {e}");
    }
}
