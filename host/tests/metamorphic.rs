//! Metamorphic tests: a valid recording, transformed the way a real one goes wrong (two columns
//! swapped, a sign, a unit, the time base, a glitch, a gap, a cut), must end in a refusal (nonzero
//! exit, a message naming the cause) or a flag (a warning in the JSON result naming the place),
//! never in `passed: true` with exit 0 and nothing said. Each transformation is tried through
//! `host segment` → `host calibrate` (a logger's hand-held CSV) and through `host calibrate --input`
//! (a table session). The table of outcomes is in docs/robustness.md.

use std::path::{Path, PathBuf};

mod common;
use common::{hand_segment_args, host};

/// What a pipeline ended in.
#[derive(Debug)]
enum Outcome {
    /// Nonzero exit; the error message.
    Refused(String),
    /// Exit 0 with these warnings in the JSON document (or on stderr for segment).
    Passed { passed: bool, warnings: String },
}

fn s(p: &Path) -> &str {
    p.to_str().unwrap()
}

/// A column transformation of a CSV's data rows (the header names the columns).
type Edit<'a> = &'a dyn Fn(&mut Vec<String>, &dyn Fn(&str) -> usize, usize);

/// Rewrites `src` into `dst` with `edit` applied to every data row (fields as strings).
fn transform(src: &Path, dst: &Path, edit: Edit<'_>) {
    let text = std::fs::read_to_string(src).unwrap();
    let mut lines = text.lines();
    let header = lines.next().unwrap();
    let names: Vec<&str> = header.split(',').collect();
    let col = |n: &str| names.iter().position(|c| *c == n).unwrap();
    let mut out = format!("{header}\n");
    for (k, l) in lines.enumerate() {
        let mut f: Vec<String> = l.split(',').map(String::from).collect();
        edit(&mut f, &col, k);
        out.push_str(&f.join(","));
        out.push('\n');
    }
    std::fs::write(dst, out).unwrap();
}

fn negate(f: &mut [String], i: usize) {
    f[i] = format!("{}", -f[i].parse::<f64>().unwrap());
}

fn scale(f: &mut [String], i: usize, by: f64) {
    f[i] = format!("{}", f[i].parse::<f64>().unwrap() * by);
}

/// Calibrates a session directory with `--json`.
fn calibrate(dir: &Path) -> Outcome {
    let (ok, stdout, stderr) = host(&["calibrate", "--input", s(dir), "--json", "--force"]);
    if !ok {
        assert!(stderr.contains("error: "), "{stderr}");
        assert!(!stderr.contains("panicked"), "{stderr}");
        return Outcome::Refused(stderr);
    }
    let v: serde_json::Value = serde_json::from_str(&stdout).unwrap();
    Outcome::Passed {
        passed: v["passed"] == true,
        warnings: v["warnings"].to_string(),
    }
}

/// The logger path: a simulated hand-held CSV, transformed, through segment and calibrate.
fn logger(name: &str, units: (&str, &str), edit: Option<Edit<'_>>) -> Outcome {
    let dir = tempfile::tempdir().unwrap();
    let csv = dir.path().join("hand.csv");
    let (ok, _, e) = host(&["-q", "simulate-hand", "--out", s(&csv), "--seed", "4"]);
    assert!(ok, "{e}");
    let input = match edit {
        Some(edit) => {
            let t = dir.path().join(format!("{name}.csv"));
            transform(&csv, &t, edit);
            t
        }
        None => csv,
    };
    let out = dir.path().join("session");
    // `--json`: segment's own warnings (e.g. a time jump it kept out of every segment) reach the
    // outcome through its document, which `-q` still writes.
    let (ok, document, stderr) = host(&[
        "-q",
        "segment",
        "--json",
        "--input",
        s(&input),
        "--out",
        s(&out),
        "--time-column",
        "t",
        "--acc-unit",
        units.0,
        "--gyro-unit",
        units.1,
    ]);
    if !ok {
        assert!(stderr.contains("error: "), "{stderr}");
        assert!(!out.exists(), "a refused segment leaves no session");
        return Outcome::Refused(stderr);
    }
    let outcome = calibrate(&out);
    if let Outcome::Passed { passed, warnings } = outcome {
        return Outcome::Passed {
            passed,
            warnings: format!("{warnings} {stderr} {document}"),
        };
    }
    outcome
}

/// The table path: a simulated session of the `short` plan (six ±1 g positions, nine spins),
/// transformed, through calibrate --input.
fn table(edit: Option<Edit<'_>>, plan_edit: Option<&dyn Fn(String) -> String>) -> Outcome {
    table_plan("short", edit, plan_edit)
}

/// [`table`] on the built-in plan `plan`.
fn table_plan(
    plan: &str,
    edit: Option<Edit<'_>>,
    plan_edit: Option<&dyn Fn(String) -> String>,
) -> Outcome {
    let dir = tempfile::tempdir().unwrap();
    let session = dir.path().join("s");
    let (ok, _, e) = host(&["-q", "simulate", "--out", s(&session), "--plan", plan]);
    assert!(ok, "{e}");
    table_of(&session, edit, plan_edit)
}

