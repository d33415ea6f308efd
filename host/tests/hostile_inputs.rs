//! Bad inputs a hostile but fair user gives the `host` binary, each with the behaviour required: a
//! clear error naming the problem (and no file, no flashing), never unbounded memory, a panic or a
//! silently wrong result. One test per kind of defect; the names say which.

use std::path::{Path, PathBuf};
use std::process::{Command, Stdio};
use std::time::Duration;

mod common;
use common::{host, host_in};

/// A simulated session of `plan` in `dir/name`.
fn session(dir: &Path, name: &str, plan: &str, extra: &[&str]) -> PathBuf {
    let s = dir.join(name);
    let mut args = vec!["simulate", "--out", s.to_str().unwrap(), "--plan", plan];
    args.extend_from_slice(extra);
    let (ok, _, stderr) = host(&args);
    assert!(ok, "{stderr}");
    s
}

fn s(p: &Path) -> &str {
    p.to_str().unwrap()
}

fn refused(result: (bool, String, String), needles: &[&str]) -> String {
    let (ok, stdout, stderr) = result;
    assert!(!ok, "accepted: {stdout}\n{stderr}");
    assert!(stderr.starts_with("error: "), "{stderr}");
    assert!(!stderr.contains("panicked"), "{stderr}");
    for n in needles {
        assert!(stderr.contains(n), "'{n}' not in: {stderr}");
    }
    stderr
}

const SIX_POSITIONS: &str = r#"
output_unit = "V"
sample_rate_hz = 100
[[segment]]
name = "x+"
up_b = [1, 0, 0]
duration_s = 10
[[segment]]
name = "x-"
up_b = [-1, 0, 0]
duration_s = 10
[[segment]]
name = "y+"
up_b = [0, 1, 0]
duration_s = 10
[[segment]]
name = "y-"
up_b = [0, -1, 0]
duration_s = 10
[[segment]]
name = "z+"
up_b = [0, 0, 1]
duration_s = 10
[[segment]]
name = "z-"
up_b = [0, 0, -1]
duration_s = 10
"#;

/// Rewrites the rows of segment `a` as `b` and vice versa.
fn swap_labels(csv: &Path, a: &str, b: &str) {
    let text = std::fs::read_to_string(csv).unwrap();
    let swapped: String = text
        .lines()
        .map(|l| {
            if let Some(rest) = l.strip_prefix(&format!("{a},")) {
                format!("{b},{rest}\n")
            } else if let Some(rest) = l.strip_prefix(&format!("{b},")) {
                format!("{a},{rest}\n")
            } else {
                format!("{l}\n")
            }
        })
        .collect();
    std::fs::write(csv, swapped).unwrap();
}

// 1. Memory without bound.
#[test]
fn endless_inputs_and_huge_sizes_are_refused_at_once() {
    let dir = tempfile::tempdir().unwrap();
    let good = session(dir.path(), "s", "short", &[]);
    let zero = dir.path().join("zero");
    std::fs::create_dir(&zero).unwrap();
    std::fs::copy(good.join("plan.toml"), zero.join("plan.toml")).unwrap();
    std::os::unix::fs::symlink("/dev/zero", zero.join("samples.csv")).unwrap();
    // An endless input: a reader without a bound would never return (HANG_GUARD).
    refused(
        ended(&["calibrate", "--input", s(&zero)]),
        &["line 1 is longer than 4096 bytes", "not a recording"],
    );
    refused(
        ended(&["flash", "--port", "sim", "--calibration", "/dev/zero"]),
        &["/dev/zero", "longer than"],
    );
    refused(
        host(&["report", "--input", s(&good), "--duration-s", "1e7"]),
        &["--duration-s", "out of range"],
    );
    let plan = std::fs::read_to_string(good.join("plan.toml")).unwrap();
    let huge = dir.path().join("huge.toml");
    std::fs::write(
        &huge,
        plan.replace("sample_rate_hz = 1000.0", "sample_rate_hz = 1e12"),
    )
    .unwrap();
    refused(
        ended(&[
            "simulate",
            "--out",
            s(&dir.path().join("h")),
            "--plan",
            s(&huge),
        ]),
        &["sample_rate_hz", "out of range"],
    );
    let long = dir.path().join("long.toml");
    std::fs::write(
        &long,
        plan.replacen("duration_s = 2.0", "duration_s = 1e12", 1),
    )
    .unwrap();
    refused(
        ended(&[
            "simulate",
            "--out",
            s(&dir.path().join("l")),
            "--plan",
            s(&long),
        ]),
        &["duration_s", "too long"],
    );
    assert!(!dir.path().join("h").join("samples.csv").exists());
}

