//! One way to say each figure, as `host calibrate` prints it: every figure of the result block in
//! one unit, a `next:` line naming the export command, and warnings kept under `-q` (its help:
//! "warnings and errors still go to stderr").

use std::path::Path;
use std::process::Command;

fn host(args: &[&str]) -> (bool, String, String) {
    let out = Command::new(env!("CARGO_BIN_EXE_host"))
        .args(args)
        .output()
        .expect("host runs");
    (
        out.status.success(),
        String::from_utf8_lossy(&out.stdout).into_owned(),
        String::from_utf8_lossy(&out.stderr).into_owned(),
    )
}

/// A simulated session of the paper's unit (volts) on the short plan, without a unit id.
fn session(dir: &Path) -> String {
    let s = dir.join("session").display().to_string();
    assert!(host(&["-q", "simulate", "--out", &s, "--plan", "short"]).0);
    s
}

#[test]
fn quiet_keeps_the_warnings() {
    let dir = tempfile::tempdir().unwrap();
    let s = session(dir.path());
    let (ok, stdout, stderr) = host(&["-q", "calibrate", "--input", &s]);
    assert!(ok, "{stderr}");
    assert!(stdout.is_empty(), "-q prints no results: {stdout}");
    assert!(
        stderr.contains("warning: plan.toml has no unit_id"),
        "-q dropped the warning: {stderr:?}"
    );
}

#[test]
fn the_result_block_gives_each_figure_one_unit_and_the_next_command() {
    let dir = tempfile::tempdir().unwrap();
    let s = session(dir.path());
    let (ok, stdout, stderr) = host(&["calibrate", "--input", &s]);
    assert!(ok, "{stderr}");
    assert!(stdout.contains("  zero-g output, V  x 2.4"), "{stdout}");
    assert!(stdout.contains("  bias 1σ, mg      x 0.0"), "{stdout}");
    for line in stdout
        .lines()
        .filter(|l| l.contains(" V ") || l.contains(", V"))
    {
        assert!(!line.contains("mg"), "two units in one figure: {line}");
    }
    let toml = Path::new(&s).join("calibration.toml");
    let next = format!(
        "next: host export --calibration {} --format json",
        toml.display()
    );
    assert!(stdout.contains(&next), "{stdout}");
    // The command it names runs.
    let out = dir.path().join("calibration.json");
    let (ok, _, stderr) = host(&[
        "export",
        "--calibration",
        &toml.display().to_string(),
        "--format",
        "json",
        "--out",
        &out.display().to_string(),
    ]);
    assert!(ok, "{stderr}");
}
