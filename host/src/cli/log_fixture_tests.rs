//! The binary log fixtures (`recording/tests/fixtures/logs/`, written by each format's reference tool
//! from a simulated hand session) through `host segment` → `host calibrate` → `host apply`, against
//! the simulated unit (`hand.truth.toml`) and against the same session read from its CSV. What the
//! readers alone read of them is `recording`'s test (`tests/reference_tools.rs`).

use super::segment::segment;
use super::{apply, calibrate, Cli, Command};
use clap::Parser;
use estimator::sim::handheld::{
    logger_unit, simulate_hand, write_logger_csv, HandSpec, LoggerLayout,
};
use estimator::sim::montecarlo::static_errors;
use estimator::unit_file::UnitFile;
use recording::session::logs::{read_log, LogSource};
use shared::{Calibration, OutputUnit};
use std::path::{Path, PathBuf};

/// The rows of the simulated session the fixtures hold (`scripts/make-log-fixtures.py`'s ROWS).
const ROWS: usize = 6000;

/// A file of the readers' fixtures.
pub(super) fn fixture(name: &str) -> PathBuf {
    recording::testkit::log_fixture(name)
}

/// The subcommand a command line parses to.
pub(super) fn command(line: &str) -> Command {
    Cli::try_parse_from(line.split_whitespace())
        .unwrap()
        .command
}

/// `what`'s calibration is as good as the reference one: its held-out error (µg) and gyro bias
/// error (°/s), as [`segment_and_calibrate`] gives them, within 10 % of the reference's, or 2 µg
/// and 0.002 °/s of it (a float32 log's rounding, a sample or two lost).
pub(super) fn assert_as_good(what: &str, (ug, bias): (f64, f64), (ref_ug, ref_bias): (f64, f64)) {
    assert!(
        ug <= (ref_ug * 1.1).max(ref_ug + 2.0),
        "{what}: {ug} µg, the reference {ref_ug}"
    );
    assert!(
        bias <= (ref_bias * 1.1).max(ref_bias + 0.002),
        "{what}: {bias} °/s, the reference {ref_bias}"
    );
}

pub(super) fn truth() -> Calibration {
    UnitFile::load(&fixture("hand.truth.toml"))
        .unwrap()
        .to_calibration()
        .unwrap()
}

/// Segments `input` (with `flags`) into `dir/s`, calibrates it into `dir/cal`; returns the intrinsic
/// rms error against the truth on held-out attitudes (µg) and the gyro bias error (°/s, worst axis).
pub(super) fn segment_and_calibrate(dir: &Path, input: &Path, flags: &str) -> (f64, f64) {
    let d = dir.display();
    let line = format!(
        "host segment -q --input {} --out {d}/s {flags}",
        input.display()
    );
    let Command::Segment(a) = command(&line) else {
        panic!("{line}")
    };
    let out = segment(&a).unwrap();
    let Command::Calibrate(c) = command(&format!("host calibrate --input {d}/s --out-dir {d}/cal"))
    else {
        panic!()
    };
    let cal = calibrate::calibrate(&c, true).unwrap();
    let e = static_errors(&truth(), &cal.fitted, &mut shared::rng::Rng::new(5, 0));
    let spec = HandSpec::standard(1);
    let fit = out.gyro.unwrap();
    let bias_err = (0..3)
        .map(|i| {
            (fit.bias_rad_s[i] - spec.gyro.bias_rad_s[i])
                .abs()
                .to_degrees()
        })
        .fold(0.0, f64::max);
    (e.rms_ug, bias_err)
}

