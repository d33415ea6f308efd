//! Where a calibration meets a recording (`apply`, `noise`, `report`), the output unit, the unit and
//! the physics are checked first: a calibration of another output unit, a temperature model without
//! a temperature, or a result that is not 1 g at rest is an error naming both sides and the fix,
//! never a wrong file with exit 0. And `host segment` replaces its directory whole or not at all.

use std::path::{Path, PathBuf};
use std::process::{Command, Stdio};
use std::time::Duration;

mod common;
use common::{hand_segment_args, host};

fn s(p: &Path) -> &str {
    p.to_str().unwrap()
}

fn refused(result: (bool, String, String), needles: &[&str]) {
    let (ok, stdout, stderr) = result;
    assert!(!ok, "accepted: {stdout}\n{stderr}");
    assert!(!stderr.contains("panicked"), "{stderr}");
    for n in needles {
        assert!(stderr.contains(n), "'{n}' not in: {stderr}");
    }
}

/// A table session of the `short` plan (volts) and its calibration.
fn table_session(dir: &Path) -> (PathBuf, PathBuf) {
    let session = dir.join("table");
    assert!(host(&["-q", "simulate", "--out", s(&session), "--plan", "short"]).0);
    let (ok, _, e) = host(&["-q", "calibrate", "--input", s(&session)]);
    assert!(ok, "{e}");
    let cal = session.join("calibration.toml");
    (session, cal)
}

/// A hand-held session (m/s²) segmented from a simulated logger CSV, and its calibration.
fn hand_session(dir: &Path) -> (PathBuf, PathBuf) {
    let csv = dir.join("hand.csv");
    assert!(host(&["-q", "simulate-hand", "--out", s(&csv)]).0);
    let session = dir.join("hand");
    let (ok, _, e) = host(&hand_segment_args(s(&csv), s(&session)));
    assert!(ok, "{e}");
    let (ok, _, e) = host(&["-q", "calibrate", "--input", s(&session)]);
    assert!(ok, "{e}");
    (session.clone(), session.join("calibration.toml"))
}

#[test]
fn apply_noise_and_report_refuse_a_calibration_of_another_output_unit() {
    let dir = tempfile::tempdir().unwrap();
    let (table, _) = table_session(dir.path());
    let (_, hand_cal) = hand_session(dir.path());
    let out = dir.path().join("applied.csv");
    refused(
        host(&[
            "apply",
            "--calibration",
            s(&hand_cal),
            "--input",
            s(&table),
            "--out",
            s(&out),
        ]),
        &["in m/s2 but the recording is in V"],
    );
    assert!(!out.exists());
    refused(
        host(&["noise", "--input", s(&table), "--calibration", s(&hand_cal)]),
        &["in m/s2 but the recording is in V"],
    );
    refused(
        host(&[
            "report",
            "--input",
            s(&table),
            "--calibration",
            s(&hand_cal),
            "--out-dir",
            s(&dir.path().join("r")),
        ]),
        &["in m/s2 but the session is in V"],
    );
}

#[test]
fn a_calibration_that_does_not_give_one_g_at_rest_is_refused() {
    let dir = tempfile::tempdir().unwrap();
    let (table, cal) = table_session(dir.path());
    let good = host(&[
        "apply",
        "--calibration",
        s(&cal),
        "--input",
        s(&table),
        "--out",
        s(&dir.path().join("a.csv")),
    ]);
    assert!(good.0, "{}", good.2);
    // The same output unit, another scale (another unit's file, edited by hand): 0.8 g at rest.
    let mut unit: toml::Value = toml::from_str(&std::fs::read_to_string(&cal).unwrap()).unwrap();
    let k = unit["static"]["scale_v_per_g"].as_array_mut().unwrap();
    for v in k.iter_mut() {
        *v = toml::Value::Float(v.as_float().unwrap() * 1.25);
    }
    let wrong = dir.path().join("wrong.toml");
    std::fs::write(&wrong, toml::to_string(&unit).unwrap()).unwrap();
    refused(
        host(&[
            "apply",
            "--calibration",
            s(&wrong),
            "--input",
            s(&table),
            "--out",
            s(&dir.path().join("b.csv")),
        ]),
        &["not 1 g"],
    );
    refused(
        host(&["noise", "--input", s(&table), "--calibration", s(&wrong)]),
        &["not 1 g"],
    );
}

