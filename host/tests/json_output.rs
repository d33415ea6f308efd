//! `--json`: one JSON document on stdout, everything for people on stderr; `--quiet` is quiet;
//! pass/fail limits give a nonzero exit.

use std::process::Command;

fn host(args: &[&str]) -> (bool, String, String) {
    let out = Command::new(env!("CARGO_BIN_EXE_host"))
        .args(args)
        .output()
        .expect("the host binary runs");
    (
        out.status.success(),
        String::from_utf8_lossy(&out.stdout).into_owned(),
        String::from_utf8_lossy(&out.stderr).into_owned(),
    )
}

#[test]
fn calibrate_compare_plan_and_noise_print_one_json_document() {
    let dir = tempfile::tempdir().unwrap();
    let s = dir.path().join("s");
    let s = s.to_str().unwrap();
    let (ok, stdout, stderr) = host(&["-q", "simulate", "--out", s, "--plan", "quick-oblique"]);
    assert!(ok, "{stderr}");
    assert!(
        stdout.is_empty(),
        "--quiet prints nothing on stdout: {stdout}"
    );

    let (ok, stdout, stderr) = host(&["calibrate", "--input", s, "--json"]);
    assert!(ok, "{stderr}");
    let v: serde_json::Value = serde_json::from_str(&stdout).expect("stdout is one JSON document");
    assert_eq!(v["parameters"].as_array().unwrap().len(), 24);
    assert_eq!(v["parameters"][0]["name"], "bias_x");
    assert!(v["parameters"][0]["sigma"].as_f64().unwrap() > 0.0);
    assert!(v["chi2_per_dof"].as_f64().unwrap() > 0.0);
    assert_eq!(v["passed"], true);
    // The human report went to stderr.
    assert!(stderr.contains("Table 1"), "{stderr}");

    // A limit the unit cannot meet: nonzero exit, the JSON still complete, the reason on stderr.
    let (ok, stdout, stderr) = host(&[
        "calibrate",
        "--input",
        s,
        "--json",
        "--force",
        "--max-bias-mg",
        "0.001",
    ]);
    assert!(!ok);
    let v: serde_json::Value = serde_json::from_str(&stdout).unwrap();
    assert_eq!(v["passed"], false);
    assert!(stderr.contains("FAIL: bias_mg"), "{stderr}");

    let cal = format!("{s}/calibration.toml");
    let (ok, stdout, stderr) = host(&["compare", &cal, &cal, "--json", "--max-sigma", "3"]);
    assert!(ok, "{stderr}");
    let v: serde_json::Value = serde_json::from_str(&stdout).unwrap();
    assert_eq!(v["passed"], true);
    assert_eq!(v["rows"].as_array().unwrap().len(), 24);

    let (ok, stdout, stderr) = host(&["plan", "--check", "oblique", "--json"]);
    assert!(ok, "{stderr}");
    let v: serde_json::Value = serde_json::from_str(&stdout).unwrap();
    assert!(v["parameters"][0]["predicted_sigma"].as_f64().unwrap() > 0.0);
    assert!(stderr.contains("segments at"), "{stderr}");

    let (ok, stdout, stderr) = host(&["noise", "--input", s, "--json"]);
    assert!(ok, "{stderr}");
    let v: serde_json::Value = serde_json::from_str(&stdout).unwrap();
    assert_eq!(v["axes"].as_array().unwrap().len(), 6);
}

#[test]
fn compare_fails_on_a_difference_beyond_the_limit() {
    let dir = tempfile::tempdir().unwrap();
    let mut cals = Vec::new();
    for seed in ["1", "2"] {
        let s = dir.path().join(seed);
        let s = s.to_str().unwrap().to_string();
        let (ok, _, e) = host(&[
            "-q",
            "simulate",
            "--out",
            &s,
            "--plan",
            "quick-oblique",
            "--seed",
            seed,
        ]);
        assert!(ok, "{e}");
        let (ok, _, e) = host(&["-q", "calibrate", "--input", &s]);
        assert!(ok, "{e}");
        cals.push(format!("{s}/calibration.toml"));
    }
    // Two sessions of one unit agree within a few σ; a limit of 0.001 σ cannot be met.
    let (ok, _, stderr) = host(&["compare", &cals[0], &cals[1], "--max-sigma", "0.001"]);
    assert!(!ok && stderr.contains("FAIL:"), "{stderr}");
    let (ok, _, stderr) = host(&["compare", &cals[0], &cals[1], "--max-sigma", "6"]);
    assert!(ok, "{stderr}");
}
