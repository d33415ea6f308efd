//! The one output convention of every subcommand (README, "Output and exit status"): results on
//! stdout (or only the `--json` document), progress, prompts and warnings on stderr, `-q` leaving
//! only errors and the document; exit status 0 success, 1 error, 2 usage, 3 a check failed; a unit
//! that fails its checks leaves its files as `calibration.FAILED.*`, never as an accepted pair.

use std::path::Path;
use std::process::Command;
use std::time::Instant;

/// `host ARGS`: exit code, stdout, stderr.
fn run(args: &[&str]) -> (i32, String, String) {
    let out = Command::new(env!("CARGO_BIN_EXE_host"))
        .args(args)
        .output()
        .expect("the host binary runs");
    (
        out.status.code().expect("exited, not killed"),
        String::from_utf8_lossy(&out.stdout).into_owned(),
        String::from_utf8_lossy(&out.stderr).into_owned(),
    )
}

fn s(p: &Path) -> &str {
    p.to_str().unwrap()
}

/// A simulated session of the `short` plan, calibrated into its own directory.
fn calibrated_session(dir: &Path, name: &str, seed: &str) -> std::path::PathBuf {
    let session = dir.join(name);
    let (code, _, err) = run(&[
        "-q",
        "simulate",
        "--out",
        s(&session),
        "--plan",
        "short",
        "--seed",
        seed,
    ]);
    assert_eq!(code, 0, "{err}");
    let (code, _, err) = run(&["-q", "calibrate", "--input", s(&session)]);
    assert_eq!(code, 0, "{err}");
    session
}

#[test]
fn simulate_results_on_stdout_errors_exit_1_usage_exits_2() {
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("sim");
    let (code, stdout, stderr) = run(&["simulate", "--out", s(&out), "--plan", "short"]);
    assert_eq!(code, 0, "{stderr}");
    assert!(stdout.contains("simulated 30000 rows") && !stderr.contains("rows ("));
    // Quiet: nothing at all on success.
    let quiet = dir.path().join("quiet");
    let (code, stdout, stderr) = run(&["-q", "simulate", "--out", s(&quiet), "--plan", "short"]);
    assert_eq!((code, stdout.as_str(), stderr.as_str()), (0, "", ""));
    // An existing session is not replaced: an error, on stderr only.
    let (code, stdout, stderr) = run(&["simulate", "--out", s(&out), "--plan", "short"]);
    assert_eq!(code, 1, "{stderr}");
    assert!(
        stdout.is_empty() && stderr.starts_with("error:"),
        "{stderr}"
    );
    // clap's own usage error.
    let (code, stdout, _) = run(&["simulate"]);
    assert_eq!((code, stdout.as_str()), (2, ""));
}

#[test]
fn calibrate_input_success_failed_check_error_and_usage() {
    let dir = tempfile::tempdir().unwrap();
    let session = dir.path().join("s");
    assert_eq!(
        run(&["-q", "simulate", "--out", s(&session), "--plan", "short"]).0,
        0
    );
    let (code, stdout, stderr) = run(&["calibrate", "--input", s(&session)]);
    assert_eq!(code, 0, "{stderr}");
    assert!(
        stdout.contains("Result (± 1σ)") && stdout.contains("wrote"),
        "{stdout}"
    );
    assert!(!stderr.contains("Result (± 1σ)"), "{stderr}");

    // A failed limit: exit 3, the tables still on stdout, the files kept under FAILED names.
    let failed = dir.path().join("failed");
    let (code, stdout, stderr) = run(&[
        "calibrate",
        "--input",
        s(&session),
        "--out-dir",
        s(&failed),
        "--max-bias-mg",
        "0.000001",
    ]);
    assert_eq!(code, 3, "{stderr}");
    assert!(stdout.contains("verdict          FAIL") && stdout.contains("calibration.FAILED.bin"));
    assert!(stderr.contains("error: FAIL:"), "{stderr}");
    assert!(failed.join("calibration.FAILED.toml").exists());
    assert!(failed.join("calibration.FAILED.bin").exists());
    assert!(!failed.join("calibration.toml").exists() && !failed.join("calibration.bin").exists());

    // --json -q: stdout is the document alone, even when the check fails; stderr the warnings
    // (which -q keeps) and the error, last.
    let json_dir = dir.path().join("json");
    let (code, stdout, stderr) = run(&[
        "-q",
        "calibrate",
        "--input",
        s(&session),
        "--out-dir",
        s(&json_dir),
        "--json",
        "--max-bias-mg",
        "0.000001",
    ]);
    assert_eq!(code, 3, "{stderr}");
    let v: serde_json::Value = serde_json::from_str(&stdout).expect("stdout is one JSON document");
    assert_eq!(v["passed"], false);
    let lines: Vec<&str> = stderr.lines().collect();
    assert!(
        lines.last().is_some_and(|l| l.starts_with("error: FAIL")),
        "{stderr}"
    );
    for l in &lines[..lines.len() - 1] {
        assert!(l.starts_with("warning: "), "{stderr}");
    }

    // An error: a missing session.
    let (code, stdout, stderr) = run(&["calibrate", "--input", s(&dir.path().join("none"))]);
    assert_eq!(code, 1, "{stderr}");
    assert!(stdout.is_empty());
    // Bare `calibrate`: a usage error, with the fix.
    let (code, stdout, stderr) = run(&["calibrate"]);
    assert_eq!(code, 2, "{stderr}");
    assert!(stdout.is_empty() && stderr.contains("--input"), "{stderr}");
}