#[test]
fn a_temperature_model_needs_a_temperature() {
    let dir = tempfile::tempdir().unwrap();
    let (table, _) = table_session(dir.path());
    let thermal = concat!(env!("CARGO_MANIFEST_DIR"), "/units/thermal-mems.toml");
    let out = dir.path().join("a.csv");
    refused(
        host(&[
            "apply",
            "--calibration",
            thermal,
            "--input",
            s(&table),
            "--out",
            s(&out),
        ]),
        &["no temp_c column", "--temperature-c"],
    );
    // Said: applied at that temperature (the unit file is the simulator's truth, not this unit's
    // calibration, so only the refusal and its fix are checked here).
    let (_, _, stderr) = host(&[
        "apply",
        "--calibration",
        thermal,
        "--input",
        s(&table),
        "--out",
        s(&out),
        "--temperature-c",
        "25",
    ]);
    assert!(!stderr.contains("no temp_c column"), "{stderr}");
    refused(
        host(&[
            "apply",
            "--calibration",
            thermal,
            "--input",
            s(&table),
            "--temperature-c",
            "NaN",
        ]),
        &["--temperature-c"],
    );
}

#[test]
fn apply_never_writes_over_its_own_input() {
    let dir = tempfile::tempdir().unwrap();
    let (table, cal) = table_session(dir.path());
    let before = std::fs::read(table.join("samples.csv")).unwrap();
    refused(
        host(&[
            "apply",
            "--calibration",
            s(&cal),
            "--input",
            s(&table),
            "--out",
            s(&table.join("samples.csv")),
            "--force",
        ]),
        &["recording's own samples.csv"],
    );
    assert_eq!(std::fs::read(table.join("samples.csv")).unwrap(), before);
}

/// A 200 Hz log read as 300 Hz: the turns look a third shorter on every axis, which a gyro whose
/// nominal scale is a third off would show as well. The turns cannot tell the two apart: the session
/// is written with a warning that names both, each with its figure (the rate the rows would need).
#[test]
fn a_wrong_sample_rate_is_named_with_the_rate_it_implies() {
    let dir = tempfile::tempdir().unwrap();
    let csv = dir.path().join("hand.csv");
    assert!(host(&["-q", "simulate-hand", "--out", s(&csv)]).0);
    let out = dir.path().join("s");
    let (ok, _, stderr) = host(&[
        "segment",
        "--input",
        s(&csv),
        "--out",
        s(&out),
        "--rate-hz",
        "300",
        "--acc-unit",
        "m/s2",
        "--gyro-unit",
        "deg/s",
    ]);
    assert!(ok, "{stderr}");
    for needle in [
        "on all three axes",
        "the gyro's nominal scale is off: its values are 0.66",
        "the rows would have to come at 200.",
        "not the --rate-hz 300",
        "give the true --rate-hz and segment again",
    ] {
        assert!(stderr.contains(needle), "'{needle}' not in: {stderr}");
    }
    assert!(out.join("gyro.toml").exists());
}

