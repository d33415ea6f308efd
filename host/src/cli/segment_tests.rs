//! `host segment` end to end on simulated hand sessions: positions found, the calibration from the
//! session it writes, the gyro from the turns, logger formats and bad input.

use super::segment::{segment, SegmentArgs};
use super::{calibrate, Cli, Command};
use clap::Parser;
use estimator::sim::handheld::{
    logger_unit, simulate_hand, write_logger_csv, HandSpec, LoggerLayout,
};
use estimator::sim::montecarlo::static_errors;
use shared::linalg::{self, RowMajor3};
use shared::{Calibration, OutputUnit};
use std::path::Path;

fn args(line: &str) -> Command {
    Cli::try_parse_from(line.split_whitespace())
        .unwrap()
        .command
}

fn segment_args(line: &str) -> SegmentArgs {
    match args(line) {
        Command::Segment(a) => a,
        c => panic!("{c:?}"),
    }
}

/// Writes a simulated hand session as a logger CSV in `dir/raw.csv`.
fn write_raw(dir: &Path, unit: OutputUnit, spec: &HandSpec, layout: &LoggerLayout) -> Calibration {
    let truth = logger_unit(unit);
    let sim = simulate_hand(&truth, spec);
    write_logger_csv(&dir.join("raw.csv"), &sim.rows, layout).unwrap();
    truth
}

/// The truth gyro matrix in the calibration's conventional body frame (x along accelerometer x's
/// sensing axis, y in the plane of x and y): `G_conv = G·Cᵀ` with C's rows the frame's axes.
fn gyro_in_convention(truth: &Calibration, g: &RowMajor3) -> RowMajor3 {
    let a = truth.statics.to_fitted().unwrap().0.m_out_per_g;
    let n = |v: [f64; 3]| v.map(|c| c / linalg::norm(&v));
    let e1 = n(a[0]);
    let e3 = n(linalg::cross(&a[0], &a[1]));
    let e2 = linalg::cross(&e3, &e1);
    let c = [e1, e2, e3];
    core::array::from_fn(|i| core::array::from_fn(|j| (0..3).map(|k| g[i][k] * c[j][k]).sum()))
}

fn run_session(
    dir: &Path,
    unit: OutputUnit,
    spec: &HandSpec,
) -> (
    Calibration,
    super::segment::SegmentOutcome,
    estimator::estimate::CalibrationOutcome,
) {
    let truth = write_raw(dir, unit, spec, &LoggerLayout::default());
    let d = dir.display();
    let out = segment(&segment_args(&format!(
        "host segment --input {d}/raw.csv --out {d}/s --time-column t --acc-unit {} --gyro-unit deg/s",
        unit.symbol()
    )))
    .unwrap();
    let cal = match args(&format!("host calibrate --input {d}/s --out-dir {d}/cal")) {
        Command::Calibrate(a) => calibrate::calibrate(&a, true).unwrap(),
        c => panic!("{c:?}"),
    };
    (truth, out, cal)
}

