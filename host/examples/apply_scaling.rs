//! How `apply`'s time grows with a long log's size: writes a PX4 ULog, an ArduPilot DataFlash log,
//! a ROS 2 MCAP bag and a logger's CSV of `N` and of `2N` samples each (default 1 000 000; a unit at
//! rest at 1 kHz, the fuzz corpora's writers) into a temporary directory, applies the fixture's
//! calibration to each as `host apply` does (window by window beyond 250 000 samples per stream,
//! the rows written to nowhere), and prints each time and the ratio of 2N's to N's. A reader whose
//! windows each re-read the file from its start takes about 4× for 2N; one that seeks to each
//! window, about 2×.
//!
//! ```text
//! cargo run --release -p host --features fuzz --example apply_scaling -- [N]
//! ```

use estimator::unit_file::UnitFile;
use outputs::apply::{apply_log_within, Setting, APPLY_MAX_SAMPLES};
use recording::session::import::{GyroUnit, ImportOptions, TimeSource};
use recording::session::logs::LogSource;
use recording::testkit::{still_sample, write_dataflash, write_mcap, write_ulog, LogSample};
use shared::compensator::LeverMode;
use shared::OutputUnit;
use std::path::{Path, PathBuf};
use std::time::Instant;

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let n: usize = std::env::args()
        .nth(1)
        .map_or(Ok(1_000_000), |s| s.parse())?;
    let truth = recording::testkit::log_fixture("hand.truth.toml");
    let cal = UnitFile::load(&truth)?.to_calibration()?;
    let dir = tempfile::tempdir()?;
    let setting = Setting {
        mode: LeverMode::RateAndAcceleration,
        assume_temp_c: None,
    };
    let binary = LogSource {
        text: None,
        instance: None,
        topic: None,
        spelling: Default::default(),
        rate_hz: None,
    };
    let csv = LogSource {
        text: Some(ImportOptions::new(
            TimeSource::Column("t".into()),
            OutputUnit::MetresPerSecondSquared,
            GyroUnit::RadPerS,
            recording::testkit::SPELLING,
        )),
        ..binary.clone()
    };
    type Writer = fn(&[LogSample], &Path) -> std::io::Result<()>;
    let formats: [(&str, Writer, &LogSource); 4] = [
        (
            "ULog",
            |s, p| std::fs::write(p, write_ulog(s, None)),
            &binary,
        ),
        (
            "DataFlash",
            |s, p| std::fs::write(p, write_dataflash(s)),
            &binary,
        ),
        (
            "MCAP",
            |s, p| std::fs::write(p, write_mcap(s, None, 0.0)),
            &binary,
        ),
        ("CSV", write_csv, &csv),
    ];
    println!("apply of N = {n} and 2N samples (budget {APPLY_MAX_SAMPLES} per stream at once)");
    let mut worst: f64 = 0.0;
    for (name, write, source) in formats {
        let mut seconds = [0.0; 2];
        for (k, size) in [n, 2 * n].into_iter().enumerate() {
            let samples: Vec<LogSample> = (0..size).map(|i| still_sample(i, 1000.0)).collect();
            let path: PathBuf = dir.path().join(format!("{name}-{size}"));
            write(&samples, &path)?;
            drop(samples);
            let start = Instant::now();
            let summary = apply_log_within(
                &path,
                source,
                &cal,
                &setting,
                APPLY_MAX_SAMPLES,
                &mut std::io::sink(),
            )?;
            seconds[k] = start.elapsed().as_secs_f64();
            assert_eq!(summary.rows, size as u64, "{name}: every sample is written");
            std::fs::remove_file(&path)?;
        }
        let ratio = seconds[1] / seconds[0];
        worst = worst.max(ratio);
        println!(
            "{name:>9}: N {:.2} s, 2N {:.2} s, ratio {ratio:.2}",
            seconds[0], seconds[1]
        );
    }
    println!("largest ratio {worst:.2} (linear: 2; each window re-reading the file: 4)");
    Ok(())
}

/// The samples as a logger's CSV, time in s.
fn write_csv(samples: &[LogSample], path: &Path) -> std::io::Result<()> {
    use std::io::Write;
    let mut w = std::io::BufWriter::new(std::fs::File::create(path)?);
    writeln!(w, "t,acc_x,acc_y,acc_z,gyr_x,gyr_y,gyr_z")?;
    for s in samples {
        let [ax, ay, az] = s.acc;
        let [gx, gy, gz] = s.gyro;
        writeln!(w, "{:.3},{ax},{ay},{az},{gx},{gy},{gz}", s.t_s)?;
    }
    w.flush()
}
