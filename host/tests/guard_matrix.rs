//! Where a calibration meets something, every mismatch is refused: each meeting of the guard's
//! table (`outputs::calibration_guard`: a recording through `apply`, `noise`, `report` and
//! `navigation-check`; a device through `flash`, `verify` and `read`; another calibration through
//! `compare` and `batch`) against each mismatch (another unit's id, another output unit, a negated
//! or a zero scale factor, another body frame, a temperature model and no temperature, a gyro in
//! another unit). Where the table checks a mismatch the cell runs the command, which must exit
//! nonzero naming both sides; where it does not, the cell prints the table's reason. The matrix is
//! printed (`cargo test -p host --test guard_matrix -- --nocapture`) and kept in
//! docs/robustness.md.

use std::path::{Path, PathBuf};

mod common;
use common::{hand_segment_args, host};
use outputs::calibration_guard::{verdict, Check, Meeting, Verdict};

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

/// The span of the first number of `key = [...]` (the x axis's), however the array is laid out.
fn first_number(text: &str, key: &str) -> std::ops::Range<usize> {
    let at = text.find(&format!("{key} = [")).unwrap();
    let start = at
        + text[at..]
            .find(|c: char| c.is_ascii_digit() || c == '-')
            .unwrap();
    let end = start + text[start..].find([',', ']']).unwrap();
    start..end
}

/// The first value of `key = [` negated (the x axis's).
fn negate_first(text: String, key: &str) -> String {
    let mut t = text;
    let at = first_number(&t, key).start;
    t.insert(at, '-');
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
    /// The session's calibration with its angles moved to a conventional frame's fixed values.
    conventional: PathBuf,
    /// A unit with a 0.5 °/s gyro bias: its calibration, and its session with the gyro written in
    /// °/s under the plan's rad/s.
    gyro_cal: PathBuf,
    gyro_in_deg: PathBuf,
}

/// The calibration text with a conventional frame's fixed angles: accelerometer x at exactly 0°,
/// 90°, 90° and accelerometer y at exactly 90° from body z.
fn conventional(text: String) -> String {
    let mut lines: Vec<String> = text.lines().map(String::from).collect();
    let at = lines
        .iter()
        .position(|l| l.starts_with("installation_angles_deg = ["))
        .unwrap();
    lines[at + 1] = "    [0.0, 90.0, 90.0],".into();
    let row = lines[at + 2].trim().trim_end_matches(',');
    let mut v: Vec<&str> = row.trim_matches(['[', ']']).split(", ").collect();
    v[2] = "90.0";
    lines[at + 2] = format!("    [{}],", v.join(", "));
    lines.join("\n") + "\n"
}

