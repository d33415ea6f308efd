//! `host batch` on the command line: `--jobs` bounded before any work, and `--out` written whole
//! (refused without `--force`, replaced whole with it, never left half-written by an interrupted run).

mod common;
use common::host;
use std::path::{Path, PathBuf};

/// `n` short sessions of the paper's unit under `dir/lot`, each with its own unit id.
fn lot(dir: &Path, n: usize) -> PathBuf {
    let input = dir.join("lot");
    for i in 0..n {
        let s = input.join(format!("unit{i}"));
        let (ok, _, e) = host(&[
            "-q",
            "simulate",
            "--out",
            s.to_str().unwrap(),
            "--plan",
            "quick-oblique",
            "--seed",
            &i.to_string(),
        ]);
        assert!(ok, "{e}");
        let plan = s.join("plan.toml");
        let text = std::fs::read_to_string(&plan).unwrap();
        let id = format!("unit_id = \"{:024x}\"\n", 0xC000 + i);
        std::fs::write(&plan, id + &text).unwrap();
    }
    input
}

#[test]
fn jobs_beyond_the_bound_are_refused_before_any_work() {
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("res");
    // The input does not even exist: the bound is checked first, nothing is created.
    for jobs in ["100000", "257", "0"] {
        let (ok, _, stderr) = host(&[
            "batch",
            "--input",
            dir.path().join("no-such-lot").to_str().unwrap(),
            "--out",
            out.to_str().unwrap(),
            "--jobs",
            jobs,
        ]);
        assert!(!ok);
        assert!(
            stderr.contains(&format!("--jobs {jobs}")) && stderr.contains("1 to 256"),
            "{stderr}"
        );
        assert!(!out.exists());
    }
}

#[test]
fn out_is_refused_without_force_and_replaced_whole_with_it() {
    let dir = tempfile::tempdir().unwrap();
    let input = lot(dir.path(), 2);
    let input = input.to_str().unwrap();
    let res = dir.path().join("res");
    let res_s = res.to_str().unwrap();
    let (ok, stdout, stderr) = host(&["batch", "--input", input, "--out", res_s, "--jobs", "8"]);
    assert!(ok, "{stdout}{stderr}");
    // One thread per session at most.
    assert!(stdout.contains("on 2 threads"), "{stdout}");
    let first = std::fs::read(res.join("summary.json")).unwrap();

    // Again without --force: refused before any work, the result untouched; before the input is
    // even listed (here it does not exist), so nothing was read either.
    let missing = dir.path().join("no-such-lot");
    for input in [input, missing.to_str().unwrap()] {
        let (ok, stdout, stderr) = host(&["batch", "--input", input, "--out", res_s]);
        assert!(!ok);
        assert!(
            stderr.contains("already exists") && stderr.contains("--force"),
            "{stderr}"
        );
        assert!(
            !stdout.contains("units,"),
            "no unit was calibrated: {stdout}"
        );
        assert_eq!(std::fs::read(res.join("summary.json")).unwrap(), first);
    }

    // With --force: every unit calibrated again and passing, the summary replaced.
    std::fs::write(res.join("stale.csv"), b"from before").unwrap();
    let (ok, stdout, stderr) = host(&["batch", "--input", input, "--out", res_s, "--force"]);
    assert!(ok, "{stdout}{stderr}");
    assert!(stdout.contains("2 passed, 0 not"), "{stdout}");
    assert!(
        !res.join("stale.csv").exists(),
        "replaced whole, not merged"
    );
    assert!(res.join("unit0").join("calibration.toml").exists());
    let leftovers: Vec<_> = std::fs::read_dir(dir.path())
        .unwrap()
        .map(|e| e.unwrap().file_name().to_string_lossy().into_owned())
        .filter(|n| n.starts_with('.'))
        .collect();
    assert!(leftovers.is_empty(), "{leftovers:?}");

    // --force never replaces a directory that is not a batch's result.
    let other = dir.path().join("other");
    std::fs::create_dir(&other).unwrap();
    std::fs::write(other.join("notes.txt"), b"keep").unwrap();
    let (ok, _, stderr) = host(&[
        "batch",
        "--input",
        input,
        "--out",
        other.to_str().unwrap(),
        "--force",
    ]);
    assert!(!ok && stderr.contains("no summary.json"), "{stderr}");
    assert_eq!(std::fs::read(other.join("notes.txt")).unwrap(), b"keep");
}

/// A run killed half-way (as by Ctrl-C) leaves no `--out` at all: the next run, without `--force`,
/// is not refused and writes the whole result.
#[test]
fn an_interrupted_run_leaves_nothing_a_later_run_refuses() {
    let dir = tempfile::tempdir().unwrap();
    let input = lot(dir.path(), 4);
    // The second unit's samples are a named pipe that nobody writes: its read blocks, so the run is
    // certainly still going when the first unit is written and the kill comes (a lot of plain files
    // could finish between two looks under load, and the test raced it).
    let blocked = input.join("unit1").join("samples.csv");
    let kept = dir.path().join("unit1-samples.csv");
    std::fs::rename(&blocked, &kept).unwrap();
    assert!(std::process::Command::new("mkfifo")
        .arg(&blocked)
        .status()
        .unwrap()
        .success());
    let res = dir.path().join("res");
    let mut child = std::process::Command::new(env!("CARGO_BIN_EXE_host"))
        .args(["-q", "batch", "--jobs", "1", "--input"])
        .arg(&input)
        .arg("--out")
        .arg(&res)
        .stdout(std::process::Stdio::null())
        .stderr(std::process::Stdio::null())
        .spawn()
        .unwrap();
    // Wait until the first unit's calibration is written (somewhere under the parent), then kill.
    let first_written = || {
        std::fs::read_dir(dir.path()).unwrap().any(|e| {
            let p = e.unwrap().path();
            p.join("unit0").join("calibration.toml").exists()
        })
    };
    let started = std::time::Instant::now();
    while !first_written() {
        assert!(
            child.try_wait().unwrap().is_none(),
            "finished before it was interrupted"
        );
        assert!(
            started.elapsed().as_secs() < 120,
            "no unit written in 2 min"
        );
        std::thread::sleep(std::time::Duration::from_millis(2));
    }
    assert!(
        child.try_wait().unwrap().is_none(),
        "finished before it was interrupted"
    );
    child.kill().unwrap();
    child.wait().unwrap();
    assert!(!res.exists(), "a half-written result at --out");
    std::fs::remove_file(&blocked).unwrap();
    std::fs::rename(&kept, &blocked).unwrap();
    let (ok, stdout, stderr) = host(&[
        "batch",
        "--input",
        input.to_str().unwrap(),
        "--out",
        res.to_str().unwrap(),
    ]);
    assert!(ok, "{stdout}{stderr}");
    assert!(stdout.contains("4 passed, 0 not"), "{stdout}");
}
