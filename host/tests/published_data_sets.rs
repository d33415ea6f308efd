//! A published IMU calibration data set, read as a user of the toolkit that published it would:
//! IMU-TK's Xsens recording (`fixtures/datasets/README.md`), raw counts of an unsigned output,
//! converted with that toolkit's own starting values (accelerometer zero 32 768 counts, gyro
//! 6 258 counts per rad/s). IMU-TK's own fit finds that gyro scale about 24 % off: a calibration
//! result, not a wrong time base.

mod common;

use std::collections::BTreeMap;
use std::path::Path;

/// IMU-TK's example gyro scale, 1/6258 rad/s per count, in counts per °/s.
const IMU_TK_LSB_PER_DPS: f64 = 6258.0 * std::f64::consts::PI / 180.0;

fn unpack(dir: &Path) -> String {
    let packed = std::fs::read(concat!(
        env!("CARGO_MANIFEST_DIR"),
        "/tests/fixtures/datasets/imu_tk-xsens.csv.zst"
    ))
    .unwrap();
    let text = zstd::decode_all(&packed[..]).unwrap();
    std::fs::write(dir.join("xsens.csv"), text).unwrap();
    "xsens.csv".into()
}

/// The gyro's rows less the output's zero (32 768 counts), as IMU-TK's pipeline removes it before
/// its fit (a calibration would otherwise hold a 300 °/s bias no device accepts): the yardstick of
/// `--gyro-offset 32768` on the raw file, which must give the same session.
fn gyro_zero_removed(dir: &Path) -> String {
    let text = std::fs::read_to_string(dir.join("xsens.csv")).unwrap();
    let mut out = String::new();
    for (k, line) in text.lines().enumerate() {
        if k == 0 {
            out.push_str(line);
        } else {
            let f: Vec<&str> = line.split(',').collect();
            let g: Vec<String> = f[4..]
                .iter()
                .map(|c| (c.parse::<i64>().unwrap() - 32_768).to_string())
                .collect();
            out.push_str(&format!("{},{}", f[..4].join(","), g.join(",")));
        }
        out.push('\n');
    }
    std::fs::write(dir.join("centred.csv"), out).unwrap();
    "centred.csv".into()
}

fn segment(dir: &Path, input: &str, out: &str) -> (bool, String, String) {
    segment_with(dir, input, out, &[])
}

/// [`segment`] with `more` options.
fn segment_with(dir: &Path, input: &str, out: &str, more: &[&str]) -> (bool, String, String) {
    let lsb = format!("{IMU_TK_LSB_PER_DPS}");
    let mut args = vec![
        "segment",
        "--input",
        input,
        "--out",
        out,
        "--time-column",
        "t",
        "--acc-unit",
        "LSB",
        "--acc-offset",
        "32768",
        "--gyro-unit",
        "LSB",
        "--gyro-lsb-per-dps",
        &lsb,
    ];
    args.extend_from_slice(more);
    common::host_in(Some(dir), &args)
}

/// The number after `key` in `text` (up to a space, comma or °).
fn number_after(text: &str, key: &str) -> f64 {
    let at = text
        .find(key)
        .unwrap_or_else(|| panic!("no '{key}' in {text}"))
        + key.len();
    text[at..]
        .trim_start()
        .split([' ', ',', '°'])
        .next()
        .unwrap()
        .parse()
        .unwrap_or_else(|_| panic!("no number after '{key}' in {text}"))
}