/// How long a refusal of an endless or huge input may run before it counts as a hang: far longer
/// than any refusal takes on a loaded machine, far shorter than reading without a bound (never ends)
/// or simulating 1e12 s.
const HANG_GUARD: Duration = Duration::from_secs(120);

/// `host ARGS`, failing the test if it has not ended within [`HANG_GUARD`].
fn ended(args: &[&str]) -> (bool, String, String) {
    common::host_within(args, HANG_GUARD)
        .unwrap_or_else(|| panic!("{args:?} still running after {HANG_GUARD:?}: an unbounded read"))
}

// 2. A wrong calibration with exit 0.
#[test]
fn swapped_labels_give_no_calibration_and_name_the_swap() {
    let dir = tempfile::tempdir().unwrap();
    let plan = dir.path().join("six.toml");
    std::fs::write(&plan, SIX_POSITIONS).unwrap();
    let yz = session(dir.path(), "yz", s(&plan), &[]);
    swap_labels(&yz.join("samples.csv"), "y+", "z+");
    refused(
        host(&["-q", "calibrate", "--input", s(&yz)]),
        &[
            "not plausible",
            "degrees of freedom",
            "'y+' looks like 'z+'",
            "'z+' looks like 'y+'",
        ],
    );
    assert!(!yz.join("calibration.toml").exists() && !yz.join("calibration.bin").exists());
    let xx = session(dir.path(), "xx", s(&plan), &["--seed", "2"]);
    swap_labels(&xx.join("samples.csv"), "x+", "x-");
    refused(
        host(&["-q", "calibrate", "--input", s(&xx)]),
        &[
            "left-handed",
            "accelerometer 1 senses",
            "'x+' looks like 'x-'",
        ],
    );
    assert!(!xx.join("calibration.toml").exists());
    // The same plan with the right labels calibrates.
    let good = session(dir.path(), "good", s(&plan), &["--seed", "3"]);
    let (ok, _, stderr) = host(&["-q", "calibrate", "--input", s(&good)]);
    assert!(ok, "{stderr}");
}

// 3. A recording overwritten.
#[test]
fn the_live_procedure_never_records_over_an_earlier_run() {
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("d");
    let live = |extra: &[&str]| {
        let mut args = vec![
            "-q",
            "calibrate",
            "--port",
            "sim",
            "--plan",
            "quick-oblique",
            "--out-dir",
            s(&out),
        ];
        args.extend_from_slice(extra);
        host(&args)
    };
    let (ok, stdout, stderr) = live(&[]);
    assert!(ok, "{stdout}{stderr}");
    let csv = out.join("recording").join("samples.csv");
    let before = std::fs::read(&csv).unwrap();
    refused(live(&[]), &["already exists", "--force"]);
    assert_eq!(std::fs::read(&csv).unwrap(), before, "recording changed");
    let (ok, _, stderr) = live(&["--force"]);
    assert!(ok, "{stderr}");
    // Without --out-dir each run gets its own time-stamped directory.
    let cwd = dir.path().join("cwd");
    std::fs::create_dir(&cwd).unwrap();
    for _ in 0..2 {
        let (ok, _, stderr) = host_in(
            Some(&cwd),
            &[
                "-q",
                "calibrate",
                "--port",
                "sim",
                "--plan",
                "quick-oblique",
            ],
        );
        assert!(ok, "{stderr}");
    }
    let runs: Vec<String> = std::fs::read_dir(&cwd)
        .unwrap()
        .map(|e| e.unwrap().file_name().to_string_lossy().into_owned())
        .collect();
    assert_eq!(runs.len(), 2, "{runs:?}");
    for r in &runs {
        assert!(r.starts_with("calibration-") && r.contains('T'), "{r}");
        assert!(cwd.join(r).join("recording").join("samples.csv").exists());
    }
}

