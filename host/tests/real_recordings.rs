//! Real recordings from other people's projects (`fixtures/corpus/README.md`: twelve files from six
//! sources in three formats, each beside its licence), read as their users would read them. Each
//! one calibrates, or is refused for a reason that is true of it; where one calibrates, an
//! independent ellipsoid fit on its rests' means (written here, not the tool's) bounds the result.
//!
//! `cargo test -p host --test real_recordings -- --nocapture` prints each file's figures: the
//! positions found, |f| − 1 g at the rests before (nominal scale) and after the calibration, and
//! the reference fit's figure.

mod common;

use std::path::{Path, PathBuf};

/// A file of `fixtures/corpus/`, unpacked into `dir` when it is zstd-compressed.
fn unpack(dir: &Path, name: &str) -> PathBuf {
    let corpus = Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/fixtures/corpus");
    recording::testkit::unpacked(&corpus.join(name), dir)
}

/// MPU-6050 logs of tomisuarez2/ImuCalibration: a preamble of four lines (rate, logging type,
/// initialisation and waiting times) before the header, no time column, the 100 Hz of the
/// preamble's `Fs,100`, raw counts at the part's default ranges (16 384 LSB/g, 131 LSB per °/s).
const TOMI: &[&str] = &[
    "--skip-lines",
    "4",
    "--columns",
    "ax,ay,az,gx,gy,gz",
    "--time-column",
    "none",
    "--rate-hz",
    "100",
    "--acc-unit",
    "LSB",
    "--gyro-unit",
    "LSB",
    "--gyro-lsb-per-dps",
    "131",
];

/// imucal's Ferraris session (mad-lab-fau/imucal `example_data/`): m/s² and °/s at the 102.4 Hz of
/// imucal's own example, no time column.
const IMUCAL: &[&str] = &[
    "--time-column",
    "none",
    "--rate-hz",
    "102.4",
    "--acc-unit",
    "m/s2",
    "--gyro-unit",
    "deg/s",
];

/// `host segment` on `input` into `dir/out` with `more` options: (ok, stdout, stderr).
fn segment(dir: &Path, input: &Path, out: &str, more: &[&str]) -> (bool, String, String) {
    let input = input.to_str().unwrap();
    let mut args = vec!["segment", "--input", input, "--out", out];
    args.extend_from_slice(more);
    common::host_in(Some(dir), &args)
}

/// The first whole number before `key` in `text`.
fn count_before(text: &str, key: &str) -> usize {
    let at = text
        .find(key)
        .unwrap_or_else(|| panic!("no '{key}' in {text}"));
    text[..at]
        .split_whitespace()
        .last()
        .and_then(|w| w.parse().ok())
        .unwrap_or_else(|| panic!("no count before '{key}' in {text}"))
}

/// rms of `v`.
fn rms(v: &[f64]) -> f64 {
    (v.iter().map(|x| x * x).sum::<f64>() / v.len().max(1) as f64).sqrt()
}

/// The reference: an ellipsoid fitted to the rests' means `u` (output unit) by Gauss–Newton, so
/// that |S (u − b)| = 1 g at every rest; `S` symmetric when the rests span nine or more
/// directions, else diagonal. Starts from `b = 0` and `S = I / per_g`. Returns |f| − 1 g at each
/// rest after the fit, mg.
fn ellipsoid_after_mg(u: &[[f64; 3]], per_g: f64, symmetric: bool) -> Vec<f64> {
    use nalgebra::{DMatrix, DVector, Matrix3, Vector3};
    // Parameters: b (3), then S's upper triangle (6) or diagonal (3).
    let n_s = if symmetric { 6 } else { 3 };
    let mut p = vec![0.0; 3 + n_s];
    for k in 0..3 {
        let at = if symmetric { [0, 3, 5][k] } else { k };
        p[3 + at] = 1.0 / per_g;
    }
    let s_of = |p: &[f64]| -> Matrix3<f64> {
        if symmetric {
            let q = &p[3..];
            Matrix3::new(q[0], q[1], q[2], q[1], q[3], q[4], q[2], q[4], q[5])
        } else {
            Matrix3::from_diagonal(&Vector3::new(p[3], p[4], p[5]))
        }
    };
    let residuals = |p: &[f64]| -> Vec<f64> {
        let s = s_of(p);
        let b = Vector3::new(p[0], p[1], p[2]);
        u.iter()
            .map(|x| (s * (Vector3::from(*x) - b)).norm() - 1.0)
            .collect()
    };
    for _ in 0..50 {
        let r = residuals(&p);
        let mut jac = DMatrix::zeros(u.len(), p.len());
        for j in 0..p.len() {
            // b in the output unit, S in g per output unit.
            let h = if j < 3 { 1e-6 * per_g } else { 1e-6 / per_g };
            let mut q = p.clone();
            q[j] += h;
            let rq = residuals(&q);
            for i in 0..u.len() {
                jac[(i, j)] = (rq[i] - r[i]) / h;
            }
        }
        let step = (jac.transpose() * &jac)
            .try_inverse()
            .map(|inv| inv * jac.transpose() * DVector::from_vec(r.clone()));
        let Some(step) = step else { break };
        for j in 0..p.len() {
            p[j] -= step[j];
        }
        if step.norm() < 1e-12 {
            break;
        }
    }
    residuals(&p).iter().map(|r| r * 1e3).collect()
}