#[test]
fn segment_force_replaces_the_whole_directory() {
    let dir = tempfile::tempdir().unwrap();
    let (session, cal) = hand_session(dir.path());
    assert!(cal.exists() && session.join("gyro.toml").exists());
    // The same directory again, from a log whose gyro fit fails: refused, the old session intact.
    let bad = dir.path().join("bad.csv");
    let text = std::fs::read_to_string(dir.path().join("hand.csv")).unwrap();
    let swapped: String = text
        .lines()
        .enumerate()
        .map(|(k, l)| {
            let mut f: Vec<&str> = l.split(',').collect();
            if k > 0 {
                f.swap(4, 5);
            }
            f.join(",") + "\n"
        })
        .collect();
    std::fs::write(&bad, swapped).unwrap();
    let args = |input: &Path| {
        vec![
            "segment".to_string(),
            "--input".into(),
            s(input).into(),
            "--out".into(),
            s(&session).into(),
            "--time-column".into(),
            "t".into(),
            "--acc-unit".into(),
            "m/s2".into(),
            "--gyro-unit".into(),
            "deg/s".into(),
            "--force".into(),
        ]
    };
    let run = |a: Vec<String>| host(&a.iter().map(String::as_str).collect::<Vec<_>>());
    refused(run(args(&bad)), &["gyro fit is refused"]);
    assert!(
        cal.exists(),
        "a refused run leaves the earlier directory as it was"
    );
    // A good run with --force: the earlier calibration (derived from the old data) is gone.
    let (ok, _, e) = run(args(&dir.path().join("hand.csv")));
    assert!(ok, "{e}");
    assert!(!cal.exists(), "a stale calibration.toml survived --force");
    assert!(session.join("gyro.toml").exists());
    // A directory holding something else is never replaced.
    std::fs::write(session.join("notes.txt"), "mine").unwrap();
    refused(run(args(&dir.path().join("hand.csv"))), &["notes.txt"]);
}

#[test]
fn segment_interrupted_leaves_nothing_that_calibrate_accepts() {
    let dir = tempfile::tempdir().unwrap();
    let csv = dir.path().join("hand.csv");
    assert!(host(&["-q", "simulate-hand", "--out", s(&csv)]).0);
    for delay_ms in [20, 80, 160, 320] {
        let out = dir.path().join(format!("s{delay_ms}"));
        let mut child = Command::new(env!("CARGO_BIN_EXE_host"))
            .arg("-q")
            .args(hand_segment_args(s(&csv), s(&out)))
            .stdout(Stdio::null())
            .stderr(Stdio::null())
            .spawn()
            .unwrap();
        std::thread::sleep(Duration::from_millis(delay_ms));
        // SIGINT, as Ctrl-C sends it.
        let _ = Command::new("kill")
            .args(["-INT", &child.id().to_string()])
            .status();
        let status = child.wait().unwrap();
        if status.success() {
            // It finished first: then the session is whole.
            assert!(host(&["-q", "calibrate", "--input", s(&out)]).0);
        } else {
            assert!(
                !out.exists(),
                "an interrupted segment left {}",
                out.display()
            );
        }
    }
}

#[test]
fn segment_binds_the_unit_and_the_sites_gravity() {
    let dir = tempfile::tempdir().unwrap();
    let csv = dir.path().join("hand.csv");
    assert!(host(&["-q", "simulate-hand", "--out", s(&csv)]).0);
    let id = "0123456789abcdef01234567";
    let mut g = Vec::new();
    for lat in ["0", "60"] {
        let out = dir.path().join(format!("lat{lat}"));
        let mut args = hand_segment_args(s(&csv), s(&out));
        args.extend(["--unit-id", id, "--latitude", lat, "-q"]);
        let (ok, _, e) = host(&args);
        assert!(ok, "{e}");
        let (ok, _, e) = host(&["-q", "calibrate", "--input", s(&out)]);
        assert!(ok, "{e}");
        assert!(!e.contains("no unit_id"), "{e}");
        let cal: toml::Value =
            toml::from_str(&std::fs::read_to_string(out.join("calibration.toml")).unwrap())
                .unwrap();
        assert_eq!(cal["unit_id"].as_str(), Some(id));
        g.push(cal["g_m_s2"].as_float().unwrap());
    }
    // WGS 84 normal gravity at the equator and at 60°: the m/s² output scales with it.
    assert!((g[0] - 9.780_325_3).abs() < 1e-6, "{g:?}");
    assert!((g[1] - 9.819_177_0).abs() < 1e-6, "{g:?}");
    assert!((g[1] / g[0] - 1.003_972_4).abs() < 1e-6, "{g:?}");
    refused(
        host(&[
            "segment",
            "--input",
            s(&csv),
            "--out",
            s(&dir.path().join("x")),
            "--time-column",
            "t",
            "--acc-unit",
            "m/s2",
            "--gyro-unit",
            "deg/s",
            "--unit-id",
            "12zz",
        ]),
        &["--unit-id 12zz", "24 hex digits"],
    );
    // The all-zero id binds nothing (flash refuses it): refused before anything is read.
    let zero = dir.path().join("zero");
    let mut args = hand_segment_args(s(&csv), s(&zero));
    args.extend(["--unit-id", "000000000000000000000000"]);
    refused(host(&args), &["all-zero id", "host read"]);
    assert!(!zero.exists());
}

