//! The estimator's outcomes as people read them: each test fits a simulated session with known truth
//! and checks what the terminal text, the report's tables and figures and the JSON summary say of
//! it (the fits themselves are checked in `estimate`'s own tests).

use crate::report::{
    build_report, page::page, render, render_prediction, render_session, ReportOptions,
};
use crate::summary::{CalibrationSummary, Limits};
use estimator::estimate::*;
use estimator::sim::synth;
use estimator::sim::testkit::{self, *};
use estimator::sim::thermal::ThermalSim;
use recording::session::Package;
use shared::sensor_models::poly_no_constant;
use shared::{Compensator, LeverMode, OutputUnit};

/// The paper plan's prediction names its bound and the lever-arm components it cannot determine.
#[test]
fn the_paper_plans_prediction_says_what_it_cannot_determine() {
    let truth = testkit::paper_unit();
    let settings = PredictSettings::white(paper_noise(&truth), recording::testkit::SPELLING);
    let plan = testkit::paper_plan(OutputUnit::Volts);
    let stats = synth::prediction_stats(&plan, &truth, &settings).unwrap();
    let prediction = predict(&plan, &truth, &stats, &settings).unwrap();
    let text = render_prediction(&prediction);
    assert!(
        text.contains("Cramér–Rao") && text.contains("not determined"),
        "{text}"
    );
}

/// The paper's method beside the joint fit on the paper's plan: the text prints both.
#[test]
fn paper_method_and_joint_fit_are_both_printed() {
    let plan = testkit::paper_plan(OutputUnit::Volts);
    let (_, stats) = clean_session(&plan, 3);
    let out = calibrate_session_stats(&plan, &stats, &EstimateOptions::default()).unwrap();
    let text = render(&out, &[]);
    assert!(
        text.contains("paper eq. 24") && text.contains("joint"),
        "{text}"
    );
}

#[test]
fn noise_free_paper_session_recovers_the_unit_exactly() {
    let truth = testkit::paper_unit();
    let plan = testkit::paper_plan(OutputUnit::Volts);
    let unit = shared::forward::ForwardModel::new(&truth).unwrap();
    let noise = synth::SynthNoise {
        out_1sigma: [paper_noise(&truth); 3],
        gyro_1sigma_rad_s: 0.0,
        sample_rate_hz: 1000.0,
    };
    let stats = synth::plan_stats(&plan, &unit, &noise, 60.0);
    let out = calibrate_session_stats(&plan, &stats, &EstimateOptions::default()).unwrap();
    let want = paper_values(&truth).unwrap();
    let got = paper_values(&out.calibration).unwrap();
    for p in 0..PAPER_LEN {
        assert!(
            (want[p] - got[p]).abs() < 1e-9 * want[p].abs().max(1e-3),
            "{}: {} vs {}",
            paper_labels()[p],
            got[p],
            want[p]
        );
    }
    assert!(out.excluded.is_empty(), "{:?}", out.excluded);
    // The paper's plan leaves the across-axis components undetermined to 200 µm.
    for i in 0..3 {
        for j in 0..3 {
            assert_eq!(out.observability.observable[i][j], i == j, "r{i}{j}");
        }
    }
    let text = render_session(&out, &plan, &stats);
    assert!(text.contains("Table 1") && text.contains("n.d."), "{text}");
}

#[test]
fn missing_and_unknown_segments_are_named() {
    let plan = testkit::paper_plan(OutputUnit::Volts);
    let (_, mut stats) = clean_session(&plan, 1);
    let removed = stats.remove(7); // "x+ 150"
    let mut extra = stats[0].clone();
    extra.name = "bonus".into();
    stats.push(extra);
    let out = calibrate_session_stats(&plan, &stats, &EstimateOptions::default()).unwrap();
    let reasons: Vec<(String, ExclusionReason)> = out
        .excluded
        .iter()
        .map(|e| (e.name.clone(), e.reason.clone()))
        .collect();
    assert!(reasons.contains(&(removed.name.clone(), ExclusionReason::MissingFromData)));
    assert!(reasons.contains(&("bonus".into(), ExclusionReason::NotInPlan)));
    assert!(out.warnings.iter().any(|w| matches!(w,
        estimator::estimate::note::Note::SegmentMissingFromData { segment }
            if *segment == removed.name)));
    let text = render_session(&out, &plan, &stats);
    assert!(
        text.contains("Excluded segments") && text.contains("'bonus'"),
        "{text}"
    );
    let strict = EstimateOptions {
        strict_segments: true,
        ..EstimateOptions::default()
    };
    let e = calibrate_session_stats(&plan, &stats, &strict).unwrap_err();
    assert!(
        matches!(e, EstimateError::UnknownSegment { ref name } if name == "bonus"),
        "{e}"
    );
    stats.pop();
    let e = calibrate_session_stats(&plan, &stats, &strict).unwrap_err();
    assert!(
        e.to_string().contains(&removed.name) && e.to_string().contains("plan.toml"),
        "{e}"
    );
}