// 4. A calibration overwritten.
#[test]
fn a_calibration_is_replaced_only_with_force() {
    let dir = tempfile::tempdir().unwrap();
    let a = session(dir.path(), "a", "short", &[]);
    assert!(host(&["-q", "calibrate", "--input", s(&a)]).0);
    let first = std::fs::read(a.join("calibration.bin")).unwrap();
    let b = session(dir.path(), "b", "short", &["--seed", "9"]);
    refused(
        host(&["-q", "calibrate", "--input", s(&b), "--out-dir", s(&a)]),
        &["calibration.toml already exists", "--force"],
    );
    assert_eq!(std::fs::read(a.join("calibration.bin")).unwrap(), first);
    let (ok, _, stderr) = host(&[
        "-q",
        "calibrate",
        "--input",
        s(&b),
        "--out-dir",
        s(&a),
        "--force",
    ]);
    assert!(ok, "{stderr}");
    assert_ne!(std::fs::read(a.join("calibration.bin")).unwrap(), first);
}

// 5. Ramp segments (live): settled before the ramp starts, so the recorded mean rate is the plan's.
#[test]
fn a_live_ramp_records_the_planned_rates() {
    let dir = tempfile::tempdir().unwrap();
    let plan = dir.path().join("ramp.toml");
    let text = format!(
        "{}\n[[segment]]\nname = \"z+ ramp\"\nup_b = [0, 0, 1]\nrate_deg_s = 100\nrate_end_deg_s = 200\nduration_s = 1\n",
        include_str!("../../recording/plans/quick-oblique.toml")
    );
    std::fs::write(&plan, text).unwrap();
    let out = dir.path().join("o");
    let (_, stdout, stderr) = host(&[
        "-q",
        "calibrate",
        "--port",
        "sim",
        "--plan",
        s(&plan),
        "--out-dir",
        s(&out),
    ]);
    let csv = std::fs::read_to_string(out.join("recording").join("samples.csv"))
        .unwrap_or_else(|e| panic!("{e}: {stdout}{stderr}"));
    let rates: Vec<f64> = csv
        .lines()
        .filter_map(|l| l.strip_prefix("z+ ramp,"))
        .map(|l| {
            l.split(',')
                .nth(6)
                .unwrap()
                .parse::<f64>()
                .unwrap()
                .to_degrees()
        })
        .collect();
    assert!(rates.len() > 10);
    let mean = rates.iter().sum::<f64>() / rates.len() as f64;
    assert!((mean - 150.0).abs() < 3.0, "mean {mean} °/s, plan 150 °/s");
    assert!((rates[0] - 100.0).abs() < 5.0, "first {} °/s", rates[0]);
}

// 6. Unknown tables accepted in unit and calibration files.
#[test]
fn unknown_tables_in_unit_and_calibration_files_are_errors_with_line_and_column() {
    let dir = tempfile::tempdir().unwrap();
    let unit = std::fs::read_to_string(concat!(
        env!("CARGO_MANIFEST_DIR"),
        "/../reference/paper-unit.toml"
    ))
    .unwrap();
    let typo = dir.path().join("typo.toml");
    std::fs::write(&typo, unit.replace("[dynamic]", "[dynamc]")).unwrap();
    refused(
        host(&[
            "simulate",
            "--out",
            s(&dir.path().join("s")),
            "--unit",
            s(&typo),
        ]),
        &["unknown key or table 'dynamc'", "line 19, column 1"],
    );
    refused(
        host(&["flash", "--port", "sim", "--calibration", s(&typo)]),
        &["'dynamc'"],
    );
    let key = dir.path().join("key.toml");
    std::fs::write(&key, unit.replace("lever_arms_m", "lever_arm_m")).unwrap();
    refused(
        host(&["export", "--calibration", s(&key)]),
        &["lever_arm_m", "line"],
    );
}