#[test]
fn calibrate_port_sim_results_on_stdout_progress_on_stderr() {
    let dir = tempfile::tempdir().unwrap();
    let ok = dir.path().join("ok");
    let (code, stdout, stderr) = run(&[
        "calibrate",
        "--port",
        "sim",
        "--plan",
        "quick-oblique",
        "--out-dir",
        s(&ok),
    ]);
    assert_eq!(code, 0, "{stderr}");
    // The same result block as `calibrate --input`, on stdout; the operator's steps on stderr.
    assert!(
        stdout.contains("Result (± 1σ)") && stdout.contains("PASS:"),
        "{stdout}"
    );
    assert!(stdout.contains("verify "), "{stdout}");
    assert!(!stderr.contains("Result (± 1σ)") && stderr.contains("mount the unit"));
    assert!(ok.join("calibration.toml").exists());

    // Quiet: nothing on stdout, not even the PASS line.
    let quiet = dir.path().join("quiet");
    let (code, stdout, stderr) = run(&[
        "-q",
        "calibrate",
        "--port",
        "sim",
        "--plan",
        "quick-oblique",
        "--out-dir",
        s(&quiet),
    ]);
    assert_eq!((code, stdout.as_str(), stderr.as_str()), (0, "", ""));

    // A verification that cannot pass: exit 3, the files marked.
    let failed = dir.path().join("failed");
    let (code, stdout, stderr) = run(&[
        "calibrate",
        "--port",
        "sim",
        "--plan",
        "quick-oblique",
        "--verify-tolerance-mg",
        "0.000001",
        "--out-dir",
        s(&failed),
    ]);
    assert_eq!(code, 3, "{stderr}");
    assert!(
        stdout.contains("FAIL") && !stdout.contains("PASS:"),
        "{stdout}"
    );
    assert!(failed.join("calibration.FAILED.bin").exists());
    assert!(!failed.join("calibration.bin").exists());

    // An error: a serial port that is not there.
    let (code, stdout, _) = run(&["calibrate", "--port", "/dev/does-not-exist"]);
    assert_eq!((code, stdout.as_str()), (1, ""));
}

