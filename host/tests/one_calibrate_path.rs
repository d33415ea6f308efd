//! One calibrate use case: the live procedure (`calibrate --port sim`), `calibrate --input` on the
//! recording it saved and `host batch` over a lot holding that recording give one JSON document —
//! the same keys, and the same values apart from where each wrote its files and the device's
//! verification, which only the live run has. (Python's `calibrate` is held to the same document
//! by the package's tests.)

mod common;
use common::host;
use serde_json::Value;

fn document(stdout: &str) -> Value {
    serde_json::from_str(stdout).unwrap_or_else(|e| panic!("{e}: {stdout}"))
}

/// `host -q ARGS --json`, which must succeed: its one JSON document.
fn json(args: &[&str]) -> Value {
    let mut all = vec!["-q"];
    all.extend_from_slice(args);
    all.push("--json");
    let (ok, stdout, stderr) = host(&all);
    assert!(ok, "{args:?}: {stderr}");
    document(&stdout)
}

/// `calibrate --input SESSION --out-dir OUT --json`.
fn calibrate_input(session: &str, out: &str) -> Value {
    json(&["calibrate", "--input", session, "--out-dir", out])
}

/// The first unit's document of `batch --input LOT --out OUT --json`.
fn batch_first_unit(lot: &str, out: &str) -> Value {
    json(&["batch", "--input", lot, "--out", out])["units"][0]["summary"].clone()
}

/// The document without what depends on where and how it was made: the files' paths and the
/// verification (and the `passed` that includes it, which is checked on its own).
fn calibration_part(doc: &Value) -> Value {
    let mut d = doc.clone();
    let o = d.as_object_mut().unwrap();
    for k in ["files", "verification"] {
        assert!(o.contains_key(k), "no '{k}' key: one shape has every key");
        o.remove(k);
    }
    d
}

#[test]
fn live_input_and_batch_calibrations_are_one_document() {
    let dir = tempfile::tempdir().unwrap();
    let p = |name: &str| dir.path().join(name).to_str().unwrap().to_string();
    let live = json(&[
        "calibrate",
        "--port",
        "sim",
        "--plan",
        "quick-oblique",
        "--out-dir",
        &p("live"),
    ]);
    assert_eq!(live["verification"]["passed"], true, "{live}");
    assert!(live["verification"]["worst_error_mg"].as_f64().unwrap() >= 0.0);
    assert_eq!(
        live["files"]["calibration_toml"],
        format!("{}/calibration.toml", p("live"))
    );

    let recording = format!("{}/recording", p("live"));
    let input = calibrate_input(&recording, &p("input"));
    assert_eq!(input["verification"], Value::Null);
    assert_eq!(
        input["files"]["calibration_bin"],
        format!("{}/calibration.bin", p("input"))
    );

    let unit = dir.path().join("lot").join("u1");
    std::fs::create_dir_all(&unit).unwrap();
    for f in ["plan.toml", "samples.csv"] {
        std::fs::copy(dir.path().join("live/recording").join(f), unit.join(f)).unwrap();
    }
    let batch = &batch_first_unit(&p("lot"), &p("res"));
    assert_eq!(
        batch["files"]["results_dir"],
        format!("{}/u1", p("res")),
        "{batch}"
    );

    assert_eq!(live["passed"], true);
    let one = calibration_part(&input);
    assert_eq!(calibration_part(&live), one);
    assert_eq!(calibration_part(batch), one);
    // Everything a calibration says, not an empty shell: 24 paper-form values and the gyro's 12.
    assert_eq!(one["parameters"].as_array().unwrap().len(), 36);
    // And the files are the same bytes (the blob's creation time aside, the `.toml`s).
    let toml = |d: &str| std::fs::read(dir.path().join(d).join("calibration.toml")).unwrap();
    assert_eq!(toml("live"), toml("input"));
    assert_eq!(toml("res/u1"), toml("input"));
}

/// A hand-held session, whose gyro comes from its hand turns (`gyro.toml`), not from its plan:
/// `host batch` takes it as `calibrate --input` does (it used to leave the gyro out).
#[test]
fn a_hand_held_sessions_gyro_is_in_the_batch_result_as_in_calibrate() {
    let dir = tempfile::tempdir().unwrap();
    let p = |name: &str| dir.path().join(name).to_str().unwrap().to_string();
    let (ok, _, stderr) = host(&[
        "-q",
        "simulate-hand",
        "--out",
        &p("hand.csv"),
        "--seed",
        "4",
    ]);
    assert!(ok, "{stderr}");
    let session = dir.path().join("lot").join("hand");
    let session_s = session.to_str().unwrap().to_string();
    let (ok, _, stderr) = host(&common::hand_segment_args(&p("hand.csv"), &session_s));
    assert!(ok, "{stderr}");
    assert!(session.join("gyro.toml").exists());
    let input = calibrate_input(&session_s, &p("input"));
    let batch = &batch_first_unit(&p("lot"), &p("res"));
    let gyro = |d: &Value| -> Vec<String> {
        d["parameters"]
            .as_array()
            .unwrap()
            .iter()
            .filter_map(|p| p["name"].as_str())
            .filter(|n| n.starts_with("gyro_"))
            .map(str::to_string)
            .collect()
    };
    assert_eq!(gyro(&input).len(), 12, "{input}");
    assert_eq!(gyro(batch), gyro(&input));
    assert_eq!(calibration_part(batch), calibration_part(&input));
}
