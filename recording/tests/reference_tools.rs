//! Each reader against the format's reference tool: the fixtures (`tests/fixtures/logs/`, written
//! by pyulog, pymavlink's reader and the mcap ROS 2 writer from one simulated hand session; their
//! README says how) and other projects' public logs, read here as those tools read them.

use recording::session::logs::{read_log, read_log_from, LogFormat, LogSource};
use recording::testkit::log_fixture;
use std::path::Path;

/// Each reader gives the reference tool's values for the first and last three samples.
#[test]
fn each_reader_reads_what_the_formats_reference_tool_reads() {
    let expected: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(log_fixture("expected.json")).unwrap())
            .unwrap();
    let none = LogSource::default();
    for (name, format) in [
        ("hand.ulg", LogFormat::Ulog),
        ("hand.bin", LogFormat::DataFlash),
        ("hand.mcap", LogFormat::Mcap),
    ] {
        let log = read_log(&log_fixture(name), &none).unwrap();
        assert_eq!(log.format, format);
        let rec = &log.recording;
        let want = expected[name].as_array().unwrap();
        let n = rec.len();
        let rows = [0, 1, 2, n - 3, n - 2, n - 1];
        for (w, &i) in want.iter().zip(&rows) {
            // The sample's own time: ULog's timestamp_sample, DataFlash's TimeUS, the Imu header
            // stamp (not ULog's publication timestamp, 150 µs later here, nor the bag's log time).
            let t = w["t_s"].as_f64().unwrap();
            assert!(
                (rec.t_s[i] - t).abs() < 1e-6,
                "{name} row {i}: {} {t}",
                rec.t_s[i]
            );
            for j in 0..3 {
                assert_eq!(
                    rec.acc[i][j],
                    w["acc"][j].as_f64().unwrap(),
                    "{name} row {i}"
                );
                assert_eq!(
                    rec.gyro_rad_s[i][j],
                    w["gyro"][j].as_f64().unwrap(),
                    "{name} row {i}"
                );
            }
        }
        assert!(
            (rec.rate_hz - 100.0).abs() < 1e-3,
            "{name}: {}",
            rec.rate_hz
        );
        // ULog and DataFlash carry the temperature ramp; an Imu message has none.
        let ramp = rec.temp_c.as_ref().map(|t| (t[0], t[n - 1]));
        match format {
            LogFormat::Mcap => assert_eq!(ramp, None),
            _ => {
                let (a, b) = ramp.unwrap();
                assert!(
                    (a - 24.0).abs() < 1e-3 && (b - 24.6).abs() < 1e-3,
                    "{name}: {a} {b}"
                );
            }
        }
        let dropout = log
            .warnings
            .iter()
            .any(|w| w.to_string().contains("dropped data 1 time(s), 20 ms"));
        assert_eq!(
            dropout,
            format == LogFormat::Ulog,
            "{name}: {:?}",
            log.warnings
        );
    }
}

/// A logger that stopped inside a message before data was appended: the same public log with its
/// last message before the first appended data (a `sensor_combined` sample at byte 434 292) made to
/// run 20 bytes into it. pyulog 1.3 drops that message and reads on at the appended data: 2372
/// samples, the last at 21.876472 s.
#[test]
fn a_message_cut_by_appended_data_is_dropped_as_pyulog_drops_it() {
    let mut bytes = std::fs::read(log_fixture("px4-sample-appended-multiple.ulg")).unwrap();
    bytes[434_292..434_294].copy_from_slice(&(74u16 + 20).to_le_bytes());
    let none = LogSource::default();
    let log = read_log_from(&bytes[..], &bytes, Path::new("cut.ulg"), &none).unwrap();
    assert_eq!(log.recording.len(), 2372);
    assert!((log.recording.t_s[2371] - 21.876472).abs() < 1e-9);
    assert!(
        log.warnings.iter().any(|w| w
            .to_string()
            .contains("byte 434292 runs into the data appended at byte 434369")),
        "{:?}",
        log.warnings
    );
}

