//! What the readers' tests share, in this crate and above it (feature `testkit`, and this crate's own
//! tests): writers of the loggers' formats (PX4 ULog, ArduPilot DataFlash, a ROS 2 bag in MCAP, a
//! logger's CSV), each writing what its logger writes for the fields the readers use, so that a
//! test states the samples it logs and reads them back; and the checks a long log's windows are
//! held to. The fuzz targets' corpora and the long-log benchmarks log their samples with them too.

use crate::session::import::{GyroUnit, ImportOptions, Recording, TimeSource};
use crate::session::logs::{read_log_windows, ulog, LogRead, LogSource};
use crate::spelling::{Spelling, Syntax, UserOption};
use shared::OutputUnit;
use std::path::{Path, PathBuf};

/// A file of the readers' fixtures (`recording/tests/fixtures/logs/`: logs written by each
/// format's reference tool, and other projects' public logs with their licences).
pub fn log_fixture(name: &str) -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("tests/fixtures/logs")
        .join(name)
}

/// The file at `src`, unpacked into `dir` when it is zstd-compressed (`.zst`, as the corpora of real
/// recordings are stored), else `src` itself.
pub fn unpacked(src: &Path, dir: &Path) -> PathBuf {
    let name = src.file_name().and_then(|n| n.to_str()).unwrap_or_default();
    match name.strip_suffix(".zst") {
        Some(plain) => {
            let packed = std::fs::read(src).unwrap_or_else(|e| panic!("{}: {e}", src.display()));
            let bytes =
                zstd::decode_all(&packed[..]).unwrap_or_else(|e| panic!("{}: {e}", src.display()));
            let out = dir.join(plain);
            std::fs::write(&out, bytes).unwrap_or_else(|e| panic!("{}: {e}", out.display()));
            out
        }
        None => src.to_path_buf(),
    }
}

/// The hand-held session of the fixtures (`hand.ulg`: 6000 samples at 100 Hz, a temperature ramp)
/// as samples to log again.
pub fn hand_session() -> Vec<LogSample> {
    let log = crate::session::logs::read_log(&log_fixture("hand.ulg"), &LogSource::default())
        .unwrap_or_else(|e| panic!("{e}"));
    samples_of(&log.recording)
}

/// A recording's samples as a logger would log them again (f32 values, its temperature or NaN).
pub fn samples_of(rec: &Recording) -> Vec<LogSample> {
    (0..rec.len())
        .map(|i| LogSample {
            t_s: rec.t_s[i],
            acc: rec.acc[i].map(|x| x as f32),
            gyro: rec.gyro_rad_s[i].map(|x| x as f32),
            temp_c: rec.temp_c.as_ref().map_or(f32::NAN, |t| t[i] as f32),
        })
        .collect()
}

/// A logger's CSV of `samples`: `t,acc_x,acc_y,acc_z,gyr_x,gyr_y,gyr_z,temp`, the time to the
/// microsecond, m/s² and rad/s ([`csv_source`] reads it).
pub fn write_csv(samples: &[LogSample]) -> Vec<u8> {
    let mut text = String::from("t,acc_x,acc_y,acc_z,gyr_x,gyr_y,gyr_z,temp\n");
    for s in samples {
        let [ax, ay, az] = s.acc;
        let [gx, gy, gz] = s.gyro;
        text.push_str(&format!(
            "{:.6},{ax},{ay},{az},{gx},{gy},{gz},{}\n",
            s.t_s, s.temp_c
        ));
    }
    text.into_bytes()
}

/// A logger's CSV of `samples` with its time in milliseconds and no temperature:
/// `t_ms,acc_x,acc_y,acc_z,gyr_x,gyr_y,gyr_z`, a time unit the reader tells from the rows.
pub fn write_csv_ms(samples: &[LogSample]) -> Vec<u8> {
    let mut text = String::from("t_ms,acc_x,acc_y,acc_z,gyr_x,gyr_y,gyr_z\n");
    for s in samples {
        let [ax, ay, az] = s.acc;
        let [gx, gy, gz] = s.gyro;
        text.push_str(&format!(
            "{:.3},{ax},{ay},{az},{gx},{gy},{gz}\n",
            s.t_s * 1e3
        ));
    }
    text.into_bytes()
}

