//! Where a calibration meets something, every mismatch is refused: each meeting (a recording
//! through `apply`, `noise` and `report`; a device through `flash`; another calibration through
//! `compare`) against each mismatch (another unit's id, another output unit, a negated or a zero
//! scale factor, a temperature model and no temperature). Each cell runs the command and must end
//! in an error naming both sides or the fault; a cell where a mismatch cannot arise says why. The
//! matrix is printed (`cargo test -p host --test guard_matrix -- --nocapture`) and kept in
//! docs/robustness.md.

use std::path::{Path, PathBuf};

mod common;
use common::{hand_segment_args, host};

const UNIT: &str = "a1b2c3d4e5f6a1b2c3d4e5f6";
const OTHER_UNIT: &str = "0f0f0f0f0f0f0f0f0f0f0f0f";
/// The simulated device's unit id (`--port sim`).
const SIM_DEVICE: &str = "53494d2d50415045522d3031";

fn s(p: &Path) -> String {
    p.to_str().unwrap().to_string()
}

fn ok(args: &[&str]) {
    let (ok, out, e) = host(args);
    assert!(ok, "{args:?}: {out}\n{e}");
}

/// A calibration file edited by `edit` on its text.
fn edited(from: &Path, to: &Path, edit: impl Fn(String) -> String) -> PathBuf {
    let text = std::fs::read_to_string(from).unwrap();
    std::fs::write(to, edit(text)).unwrap();
    to.to_path_buf()
}

/// The first value of `key = [` negated (the x axis's).
fn negate_first(text: String, key: &str) -> String {
    let at = text.find(&format!("{key} = [")).unwrap();
    let start = at + text[at..].find('\n').unwrap() + 1;
    let digits = start + text[start..].find(|c: char| c.is_ascii_digit()).unwrap();
    let mut t = text;
    t.insert(digits, '-');
    t
}

struct Fixtures {
    _dir: tempfile::TempDir,
    tmp: PathBuf,
    session: PathBuf,
    cal: PathBuf,
    other_unit: PathBuf,
    other_output: PathBuf,
    other_output_device: PathBuf,
    negated: PathBuf,
    zero: PathBuf,
    thermal: PathBuf,
}

fn fixtures() -> Fixtures {
    let dir = tempfile::tempdir().unwrap();
    let tmp = dir.path().to_path_buf();
    let session = tmp.join("session");
    ok(&["-q", "simulate", "--plan", "short", "--out", &s(&session)]);
    let plan = session.join("plan.toml");
    let text = std::fs::read_to_string(&plan).unwrap();
    std::fs::write(&plan, format!("unit_id = \"{UNIT}\"\n{text}")).unwrap();
    ok(&["-q", "calibrate", "--input", &s(&session)]);
    let cal = session.join("calibration.toml");
    let other_unit = edited(&cal, &tmp.join("other-unit.toml"), |t| {
        t.replace(UNIT, OTHER_UNIT)
    });
    let negated = edited(&cal, &tmp.join("negated.toml"), |t| {
        negate_first(t, "scale_v_per_g")
    });
    let zero = edited(&cal, &tmp.join("zero.toml"), |t| {
        let at = t.find("scale_v_per_g = [").unwrap();
        let start = at + t[at..].find('\n').unwrap() + 1;
        let end = start + t[start..].find(',').unwrap();
        format!("{}    0.0{}", &t[..start], &t[end..])
    });
    let csv = tmp.join("hand.csv");
    ok(&["-q", "simulate-hand", "--out", &s(&csv)]);
    let hand = tmp.join("hand");
    let mut seg = hand_segment_args(&s(&csv), &s(&hand))
        .iter()
        .map(|a| a.to_string())
        .collect::<Vec<_>>();
    seg.extend(["--unit-id".into(), UNIT.into(), "-q".into()]);
    ok(&seg.iter().map(String::as_str).collect::<Vec<_>>());
    ok(&["-q", "calibrate", "--input", &s(&hand)]);
    let thermal_dir = tmp.join("thermal");
    ok(&[
        "-q",
        "simulate",
        "--plan",
        "thermal-soak",
        "--out",
        &s(&thermal_dir),
    ]);
    let plan = thermal_dir.join("plan.toml");
    let text = std::fs::read_to_string(&plan).unwrap();
    std::fs::write(&plan, format!("unit_id = \"{UNIT}\"\n{text}")).unwrap();
    ok(&["-q", "calibrate", "--input", &s(&thermal_dir)]);
    Fixtures {
        _dir: dir,
        tmp: tmp.clone(),
        session,
        cal,
        other_unit,
        other_output_device: edited(
            &hand.join("calibration.toml"),
            &tmp.join("device.toml"),
            |t| t.replace(UNIT, SIM_DEVICE),
        ),
        other_output: hand.join("calibration.toml"),
        negated,
        zero,
        thermal: thermal_dir.join("calibration.toml"),
    }
}