#[test]
fn hand_session_in_m_s2_and_deg_s_calibrates_accelerometer_and_gyro() {
    let tmp = tempfile::tempdir().unwrap();
    let spec = HandSpec::standard(7);
    let (truth, out, cal) = run_session(tmp.path(), OutputUnit::MetresPerSecondSquared, &spec);
    assert_eq!(out.segmentation.stills.len(), spec.ups.len());
    let e = static_errors(&truth, &cal.fitted, &mut shared::rng::Rng::new(3, 0));
    println!(
        "hand session: intrinsic (worst after the best common rotation) {:.1} µg, rms {:.1} µg",
        e.worst_ug, e.rms_ug
    );
    // The intrinsic error as the fixture Monte Carlo defines it: rms over held-out attitudes after
    // the best common rotation (the body frame is a convention here).
    assert!(e.rms_ug <= 30.0, "{:.1} µg", e.rms_ug);
    let fit = out.gyro.unwrap();
    let want = gyro_in_convention(&truth, &spec.gyro.matrix);
    for i in 0..3 {
        let (ne, nw) = (linalg::norm(&fit.matrix[i]), linalg::norm(&want[i]));
        let scale_err = (ne / nw - 1.0).abs();
        let angle = (linalg::dot(&fit.matrix[i], &want[i]) / ne / nw)
            .clamp(-1.0, 1.0)
            .acos()
            .to_degrees();
        let bias_err = (fit.bias_rad_s[i] - spec.gyro.bias_rad_s[i])
            .abs()
            .to_degrees();
        println!(
            "gyro axis {i}: scale error {:.4} %, axis error {:.4}°, bias error {:.4} °/s",
            scale_err * 100.0,
            angle,
            bias_err
        );
        assert!(scale_err <= 1e-3, "axis {i}: scale {scale_err}");
        assert!(angle <= 0.1, "axis {i}: {angle}°");
        assert!(bias_err <= 0.01, "axis {i}: bias {bias_err} °/s");
    }
    assert!(fit.undetermined().is_empty(), "{:?}", fit.undetermined());
    let text = std::fs::read_to_string(tmp.path().join("s/gyro.toml")).unwrap();
    let v: toml::Table = toml::from_str(&text).unwrap();
    assert!(v["gyro"].get("matrix").is_some() && v["gyro"].get("bias_rad_s").is_some());
    assert!(tmp.path().join("s/segments.svg").exists());
    // `host calibrate --input` carries the hand gyro into calibration.toml with the same keys.
    let cal_file =
        estimator::unit_file::UnitFile::load(&tmp.path().join("cal/calibration.toml")).unwrap();
    let g = cal_file.gyro.expect("[gyro] in calibration.toml");
    assert_eq!(g.matrix, fit.matrix);
}

/// Bound on one seed's intrinsic rms error in the logger-format tests (which test reading the format):
/// the 20-seed run of the stated session (`hand_sessions_many_seeds`) has a mean of 21 µg and a
/// maximum of 30 µg, so one seed is held to 1.5 × the 30 µg average requirement.
const SINGLE_SEED_UG: f64 = 45.0;

/// Segments `dir/raw.csv` with the given flags and calibrates the session; returns the stills found
/// and the intrinsic rms error, µg.
fn segment_and_calibrate(dir: &Path, truth: &Calibration, flags: &str) -> (usize, f64) {
    let d = dir.display();
    let out = segment(&segment_args(&format!(
        "host segment --input {d}/raw.csv --out {d}/s {flags}"
    )))
    .unwrap();
    let cal = match args(&format!("host calibrate --input {d}/s --out-dir {d}/cal")) {
        Command::Calibrate(a) => calibrate::calibrate(&a, true).unwrap(),
        c => panic!("{c:?}"),
    };
    let e = static_errors(truth, &cal.fitted, &mut shared::rng::Rng::new(5, 0));
    (out.segmentation.stills.len(), e.rms_ug)
}

#[test]
fn logger_m_s2_deg_s_at_102_4_hz_with_a_sample_index() {
    let tmp = tempfile::tempdir().unwrap();
    let spec = HandSpec {
        rate_hz: 102.4,
        ..HandSpec::standard(11)
    };
    let layout = LoggerLayout {
        time_column: None,
        ..LoggerLayout::default()
    };
    let truth = write_raw(
        tmp.path(),
        OutputUnit::MetresPerSecondSquared,
        &spec,
        &layout,
    );
    let head = std::fs::read_to_string(tmp.path().join("raw.csv")).unwrap();
    assert!(head.starts_with("sample,acc_x,acc_y,acc_z,gyr_x,gyr_y,gyr_z\n0,"));
    let (n, rms) = segment_and_calibrate(
        tmp.path(),
        &truth,
        "--rate-hz 102.4 --acc-unit m/s2 --gyro-unit deg/s",
    );
    assert_eq!(n, 24);
    println!("102.4 Hz: intrinsic rms {rms:.1} µg");
    // This test is about the format. The 30 µg figure is for the stated 200 Hz session; at 102.4 Hz
    // each position has half the samples, so the noise-limited error is √(200/102.4) ≈ 1.4× larger.
    assert!(rms <= 1.4 * SINGLE_SEED_UG, "{rms} µg at 102.4 Hz");
}