#[test]
fn bad_segments_are_excluded_with_reasons() {
    // The paper's plan plus six oblique static attitudes, so that the fit survives five bad statics.
    let mut plan = testkit::paper_plan(OutputUnit::Volts);
    let s3 = 1.0 / 3f64.sqrt();
    for (k, up) in [
        [s3, s3, s3],
        [-s3, s3, s3],
        [s3, -s3, s3],
        [s3, s3, -s3],
        [-s3, -s3, s3],
        [-s3, s3, -s3],
    ]
    .into_iter()
    .enumerate()
    {
        let mut seg = plan.segments[0].clone();
        seg.name = format!("oblique {k}");
        seg.up_b = up;
        plan.segments.push(seg);
    }
    let (_, clean) = clean_session(&plan, 2);
    let reason_of = |out: &CalibrationOutcome, name: &str| {
        out.excluded
            .iter()
            .find(|e| e.name == name)
            .map(|e| e.reason.clone())
    };
    let mut stats = clean.clone();
    // A static segment with motion: the gyro shows 2 °/s.
    stats[2].mean_w_rad_s = [0.0, 0.0, 2f64.to_radians()];
    // Another one shakes: its outputs are 5× noisier, and its mean is off.
    stats[3].cov_u[0][0] *= 25.0;
    stats[3].mean_u[0] += 1e-3;
    // An empty segment, a stuck output, a wrong attitude (z+ recorded where the plan says x−), and a
    // rotation that did not happen.
    stats[4].count = 0;
    stats[5].min_u[2] = stats[5].max_u[2];
    stats[1].mean_u = clean[4].mean_u;
    stats[10].mean_w_rad_s = [0.0, 0.0, 0.0];
    let out = calibrate_session_stats(&plan, &stats, &EstimateOptions::default()).unwrap();
    for e in &out.excluded {
        eprintln!("{}: {}", e.name, e.reason);
    }
    assert!(matches!(
        reason_of(&out, "y+"),
        Some(ExclusionReason::Motion { .. })
    ));
    assert!(matches!(
        reason_of(&out, "y-"),
        Some(ExclusionReason::Motion { .. })
    ));
    assert!(matches!(
        reason_of(&out, "z+"),
        Some(ExclusionReason::Empty { rows: 0, .. })
    ));
    assert!(matches!(
        reason_of(&out, "z-"),
        Some(ExclusionReason::Saturated { axis: 2, .. })
    ));
    assert!(matches!(
        reason_of(&out, "x-"),
        Some(ExclusionReason::AttitudeContradiction { .. })
    ));
    assert!(matches!(
        reason_of(&out, "y+ 150"),
        Some(ExclusionReason::RateContradiction { .. })
    ));
    assert_eq!(out.excluded.len(), 6, "{:?}", out.excluded);
    let text = render_session(&out, &plan, &stats);
    assert!(
        text.contains("planned static but moved") && text.contains("from the plan's up_b"),
        "{text}"
    );
    // What is left still gives the unit, within its (larger) 1σ.
    let truth = testkit::paper_unit();
    let a = paper_values(&out.calibration).unwrap();
    let b = paper_values(&truth).unwrap();
    for p in 0..PAPER_LEN {
        let s = out.covariance[p][p].sqrt();
        assert!(
            (a[p] - b[p]).abs() < 5.0 * s,
            "{}: {} vs {} ± {s}",
            paper_labels()[p],
            a[p],
            b[p]
        );
    }
    // An output range: a segment touching the rail is saturated.
    let options = EstimateOptions {
        output_range: Some([0.0, clean[0].max_u[0] - 1e-6]),
        ..EstimateOptions::default()
    };
    let out = calibrate_session_stats(&plan, &clean, &options).unwrap();
    assert!(matches!(
        reason_of(&out, "x+"),
        Some(ExclusionReason::Saturated { axis: 0, .. })
    ));
}