#[test]
fn imu_tks_xsens_recording_segments_and_calibrates() {
    let tmp = tempfile::tempdir().unwrap();
    let d = tmp.path();
    let raw = unpack(d);
    // As published: the gyro's unsigned zero reads as a 300 °/s bias, which the fit must take as a
    // bias, not as a rotation of the still positions (it used to misfit the turns by 44°).
    let (ok, stdout, stderr) = segment(d, &raw, "raw");
    assert!(ok, "{stderr}");
    assert!(stdout.contains("in 38 static segments"), "{stdout}");
    assert!(number_after(&stdout, "rms misfit") < 1.0, "{stdout}");
    // The nominal scale 24 % off: a result with the warning, both causes named with their figures.
    let implied = number_after(&stderr, "the turns imply");
    let off = implied / IMU_TK_LSB_PER_DPS - 1.0;
    assert!((-0.25..-0.22).contains(&off), "{off}: {stderr}");
    assert!(
        stderr.contains("its stamps would have to step at"),
        "{stderr}"
    );
    // The unsigned zero is named, with the option that takes it out.
    assert!(
        stderr.contains("mid-scale of a 16-bit unsigned output")
            && stderr.contains("give --gyro-offset 32768"),
        "{stderr}"
    );
    // With the gyro's zero removed, as IMU-TK's pipeline does: the same turns, and a calibration
    // that passes its checks.
    let centred = gyro_zero_removed(d);
    let (ok, stdout, stderr) = segment(d, &centred, "s");
    assert!(ok, "{stderr}");
    assert!(number_after(&stdout, "rms misfit") < 1.0, "{stdout}");
    assert!(
        (number_after(&stderr, "the turns imply") - implied).abs() < 0.01,
        "{stderr}"
    );
    let (ok, stdout, stderr) =
        common::host_in(Some(d), &["calibrate", "--input", "s", "--out", "c"]);
    assert!(ok, "{stderr}");
    assert!(stdout.contains("verdict          PASS"), "{stdout}");
    // The raw file with --gyro-offset: the session the centred file gives, to the byte.
    let (ok, _, stderr) = segment_with(d, &raw, "off", &["--gyro-offset", "32768"]);
    assert!(ok, "{stderr}");
    assert!(!stderr.contains("--gyro-offset"), "{stderr}");
    for f in ["samples.csv", "gyro.toml", "plan.toml"] {
        let (a, b) = (d.join("s").join(f), d.join("off").join(f));
        assert!(
            std::fs::read(&a).unwrap() == std::fs::read(&b).unwrap(),
            "{f} differs"
        );
    }
}

/// rosbag2's own test bags (`fixtures/logs/rosbag2.LICENSE`, Apache-2.0): ROS 2 bags that hold no
/// IMU. Each is read and refused for that reason, naming the topics rosbag2's tests say it holds
/// (`rosbag2_py/test/test_sequential_reader.py`: the talker bag's `rcl_interfaces/msg/Log`,
/// `rcl_interfaces/msg/ParameterEvent` and `std_msgs/msg/String`; `rosbag2_tests`' cdr bag of
/// `test_msgs/msg/BasicTypes` and `Arrays`), and the command that records an IMU.
#[test]
fn rosbag2s_test_bags_are_read_and_refused_for_holding_no_imu() {
    let tmp = tempfile::tempdir().unwrap();
    let fixtures = recording::testkit::log_fixture("");
    let fixtures = fixtures.display();
    for (bag, types) in [
        (
            "rosbag2-talker.mcap",
            &[
                "rcl_interfaces/msg/Log",
                "rcl_interfaces/msg/ParameterEvent",
                "std_msgs/msg/String",
            ][..],
        ),
        (
            "rosbag2-cdr_test_0.mcap",
            &["test_msgs/msg/BasicTypes", "test_msgs/msg/Arrays"][..],
        ),
    ] {
        let input = format!("{fixtures}/{bag}");
        let (ok, _, stderr) = common::host_in(
            Some(tmp.path()),
            &["segment", "--input", &input, "--out", bag],
        );
        assert!(!ok, "{bag}");
        assert!(stderr.contains("no sensor_msgs/msg/Imu topic"), "{stderr}");
        for t in types {
            assert!(stderr.contains(t), "{bag}: {t} not named: {stderr}");
        }
        assert!(stderr.contains("ros2 bag record"), "{stderr}");
        assert!(
            !tmp.path().join(bag).exists(),
            "{bag}: a session was written"
        );
    }
}