#[test]
fn logger_g_rad_s_with_a_time_column_other_names_and_an_extra_column() {
    let tmp = tempfile::tempdir().unwrap();
    let spec = HandSpec::standard(12);
    let layout = LoggerLayout {
        columns: ["ax", "ay", "az", "gx", "gy", "gz"].map(String::from),
        time_column: Some("time".into()),
        gyro_deg_s: false,
        extra_column: true,
        ..LoggerLayout::default()
    };
    let truth = write_raw(tmp.path(), OutputUnit::StandardGravity, &spec, &layout);
    let (n, rms) = segment_and_calibrate(
        tmp.path(),
        &truth,
        "--columns ax,ay,az,gx,gy,gz --time-column time --acc-unit g --gyro-unit rad/s",
    );
    assert_eq!(n, 24);
    println!("intrinsic rms {rms:.1} µg");
    assert!(rms <= SINGLE_SEED_UG, "{rms} µg");
    let plan = std::fs::read_to_string(tmp.path().join("s/plan.toml")).unwrap();
    assert!(plan.contains("output_unit = \"g\""), "{plan}");
}

#[test]
fn logger_raw_counts() {
    let tmp = tempfile::tempdir().unwrap();
    let spec = HandSpec {
        acc_step: 1.0,
        ..HandSpec::standard(13)
    };
    let truth = write_raw(tmp.path(), OutputUnit::Lsb, &spec, &LoggerLayout::default());
    let (n, rms) = segment_and_calibrate(
        tmp.path(),
        &truth,
        "--time-column t --acc-unit LSB --gyro-unit deg/s",
    );
    assert_eq!(n, 24);
    println!("intrinsic rms {rms:.1} µg");
    assert!(rms <= SINGLE_SEED_UG, "{rms} µg");
    let cal = std::fs::read_to_string(tmp.path().join("cal/calibration.toml")).unwrap();
    assert!(cal.contains("scale_lsb_per_g"), "{cal}");
}

/// The message of `host segment` on `dir/raw.csv` with `flags`.
fn segment_error(dir: &Path, flags: &str) -> String {
    let d = dir.display();
    match segment(&segment_args(&format!(
        "host segment --input {d}/raw.csv --out {d}/s {flags}"
    ))) {
        Ok(_) => panic!("accepted"),
        Err(e) => e.to_string(),
    }
}

const M_S2: &str = "--time-column t --acc-unit m/s2 --gyro-unit deg/s";

#[test]
fn bad_recordings_get_a_message_saying_what_to_record() {
    let tmp = tempfile::tempdir().unwrap();
    let unit = OutputUnit::MetresPerSecondSquared;
    let lay = LoggerLayout::default();
    let base = HandSpec::standard(21);

    let moving = HandSpec {
        hold_s: (0.1, 0.2),
        ..base.clone()
    };
    write_raw(tmp.path(), unit, &moving, &lay);
    let m = segment_error(tmp.path(), M_S2);
    assert!(
        m.contains("no still interval") && m.contains("hold the unit still"),
        "{m}"
    );

    let one = HandSpec {
        ups: vec![[0.0, 0.0, 1.0]],
        ..base.clone()
    };
    write_raw(tmp.path(), unit, &one, &lay);
    let m = segment_error(tmp.path(), M_S2);
    assert!(
        m.contains("1 still interval(s) in 1 distinct") && m.contains("record 8 more"),
        "{m}"
    );

    let same = HandSpec {
        ups: vec![[0.6, 0.0, 0.8]; 12],
        ..base.clone()
    };
    write_raw(tmp.path(), unit, &same, &lay);
    let m = segment_error(tmp.path(), M_S2);
    assert!(m.contains("12 still interval(s) in 1 distinct"), "{m}");
    assert!(m.contains("x down") && m.contains("z down"), "{m}");

    let few = HandSpec {
        ups: base.ups[..6].to_vec(),
        ..base.clone()
    };
    write_raw(tmp.path(), unit, &few, &lay);
    let m = segment_error(tmp.path(), M_S2);
    assert!(
        m.contains("6 distinct position(s)") && m.contains("record 3 more"),
        "{m}"
    );
}

