//! `host segment` end to end on simulated hand sessions: positions found, the calibration from the
//! session it writes, the gyro from the turns, logger formats and bad input.

use super::segment::{segment, SegmentArgs};
use super::{calibrate, Cli, Command};
use crate::sim::handheld::{logger_unit, simulate_hand, write_logger_csv, HandSpec, LoggerLayout};
use crate::sim::montecarlo::static_errors;
use crate::sim::testkit;
use clap::Parser;
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
    crate::estimate::CalibrationOutcome,
) {
    let truth = write_raw(dir, unit, spec, &LoggerLayout::default());
    let d = dir.display();
    let out = segment(&segment_args(&format!(
        "host segment --input {d}/raw.csv --out {d}/s --time-column t --acc-unit {} --gyro-unit deg/s",
        unit.symbol()
    )))
    .unwrap();
    let cal = match args(&format!("host calibrate --input {d}/s --out-dir {d}/cal")) {
        Command::Calibrate(a) => calibrate(&a, true).unwrap(),
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
    let e = static_errors(&truth, &cal.fitted, &mut testkit::Rng::new(3));
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
}
