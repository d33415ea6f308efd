//! A long log's windows read from the survey's marks (each its own stretches of the file) against
//! the same windows read by a pass over the whole file, on logs damaged where a reader counts or
//! says something of the whole file: values that are not finite, stamps far from their place,
//! a logger's dropout, bytes that start no message, a time that is not a number, an overlong line,
//! a file cut short, a bag without stamps, samples re-timed at a given rate.

use recording::session::import::MAX_LINE_BYTES;
use recording::session::logs::LogSource;
use recording::testkit::{
    assert_windows_from_marks, csv_source, hand_session, write_csv, write_dataflash, write_mcap,
    write_mcap_unstamped, write_ulog, LogSample,
};
use shared::rng::Rng;
use std::path::Path;

/// Values that are not finite in three samples, and three stamps moved far: one beyond the log's
/// end, one well before its start, one into another window.
fn damage(samples: &mut [LogSample], rng: &mut Rng) {
    let n = samples.len();
    let span_s = samples[n - 1].t_s - samples[0].t_s;
    let mut pick = || 1 + (rng.uniform() * (n - 2) as f64) as usize;
    for k in 0..3 {
        let i = pick();
        match k {
            0 => samples[i].acc[1] = f32::NAN,
            1 => samples[i].gyro[2] = f32::INFINITY,
            _ => samples[i].acc = [f32::NAN; 3],
        }
    }
    for offset_s in [10.0 * span_s, -0.5 * span_s, 0.37 * span_s] {
        let i = pick();
        samples[i].t_s = (samples[i].t_s + offset_s).max(0.0);
    }
}

/// A text file of `samples` at `path` with a time that is not a number, an overlong line and a
/// last line cut short.
fn write_damaged_csv(path: &Path, samples: &[LogSample], rng: &mut Rng) {
    let text = String::from_utf8(write_csv(samples)).unwrap();
    let mut lines: Vec<String> = text.lines().map(str::to_string).collect();
    let n = lines.len();
    let mut pick = || 2 + (rng.uniform() * (n - 4) as f64) as usize;
    let i = pick();
    let rest = lines[i].split_once(',').unwrap().1.to_string();
    lines[i] = format!("nan,{rest}");
    lines.insert(pick(), "x".repeat(MAX_LINE_BYTES + 10));
    let mut out = lines.join("\n");
    out.truncate(out.len() - 3);
    std::fs::write(path, out).unwrap();
}

/// `bytes` with a run of bytes that start no message put in at a random place.
fn with_garbage(mut bytes: Vec<u8>, rng: &mut Rng) -> Vec<u8> {
    let at = bytes.len() / 4 + (rng.uniform() * (bytes.len() / 2) as f64) as usize;
    bytes.splice(at..at, [0x11, 0xA3, 0x00, 0x42, 0x95, 0x07, 0x00]);
    bytes
}

#[test]
fn windows_read_from_the_surveys_marks_are_the_windows_a_whole_pass_reads() {
    let tmp = tempfile::tempdir().unwrap();
    let clean = hand_session();
    let n = clean.len();
    for seed in 0..4 {
        let mut rng = Rng::new(seed, 57);
        let mut samples = clean.clone();
        damage(&mut samples, &mut rng);
        let dropout = Some(n / 3 + seed as usize * 97);
        let retimed = LogSource {
            rate_hz: Some(250.0),
            ..LogSource::default()
        };
        let cases: [(&str, LogSource); 6] = [
            ("ULog", LogSource::default()),
            ("DataFlash re-timed", retimed),
            ("DataFlash", LogSource::default()),
            ("MCAP", LogSource::default()),
            ("MCAP without stamps", LogSource::default()),
            ("CSV", csv_source()),
        ];
        for (name, source) in cases {
            let path = tmp.path().join(format!("{name}-{seed}"));
            match name {
                "ULog" => std::fs::write(&path, write_ulog(&samples, dropout)),
                "DataFlash" | "DataFlash re-timed" => {
                    let bytes = with_garbage(write_dataflash(&samples), &mut rng);
                    std::fs::write(&path, bytes)
                }
                "MCAP" => {
                    let bytes = write_mcap(&samples, Some(::mcap::Compression::Zstd), 0.0);
                    std::fs::write(&path, bytes)
                }
                "MCAP without stamps" => std::fs::write(&path, write_mcap_unstamped(&clean)),
                _ => {
                    write_damaged_csv(&path, &samples, &mut rng);
                    Ok(())
                }
            }
            .unwrap();
            for max_samples in [2 * (n / 9), n / 2 + 37, n - 100] {
                let case = format!("seed {seed}, {name}, budget {max_samples}");
                assert_windows_from_marks(&path, &source, max_samples, &case);
            }
        }
    }
}
