//! The binary log readers' fuzz targets and their corpora: small valid logs of each format, built
//! by `recording::testkit` (150 samples at 100 Hz; the MCAP ones by the `mcap` crate's writer, once uncompressed so
//! that mutations reach the records, once in lz4 and once in zstd chunks).

use recording::session::import::{Recording, MAX_ROWS};
use recording::session::logs::{dataflash, mcap, ulog};
use recording::testkit::{still_sample, write_dataflash, write_mcap, write_ulog, LogSample};

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
pub(crate) fn ulog(data: &[u8]) {
    for instance in [0, 1] {
        if let Ok((rec, _)) = ulog::read(data, instance) {
            check(&rec);
        }
    }
}

/// An ArduPilot DataFlash log: instance 0 and 1.
pub(crate) fn dataflash(data: &[u8]) {
    for instance in [0, 1] {
        if let Ok((rec, _)) = dataflash::read(data, instance) {
            check(&rec);
        }
    }
}

/// An MCAP file: the only Imu topic, and a topic by name.
pub(crate) fn mcap(data: &[u8]) {
    for topic in [None, Some("/imu")] {
        if let Ok((rec, _)) = mcap::read(data, topic) {
            check(&rec);
        }
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

/// A DataFlash log: `FMT` of `FMT`, `FMT` of `IMU` (ArduPilot 4.x's fields) and the samples.
pub(crate) fn dataflash_corpus() -> Vec<u8> {
    write_dataflash(&corpus_samples())
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
