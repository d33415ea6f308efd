//! A gyro whose nominal scale is off, as a real toolkit's example converts it (24 % low): the turns
//! fit a gyro that reads 0.763× the true rates on every axis. That is a calibration result with a
//! warning naming every cause consistent with it (the nominal scale, or the time base, each with the
//! figure it implies, in the input's own terms), never a refusal blaming one guessed cause. A 2×
//! error (an LSB per °/s for another full-scale range, a rate given twice too high) follows the same
//! rule as 1.5×.

use super::segment::segment;
use super::{Cli, Command};
use clap::Parser;
use estimator::estimate::handheld_gyro::HandGyroFit;
use estimator::sim::handheld::{
    logger_unit, simulate_hand, write_logger_csv, HandSpec, LoggerLayout,
};
use recording::testkit::{write_mcap, LogSample};
use shared::OutputUnit;
use std::path::Path;

fn segment_line(line: &str) -> (HandGyroFit, Vec<String>) {
    let Command::Segment(a) = Cli::try_parse_from(line.split_whitespace())
        .unwrap()
        .command
    else {
        panic!("{line}")
    };
    let out = segment(&a).unwrap_or_else(|e| panic!("{line}: {e}"));
    let warnings = out
        .recording
        .reader_warnings(recording::session::import::Places::InFile);
    let fit = out.gyro.unwrap_or_else(|e| panic!("{line}: gyro {e}"));
    // The session's warnings are not kept in the outcome: rebuild the note from the fit.
    let note = app::handheld::gyro::common_scale_note(&fit, &out.recording, super::spelling::FLAGS);
    let warnings = warnings.iter().map(ToString::to_string);
    (fit, warnings.chain(note).collect())
}

type Rows = Vec<(f64, [f64; 3], [f64; 3])>;

/// The rows as a logger CSV (m/s², the gyro in rad/s or, with `lsb_per_dps`, in counts), each gyro
/// value first multiplied by `k`.
fn write_csv(path: &Path, rows: &Rows, k: f64, lsb_per_dps: Option<f64>) {
    let scaled: Rows = rows
        .iter()
        .map(|&(t, a, g)| (t, a, g.map(|v| v * k)))
        .collect();
    let layout = LoggerLayout {
        gyro_deg_s: false,
        gyro_lsb_per_dps: lsb_per_dps,
        ..LoggerLayout::default()
    };
    write_logger_csv(path, &scaled, &layout).unwrap();
}

/// `fit`'s `G` and `b` divided by `k` against the true-scale fit `reference`: the same gyro to
/// float rounding (the turns are the same turns, read `k`× larger).
fn same_gyro(fit: &HandGyroFit, reference: &HandGyroFit, k: f64, case: &str) {
    for i in 0..3 {
        for j in 0..3 {
            let (a, b) = (fit.matrix[i][j] / k, reference.matrix[i][j]);
            assert!((a - b).abs() < 2e-4, "{case}: G[{i}][{j}] {a} against {b}");
        }
        let (a, b) = (fit.bias_rad_s[i] / k, reference.bias_rad_s[i]);
        assert!((a - b).abs() < 2e-5, "{case}: b[{i}] {a} against {b}");
    }
}