// 7. "excluded (see the reasons above)" with no reasons; noise-free sessions classed as stuck.
#[test]
fn noise_free_sessions_calibrate_and_exclusions_come_with_reasons() {
    let dir = tempfile::tempdir().unwrap();
    let clean = session(dir.path(), "clean", "short", &["--no-noise"]);
    let (ok, stdout, stderr) = host(&["calibrate", "--input", s(&clean)]);
    assert!(ok, "{stdout}{stderr}");
    assert!(!stdout.contains("stuck"), "{stdout}");
    // A stuck output (one channel frozen, the others noisy) is still excluded, and when that leaves
    // no static segment the error lists each reason.
    let noisy = session(dir.path(), "noisy", "short", &[]);
    let csv = noisy.join("samples.csv");
    let text = std::fs::read_to_string(&csv).unwrap();
    let frozen: String = text
        .lines()
        .enumerate()
        .map(|(i, l)| {
            let mut f: Vec<String> = l.split(',').map(str::to_string).collect();
            if i > 0 {
                f[2] = "2.5".into();
            }
            f.join(",") + "\n"
        })
        .collect();
    std::fs::write(&csv, frozen).unwrap();
    let e = refused(
        host(&["-q", "calibrate", "--input", s(&noisy)]),
        &["0 static segments left of the 6 planned", "Left out (15):"],
    );
    assert!(
        e.contains("'x+': accelerometer x saturated or stuck"),
        "{e}"
    );
}

// 8. Panics reachable from the command line.
#[test]
fn closed_or_full_stdout_is_an_error_after_the_files_are_written() {
    let dir = tempfile::tempdir().unwrap();
    let a = session(dir.path(), "a", "short", &[]);
    // A pipe whose reader is gone (`| head` that has exited).
    let mut child = Command::new(env!("CARGO_BIN_EXE_host"))
        .args(["calibrate", "--input", s(&a)])
        .stdout(Stdio::piped())
        .stderr(Stdio::piped())
        .spawn()
        .unwrap();
    drop(child.stdout.take());
    let out = child.wait_with_output().unwrap();
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert_eq!(out.status.code(), Some(1), "{stderr}");
    assert!(stderr.contains("cannot write to standard output") && !stderr.contains("panicked"));
    assert!(a.join("calibration.toml").exists() && a.join("calibration.bin").exists());
    // A full disk.
    let b = session(dir.path(), "b", "short", &[]);
    let out = Command::new(env!("CARGO_BIN_EXE_host"))
        .args(["calibrate", "--input", s(&b)])
        .stdout(std::fs::File::create("/dev/full").unwrap())
        .output()
        .unwrap();
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert_eq!(out.status.code(), Some(1), "{stderr}");
    assert!(
        stderr.contains("No space left") && !stderr.contains("panicked"),
        "{stderr}"
    );
    assert!(b.join("calibration.bin").exists());
    refused(
        host(&[
            "calibrate",
            "--port",
            "sim",
            "--timeout-s",
            "1e300",
            "--out-dir",
            s(&dir.path().join("t")),
        ]),
        &["--timeout-s", "1e300 is out of range"],
    );
}