#[test]
fn bad_columns_and_units_get_a_message_naming_the_fix() {
    let tmp = tempfile::tempdir().unwrap();
    let spec = HandSpec::standard(22);
    let missing = LoggerLayout {
        columns: ["acc_x", "acc_y", "acc_z", "gyr_x", "gyr_y", "gyro_z"].map(String::from),
        ..LoggerLayout::default()
    };
    write_raw(
        tmp.path(),
        OutputUnit::MetresPerSecondSquared,
        &spec,
        &missing,
    );
    let m = segment_error(tmp.path(), M_S2);
    assert!(
        m.contains("'gyr_z' is not in the header") && m.contains("--columns"),
        "{m}"
    );

    // Gravity reads 9.8 "g": the file is in m/s².
    write_raw(
        tmp.path(),
        OutputUnit::MetresPerSecondSquared,
        &spec,
        &LoggerLayout::default(),
    );
    let m = segment_error(tmp.path(), "--time-column t --acc-unit g --gyro-unit deg/s");
    assert!(m.contains("--acc-unit m/s2"), "{m}");
    // Gravity reads 0.1 "m/s²": the file is in g.
    write_raw(
        tmp.path(),
        OutputUnit::StandardGravity,
        &spec,
        &LoggerLayout::default(),
    );
    let m = segment_error(tmp.path(), M_S2);
    assert!(m.contains("--acc-unit g"), "{m}");
    // A gyro in °/s declared rad/s turns 57× too far.
    write_raw(
        tmp.path(),
        OutputUnit::MetresPerSecondSquared,
        &spec,
        &LoggerLayout::default(),
    );
    let m = segment_error(
        tmp.path(),
        "--time-column t --acc-unit m/s2 --gyro-unit rad/s",
    );
    assert!(m.contains("--gyro-unit deg/s"), "{m}");
    assert!(
        !tmp.path().join("s/samples.csv").exists(),
        "no session from bad input"
    );
}

