//! `host apply` on a raw log in counts read with an offset (`--acc-offset`): the calibration made
//! from the same log holds the offset in its biases and records it, so the log's own counts are
//! compensated once, whether the offset is given again or left out, and another offset is refused
//! with both figures. Truth: the simulator's up of each hold, where the specific force is 1 g.

use crate::cli::{apply, calibrate, segment, Cli, CliError, Command};
use clap::Parser;
use estimator::sim::handheld::{
    logger_unit, simulate_hand, write_logger_csv, HandSpec, LoggerLayout,
};
use shared::OutputUnit;
use std::path::Path;

fn parse(line: &str) -> Command {
    Cli::try_parse_from(line.split_whitespace())
        .unwrap()
        .command
}

/// `host apply` on `dir/raw.csv` with `extra` flags, into `dir/{name}`; the CSV's text.
fn apply_raw(dir: &Path, name: &str, extra: &str) -> Result<String, CliError> {
    let d = dir.display();
    let line = format!(
        "host apply --calibration {d}/cal/calibration.toml --input {d}/raw.csv --out {d}/{name} \
         --time-column t --acc-unit LSB --gyro-unit deg/s {extra}"
    );
    let Command::Apply(a) = parse(&line) else {
        panic!("{line}")
    };
    apply::run(&a, true)?;
    Ok(std::fs::read_to_string(dir.join(name)).unwrap())
}

/// The specific force of each row (g), from `apply`'s CSV.
fn forces(csv: &str) -> Vec<[f64; 3]> {
    csv.lines()
        .skip(1)
        .map(|l| {
            let v: Vec<f64> = l
                .split(',')
                .skip(2)
                .take(3)
                .map(|x| x.parse().unwrap())
                .collect();
            [v[0], v[1], v[2]]
        })
        .collect()
}

/// Segments `dir/raw.csv` with `flags` and calibrates it into `dir/cal`.
fn calibrate_raw(dir: &Path, flags: &str) {
    let d = dir.display();
    let Command::Segment(s) = parse(&format!(
        "host segment --input {d}/raw.csv --out {d}/s --time-column t --acc-unit LSB \
         --gyro-unit deg/s {flags}"
    )) else {
        panic!()
    };
    segment::segment(&s).unwrap();
    let Command::Calibrate(c) = parse(&format!("host calibrate --input {d}/s --out-dir {d}/cal"))
    else {
        panic!()
    };
    calibrate::calibrate(&c, true).unwrap();
}

/// Truth: the same log without an offset (signed counts), calibrated and applied the same way. An
/// offset added to every count and declared changes nothing but the biases, so every compensated
/// row is the same (a second subtraction of 80 counts is 19.5 mg on every axis at 4096 per g).
#[test]
fn a_raw_log_is_compensated_once_with_the_calibrations_offset() {
    let truth = logger_unit(OutputUnit::Lsb);
    let sim = simulate_hand(
        &truth,
        &HandSpec {
            acc_step: 1.0,
            ..HandSpec::standard(17)
        },
    );
    let signed = tempfile::tempdir().unwrap();
    write_logger_csv(
        &signed.path().join("raw.csv"),
        &sim.rows,
        &LoggerLayout::default(),
    )
    .unwrap();
    calibrate_raw(signed.path(), "");
    let want = forces(&apply_raw(signed.path(), "a.csv", "").unwrap());
    for offset in [80.0, 32768.0] {
        let tmp = tempfile::tempdir().unwrap();
        let dir = tmp.path();
        let layout = LoggerLayout {
            acc_offset: offset,
            ..LoggerLayout::default()
        };
        write_logger_csv(&dir.join("raw.csv"), &sim.rows, &layout).unwrap();
        calibrate_raw(dir, &format!("--acc-offset {offset}"));
        let file = estimator::unit_file::UnitFile::load(&dir.join("cal/calibration.toml")).unwrap();
        assert_eq!(file.statics.raw_offset_lsb, Some([offset; 3]));

        // The same offset: compensated once, as the signed log is.
        let given = apply_raw(dir, "given.csv", &format!("--acc-offset {offset}")).unwrap();
        let got = forces(&given);
        assert_eq!(got.len(), want.len());
        let worst = got
            .iter()
            .zip(&want)
            .flat_map(|(a, b)| (0..3).map(move |j| (a[j] - b[j]).abs()))
            .fold(0.0, f64::max);
        println!(
            "offset {offset}: worst difference from the signed log {:.4} mg",
            worst * 1e3
        );
        assert!(worst < 1e-4, "offset {offset}: {} mg", worst * 1e3);
        // Left out: the calibration's offset reads the log, the same output.
        let left_out = apply_raw(dir, "left_out.csv", "").unwrap();
        assert_eq!(left_out, given, "offset {offset}");
        // Another offset contradicts the calibration: refused, both figures named, a usage error.
        let other = offset + 100.0;
        let e = apply_raw(dir, "other.csv", &format!("--acc-offset {other}")).unwrap_err();
        let m = e.to_string();
        assert!(
            m.contains(&format!("--acc-offset {other}")) && m.contains(&format!("{offset} counts")),
            "{m}"
        );
        assert_eq!(e.exit_code(), crate::cli::error::EXIT_USAGE, "{m}");
        assert!(!dir.join("other.csv").exists());
    }
}