/// The simulated device's unit id (`--port sim`).
const SIM_UNIT_ID: &str = "53494d2d50415045522d3031";

/// A calibration whose x scale factor is negated compensates x with the wrong sign while |f| stays
/// 1 g at rest: `apply` refuses it as `export` does, and `flash` names the scale factor (it said
/// "zero scale factor").
#[test]
fn a_negated_scale_factor_is_refused_where_the_calibration_meets_anything() {
    let dir = tempfile::tempdir().unwrap();
    let (session, cal) = table_session(dir.path());
    let text = std::fs::read_to_string(&cal).unwrap();
    let at = text.find("scale_v_per_g = [").unwrap() + "scale_v_per_g = [".len();
    let first = text[at..].trim_start();
    let negated = format!("{}-{first}", &text[..text.len() - text[at..].len()]);
    let bad = dir.path().join("negated.toml");
    std::fs::write(&bad, &negated).unwrap();
    refused(
        host(&["apply", "--calibration", s(&bad), "--input", s(&session)]),
        &["accelerometer x has a negative scale factor", "positive"],
    );
    // The unmodified file applies: the refusal is the sign's.
    assert!(
        host(&[
            "-q",
            "apply",
            "--calibration",
            s(&cal),
            "--input",
            s(&session)
        ])
        .0
    );
    refused(
        host(&["flash", "--port", "sim", "--calibration", s(&bad)]),
        &["accelerometer x has a negative scale factor"],
    );
}

/// A calibration in m/s² (a logger's session bound to the simulated device's id) is not flashed onto
/// the simulated device, whose outputs are volts: both units are named.
#[test]
fn flash_refuses_a_calibration_of_another_output_unit() {
    let dir = tempfile::tempdir().unwrap();
    let csv = dir.path().join("hand.csv");
    assert!(host(&["-q", "simulate-hand", "--out", s(&csv)]).0);
    let session = dir.path().join("hand");
    let mut args = hand_segment_args(s(&csv), s(&session));
    args.extend(["--unit-id", SIM_UNIT_ID]);
    let (ok, _, e) = host(&args);
    assert!(ok, "{e}");
    let (ok, _, e) = host(&["-q", "calibrate", "--input", s(&session)]);
    assert!(ok, "{e}");
    for file in ["calibration.toml", "calibration.bin"] {
        refused(
            host(&[
                "flash",
                "--port",
                "sim",
                "--calibration",
                s(&session.join(file)),
            ]),
            &["outputs in m/s2", "the device is in V"],
        );
    }
}

/// `apply` of a logger's CSV whose gyro is in °/s, declared rad/s: no interval is still (the gyro
/// moves 57× a still gyro's), and the rest check that would have caught it is not skipped for that:
/// refused, nothing written. Declared right, the same file applies.
#[test]
fn a_gyro_in_the_wrong_unit_is_refused_even_where_nothing_is_still() {
    let dir = tempfile::tempdir().unwrap();
    let (_, cal) = hand_session(dir.path());
    let csv = dir.path().join("hand.csv");
    let apply = |unit: &str, out: &Path| {
        host(&[
            "apply",
            "--calibration",
            s(&cal),
            "--input",
            s(&csv),
            "--time-column",
            "t",
            "--acc-unit",
            "m/s2",
            "--gyro-unit",
            unit,
            "--out",
            s(out),
        ])
    };
    let good = dir.path().join("good.csv");
    let (ok, _, e) = apply("deg/s", &good);
    assert!(ok, "{e}");
    let wrong = dir.path().join("wrong.csv");
    refused(
        apply("rad/s", &wrong),
        &["no stretch of the recording is at rest", "57×"],
    );
    assert!(!wrong.exists());
}