/// A calibrated session's figures: the rests' means (output unit), |f| − 1 g at them before (the
/// nominal `per_g`) and after our calibration, and the reference's after, mg rms.
struct Figures {
    rests: usize,
    before_mg: f64,
    ours_mg: f64,
    reference_mg: f64,
}

impl Figures {
    /// `rests` rests, more than `before_above_mg` off at the nominal scale, and calibrated to
    /// within 0.2 mg of the reference ellipsoid.
    fn bounded(&self, rests: usize, before_above_mg: f64) {
        assert_eq!(self.rests, rests);
        assert!(self.before_mg > before_above_mg, "{}", self.before_mg);
        let (ours, reference) = (self.ours_mg, self.reference_mg);
        assert!(ours < reference + 0.2, "{ours} vs {reference}");
    }
}

fn figures(session: &Path, calibration: &Path, per_g: f64, symmetric: bool) -> Figures {
    let s =
        recording::session::read_session(session, &recording::session::ReadOptions { quiet: true })
            .unwrap();
    let u: Vec<[f64; 3]> = s.stats.iter().map(|st| st.mean_u).collect();
    let cal = estimator::unit_file::UnitFile::load(calibration)
        .unwrap()
        .to_calibration()
        .unwrap();
    let (fitted, _) = cal.statics.to_fitted().unwrap();
    let minv = shared::linalg::inverse(&fitted.m_out_per_g).unwrap();
    let before: Vec<f64> = u
        .iter()
        .map(|x| (shared::linalg::norm(x) / per_g - 1.0) * 1e3)
        .collect();
    let ours: Vec<f64> = u
        .iter()
        .map(|x| {
            let d: [f64; 3] = core::array::from_fn(|j| x[j] - fitted.zero_bias_out[j]);
            (shared::linalg::norm(&shared::linalg::mat_vec(&minv, &d)) - 1.0) * 1e3
        })
        .collect();
    Figures {
        rests: u.len(),
        before_mg: rms(&before),
        ours_mg: rms(&ours),
        reference_mg: rms(&ellipsoid_after_mg(&u, per_g, symmetric)),
    }
}

/// Segments and calibrates `name`; its figures, printed. The session must pass its checks.
fn calibrated(dir: &Path, name: &str, more: &[&str], per_g: f64, symmetric: bool) -> Figures {
    let input = unpack(dir, name);
    let (ok, stdout, stderr) = segment(dir, &input, "s", more);
    assert!(ok, "{name}: {stderr}");
    let (ok, out, err) = common::host_in(Some(dir), &["calibrate", "--input", "s", "--out", "c"]);
    assert!(ok, "{name}: {err}");
    assert!(out.contains("PASS"), "{name}: {out}");
    let f = figures(
        &dir.join("s"),
        &dir.join("c/calibration.toml"),
        per_g,
        symmetric,
    );
    println!(
        "{name}: {} still interval(s) in {} distinct position(s); |f| − 1 g at the rests {:.2} → \
         {:.3} mg rms (the reference ellipsoid: {:.3} mg)",
        count_before(&stdout, "still interval(s)"),
        count_before(&stdout, "distinct position"),
        f.before_mg,
        f.ours_mg,
        f.reference_mg
    );
    f
}