// 9. Unbounded numbers.
#[test]
fn nan_zero_and_negative_numbers_are_refused_before_any_work() {
    let dir = tempfile::tempdir().unwrap();
    let a = session(dir.path(), "a", "short", &[]);
    assert!(host(&["-q", "calibrate", "--input", s(&a)]).0);
    for v in ["NaN", "0", "-5", "inf"] {
        let flag = format!("--duration-s={v}");
        refused(
            host(&["report", "--input", s(&a), &flag, "--no-png"]),
            &["--duration-s"],
        );
        refused(host(&["navigation-check", &flag]), &["--duration-s"]);
    }
    assert!(!a.join("report").exists());
    for v in ["NaN", "-1", "0"] {
        let out = dir.path().join(format!("v{v}"));
        let flag = format!("--verify-tolerance-mg={v}");
        refused(
            host(&["calibrate", "--port", "sim", &flag, "--out-dir", s(&out)]),
            &["--verify-tolerance-mg", "out of range"],
        );
        assert!(!out.exists(), "work was done before the check");
    }
}

// 11. Misleading messages.
#[test]
fn messages_name_the_real_problem() {
    let dir = tempfile::tempdir().unwrap();
    let a = session(dir.path(), "a", "short", &[]);
    let csv = a.join("samples.csv");
    let mut bytes = std::fs::read(&csv).unwrap();
    let at = bytes.iter().position(|&b| b == b'\n').unwrap() + 1;
    bytes[at] = 0xFF;
    std::fs::write(&csv, &bytes).unwrap();
    refused(
        host(&["calibrate", "--input", s(&a)]),
        &["line 2 has bytes that are not UTF-8"],
    );
    let plan = std::fs::read_to_string(a.join("plan.toml")).unwrap();
    let check = |text: String, needles: &[&str]| {
        let p = dir.path().join("p.toml");
        std::fs::write(&p, text).unwrap();
        refused(host(&["plan", "--check", s(&p)]), needles);
    };
    check(
        plan.replacen(
            "mount = \"x+\"",
            "mount = \"x+\"\ntable_centre_m = [nan, 0, 0]",
            1,
        ),
        &["table_centre_m", "finite"],
    );
    check(
        plan.replacen("rate_deg_s = 100.0", "rate_deg_s = 1e9", 1),
        &["rate_deg_s = 1000000000", "beyond any rate table"],
    );
    check(
        format!("{plan}\n[[segment]]\nname = \"m1\"\nup_b = [1, 0, 0]\nmount = \"M\"\n[[segment]]\nname = \"m2\"\nup_b = [0, 1, 0]\nmount = \"M\"\n"),
        &["mount 'M'", "one mount has one up_b"],
    );
    check(
        format!("{plan}\n[[segment]]\nname = \"m1\"\nup_b = [1, 0, 0]\nmount = \"M\"\ntable_centre_m = [0, 0, 0]\n[[segment]]\nname = \"m2\"\nup_b = [1, 0, 0]\nmount = \"M\"\ntable_centre_m = [0.01, 0, 0]\n"),
        &["one mount has one table centre"],
    );
    refused(
        host(&[
            "calibrate",
            "--port",
            "sim",
            "--window",
            "0",
            "--out-dir",
            s(&dir.path().join("w")),
        ]),
        &["--window", "0 is out of range", "1..="],
    );
    // The unit id wherever a calibration meets data or another calibration.
    let b = session(dir.path(), "b", "short", &["--seed", "5"]);
    let (ok, _, stderr) = host(&["-q", "calibrate", "--input", s(&b)]);
    assert!(ok, "{stderr}");
    let bind = |dir: &Path, id: &str| {
        for f in ["plan.toml", "calibration.toml"] {
            let p = dir.join(f);
            let t = std::fs::read_to_string(&p).unwrap();
            let t = t.replace("unit_id = \"000000000000000000000000\"\n", "");
            std::fs::write(&p, format!("unit_id = \"{id}\"\n{t}")).unwrap();
        }
    };
    bind(&b, "0102030405060708090a0b0c");
    let other = dir.path().join("other.toml");
    let t = std::fs::read_to_string(b.join("calibration.toml")).unwrap();
    std::fs::write(
        &other,
        t.replace("0102030405060708090a0b0c", "0c0b0a090807060504030201"),
    )
    .unwrap();
    refused(
        host(&[
            "report",
            "--input",
            s(&b),
            "--calibration",
            s(&other),
            "--no-png",
        ]),
        &[
            "unit 0c0b0a090807060504030201",
            "the session is of unit 0102030405060708090a0b0c",
        ],
    );
    refused(
        host(&["compare", s(&b.join("calibration.toml")), s(&other)]),
        &["unit"],
    );
}

