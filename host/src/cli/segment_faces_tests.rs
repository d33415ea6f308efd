//! `host segment` on raw counts (a mid-scale offset, a gyro in counts) and on a six-face session,
//! each calibrated and compared with the simulator's truth. The six-face session is also compared
//! with the peers' classic six-position least squares (Tedaldi et al. 2014's and imucal's
//! `FerrarisCalibration` model: `f = M·u + b` from six known ups, bias, scale and misalignment),
//! implemented here only as the reference, fed the true faces and the nominal ones.

use crate::cli::segment::{segment, SegmentArgs, SegmentOutcome};
use crate::cli::{calibrate, Cli, Command};
use clap::Parser;
use estimator::estimate::handheld_gyro::HandGyroError;
use estimator::sim::handheld::{
    logger_unit, simulate_hand, write_logger_csv, HandSpec, LoggerLayout,
};
use estimator::sim::montecarlo::static_errors;
use nalgebra::{Matrix3, Matrix4, Vector4};
use shared::forward::{ForwardModel, TableState};
use shared::linalg::{self, RowMajor3};
use shared::{Calibration, OutputUnit};
use std::path::Path;

fn segment_args(line: &str) -> SegmentArgs {
    match Cli::try_parse_from(line.split_whitespace())
        .unwrap()
        .command
    {
        Command::Segment(a) => a,
        c => panic!("{c:?}"),
    }
}

/// Segments `dir/raw.csv` with `flags` and calibrates the session it writes.
fn segment_and_calibrate(
    dir: &Path,
    flags: &str,
) -> (SegmentOutcome, estimator::estimate::CalibrationOutcome) {
    let d = dir.display();
    let out = segment(&segment_args(&format!(
        "host segment --input {d}/raw.csv --out {d}/s --time-column t {flags}"
    )))
    .unwrap();
    let line = format!("host calibrate --input {d}/s --out-dir {d}/cal");
    let cal = match Cli::try_parse_from(line.split_whitespace())
        .unwrap()
        .command
    {
        Command::Calibrate(a) => calibrate::calibrate(&a, true).unwrap(),
        c => panic!("{c:?}"),
    };
    (out, cal)
}

/// A simulated session written as the logger's CSV (m/s², °/s) in `dir`, segmented and calibrated.
fn segment_and_calibrate_sim(
    dir: &Path,
    sim: &estimator::sim::handheld::HandSession,
) -> (SegmentOutcome, estimator::estimate::CalibrationOutcome) {
    write_logger_csv(&dir.join("raw.csv"), &sim.rows, &LoggerLayout::default()).unwrap();
    segment_and_calibrate(dir, "--acc-unit m/s2 --gyro-unit deg/s")
}

#[test]
fn raw_counts_at_mid_scale_with_a_gyro_in_counts_calibrate_with_the_offset_and_scale() {
    let tmp = tempfile::tempdir().unwrap();
    let spec = HandSpec {
        acc_step: 1.0,
        ..HandSpec::standard(31)
    };
    let mut truth = logger_unit(OutputUnit::Lsb);
    let sim = simulate_hand(&truth, &spec);
    let layout = LoggerLayout {
        acc_offset: 32768.0,
        gyro_lsb_per_dps: Some(16.4),
        ..LoggerLayout::default()
    };
    write_logger_csv(&tmp.path().join("raw.csv"), &sim.rows, &layout).unwrap();
    truth.statics.zero_bias_out = truth.statics.zero_bias_out.map(|b| b + 32768.0);
    let (out, cal) = segment_and_calibrate(
        tmp.path(),
        "--acc-unit LSB --acc-offset 32768 --gyro-unit LSB --gyro-lsb-per-dps 16.4",
    );
    assert_eq!(out.segmentation.stills.len(), 24);
    // The biases are in the logger's own counts, the offset included.
    let fitted = &cal.fitted;
    let true_fitted = truth.statics.to_fitted().unwrap().0;
    for i in 0..3 {
        let e = fitted.zero_bias_out[i] - true_fitted.zero_bias_out[i];
        println!(
            "bias {i}: {:.2} counts (truth {:.2}), error {e:+.3} counts",
            fitted.zero_bias_out[i], true_fitted.zero_bias_out[i]
        );
        // 0.25 counts is 61 µg at 4096 per g, the 24-position session's noise level.
        assert!(e.abs() < 0.25, "axis {i}: {e} counts");
    }
    let e = static_errors(&truth, fitted, &mut shared::rng::Rng::new(5, 0));
    println!(
        "intrinsic rms {:.1} µg, worst {:.1} µg",
        e.rms_ug, e.worst_ug
    );
    assert!(e.rms_ug < 45.0, "{} µg", e.rms_ug);
    // The gyro's true scale from its nominal one: 0.5 %, −0.5 %, 0.4 % (GyroTruth::half_percent).
    let fit = out.gyro.as_ref().unwrap();
    let want = [0.005, -0.005, 0.004];
    for i in 0..3 {
        let s = fit.scale_rel()[i];
        println!(
            "gyro scale {i}: {:+.4} % (truth {:+.4} %)",
            s * 100.0,
            want[i] * 100.0
        );
        assert!((s - want[i]).abs() < 3e-4, "axis {i}: {s}");
    }
    let plan = std::fs::read_to_string(tmp.path().join("cal/calibration.toml")).unwrap();
    assert!(plan.contains("scale_lsb_per_g"), "{plan}");
}