/// A session of a unit whose gyro has a 0.5 °/s bias, calibrated, and a copy of it with the gyro
/// columns in °/s (the plan still says rad/s): (the calibration, the copy).
fn gyro_fixtures(tmp: &Path, cal: &Path) -> (PathBuf, PathBuf) {
    let unit = edited(cal, &tmp.join("gyro-unit.toml"), |t| {
        let at = t.find("bias_rad_s = [").unwrap();
        let end = at + t[at..].find(']').unwrap() + 1;
        format!(
            "{}bias_rad_s = [0.01, -0.008, 0.012]{}",
            &t[..at],
            &t[end..]
        )
    });
    let session = tmp.join("gyro");
    ok(&[
        "-q",
        "simulate",
        "--plan",
        "short",
        "--unit",
        &s(&unit),
        "--out",
        &s(&session),
    ]);
    ok(&["-q", "calibrate", "--input", &s(&session)]);
    let deg = tmp.join("gyro-deg");
    std::fs::create_dir(&deg).unwrap();
    std::fs::copy(session.join("plan.toml"), deg.join("plan.toml")).unwrap();
    let text = std::fs::read_to_string(session.join("samples.csv")).unwrap();
    let mut out = String::new();
    for (i, line) in text.lines().enumerate() {
        let mut f: Vec<String> = line.split(',').map(String::from).collect();
        if i > 0 {
            for v in &mut f[5..8] {
                *v = v.parse::<f64>().unwrap().to_degrees().to_string();
            }
        }
        out += &(f.join(",") + "\n");
    }
    std::fs::write(deg.join("samples.csv"), out).unwrap();
    (session.join("calibration.toml"), deg)
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
        let r = first_number(&t, "scale_v_per_g");
        format!("{}0.0{}", &t[..r.start], &t[r.end..])
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
    let (gyro_cal, gyro_in_deg) = gyro_fixtures(&tmp, &cal);
    Fixtures {
        conventional: edited(&cal, &tmp.join("conventional.toml"), conventional),
        gyro_cal,
        gyro_in_deg,
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

/// One cell: the command run and what its refusal must name (both sides), or why it is not run.
enum Cell {
    Run(Vec<String>, Vec<&'static str>),
    /// The guard checks it, but no command line can bring the mismatch to it.
    NotDriven(&'static str),
}

/// The columns: a mismatch, the guard's check that refuses it.
const MISMATCHES: [(&str, Check); 7] = [
    ("another unit's id", Check::UnitId),
    ("another output unit", Check::OutputUnit),
    ("a negated scale", Check::Scales),
    ("a zero scale", Check::Scales),
    ("another body frame", Check::Frame),
    ("temperature model, no temperature", Check::Temperature),
    ("gyro in another unit", Check::GyroUnit),
];

/// The command line of `meeting` with the calibration `cal` (against `input`, a session, where it
/// reads one; `compare`: against the session's own calibration).
fn line(f: &Fixtures, meeting: Meeting, cal: &Path, input: &Path) -> Vec<String> {
    let (cal, input, out) = (s(cal), s(input), s(&f.tmp.join("out.csv")));
    let v: Vec<&str> = match meeting {
        Meeting::Apply => vec![
            "apply",
            "--calibration",
            &cal,
            "--input",
            &input,
            "--out",
            &out,
            "--force",
        ],
        Meeting::Noise => vec!["noise", "--calibration", &cal, "--input", &input],
        Meeting::Report => vec!["report", "--calibration", &cal, "--input", &input],
        Meeting::NavigationCheck => vec!["navigation-check", "--unit", &cal, "--duration-s", "10"],
        Meeting::Flash => vec!["flash", "--port", "sim", "--calibration", &cal],
        Meeting::Compare => vec!["compare", "A", &cal, "--max-sigma", "1e6"],
        _ => unreachable!("{meeting:?} is not run"),
    };
    let mut v: Vec<String> = v.into_iter().map(String::from).collect();
    if meeting == Meeting::Compare {
        v[1] = s(&f.cal);
    }
    v
}

/// The cell of `meeting` × column `k` where the guard checks it.
fn cell(f: &Fixtures, meeting: Meeting, k: usize) -> Cell {
    let run = |cal: &Path, needles: &[&'static str]| {
        Cell::Run(line(f, meeting, cal, &f.session), needles.to_vec())
    };
    match (meeting, k) {
        (Meeting::Read, _) => Cell::NotDriven(
            "a simulated device (--port sim) starts every run holding no calibration, so no \
             mismatched one can be read back (the guard's unit tests hold read's checks)",
        ),
        // The device's own id on another output unit's calibration: only the unit differs.
        (Meeting::Flash, 0) => run(&f.cal, &[UNIT, SIM_DEVICE]),
        (Meeting::Flash, 1) => run(&f.other_output_device, &["m/s", "V"]),
        (_, 0) => run(&f.other_unit, &[UNIT, OTHER_UNIT]),
        (_, 1) => run(&f.other_output, &["m/s", "V"]),
        (_, 2) => run(
            &f.negated,
            &[
                "cannot meet",
                other_side(meeting),
                "negative scale factor",
                "accelerometer x",
            ],
        ),
        // A zero scale factor has no inverse: the file itself is refused as it is read (its
        // parameters' validity, `shared::params`), before the guard's own check could meet it.
        (_, 3) => run(
            &f.zero,
            &["zero.toml", "zero scale factor", "accelerometer x"],
        ),
        (_, 4) => run(
            &f.conventional,
            &["a conventional body frame", "the table's body frame"],
        ),
        (_, 5) => run(&f.thermal, &["temperature model", "no temp_c column"]),
        (Meeting::Apply, 6) => Cell::Run(
            line(f, meeting, &f.gyro_cal, &f.gyro_in_deg),
            vec!["gyro rate of", "°/s", "the calibration", "the recording"],
        ),
        _ => unreachable!("no driver for {meeting:?} × column {k}"),
    }
}

/// How the guard names what the calibration meets at `meeting`.
fn other_side(meeting: Meeting) -> &'static str {
    match meeting {
        Meeting::Apply | Meeting::Noise => "the recording",
        Meeting::Report => "the session",
        Meeting::NavigationCheck => "its simulated session",
        Meeting::Flash => "the device",
        _ => "B (",
    }
}

/// Runs one cell; `None` when it was refused as it must be, else why not.
fn judge(line: &[String], needles: &[&str]) -> Option<String> {
    let args: Vec<&str> = line.iter().map(String::as_str).collect();
    let (ok, _, stderr) = host(&args);
    let named = needles.iter().all(|n| stderr.contains(n));
    (ok || !named || stderr.contains("panicked")).then(|| {
        format!(
            "host {}: accepted={ok}, needles {needles:?}: {}",
            line.join(" "),
            stderr.trim()
        )
    })
}

#[test]
fn every_meeting_refuses_every_mismatch() {
    let f = fixtures();
    let names: Vec<&str> = MISMATCHES.iter().map(|m| m.0).collect();
    let mut table = format!(
        "| meeting | {} |\n|---|{}\n",
        names.join(" | "),
        "---|".repeat(MISMATCHES.len())
    );
    let (mut failures, mut refused, mut not_applicable, mut not_driven) = (Vec::new(), 0, 0, 0);
    for meeting in Meeting::ALL {
        let mut row = format!("| `{}` |", meeting.command());
        for (k, (mismatch, check)) in MISMATCHES.iter().enumerate() {
            let cell = match verdict(meeting, *check) {
                Verdict::DoesNotApply(why) => {
                    not_applicable += 1;
                    row += &format!(" n/a: {why} |");
                    continue;
                }
                Verdict::Checked => cell(&f, meeting, k),
            };
            match cell {
                Cell::NotDriven(why) => {
                    not_driven += 1;
                    row += &format!(" checked, not driven: {why} |");
                }
                Cell::Run(line, needles) => match judge(&line, &needles) {
                    None => {
                        refused += 1;
                        row += " refused |";
                    }
                    Some(why) => {
                        failures.push(format!("{} × {mismatch}: {why}", meeting.command()));
                        row += " **accepted** |";
                    }
                },
            }
        }
        table += &(row + "\n");
    }
    println!("{table}");
    println!(
        "guard matrix: {} meetings × {} mismatches: {refused} refused, {not_applicable} not \
         applicable, {not_driven} checked but not driven",
        Meeting::ALL.len(),
        MISMATCHES.len()
    );
    assert!(failures.is_empty(), "{}", failures.join("\n"));
}