#[test]
fn a_silent_device_is_reported_in_plain_words() {
    let e = device::LinkError::Timeout {
        waiting_for: "an identity",
        after: Duration::from_secs(5),
    }
    .to_string();
    assert!(
        e.contains("waited 5.0 s for an identity and got nothing") && !e.contains("no an"),
        "{e}"
    );
}

// 12. Exports drop observability.
#[test]
fn exports_mark_lever_arms_the_plan_did_not_determine() {
    let dir = tempfile::tempdir().unwrap();
    let a = session(dir.path(), "a", "short", &[]);
    let (ok, stdout, stderr) = host(&["calibrate", "--input", s(&a)]);
    assert!(ok, "{stderr}");
    assert!(
        stdout.contains("n.d.") || stdout.contains("n.o."),
        "{stdout}"
    );
    let (ok, text, stderr) = host(&[
        "export",
        "--calibration",
        s(&a.join("calibration.toml")),
        "--format",
        "plain",
    ]);
    assert!(ok, "{stderr}");
    assert!(
        text.contains("NOT DETERMINED") && text.contains("nan"),
        "{text}"
    );
    // A plan that determines every component exports numbers only.
    let b = session(dir.path(), "b", "short-oblique", &[]);
    assert!(host(&["-q", "calibrate", "--input", s(&b)]).0);
    let (ok, text, _) = host(&["export", "--calibration", s(&b.join("calibration.toml"))]);
    assert!(
        ok && !text.contains("nan") && !text.contains("NOT DETERMINED"),
        "{text}"
    );
}

// 13. Exports that assumed a driver scale, wrote placeholders or files their consumer rejects.
#[test]
fn exports_refuse_what_their_consumer_cannot_take_and_say_what_to_give() {
    let unit = concat!(env!("CARGO_MANIFEST_DIR"), "/../reference/paper-unit.toml");
    let export = |args: &[&str]| {
        let mut all = vec!["export", "--calibration", unit];
        all.extend_from_slice(args);
        host(&all)
    };
    refused(
        export(&["--format", "ardupilot"]),
        &["output unit is V", "--driver-scale"],
    );
    refused(
        export(&["--format", "ardupilot", "--driver-scale", "1e-3"]),
        &["--device-id", "INS_ACC_ID", "3D Accel calibration needed"],
    );
    let out_of_range = [
        "--format",
        "ardupilot",
        "--driver-scale",
        "1e-3",
        "--device-id",
        "3932170",
    ];
    refused(
        export(&out_of_range),
        &["INS_ACCSCAL_X", "0.8..1.2", "--allow-out-of-range"],
    );
    let (ok, _, stderr) = export(&[&out_of_range[..], &["--allow-out-of-range"]].concat());
    assert!(ok && stderr.contains("warning: INS_ACCSCAL_X"), "{stderr}");
    refused(
        export(&["--format", "px4", "--driver-scale", "24.5"]),
        &["--device-id"],
    );
    refused(
        export(&[
            "--format",
            "px4",
            "--device-id",
            "1",
            "--driver-scale",
            "-2",
        ]),
        &["-2 is out of range: give a number in [1e-9, 1e6]"],
    );
    let e = refused(
        export(&[
            "--format",
            "px4",
            "--device-id",
            "1",
            "--driver-scale",
            "1e300",
        ]),
        &["1e300 is out of range"],
    );
    assert!(!e.contains("zero scale factor"), "{e}");
    refused(export(&["--format", "kalibr"]), &["host noise", "--noise"]);
    refused(export(&["--format", "c"]), &["--out DIR"]);
}