#[test]
fn plans_that_cannot_observe_lever_arms_flag_them() {
    // Static only: no lever arm is observable; they are fixed at 0, and the text says they are not
    // calibrated (no advice about tilted mounts or a table centre for a plan that never turns).
    let mut plan = testkit::paper_plan(OutputUnit::Volts);
    plan.segments.retain(|s| s.is_static());
    let (_, stats) = clean_session(&plan, 4);
    let out = calibrate_session_stats(&plan, &stats, &EstimateOptions::default()).unwrap();
    assert_eq!(out.observability.fixed_at_zero, [[true; 3]; 3]);
    assert_eq!(out.uncertainty.lever_arms_observable, [[false; 3]; 3]);
    assert_eq!(out.calibration.lever_arms.r_m, [[0.0; 3]; 3]);
    let text = render_session(&out, &plan, &stats);
    assert!(text.contains("Lever arms: not calibrated"), "{text}");
    for table_word in ["oblique", "table centre", "Table 3"] {
        assert!(!text.contains(table_word), "{text}");
    }
    let require = EstimateOptions {
        require_lever_arms: true,
        ..EstimateOptions::default()
    };
    let e = calibrate_session_stats(&plan, &stats, &require).unwrap_err();
    assert!(
        matches!(e, EstimateError::PlanCannotObserve { ref parameters, .. } if parameters.len() == 9),
        "{e}"
    );
    // The paper's method needs x, y and z-up spins.
    let paper = EstimateOptions {
        method: Method::Paper,
        ..EstimateOptions::default()
    };
    let e = calibrate_session_stats(&plan, &stats, &paper).unwrap_err();
    assert!(e.to_string().contains("eq. 24"), "{e}");

    // Only the z axis spun: the z components are not seen at all, nor the x/y across-components of
    // accelerometers x and y; the along-axis r1x, r2y still are.
    let mut plan = testkit::paper_plan(OutputUnit::Volts);
    plan.segments.retain(|s| s.is_static() || s.up_b[2] > 0.5);
    let (truth, stats) = clean_session(&plan, 5);
    let out = calibrate_session_stats(&plan, &stats, &EstimateOptions::default()).unwrap();
    let obs = &out.observability;
    eprintln!("{:?}\n{:?}", obs.observable, obs.fixed_at_zero);
    for i in 0..3 {
        assert!(obs.fixed_at_zero[i][2], "r{}z", i + 1);
        assert!(!obs.observable[i][2]);
    }
    assert!(obs.observable[0][0] && obs.observable[1][1]);
    assert!(!obs.observable[0][1] && !obs.observable[1][0]);
    // A z spin shows accelerometer i only `a_ix·r_ix + a_iy·r_iy`; with the across component r_ij
    // (j ≠ i) fixed at zero, the along component takes its share: r_ii + (a_ij/a_ii)·r_ij. For the
    // paper's unit that is +5 µm on r1x and −33 µm on r2y (a_yx = cos 89.255° times r2x = −2.56 mm).
    let (a, _) = truth.statics.sensing_directions().unwrap();
    for i in 0..2 {
        let j = 1 - i;
        let r = &truth.lever_arms.r_m[i];
        let expected = r[i] + a[i][j] / a[i][i] * r[j];
        let got = out.calibration.lever_arms.r_m[i][i];
        assert!(
            (got - expected).abs() < 30e-6,
            "r{i}{i}: {got} vs {expected}"
        );
    }
}