/// The same session as a logger CSV, as `host simulate-hand --rate-hz 100 --gyro-unit rad/s` writes
/// it, cut to the fixtures' rows; its calibration is the yardstick for the binary formats.
pub(super) fn csv_reference(dir: &Path) -> (f64, f64) {
    let spec = HandSpec {
        rate_hz: 100.0,
        ..HandSpec::standard(1)
    };
    let sim = simulate_hand(&logger_unit(OutputUnit::MetresPerSecondSquared), &spec);
    let layout = LoggerLayout {
        gyro_deg_s: false,
        ..LoggerLayout::default()
    };
    std::fs::create_dir_all(dir).unwrap();
    let csv = dir.join("hand.csv");
    write_logger_csv(&csv, &sim.rows[..ROWS], &layout).unwrap();
    // The fixtures hold this very session: their first sample is its first row, as float32.
    let expected: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(fixture("expected.json")).unwrap()).unwrap();
    let first = &expected["hand.bin"][0]["acc"];
    for j in 0..3 {
        assert_eq!(
            first[j].as_f64().unwrap(),
            f64::from(sim.rows[0].1[j] as f32)
        );
    }
    segment_and_calibrate(
        dir,
        &csv,
        "--time-column t --acc-unit m/s2 --gyro-unit rad/s",
    )
}

/// Every format calibrates like the CSV of the same session: the accelerometer's intrinsic error on
/// held-out attitudes and the gyro bias against the simulated unit, and `host apply` on the log
/// gives 1 g at rest with the corrected rate beside it.
#[test]
fn every_format_calibrates_like_the_csv_and_applies() {
    let tmp = tempfile::tempdir().unwrap();
    let (csv_ug, csv_bias) = csv_reference(&tmp.path().join("csv"));
    println!("CSV: intrinsic rms {csv_ug:.1} µg, gyro bias error {csv_bias:.4} °/s");
    // Ten positions, none near z down (segment's advice says so): a few times the 24-position
    // session's 21 µg, and well inside the 1 mg a consumer IMU's calibration is held to.
    assert!(csv_ug < 400.0 && csv_bias < 0.02, "{csv_ug} {csv_bias}");
    for name in ["hand.ulg", "hand.bin", "hand.mcap"] {
        let dir = tmp.path().join(name);
        std::fs::create_dir_all(&dir).unwrap();
        let (ug, bias) = segment_and_calibrate(&dir, &fixture(name), "");
        println!("{name}: intrinsic rms {ug:.1} µg, gyro bias error {bias:.4} °/s");
        // The logs hold the values as float32 (0.5 µg steps at 1 g) and ULog lost two samples:
        // within 10 % (or 2 µg) of the CSV's error.
        assert_as_good(name, (ug, bias), (csv_ug, csv_bias));
        let out = dir.join("applied.csv");
        let line = format!(
            "host apply --calibration {}/cal/calibration.toml --input {} --out {}",
            dir.display(),
            fixture(name).display(),
            out.display()
        );
        let Command::Apply(a) = command(&line) else {
            panic!()
        };
        apply::run(&a, true).unwrap();
        let text = std::fs::read_to_string(&out).unwrap();
        let mut lines = text.lines();
        assert_eq!(lines.next(), Some(outputs::apply::APPLY_HEADER));
        let rows: Vec<Vec<f64>> = lines
            .map(|l| l.split(',').skip(1).map(|v| v.parse().unwrap()).collect())
            .collect();
        assert!(rows.len() >= ROWS - 2, "{name}: {}", rows.len());
        // At rest (corrected rate under 1 °/s: the hand trembles), the median |f| is 1 g within 0.2 mg.
        let mut rest: Vec<f64> = rows
            .iter()
            .filter(|r| shared::linalg::norm(&[r[4], r[5], r[6]]).to_degrees() < 1.0)
            .map(|r| shared::linalg::norm(&[r[1], r[2], r[3]]) - 1.0)
            .collect();
        assert!(rest.len() > 1000, "{name}: {} rows at rest", rest.len());
        rest.sort_by(f64::total_cmp);
        let median_ug = rest[rest.len() / 2] * 1e6;
        println!("{name}: apply, median |f| − 1 g at rest {median_ug:.1} µg");
        assert!(median_ug.abs() < 200.0, "{name}: {median_ug} µg");
        // `host noise` on the same file: its longest still interval, in m/s² through the calibration
        // (which must turn it into 1 g).
        let line = format!(
            "host noise --input {} --calibration {}/cal/calibration.toml --out {}/noise",
            fixture(name).display(),
            dir.display(),
            dir.display()
        );
        let Command::Noise(a) = command(&line) else {
            panic!()
        };
        super::noise::run(&a, true).unwrap();
        let doc: serde_json::Value =
            serde_json::from_str(&std::fs::read_to_string(dir.join("noise/noise.json")).unwrap())
                .unwrap();
        let samples = doc["samples"].as_u64().unwrap();
        assert!((300..=600).contains(&samples), "{name}: {samples}");
        assert!(
            doc["segment"].as_str().unwrap().starts_with("still "),
            "{doc}"
        );
    }
}