/// Held-out accuracy, mg: |compensated − true specific force| over random attitudes, in the true
/// body frame and after the best common rotation (the frame-free, intrinsic part).
#[derive(Clone, Copy, Debug, Default)]
struct HeldOut {
    rms_mg: f64,
    max_mg: f64,
    rms_rotated_mg: f64,
    max_rotated_mg: f64,
}

fn held_out(truth: &Calibration, m: &RowMajor3, b: &[f64; 3], seed: u64) -> HeldOut {
    let model = ForwardModel::new(truth).unwrap();
    let g = truth.gravity_m_s2;
    let minv = linalg::inverse(m).unwrap();
    let mut rng = shared::rng::Rng::new(seed, 77);
    let ups: Vec<[f64; 3]> = (0..100)
        .map(|_| {
            let v: [f64; 3] = core::array::from_fn(|_| rng.normal());
            v.map(|c| c / linalg::norm(&v))
        })
        .collect();
    let est: Vec<[f64; 3]> = ups
        .iter()
        .map(|up| {
            let raw = model.outputs(&TableState::at_rest(*up).motion(g)).raw;
            linalg::mat_vec(&minv, &core::array::from_fn(|i| raw[i] - b[i]))
        })
        .collect();
    let errors = |r: &Matrix3<f64>| -> Vec<f64> {
        est.iter()
            .zip(&ups)
            .map(|(f, up)| {
                let f = r * nalgebra::Vector3::from(*f);
                (f - nalgebra::Vector3::from(*up)).norm() * 1e3
            })
            .collect()
    };
    let rms = |v: &[f64]| (v.iter().map(|x| x * x).sum::<f64>() / v.len() as f64).sqrt();
    let max = |v: &[f64]| v.iter().copied().fold(0.0, f64::max);
    // Kabsch: the rotation taking the estimates closest to the truth.
    let h: Matrix3<f64> = est
        .iter()
        .zip(&ups)
        .map(|(f, u)| nalgebra::Vector3::from(*u) * nalgebra::Vector3::from(*f).transpose())
        .sum();
    let svd = h.svd(true, true);
    let (u, vt) = (svd.u.unwrap(), svd.v_t.unwrap());
    let d = (u * vt).determinant().signum();
    let rot = u * Matrix3::from_diagonal(&nalgebra::Vector3::new(1.0, 1.0, d)) * vt;
    let (plain, rotated) = (errors(&Matrix3::identity()), errors(&rot));
    HeldOut {
        rms_mg: rms(&plain),
        max_mg: max(&plain),
        rms_rotated_mg: rms(&rotated),
        max_rotated_mg: max(&rotated),
    }
}

/// The peers' six-position least squares: per output axis i, `f_k[i] = M_i·u_k + b_i` over the six
/// positions (four unknowns, six equations), solved by the normal equations.
fn six_position_fit(means: &[[f64; 3]], ups: &[[f64; 3]]) -> (RowMajor3, [f64; 3]) {
    let mut ata = Matrix4::zeros();
    for u in ups {
        let x = Vector4::new(u[0], u[1], u[2], 1.0);
        ata += x * x.transpose();
    }
    let inv = ata.try_inverse().unwrap();
    let mut m = [[0.0; 3]; 3];
    let mut b = [0.0; 3];
    for i in 0..3 {
        let atf: Vector4<f64> = means
            .iter()
            .zip(ups)
            .map(|(f, u)| Vector4::new(u[0], u[1], u[2], 1.0) * f[i])
            .sum();
        let p = inv * atf;
        m[i] = [p[0], p[1], p[2]];
        b[i] = p[3];
    }
    (m, b)
}

/// The mean output of each hold (its middle, 1 s trimmed from each end) and its true up.
fn hold_means(
    rows: &[estimator::sim::handheld::HandRow],
    holds: &[(f64, f64, [f64; 3])],
) -> Vec<[f64; 3]> {
    holds
        .iter()
        .map(|(t0, t1, _)| {
            let inside: Vec<&[f64; 3]> = rows
                .iter()
                .filter(|r| r.0 >= t0 + 1.0 && r.0 <= t1 - 1.0)
                .map(|r| &r.1)
                .collect();
            core::array::from_fn(|j| inside.iter().map(|a| a[j]).sum::<f64>() / inside.len() as f64)
        })
        .collect()
}

