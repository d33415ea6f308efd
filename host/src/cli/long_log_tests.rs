//! A long log read within a budget far below its size: the hand-held fixture session between two
//! five-minute stretches of motion (a flight before and after it). Only the session is kept, and
//! it calibrates as the session alone does. How `apply` reads such a log window by window is
//! `outputs`' test (`tests/apply_long_logs.rs`).

use super::log_fixture_tests::{assert_as_good, fixture, segment_and_calibrate};
use recording::session::import::{GyroUnit, ImportOptions, TimeSource, TimeUnit};
use recording::session::logs::{read_log_keeping, LogSource};
use recording::testkit::{session_in_flight, write_csv_ms, write_ulog, LogSample};
use shared::OutputUnit;

/// Seconds of motion before and after the session.
const MOTION_S: f64 = 300.0;
const RATE_HZ: f64 = 100.0;

fn none() -> LogSource {
    LogSource::new(super::spelling::FLAGS)
}

/// The fixture session with `MOTION_S` of flight before and after it, as one ULog; the number of
/// the session's samples.
fn long_log(path: &std::path::Path) -> usize {
    let (samples, session) = long_samples();
    std::fs::write(path, write_ulog(&samples, None)).unwrap();
    session
}

/// The text reader's options for [`long_csv`].
fn csv_source() -> LogSource {
    LogSource {
        text: Some(ImportOptions::new(
            TimeSource::Column("t_ms".into()),
            OutputUnit::MetresPerSecondSquared,
            GyroUnit::RadPerS,
            crate::cli::spelling::FLAGS,
        )),
        ..none()
    }
}

/// The same as a logger's CSV with its time in milliseconds, a unit told from the rows; the
/// number of the session's samples.
fn long_csv(path: &std::path::Path) -> usize {
    let (samples, session) = long_samples();
    std::fs::write(path, write_csv_ms(&samples)).unwrap();
    session
}

/// The samples of [`long_log`] and the number of the session's.
fn long_samples() -> (Vec<LogSample>, usize) {
    session_in_flight(MOTION_S, RATE_HZ)
}

/// `segment` + `calibrate` of the long log at `path` (with `flags`) against the fixture session
/// alone: the held-out error and the gyro bias within 10 % of the session's own.
fn calibrates_as_the_session_alone(tmp: &std::path::Path, path: &std::path::Path, flags: &str) {
    let (alone_ug, alone_bias) = segment_and_calibrate(&tmp.join("a"), &fixture("hand.ulg"), "");
    let (ug, bias) = segment_and_calibrate(&tmp.join("b"), path, flags);
    println!(
        "the session alone: {alone_ug:.1} µg, {alone_bias:.4} °/s; in the long log: {ug:.1} µg, \
         {bias:.4} °/s"
    );
    assert_as_good("the long log", (ug, bias), (alone_ug, alone_bias));
}

#[test]
fn a_long_log_keeps_its_session_within_the_budget_and_calibrates_as_the_session() {
    let tmp = tempfile::tempdir().unwrap();
    let path = tmp.path().join("long.ulg");
    let session = long_log(&path);
    let budget = 10_000;
    let log = read_log_keeping(&path, &none(), budget).unwrap();
    let rec = &log.recording;
    println!(
        "{} samples in the log, {} kept within a budget of {budget}; the session has {session}",
        session + 2 * (MOTION_S * RATE_HZ) as usize,
        rec.len()
    );
    assert!(rec.len() <= budget, "{}", rec.len());
    // The session whole, and of the flights no more than the margins and a block either side.
    assert!(rec.len() >= session, "{} of {session}", rec.len());
    assert!(rec.len() <= session + 2 * 300, "{}", rec.len());
    assert!(rec.t_s[0] > MOTION_S - 3.0, "{}", rec.t_s[0]);
    let note = log
        .warnings
        .iter()
        .find(|w| w.to_string().contains("are left out"));
    assert!(
        note.is_some_and(|w| w.to_string().contains("moves longer than 60 s")),
        "{:?}",
        log.warnings
    );
    assert!(
        !log.warnings
            .iter()
            .any(|w| w.to_string().contains("--max-samples")),
        "the session fits the budget: {:?}",
        log.warnings
    );

    calibrates_as_the_session_alone(tmp.path(), &path, &format!("--max-samples {budget}"));
}

/// A budget smaller than the session: the first samples are kept, and the note says from when on
/// the rest is left out and which option keeps it.
#[test]
fn a_session_larger_than_the_budget_is_cut_and_said_so() {
    let tmp = tempfile::tempdir().unwrap();
    let path = tmp.path().join("long.ulg");
    long_log(&path);
    let log = read_log_keeping(&path, &none(), 3000).unwrap();
    assert!(log.recording.len() <= 3000);
    let cut = log
        .warnings
        .iter()
        .find(|w| w.to_string().contains("--max-samples"))
        .unwrap_or_else(|| panic!("{:?}", log.warnings));
    let t_last = log.recording.t_s.last().unwrap();
    let from: f64 = cut
        .to_string()
        .split("from t = ")
        .nth(1)
        .unwrap()
        .split(' ')
        .next()
        .unwrap()
        .parse()
        .unwrap();
    assert!(
        (from - (t_last + 1.0 / RATE_HZ)).abs() < 1e-3,
        "{cut} {t_last}"
    );
}

/// A text log too: its time unit (ms) is told from the rows read before the budget ran out, and
/// the session calibrates as in the ULog.
#[test]
fn a_long_text_log_keeps_its_session_too() {
    let tmp = tempfile::tempdir().unwrap();
    let path = tmp.path().join("long.csv");
    let session = long_csv(&path);
    let options = "--time-column t_ms --acc-unit m/s2 --gyro-unit rad/s";
    let log = read_log_keeping(&path, &csv_source(), 10_000).unwrap();
    let rec = &log.recording;
    assert!((session..=10_000).contains(&rec.len()), "{}", rec.len());
    assert_eq!(rec.time_unit, Some((TimeUnit::Ms, true)));
    assert!(rec.t_s[0] > MOTION_S - 3.0, "{}", rec.t_s[0]);
    assert!(
        log.warnings
            .iter()
            .any(|w| w.to_string().contains("moves longer than 60 s")),
        "{:?}",
        log.warnings
    );
    calibrates_as_the_session_alone(tmp.path(), &path, &format!("{options} --max-samples 10000"));
}