#[test]
fn soak_steps_calibrate_bias_and_scale_over_temperature() {
    let truth = hot_unit();
    let plan = soak_plan(&[-20.0, 5.0, 25.0, 40.0, 60.0], 10.0);
    let stats = simulate_stats(&truth, &plan, &nuisances(), &ThermalSim::default(), 7);
    let out = calibrate_session_stats(&plan, &stats, &EstimateOptions::default()).unwrap();
    let fit = out.thermal.as_ref().expect("a temperature model");
    let th = truth.temperature.unwrap();
    // The data chose the true degrees: quadratic bias, linear scale.
    assert_eq!(fit.zero_bias_degree, [2; 3], "{:?}", fit.notes);
    assert_eq!(fit.scale_degree, [1; 3], "{:?}", fit.notes);
    // Every fitted coefficient within 4σ of the truth, and its 1σ small against it.
    for i in 0..3 {
        for k in 0..2 {
            let (est, sd) = (
                fit.model.zero_bias_out_per_c[i][k],
                fit.zero_bias_sigma[i][k],
            );
            let t = th.zero_bias_out_per_c[i][k];
            assert!(
                (est - t).abs() < 4.0 * sd,
                "P[{i}][{k}] {est} ± {sd} vs {t}"
            );
            assert!(sd < 0.05 * t.abs(), "P[{i}][{k}] 1σ {sd} vs {t}");
        }
        let (est, sd) = (fit.model.scale_rel_per_c[i][0], fit.scale_sigma[i][0]);
        let t = th.scale_rel_per_c[i][0];
        assert!((est - t).abs() < 4.0 * sd, "S[{i}] {est} ± {sd} vs {t}");
    }
    assert_eq!(fit.model.reference_c, 25.0);
    let [lo, hi] = fit.model.valid_range_c;
    assert!(
        (lo + 20.0).abs() < 0.2 && (hi - 60.0).abs() < 0.2,
        "{lo} {hi}"
    );

    // Held-out attitudes at held-out temperatures: the intrinsic error with and without the model.
    let mut without = out.calibration;
    without.temperature = None;
    for temp in [0.0, 45.0] {
        let with = worst_error_ug(&truth, &out.calibration, temp, &HELD_OUT_UPS);
        let plain = worst_error_ug(&truth, &without, temp, &HELD_OUT_UPS);
        println!(
            "held-out at {temp} °C: worst error {with:.1} µg with the model, {plain:.0} µg without"
        );
        assert!(with <= 30.0, "{temp} °C: {with} µg");
        assert!(plain > 3000.0, "{temp} °C: {plain} µg without the model");
    }
    // The fitted curves' 1σ bands hold the truth, and the figure draws them.
    for i in 0..3 {
        for temp in [0.0, 45.0] {
            let dt = temp - th.reference_c;
            for (c, cov, truth) in [
                (
                    &fit.model.zero_bias_out_per_c[i],
                    &fit.zero_bias_cov[i],
                    poly_no_constant(&th.zero_bias_out_per_c[i], dt),
                ),
                (
                    &fit.model.scale_rel_per_c[i],
                    &fit.scale_cov[i],
                    poly_no_constant(&th.scale_rel_per_c[i], dt),
                ),
            ] {
                let (y, sd) = fit.curve(c, cov, temp);
                assert!(
                    sd > 0.0 && (y - truth).abs() < 4.0 * sd,
                    "{i} {temp}: {y} ± {sd} vs {truth}"
                );
            }
        }
    }
    let soaks = crate::report::thermal::soak_points(&out, &plan, &stats);
    let fig = crate::report::thermal::figure(&out, Some(&soaks)).unwrap();
    assert_eq!(fig.panels.len(), 9);
    assert_eq!(fig.panels[6].series[0].points.len(), plan.segments.len());
    // Each soak's measured bias lies on the true curve within its own noise and the misalignment's
    // share (independent truth: the simulated unit's tempco).
    for i in 0..3 {
        assert!(!soaks.bias_mg[i].is_empty(), "axis {i}: no soak pair");
        for &(t, mg, sigma) in &soaks.bias_mg[i] {
            let truth = poly_no_constant(&th.zero_bias_out_per_c[i], t - fit.model.reference_c)
                / out.calibration.statics.scale_out_per_g[i]
                * 1e3;
            assert!(
                (mg - truth).abs() < 5.0 * sigma + 0.02,
                "axis {i} {t} °C: {mg} vs {truth} mg"
            );
        }
    }
    let dir = tempfile::tempdir().unwrap();
    let formats = crate::report::plot::Formats {
        png: false,
        svg: true,
    };
    let drawn = crate::report::plot::render(&fig, dir.path(), formats).unwrap();
    assert!(dir.path().join("temperature.svg").exists(), "{drawn:?}");

    // Outside the range: clamped and flagged.
    let mut comp = Compensator::new(&out.calibration, LeverMode::Off).unwrap();
    assert!(comp.refresh(70.0).is_flagged());
    assert!(!comp.refresh(45.0).is_flagged());
}