/// `host segment` on `name` (with `more`), which must accept it: its stdout and stderr.
fn probe(dir: &Path, name: &str, more: &[&str]) -> (String, String) {
    let input = unpack(dir, name);
    let (ok, stdout, stderr) = segment(dir, &input, "probe", more);
    assert!(ok, "{name}: {stderr}");
    (stdout, stderr)
}

/// imucal's Ferraris session: the six faces on a table and three turns, found as a six-face
/// session (13 rests in the six directions of the authors' list), calibrated to within 0.2 mg of
/// the reference ellipsoid fit.
#[test]
fn imucals_ferraris_session_calibrates_as_six_faces() {
    let tmp = tempfile::tempdir().unwrap();
    let d = tmp.path();
    let (stdout, _) = probe(d, "imucal_ferraris_session.csv.zst", IMUCAL);
    assert_eq!(count_before(&stdout, "distinct position"), 6, "{stdout}");
    assert!(stdout.contains("six-face session"), "{stdout}");
    let f = calibrated(
        d,
        "imucal_ferraris_session.csv.zst",
        IMUCAL,
        shared::STANDARD_GRAVITY_M_S2,
        false,
    );
    f.bounded(13, 20.0);
}

/// imucal's annotated session (the same kind of unit in counts, its nine annotated pieces joined):
/// the six faces, no more; its six rests determine the six axis-aligned parameters exactly.
#[test]
fn imucals_annotated_session_calibrates_from_its_six_faces() {
    let tmp = tempfile::tempdir().unwrap();
    let more = [
        "--time-column",
        "none",
        "--rate-hz",
        "204.8",
        "--acc-unit",
        "LSB",
        "--gyro-unit",
        "LSB",
        "--gyro-lsb-per-dps",
        "16.4",
    ];
    let f = calibrated(
        tmp.path(),
        "imucal_annotated_session.csv.zst",
        &more,
        2048.0,
        false,
    );
    assert_eq!(f.rests, 6);
    assert!(
        f.before_mg > 10.0 && f.ours_mg < 0.05,
        "{} → {}",
        f.before_mg,
        f.ours_mg
    );
}

/// An MPU-6050 session of 37 s on a table and nine positions held by hand (tremor about 1 °/s):
/// all ten positions found by default, the hand's rests beside the table's, and calibrated; three
/// turns that drove the gyro to its ±250 °/s range are left out of the gyro fit, each named.
#[test]
fn a_hand_held_session_with_a_table_rest_calibrates() {
    let tmp = tempfile::tempdir().unwrap();
    let d = tmp.path();
    let (stdout, stderr) = probe(d, "tomisuarez_calibration.csv.zst", TOMI);
    // The authors' own list (`optmization result data/static_intervals.csv`) has ten.
    assert_eq!(count_before(&stdout, "still interval(s)"), 10, "{stdout}");
    assert_eq!(count_before(&stdout, "distinct position"), 10, "{stdout}");
    let saturated = stderr
        .lines()
        .filter(|l| l.contains("reads its extreme, ±250.1 °/s"))
        .count();
    assert_eq!(saturated, 3, "{stderr}");
    let f = calibrated(d, "tomisuarez_calibration.csv.zst", TOMI, 16384.0, true);
    f.bounded(10, 50.0);
}

