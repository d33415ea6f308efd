//! Writes one PX4 ULog, one ArduPilot DataFlash log, one ROS 2 MCAP bag and one logger's CSV of
//! about `MB` megabytes each (default 500) into `DIR`: a unit at rest sampled at 1 kHz, the binary
//! logs written by the fuzz corpora's writers. They are the inputs of the peak-memory figure of
//! `host segment` on a large log of each format (the CSV with `--time-column t --acc-unit m/s2
//! --gyro-unit rad/s`):
//!
//! ```text
//! cargo run -p host --features fuzz --example log_memory -- DIR [MB]
//! /usr/bin/time -v target/debug/host -q segment --input DIR/big.ulg --out DIR/s-ulg
//! ```
//!
//! ("Maximum resident set size"). The files are not kept in the repository.

use recording::testkit::{still_sample, write_dataflash, write_mcap, write_ulog, LogSample};
use std::path::PathBuf;

/// Sample `k` at 1 kHz.
fn still(k: usize) -> LogSample {
    still_sample(k, 1000.0)
}

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let mut args = std::env::args().skip(1);
    let dir = PathBuf::from(args.next().ok_or("usage: log_memory DIR [MB]")?);
    let mb: f64 = args.next().map_or(Ok(500.0), |s| s.parse())?;
    std::fs::create_dir_all(&dir)?;
    let probe: Vec<LogSample> = (0..10_000).map(still).collect();
    type Writer = fn(&[LogSample]) -> Vec<u8>;
    let writers: [(&str, Writer); 3] = [
        ("big.ulg", |s| write_ulog(s, None)),
        ("big.bin", write_dataflash),
        ("big.mcap", |s| write_mcap(s, None, 0.0)),
    ];
    for (name, write) in writers {
        let per_sample = write(&probe).len() as f64 / probe.len() as f64;
        let n = (mb * 1e6 / per_sample) as usize;
        let samples: Vec<LogSample> = (0..n).map(still).collect();
        let bytes = write(&samples);
        std::fs::write(dir.join(name), &bytes)?;
        println!(
            "{name}: {n} samples, {:.0} MB ({per_sample:.1} bytes per sample)",
            bytes.len() as f64 / 1e6
        );
    }
    write_csv(&dir.join("big.csv"), mb)
}

/// The same unit at rest as a logger's CSV (time in s), written as it goes.
fn write_csv(path: &std::path::Path, mb: f64) -> Result<(), Box<dyn std::error::Error>> {
    use std::io::Write;
    let mut w = std::io::BufWriter::new(std::fs::File::create(path)?);
    let header = "t,acc_x,acc_y,acc_z,gyr_x,gyr_y,gyr_z\n";
    w.write_all(header.as_bytes())?;
    let (mut bytes, mut k) = (header.len(), 0);
    while (bytes as f64) < mb * 1e6 {
        let s = still(k);
        let [ax, ay, az] = s.acc;
        let [gx, gy, gz] = s.gyro;
        let line = format!("{:.3},{ax},{ay},{az},{gx},{gy},{gz}\n", s.t_s);
        w.write_all(line.as_bytes())?;
        bytes += line.len();
        k += 1;
    }
    w.flush()?;
    println!("big.csv: {k} rows, {:.0} MB", bytes as f64 / 1e6);
    Ok(())
}