/// Each message name's `TimeUS` stamps, counted by walking a DataFlash log the way ArduPilot writes
/// it (`libraries/AP_Logger/LogStructure.h`): every message is `0xA3 0x95 type`, its length given by
/// an earlier `FMT` (type 128, 89 bytes: Type, Length, Name `char[4]`, Format `char[16]`, Columns
/// `char[64]`). Independent of the reader under test: no resynchronisation, so it stops the test if
/// a message does not start where the previous one ended. Also the bytes of a last message cut off
/// by the end of the file.
fn walk_dataflash(bytes: &[u8], names: &[&str]) -> (BTreeMap<String, Vec<u64>>, usize) {
    let mut length = BTreeMap::from([(128u8, 89usize)]);
    let mut name = BTreeMap::from([(128u8, "FMT".to_string())]);
    let mut stamps: BTreeMap<String, Vec<u64>> = BTreeMap::new();
    let mut at = 0;
    while at + 3 <= bytes.len() {
        assert_eq!(
            bytes[at..at + 2],
            [0xA3, 0x95],
            "no message starts at byte {at}"
        );
        let kind = bytes[at + 2];
        let len = length[&kind];
        if at + len > bytes.len() {
            return (stamps, bytes.len() - at);
        }
        let m = &bytes[at..at + len];
        if kind == 128 {
            let text = |r: std::ops::Range<usize>| {
                String::from_utf8_lossy(&m[r])
                    .trim_end_matches('\0')
                    .to_string()
            };
            let (n, format, columns) = (text(5..9), text(9..25), text(25..89));
            if names.contains(&n.as_str()) {
                assert!(
                    format.starts_with('Q') && columns.starts_with("TimeUS,"),
                    "{n}"
                );
            }
            length.insert(m[3], usize::from(m[4]));
            name.insert(m[3], n);
        } else if names.contains(&name[&kind].as_str()) {
            let t = u64::from_le_bytes(m[3..11].try_into().unwrap());
            stamps.entry(name[&kind].clone()).or_default().push(t);
        }
        at += len;
    }
    (stamps, bytes.len() - at)
}

