//! A segment `calibrate` leaves out is named in the text output (without `-v`) and in the JSON
//! document, with the figure that failed and its limit: here a static segment whose gyro turns at
//! a planted 2 °/s (the independent truth its figure must show).

mod common;
use common::host;

/// The planted turn, °/s.
const PLANTED_DEG_S: f64 = 2.0;

/// Adds [`PLANTED_DEG_S`] about z to every gyro sample of segment `name` in `samples.csv`.
fn turn_segment(samples: &std::path::Path, name: &str) {
    let text = std::fs::read_to_string(samples).unwrap();
    let mut lines = text.lines();
    let header = lines.next().unwrap();
    let cols: Vec<&str> = header.split(',').collect();
    let wz = cols.iter().position(|c| *c == "w_z").unwrap();
    let mut out = format!("{header}\n");
    let mut turned = 0;
    for line in lines {
        let mut f: Vec<String> = line.split(',').map(String::from).collect();
        if f[0] == name {
            let w: f64 = f[wz].parse().unwrap();
            f[wz] = (w + PLANTED_DEG_S.to_radians()).to_string();
            turned += 1;
        }
        out.push_str(&f.join(","));
        out.push('\n');
    }
    assert!(turned > 100, "{turned} rows of '{name}'");
    std::fs::write(samples, out).unwrap();
}

#[test]
fn a_segment_left_out_is_named_with_its_figure_in_text_and_json() {
    let dir = tempfile::tempdir().unwrap();
    let s = dir.path().join("s");
    let s = s.to_str().unwrap();
    let (ok, _, stderr) = host(&["-q", "simulate", "--out", s, "--plan", "quick-oblique"]);
    assert!(ok, "{stderr}");
    turn_segment(&dir.path().join("s/samples.csv"), "y+");

    // The text output, without -v: the segment, why, the planted rate and the limit.
    let (_, stdout, stderr) = host(&["calibrate", "--input", s]);
    let line = stdout
        .lines()
        .find(|l| l.contains("'y+'"))
        .unwrap_or_else(|| panic!("'y+' not named in:\n{stdout}\n{stderr}"));
    assert!(stdout.contains("Excluded segments (1):"), "{stdout}");
    assert!(
        line.contains("moved") && line.contains(" °/s > limit 0.500 °/s"),
        "{line}"
    );
    // The figure shown is the planted rate (within the simulated gyro noise of the other rests).
    let shown: f64 = line
        .split(" °/s > limit")
        .next()
        .and_then(|head| head.rsplit(' ').next())
        .and_then(|v| v.parse().ok())
        .unwrap_or_else(|| panic!("no figure in {line}"));
    assert!((shown - PLANTED_DEG_S).abs() < 0.01, "{line}");

    // The JSON document: the same segment with its figure, limit and unit.
    let out = dir.path().join("json");
    let (_, stdout, stderr) = host(&[
        "calibrate",
        "--input",
        s,
        "--out-dir",
        out.to_str().unwrap(),
        "--json",
    ]);
    let v: serde_json::Value =
        serde_json::from_str(&stdout).unwrap_or_else(|e| panic!("{e}: {stdout}\n{stderr}"));
    let list = v["excluded_segments"].as_array().unwrap();
    assert_eq!(list.len(), 1, "{list:?}");
    assert_eq!(list[0]["segment"], "y+");
    let fig = &list[0]["figure"];
    assert!(
        (fig["value"].as_f64().unwrap() - PLANTED_DEG_S).abs() < 0.01,
        "{fig}"
    );
    assert_eq!(fig["limit"].as_f64().unwrap(), 0.5);
    assert_eq!(fig["unit"], "°/s");
    assert_eq!(fig["bound"], "at_most");
}
