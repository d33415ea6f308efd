//! `apply` on a long log read window by window, within a budget far below its size: it writes
//! what it writes reading the log whole, byte for byte, in the four formats (the hand-held fixture
//! session between two five-minute stretches of flight), and where it cannot (a stamp damaged so
//! far that it lands in another window) it says so.

use estimator::unit_file::UnitFile;
use outputs::apply::{apply_log_within, ApplySummary, Setting};
use outputs::note::Note;
use recording::session::import::MAX_ROWS;
use recording::session::import::{GyroUnit, ImportOptions, TimeSource};
use recording::session::logs::LogSource;
use recording::testkit::{
    flying, hand_session, log_fixture, session_in_flight, write_csv_ms, write_dataflash,
    write_mcap, write_ulog, LogSample, SPELLING,
};
use shared::compensator::LeverMode;
use shared::rng::Rng;
use shared::{Calibration, OutputUnit};

/// Seconds of flight before and after the session.
const MOTION_S: f64 = 300.0;
const RATE_HZ: f64 = 100.0;

fn none() -> LogSource {
    LogSource::new(SPELLING)
}

/// The simulated unit the log fixtures' session was recorded with.
fn truth() -> Calibration {
    UnitFile::load(&log_fixture("hand.truth.toml"))
        .unwrap()
        .to_calibration()
        .unwrap()
}

/// The long log's samples.
fn long_samples() -> (Vec<LogSample>, usize) {
    session_in_flight(MOTION_S, RATE_HZ)
}

/// The long log as a logger's CSV with its time in milliseconds.
fn long_csv(path: &std::path::Path) {
    std::fs::write(path, write_csv_ms(&long_samples().0)).unwrap();
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
            SPELLING,
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
        let Note::ReadInWindows { windows, .. } = *note else {
            panic!("{:?}", summary.warnings)
        };
        // About 66 000 samples in windows of about 5 000.
        assert!((10..=16).contains(&windows), "{note}");
        assert!(
            !whole_summary
                .warnings
                .iter()
                .any(|w| w.to_string().contains("windows")),
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
        let w = s.warnings.iter().map(ToString::to_string);
        w.filter(|w| w.contains("time stamps repaired")).collect()
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
        summary.warnings.iter().any(|w| w
            .to_string()
            .starts_with("1 sample(s) left out by the window rule")),
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

/// A drive after a bench rest: the fixture session, a minute of driving, five seconds of smooth
/// 0.4 g braking with little vibration (9 mg and 0.2 °/s on each axis: far above the bench's
/// noise and its hand's tremor, yet the quietest stretch of a stretch of driving), and another
/// minute of driving.
fn drive_after_rest() -> Vec<LogSample> {
    let hand = hand_session();
    let t0 = hand[0].t_s;
    let mut samples: Vec<LogSample> = hand
        .iter()
        .map(|s| LogSample {
            t_s: s.t_s - t0,
            ..*s
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
        summary.warnings[0].to_string().contains("time windows"),
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