/// The terminal text, the JSON summary and the report's Table 3 of a single-package fit say the
/// in-package size effect is not observable and give the package's one lever arm, not three rows;
/// a nine-component fit of the same session shows three rows and no such line.
#[test]
fn outputs_say_the_in_package_size_effect_is_not_observable() {
    let truth = single_package_unit();
    let (one, nine) = single_package_fits(&truth, 3);
    let text = render(&one, &[]);
    assert!(
        text.contains("in-package size effect") && text.contains("not observable"),
        "{text}"
    );
    assert!(text.contains("\nr    ") && !text.contains("\nr2 ") && !text.contains("\nr3 "));
    let text9 = render(&nine, &[]);
    assert!(!text9.contains("in-package") && text9.contains("\nr2 "));
    let json = |o: &CalibrationOutcome| {
        serde_json::to_value(CalibrationSummary::new(o, None, &Limits::default())).unwrap()
    };
    let j = json(&one);
    assert!(j["in_package_size_effect"]
        .as_str()
        .is_some_and(|s| s.contains("not observable")));
    assert_eq!(j["calibration"]["dynamic"]["package"], "single");
    assert!(json(&nine).get("in_package_size_effect").is_none());
    // The HTML/Markdown report's Table 3.
    let p = single_package_plan(Package::Single);
    let stats = simulate_stats(&truth, &p, &mems_noise(), &ThermalSim::default(), 3);
    let data = build_report(
        &p,
        &stats,
        &one.calibration,
        Some(&one.uncertainty),
        Ok(one.clone()),
        &ReportOptions::default(),
    )
    .unwrap();
    let blocks = format!("{:?}", page(&data, "s", "c", &[]));
    assert!(blocks.contains("Lever arm of the package") && blocks.contains("not observable"));
    assert!(!blocks.contains("\"r2\""), "{blocks}");
}

/// `host plan --check single-package`'s text: the common lever arm is observable, the in-package
/// size effect is not.
#[test]
fn plan_check_says_the_common_lever_arm_is_observable() {
    let truth = single_package_unit();
    let p = single_package_plan(Package::Single);
    let k = truth.statics.scale_out_per_g;
    let settings = PredictSettings {
        noise_out_per_sample_1sigma: k.map(|k| 1e-3 * k.abs()),
        gyro_noise_rad_s: 0.05f64.to_radians(),
        ..PredictSettings::white(0.0, recording::testkit::SPELLING)
    };
    let stats = synth::prediction_stats(&p, &truth, &settings).unwrap();
    let prediction = predict(&p, &truth, &stats, &settings).unwrap();
    assert!(prediction.single_package);
    let text = render_prediction(&prediction);
    assert!(
        text.contains("Common lever arm r") && text.contains(": observable"),
        "{text}"
    );
    assert!(
        text.contains("in-package size effect") && !text.contains("  r2x"),
        "{text}"
    );
    for j in 0..3 {
        assert!(
            prediction.sigma[15 + j] < 12e-6,
            "{}",
            prediction.sigma[15 + j]
        );
    }
}