/// Held-out accuracy of the peers' six-position least squares on the holds' means, with the true
/// faces (the oracle) and with the nominal ones.
fn six_position_references(
    truth: &Calibration,
    sim: &estimator::sim::handheld::HandSession,
    seed: u64,
) -> (HeldOut, HeldOut) {
    let means = hold_means(&sim.rows, &sim.holds);
    let true_ups: Vec<[f64; 3]> = sim.holds.iter().map(|h| h.2).collect();
    let nominal: Vec<[f64; 3]> = true_ups.iter().map(|u| u.map(f64::round)).collect();
    let (m, b) = six_position_fit(&means, &true_ups);
    let oracle = held_out(truth, &m, &b, seed);
    let (m, b) = six_position_fit(&means, &nominal);
    (oracle, held_out(truth, &m, &b, seed))
}

/// One unit, four calibrations, held-out accuracy of each: (a) ours on the six-face session, (b) the
/// six-position fit with the true faces, (c) with the nominal faces, (d) ours on a 24-position
/// hand-held session of the same unit (free attitudes: its body frame is a convention, so only its
/// rotated figures compare).
fn six_face_case(seed: u64) -> [HeldOut; 4] {
    let tmp = tempfile::tempdir().unwrap();
    let unit = OutputUnit::MetresPerSecondSquared;
    let truth = logger_unit(unit);
    let spec = HandSpec::six_faces(seed, 1.0, 1);
    let sim = simulate_hand(&truth, &spec);
    let (out, cal) = segment_and_calibrate_sim(tmp.path(), &sim);
    assert_eq!(out.segmentation.stills.len(), 6, "seed {seed}");
    assert!(out
        .plan
        .segments
        .iter()
        .all(|s| s.attitude_sigma_deg == Some(2.0)));
    let ours = held_out(
        &truth,
        &cal.fitted.m_out_per_g,
        &cal.fitted.zero_bias_out,
        seed,
    );
    let (reference_true, reference_nominal) = six_position_references(&truth, &sim, seed);
    let hand = HandSpec {
        noise_g: spec.noise_g,
        gyro_noise_deg_s: spec.gyro_noise_deg_s,
        ..HandSpec::standard(seed)
    };
    let tmp = tempfile::tempdir().unwrap();
    let sim = simulate_hand(&truth, &hand);
    let (_, cal) = segment_and_calibrate_sim(tmp.path(), &sim);
    let hand_held = held_out(
        &truth,
        &cal.fitted.m_out_per_g,
        &cal.fitted.zero_bias_out,
        seed,
    );
    [ours, reference_true, reference_nominal, hand_held]
}

const NAMES: [&str; 4] = [
    "(a) ours, six-face session, nominal faces with a 2° prior",
    "(b) six-position least squares, true faces",
    "(c) six-position least squares, nominal faces",
    "(d) ours, 24-position hand-held session",
];

fn print_table(rows: &[[HeldOut; 4]]) {
    println!("held-out accuracy, 100 random attitudes per seed, mg: rms | max in the true body frame; rms | max after the best common rotation");
    for (k, name) in NAMES.iter().enumerate() {
        let mean = |f: &dyn Fn(&HeldOut) -> f64| {
            rows.iter().map(|r| f(&r[k])).sum::<f64>() / rows.len() as f64
        };
        let worst = |f: &dyn Fn(&HeldOut) -> f64| rows.iter().map(|r| f(&r[k])).fold(0.0, f64::max);
        println!(
            "  {name:<58} {:>7.3} | {:>7.3}   {:>7.3} | {:>7.3}",
            mean(&|h| h.rms_mg),
            worst(&|h| h.max_mg),
            mean(&|h| h.rms_rotated_mg),
            worst(&|h| h.max_rotated_mg)
        );
    }
    let better = rows.iter().filter(|r| r[0].rms_mg <= r[2].rms_mg).count();
    println!(
        "  ({} seed(s); rms: mean over seeds, max: over all seeds; (a) at or below (c) in rms on \
         {better} of them)",
        rows.len()
    );
}

#[test]
fn six_face_session_is_taken_as_a_cube_and_calibrates_as_well_as_the_peers_six_position_fit() {
    let rows = [six_face_case(1)];
    print_table(&rows);
    let [ours, _, nominal, _] = rows[0];
    // Ours against the peers' method on the same (nominal) information.
    assert!(
        ours.rms_mg <= nominal.rms_mg,
        "{ours:?} against {nominal:?}"
    );
}

/// `cargo test --release -p host --lib six_face_sessions_many_seeds -- --ignored --nocapture`
#[test]
#[ignore]
fn six_face_sessions_many_seeds() {
    let rows: Vec<[HeldOut; 4]> = (1..=10).map(six_face_case).collect();
    print_table(&rows);
    // docs/model.md §7.1: (a) at or below (c) in rms on every seed.
    for (seed, r) in (1..).zip(&rows) {
        assert!(
            r[0].rms_mg <= r[2].rms_mg,
            "seed {seed}: {:?} against {:?}",
            r[0],
            r[2]
        );
    }
}

