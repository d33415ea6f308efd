//! A long log read window by window keeps the whole read's meaning: for any log and any window
//! size, `apply` writes and says what it writes and says reading the log whole, except the rows
//! the window rule leaves out (a stamp damaged so far that it lies outside its own window's
//! reach), and those are said as left out. Checked over many seeds, window sizes and the four
//! formats, each log with damage drawn from the seed: a 3 s gap, a temperature dropout (some
//! covering whole windows), a damaged stamp, an exact repeat, two samples swapped.
//!
//! `WINDOW_SEEDS=40 cargo test -p host --lib window_property -- --nocapture` runs more seeds (the
//! suite runs 6) and prints every case.

use super::log_fixture_tests::{fixture, truth};
use crate::apply::{apply_log_within, Setting};
use crate::fuzz::logs::{write_dataflash, write_mcap, write_ulog, LogSample};
use crate::session::import::{GyroUnit, ImportOptions, TimeSource, MAX_ROWS};
use crate::session::logs::{read_log, LogSource};
use crate::sim::testkit::Rng;
use shared::compensator::LeverMode;
use shared::OutputUnit;
use std::path::Path;

fn binary() -> LogSource {
    LogSource {
        text: None,
        instance: None,
        topic: None,
        spelling: Default::default(),
    }
}

fn csv_source() -> LogSource {
    let mut options = ImportOptions::new(
        TimeSource::Column("t".into()),
        OutputUnit::MetresPerSecondSquared,
        GyroUnit::RadPerS,
    );
    options.temp_column = Some("temp".into());
    LogSource {
        text: Some(options),
        ..binary()
    }
}

/// The hand-held fixture session's samples.
fn session() -> Vec<LogSample> {
    let hand = read_log(&fixture("hand.ulg"), &binary()).unwrap().recording;
    let temps = hand.temp_c.clone().unwrap();
    (0..hand.len())
        .map(|i| LogSample {
            t_s: hand.t_s[i],
            acc: hand.acc[i].map(|x| x as f32),
            gyro: hand.gyro_rad_s[i].map(|x| x as f32),
            temp_c: temps[i] as f32,
        })
        .collect()
}

/// The damage drawn for one case, said for the case's line.
fn damage(samples: &mut Vec<LogSample>, rng: &mut Rng) -> String {
    let n = samples.len();
    let mut pick = |lo: usize, hi: usize| lo + (rng.uniform() * (hi - lo) as f64) as usize;
    let mut said = Vec::new();
    let (gap, drop_at, drop_len) = (pick(10, n - 10), pick(0, n - 10), pick(1, n / 3));
    let (stamp, swap, repeat) = (pick(10, n - 10), pick(10, n - 10), pick(10, n - 10));
    let offset_s = [0.3, -0.7, 2.5, -12.0, 40.0][pick(0, 5)];
    let kinds = pick(0, 32);
    if kinds & 1 != 0 {
        samples[gap..].iter_mut().for_each(|s| s.t_s += 3.0);
        said.push(format!("gap after {gap}"));
    }
    if kinds & 2 != 0 {
        let end = (drop_at + drop_len).min(n);
        samples[drop_at..end]
            .iter_mut()
            .for_each(|s| s.temp_c = f32::NAN);
        said.push(format!("no temperature {drop_at}..{end}"));
    }
    if kinds & 4 != 0 {
        samples[stamp].t_s += offset_s;
        said.push(format!("stamp {stamp} {offset_s:+} s"));
    }
    if kinds & 8 != 0 {
        samples.swap(swap, swap + 1);
        said.push(format!("swap {swap}"));
    }
    if kinds & 16 != 0 {
        let s = samples[repeat];
        samples.insert(repeat + 1, s);
        said.push(format!("repeat {repeat}"));
    }
    said.join(", ")
}

fn write_csv(path: &Path, samples: &[LogSample]) {
    let mut text = String::from("t,acc_x,acc_y,acc_z,gyr_x,gyr_y,gyr_z,temp\n");
    for s in samples {
        let [ax, ay, az] = s.acc;
        let [gx, gy, gz] = s.gyro;
        text.push_str(&format!(
            "{:.6},{ax},{ay},{az},{gx},{gy},{gz},{}\n",
            s.t_s, s.temp_c
        ));
    }
    std::fs::write(path, text).unwrap();
}