/// A vehicle in flight at `t_s`: 1 g of vibration on each axis about gravity and 1 rad/s of
/// rotation, at 24 °C.
pub fn flying(t_s: f64, rng: &mut shared::rng::Rng) -> LogSample {
    let mut n = || rng.normal() as f32;
    LogSample {
        t_s,
        acc: [9.81 * n(), 9.81 * n(), -9.81 + 9.81 * n()],
        gyro: [n(), n(), n()],
        temp_c: 24.0,
    }
}

/// The fixtures' hand-held session ([`hand_session`]) between two stretches of flight
/// ([`flying`], seed 3) of `motion_s` seconds each at `rate_hz`, as one long log's samples; and
/// the number of the session's samples.
pub fn session_in_flight(motion_s: f64, rate_hz: f64) -> (Vec<LogSample>, usize) {
    let hand = hand_session();
    let mut rng = shared::rng::Rng::new(3, 0);
    let before = (motion_s * rate_hz) as usize;
    let mut samples: Vec<LogSample> = (0..before)
        .map(|k| flying(k as f64 / rate_hz, &mut rng))
        .collect();
    let start = motion_s + 1.0 / rate_hz - hand[0].t_s;
    samples.extend(hand.iter().map(|s| LogSample {
        t_s: s.t_s + start,
        ..*s
    }));
    let end = samples.last().map_or(0.0, |s| s.t_s);
    samples.extend((1..=before).map(|k| flying(end + k as f64 / rate_hz, &mut rng)));
    (samples, hand.len())
}

/// How [`write_csv`]'s files are read.
pub fn csv_source() -> LogSource {
    let mut options = ImportOptions::new(
        TimeSource::Column("t".into()),
        OutputUnit::MetresPerSecondSquared,
        GyroUnit::RadPerS,
        crate::testkit::SPELLING,
    );
    options.temp_column = Some("temp".into());
    LogSource {
        text: Some(options),
        ..LogSource::default()
    }
}

/// A long log's windows read from the survey's marks (each its own stretches of the file) are the
/// windows a pass over the whole file reads: samples, places in the file and what is said, compared
/// as their `Debug` text. Panics naming `case` and the window otherwise, or when `max_samples` does
/// not make the read window by window with marks.
pub fn assert_windows_from_marks(path: &Path, source: &LogSource, max_samples: usize, case: &str) {
    let read =
        || read_log_windows(path, source, max_samples).unwrap_or_else(|e| panic!("{case}: {e}"));
    let LogRead::Windows(marked) = read() else {
        panic!("{case}: read whole");
    };
    assert!(marked.marked(), "{case}: no marks");
    let LogRead::Windows(whole) = read() else {
        panic!("{case}: read whole");
    };
    let whole = whole.without_marks();
    for k in 0..marked.len() {
        let (a, b) = (marked.read(k), whole.read(k));
        assert_eq!(format!("{a:?}"), format!("{b:?}"), "{case}: window {k}");
    }
}

/// One sample as a logger writes it: time s, acc m/s², gyro rad/s, temperature °C.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct LogSample {
    /// Time stamp, s.
    pub t_s: f64,
    /// Accelerometer, m/s².
    pub acc: [f32; 3],
    /// Gyro, rad/s.
    pub gyro: [f32; 3],
    /// Temperature, °C.
    pub temp_c: f32,
}

/// Sample `k` of a unit at rest, z up, at `rate_hz` (the corpora's at 100 Hz): small deterministic
/// noise on every axis.
pub fn still_sample(k: usize, rate_hz: f64) -> LogSample {
    let e = 1e-3 * ((k * 7 % 11) as f32 - 5.0);
    LogSample {
        t_s: k as f64 / rate_hz,
        acc: [e, -e, 9.81 + e],
        gyro: [e, 0.01, -e],
        temp_c: 25.0 + e,
    }
}

/// A PX4 ULog of `samples` (1 s added to each stamp, as a vehicle's clock starts at boot): one
/// `sensor_accel` and one `sensor_gyro` message per sample (PX4's fields, multi_id 0), and a 20 ms
/// dropout message after sample `dropout`, if given.
pub fn write_ulog(samples: &[LogSample], dropout: Option<usize>) -> Vec<u8> {
    write_ulog_imus(
        &[UlogImu {
            samples,
            accel_id: 7,
            gyro_id: 7,
        }],
        &[],
        dropout,
    )
}