#[test]
fn count_time_and_face_options_are_checked_before_any_work() {
    let base = "host segment --input r.csv --out o";
    let error = |extra: &str| {
        segment_args(&format!("{base} {extra}"))
            .log
            .source(std::path::Path::new("r.csv"))
            .unwrap_err()
            .to_string()
    };
    let t = "--time-column t --acc-unit LSB";
    let e = error(&format!("{t} --gyro-unit LSB"));
    assert!(
        e.contains("needs the gyro's nominal scale: add --gyro-lsb-per-dps"),
        "{e}"
    );
    let e = error(&format!("{t} --gyro-unit deg/s --gyro-lsb-per-dps 16.4"));
    assert!(e.contains("give --gyro-unit LSB"), "{e}");
    let e = error("--time-column t --acc-unit m/s2 --gyro-unit deg/s --acc-offset 32768");
    assert!(e.contains("--acc-offset is for raw counts"), "{e}");
    let e = error(&format!("{t} --gyro-unit deg/s --acc-offset 1,2"));
    assert!(e.contains("one number (e.g. 32768) or three"), "{e}");
    let e = error("--rate-hz 100 --time-unit ms --acc-unit g --gyro-unit deg/s");
    assert!(e.contains("applies to --time-column"), "{e}");
    let e = error(&format!("{t} --gyro-unit deg/s --time-unit hours"));
    assert!(e.contains("use s, ms, us or ns"), "{e}");
    let o = segment_args(&format!(
        "{base} {t} --time-unit us --acc-offset 32768,32768,32000 --gyro-unit LSB --gyro-lsb-per-dps 131"
    ))
    .log
    .source(std::path::Path::new("r.csv"))
    .unwrap()
    .text
    .unwrap();
    assert_eq!(o.acc_offset, [32768.0, 32768.0, 32000.0]);
    assert_eq!(o.gyro_lsb_per_dps, Some(131.0));
    assert_eq!(o.time_unit, Some(recording::session::import::TimeUnit::Us));
}

/// The gyro's errors against the simulator's truth, in the true body frame: the largest scale
/// (diagonal) error, %, and the rms of the six misalignment (off-diagonal) errors, degrees.
#[derive(Clone, Copy, Debug, Default)]
struct GyroErrors {
    scale_max_pct: f64,
    misalignment_rms_deg: f64,
    /// Entries `host segment` calls undetermined (1σ over 0.1 %); 0 for the peers' reference.
    undetermined: usize,
}

fn gyro_errors(fitted: &RowMajor3, truth: &RowMajor3, undetermined: usize) -> GyroErrors {
    let scale_max_pct = (0..3)
        .map(|i| (fitted[i][i] - truth[i][i]).abs() * 100.0)
        .fold(0.0, f64::max);
    let off: Vec<f64> = (0..9)
        .filter(|k| k / 3 != k % 3)
        .map(|k| fitted[k / 3][k % 3] - truth[k / 3][k % 3])
        .collect();
    GyroErrors {
        scale_max_pct,
        misalignment_rms_deg: (off.iter().map(|x| x * x).sum::<f64>() / 6.0)
            .sqrt()
            .to_degrees(),
        undetermined,
    }
}

/// The peers' classic six-position gyro calibration on the same data: the bias is the mean rate of
/// the still holds; the turn about face `n = ±e_j` gives `∫(w − b)dt = 2πk·G·n`, so column j of `G` is
/// that integral over `2πk·n_j` (`k` the whole turns, rounded), averaged over the two faces of each
/// axis. The faces are taken as exact, as the method does.
fn classic_six_position_gyro(
    rows: &[estimator::sim::handheld::HandRow],
    holds: &[(f64, f64, [f64; 3])],
) -> RowMajor3 {
    let in_holds = |t: f64| holds.iter().any(|h| t >= h.0 && t <= h.1);
    let still: Vec<&[f64; 3]> = rows
        .iter()
        .filter(|r| in_holds(r.0))
        .map(|r| &r.2)
        .collect();
    let b: [f64; 3] =
        core::array::from_fn(|j| still.iter().map(|w| w[j]).sum::<f64>() / still.len() as f64);
    let mut g = [[0.0; 3]; 3];
    // Holds come in pairs per face: before and after its table turn.
    for pair in holds.chunks(2) {
        let (t0, t1) = (pair[0].1, pair[1].0);
        let turn: Vec<&estimator::sim::handheld::HandRow> =
            rows.iter().filter(|r| r.0 >= t0 && r.0 <= t1).collect();
        let mut s = [0.0; 3];
        for w in turn.windows(2) {
            let dt = w[1].0 - w[0].0;
            for j in 0..3 {
                s[j] += (0.5 * (w[0].2[j] + w[1].2[j]) - b[j]) * dt;
            }
        }
        let n = pair[0].2.map(f64::round);
        let j = (0..3).find(|&j| n[j] != 0.0).unwrap();
        let k = (s[j] * n[j] / (2.0 * std::f64::consts::PI)).round();
        for i in 0..3 {
            g[i][j] += 0.5 * s[i] / (2.0 * std::f64::consts::PI * k * n[j]);
        }
    }
    g
}