/// A DataFlash log with `ACC` + `GYR` (the batch sampler's raw messages) and no `IMU`, two
/// instances: each instance reads as pymavlink reads it, the second with its 0.25 m/s² on x.
#[test]
fn dataflash_acc_and_gyr_messages_read_per_instance_as_pymavlink_reads_them() {
    let expected: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(log_fixture("expected.json")).unwrap())
            .unwrap();
    let want = expected["hand-accgyr.bin"].as_array().unwrap();
    for (instance, dx) in [(0u8, 0.0f32), (1, 0.25)] {
        let source = LogSource {
            text: None,
            instance: Some(instance),
            topic: None,
            spelling: Default::default(),
            rate_hz: None,
        };
        let log = read_log(&log_fixture("hand-accgyr.bin"), &source).unwrap();
        assert_eq!(log.format, LogFormat::DataFlash);
        let rec = &log.recording;
        assert_eq!(rec.len(), 1500);
        assert_eq!(rec.temp_c, None, "ACC and GYR carry no temperature");
        let n = rec.len();
        for (w, &i) in want.iter().zip(&[0, 1, 2, n - 3, n - 2, n - 1]) {
            // SampleUS, the sample's own time, not TimeUS (800 µs later, when it was written).
            assert!((rec.t_s[i] - w["t_s"].as_f64().unwrap()).abs() < 1e-9);
            let ax = w["acc"][0].as_f64().unwrap() as f32 + dx;
            assert_eq!(rec.acc[i][0], f64::from(ax), "instance {instance} row {i}");
            for j in 0..3 {
                assert_eq!(rec.gyro_rad_s[i][j], w["gyro"][j].as_f64().unwrap());
            }
        }
    }
    let source = LogSource {
        text: None,
        instance: Some(2),
        topic: None,
        spelling: Default::default(),
        rate_hz: None,
    };
    let e = shared::chain::Chain(&read_log(&log_fixture("hand-accgyr.bin"), &source).unwrap_err())
        .to_string();
    assert!(e.contains("ACC") && e.contains('1'), "{e}");
}

/// A public PX4 log, pyulog's own test file `test/sample_appended_multiple.ulg` (BSD-3-Clause,
/// licence beside it): a vehicle's `sensor_combined` at 250 Hz, with data appended three times after
/// the log was first closed. The values are pyulog 1.3's (`ULog(f).get_dataset("sensor_combined")`,
/// the accelerometer at `timestamp + accelerometer_timestamp_relative`).
#[test]
fn a_public_px4_log_reads_as_pyulog_reads_it() {
    let path = log_fixture("px4-sample-appended-multiple.ulg");
    let none = LogSource::default();
    let log = read_log(&path, &none).unwrap();
    assert_eq!(log.format, LogFormat::Ulog);
    let rec = &log.recording;
    assert_eq!(rec.len(), 2373, "pyulog reads 2373 sensor_combined samples");
    assert!((rec.t_s[0] - 12.262822).abs() < 1e-9, "{}", rec.t_s[0]);
    assert!(
        (rec.t_s[2372] - 21.880422).abs() < 1e-9,
        "{}",
        rec.t_s[2372]
    );
    let first = [0.5401454567909241, 0.32172298431396484, -9.93630313873291];
    let last = [0.5413755178451538, 0.30004557967185974, -9.923652648925781];
    assert_eq!(rec.acc[0], first);
    assert_eq!(rec.acc[2372], last);
    let mut norms: Vec<f64> = rec.acc.iter().map(shared::linalg::norm).collect();
    norms.sort_by(f64::total_cmp);
    assert!((norms[norms.len() / 2] - 9.939994).abs() < 5e-6);
    // The estimator publishes at 250 Hz (the median step, 4 ms) and now and then skips a
    // cycle: the rate is the mean over the steps, each counted in whole periods (2 372 steps in
    // 9.618 s), below the median's 250 Hz and above the plain mean's 246.6 Hz.
    let periods: f64 = rec
        .t_s
        .windows(2)
        .map(|w| ((w[1] - w[0]) / 0.004).round())
        .sum();
    let span = rec.t_s[2372] - rec.t_s[0];
    assert!(
        (rec.rate_hz - periods / span).abs() < 1e-6,
        "{}",
        rec.rate_hz
    );
    assert!((246.6..250.0).contains(&rec.rate_hz), "{}", rec.rate_hz);
    assert_eq!(rec.temp_c, None, "sensor_combined carries no temperature");
}