/// One cell: the command run, and what its refusal must name.
enum Cell {
    Run(Vec<String>, &'static [&'static str]),
    DoesNotArise(&'static str),
}

const MISMATCHES: [&str; 5] = [
    "another unit's id",
    "another output unit",
    "a negated scale",
    "a zero scale",
    "temperature model, no temperature",
];

fn cells(f: &Fixtures, meeting: &str) -> Vec<Cell> {
    let out = s(&f.tmp.join("out.csv"));
    let session = s(&f.session);
    let line = |cal: &Path| -> Vec<String> {
        let cal = s(cal);
        let v: Vec<&str> = match meeting {
            "apply" => vec![
                "apply",
                "--calibration",
                &cal,
                "--input",
                &session,
                "--out",
                &out,
                "--force",
            ],
            "noise" => vec!["noise", "--calibration", &cal, "--input", &session],
            "report" => vec!["report", "--calibration", &cal, "--input", &session],
            "flash" => vec!["flash", "--port", "sim", "--calibration", &cal],
            "compare" => vec!["compare", &cal, "--max-sigma", "1e6"],
            _ => unreachable!(),
        };
        let mut v: Vec<String> = v.into_iter().map(String::from).collect();
        if meeting == "compare" {
            v.insert(1, s(&f.cal));
        }
        v
    };
    let unit_needles: &'static [&'static str] = if meeting == "flash" {
        &[SIM_DEVICE]
    } else {
        &[UNIT, OTHER_UNIT]
    };
    // The device's own id on another output unit's calibration: only the unit differs.
    let other_output = if meeting == "flash" {
        &f.other_output_device
    } else {
        &f.other_output
    };
    let other_unit = if meeting == "flash" {
        &f.cal
    } else {
        &f.other_unit
    };
    vec![
        Cell::Run(line(other_unit), unit_needles),
        Cell::Run(line(other_output), &["m/s", "V"]),
        Cell::Run(line(&f.negated), &["scale"]),
        Cell::Run(line(&f.zero), &["scale"]),
        match meeting {
            "flash" => Cell::DoesNotArise("the device measures its own temperature"),
            "noise" => Cell::DoesNotArise(
                "the Allan deviation is blind to the constant offset of a model held at its \
                 reference temperature",
            ),
            "compare" => Cell::DoesNotArise("two calibrations meet no temperature data"),
            _ => Cell::Run(line(&f.thermal), &["temperature"]),
        },
    ]
}

#[test]
fn every_meeting_refuses_every_mismatch() {
    let f = fixtures();
    let meetings = ["apply", "noise", "report", "flash", "compare"];
    let mut table = format!(
        "| meeting | {} |\n|---|{}\n",
        MISMATCHES.join(" | "),
        "---|".repeat(5)
    );
    let mut failures = Vec::new();
    for meeting in meetings {
        let mut row = format!("| `{meeting}` |");
        for (cell, mismatch) in cells(&f, meeting).into_iter().zip(MISMATCHES) {
            match cell {
                Cell::DoesNotArise(why) => row += &format!(" n/a: {why} |"),
                Cell::Run(line, needles) => {
                    let args: Vec<&str> = line.iter().map(String::as_str).collect();
                    let (ok, _, stderr) = host(&args);
                    let named = needles.iter().all(|n| stderr.contains(n));
                    if ok || !named || stderr.contains("panicked") {
                        failures.push(format!(
                            "{meeting} × {mismatch}: accepted={ok}, needles {needles:?}: {}",
                            stderr.trim()
                        ));
                        row += " **accepted** |";
                    } else {
                        row += " refused |";
                    }
                }
            }
        }
        table += &(row + "\n");
    }
    println!("{table}");
    assert!(failures.is_empty(), "{}", failures.join("\n"));
}