/// `apply` of the truth to `path`, at most `max_samples` read at once: the CSV's lines and what
/// was said.
fn apply(path: &Path, source: &LogSource, max_samples: usize) -> (Vec<String>, Vec<String>) {
    let mut out = Vec::new();
    let setting = Setting {
        mode: LeverMode::RateAndAcceleration,
        assume_temp_c: None,
    };
    let summary = apply_log_within(path, source, &truth(), &setting, max_samples, &mut out)
        .unwrap_or_else(|e| panic!("{} within {max_samples}: {e}", path.display()));
    let text = String::from_utf8(out).unwrap();
    (text.lines().map(str::to_string).collect(), summary.warnings)
}

/// The time column of an output line.
fn time_of(line: &str) -> &str {
    line.split(',').nth(1).unwrap_or("")
}

/// Samples the windowed read says the window rule left out.
fn said_lost(warnings: &[String]) -> usize {
    let w = warnings.iter().find(|w| w.contains("left out by the window rule"));
    w.and_then(|w| w.split(' ').next()?.parse().ok())
        .unwrap_or(0)
}

/// One case: the windowed read against the whole read, as the module docs say. The number of
/// windows read.
fn check(path: &Path, source: &LogSource, max_samples: usize, case: &str) -> (usize, usize) {
    let (whole, whole_said) = apply(path, source, MAX_ROWS);
    let (windowed, mut said) = apply(path, source, max_samples);
    let note = said.remove(0);
    assert!(note.contains("time windows"), "{case}: {note}");
    let windows: usize = note
        .split(" in ")
        .nth(1)
        .and_then(|w| w.split(' ').next()?.parse().ok())
        .unwrap_or(0);
    let lost = said_lost(&said);
    assert_eq!(
        windowed.len() + lost,
        whole.len(),
        "{case}: {} rows written window by window, {lost} said left out, {} written whole\n\
         whole: {whole_said:#?}\nwindowed: {said:#?}",
        windowed.len(),
        whole.len()
    );
    // Every row written is the whole read's row, in order; with none left out, every line.
    let mut k = 0;
    for line in &windowed {
        while k < whole.len() && time_of(&whole[k]) != time_of(line) {
            k += 1;
        }
        assert!(k < whole.len(), "{case}: row at t = {} not written whole", time_of(line));
        if lost == 0 {
            assert_eq!(line, &whole[k], "{case}");
        }
        k += 1;
    }
    let sorted = |v: &[String], keep: &dyn Fn(&String) -> bool| {
        let mut v: Vec<String> = v.iter().filter(|w| keep(w)).cloned().collect();
        v.sort();
        v
    };
    // A row left out by the window rule is re-timed in a whole read, moves the rows after it and
    // is counted among the rows: what names rows is said alike, but for those numbers.
    let counts_rows = |w: &String| {
        w.contains("time stamps repaired")
            || w.contains("the time stamps jump")
            || w.contains("left out by the window rule")
            || w.contains("have no temperature reading")
    };
    let comparable = |w: &String| lost == 0 || !counts_rows(w);
    assert_eq!(
        sorted(&said, &comparable),
        sorted(&whole_said, &comparable),
        "{case}: what is said"
    );
    (windows, lost)
}

#[test]
fn a_window_by_window_apply_writes_and_says_what_a_whole_read_does() {
    let seeds: u64 = std::env::var("WINDOW_SEEDS")
        .ok()
        .and_then(|s| s.parse().ok())
        .unwrap_or(6);
    let tmp = tempfile::tempdir().unwrap();
    let clean = session();
    let n = clean.len();
    let (mut cases, mut lost_rows) = (0, 0);
    for seed in 0..seeds {
        let mut rng = Rng::new(seed, 52);
        let mut samples = clean.clone();
        let damage = damage(&mut samples, &mut rng);
        let format = seed % 4;
        let path = tmp.path().join(format!("log{seed}"));
        let source = match format {
            0 => std::fs::write(&path, write_ulog(&samples, None)).map(|_| binary()),
            1 => std::fs::write(&path, write_dataflash(&samples)).map(|_| binary()),
            2 => std::fs::write(&path, write_mcap(&samples, None, 0.0)).map(|_| binary()),
            _ => {
                write_csv(&path, &samples);
                Ok(csv_source())
            }
        }
        .unwrap();
        let name = ["ULog", "DataFlash", "MCAP", "CSV"][format as usize];
        for per_window in [n / 9, n / 4 + 37, n / 2 - 11] {
            let max_samples = 2 * per_window;
            let case = format!("seed {seed}, {name}, {damage}, budget {max_samples}");
            let (windows, lost) = check(&path, &source, max_samples, &case);
            println!("{case}: {windows} windows, {lost} row(s) said left out by the window rule");
            cases += 1;
            lost_rows += lost;
        }
    }
    println!("{cases} cases of {n} samples, {lost_rows} row(s) left out by the window rule in all");
}