/// One IMU of a ULog: its samples and its sensors' device ids.
pub struct UlogImu<'a> {
    /// The samples.
    pub samples: &'a [LogSample],
    /// `sensor_accel.device_id`.
    pub accel_id: u32,
    /// `sensor_gyro.device_id`.
    pub gyro_id: u32,
}

/// A PX4 ULog parameter: `int32_t` (`Int`) or `float`.
#[derive(Clone, Copy, Debug)]
pub enum UlogParam {
    /// An `int32_t` parameter (ids are stored as their int32 bits).
    Int(i32),
    /// A `float` parameter.
    Float(f32),
}

/// [`write_ulog`] for several IMUs (IMU `i` is `multi_id` `i`, its messages interleaved sample by
/// sample) with the parameter messages `params` in the definitions section, as PX4's logger writes
/// its start-up parameters (`P`: key length, `"type name"`, value).
pub fn write_ulog_imus(
    imus: &[UlogImu<'_>],
    params: &[(&str, UlogParam)],
    dropout: Option<usize>,
) -> Vec<u8> {
    const FORMAT: &str = "uint64_t timestamp;uint64_t timestamp_sample;uint32_t device_id;\
        float x;float y;float z;float temperature;uint32_t error_count;uint8_t[3] clip_counter;\
        uint8_t samples;uint8_t[4] _padding0;";
    let mut out = ulog::MAGIC.to_vec();
    out.push(1);
    out.extend(0u64.to_le_bytes());
    let mut msg = |ty: u8, body: &[u8]| {
        out.extend((body.len() as u16).to_le_bytes());
        out.push(ty);
        out.extend_from_slice(body);
    };
    msg(b'B', &[0u8; 40]);
    for name in ["sensor_accel", "sensor_gyro"] {
        msg(b'F', format!("{name}:{FORMAT}").as_bytes());
    }
    for (name, value) in params {
        let (ty, bytes) = match value {
            UlogParam::Int(v) => ("int32_t", v.to_le_bytes()),
            UlogParam::Float(v) => ("float", v.to_le_bytes()),
        };
        let key = format!("{ty} {name}");
        let mut b = vec![key.len() as u8];
        b.extend(key.as_bytes());
        b.extend(bytes);
        msg(b'P', &b);
    }
    for (i, _) in imus.iter().enumerate() {
        for (k, name) in ["sensor_accel", "sensor_gyro"].iter().enumerate() {
            let mut b = vec![i as u8];
            b.extend(((2 * i + k) as u16).to_le_bytes());
            b.extend(name.as_bytes());
            msg(b'A', &b);
        }
    }
    let n = imus.iter().map(|m| m.samples.len()).max().unwrap_or(0);
    for k in 0..n {
        for (i, imu) in imus.iter().enumerate() {
            let Some(s) = imu.samples.get(k) else {
                continue;
            };
            let ids = [imu.accel_id, imu.gyro_id];
            for (j, v) in [s.acc, s.gyro].iter().enumerate() {
                let mut b = ((2 * i + j) as u16).to_le_bytes().to_vec();
                let us = (s.t_s * 1e6).round() as u64 + 1_000_000;
                b.extend((us + 100).to_le_bytes());
                b.extend(us.to_le_bytes());
                b.extend(ids[j].to_le_bytes());
                v.iter().for_each(|x| b.extend(x.to_le_bytes()));
                b.extend(s.temp_c.to_le_bytes());
                b.extend([0u8; 8]);
                msg(b'D', &b);
            }
        }
        if Some(k) == dropout {
            msg(b'O', &20u16.to_le_bytes());
        }
    }
    out
}

/// A DataFlash log of `samples`, one `IMU` message (instance 0) each, after the parameters of
/// ArduPilot's IMU correction at their defaults ([`ardupilot_default_params`]): the samples are
/// the sensor's own.
pub fn write_dataflash(samples: &[LogSample]) -> Vec<u8> {
    write_dataflash_imus(&[samples], &ardupilot_default_params(1))
}

/// The parameters ArduPilot corrects `instances` IMUs with (`_rotate_and_correct_accel`), each at
/// its default (offsets 0, scales 1, no board rotation), and the IMUs' ids.
pub fn ardupilot_default_params(instances: u8) -> Vec<(String, f32)> {
    let mut v = vec![("AHRS_ORIENTATION".to_string(), 0.0)];
    for i in 0..instances {
        let sfx = if i == 0 {
            String::new()
        } else {
            (i + 1).to_string()
        };
        v.push((format!("INS_ACC{sfx}_ID"), 2_753_028.0 + 8.0 * f32::from(i)));
        v.push((format!("INS_GYR{sfx}_ID"), 2_752_772.0 + 8.0 * f32::from(i)));
        for axis in ["X", "Y", "Z"] {
            v.push((format!("INS_ACC{sfx}OFFS_{axis}"), 0.0));
            v.push((format!("INS_ACC{sfx}SCAL_{axis}"), 1.0));
            v.push((format!("INS_GYR{sfx}OFFS_{axis}"), 0.0));
        }
    }
    v
}

/// A DataFlash log: `FMT`s, the `PARM` messages `params` (format `QNf`, as ArduPilot's
/// `Write_Parameter`), then IMU `i`'s samples as `IMU` messages with `I = i`, interleaved sample by
/// sample.
pub fn write_dataflash_imus(imus: &[&[LogSample]], params: &[(String, f32)]) -> Vec<u8> {
    let fmt = |ty: u8, len: u8, name: &str, format: &str, cols: &str| {
        let mut b = vec![0xA3, 0x95, 0x80, ty, len];
        for (s, n) in [(name, 4), (format, 16), (cols, 64)] {
            let mut v = s.as_bytes().to_vec();
            v.resize(n, 0);
            b.extend(v);
        }
        b
    };
    let mut out = fmt(0x80, 89, "FMT", "BBnNZ", "Type,Length,Name,Format,Columns");
    let cols = "TimeUS,I,GyrX,GyrY,GyrZ,AccX,AccY,AccZ,EG,EA,T,GH,AH,GHz,AHz";
    out.extend(fmt(0xA5, 54, "IMU", "QBffffffIIfBBHH", cols));
    out.extend(fmt(0x81, 31, "PARM", "QNf", "TimeUS,Name,Value"));
    for (name, value) in params {
        out.extend([0xA3, 0x95, 0x81]);
        out.extend(0u64.to_le_bytes());
        let mut n = name.as_bytes().to_vec();
        n.resize(16, 0);
        out.extend(n);
        out.extend(value.to_le_bytes());
    }
    let n = imus.iter().map(|m| m.len()).max().unwrap_or(0);
    for k in 0..n {
        for (i, imu) in imus.iter().enumerate() {
            let Some(s) = imu.get(k) else {
                continue;
            };
            out.extend([0xA3, 0x95, 0xA5]);
            out.extend(((s.t_s * 1e6).round() as u64).to_le_bytes());
            out.push(i as u8);
            s.gyro
                .iter()
                .chain(&s.acc)
                .for_each(|x| out.extend(x.to_le_bytes()));
            out.extend([0u8; 8]);
            out.extend(s.temp_c.to_le_bytes());
            out.extend([1, 1, 100, 0, 100, 0]);
        }
    }
    out
}

/// An Imu message in little-endian CDR (the layout `session::logs::mcap` documents).
fn imu_cdr(t: f64, a: [f32; 3], g: [f32; 3]) -> Vec<u8> {
    let mut b = vec![0, 1, 0, 0];
    b.extend((t.floor() as i32).to_le_bytes());
    b.extend((((t - t.floor()) * 1e9).round() as u32).to_le_bytes());
    b.extend(4u32.to_le_bytes());
    b.extend(b"imu\0");
    let mut doubles = vec![0.0, 0.0, 0.0, 1.0];
    doubles.extend([0.0; 9]);
    doubles.extend(g.map(f64::from));
    doubles.extend([0.0; 9]);
    doubles.extend(a.map(f64::from));
    doubles.extend([0.0; 9]);
    doubles.iter().for_each(|x| b.extend(x.to_le_bytes()));
    b
}

/// A ROS 2 bag of `samples` on the Imu topic `/imu`, written by the mcap crate: `header.stamp`
/// the sample's time, the log time the recorder's clock, `recorder_offset_s` later (a bag recorded
/// in simulated time has stamps from 0 and a wall-clock log time).
pub fn write_mcap(
    samples: &[LogSample],
    compression: Option<::mcap::Compression>,
    recorder_offset_s: f64,
) -> Vec<u8> {
    write_mcap_with(samples, compression, recorder_offset_s, None)
}

/// [`write_mcap`], and with `junk_at` a second topic `/junk` whose schema is 1 MiB of bytes that
/// are no message definition, with one message of garbage after sample `junk_at` (an oversized,
/// malformed format record beside the IMU's).
pub fn write_mcap_with(
    samples: &[LogSample],
    compression: Option<::mcap::Compression>,
    recorder_offset_s: f64,
    junk_at: Option<usize>,
) -> Vec<u8> {
    write_mcap_stamped(samples, compression, recorder_offset_s, junk_at, |t| t)
}

/// [`write_mcap`] of a driver that stamps nothing: every `header.stamp` 0, the log time the
/// sample's time (the recorder's clock).
pub fn write_mcap_unstamped(samples: &[LogSample]) -> Vec<u8> {
    write_mcap_stamped(samples, None, 0.0, None, |_| 0.0)
}

/// [`write_mcap_with`], each message's `header.stamp` `stamp` of its sample's time.
fn write_mcap_stamped(
    samples: &[LogSample],
    compression: Option<::mcap::Compression>,
    recorder_offset_s: f64,
    junk_at: Option<usize>,
    stamp: fn(f64) -> f64,
) -> Vec<u8> {
    let write = || -> ::mcap::McapResult<Vec<u8>> {
        let mut cursor = std::io::Cursor::new(Vec::new());
        let options = ::mcap::WriteOptions::new().compression(compression);
        let mut w = options.create(&mut cursor)?;
        let schema = w.add_schema("sensor_msgs/msg/Imu", "ros2msg", b"")?;
        let channel = w.add_channel(schema, "/imu", "cdr", &Default::default())?;
        let junk_schema: Vec<u8> = (0..1u32 << 20).map(|i| (i * 131 % 251) as u8).collect();
        let junk = match junk_at {
            Some(_) => {
                let s = w.add_schema("junk/msg/Junk", "ros2msg", &junk_schema)?;
                Some(w.add_channel(s, "/junk", "cdr", &Default::default())?)
            }
            None => None,
        };
        for (k, s) in samples.iter().enumerate() {
            let log_time = ((s.t_s + recorder_offset_s).max(0.0) * 1e9) as u64;
            let header = ::mcap::records::MessageHeader {
                channel_id: channel,
                sequence: k as u32,
                log_time,
                publish_time: log_time,
            };
            w.write_to_known_channel(&header, &imu_cdr(stamp(s.t_s), s.acc, s.gyro))?;
            if let (Some(channel_id), true) = (junk, junk_at == Some(k)) {
                let header = ::mcap::records::MessageHeader {
                    channel_id,
                    sequence: 0,
                    log_time,
                    publish_time: log_time,
                };
                w.write_to_known_channel(&header, &junk_schema[..333])?;
            }
        }
        w.finish()?;
        drop(w);
        Ok(cursor.into_inner())
    };
    write().unwrap_or_default()
}

/// The spelling of the tests below the edges: each option by its neutral name, `<AccUnit>`, with
/// the command line's syntax. The flags and the keywords are the edges' (`host`, the Python
/// package), whose tests pin the real words; a lower crate's test checks that a message names the
/// right option, not how an edge spells it.
pub const SPELLING: Spelling = Spelling::new(neutral_name, Syntax::Flags);

/// [`SPELLING`]'s names with a keyword call's syntax: `<AccUnit>="g"`, `<NoGyro>=True`.
pub const KEYWORD_SPELLING: Spelling = Spelling::new(neutral_name, Syntax::Keywords);

/// The option's neutral name: its variant in angle brackets.
fn neutral_name(option: UserOption) -> &'static str {
    static NAMES: std::sync::OnceLock<Vec<String>> = std::sync::OnceLock::new();
    let names = NAMES.get_or_init(|| UserOption::ALL.iter().map(|o| format!("<{o:?}>")).collect());
    let i = UserOption::ALL.iter().position(|&o| o == option);
    &names[i.expect("UserOption::ALL holds every option")]
}
