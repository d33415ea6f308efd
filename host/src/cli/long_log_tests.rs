//! A long log read within a budget far below its size: the hand-held fixture session between two
//! five-minute stretches of motion (a flight before and after it). Only the session is kept, and
//! it calibrates as the session alone does.

use super::log_fixture_tests::{assert_as_good, fixture, segment_and_calibrate, truth};
use outputs::apply::{apply_log_within, ApplySummary, Setting};
use recording::session::import::MAX_ROWS;
use recording::session::import::{GyroUnit, ImportOptions, TimeSource, TimeUnit};
use recording::session::logs::{read_log, read_log_keeping, LogSource};
use recording::testkit::{write_dataflash, write_mcap, write_ulog, LogSample};
use shared::compensator::LeverMode;
use shared::rng::Rng;
use shared::OutputUnit;

/// Seconds of motion before and after the session.
const MOTION_S: f64 = 300.0;
const RATE_HZ: f64 = 100.0;

fn none() -> LogSource {
    LogSource {
        text: None,
        instance: None,
        topic: None,
        spelling: super::spelling::FLAGS,
        rate_hz: None,
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

/// `apply` of the truth's calibration to the log at `path` (read as `source` says), reading at
/// most `max_samples` at once: the CSV's lines and the summary.
fn apply_within(
    path: &std::path::Path,
    source: &LogSource,
    max_samples: usize,
) -> (Vec<String>, ApplySummary) {
    let mut out = Vec::new();
    let setting = Setting {
        mode: LeverMode::RateAndAcceleration,
        assume_temp_c: None,
    };
    let summary = apply_log_within(path, source, &truth(), &setting, max_samples, &mut out)
        .unwrap_or_else(|e| panic!("{e}"));
    let text = String::from_utf8(out).unwrap();
    (text.lines().map(str::to_string).collect(), summary)
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

/// `apply` on the long log read window by window writes what it writes reading the log whole, byte
/// for byte, in each of the four formats: each window's repair and pairing see the neighbours a
/// whole read does, and the device's state (ω̇, temperature refresh, gaps) is carried from one
/// window to the next.
#[test]
fn a_long_log_applied_window_by_window_is_the_log_applied_whole() {
    let tmp = tempfile::tempdir().unwrap();
    let (samples, _) = long_samples();
    let logs = [
        ("long.ulg", write_ulog(&samples, None)),
        ("long.bin", write_dataflash(&samples)),
        ("long.mcap", write_mcap(&samples, None, 0.0)),
    ];
    let mut inputs: Vec<(std::path::PathBuf, LogSource)> = Vec::new();
    for (name, bytes) in logs {
        std::fs::write(tmp.path().join(name), bytes).unwrap();
        inputs.push((tmp.path().join(name), none()));
    }
    long_csv(&tmp.path().join("long.csv"));
    inputs.push((tmp.path().join("long.csv"), csv_source()));
    for (path, source) in &inputs {
        let (whole, whole_summary) = apply_within(path, source, MAX_ROWS);
        let (windowed, summary) = apply_within(path, source, 10_000);
        let note = &summary.warnings[0];
        println!(
            "{}: {} rows whole and window by window; {note}",
            path.display(),
            whole_summary.rows
        );
        let windows: usize = note
            .split(" in ")
            .nth(1)
            .and_then(|w| w.split(' ').next())
            .and_then(|n| n.parse().ok())
            .unwrap_or_else(|| panic!("{:?}", summary.warnings));
        // About 66 000 samples in windows of about 5 000.
        assert!((10..=16).contains(&windows), "{note}");
        assert!(
            !whole_summary.warnings.iter().any(|w| w.contains("windows")),
            "{:?}",
            whole_summary.warnings
        );
        assert_eq!(summary.rows, whole_summary.rows);
        assert_eq!(windowed.len(), whole.len());
        for (k, (a, b)) in windowed.iter().zip(&whole).enumerate() {
            assert_eq!(a, b, "{}: line {}", path.display(), k + 1);
        }
    }
}

/// A stamp damaged so far that it lands in another window is left out there (the repair's end
/// rule) where a whole read re-times it: one row fewer, every other row at its own time, and said
/// as left out by the window rule. An exact repeat and a swapped pair cost nothing, and are said
/// with their places in the file as a whole read says them.
#[test]
fn a_far_damaged_stamp_costs_its_row_in_a_windowed_apply() {
    let tmp = tempfile::tempdir().unwrap();
    let path = tmp.path().join("long.ulg");
    let (mut samples, _) = long_samples();
    let damaged = 20_000;
    samples[damaged].t_s += 1000.0;
    samples.swap(40_000, 40_001);
    let repeat = samples[50_000];
    samples.insert(50_001, repeat);
    std::fs::write(&path, write_ulog(&samples, None)).unwrap();
    let (whole, whole_summary) = apply_within(&path, &none(), MAX_ROWS);
    let (windowed, summary) = apply_within(&path, &none(), 10_000);
    // Each repair is said with the samples' places in the file, read whole or window by window.
    let repairs = |s: &ApplySummary| -> Vec<String> {
        let w = s
            .warnings
            .iter()
            .filter(|w| w.contains("time stamps repaired"));
        w.cloned().collect()
    };
    let said = repairs(&whole_summary).join(" | ");
    println!("read whole: {said}");
    for part in [
        "1 isolated stamp(s) that jumped and came back re-timed from their neighbours (",
        &format!("sample {} stamped", damaged + 1),
        "1 exact repeat(s) (same stamp, same values) left out (",
        "sample(s) out of order sorted into time order",
    ] {
        assert!(said.contains(part), "{part}: {said}");
    }
    let said = repairs(&summary).join(" | ");
    println!("window by window: {said}");
    for part in [
        &format!(
            "1 exact repeat(s) (same stamp, same values) left out (IMU sample {})",
            50_002
        ),
        "2 sample(s) out of order sorted into time order",
    ] {
        assert!(said.contains(part), "{part}: {said}");
    }
    assert!(!said.contains("re-timed"), "{said}");
    assert!(
        summary
            .warnings
            .iter()
            .any(|w| w.starts_with("1 sample(s) left out by the window rule")),
        "{:?}",
        summary.warnings
    );
    let times = |lines: &[String]| -> Vec<f64> {
        let t = lines.iter().skip(1).map(|l| l.split(',').nth(1).unwrap());
        t.map(|t| t.parse().unwrap()).collect()
    };
    let (whole_t, windowed_t) = (times(&whole), times(&windowed));
    assert_eq!(whole_t.len(), samples.len() - 1, "the repeat left out");
    assert_eq!(windowed_t.len(), whole_t.len() - 1);
    let missing: Vec<f64> = whole_t
        .iter()
        .copied()
        .filter(|t| windowed_t.binary_search_by(|w| w.total_cmp(t)).is_err())
        .collect();
    // The log's times start where the writer's do: the rows are the samples moved by that.
    let start = whole_t[0] - samples[0].t_s;
    let retimed = start + (samples[damaged - 1].t_s + samples[damaged + 1].t_s) / 2.0;
    assert_eq!(missing.len(), 1, "{missing:?}");
    assert!((missing[0] - retimed).abs() < 1e-4, "{missing:?} {retimed}");
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

/// A drive after a bench rest: the fixture session, a minute of driving, five seconds of smooth
/// 0.4 g braking with little vibration (9 mg and 0.2 °/s on each axis: far above the bench's
/// noise and its hand's tremor, yet the quietest stretch of a stretch of driving), and another
/// minute of driving.
fn drive_after_rest() -> Vec<LogSample> {
    let hand = read_log(&fixture("hand.ulg"), &none()).unwrap().recording;
    let temps = hand.temp_c.clone().unwrap();
    let mut samples: Vec<LogSample> = (0..hand.len())
        .map(|i| LogSample {
            t_s: hand.t_s[i] - hand.t_s[0],
            acc: hand.acc[i].map(|x| x as f32),
            gyro: hand.gyro_rad_s[i].map(|x| x as f32),
            temp_c: temps[i] as f32,
        })
        .collect();
    let mut rng = Rng::new(5, 0);
    drive(&mut samples, &mut rng);
    let (acc_sd, gyro_sd) = (9e-3 * 9.81, 0.2f64.to_radians());
    for _ in 0..(5.0 * RATE_HZ) as usize {
        let t_s = samples.last().unwrap().t_s + 1.0 / RATE_HZ;
        let mut n = |sd: f64| (sd * rng.normal()) as f32;
        let acc = [-0.4 * 9.81 + n(acc_sd), n(acc_sd), -9.81 + n(acc_sd)];
        let gyro = [n(gyro_sd), n(gyro_sd), n(gyro_sd)];
        samples.push(LogSample {
            t_s,
            acc,
            gyro,
            temp_c: 24.0,
        });
    }
    drive(&mut samples, &mut rng);
    samples
}

/// Every window of a long log judges rest by the same noise floors, those of the whole log: the
/// window that holds the drive's braking and no rest does not take the braking for a still
/// position (which compensates to 1.08 g and would refuse the calibration). Read window by window
/// the log is applied as read whole: accepted, byte for byte the same output.
#[test]
fn a_window_without_a_rest_judges_rest_by_the_whole_logs_noise() {
    let tmp = tempfile::tempdir().unwrap();
    let samples = drive_after_rest();
    let path = tmp.path().join("drive.ulg");
    std::fs::write(&path, write_ulog(&samples, None)).unwrap();
    let (whole, whole_summary) = apply_within(&path, &none(), MAX_ROWS);
    let (windowed, summary) = apply_within(&path, &none(), 10_000);
    assert!(
        summary.warnings[0].contains("time windows"),
        "{:?}",
        summary.warnings
    );
    assert_eq!(summary.rows, whole_summary.rows);
    assert_eq!(summary.rows as usize, samples.len());
    assert_eq!(windowed.len(), whole.len());
    for (k, (a, b)) in windowed.iter().zip(&whole).enumerate() {
        assert_eq!(a, b, "line {}", k + 1);
    }
}

/// A minute of driving ([`flying`]) after the last of `samples`.
fn drive(samples: &mut Vec<LogSample>, rng: &mut Rng) {
    let t0 = samples.last().map_or(0.0, |s| s.t_s);
    for k in 1..=(60.0 * RATE_HZ) as usize {
        samples.push(flying(t0 + k as f64 / RATE_HZ, rng));
    }
}