fn table_of(
    session: &Path,
    edit: Option<Edit<'_>>,
    plan_edit: Option<&dyn Fn(String) -> String>,
) -> Outcome {
    let samples = session.join("samples.csv");
    if let Some(edit) = edit {
        let t = session.join("edited.csv");
        transform(&samples, &t, edit);
        std::fs::rename(&t, &samples).unwrap();
    }
    if let Some(pe) = plan_edit {
        let p = session.join("plan.toml");
        let text = std::fs::read_to_string(&p).unwrap();
        std::fs::write(&p, pe(text)).unwrap();
    }
    calibrate(session)
}

/// Refused, the message containing every needle.
fn assert_refused(o: &Outcome, needles: &[&str]) {
    match o {
        Outcome::Refused(m) => {
            for n in needles {
                assert!(m.contains(n), "'{n}' not in: {m}");
            }
            eprintln!("refused: {m}");
        }
        other => panic!("accepted: {other:?}"),
    }
}

#[test]
fn the_untransformed_recordings_calibrate_and_pass() {
    for o in [logger("clean", ("m/s2", "deg/s"), None), table(None, None)] {
        match o {
            Outcome::Passed { passed: true, .. } => {}
            other => panic!("{other:?}"),
        }
    }
}

#[test]
fn two_accelerometer_axes_swapped() {
    let swap: Edit<'_> = &|f, c, _| f.swap(c("acc_x"), c("acc_y"));
    assert_refused(
        &logger("swap_acc", ("m/s2", "deg/s"), Some(swap)),
        &["swapped"],
    );
    let swap: Edit<'_> = &|f, c, _| f.swap(c("u_x"), c("u_y"));
    assert_refused(&table(Some(swap), None), &["not plausible"]);
}

#[test]
fn one_accelerometer_axis_negated() {
    let neg: Edit<'_> = &|f, c, _| negate(f, c("acc_y"));
    assert_refused(&logger("neg_acc", ("m/s2", "deg/s"), Some(neg)), &["sign"]);
    let neg: Edit<'_> = &|f, c, _| negate(f, c("u_y"));
    assert_refused(&table(Some(neg), None), &["left-handed"]);
}

#[test]
fn one_gyro_axis_negated() {
    let neg: Edit<'_> = &|f, c, _| negate(f, c("gyr_z"));
    assert_refused(
        &logger("neg_gyro", ("m/s2", "deg/s"), Some(neg)),
        &["gyro fit is refused"],
    );
    let neg: Edit<'_> = &|f, c, _| negate(f, c("w_z"));
    assert_refused(&table(Some(neg), None), &["sign reversed"]);
}

/// On the oblique plans a negated column reads −1 on its own axis's spins but 0 on the spins
/// between it and another axis: every spin still names the one column, and nothing is half kept.
#[test]
fn one_gyro_axis_negated_on_the_oblique_plans() {
    for plan in ["short-oblique", "quick-oblique"] {
        for (column, axis) in [("w_x", "x"), ("w_y", "y"), ("w_z", "z")] {
            let neg: Edit<'_> = &|f, c, _| negate(f, c(column));
            let o = table_plan(plan, Some(neg), None);
            let needle = format!("gyro's {axis} column has its sign reversed");
            eprintln!("{plan}, {column} negated:");
            assert_refused(&o, &[needle.as_str()]);
        }
    }
}

#[test]
fn two_gyro_axes_swapped() {
    let swap: Edit<'_> = &|f, c, _| f.swap(c("gyr_x"), c("gyr_y"));
    assert_refused(
        &logger("swap_gyro", ("m/s2", "deg/s"), Some(swap)),
        &["swapped"],
    );
    let swap: Edit<'_> = &|f, c, _| f.swap(c("w_x"), c("w_y"));
    assert_refused(&table(Some(swap), None), &["swapped"]);
}

#[test]
fn time_scaled_by_one_and_a_half() {
    // The logger path: the turns look 1.5× longer on every axis, as a gyro whose nominal scale is
    // 1.5× would: a result, flagged with both causes and the rate the stamps would need.
    let slow: Edit<'_> = &|f, c, _| scale(f, c("t"), 1.5);
    match logger("time", ("m/s2", "deg/s"), Some(slow)) {
        Outcome::Passed { warnings, .. } => {
            assert!(
                warnings.contains("on all three axes")
                    && warnings.contains("nominal scale is off")
                    && warnings.contains("would have to step at 200."),
                "{warnings}"
            );
            eprintln!("flagged: {warnings}");
        }
        other => panic!("{other:?}"),
    }
    let slow: Edit<'_> = &|f, c, _| scale(f, c("t_s"), 1.5);
    assert_refused(&table(Some(slow), None), &["time stamps", "666.667 Hz"]);
}

#[test]
fn metres_per_second_squared_declared_as_g() {
    assert_refused(&logger("as_g", ("g", "deg/s"), None), &["--acc-unit m/s2"]);
    // The table session is in volts: declared as g.
    let as_g = |p: String| p.replace("output_unit = \"V\"", "output_unit = \"g\"");
    assert_refused(&table(None, Some(&as_g)), &["output_unit"]);
}