/// The other recordings: each refused by `segment` for a reason true of it (the reason checked
/// against what the file holds), and the still ones read by `noise`.
#[test]
fn the_other_recordings_are_refused_for_what_they_are() {
    let tmp = tempfile::tempdir().unwrap();
    let d = tmp.path();
    let xio_columns = "Accelerometer X (g),Accelerometer Y (g),Accelerometer Z (g),\
                       Gyroscope X (deg/s),Gyroscope Y (deg/s),Gyroscope Z (deg/s)";
    let xio: &[&str] = &[
        "--time-column",
        "Time (s)",
        "--columns",
        xio_columns,
        "--acc-unit",
        "g",
        "--gyro-unit",
        "deg/s",
    ];
    // (file, options, the refusal's reason, whether `noise` reads it)
    let cases: &[(&str, &[&str], &str, bool)] = &[
        // imucal's unit-test fixture: half a second.
        (
            "imucal_tests_ferraris_example.csv.zst",
            IMUCAL,
            "only 50 usable rows",
            false,
        ),
        // One long rest each (the authors' initialisation and static tests).
        (
            "tomisuarez_tinit_static.csv.zst",
            TOMI,
            "1 distinct position",
            true,
        ),
        (
            "tomisuarez_static_test.csv.zst",
            TOMI,
            "1 distinct position",
            true,
        ),
        // Two rests, a quarter turn about x between them.
        (
            "tomisuarez_90_x_rot.csv.zst",
            TOMI,
            "2 distinct position",
            false,
        ),
        // Fusion's example: moved about by hand, at rest the right way up on the desk six
        // times and held tilted (y 62° up) for 2.5 s once, at 17.4–19.9 s.
        (
            "xio_fusion_sensor_data.csv.zst",
            xio,
            "2 distinct position",
            true,
        ),
        // PX4's logs hold only sensor_combined, which PX4 has already corrected.
        ("pyulog_sample.ulg.zst", &[], "sensor_combined", true),
        ("pyulog_sample_log_small.ulg", &[], "sensor_combined", true),
        // A quadrotor's flight (PX4 on an FMU-V6C, 92 s): about 6 s still on the ground before
        // take-off and 2.7 s after landing, its IMU at rate only in sensor_combined; `noise`
        // finds the rest before take-off (`a_flight_logs_short_rest_is_found`).
        (
            "px4ulogrs_quadrotor_local.ulg.zst",
            &[],
            "sensor_combined",
            true,
        ),
        // A ROS 1 bag (an AR.Drone's IMU over WiFi): the conversion that makes it a ROS 2 bag.
        (
            "imutools_ardrone_imu.bag",
            &[],
            "ROS 1 bag: convert it with `rosbags-convert",
            false,
        ),
        // The same bag so converted: host-stamped, two rests on the bench between handling.
        (
            "imutools_ardrone_imu_ros2.mcap.zst",
            &[],
            "2 distinct position",
            true,
        ),
        // A truncated ArduPilot log of 45 IMU samples; a flight log without IMU messages.
        ("pymavlink_test.BIN", &[], "45 IMU samples", false),
        ("flightdata_center_0003.bin", &[], "no IMU samples", false),
    ];
    for (k, &(name, more, reason, noise)) in cases.iter().enumerate() {
        let input = unpack(d, name);
        let (ok, _, stderr) = segment(d, &input, &format!("s{k}"), more);
        assert!(!ok, "{name}: a session from it");
        assert!(stderr.contains(reason), "{name}: {stderr}");
        println!(
            "{name}: refused: {}",
            stderr.lines().last().unwrap_or_default()
        );
        if noise {
            let input = input.to_str().unwrap();
            let out = format!("n{k}");
            let mut args = vec!["noise", "--input", input, "--out", &out];
            args.extend_from_slice(more);
            let (ok, _, stderr) = common::host_in(Some(d), &args);
            assert!(ok, "{name}: noise: {stderr}");
        }
    }
}

/// The moves on a face in a six-face session: the time between two consecutive still intervals on
/// the same face (their mean directions within 1°), more than a second apart: (start s, end s, the
/// face's body axis 0–2), from `segment --json`'s intervals.
fn turns_on_a_face(doc: &serde_json::Value) -> Vec<(f64, f64, usize)> {
    let stills: Vec<(f64, f64, [f64; 3])> = doc["intervals"]
        .as_array()
        .unwrap()
        .iter()
        .filter(|iv| iv["kind"] == "static")
        .map(|iv| {
            let d = &iv["mean_direction"];
            let start = iv["start_s"].as_f64().unwrap();
            let dir = core::array::from_fn(|j| d[j].as_f64().unwrap());
            (start, start + iv["duration_s"].as_f64().unwrap(), dir)
        })
        .collect();
    stills
        .windows(2)
        .filter(|w| {
            let cos: f64 = (0..3).map(|j| w[0].2[j] * w[1].2[j]).sum();
            cos > 1f64.to_radians().cos() && w[1].0 - w[0].1 > 1.0
        })
        .map(|w| {
            let axis = (0..3)
                .max_by(|&a, &b| w[0].2[a].abs().total_cmp(&w[0].2[b].abs()))
                .unwrap();
            (w[0].1, w[1].0, axis)
        })
        .collect()
}

