//! A long log read window by window keeps the whole read's meaning: for any log and any window
//! size, `apply` writes and says what it writes and says reading the log whole, except the rows
//! the window rule leaves out (a stamp damaged so far that it lies outside its own window's
//! reach), and those are said as left out. Checked over many seeds, window sizes and the four
//! formats, each log with damage drawn from the seed: a 3 s gap, a temperature dropout (some
//! covering whole windows), a damaged stamp, an exact repeat, two samples swapped.
//!
//! `WINDOW_SEEDS=40 cargo test -p outputs --test apply_window_by_window -- --nocapture` runs more
//! seeds (the suite runs 6) and prints every case.

use estimator::unit_file::UnitFile;
use outputs::apply::{apply_log_within, Setting};
use recording::session::import::MAX_ROWS;
use recording::session::logs::{read_log_windows, LogRead, LogSource};
use recording::testkit::{
    assert_windows_from_marks, csv_source, hand_session, log_fixture, write_csv, write_dataflash,
    write_mcap, write_mcap_unstamped, write_ulog, LogSample,
};
use shared::compensator::LeverMode;
use shared::rng::Rng;
use shared::Calibration;
use std::path::Path;

/// The simulated unit the log fixtures' session was recorded with.
fn truth() -> Calibration {
    UnitFile::load(&log_fixture("hand.truth.toml"))
        .unwrap()
        .to_calibration()
        .unwrap()
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

/// `apply` of the truth to `path`, at most `max_samples` read at once: the CSV's lines and what
/// was said.
fn apply(
    path: &Path,
    source: &LogSource,
    cal: &Calibration,
    max_samples: usize,
) -> (Vec<String>, Vec<String>) {
    let mut out = Vec::new();
    let setting = Setting {
        mode: LeverMode::RateAndAcceleration,
        assume_temp_c: None,
    };
    let summary = apply_log_within(path, source, cal, &setting, max_samples, &mut out)
        .unwrap_or_else(|e| panic!("{} within {max_samples}: {e}", path.display()));
    let text = String::from_utf8(out).unwrap();
    (
        text.lines().map(str::to_string).collect(),
        outputs::note::Note::texts(&summary.warnings),
    )
}

/// The time column of an output line.
fn time_of(line: &str) -> &str {
    line.split(',').nth(1).unwrap_or("")
}

/// Samples the windowed read says the window rule left out.
fn said_lost(warnings: &[String]) -> usize {
    let w = warnings
        .iter()
        .find(|w| w.contains("left out by the window rule"));
    w.and_then(|w| w.split(' ').next()?.parse().ok())
        .unwrap_or(0)
}

/// Every window read from the survey's marks is the window read by a pass over the whole file:
/// the same samples, places and words.
/// One case: the windowed read against the whole read, as the module docs say. The number of
/// windows read and of rows said left out by the window rule.
fn check(path: &Path, source: &LogSource, max_samples: usize, case: &str) -> (usize, usize) {
    check_with(path, source, &truth(), max_samples, case).0
}

/// [`check`] applying `cal`; and what the whole read said.
fn check_with(
    path: &Path,
    source: &LogSource,
    cal: &Calibration,
    max_samples: usize,
    case: &str,
) -> ((usize, usize), Vec<String>) {
    assert_windows_from_marks(path, source, max_samples, case);
    let (whole, whole_said) = apply(path, source, cal, MAX_ROWS);
    let (windowed, mut said) = apply(path, source, cal, max_samples);
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
        assert!(
            k < whole.len(),
            "{case}: row at t = {} not written whole",
            time_of(line)
        );
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
    ((windows, lost), whole_said)
}

#[test]
fn a_window_by_window_apply_writes_and_says_what_a_whole_read_does() {
    let seeds: u64 = std::env::var("WINDOW_SEEDS")
        .ok()
        .and_then(|s| s.parse().ok())
        .unwrap_or(6);
    let tmp = tempfile::tempdir().unwrap();
    let clean = hand_session();
    let n = clean.len();
    let (mut cases, mut lost_rows) = (0, 0);
    for seed in 0..seeds {
        let mut rng = Rng::new(seed, 52);
        let mut samples = clean.clone();
        let damage = damage(&mut samples, &mut rng);
        let format = seed % 4;
        let path = tmp.path().join(format!("log{seed}"));
        let source = match format {
            0 => std::fs::write(&path, write_ulog(&samples, None)).map(|_| LogSource::default()),
            1 => std::fs::write(&path, write_dataflash(&samples)).map(|_| LogSource::default()),
            2 => {
                std::fs::write(&path, write_mcap(&samples, None, 0.0)).map(|_| LogSource::default())
            }
            _ => {
                std::fs::write(&path, write_csv(&samples)).unwrap();
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

/// The budget of the targeted cases below: windows of about 666 samples of the 5998.
const BUDGET: usize = 1332;

/// A DataFlash log of `samples` (its times those written) at `path`, and its windows' starts.
fn dataflash_windows(path: &Path, samples: &[LogSample]) -> Vec<f64> {
    std::fs::write(path, write_dataflash(samples)).unwrap();
    let LogRead::Windows(w) = read_log_windows(path, &LogSource::default(), BUDGET).unwrap() else {
        panic!("read whole");
    };
    (1..w.len()).map(|k| w.span(k).0).collect()
}

/// The sample at time `t_s`.
fn at(samples: &[LogSample], t_s: f64) -> usize {
    samples.iter().position(|s| s.t_s == t_s).unwrap()
}

/// A gap exactly at a window's edge is said, and a gap inside a later window is said after its
/// row in the log, not in the window: as a whole read says both.
#[test]
fn gaps_are_said_with_their_rows_in_the_log_at_a_window_edge_too() {
    let tmp = tempfile::tempdir().unwrap();
    let path = tmp.path().join("gaps.bin");
    let mut samples = hand_session();
    let starts = dataflash_windows(&path, &samples);
    let edge = at(&samples, starts[3]);
    let inside = at(&samples, starts[5]) + 100;
    for from in [edge, inside] {
        samples[from..].iter_mut().for_each(|s| s.t_s += 3.0);
    }
    let starts = dataflash_windows(&path, &samples);
    assert!(starts.contains(&samples[edge].t_s), "the gap is at an edge");
    let ((windows, lost), whole) =
        check_with(&path, &LogSource::default(), &truth(), BUDGET, "two gaps");
    let jumps = whole
        .iter()
        .find(|w| w.contains("time stamps jump 2 time(s)"));
    let jumps = jumps.unwrap_or_else(|| panic!("{whole:?}"));
    for row in [edge, inside] {
        assert!(
            jumps.contains(&format!("after data row {row} (")),
            "{jumps}"
        );
    }
    println!("{windows} windows, {lost} left out: {jumps}");
}

/// A stamp damaged 4 rows before a window's edge, so far (2.5 s) that it lies beyond its own
/// window's reach: that row is left out (the window rule) and said so, not said re-timed.
#[test]
fn a_stamp_damaged_before_a_window_edge_is_said_left_out_not_re_timed() {
    let tmp = tempfile::tempdir().unwrap();
    let path = tmp.path().join("stamp.bin");
    let mut samples = hand_session();
    let starts = dataflash_windows(&path, &samples);
    let damaged = at(&samples, starts[2]) - 4;
    samples[damaged].t_s += 2.5;
    dataflash_windows(&path, &samples);
    let (whole, _) = apply(&path, &LogSource::default(), &truth(), MAX_ROWS);
    let (windowed, said) = apply(&path, &LogSource::default(), &truth(), BUDGET);
    println!("{said:#?}");
    assert_eq!(windowed.len(), whole.len() - 1);
    assert_eq!(said_lost(&said), 1, "{said:?}");
    assert!(
        !said.iter().any(|w| w.contains("isolated stamp")),
        "{said:?}"
    );
    check(
        &path,
        &LogSource::default(),
        BUDGET,
        "a stamp damaged before an edge",
    );
}

/// A calibration with a temperature model (one that changes nothing: the truth's values at
/// every temperature).
fn thermal_truth() -> Calibration {
    let zero = [[0.0; shared::sensor_models::MAX_TEMPERATURE_DEGREE]; 3];
    Calibration {
        temperature: Some(shared::TemperatureModel {
            reference_c: 24.0,
            valid_range_c: [-40.0, 85.0],
            zero_bias_out_per_c: zero,
            scale_rel_per_c: zero,
            gyro_bias_rad_s_per_c: None,
        }),
        ..truth()
    }
}

/// A temperature dropout covering whole windows: the log has temperatures, and those windows are
/// applied as the whole read applies them (rows without a reading kept), not refused for want of a
/// temperature column.
#[test]
fn a_temperature_dropout_covering_whole_windows_is_applied_as_a_whole_read_applies_it() {
    let tmp = tempfile::tempdir().unwrap();
    let path = tmp.path().join("temps.bin");
    let mut samples = hand_session();
    let starts = dataflash_windows(&path, &samples);
    let (from, to) = (at(&samples, starts[1]) - 50, at(&samples, starts[4]) + 50);
    samples[from..to]
        .iter_mut()
        .for_each(|s| s.temp_c = f32::NAN);
    dataflash_windows(&path, &samples);
    let ((windows, _), whole) = check_with(
        &path,
        &LogSource::default(),
        &thermal_truth(),
        BUDGET,
        "a dropout",
    );
    let note = format!(
        "{} of {} samples have no temperature",
        to - from,
        samples.len()
    );
    assert!(whole.iter().any(|w| w.contains(&note)), "{whole:?}");
    println!("{windows} windows: {note}");
}

/// A bag whose every header stamp is 0, longer than the budget: cut into windows by its log
/// time as a whole read times it, not refused as a stream that cannot be read again.
#[test]
fn a_bag_without_stamps_longer_than_the_budget_is_read_window_by_window() {
    let tmp = tempfile::tempdir().unwrap();
    let path = tmp.path().join("unstamped.mcap");
    std::fs::write(&path, write_mcap_unstamped(&hand_session())).unwrap();
    let ((windows, lost), whole) =
        check_with(&path, &LogSource::default(), &truth(), BUDGET, "unstamped");
    assert!(
        whole.iter().any(|w| w.contains("no header stamp (all 0)")),
        "{whole:?}"
    );
    assert_eq!(lost, 0);
    println!("{windows} windows");
}