#[test]
fn a_nominal_gyro_scale_24_percent_off_calibrates_with_a_warning_in_every_form() {
    const K: f64 = 0.763;
    let tmp = tempfile::tempdir().unwrap();
    let p = |name: &str| tmp.path().join(name);
    let sim = simulate_hand(
        &logger_unit(OutputUnit::MetresPerSecondSquared),
        &HandSpec::standard(6),
    );
    let rows: Rows = sim.rows.clone();
    let flags = "--time-column t --acc-unit m/s2";
    write_csv(&p("true.csv"), &rows, 1.0, None);
    let line = |input: &str, out: &str, more: &str| {
        format!(
            "host segment -q --input {} --out {} {more}",
            p(input).display(),
            p(out).display()
        )
    };
    let (reference, said) = segment_line(&line(
        "true.csv",
        "true",
        &format!("{flags} --gyro-unit rad/s"),
    ));
    assert!(
        !said.iter().any(|w| w.contains("all three axes")),
        "{said:?}"
    );

    // A CSV in rad/s, converted at a nominal scale 24 % low.
    write_csv(&p("low.csv"), &rows, K, None);
    let (fit, said) = segment_line(&line(
        "low.csv",
        "low",
        &format!("{flags} --gyro-unit rad/s"),
    ));
    same_gyro(&fit, &reference, K, "rad/s");
    let note = said.iter().find(|w| w.contains("all three axes")).unwrap();
    println!("{note}");
    assert!(
        note.contains("values are 0.76")
            && note.contains("time column")
            && !note.contains("--rate-hz"),
        "{note}"
    );

    // Raw counts of a 65.5 LSB per °/s part, converted at 85.84 (65.5 / 0.763).
    let lsb = 65.5 / K;
    write_csv(&p("counts.csv"), &rows, 1.0, Some(65.5));
    let (fit, said) = segment_line(&line(
        "counts.csv",
        "counts",
        &format!("{flags} --gyro-unit LSB --gyro-lsb-per-dps {lsb}"),
    ));
    same_gyro(&fit, &reference, K, "counts");
    let note = said.iter().find(|w| w.contains("all three axes")).unwrap();
    println!("{note}");
    assert!(note.contains("the turns imply 65.5"), "{note}");

    // The same as a ROS 2 bag, whose stamps no option sets.
    let samples: Vec<LogSample> = rows
        .iter()
        .map(|&(t, a, g)| LogSample {
            t_s: 100.0 + t,
            acc: a.map(|x| x as f32),
            gyro: g.map(|x| (x * K) as f32),
            temp_c: 25.0,
        })
        .collect();
    std::fs::write(p("low.mcap"), write_mcap(&samples, None, 0.01)).unwrap();
    let (fit, said) = segment_line(&line("low.mcap", "mcap", ""));
    same_gyro(&fit, &reference, K, "MCAP");
    let note = said.iter().find(|w| w.contains("all three axes")).unwrap();
    println!("{note}");
    assert!(
        note.contains("MCAP log's stamps")
            && !note.contains("--rate-hz")
            && !note.contains("--time"),
        "{note}"
    );
}

/// 2× and 1.5× follow one rule: a gyro read at half its true LSB per °/s (131 for 65.5), or rows
/// given at half their rate, calibrate with the note naming the figure, as 1.5× does.
#[test]
fn twice_and_one_and_a_half_times_follow_one_rule() {
    let tmp = tempfile::tempdir().unwrap();
    let p = |name: &str| tmp.path().join(name);
    let sim = simulate_hand(
        &logger_unit(OutputUnit::MetresPerSecondSquared),
        &HandSpec::standard(7),
    );
    let rows: Rows = sim.rows.clone();
    write_csv(&p("counts.csv"), &rows, 1.0, Some(65.5));
    for (lsb, implied) in [(131.0, "65.5"), (98.25, "65.5")] {
        let (_, said) = segment_line(&format!(
            "host segment -q --input {} --out {} --time-column t --acc-unit m/s2 --gyro-unit LSB \
             --gyro-lsb-per-dps {lsb}",
            p("counts.csv").display(),
            p(&format!("c{lsb}")).display()
        ));
        let note = said.iter().find(|w| w.contains("all three axes")).unwrap();
        println!("{note}");
        assert!(
            note.contains(&format!("the turns imply {implied}")),
            "{lsb}: {note}"
        );
    }
    for rate in [100.0, 133.333] {
        let (_, said) = segment_line(&format!(
            "host segment -q --input {} --out {} --rate-hz {rate} --acc-unit m/s2 --gyro-unit LSB \
             --gyro-lsb-per-dps 65.5",
            p("counts.csv").display(),
            p(&format!("r{rate}")).display()
        ));
        let note = said.iter().find(|w| w.contains("all three axes")).unwrap();
        println!("{note}");
        assert!(
            note.contains("rows would have to come at 200.")
                && note.contains(&format!("--rate-hz {rate}")),
            "{rate}: {note}"
        );
    }
}