/// One unit on a six-face session with a whole table turn on each face (one round, 1° placement
/// errors, consumer MEMS noise), and the same seed's session without the table turns: the gyro by
/// (a) ours with the table turns, (b) ours without them, (c) the peers' classic six-position method
/// on (a)'s data; the accelerometer's held-out accuracy with and without the table turns.
fn table_turn_case(seed: u64) -> ([GyroErrors; 3], [HeldOut; 2]) {
    let unit = OutputUnit::MetresPerSecondSquared;
    let truth = logger_unit(unit);
    let mut gyro = [GyroErrors::default(); 3];
    let mut acc = [HeldOut::default(); 2];
    for (k, table_turns) in [true, false].into_iter().enumerate() {
        let tmp = tempfile::tempdir().unwrap();
        let spec = HandSpec {
            table_turns,
            ..HandSpec::six_faces(seed, 1.0, 1)
        };
        let sim = simulate_hand(&truth, &spec);
        let (out, cal) = segment_and_calibrate_sim(tmp.path(), &sim);
        let used = out
            .table_turns
            .iter()
            .filter(|t| t.used().is_some())
            .count();
        assert_eq!(used, if table_turns { 6 } else { 0 }, "seed {seed}");
        gyro[k] = match &out.gyro {
            Ok(fit) => {
                assert_eq!(fit.table_turns, used);
                gyro_errors(&fit.matrix, &spec.gyro.matrix, fit.undetermined().len())
            }
            // One round's five hand turns alone are too few: no gyro, every entry open.
            Err(HandGyroError::TooFewTurns { turns: 5, .. }) if !table_turns => GyroErrors {
                scale_max_pct: f64::NAN,
                misalignment_rms_deg: f64::NAN,
                undetermined: 9,
            },
            Err(e) => panic!("seed {seed}: {e}"),
        };
        acc[k] = held_out(
            &truth,
            &cal.fitted.m_out_per_g,
            &cal.fitted.zero_bias_out,
            seed,
        );
        if table_turns {
            let g = classic_six_position_gyro(&sim.rows, &sim.holds);
            gyro[2] = gyro_errors(&g, &spec.gyro.matrix, 0);
        }
    }
    (gyro, acc)
}

fn print_table_turn_figures(rows: &[([GyroErrors; 3], [HeldOut; 2])]) {
    let n = rows.len() as f64;
    println!(
        "gyro against truth (true body frame), one face round, 1° placement: largest scale error % \
         (mean over seeds | worst), misalignment rms ° (mean | worst), entries undetermined (mean)"
    );
    let names = [
        "(a) ours, with a whole table turn on each face",
        "(b) ours, the same seed without table turns",
        "(c) classic six-position method on (a)'s data (faces exact)",
    ];
    for (k, name) in names.iter().enumerate() {
        let mean =
            |f: &dyn Fn(&GyroErrors) -> f64| rows.iter().map(|r| f(&r.0[k])).sum::<f64>() / n;
        let worst =
            |f: &dyn Fn(&GyroErrors) -> f64| rows.iter().map(|r| f(&r.0[k])).fold(0.0, f64::max);
        println!(
            "  {name:<62} {:>8.4} | {:>8.4}   {:>7.3} | {:>7.3}   {:>4.1}",
            mean(&|g| g.scale_max_pct),
            worst(&|g| g.scale_max_pct),
            mean(&|g| g.misalignment_rms_deg),
            worst(&|g| g.misalignment_rms_deg),
            mean(&|g| g.undetermined as f64)
        );
    }
    let better = rows
        .iter()
        .filter(|r| r.0[0].scale_max_pct <= r.0[2].scale_max_pct)
        .count();
    println!(
        "  (a)'s largest scale error at or below (c)'s on {better} of {} seed(s)",
        rows.len()
    );
    println!("accelerometer held-out, mg: rms | max in the true body frame; rms | max after the best common rotation");
    for (k, name) in ["with table turns", "without"].iter().enumerate() {
        let mean = |f: &dyn Fn(&HeldOut) -> f64| rows.iter().map(|r| f(&r.1[k])).sum::<f64>() / n;
        let worst =
            |f: &dyn Fn(&HeldOut) -> f64| rows.iter().map(|r| f(&r.1[k])).fold(0.0, f64::max);
        println!(
            "  {name:<20} {:>7.3} | {:>7.3}   {:>7.3} | {:>7.3}",
            mean(&|h| h.rms_mg),
            worst(&|h| h.max_mg),
            mean(&|h| h.rms_rotated_mg),
            worst(&|h| h.max_rotated_mg)
        );
    }
}