/// One simulated hand session through detection, calibration and the gyro fit, in memory:
/// (stills found == holds, intrinsic rms µg, intrinsic worst µg, worst gyro scale error, worst gyro
/// axis error °).
fn hand_case(spec: &HandSpec) -> (bool, f64, f64, f64, f64) {
    use estimator::estimate::{calibrate_session_stats, EstimateOptions};
    use recording::session::from_recording::{plan_for, stats_for};
    use recording::session::import::Recording;
    use recording::session::segment::{find_intervals, SegmentOptions};
    let unit = OutputUnit::MetresPerSecondSquared;
    let truth = logger_unit(unit);
    let sim = simulate_hand(&truth, spec);
    let rec = Recording {
        t_s: sim.rows.iter().map(|r| r.0).collect(),
        acc: sim.rows.iter().map(|r| r.1).collect(),
        gyro_rad_s: sim.rows.iter().map(|r| r.2).collect(),
        acc_unit: Some(unit),
        rate_hz: spec.rate_hz,
        ..Recording::default()
    };
    let seg = find_intervals(&rec, &SegmentOptions::new(super::spelling::FLAGS)).unwrap();
    let found_all = seg.stills.len() == sim.holds.len()
        && seg
            .stills
            .iter()
            .zip(&sim.holds)
            .all(|(s, h)| s.start_s >= h.0 && s.start_s + s.duration_s <= h.1);
    let plan = plan_for(&rec, &seg);
    let options = EstimateOptions {
        compare_methods: false,
        ..EstimateOptions::new(super::spelling::FLAGS)
    };
    let cal = calibrate_session_stats(&plan, &stats_for(&rec, &seg, &plan), &options).unwrap();
    let e = static_errors(
        &truth,
        &cal.fitted,
        &mut shared::rng::Rng::new(spec.seed, 0),
    );
    let dropped = app::handheld::gyro::dropped_turns(&rec, &seg);
    let fit = app::handheld::gyro::fit(&rec, &seg, &plan, &dropped, super::spelling::FLAGS)
        .unwrap()
        .unwrap();
    let want = gyro_in_convention(&truth, &spec.gyro.matrix);
    let (mut scale, mut axis) = (0.0f64, 0.0f64);
    for i in 0..3 {
        let (ne, nw) = (linalg::norm(&fit.matrix[i]), linalg::norm(&want[i]));
        scale = scale.max((ne / nw - 1.0).abs());
        let c = (linalg::dot(&fit.matrix[i], &want[i]) / ne / nw).clamp(-1.0, 1.0);
        axis = axis.max(c.acos().to_degrees());
    }
    (found_all, e.rms_ug, e.worst_ug, scale, axis)
}

/// The stated hand session over many seeds: every position found, the intrinsic error and the gyro.
/// `cargo test -p host --release --lib hand_sessions_many_seeds -- --ignored --nocapture`
#[test]
#[ignore]
fn hand_sessions_many_seeds() {
    many_seeds(100..120, 200.0);
}

/// The short run of [`hand_sessions_many_seeds`].
#[test]
fn hand_sessions_two_seeds() {
    many_seeds(100..102, 200.0);
}

fn many_seeds(seeds: std::ops::Range<u64>, rate_hz: f64) {
    let mut rows = Vec::new();
    for seed in seeds {
        let spec = HandSpec {
            rate_hz,
            ..HandSpec::standard(seed)
        };
        let r = hand_case(&spec);
        println!(
            "seed {seed}: positions {} | intrinsic rms {:5.1} µg, worst {:5.1} µg | gyro scale {:.4} %, axis {:.4}°",
            if r.0 { "all found" } else { "MISSED" },
            r.1,
            r.2,
            r.3 * 100.0,
            r.4
        );
        rows.push(r);
    }
    let n = rows.len() as f64;
    let mut rms: Vec<f64> = rows.iter().map(|r| r.1).collect();
    rms.sort_by(f64::total_cmp);
    let mean_rms = rms.iter().sum::<f64>() / n;
    let worst_scale = rows.iter().map(|r| r.3).fold(0.0, f64::max);
    let worst_axis = rows.iter().map(|r| r.4).fold(0.0, f64::max);
    println!(
        "{} sessions at {rate_hz} Hz: all positions found in {}; intrinsic rms mean {mean_rms:.1} µg, max {:.1} µg; \
         gyro worst scale error {:.4} %, worst axis error {:.4}°",
        rows.len(),
        rows.iter().filter(|r| r.0).count(),
        rms[rms.len() - 1],
        worst_scale * 100.0,
        worst_axis
    );
    assert!(rows.iter().all(|r| r.0));
    // The intrinsic error is noise-limited (about 50 µg per position mean, 24 positions): 30 µg is
    // met on average over seeds; one seed may exceed it (20 seeds 100–119: mean 20.8 µg, max 29.5 µg).
    assert!(mean_rms <= 30.0, "mean {mean_rms:.1} µg");
    assert!(worst_scale <= 1e-3 && worst_axis <= 0.1);
}
