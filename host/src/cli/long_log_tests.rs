//! A long log read within a budget far below its size: the hand-held fixture session between two
//! five-minute stretches of motion (a flight before and after it). Only the session is kept, and
//! it calibrates as the session alone does.

use super::log_fixture_tests::{fixture, segment_and_calibrate};
use crate::fuzz::logs::{write_ulog, LogSample};
use crate::session::import::{GyroUnit, ImportOptions, TimeSource, TimeUnit};
use crate::session::logs::{read_log, read_log_keeping, LogSource};
use crate::sim::testkit::Rng;
use shared::OutputUnit;

/// Seconds of motion before and after the session.
const MOTION_S: f64 = 300.0;
const RATE_HZ: f64 = 100.0;

fn none() -> LogSource {
    LogSource {
        text: None,
        instance: None,
        topic: None,
        spelling: Default::default(),
    }
}

/// A vehicle in flight: 1 g of vibration on each axis about gravity and 1 rad/s of rotation.
fn flying(t_s: f64, rng: &mut Rng) -> LogSample {
    let mut n = || rng.normal() as f32;
    LogSample {
        t_s,
        acc: [9.81 * n(), 9.81 * n(), -9.81 + 9.81 * n()],
        gyro: [n(), n(), n()],
        temp_c: 24.0,
    }
}

/// The fixture session with `MOTION_S` of flight before and after it, as one ULog; the number of
/// the session's samples.
fn long_log(path: &std::path::Path) -> usize {
    let (samples, session) = long_samples();
    std::fs::write(path, write_ulog(&samples, None)).unwrap();
    session
}

/// The same as a logger's CSV with its time in milliseconds, a unit told from the rows.
fn long_csv(path: &std::path::Path) -> usize {
    let (samples, session) = long_samples();
    let mut text = String::from("t_ms,acc_x,acc_y,acc_z,gyr_x,gyr_y,gyr_z\n");
    for s in &samples {
        let [ax, ay, az] = s.acc;
        let [gx, gy, gz] = s.gyro;
        text.push_str(&format!(
            "{:.3},{ax},{ay},{az},{gx},{gy},{gz}\n",
            s.t_s * 1e3
        ));
    }
    std::fs::write(path, text).unwrap();
    session
}

/// The samples of [`long_log`] and the number of the session's.
fn long_samples() -> (Vec<LogSample>, usize) {
    let hand = read_log(&fixture("hand.ulg"), &none()).unwrap().recording;
    let temps = hand.temp_c.clone().unwrap();
    let mut rng = Rng::new(3, 0);
    let before = (MOTION_S * RATE_HZ) as usize;
    let mut samples: Vec<LogSample> = (0..before)
        .map(|k| flying(k as f64 / RATE_HZ, &mut rng))
        .collect();
    let start = MOTION_S + 1.0 / RATE_HZ - hand.t_s[0];
    for i in 0..hand.len() {
        samples.push(LogSample {
            t_s: hand.t_s[i] + start,
            acc: hand.acc[i].map(|x| x as f32),
            gyro: hand.gyro_rad_s[i].map(|x| x as f32),
            temp_c: temps[i] as f32,
        });
    }
    let end = samples.last().unwrap().t_s;
    samples.extend((1..=before).map(|k| flying(end + k as f64 / RATE_HZ, &mut rng)));
    (samples, hand.len())
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
    assert!(
        ug <= (alone_ug * 1.1).max(alone_ug + 2.0),
        "{ug} {alone_ug}"
    );
    assert!(
        bias <= (alone_bias * 1.1).max(alone_bias + 0.002),
        "{bias} {alone_bias}"
    );
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
    let note = log.warnings.iter().find(|w| w.contains("are left out"));
    assert!(
        note.is_some_and(|w| w.contains("moves longer than 60 s")),
        "{:?}",
        log.warnings
    );
    assert!(
        !log.warnings.iter().any(|w| w.contains("--max-samples")),
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
        .find(|w| w.contains("--max-samples"))
        .unwrap_or_else(|| panic!("{:?}", log.warnings));
    let t_last = log.recording.t_s.last().unwrap();
    let from: f64 = cut
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
    let source = LogSource {
        text: Some(ImportOptions::new(
            TimeSource::Column("t_ms".into()),
            OutputUnit::MetresPerSecondSquared,
            GyroUnit::RadPerS,
        )),
        ..none()
    };
    let log = read_log_keeping(&path, &source, 10_000).unwrap();
    let rec = &log.recording;
    assert!((session..=10_000).contains(&rec.len()), "{}", rec.len());
    assert_eq!(rec.time_unit, Some((TimeUnit::Ms, true)));
    assert!(rec.t_s[0] > MOTION_S - 3.0, "{}", rec.t_s[0]);
    assert!(
        log.warnings
            .iter()
            .any(|w| w.contains("moves longer than 60 s")),
        "{:?}",
        log.warnings
    );
    calibrates_as_the_session_alone(tmp.path(), &path, &format!("{options} --max-samples 10000"));
}