/// `cargo test --release -p host --lib six_face_table_turns_many_seeds -- --ignored --nocapture`
#[test]
#[ignore]
fn six_face_table_turns_many_seeds() {
    let rows: Vec<_> = (1..=10).map(table_turn_case).collect();
    print_table_turn_figures(&rows);
    // docs/model.md §7.2: (a)'s largest scale error at or below the classic method's on every
    // seed; without the table turns one round's five hand turns leave the gyro uncalibrated.
    for (seed, r) in (1..).zip(&rows) {
        let (a, b, c) = (&r.0[0], &r.0[1], &r.0[2]);
        assert!(
            a.scale_max_pct <= c.scale_max_pct,
            "seed {seed}: {a:?} against {c:?}"
        );
        assert_eq!(b.undetermined, 9, "seed {seed}: {b:?}");
    }
}

#[test]
fn six_face_table_turns_determine_the_gyro_scale_and_leave_the_accelerometer_as_good() {
    let case = table_turn_case(2);
    print_table_turn_figures(&[case]);
    let ([ours, without, classic], [acc_with, acc_without]) = case;
    // Without the table turns one round's five hand turns are too few: no gyro (said so).
    assert!(
        without.scale_max_pct.is_nan() && without.undetermined == 9,
        "{without:?}"
    );
    // With them every scale is known to the stop's repeatability, as in the classic method.
    assert!(ours.scale_max_pct < 0.1, "{ours:?}");
    assert!(ours.undetermined <= 6, "{ours:?}");
    assert!(
        ours.scale_max_pct <= classic.scale_max_pct,
        "{ours:?} against {classic:?}"
    );
    assert!(
        ours.misalignment_rms_deg <= classic.misalignment_rms_deg,
        "{ours:?} against {classic:?}"
    );
    // The accelerometer sees each face twice (one mount): as good as without the turns, to the
    // holds' own noise (1.5 mg per sample over 6–9 s at 200 Hz: 0.05 mg per face).
    assert!(
        acc_with.rms_mg <= acc_without.rms_mg + 0.1,
        "{acc_with:?} against {acc_without:?}"
    );
}

/// The hand-held method at its minimum, nine positions (the six faces and three diagonals, held
/// exactly: no placement error), on the six-face sessions' unit and noise: held-out accuracy per
/// seed, or why `segment` or `calibrate` refuses it. Positions near a body axis define the body
/// frame, so with exact faces the true-frame figure is not comparable with a six-face session's
/// 1°-misplaced faces; the rotated figure is.
/// `cargo test --release -p host --lib nine_position_hand_sessions_many_seeds -- --ignored --nocapture`
#[test]
#[ignore]
fn nine_position_hand_sessions_many_seeds() {
    let r = 1.0 / 3f64.sqrt();
    let ups = vec![
        [1.0, 0.0, 0.0],
        [-1.0, 0.0, 0.0],
        [0.0, 1.0, 0.0],
        [0.0, -1.0, 0.0],
        [0.0, 0.0, 1.0],
        [0.0, 0.0, -1.0],
        [r, r, r],
        [-r, r, -r],
        [r, -r, -r],
    ];
    let truth = logger_unit(OutputUnit::MetresPerSecondSquared);
    println!(
        "nine-position hand-held sessions, held-out mg: rms | max in the true body frame; \
         after the best common rotation"
    );
    let mut rotated_rms_mg = Vec::new();
    for seed in 1..=10 {
        let faces = HandSpec::six_faces(seed, 1.0, 1);
        let spec = HandSpec {
            ups: ups.clone(),
            noise_g: faces.noise_g,
            gyro_noise_deg_s: faces.gyro_noise_deg_s,
            ..HandSpec::standard(seed)
        };
        let sim = simulate_hand(&truth, &spec);
        let tmp = tempfile::tempdir().unwrap();
        write_logger_csv(
            &tmp.path().join("raw.csv"),
            &sim.rows,
            &LoggerLayout::default(),
        )
        .unwrap();
        let d = tmp.path().display();
        let seg = segment(&segment_args(&format!(
            "host segment -q --input {d}/raw.csv --out {d}/s --time-column t --acc-unit m/s2 --gyro-unit deg/s"
        )));
        let cal = seg.map_err(|e| e.to_string()).and_then(|_| {
            let line = format!("host calibrate --input {d}/s --out-dir {d}/cal");
            match Cli::try_parse_from(line.split_whitespace())
                .unwrap()
                .command
            {
                Command::Calibrate(c) => calibrate::calibrate(&c, true).map_err(|e| e.to_string()),
                c => panic!("{c:?}"),
            }
        });
        match cal {
            Ok(cal) => {
                let h = held_out(
                    &truth,
                    &cal.fitted.m_out_per_g,
                    &cal.fitted.zero_bias_out,
                    seed,
                );
                println!(
                    "  seed {seed:>2}: {:7.3} | {:7.3}   {:7.3} | {:7.3}",
                    h.rms_mg, h.max_mg, h.rms_rotated_mg, h.max_rotated_mg
                );
                rotated_rms_mg.push(h.rms_rotated_mg);
            }
            Err(e) => println!("  seed {seed:>2}: refused: {e}"),
        }
    }
    // docs/model.md §7.1: every seed calibrates, 0.06–0.13 mg rms after the best common rotation
    // (the six-face sessions': 9.06 mg).
    assert_eq!(rotated_rms_mg.len(), 10, "refused on some seeds");
    assert!(
        rotated_rms_mg.iter().all(|&mg| mg < 0.15),
        "{rotated_rms_mg:?}"
    );
}

