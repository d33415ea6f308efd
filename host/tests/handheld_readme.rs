//! The README's hand-held section, run as written: its commands (simulate a hand session, segment it,
//! calibrate it; rehearse the live procedure; raw counts; six faces) with the `host` binary in a fresh directory.

use std::path::Path;
use std::process::Command;

/// The README's hand-held section.
fn section() -> String {
    let readme =
        std::fs::read_to_string(concat!(env!("CARGO_MANIFEST_DIR"), "/../README.md")).unwrap();
    readme
        .split("## Hand-held calibration")
        .nth(1)
        .and_then(|s| s.split("\n## ").next())
        .expect("the README has a hand-held section")
        .to_string()
}

/// Runs `host` with the command line `c` in `dir`; its stdout.
fn run(dir: &Path, c: &str) -> String {
    let out = Command::new(env!("CARGO_BIN_EXE_host"))
        .args(c.split_whitespace())
        .current_dir(dir)
        .output()
        .unwrap();
    let text = String::from_utf8_lossy(&out.stdout).to_string();
    assert!(
        out.status.success(),
        "{c}: {}\n{text}",
        String::from_utf8_lossy(&out.stderr)
    );
    text
}

#[test]
fn readme_hand_held_commands_work_as_written() {
    let section = section();
    let prefix = "cargo run --release -p host -- ";
    let commands: Vec<&str> = section
        .lines()
        .filter_map(|l| l.strip_prefix(prefix))
        .collect();
    assert_eq!(commands.len(), 6, "{commands:?}");
    assert!(commands[0].starts_with("simulate-hand "));
    assert!(commands[1].starts_with("segment ") && commands[2].starts_with("calibrate "));
    // The live rehearsal: the simulated device in a simulated hand, no file in.
    assert!(commands[3].starts_with("calibrate --port sim-hand "));
    // Its window log, segmented and calibrated by hand.
    assert!(commands[4].starts_with("segment --input hand-live/stream.csv "));
    assert!(commands[5].starts_with("calibrate --input hand-live-again "));

    let dir = tempfile::tempdir().unwrap();
    for c in &commands {
        let text = run(dir.path(), c);
        if c.starts_with("segment") {
            assert!(text.contains("24 still interval(s)"), "{text}");
            assert!(text.contains("every entry of G determined"), "{text}");
        }
    }
    for f in [
        "raw.truth.toml",
        "hand-session/gyro.toml",
        "hand-session/segments.svg",
        "hand-calibration/calibration.toml",
        "hand-live/calibration.toml",
        "hand-live/recording/plan.toml",
        "hand-live/stream.csv",
        "hand-live/segmented/gyro.toml",
    ] {
        assert!(dir.path().join(f).exists(), "{f}");
    }
    // The live session's calibration is the offline path's on its window log: the gyro fitted
    // from the hand's turns, and everything else, to the last digit.
    let read = |f: &str| std::fs::read_to_string(dir.path().join(f)).unwrap();
    let live = read("hand-live/calibration.toml");
    let offline = read("hand-live-again-cal/calibration.toml");
    let gyro = |t: &str| {
        t.split("\n[gyro]\n")
            .nth(1)
            .map(|g| g.split("\n[").next().unwrap_or_default().to_string())
    };
    let live_gyro = gyro(&live).expect("the live session's calibration has [gyro]");
    assert!(live_gyro.contains("matrix = ["), "{live_gyro}");
    assert_eq!(Some(live_gyro), gyro(&offline));
    assert_eq!(live, offline);
}

/// The raw-count (mid-scale offset, gyro in counts) and six-face commands (`host …` lines).
#[test]
fn readme_counts_and_six_face_commands_work_as_written() {
    let section = section();
    // The binary-log examples name the user's own logs (flight.ulg, bench.mcap); the log readers
    // are run on the reference tools' files in `cli::log_fixture_tests` and in `recording`'s
    // `tests/reference_tools.rs`.
    let commands: Vec<&str> = section
        .lines()
        .filter_map(|l| l.strip_prefix("host "))
        .filter(|c| !c.contains(".ulg") && !c.contains(".mcap"))
        .collect();
    assert_eq!(commands.len(), 5, "{commands:?}");
    let dir = tempfile::tempdir().unwrap();
    for c in &commands {
        let text = run(dir.path(), c);
        if c.starts_with("segment --input counts.csv") {
            assert!(text.contains("24 still interval(s)"), "{text}");
            assert!(text.contains("every entry of G determined"), "{text}");
        }
        if c.starts_with("segment --input cube.csv") {
            assert!(text.contains("six-face session: "), "{text}");
            assert!(text.contains("every entry of G determined"), "{text}");
        }
    }
    let counts = std::fs::read_to_string(dir.path().join("counts-session/plan.toml")).unwrap();
    assert!(counts.contains("output_unit = \"LSB\""), "{counts}");
    // The session keeps the logger's own counts: the offset is added back.
    let samples = std::fs::read_to_string(dir.path().join("counts-session/samples.csv")).unwrap();
    let row: Vec<f64> = samples
        .lines()
        .nth(1)
        .unwrap()
        .split(',')
        .skip(2)
        .take(3)
        .map(|x| x.parse().unwrap())
        .collect();
    assert!(
        row.iter().all(|x| (28_000.0..38_000.0).contains(x)),
        "{row:?}"
    );
    assert!(dir
        .path()
        .join("cube-calibration/calibration.toml")
        .exists());
}