/// A directory holds one result: a failing run (a bias limit no unit meets) leaves its failed
/// pair; a passing `--force` run then replaces it with the accepted pair, and a failing `--force`
/// run the accepted pair with a failed one.
#[test]
fn a_directory_holds_one_result() {
    let dir = tempfile::tempdir().unwrap();
    let session = dir.path().join("table");
    assert!(host(&["-q", "simulate", "--out", s(&session), "--plan", "short"]).0);
    let names = |d: &Path| {
        let mut v: Vec<String> = std::fs::read_dir(d)
            .unwrap()
            .map(|e| e.unwrap().file_name().to_string_lossy().into_owned())
            .filter(|n| n.starts_with("calibration"))
            .collect();
        v.sort();
        v
    };
    let failing = [
        "-q",
        "calibrate",
        "--input",
        s(&session),
        "--max-bias-mg",
        "0.000001",
    ];
    let (ok, _, _) = host(&failing);
    assert!(!ok);
    assert_eq!(
        names(&session),
        ["calibration.FAILED.bin", "calibration.FAILED.toml"]
    );
    let (ok, _, e) = host(&["-q", "calibrate", "--input", s(&session), "--force"]);
    assert!(ok, "{e}");
    assert_eq!(names(&session), ["calibration.bin", "calibration.toml"]);
    let mut forced = failing.to_vec();
    forced.push("--force");
    assert!(!host(&forced).0);
    assert_eq!(
        names(&session),
        ["calibration.FAILED.bin", "calibration.FAILED.toml"]
    );
}

/// The hand plan on the virtual table calibrates in a conventional body frame (no attitude is
/// known), not the table's: verified in the table's frame it failed at 4.6–13 mg (exit 3) although
/// the calibration is right. It is verified after the best common rotation, and says so.
#[test]
fn a_calibration_in_a_conventional_frame_is_verified_in_its_own_frame() {
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("hand");
    let (ok, stdout, stderr) = host(&[
        "calibrate",
        "--port",
        "sim",
        "--plan",
        "hand",
        "--out-dir",
        s(&out),
    ]);
    assert!(ok, "{stdout}\n{stderr}");
    let all = format!("{stdout}\n{stderr}");
    assert!(all.contains("body frame is a convention"), "{all}");
    let lines: Vec<&str> = all
        .lines()
        .filter(|l| l.starts_with("verify ") && l.contains("(frame-free)"))
        .collect();
    assert_eq!(lines.len(), 3, "{all}");
    assert!(lines.iter().all(|l| l.ends_with("ok")), "{lines:?}");
}

/// `navigation-check` on a plan whose positions are all held by hand has nothing to replay: it
/// printed an empty table, exit 0. It fails naming why; a plan with static positions but no
/// spin names the replay it leaves out under its table.
#[test]
fn an_empty_navigation_table_says_why() {
    let (ok, stdout, stderr) = host(&["navigation-check", "--plan", "hand"]);
    assert!(!ok, "{stdout}");
    assert!(
        stderr.contains("nothing to replay") && stderr.contains("held by hand"),
        "{stderr}"
    );
    let dir = tempfile::tempdir().unwrap();
    let plan = dir.path().join("still.toml");
    let short = Path::new(env!("CARGO_MANIFEST_DIR")).join("../recording/plans/short.toml");
    let short = std::fs::read_to_string(short).unwrap();
    // The six positions without the spins.
    let still: String = short
        .split("[[segment]]")
        .filter(|block| !block.contains("rate_deg_s"))
        .collect::<Vec<_>>()
        .join("[[segment]]");
    std::fs::write(&plan, still).unwrap();
    let (ok, stdout, stderr) = host(&["navigation-check", "--plan", s(&plan)]);
    assert!(ok, "{stderr}");
    assert!(
        stdout.contains("left out: no constant-rate segment"),
        "{stdout}"
    );
}
