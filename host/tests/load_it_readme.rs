//! The README's "Load it" recipes, run as written in a fresh directory, each file checked by its
//! consumer's own rules: PX4's QGroundControl parameter file (five tab-separated fields, ids as
//! type 6 integers), ArduPilot's parameter file (`NAME,VALUE`, its device ids, the note on
//! `INS_GYR_CAL`), and the C package, built and run.

use std::path::Path;
use std::process::Command;

fn section() -> String {
    let readme =
        std::fs::read_to_string(concat!(env!("CARGO_MANIFEST_DIR"), "/../README.md")).unwrap();
    readme
        .split("## Load it")
        .nth(1)
        .and_then(|s| s.split("\n## ").next())
        .expect("the README has a Load it section")
        .to_string()
}

fn run(dir: &Path, c: &str) {
    let out = Command::new(env!("CARGO_BIN_EXE_host"))
        .args(c.split_whitespace())
        .current_dir(dir)
        .output()
        .unwrap();
    assert!(
        out.status.success(),
        "{c}: {}",
        String::from_utf8_lossy(&out.stderr)
    );
}

/// `NAME` → value of a parameter file's lines (`split` the field separator, name and value at
/// `name_at` and `name_at + 1`), comments left out.
fn params(text: &str, split: char, name_at: usize) -> Vec<(String, String)> {
    text.lines()
        .filter(|l| !l.starts_with('#') && !l.trim().is_empty())
        .map(|l| {
            let f: Vec<&str> = l.split(split).collect();
            (f[name_at].to_string(), f[name_at + 1].to_string())
        })
        .collect()
}

#[test]
fn readme_load_it_recipes_work_as_written() {
    let section = section();
    let commands: Vec<&str> = section
        .lines()
        .filter_map(|l| l.strip_prefix("host "))
        .collect();
    assert_eq!(commands.len(), 6, "{commands:?}");
    let dir = tempfile::tempdir().unwrap();
    for c in &commands {
        run(dir.path(), c);
    }
    // PX4: QGroundControl reads `sysid compid name value type`, tab-separated (type 6 an int32).
    let px4 = std::fs::read_to_string(dir.path().join("px4.params")).unwrap();
    for line in px4.lines().filter(|l| !l.starts_with('#') && !l.is_empty()) {
        assert_eq!(line.split('\t').count(), 5, "{line}");
    }
    let px4 = params(&px4.replace('\t', " "), ' ', 2);
    let get = |p: &[(String, String)], k: &str| {
        p.iter()
            .find(|(n, _)| n == k)
            .map(|(_, v)| v.clone())
            .unwrap_or_else(|| panic!("{k} missing"))
    };
    assert_eq!(get(&px4, "CAL_ACC0_ID"), "1310988");
    assert_eq!(get(&px4, "CAL_GYRO0_ID"), "1310996");
    for k in ["CAL_ACC0_XSCALE", "CAL_ACC0_YSCALE", "CAL_ACC0_ZSCALE"] {
        let v: f64 = get(&px4, k).parse().unwrap();
        assert!((v - 1.0).abs() < 0.05, "{k} = {v}");
    }
    // ArduPilot: `NAME,VALUE`; the ids it compares at start-up, and what to do about INS_GYR_CAL.
    let ap_text = std::fs::read_to_string(dir.path().join("ardupilot.parm")).unwrap();
    let ap = params(&ap_text, ',', 0);
    assert_eq!(get(&ap, "INS_ACC_ID"), "2753028");
    assert_eq!(get(&ap, "INS_GYR_ID"), "2752772");
    for k in ["INS_ACCOFFS_X", "INS_ACCOFFS_Y", "INS_ACCOFFS_Z"] {
        let v: f64 = get(&ap, k).parse().unwrap();
        assert!(v.abs() <= 3.5, "{k} = {v} outside ArduPilot's range");
    }
    assert!(ap_text.contains("INS_GYR_CAL = 0"), "{ap_text}");
    // The C package: built with the README's own line and run.
    let acal = dir.path().join("acal");
    let cc = section
        .split('`')
        .find(|s| s.starts_with("cc "))
        .expect("the README gives the cc line");
    let out = Command::new("sh")
        .arg("-c")
        .arg(format!("{cc} && ./example"))
        .current_dir(&acal)
        .output()
        .expect("sh runs");
    assert!(
        out.status.success(),
        "{cc}: {}",
        String::from_utf8_lossy(&out.stderr)
    );
    assert!(!out.stdout.is_empty());
}
