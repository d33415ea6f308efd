//! Every long step shows progress on a terminal, and none without one: `host segment`, `apply` and
//! `noise` on a logger's CSV, run under a pseudo-terminal (`script` from util-linux), name each step
//! on stderr; the same runs piped, or with `-q`, draw nothing.

mod common;

use std::path::Path;
use std::process::Command;

/// Runs `host ARGS` in `dir` under a pseudo-terminal; what the terminal showed.
fn on_a_terminal(dir: &Path, args: &[&str]) -> String {
    let line = std::iter::once(env!("CARGO_BIN_EXE_host"))
        .chain(args.iter().copied())
        .collect::<Vec<_>>()
        .join(" ");
    let out = Command::new("script")
        .args(["-q", "-e", "-c", &line, "/dev/null"])
        .current_dir(dir)
        .output()
        .expect("`script` (util-linux) runs: it gives the command a terminal");
    assert!(
        out.status.success(),
        "{line}: {}",
        String::from_utf8_lossy(&out.stdout)
    );
    String::from_utf8_lossy(&out.stdout).into_owned()
}

#[test]
fn long_steps_show_progress_on_a_terminal_only() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    let (ok, _, e) = common::host_in(Some(d), &["simulate-hand", "--out", "hand.csv"]);
    assert!(ok, "{e}");
    let mut segment = common::hand_segment_args("hand.csv", "s");
    let shown = on_a_terminal(d, &segment);
    for step in [
        "reading hand.csv",
        "finding the still intervals and the turns",
        "choosing the positions and fitting the gyro to the turns",
        "writing the session",
        "drawing the segments' figure",
    ] {
        assert!(shown.contains(step), "no '{step}' in: {shown}");
    }
    let (ok, _, e) = common::host_in(Some(d), &["calibrate", "--input", "s", "--out", "c"]);
    assert!(ok, "{e}");
    let mut apply = vec!["apply", "--input", "hand.csv", "--out", "a.csv"];
    apply.extend(common::HAND_CSV_READING);
    apply.extend(["--calibration", "c/calibration.toml"]);
    let shown = on_a_terminal(d, &apply);
    assert!(
        shown.contains("applying the calibration to hand.csv"),
        "{shown}"
    );
    let mut noise = vec!["noise", "--input", "hand.csv", "--out", "n"];
    noise.extend(common::HAND_CSV_READING);
    let shown = on_a_terminal(d, &noise);
    assert!(shown.contains("reading hand.csv"), "{shown}");
    assert!(
        shown.contains("Allan deviation and fit, per axis"),
        "{shown}"
    );
    // Piped (stderr is not a terminal), or quiet on a terminal: no step is drawn.
    segment[4] = "s2";
    let (ok, _, stderr) = common::host_in(Some(d), &segment);
    assert!(ok, "{stderr}");
    assert!(!stderr.contains("reading hand.csv"), "{stderr}");
    segment[4] = "s3";
    let quiet: Vec<&str> = std::iter::once("-q")
        .chain(segment.iter().copied())
        .collect();
    let shown = on_a_terminal(d, &quiet);
    assert!(!shown.contains("reading hand.csv"), "{shown}");
}
