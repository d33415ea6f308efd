//! `--json`: one JSON document on stdout, everything for people on stderr; `--quiet` is quiet;
//! pass/fail limits give a nonzero exit.

mod common;
use common::host;

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
    // The accelerometer's 24 paper-form values, then the gyro's G and b (quick-oblique spins it).
    assert_eq!(v["parameters"].as_array().unwrap().len(), 24 + 12);
    assert_eq!(v["parameters"][0]["name"], "bias_x");
    assert_eq!(v["parameters"][24]["name"], "gyro_g_xx");
    assert!(v["parameters"][0]["sigma"].as_f64().unwrap() > 0.0);
    assert!(v["chi2_per_dof"].as_f64().unwrap() > 0.0);
    assert_eq!(v["passed"], true);
    // The human report went to stderr.
    assert!(stderr.contains("Result (± 1σ)"), "{stderr}");

    // A limit the unit cannot meet: nonzero exit, the JSON still complete, the reason on stderr
    // (its files, elsewhere, are marked FAILED; the accepted pair above stays).
    let failed = format!("{s}/failed");
    let (ok, stdout, stderr) = host(&[
        "calibrate",
        "--input",
        s,
        "--out-dir",
        &failed,
        "--json",
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
    // The accelerometer's 24 values and the gyro's 12.
    assert_eq!(v["rows"].as_array().unwrap().len(), 24 + 12);

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

#[test]
fn segment_prints_one_json_document_with_every_position_and_the_gyro() {
    let dir = tempfile::tempdir().unwrap();
    let raw = dir.path().join("raw.csv");
    let raw = raw.to_str().unwrap();
    let (ok, stdout, stderr) = host(&["simulate-hand", "--out", raw]);
    assert!(ok, "{stderr}");
    // "wrote raw.csv (N rows, P positions, …)": the simulator's own count of held positions.
    let positions: usize = stdout
        .split(" positions")
        .next()
        .and_then(|s| s.rsplit(' ').next())
        .and_then(|n| n.parse().ok())
        .unwrap_or_else(|| panic!("the number of positions in {stdout}"));

    let session = dir.path().join("s");
    let session = session.to_str().unwrap();
    let (ok, stdout, stderr) = host(&[
        "segment",
        "--input",
        raw,
        "--out",
        session,
        "--time-column",
        "t",
        "--acc-unit",
        "m/s2",
        "--gyro-unit",
        "deg/s",
        "--json",
    ]);
    assert!(ok, "{stderr}");
    let v: serde_json::Value = serde_json::from_str(&stdout).expect("stdout is one JSON document");
    let intervals = v["intervals"].as_array().unwrap();
    let stills: Vec<_> = intervals.iter().filter(|i| i["kind"] == "static").collect();
    assert_eq!(stills.len(), positions, "{stdout}");
    assert_eq!(v["still_intervals"], positions);
    assert_eq!(
        intervals.len(),
        positions + v["spins"].as_u64().unwrap() as usize
    );
    for (k, iv) in intervals.iter().enumerate() {
        assert_eq!(iv["index"], k + 1);
        assert!(iv["duration_s"].as_f64().unwrap() >= 1.0, "{iv}");
        let d: Vec<f64> = (0..3)
            .map(|j| iv["mean_direction"][j].as_f64().unwrap())
            .collect();
        assert!((d.iter().map(|c| c * c).sum::<f64>().sqrt() - 1.0).abs() < 1e-9);
        assert!(iv["acc_noise_mg"].as_f64().unwrap() > 0.0);
    }
    for iv in &stills {
        let att = &iv["attitude"];
        match att["kind"].as_str().unwrap() {
            "free" => assert!(att["prior_1sigma_deg"].is_null(), "{att}"),
            "axis" => assert!(att["prior_1sigma_deg"].as_f64().unwrap() > 0.0, "{att}"),
            k => panic!("attitude kind {k}"),
        }
    }
    assert_eq!(v["acc_unit"], "m/s2");
    // Measured from the time column: the simulated 200 Hz.
    assert!((v["sample_rate_hz"].as_f64().unwrap() - 200.0).abs() < 1e-6);
    assert_eq!(v["out_dir"], session);
    // The simulated gyro (raw.truth.toml): bias within 5σ of the fit's own 1σ; scale (the diagonal,
    // which a small rotation between the true and the calibrated body axes moves only at second
    // order) within 0.1 %.
    let truth: toml::Value =
        toml::from_str(&std::fs::read_to_string(dir.path().join("raw.truth.toml")).unwrap())
            .unwrap();
    let num = |x: &toml::Value| x.as_float().unwrap();
    let g = &v["gyro"];
    for i in 0..3 {
        let b = g["bias_rad_s"][i].as_f64().unwrap();
        let b_sigma = g["bias_rad_s_1sigma"][i].as_f64().unwrap();
        let b_true = num(&truth["gyro"]["bias_rad_s"][i]);
        assert!(b_sigma > 0.0 && (b - b_true).abs() < 5.0 * b_sigma, "{g}");
        let m = g["matrix"][i][i].as_f64().unwrap();
        let m_true = num(&truth["gyro"]["matrix"][i][i]);
        assert!((m - m_true).abs() < 1e-3, "{g}");
    }
    assert!(g["undetermined"].as_array().unwrap().is_empty(), "{g}");
    // The human table and the gyro text went to stderr.
    assert!(
        stderr.contains(&format!("{positions} still interval(s)")),
        "{stderr}"
    );
    assert!(stderr.contains("gyro from"), "{stderr}");
    assert!(std::path::Path::new(session).join("gyro.toml").exists());
}

/// A refusal under `--json` is a document too: the error, its kind and the exit status on stdout
/// (the message also on stderr), so a script reading stdout never gets nothing.
#[test]
fn a_refusal_under_json_is_a_json_document() {
    let dir = tempfile::tempdir().unwrap();
    let missing = dir.path().join("missing");
    let missing = missing.to_str().unwrap();
    for (args, code, kind) in [
        (vec!["calibrate", "--input", missing, "--json"], 1, "error"),
        (
            vec!["calibrate", "--input", missing, "--baud", "9600", "--json"],
            2,
            "usage",
        ),
        (vec!["plan", "--check", missing, "--json"], 1, "error"),
        (vec!["compare", missing, missing, "--json"], 1, "error"),
    ] {
        let (ok, stdout, stderr) = host(&args);
        assert!(!ok);
        let v: serde_json::Value = serde_json::from_str(stdout.trim())
            .unwrap_or_else(|e| panic!("{args:?}: stdout is no JSON document ({e}): {stdout}"));
        assert_eq!(v["exit_code"], code, "{args:?}: {v}");
        assert_eq!(v["kind"], kind, "{args:?}: {v}");
        let message = v["error"].as_str().unwrap();
        assert!(
            !message.is_empty() && stderr.contains(message),
            "{args:?}: {v} / {stderr}"
        );
    }
    // Without --json, stdout stays empty.
    let (_, stdout, _) = host(&["calibrate", "--input", missing]);
    assert!(stdout.is_empty(), "{stdout}");
}

/// The argument parser's own refusals (a value below its bound) under `--json` give the same
/// document as every other usage error: the message (also on stderr), kind "usage", exit 2. Help is
/// no error and stays text.
#[test]
fn a_parser_refusal_under_json_is_the_same_json_document() {
    let dir = tempfile::tempdir().unwrap();
    let missing = dir.path().join("missing");
    let missing = missing.to_str().unwrap();
    for (args, flag) in [
        (
            vec![
                "segment",
                "--input",
                missing,
                "--max-samples",
                "0",
                "--json",
            ],
            "--max-samples",
        ),
        (
            vec![
                "calibrate",
                "--input",
                missing,
                "--max-chi2-per-dof",
                "0",
                "--json",
            ],
            "--max-chi2-per-dof",
        ),
        (
            vec!["noise", "--input", missing, "--rate-hz", "0", "--json"],
            "--rate-hz",
        ),
    ] {
        let (ok, stdout, stderr) = host(&args);
        assert!(!ok);
        let v: serde_json::Value = serde_json::from_str(stdout.trim())
            .unwrap_or_else(|e| panic!("{args:?}: stdout is no JSON document ({e}): {stdout}"));
        assert_eq!(v["exit_code"], 2, "{args:?}: {v}");
        assert_eq!(v["kind"], "usage", "{args:?}: {v}");
        let message = v["error"].as_str().unwrap();
        assert!(message.contains(flag), "{args:?}: {v}");
        assert!(!message.starts_with("error:"), "{args:?}: {v}");
        assert!(
            stderr.contains(message.lines().next().unwrap()),
            "{args:?}: {v} / {stderr}"
        );
        // Without --json the refusal is text on stderr only.
        let plain: Vec<&str> = args.iter().copied().filter(|a| *a != "--json").collect();
        let (ok, stdout, _) = host(&plain);
        assert!(!ok && stdout.is_empty(), "{plain:?}: {stdout}");
    }
    let (ok, stdout, _) = host(&["calibrate", "--json", "--help"]);
    assert!(ok && stdout.contains("Usage"), "{stdout}");
}

/// The walk in the document (docs/model.md §11): `calibrate --bias-walk-from truth.toml` takes the
/// simulator's own walk (its `[noise]`, 0.003 mg/√s) as the unit's, and the document says so, with
/// one bias-track point per segment of the plan; the same session without a walk option has no
/// `bias_walk` key at all, and `--bias-walk 0.003` is the same fit labelled `given`.
#[test]
fn the_document_carries_the_walk_and_its_source() {
    let dir = tempfile::tempdir().unwrap();
    let s = dir.path().join("s");
    let s = s.to_str().unwrap();
    let (ok, _, e) = host(&[
        "-q",
        "simulate",
        "--out",
        s,
        "--plan",
        "quick-oblique",
        "--drift-mg-sqrt-s",
        "0.003",
    ]);
    assert!(ok, "{e}");
    let truth = format!("{s}/truth.toml");
    let run = |extra: &[&str], out: &str| {
        let out = dir.path().join(out);
        let mut args = vec!["-q", "calibrate", "--input", s, "--json", "--out"];
        args.push(out.to_str().unwrap());
        args.extend(extra);
        let (ok, stdout, stderr) = host(&args);
        assert!(ok, "{stderr}");
        serde_json::from_str::<serde_json::Value>(&stdout).unwrap()
    };
    let unit = run(&["--bias-walk-from", &truth], "unit");
    let w = &unit["bias_walk"];
    assert_eq!(w["source"], "unit", "{w}");
    assert_eq!(w["mg_sqrt_s"].as_f64(), Some(0.003));
    assert_eq!(
        w["axes_mg_sqrt_s"],
        serde_json::json!([0.003, 0.003, 0.003])
    );
    assert!(w["sigma_mg_sqrt_s"].is_null());
    let plan = std::fs::read_to_string(format!("{s}/plan.toml")).unwrap();
    let segments = plan.matches("[[segment]]").count();
    let track = w["track"].as_array().unwrap();
    assert!(
        segments > 0 && track.len() <= segments,
        "{} of {segments}",
        track.len()
    );
    assert!(!track.is_empty());
    for p in track {
        for a in 0..3 {
            assert!(p["sigma_mg"][a].as_f64().unwrap() > 0.0, "{p}");
        }
    }
    let given = run(&["--bias-walk", "0.003"], "given");
    assert_eq!(given["bias_walk"]["source"], "given");
    assert_eq!(given["bias_walk"]["track"], w["track"]);
    assert_eq!(given["parameters"], unit["parameters"]);
    // Asked for none: the constant-bias fit, and no walk in the document.
    let none = run(&["--bias-walk", "0", "--gyro-bias-walk", "0"], "none");
    assert!(none.get("bias_walk").is_none(), "{none}");
    // By default both walks are estimated from the session; this short one determines neither,
    // so the fit is the constant-bias fit to the last digit.
    let default = run(&[], "default");
    assert_eq!(default["bias_walk"]["source"], "estimated", "{default}");
    assert_eq!(default["bias_walk"]["used"], false, "{default}");
    assert_eq!(default["gyro_walk"]["used"], false, "{default}");
    assert_eq!(default["parameters"], none["parameters"]);
}

/// `plan --check --bias-walk` advises on the order only where one helps: the paper's plan with each
/// mount's spins moved right after its rest gets the advice to run the static segments first (the
/// paper's own order) in its document; the paper's plan itself gets none, and no `order_advice` key.
#[test]
fn plan_check_advises_on_a_bad_order_only() {
    let dir = tempfile::tempdir().unwrap();
    let text = include_str!("../../recording/plans/paper.toml");
    let mut parts = text.split("[[segment]]");
    let head = parts.next().unwrap();
    let segs: Vec<&str> = parts.collect();
    let name = |s: &str| s.split('"').nth(1).unwrap().to_string();
    let order = [
        "x+", "x+ 100", "x+ 150", "x+ 200", "x-", "y+", "y+ 100", "y+ 150", "y+ 200", "y-", "z+",
        "z+ 100", "z+ 150", "z+ 200", "z-",
    ];
    let mut bad = head.to_string();
    for n in order {
        let s = segs.iter().find(|s| name(s) == n).unwrap();
        bad.push_str("[[segment]]");
        bad.push_str(s);
    }
    let path = dir.path().join("bad.toml");
    std::fs::write(&path, bad).unwrap();
    let check = |plan: &str| {
        let (ok, stdout, stderr) =
            host(&["plan", "--check", plan, "--bias-walk", "0.002", "--json"]);
        assert!(ok, "{stderr}");
        (
            serde_json::from_str::<serde_json::Value>(&stdout).unwrap(),
            stderr,
        )
    };
    let (v, stderr) = check(path.to_str().unwrap());
    let advice = v["order_advice"].as_array().expect("advice");
    assert!(advice[0]["change"]
        .as_str()
        .unwrap()
        .contains("static segments first"));
    let advised: Vec<&str> = advice[0]["order"]
        .as_array()
        .unwrap()
        .iter()
        .map(|n| n.as_str().unwrap())
        .collect();
    let paper: Vec<String> = segs.iter().map(|s| name(s)).collect();
    assert_eq!(advised, paper);
    assert!(stderr.contains("order under the walk"), "{stderr}");
    let (v, stderr) = check("paper");
    assert!(v.get("order_advice").is_none(), "{v}");
    assert!(!stderr.contains("order under the walk"), "{stderr}");
}

/// The walk from `host noise` end to end: a still recording simulated with a 0.01 mg/√s walk, its
/// Allan K (in V/√s: no calibration given) taken by `calibrate --bias-walk-from noise.json`, which
/// reports each axis's K over the fitted scale factor, ×10³ mg/√s: the noise file's figures turned
/// by hand here with the truth's scale factors (the fitted ones differ by parts in 10⁴), and within
/// 35 % of the simulated walk (half an hour of still data; an Allan K is a statistic of it).
#[test]
fn the_walk_from_host_noise_is_the_simulated_one() {
    let dir = tempfile::tempdir().unwrap();
    let p = |n: &str| dir.path().join(n).to_str().unwrap().to_string();
    std::fs::write(
        p("still.toml"),
        "format_version = 1\noutput_unit = \"V\"\nsample_rate_hz = 100.0\n\n[[segment]]\n\
         name = \"still\"\nup_b = [0, 0, 1]\nduration_s = 1800\n",
    )
    .unwrap();
    let walk = ["--drift-mg-sqrt-s", "0.01"];
    let mut args = vec!["-q", "simulate", "--out"];
    let (still, plan) = (p("still"), p("still.toml"));
    args.extend([still.as_str(), "--plan", plan.as_str(), "--seed", "3"]);
    args.extend(walk);
    let (ok, _, e) = host(&args);
    assert!(ok, "{e}");
    let noise_dir = p("noise");
    let (ok, _, e) = host(&["-q", "noise", "--input", &still, "--out", &noise_dir]);
    assert!(ok, "{e}");
    let noise: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(format!("{noise_dir}/noise.json")).unwrap())
            .unwrap();
    let cal = p("cal");
    let mut args = vec![
        "-q",
        "simulate",
        "--out",
        cal.as_str(),
        "--plan",
        "quick-oblique",
    ];
    args.extend(walk);
    let (ok, _, e) = host(&args);
    assert!(ok, "{e}");
    let json = format!("{noise_dir}/noise.json");
    let (ok, stdout, e) = host(&[
        "-q",
        "calibrate",
        "--input",
        &cal,
        "--bias-walk-from",
        &json,
        "--json",
    ]);
    assert!(ok, "{e}");
    let w = &serde_json::from_str::<serde_json::Value>(&stdout).unwrap()["bias_walk"];
    assert_eq!(w["source"], "unit");
    // The paper unit's scale factors, V/g (reference/paper-unit.toml).
    let k = [0.39496, 0.39808, 0.40024];
    for a in 0..3 {
        let axis = &noise["axes"][a];
        assert_eq!(axis["unit"], "output unit");
        let k_v = axis["terms"]["random_walk"].as_f64().unwrap();
        let by_hand = k_v / k[a] * 1e3;
        let got = w["axes_mg_sqrt_s"][a].as_f64().unwrap();
        assert!(
            (got / by_hand - 1.0).abs() < 1e-3,
            "{a}: {got} against {by_hand}"
        );
        assert!((got / 0.01 - 1.0).abs() < 0.35, "{a}: {got} against 0.01");
    }
}

/// `--bias-walk-from` a unit file whose `[noise]` holds both walks: the gyro's is assumed too (the
/// document says the file's figure), and `--gyro-bias-walk` given beside it takes its place.
#[test]
fn the_gyro_walk_comes_from_the_same_file_unless_given() {
    let dir = tempfile::tempdir().unwrap();
    let p = |n: &str| dir.path().join(n).to_str().unwrap().to_string();
    let paper = std::fs::read_to_string(concat!(
        env!("CARGO_MANIFEST_DIR"),
        "/../reference/paper-unit.toml"
    ))
    .unwrap();
    let unit = p("unit.toml");
    std::fs::write(
        &unit,
        format!(
            "{paper}\n[noise]\naccel_bias_walk_mg_sqrt_s = 0.002\n\
             gyro_bias_walk_deg_s_sqrt_s = 0.0003\n"
        ),
    )
    .unwrap();
    let session = p("s");
    let (ok, _, e) = host(&[
        "-q",
        "simulate",
        "--out",
        &session,
        "--plan",
        "quick-oblique",
    ]);
    assert!(ok, "{e}");
    let gyro_walk = |extra: &[&str]| {
        let mut args = vec![
            "-q",
            "calibrate",
            "--input",
            &session,
            "--bias-walk-from",
            &unit,
        ];
        args.extend_from_slice(extra);
        args.extend(["--json", "--force"]);
        let (ok, stdout, e) = host(&args);
        assert!(ok, "{e}");
        let doc: serde_json::Value = serde_json::from_str(&stdout).unwrap();
        assert_eq!(doc["bias_walk"]["axes_mg_sqrt_s"][0], 0.002, "{doc}");
        doc["gyro_bias_walk_deg_s_sqrt_s"].as_f64()
    };
    assert_eq!(gyro_walk(&[]), Some(0.0003));
    assert_eq!(gyro_walk(&["--gyro-bias-walk", "0.0001"]), Some(0.0001));
}