/// The options that choose an IMU say what the log has when they choose nothing.
#[test]
fn a_missing_instance_or_topic_names_what_the_log_has() {
    let read = |name: &str, instance, topic: Option<&str>| {
        let source = LogSource {
            text: None,
            instance,
            topic: topic.map(String::from),
            spelling: super::spelling::FLAGS,
            rate_hz: None,
        };
        shared::chain::Chain(&read_log(&fixture(name), &source).unwrap_err()).to_string()
    };
    let e = read("hand.ulg", Some(1), None);
    assert!(
        e.contains("instance 1") && e.contains("sensor_accel instance 0"),
        "{e}"
    );
    let e = read("hand.bin", Some(2), None);
    assert!(
        e.contains("instance 2") && e.contains("IMU instance 0"),
        "{e}"
    );
    let e = read("hand.mcap", None, Some("/imu/raw"));
    assert!(
        e.contains("--topic /imu/raw") && e.contains("/imu/data"),
        "{e}"
    );
    let e = read("hand.mcap", Some(1), None);
    assert!(e.contains("--instance does not apply"), "{e}");
    let mut source = LogSource {
        text: None,
        instance: None,
        topic: Some("/imu/data".into()),
        spelling: super::spelling::FLAGS,
        rate_hz: None,
    };
    assert_eq!(
        read_log(&fixture("hand.mcap"), &source)
            .unwrap()
            .recording
            .len(),
        ROWS
    );
    source.text = Some(recording::session::import::ImportOptions::new(
        recording::session::import::TimeSource::RateHz(100.0),
        OutputUnit::StandardGravity,
        recording::session::import::GyroUnit::DegPerS,
        crate::cli::spelling::FLAGS,
    ));
    let e = read_log(&fixture("hand.mcap"), &source)
        .unwrap_err()
        .to_string();
    assert!(
        e.contains("states its own units") && e.contains("--acc-unit"),
        "{e}"
    );
}

/// A logger's file options given with a session directory would be ignored: refused instead.
#[test]
fn log_options_on_a_session_directory_are_refused() {
    let tmp = tempfile::tempdir().unwrap();
    let d = tmp.path().display();
    for extra in ["--topic /imu", "--instance 1", "--acc-unit g"] {
        let Command::Noise(a) = command(&format!("host noise --input {d} {extra}")) else {
            panic!()
        };
        let e = super::noise::run(&a, true).unwrap_err().to_string();
        assert!(
            e.contains("is a session directory") && e.contains("leave them out"),
            "{e}"
        );
    }
    let Command::Noise(a) = command(&format!("host noise --input {d}")) else {
        panic!()
    };
    let e = super::noise::run(&a, true).unwrap_err().to_string();
    assert!(!e.contains("is a session directory"), "{e}");
}

/// A public PX4 log (pyulog's own test file, read as pyulog reads it in `recording`'s
/// `tests/reference_tools.rs`) is a flight log, not a calibration session, and its IMU data are
/// `sensor_combined`, which PX4 has already corrected: `segment` must say so, and `apply` must refuse
/// it by the same rule (it would correct the samples a second time), writing nothing.
#[test]
fn segment_and_apply_say_why_a_corrected_flight_log_is_no_session() {
    let path = fixture("px4-sample-appended-multiple.ulg");
    let tmp = tempfile::tempdir().unwrap();
    let line = format!(
        "host segment -q --input {} --out {}/s",
        path.display(),
        tmp.path().display()
    );
    let Command::Segment(a) = command(&line) else {
        panic!()
    };
    let Err(e) = segment(&a) else {
        panic!("a flight log segmented")
    };
    let e = e.to_string();
    assert!(
        e.contains("sensor_combined") && e.contains("Log the sensor's raw topics"),
        "{e}"
    );

    let out = tmp.path().join("applied.csv");
    let line = format!(
        "host apply --calibration {} --input {} --out {}",
        fixture("hand.truth.toml").display(),
        path.display(),
        out.display()
    );
    let Command::Apply(a) = command(&line) else {
        panic!()
    };
    let e = apply::run(&a, true).unwrap_err().to_string();
    assert!(
        e.contains("sensor_combined") && e.contains("a second time"),
        "{e}"
    );
    assert!(!out.exists(), "apply wrote a corrected-twice file");
}