#[test]
fn degrees_per_second_declared_as_radians() {
    assert_refused(&logger("as_rad", ("m/s2", "rad/s"), None), &["error"]);
    // The table session's gyro written in °/s where the format says rad/s.
    let deg: Edit<'_> = &|f, c, _| {
        for n in ["w_x", "w_y", "w_z"] {
            scale(f, c(n), 180.0 / std::f64::consts::PI);
        }
    };
    assert_refused(&table(Some(deg), None), &["57.3"]);
}

#[test]
fn a_ten_second_time_gap() {
    let gap: Edit<'_> = &|f, c, k| {
        if k >= 15_000 {
            scale(f, c("t"), 1.0);
            let t = f[c("t")].parse::<f64>().unwrap() + 10.0;
            f[c("t")] = format!("{t}");
        }
    };
    match logger("gap", ("m/s2", "deg/s"), Some(gap)) {
        // Inside a turn: the gyro fit is refused; inside a still position: flagged with its place.
        Outcome::Refused(m) => assert!(m.contains("gap"), "{m}"),
        Outcome::Passed { warnings, .. } => {
            // Flagged with its place: by segment, which keeps it out of every still interval and
            // turn ("after data row"), or by the session's reader if a segment spans it.
            assert!(
                warnings.contains("time stamps jump")
                    && (warnings.contains("first at line") || warnings.contains("after data row")),
                "{warnings}"
            );
        }
    }
    // In the middle of a table segment: flagged with its place.
    let gap: Edit<'_> = &|f, c, k| {
        if k >= 1000 {
            let t = f[c("t_s")].parse::<f64>().unwrap() + 10.0;
            f[c("t_s")] = format!("{t}");
        }
    };
    match table(Some(gap), None) {
        Outcome::Refused(m) => eprintln!("refused: {m}"),
        Outcome::Passed { warnings, .. } => {
            assert!(
                warnings.contains("jump") && warnings.contains("line 1002"),
                "{warnings}"
            );
            eprintln!("flagged: {warnings}");
        }
    }
}

#[test]
fn a_truncated_last_line() {
    let cut = |p: &Path| {
        let text = std::fs::read(p).unwrap();
        std::fs::write(p, &text[..text.len() - 9]).unwrap();
    };
    let dir = tempfile::tempdir().unwrap();
    let csv = dir.path().join("hand.csv");
    assert!(host(&["-q", "simulate-hand", "--out", s(&csv), "--seed", "4"]).0);
    cut(&csv);
    let out = dir.path().join("session");
    let (ok, _, stderr) = host(&hand_segment_args(s(&csv), s(&out)));
    // The logger's CSV: the cut line is left out, flagged with its number.
    assert!(ok, "{stderr}");
    assert!(
        stderr.contains("has no line end: the file was cut short"),
        "{stderr}"
    );
    let session: PathBuf = dir.path().join("s");
    assert!(host(&["-q", "simulate", "--out", s(&session), "--plan", "short"]).0);
    cut(&session.join("samples.csv"));
    assert_refused(&calibrate(&session), &["cut short"]);
}

#[test]
fn a_temperature_glitch() {
    // A soak session (the built-in plan, shortened): one reading of 150 °C among 60 000.
    let dir = tempfile::tempdir().unwrap();
    let plan = dir.path().join("plan.toml");
    let text = std::fs::read_to_string(concat!(
        env!("CARGO_MANIFEST_DIR"),
        "/../recording/plans/thermal-soak.toml"
    ))
    .unwrap();
    std::fs::write(&plan, text.replace("duration_s = 20", "duration_s = 2")).unwrap();
    let session = dir.path().join("s");
    let (ok, _, e) = host(&[
        "-q",
        "simulate",
        "--out",
        s(&session),
        "--plan",
        s(&plan),
        "--unit",
        concat!(env!("CARGO_MANIFEST_DIR"), "/units/thermal-mems.toml"),
    ]);
    assert!(ok, "{e}");
    let glitch: Edit<'_> = &|f, c, k| {
        if k == 30_000 {
            f[c("temp_c")] = "150".into();
        }
    };
    match table_of(&session, Some(glitch), None) {
        Outcome::Passed { passed, warnings } => {
            assert!(passed, "{warnings}");
            assert!(
                warnings.contains("150 °C") && warnings.contains("line 30002"),
                "{warnings}"
            );
            eprintln!("flagged: {warnings}");
        }
        Outcome::Refused(m) => panic!("the glitch is left out, not the session: {m}"),
    }
    let cal: toml::Value =
        toml::from_str(&std::fs::read_to_string(session.join("calibration.toml")).unwrap())
            .unwrap();
    let high = cal["temperature"]["valid_range_c"][1].as_float().unwrap();
    assert!(high < 61.0, "the glitch stretched the range to {high} °C");
    // The logger's importer reads no temperature column: the transformation does not apply there.
}