/// The peers' six-position least squares with the faces taken as exact (imucal's
/// `FerrarisCalibration` model, `u = K·n + b` for each rest's mean output `u` and its face `n`,
/// per output axis by the normal equations): `(K⁻¹, b)`, so that `f = K⁻¹(u − b)` in g.
fn faces_exact_fit(rests: &[([f64; 3], [f64; 3])]) -> (nalgebra::Matrix3<f64>, [f64; 3]) {
    use nalgebra::{Matrix3, Matrix4, Vector4};
    let (mut k, mut b) = (Matrix3::zeros(), [0.0; 3]);
    for i in 0..3 {
        let (mut a, mut y) = (Matrix4::zeros(), Vector4::zeros());
        for (u, n) in rests {
            let x = Vector4::new(n[0], n[1], n[2], 1.0);
            a += x * x.transpose();
            y += x * u[i];
        }
        let s = a.try_inverse().unwrap() * y;
        for j in 0..3 {
            k[(i, j)] = s[j];
        }
        b[i] = s[3];
    }
    (k.try_inverse().unwrap(), b)
}

/// The mean of `rows` (t, x, y, z) over `[t0, t1]`.
fn mean_over(rows: &[(f64, [f64; 3])], t0: f64, t1: f64) -> [f64; 3] {
    let within: Vec<&[f64; 3]> = rows
        .iter()
        .filter(|(t, _)| (t0..=t1).contains(t))
        .map(|(_, v)| v)
        .collect();
    core::array::from_fn(|j| within.iter().map(|v| v[j]).sum::<f64>() / within.len() as f64)
}

/// The specific force across axis `axis`, mg.
fn off_axis_mg(f_g: &[f64; 3], axis: usize) -> f64 {
    let across: f64 = (0..3).filter(|&j| j != axis).map(|j| f_g[j] * f_g[j]).sum();
    across.sqrt() * 1e3
}

/// The frame of a six-face calibration, held out: imucal's Ferraris session turns the unit about
/// the vertical on three faces, and no fit sees those turns (they are not still). Turned flat on a
/// face, the unit's specific force stays along that face's normal, so in the housing's frame
/// (`calibration.toml`'s `[frame]`, `faces`) its mean over each turn lies on that body axis. Ours
/// (`host apply` on the log) keeps it there at least as well as the peers' six-position least
/// squares with the faces taken as exact, which puts every face exactly on its axis by design.
#[test]
fn imucals_turns_on_a_face_keep_their_force_on_that_axis() {
    let tmp = tempfile::tempdir().unwrap();
    let d = tmp.path();
    let name = "imucal_ferraris_session.csv.zst";
    let input = unpack(d, name);
    let (ok, doc, err) = segment(d, &input, "s", &[IMUCAL, &["--json"]].concat());
    assert!(ok, "{err}");
    let doc: serde_json::Value = serde_json::from_str(&doc).unwrap();
    // n_samples,gyr_x,gyr_y,gyr_z,acc_x,acc_y,acc_z at 102.4 Hz, °/s and m/s².
    let rows = numeric_rows(&input);
    let t_of = |n: usize| n as f64 / 102.4;
    // A turn about the vertical: the gyro's integral about the face's axis at least 90°.
    let turns: Vec<(f64, f64, usize)> = turns_on_a_face(&doc)
        .into_iter()
        .filter(|&(t0, t1, axis)| {
            let inside = rows
                .iter()
                .enumerate()
                .filter(|(n, _)| (t0..=t1).contains(&t_of(*n)));
            let turned: f64 = inside.map(|(_, r)| r[1 + axis] / 102.4).sum();
            turned.abs() > 90.0
        })
        .collect();
    assert_eq!(turns.len(), 3, "{turns:?}");
    let (ok, out, err) = common::host_in(Some(d), &["calibrate", "--input", "s", "--out", "c"]);
    assert!(ok && out.contains("PASS"), "{out}{err}");
    let toml = std::fs::read_to_string(d.join("c/calibration.toml")).unwrap();
    assert!(toml.contains("[frame]\nkind = \"faces\""), "{toml}");
    let applied = d.join("applied.csv");
    let args = [
        &["apply", "--calibration", "c/calibration.toml"][..],
        &["--input", input.to_str().unwrap(), "--out", "applied.csv"],
        IMUCAL,
    ]
    .concat();
    let (ok, _, err) = common::host_in(Some(d), &args);
    assert!(ok, "{err}");
    // segment,t_s,f_x_g,f_y_g,f_z_g,…
    let ours_rows: Vec<(f64, [f64; 3])> = numeric_rows(&applied)
        .iter()
        .map(|r| (r[1], core::array::from_fn(|j| r[2 + j])))
        .collect();
    // The reference: the rests' mean outputs and their faces, from the segmented session.
    let session =
        recording::session::read_session(&d.join("s"), &recording::session::ReadOptions::default())
            .unwrap();
    let rests: Vec<([f64; 3], [f64; 3])> = (session.stats.iter())
        .map(|st| (st.mean_u, session.plan.segment(&st.name).unwrap().up_b))
        .collect();
    let (k_inv, b) = faces_exact_fit(&rests);
    let raw: Vec<(f64, [f64; 3])> = rows
        .iter()
        .enumerate()
        .map(|(n, r)| {
            let u = nalgebra::Vector3::from_fn(|j, _| r[4 + j] - b[j]);
            let f = k_inv * u;
            (t_of(n), [f[0], f[1], f[2]])
        })
        .collect();
    let (mut ours, mut exact) = (Vec::new(), Vec::new());
    for &(t0, t1, axis) in &turns {
        ours.push(off_axis_mg(&mean_over(&ours_rows, t0, t1), axis));
        exact.push(off_axis_mg(&mean_over(&raw, t0, t1), axis));
        println!(
            "turn on face {} ({t0:.1}–{t1:.1} s): mean specific force {:.2} mg off the axis \
             (faces taken as exact: {:.2} mg)",
            ["x", "y", "z"][axis],
            ours.last().unwrap(),
            exact.last().unwrap()
        );
    }
    println!(
        "rms over the turns: ours {:.2} mg, faces taken as exact {:.2} mg",
        rms(&ours),
        rms(&exact)
    );
    assert!(rms(&ours) <= rms(&exact), "{ours:?} against {exact:?}");
    assert!(ours.iter().all(|&mg| mg < 5.0), "{ours:?}");
}

