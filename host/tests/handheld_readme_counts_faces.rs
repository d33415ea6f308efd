//! The README hand-held section's `host …` commands (raw counts with a mid-scale offset and a gyro in
//! counts; the six-face session), run as written with the `host` binary in a fresh directory.

use std::process::Command;

#[test]
fn readme_counts_and_six_face_commands_work_as_written() {
    let readme =
        std::fs::read_to_string(concat!(env!("CARGO_MANIFEST_DIR"), "/../README.md")).unwrap();
    let section = readme
        .split("## Hand-held calibration")
        .nth(1)
        .and_then(|s| s.split("\n## ").next())
        .expect("the README has a hand-held section");
    let commands: Vec<&str> = section
        .lines()
        .filter_map(|l| l.strip_prefix("host "))
        .collect();
    assert_eq!(commands.len(), 5, "{commands:?}");
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