/// A gyro bias walk the fit assumed is said: in the text (its strength, docs/model.md §11.6) and
/// in the JSON summary; without one, neither.
#[test]
fn a_gyro_bias_walk_is_said_in_the_text_and_the_summary() {
    let plan = testkit::paper_plan(OutputUnit::Volts);
    let (_, stats) = clean_session(&plan, 5);
    for k in [0.0, 3e-4] {
        let options = EstimateOptions {
            gyro_bias_walk_deg_s_sqrt_s: k,
            ..EstimateOptions::default()
        };
        let out = calibrate_session_stats(&plan, &stats, &options).unwrap();
        let text = render(&out, &[]);
        let json =
            serde_json::to_value(CalibrationSummary::new(&out, None, &Limits::default())).unwrap();
        let field = json
            .get("gyro_bias_walk_deg_s_sqrt_s")
            .and_then(|v| v.as_f64());
        if k > 0.0 {
            assert!(
                text.contains("Gyro bias random walk: 0.00030 °/s/√s"),
                "{text}"
            );
            assert_eq!(field, Some(k));
        } else {
            assert!(!text.contains("Gyro bias random walk"), "{text}");
            assert_eq!(field, None);
        }
    }
}

/// The gyro walk estimated per axis is said where the fit used it: the text's line gives each
/// axis's strength with its 1σ and the strengths the means were weighted with, and the JSON's
/// `gyro_walk.axes` them all, `gyro_bias_walk_deg_s_sqrt_s` the strongest; where the axes walk
/// alike the line is the one strength's, as it always was, and `gyro_walk.axes` says why
/// (not used). Against the simulated walks (docs/model.md §11.6).
#[test]
fn a_gyro_walk_per_axis_is_said_where_it_is_used() {
    let truth = testkit::single_package_unit();
    let plan = testkit::paper_plan(OutputUnit::Lsb);
    for (walks, per_axis) in [([0.0002, 0.0005, 0.0015], true), ([0.0005; 3], false)] {
        let noise = estimator::sim::NoiseModel {
            accel_bias_walk_mg_sqrt_s: 0.002,
            gyro_bias_walk_per_axis_deg_s_sqrt_s: Some(walks),
            ..testkit::mems_noise()
        };
        let stats = estimator::sim::simulate_stats(&truth, &plan, &noise, 40).unwrap();
        let options = EstimateOptions::default().drift_aware();
        let out = calibrate_session_stats(&plan, &stats, &options).unwrap();
        let text = render(&out, &[]);
        let line = text
            .lines()
            .find(|l| l.starts_with("Gyro bias random walk"))
            .unwrap();
        println!("{line}");
        let json =
            serde_json::to_value(CalibrationSummary::new(&out, None, &Limits::default())).unwrap();
        let axes = &json["gyro_walk"]["axes"];
        let a = out.gyro_walk.unwrap().axes.unwrap();
        assert_eq!(axes["used"], per_axis, "{json}");
        assert_eq!(axes["deg_s_sqrt_s"][2].as_f64(), Some(a.deg_s_sqrt_s[2]));
        assert_eq!(json["gyro_walk"]["used"], true);
        // A summary written before per-axis walks, without the key, still reads.
        let mut before = json["gyro_walk"].clone();
        before.as_object_mut().unwrap().remove("axes");
        let read: crate::summary::GyroWalkSummary = serde_json::from_value(before).unwrap();
        assert!(read.axes.is_none());
        let weighted = json["gyro_bias_walk_deg_s_sqrt_s"].as_f64().unwrap();
        if per_axis {
            let z = format!(
                "z {:.6} ± {:.6}",
                a.deg_s_sqrt_s[2], a.sigma_deg_s_sqrt_s[2]
            );
            assert!(
                line.contains(&z) && line.contains("weighted per axis"),
                "{line}"
            );
            assert_eq!(weighted, a.fit_deg_s_sqrt_s[2]);
            // The strongest axis is the one simulated strongest, within 3σ of it.
            assert!((a.deg_s_sqrt_s[2] - walks[2]).abs() < 3.0 * a.sigma_deg_s_sqrt_s[2]);
        } else {
            assert!(!line.contains("per axis"), "{line}");
            assert!(
                line.contains("; the gyro's mean rates weighted with √(K² + σ²) = "),
                "{line}"
            );
            assert_eq!(
                weighted,
                json["gyro_walk"]["deg_s_sqrt_s"]
                    .as_f64()
                    .unwrap()
                    .hypot(json["gyro_walk"]["sigma_deg_s_sqrt_s"].as_f64().unwrap())
            );
        }
    }
}