/// The rows of a CSV file after its header, each cell as a number (NaN where it is not one).
fn numeric_rows(path: &Path) -> Vec<Vec<f64>> {
    std::fs::read_to_string(path)
        .unwrap()
        .lines()
        .skip(1)
        .map(|l| {
            l.split(',')
                .map(|c| c.parse().unwrap_or(f64::NAN))
                .collect()
        })
        .collect()
}

/// A short rest in a long flight log: PX4's 92 s quadrotor flight is still only for about 6 s
/// before take-off and 2.7 s after landing. `noise` finds a rest of more than 4 s, which only the
/// one before take-off is, and says that sensor_combined is what it read.
#[test]
fn a_flight_logs_short_rest_is_found() {
    let tmp = tempfile::tempdir().unwrap();
    let d = tmp.path();
    let input = unpack(d, "px4ulogrs_quadrotor_local.ulg.zst");
    let input = input.to_str().unwrap();
    let args = ["noise", "--input", input, "--out", "n", "--json"];
    let (ok, out, err) = common::host_in(Some(d), &args);
    assert!(ok, "{err}");
    let doc: serde_json::Value = serde_json::from_str(&out).unwrap();
    let seconds = doc["samples"].as_f64().unwrap() / doc["sample_rate_hz"].as_f64().unwrap();
    println!("PX4 flight log: the rest `noise` reads lasts {seconds:.2} s");
    assert!((4.0..6.5).contains(&seconds), "{seconds} s: {out}");
    assert!(err.contains("reading sensor_combined"), "{err}");
}

/// A host-stamped ROS bag (an AR.Drone's IMU stamped by its driver on WiFi receipt, 50 Hz, packets
/// lost in runs of up to a second), converted to a ROS 2 bag as the reader's refusal of the ROS 1
/// bag says: read at its 50 Hz, each gap named, the two rests on the bench found (9.7 s and 11.5 s),
/// and refused for having only those two positions.
#[test]
fn a_host_stamped_bag_is_read_with_its_gaps_named() {
    let tmp = tempfile::tempdir().unwrap();
    let d = tmp.path();
    let input = unpack(d, "imutools_ardrone_imu_ros2.mcap.zst");
    let (ok, stdout, stderr) = segment(d, &input, "s", &[]);
    assert!(!ok, "{stdout}");
    assert!(stderr.contains("time stamps jump 24 time(s)"), "{stderr}");
    assert_eq!(count_before(&stdout, "still interval(s)"), 2, "{stdout}");
    assert!(stderr.contains("2 distinct position(s)"), "{stderr}");
}