/// pymavlink's own test log (`fixtures/logs/pymavlink-test.bin`, its `tests/test.BIN`, LGPL-3.0;
/// licence beside it): the first 64 KiB of a real ArduPlane 3.8.2-dev log (a PX4v4 board, armed on
/// the ground, 2017), its two IMUs in the older naming, messages `IMU` and `IMU2` with no `I` field,
/// each with the sensor's temperature `T`. Both read as pymavlink 2.4.50's `DFReader_binary` reads
/// them: 45 samples each (the same count as the walk above), the first and last values equal, at
/// 50.3 Hz; the message the file's end cuts short is left out and said so. A second of data is no
/// calibration session: `segment` refuses it for that, naming the count, and
/// the reason is true of the log (it is 0.97 s long, shorter than one still position of the default
/// 1 s, let alone minutes). An instance the log does not have is refused with the two it has.
#[test]
fn pymavlinks_test_log_reads_as_pymavlink_reads_it_and_is_too_short_for_a_session() {
    let path = recording::testkit::log_fixture("pymavlink-test.bin");
    let path = path.to_str().unwrap();
    let bytes = std::fs::read(path).unwrap();
    assert_eq!(bytes[..3], [0xA3, 0x95, 0x80]);
    let (stamps, cut) = walk_dataflash(&bytes, &["IMU", "IMU2"]);
    assert_eq!(cut, 24, "the file ends 24 bytes into an AHR2 message");
    // pymavlink's values (`DFReader_binary(f).recv_msg()`): TimeUS, AccX..Z, GyrX..Z, T of the
    // first and last samples.
    let pymavlink = [
        (
            "IMU",
            [
                (
                    81_794_643u64,
                    [0.41619187593460083, 0.4691760838031769, -9.780994415283203],
                    [
                        -0.1165708526968956,
                        0.009646732360124588,
                        -0.0036614425480365753,
                    ],
                    44.423282623291016,
                ),
                (
                    82_769_489,
                    [0.3519606590270996, 0.735745906829834, -9.931867599487305],
                    [
                        -0.05384852737188339,
                        -0.009476035833358765,
                        -0.004102954640984535,
                    ],
                    44.46217346191406,
                ),
            ],
        ),
        (
            "IMU2",
            [
                (
                    81_794_643,
                    [0.3878509998321533, 0.5220719575881958, -9.676275253295898],
                    [
                        -0.11092303693294525,
                        0.009959599003195763,
                        -0.001431140466593206,
                    ],
                    39.922950744628906,
                ),
                (
                    82_769_489,
                    [0.31356990337371826, 0.78541499376297, -9.849275588989258],
                    [
                        -0.052002906799316406,
                        -0.009817482903599739,
                        -0.0028600424993783236,
                    ],
                    39.95038604736328,
                ),
            ],
        ),
    ];
    let tmp = tempfile::tempdir().unwrap();
    for (instance, (name, want)) in pymavlink.iter().enumerate() {
        let walked = &stamps[*name];
        assert_eq!(walked.len(), 45, "{name}: pymavlink reads 45");
        let (rec, warnings) = recording::session::logs::dataflash::read(
            std::fs::File::open(path).unwrap(),
            instance as u8,
        )
        .unwrap();
        assert_eq!(rec.len(), walked.len(), "{name}");
        let cut_at = format!("(at byte {}) is cut short", bytes.len() - cut);
        assert!(
            warnings.iter().any(|w| w.to_string().contains(&cut_at)),
            "{warnings:?}"
        );
        // 20 ms steps with a few missed (the median step, 20 ms; 44 steps of 49 periods in 0.975 s):
        // the rate is the mean over the steps, each counted in whole periods.
        let periods: f64 = walked
            .windows(2)
            .map(|w| ((w[1] - w[0]) as f64 / 20_000.0).round())
            .sum();
        let span_s = (walked[walked.len() - 1] - walked[0]) as f64 * 1e-6;
        assert_eq!(periods, 49.0);
        assert!(
            (rec.rate_hz - periods / span_s).abs() < 1e-6,
            "{}",
            rec.rate_hz
        );
        let temp = rec.temp_c.as_ref().expect("IMU messages carry T");
        for (i, (t_us, acc, gyro, t_c)) in [0, rec.len() - 1].into_iter().zip(want) {
            assert_eq!(walked[i], *t_us, "{name}");
            assert!(
                (rec.t_s[i] - *t_us as f64 * 1e-6).abs() < 1e-9,
                "{name} {i}"
            );
            assert_eq!(rec.acc[i], *acc, "{name} {i}");
            assert_eq!(rec.gyro_rad_s[i], *gyro, "{name} {i}");
            assert_eq!(temp[i], *t_c, "{name} {i}");
        }
        assert!(span_s < 1.0, "{span_s}");

        let out = format!("s{instance}");
        let inst = instance.to_string();
        let (ok, _, stderr) = common::host_in(
            Some(tmp.path()),
            &[
                "segment",
                "--input",
                path,
                "--out",
                &out,
                "--instance",
                &inst,
            ],
        );
        assert!(!ok, "{name}: a second of data segmented");
        let count = format!("only {} IMU samples", walked.len());
        assert!(
            stderr.contains(&count) && stderr.contains("needs minutes of data"),
            "{stderr}"
        );
        assert!(
            !tmp.path().join(&out).exists(),
            "{name}: a session was written"
        );
        // A second of data is no session, but it is a log: `apply` and `noise` read it whole (the
        // reason above is `segment`'s alone).
        let source = recording::session::logs::LogSource {
            text: None,
            instance: Some(instance as u8),
            topic: None,
            spelling: Default::default(),
            rate_hz: None,
        };
        let log = recording::session::logs::read_log(Path::new(path), &source).unwrap();
        assert_eq!(log.recording.len(), walked.len(), "{name}");
    }
    let (ok, _, stderr) = common::host_in(
        Some(tmp.path()),
        &["segment", "--input", path, "--out", "s2", "--instance", "2"],
    );
    assert!(!ok);
    assert!(
        stderr.contains("no IMU samples for instance 2")
            && stderr.contains("IMU instance 0, IMU instance 1"),
        "{stderr}"
    );
}

