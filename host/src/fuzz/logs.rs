//! The binary log readers' fuzz targets and their corpora: small valid logs of each format, built
//! here (150 samples at 100 Hz; the MCAP ones by the `mcap` crate's writer, once uncompressed so
//! that mutations reach the records, once in lz4 and once in zstd chunks).

use recording::session::import::{Recording, MAX_ROWS};
use recording::session::logs::{dataflash, mcap, ulog};

/// A recording a reader accepts: as many times, accelerometer, gyro (and temperature) values as
/// rows, at most `MAX_ROWS` of them, strictly increasing finite times, finite values, a positive
/// rate where there are two rows or more.
fn check(rec: &Recording) {
    let n = rec.len();
    assert!(n <= MAX_ROWS, "{n} rows");
    assert!(rec.acc.len() == n && rec.gyro_rad_s.len() == n);
    assert!(rec.temp_c.as_ref().is_none_or(|t| t.len() == n));
    assert!(
        rec.t_s.windows(2).all(|w| w[1] > w[0]),
        "time not increasing"
    );
    let values = rec.acc.iter().chain(&rec.gyro_rad_s).flatten();
    assert!(values.chain(&rec.t_s).all(|v| v.is_finite()));
    assert!(n < 2 || rec.rate_hz > 0.0, "rate {}", rec.rate_hz);
}

/// A PX4 ULog: instance 0 and 1.
pub fn ulog(data: &[u8]) {
    for instance in [0, 1] {
        if let Ok((rec, _)) = ulog::read(data, instance) {
            check(&rec);
        }
    }
}

/// An ArduPilot DataFlash log: instance 0 and 1.
pub fn dataflash(data: &[u8]) {
    for instance in [0, 1] {
        if let Ok((rec, _)) = dataflash::read(data, instance) {
            check(&rec);
        }
    }
}

/// An MCAP file: the only Imu topic, and a topic by name.
pub fn mcap(data: &[u8]) {
    for topic in [None, Some("/imu")] {
        if let Ok((rec, _)) = mcap::read(data, topic) {
            check(&rec);
        }
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

const SAMPLES: usize = 150;

fn corpus_samples() -> Vec<LogSample> {
    (0..SAMPLES).map(|k| still_sample(k, 100.0)).collect()
}

/// A ULog with `sensor_accel` and `sensor_gyro` (PX4's fields) and a dropout.
pub(crate) fn ulog_corpus() -> Vec<u8> {
    write_ulog(&corpus_samples(), Some(75))
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
pub(crate) struct UlogImu<'a> {
    /// The samples.
    pub samples: &'a [LogSample],
    /// `sensor_accel.device_id`.
    pub accel_id: u32,
    /// `sensor_gyro.device_id`.
    pub gyro_id: u32,
}

/// A PX4 ULog parameter: `int32_t` (`Int`) or `float`.
#[derive(Clone, Copy, Debug)]
pub(crate) enum UlogParam {
    /// An `int32_t` parameter (ids are stored as their int32 bits).
    Int(i32),
    /// A `float` parameter.
    Float(f32),
}

/// [`write_ulog`] for several IMUs (IMU `i` is `multi_id` `i`, its messages interleaved sample by
/// sample) with the parameter messages `params` in the definitions section, as PX4's logger writes
/// its start-up parameters (`P`: key length, `"type name"`, value).
pub(crate) fn write_ulog_imus(
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

/// A DataFlash log: `FMT` of `FMT`, `FMT` of `IMU` (ArduPilot 4.x's fields) and the samples.
pub(crate) fn dataflash_corpus() -> Vec<u8> {
    write_dataflash(&corpus_samples())
}

/// A DataFlash log of `samples`, one `IMU` message (instance 0) each, after the parameters of
/// ArduPilot's IMU correction at their defaults ([`ardupilot_default_params`]): the samples are
/// the sensor's own.
pub fn write_dataflash(samples: &[LogSample]) -> Vec<u8> {
    write_dataflash_imus(&[samples], &ardupilot_default_params(1))
}

/// The parameters ArduPilot corrects `instances` IMUs with (`_rotate_and_correct_accel`), each at
/// its default (offsets 0, scales 1, no board rotation), and the IMUs' ids.
pub(crate) fn ardupilot_default_params(instances: u8) -> Vec<(String, f32)> {
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
pub(crate) fn write_dataflash_imus(imus: &[&[LogSample]], params: &[(String, f32)]) -> Vec<u8> {
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

/// An Imu message in little-endian CDR (the layout [`mcap::decode_imu`] documents).
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

/// A ROS 2 bag with one Imu topic `/imu`, written by the mcap crate.
pub(crate) fn mcap_corpus(compression: Option<::mcap::Compression>) -> Vec<u8> {
    let samples: Vec<LogSample> = corpus_samples()
        .into_iter()
        .map(|s| LogSample {
            t_s: s.t_s + 100.0,
            ..s
        })
        .collect();
    write_mcap(&samples, compression, 0.0)
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
pub(crate) fn write_mcap_with(
    samples: &[LogSample],
    compression: Option<::mcap::Compression>,
    recorder_offset_s: f64,
    junk_at: Option<usize>,
) -> Vec<u8> {
    write_mcap_stamped(samples, compression, recorder_offset_s, junk_at, |t| t)
}

/// [`write_mcap`] of a driver that stamps nothing: every `header.stamp` 0, the log time the
/// sample's time (the recorder's clock).
pub(crate) fn write_mcap_unstamped(samples: &[LogSample]) -> Vec<u8> {
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

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_log_corpora_read_whole() {
        let (rec, w) = ulog::read(ulog_corpus().as_slice(), 0).unwrap();
        assert_eq!(rec.len(), SAMPLES);
        assert!(
            w.iter()
                .any(|w| w.to_string().contains("dropped data 1 time(s), 20 ms")),
            "{w:?}"
        );
        assert_eq!(rec.temp_c.as_ref().map(Vec::len), Some(SAMPLES));
        let (rec, _) = dataflash::read(dataflash_corpus().as_slice(), 0).unwrap();
        assert_eq!(rec.len(), SAMPLES);
        assert_eq!(rec.acc[3], still_sample(3, 100.0).acc.map(f64::from));
        for c in [
            None,
            Some(::mcap::Compression::Lz4),
            Some(::mcap::Compression::Zstd),
        ] {
            let (rec, _) = mcap::read(mcap_corpus(c).as_slice(), None).unwrap();
            assert_eq!(rec.len(), SAMPLES, "{c:?}");
            assert_eq!(
                rec.gyro_rad_s[3],
                still_sample(3, 100.0).gyro.map(f64::from)
            );
            assert!((rec.t_s[3] - 100.03).abs() < 1e-6, "{}", rec.t_s[3]);
        }
    }
}