#[test]
fn plan_export_compare_noise_apply_follow_the_convention() {
    let dir = tempfile::tempdir().unwrap();
    let a = calibrated_session(dir.path(), "a", "1");
    let b = calibrated_session(dir.path(), "b", "2");
    let cal_a = a.join("calibration.toml");
    let cal_b = b.join("calibration.toml");

    // plan: the prediction on stdout; an unknown plan is an error.
    let (code, stdout, stderr) = run(&["plan", "--check", "short"]);
    assert_eq!(code, 0, "{stderr}");
    assert!(!stdout.is_empty());
    assert_eq!(run(&["plan", "--check", "no-such-plan"]).0, 1);

    // export: the export itself on stdout, also with -q; the package without --out is a usage
    // error.
    let (code, stdout, _) = run(&[
        "-q",
        "export",
        "--calibration",
        s(&cal_a),
        "--format",
        "json",
    ]);
    assert_eq!(code, 0);
    serde_json::from_str::<serde_json::Value>(&stdout).expect("the export is on stdout");
    let out = dir.path().join("a.json");
    let (code, stdout, _) = run(&[
        "export",
        "--calibration",
        s(&cal_a),
        "--format",
        "json",
        "--out",
        s(&out),
    ]);
    assert_eq!(code, 0);
    assert!(stdout.starts_with("wrote "), "{stdout}");
    let (code, stdout, _) = run(&["export", "--calibration", s(&cal_a), "--format", "c"]);
    assert_eq!((code, stdout.as_str()), (2, ""));
    let missing = dir.path().join("missing.toml");
    assert_eq!(
        run(&["export", "--calibration", s(&missing), "--format", "json"]).0,
        1
    );

    // compare: the table on stdout; a limit two seeds cannot meet fails the check (3).
    let (code, stdout, stderr) = run(&["compare", s(&cal_a), s(&cal_b)]);
    assert_eq!(code, 0, "{stderr}");
    assert!(!stdout.is_empty());
    let (code, stdout, stderr) = run(&["compare", s(&cal_a), s(&cal_b), "--max-sigma", "0.000001"]);
    assert_eq!(code, 3, "{stderr}");
    assert!(!stdout.is_empty() && stderr.contains("FAIL"), "{stderr}");
    assert_eq!(run(&["compare", s(&cal_a), s(&missing)]).0, 1);

    // noise: the table on stdout, nothing but warnings with -q; --json -q: the document alone on
    // stdout.
    let (code, stdout, stderr) = run(&["noise", "--input", s(&a)]);
    assert_eq!(code, 0, "{stderr}");
    assert!(stdout.contains("Allan deviation"), "{stdout}");
    assert!(!stderr.contains("Allan deviation"));
    let (code, stdout, stderr) = run(&["-q", "noise", "--input", s(&a), "--json"]);
    assert_eq!(code, 0, "{stderr}");
    assert!(
        stderr.lines().all(|l| l.starts_with("warning: ")),
        "{stderr}"
    );
    serde_json::from_str::<serde_json::Value>(&stdout).expect("the document alone");
    assert_eq!(run(&["noise", "--input", s(&missing)]).0, 1);

    // apply: the CSV on stdout with its summary on stderr; with --out the summary is the result.
    let (code, stdout, stderr) = run(&["apply", "--calibration", s(&cal_a), "--input", s(&a)]);
    assert_eq!(code, 0, "{stderr}");
    assert!(stdout.starts_with("segment,") && !stdout.contains("applied"));
    assert!(stderr.contains("applied"), "{stderr}");
    let csv = dir.path().join("applied.csv");
    let (code, stdout, _) = run(&[
        "apply",
        "--calibration",
        s(&cal_a),
        "--input",
        s(&a),
        "--out",
        s(&csv),
    ]);
    assert_eq!(code, 0);
    assert!(stdout.starts_with("applied"), "{stdout}");
    assert_eq!(
        run(&["apply", "--calibration", s(&missing), "--input", s(&a)]).0,
        1
    );
}

/// `monitor --port sim` runs the simulated device at its real rate: 5 lines of 100 samples at
/// 1 kHz take at least half a second, and the output is those lines and no more.
///
/// Only the bounds a loaded machine cannot cross are checked: a paced run cannot end before its
/// virtual time has passed, and `--fast` over 200 s of virtual time must end well before real time
/// would (it takes about a second; a test machine busy enough to make it take 200 s would fail every
/// other test too). An upper bound near the paced run's half second raced the machine's load.
#[test]
fn monitor_sim_is_paced_and_bounded() {
    let started = Instant::now();
    let (code, stdout, stderr) = run(&["monitor", "--port", "sim", "--count", "5"]);
    let wall_s = started.elapsed().as_secs_f64();
    assert_eq!(code, 0, "{stderr}");
    let lines: Vec<&str> = stdout.lines().collect();
    assert_eq!(lines.len(), 6, "a header and 5 lines: {stdout}");
    // The last line's device time stamp: its window starts at 0.4 s of virtual time.
    let t_s: f64 = lines[5].split_whitespace().next().unwrap().parse().unwrap();
    assert!((0.39..0.41).contains(&t_s), "{t_s}");
    // Wall time ≥ virtual time (0.5 s, less the first window's set-up).
    assert!(wall_s >= 0.45, "{wall_s} s");
    // --fast needs --count (bounded), and is then quicker than real time.
    assert_eq!(run(&["monitor", "--port", "sim", "--fast"]).0, 2);
    let started = Instant::now();
    let (code, stdout, _) = run(&["monitor", "--port", "sim", "--fast", "--count", "2000"]);
    let wall_s = started.elapsed().as_secs_f64();
    assert_eq!(code, 0);
    assert_eq!(stdout.lines().count(), 2001);
    let last_t_s: f64 = stdout
        .lines()
        .last()
        .unwrap()
        .split_whitespace()
        .next()
        .unwrap()
        .parse()
        .unwrap();
    assert!(
        wall_s < last_t_s,
        "{wall_s} s of wall time for {last_t_s} s of device time"
    );
}