/// A consumer MEMS unit (biases of 40–100 mg on every axis, seeded) turned over `rounds` times
/// through its six faces, each set down 5° off its axis, written as the logger's CSV `dir/raw.csv`:
/// the unit, the session's spec and the simulated session.
fn biased_mems_faces(
    dir: &Path,
    seed: u64,
    rounds: usize,
) -> (Calibration, HandSpec, estimator::sim::handheld::HandSession) {
    let mut truth = logger_unit(OutputUnit::MetresPerSecondSquared);
    let mut rng = shared::rng::Rng::new(seed, 91);
    truth.statics.zero_bias_out = core::array::from_fn(|_| {
        let mg = rng.range(40.0, 100.0) * if rng.range(0.0, 1.0) < 0.5 { -1.0 } else { 1.0 };
        mg * 1e-3 * truth.gravity_m_s2
    });
    let spec = HandSpec::six_faces(100 + seed, 5.0, rounds);
    let sim = simulate_hand(&truth, &spec);
    write_logger_csv(&dir.join("raw.csv"), &sim.rows, &LoggerLayout::default()).unwrap();
    (truth, spec, sim)
}

/// A consumer MEMS unit's six faces: biases of 40–100 mg on every axis and each face set down 5°
/// off its axis (one face's raw direction is then up to 13° from its axis, where a raw 5° test
/// refused it). Found as six faces on every seed; held-out accuracy against the six-position fit
/// with the true faces (the oracle) and with the nominal faces (the peers' method).
/// `BIASED_FACE_SEEDS=N` runs N seeds (default 4).
#[test]
fn biased_mems_faces_five_degrees_off_are_found_and_calibrate() {
    let seeds: u64 = std::env::var("BIASED_FACE_SEEDS")
        .ok()
        .and_then(|s| s.parse().ok())
        .unwrap_or(4);
    let mut rows = Vec::new();
    let mut worst_raw_deg: f64 = 0.0;
    for seed in 0..seeds {
        let tmp = tempfile::tempdir().unwrap();
        let (truth, _, sim) = biased_mems_faces(tmp.path(), seed, 1);
        if seed == 0 {
            // With the default 2° prior the session is still written (one round's turns are too
            // few for a gyro, said before any fit), and calibrate names the faces the prior could
            // not hold, how far off they sat, and the option that sets the prior.
            let d = tmp.path().display();
            segment(&segment_args(&format!(
                "host segment -q --input {d}/raw.csv --out {d}/default --time-column t \
                 --acc-unit m/s2 --gyro-unit deg/s"
            )))
            .unwrap();
            let line = format!("host calibrate -q --input {d}/default --out-dir {d}/dcal");
            let Command::Calibrate(c) = Cli::try_parse_from(line.split_whitespace())
                .unwrap()
                .command
            else {
                panic!("{line}")
            };
            // Either the faces left leave no check (refused) or the fit goes on without them
            // (each exclusion said): both name the prior and the option.
            let said = match calibrate::calibrate(&c, true) {
                Err(e) => e.to_string(),
                Ok(o) => o.excluded.iter().map(|x| x.reason.to_string()).collect(),
            };
            assert!(
                said.contains("placement prior") && said.contains("--face-sigma-deg"),
                "{said}"
            );
        }
        // Faces placed to 5° are a wider prior than the bench's default 2°: the user says so. One
        // round's five turns are too few for the gyro (absent, said), never a refusal.
        let (out, cal) = segment_and_calibrate(
            tmp.path(),
            "--acc-unit m/s2 --gyro-unit deg/s --face-sigma-deg 5",
        );
        assert_eq!(out.segmentation.stills.len(), 6, "seed {seed}");
        assert!(
            matches!(out.gyro, Err(HandGyroError::TooFewTurns { turns: 5, .. })),
            "seed {seed}: {:?}",
            out.gyro
        );
        for s in &out.segmentation.stills {
            let d = s.direction;
            let big = d.iter().fold(0.0f64, |m, x| m.max(x.abs()));
            worst_raw_deg = worst_raw_deg.max(big.acos().to_degrees());
        }
        let ours = held_out(
            &truth,
            &cal.fitted.m_out_per_g,
            &cal.fitted.zero_bias_out,
            seed,
        );
        let (oracle, peers) = six_position_references(&truth, &sim, seed);
        rows.push([ours, oracle, peers]);
    }
    println!("worst raw face direction off its axis: {worst_raw_deg:.1}°");
    println!("held-out rms, mg, per seed: ours (nominal faces, 5° prior) | oracle (true faces) | peers (nominal faces)");
    for (seed, [ours, oracle, peers]) in rows.iter().enumerate() {
        println!(
            "  seed {seed}: {:>8.3} | {:>8.3} | {:>8.3}",
            ours.rms_mg, oracle.rms_mg, peers.rms_mg
        );
    }
    // The biases tilt the raw faces beyond the old 5° test on some seed.
    assert!(worst_raw_deg > 5.0, "{worst_raw_deg}");
    for r in &rows {
        let [ours, _, peers] = r;
        assert!(
            ours.rms_mg <= peers.rms_mg * 1.05,
            "{ours:?} against {peers:?}"
        );
    }
}