/// pymavlink's test log (above) is a real vehicle's, and its IMU samples were logged after the
/// vehicle's own calibration. Its PARM messages read as pymavlink decodes them (`TimeUS`, `Name`
/// `char[16]`, `Value` `float`; these values from a walk of the file with Python's `struct`):
/// AHRS_ORIENTATION 8 (roll 180°), INS_ACCOFFS_Y 2.485 m/s², INS_ACCSCAL_Y 0.9025 (9.7 %), the two
/// IMUs' ids. `read_log` gives the samples with that correction undone: corrected again the way
/// `_rotate_and_correct_accel` does (offsets, scales, then `ROTATION_ROLL_180`: y and z negated),
/// they are pymavlink's logged values, to `float` rounding.
#[test]
fn pymavlinks_test_log_is_undone_with_its_own_parameters() {
    use recording::session::logs::vehicle::{read_vehicle_params, SensorKind};
    use recording::session::logs::{read_log, LogSource};
    let path = recording::testkit::log_fixture("pymavlink-test.bin");
    let (_, params) = read_vehicle_params(&path).unwrap().unwrap();
    let offs = [
        -0.03169693425297737,
        2.4852089881896973,
        -0.29318252205848694,
    ];
    let scal = [0.999653160572052, 0.9025073051452637, 1.0012799501419067];
    let gyro_offs = [
        -0.07990042120218277,
        -0.005997729022055864,
        0.00634012371301651,
    ];
    assert_eq!(params.get("AHRS_ORIENTATION"), Some(8.0));
    for (i, axis) in ["X", "Y", "Z"].iter().enumerate() {
        assert_eq!(params.get(&format!("INS_ACCOFFS_{axis}")), Some(offs[i]));
        assert_eq!(params.get(&format!("INS_ACCSCAL_{axis}")), Some(scal[i]));
        assert_eq!(
            params.get(&format!("INS_GYROFFS_{axis}")),
            Some(gyro_offs[i])
        );
    }
    let slot = |k, i| params.ardupilot_slot(k, i).unwrap().device_id;
    assert_eq!(slot(SensorKind::Accel, 0), 1_246_730);
    assert_eq!(slot(SensorKind::Accel, 1), 1_442_826);
    assert_eq!(slot(SensorKind::Gyro, 0), 2_164_234);
    let source = LogSource {
        text: None,
        instance: Some(0),
        topic: None,
        spelling: Default::default(),
        rate_hz: None,
    };
    let undone = read_log(&path, &source).unwrap();
    assert!(
        undone
            .warnings
            .iter()
            .any(|w| w.to_string().contains("undone")),
        "{:?}",
        undone.warnings
    );
    let (logged, _) =
        recording::session::logs::dataflash::read(std::fs::File::open(path).unwrap(), 0).unwrap();
    let rec = &undone.recording;
    assert_eq!(rec.len(), logged.len());
    let roll_180 = |v: [f64; 3]| [v[0], -v[1], -v[2]];
    for k in 0..rec.len() {
        let acc = roll_180(std::array::from_fn(|i| (rec.acc[k][i] - offs[i]) * scal[i]));
        let gyro = roll_180(std::array::from_fn(|i| rec.gyro_rad_s[k][i] - gyro_offs[i]));
        for i in 0..3 {
            assert!((acc[i] - logged.acc[k][i]).abs() < 1e-5, "sample {k}");
            assert!(
                (gyro[i] - logged.gyro_rad_s[k][i]).abs() < 1e-6,
                "sample {k}"
            );
        }
    }
    // Not the logged values themselves: y carries the vehicle's 2.5 m/s² offset again, less the
    // logged reading turned over (about 0.6 m/s² on average here).
    let mean_y = |a: &[[f64; 3]]| a.iter().map(|v| v[1]).sum::<f64>() / a.len() as f64;
    let shift = mean_y(&rec.acc) - mean_y(&logged.acc);
    assert!(shift > 0.5, "{shift}");
}
