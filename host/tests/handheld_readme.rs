//! The README's hand-held section, run as written: its commands (simulate a hand session, segment it,
//! calibrate it) with the `host` binary in a fresh directory.

use std::process::Command;

#[test]
fn readme_hand_held_commands_work_as_written() {
    let readme =
        std::fs::read_to_string(concat!(env!("CARGO_MANIFEST_DIR"), "/../README.md")).unwrap();
    let section = readme
        .split("## Hand-held calibration")
        .nth(1)
        .and_then(|s| s.split("\n## ").next())
        .expect("the README has a hand-held section");
    let prefix = "cargo run --release -p host -- ";
    let commands: Vec<&str> = section
        .lines()
        .filter_map(|l| l.strip_prefix(prefix))
        .collect();
    assert_eq!(commands.len(), 3, "{commands:?}");
    assert!(commands[0].starts_with("simulate-hand "));
    assert!(commands[1].starts_with("segment ") && commands[2].starts_with("calibrate "));

    let dir = tempfile::tempdir().unwrap();
    for c in &commands {
        let out = Command::new(env!("CARGO_BIN_EXE_host"))
            .args(c.split_whitespace())
            .current_dir(dir.path())
            .output()
            .unwrap();
        let text = String::from_utf8_lossy(&out.stdout);
        assert!(
            out.status.success(),
            "{c}: {}\n{text}",
            String::from_utf8_lossy(&out.stderr)
        );
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
    ] {
        assert!(dir.path().join(f).exists(), "{f}");
    }
}