/// The same biased MEMS unit turned over twice (eleven turns): its hand-turn gyro is calibrated on
/// every seed. Its `G` is in the body frame the faces' 5° prior defines, a few degrees from the
/// true one, so the check is on what no rotation of the body changes: each gyro axis's scale (the
/// norm of `G`'s row) within 4σ of its diagonal 1σ, and the bias (gyro axes) within 4σ.
#[test]
fn a_biased_mems_units_gyro_is_calibrated_from_two_rounds_of_faces() {
    for seed in 0..3 {
        let tmp = tempfile::tempdir().unwrap();
        let (_, spec, _) = biased_mems_faces(tmp.path(), seed, 2);
        let (out, _) = segment_and_calibrate(
            tmp.path(),
            "--acc-unit m/s2 --gyro-unit deg/s --face-sigma-deg 5",
        );
        let fit = out
            .gyro
            .unwrap_or_else(|e| panic!("seed {seed}: gyro not calibrated: {e}"));
        for i in 0..3 {
            let (got, want) = (
                linalg::norm(&fit.matrix[i]),
                linalg::norm(&spec.gyro.matrix[i]),
            );
            let s = fit.matrix_1sigma[i][i];
            assert!(
                (got - want).abs() < 4.0 * s,
                "seed {seed} |G[{i}]| {got} ± {s} vs {want}"
            );
            let (got, want, s) = (
                fit.bias_rad_s[i],
                spec.gyro.bias_rad_s[i],
                fit.bias_1sigma_rad_s[i],
            );
            assert!(
                (got - want).abs() < 4.0 * s,
                "seed {seed} b[{i}] {got} ± {s} vs {want}"
            );
        }
    }
}

/// The faces as the user labels them (`--faces`, one per still in order, as imucal's users name
/// their sections): the labels that match the data give the session the automatic labelling gives;
/// two labels swapped are refused naming the still and its reading; a label too few is refused
/// naming both counts.
#[test]
fn faces_labelled_by_the_user_are_checked_against_the_data() {
    let mut truth = logger_unit(OutputUnit::MetresPerSecondSquared);
    truth.statics.zero_bias_out = [0.6, -0.8, 0.9];
    let spec = HandSpec::six_faces(7, 2.0, 1);
    let sim = simulate_hand(&truth, &spec);
    let tmp = tempfile::tempdir().unwrap();
    let d = tmp.path().display();
    write_logger_csv(
        &tmp.path().join("raw.csv"),
        &sim.rows,
        &LoggerLayout::default(),
    )
    .unwrap();
    // The true faces, from the simulator's holds.
    let names = ["x", "y", "z"];
    let labels: Vec<String> = sim
        .holds
        .iter()
        .map(|(_, _, up)| {
            let j = (0..3)
                .max_by(|&a, &b| up[a].abs().total_cmp(&up[b].abs()))
                .unwrap();
            format!("{}{}", names[j], if up[j] > 0.0 { "+" } else { "-" })
        })
        .collect();
    assert_eq!(labels.len(), 6);
    let run = |out: &str, faces: &str| {
        let faces = if faces.is_empty() {
            String::new()
        } else {
            format!(" --faces {faces}")
        };
        segment(&segment_args(&format!(
            "host segment -q --input {d}/raw.csv --out {d}/{out} --time-column t \
             --acc-unit m/s2 --gyro-unit deg/s{faces}"
        )))
    };
    let auto = run("auto", "").unwrap();
    let given = run("given", &labels.join(",")).unwrap();
    assert_eq!(given.plan, auto.plan);
    let mut swapped = labels.clone();
    swapped.swap(0, 1);
    let e = run("swapped", &swapped.join(","))
        .err()
        .unwrap()
        .to_string();
    assert!(
        e.contains("still interval 1 is labelled") && e.contains("check the labels' order"),
        "{e}"
    );
    let e = run("short", &labels[..5].join(","))
        .err()
        .unwrap()
        .to_string();
    assert!(
        e.contains("5 face label(s) given for 6 still interval(s)"),
        "{e}"
    );
}