/// A still unit whose driver stamped it on the host in bursts: eight samples share the stamp of the
/// first, the true rate 100 Hz (the stamps' median step is 0, their count per second 100).
fn bursty_still(n: usize) -> Vec<recording::testkit::LogSample> {
    (0..n)
        .map(|k| recording::testkit::LogSample {
            t_s: (k / 8 * 8) as f64 / 100.0,
            ..recording::testkit::still_sample(k, 100.0)
        })
        .collect()
}

/// `--rate-hz` on a binary log re-times every sample at the rate given, from the first stamp, and
/// says the rate the stamps imply beside it (here the user's 99.3 Hz against the stamps' 100 Hz),
/// in every binary format; with another text option it is still refused.
#[test]
fn a_rate_given_for_a_binary_log_re_times_it_and_says_what_the_stamps_imply() {
    use recording::testkit::{write_dataflash, write_mcap, write_ulog};
    let tmp = tempfile::tempdir().unwrap();
    let samples = bursty_still(3000);
    for (name, bytes) in [
        ("still.mcap", write_mcap(&samples, None, 0.0)),
        ("still.bin", write_dataflash(&samples)),
        ("still.ulg", write_ulog(&samples, None)),
    ] {
        let path = tmp.path().join(name);
        std::fs::write(&path, bytes).unwrap();
        let Command::Noise(a) = command(&format!(
            "host noise --input {} --rate-hz 99.3",
            path.display()
        )) else {
            panic!("noise parses")
        };
        let source = a.log.source(&path).unwrap();
        assert_eq!(source.rate_hz, Some(99.3));
        let log = read_log(&path, &source).unwrap();
        let rec = &log.recording;
        assert_eq!(rec.len(), 3000, "{name}: every sample kept");
        for (k, t) in rec.t_s.iter().enumerate() {
            let want = rec.t_s[0] + k as f64 / 99.3;
            assert!(
                (t - want).abs() < 1e-9,
                "{name}: sample {k} at {t}, not {want}"
            );
        }
        let note = log
            .warnings
            .iter()
            .find(|w| w.to_string().contains("re-timed at 99.3 Hz"))
            .unwrap_or_else(|| panic!("{name}: {:?}", log.warnings));
        let implied: f64 = note
            .to_string()
            .split("the stamps imply ")
            .nth(1)
            .and_then(|s| s.split(' ').next())
            .and_then(|s| s.parse().ok())
            .unwrap_or_else(|| panic!("{note}"));
        assert!((implied - 100.0).abs() < 0.3, "{name}: {note}");
        assert!(note.to_string().contains("+0.7"), "{note}");
        // Without the rate, the stamps are the log's own.
        let own = read_log(
            &path,
            &LogSource {
                rate_hz: None,
                ..source
            },
        )
        .unwrap();
        assert!(own
            .warnings
            .iter()
            .all(|w| !w.to_string().contains("re-timed at")));
        // The rate with a text file's option on a binary log: refused, naming what was given.
        let Command::Noise(b) = command(&format!(
            "host noise --input {} --rate-hz 99.3 --acc-unit g",
            path.display()
        )) else {
            panic!("noise parses")
        };
        let e = b.log.source(&path).unwrap_err().to_string();
        assert!(e.contains("--acc-unit") && e.contains("--rate-hz"), "{e}");
    }
}
