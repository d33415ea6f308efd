//! A hand-held session's output speaks of what was done: positions held by hand, no rate table.
//! `calibrate`'s text and `report`'s page carry none of the table's words, the report compares every
//! position against its fitted attitude (residuals at the positions' own noise, as the terminal
//! shows), and leaves the navigation replay out with the reason.

mod common;

use std::path::Path;

fn s(p: &Path) -> &str {
    p.to_str().unwrap()
}

/// Runs `host ARGS`, which must succeed: stdout, stderr.
fn host(args: &[&str]) -> (String, String) {
    let (ok, out, err) = common::host(args);
    assert!(ok, "host {args:?}: {err}");
    (out, err)
}

/// Words that belong to a rate table or a fixture, or to the program rather than the reader.
const TABLE_WORDS: &[&str] = &[
    "table centre",
    "table attitude",
    "table rate",
    "oblique axes",
    "tilted mounts",
    "up_b as exact",
    "non-coplanar",
    "tilt 0.0000",
    "Table 3",
    "TableAxis",
    "Centroid",
    "BodyPoint",
    "± ∞",
];

fn assert_no_table_words(what: &str, text: &str) {
    for w in TABLE_WORDS {
        assert!(!text.contains(w), "{what} says '{w}':\n{text}");
    }
}

/// The value before " ± " of a residual cell, µg.
fn residual_ug(cell: &str) -> Option<f64> {
    cell.split(" ± ").next()?.trim().parse().ok()
}

#[test]
fn a_hand_held_calibration_and_its_report_speak_of_no_table() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    let raw = d.join("raw.csv");
    let session = d.join("hand-session");
    let cal = d.join("cal");
    let rep = d.join("rep");
    host(&["-q", "simulate-hand", "--out", s(&raw)]);
    host(&common::hand_segment_args(s(&raw), s(&session)));
    let (out, err) = host(&["calibrate", "-v", "--input", s(&session), "--out", s(&cal)]);
    assert_no_table_words("calibrate", &format!("{out}{err}"));
    assert!(out.contains("Free positions"), "{out}");
    assert!(out.contains("Lever arms: not calibrated"), "{out}");
    let (out, err) = host(&[
        "report",
        "--input",
        s(&session),
        "--calibration",
        s(&cal.join("calibration.toml")),
        "--out-dir",
        s(&rep),
    ]);
    let page = std::fs::read_to_string(rep.join("report.md")).unwrap();
    assert_no_table_words("report", &format!("{out}{err}{page}"));
    assert!(
        err.contains("navigation replay is left out") && !out.contains("|p| end m"),
        "{out}{err}"
    );
    // Every position against its fitted attitude: after static compensation the residuals are the
    // positions' own noise (about 50 µg per axis for 1 mg white noise and tremor over 3–5 s), not
    // the tens of mg of the rough starting guesses.
    let mut residuals = Vec::new();
    for line in page.lines().filter(|l| l.starts_with("| ")) {
        let cells: Vec<&str> = line.split('|').map(str::trim).collect();
        if cells.len() >= 8 && ["x", "y", "z"].contains(&cells[2]) {
            residuals.push(residual_ug(cells[7]).expect(line));
        }
    }
    assert_eq!(residuals.len(), 72, "{page}");
    let rms = (residuals.iter().map(|r| r * r).sum::<f64>() / 72.0).sqrt();
    let worst = residuals.iter().fold(0.0f64, |m, r| m.max(r.abs()));
    eprintln!("hand-held report: residual rms {rms:.1} µg, worst {worst:.1} µg");
    assert!(
        rms < 100.0 && worst < 400.0,
        "rms {rms} µg, worst {worst} µg"
    );
}

/// The advice for a session with enough positions but fewer than recommended reads as one sentence:
/// how many there are, what is missing, how many more to record.
#[test]
fn the_coverage_advice_is_one_plain_sentence() {
    use recording::session::coverage::Coverage;
    let c = Coverage {
        distinct: 10,
        repeats: vec![None; 10],
        missing_faces: vec!["x down", "z up"],
        faces: None,
    };
    let a = c.advice().unwrap();
    assert_eq!(
        a,
        "10 distinct positions (24 recommended), and none within 50° of x down, z up: recording 14 \
         more, spread over the whole sphere (those directions included), would make the calibration \
         more robust"
    );
    let full = Coverage {
        distinct: 24,
        repeats: vec![None; 24],
        missing_faces: vec![],
        faces: None,
    };
    assert_eq!(full.advice(), None);
}
