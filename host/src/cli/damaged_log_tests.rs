//! Logs as real loggers damage them, through `host segment` → `host calibrate` → `host apply`: the
//! reference-tool fixtures (`recording/tests/fixtures/logs/`) and simulated sessions with one damaged
//! stamp, repeated or reversed rows, jitter or simulated time. Each must calibrate as its clean self
//! does (within the clean calibration's 1σ) and say what was repaired.

use super::log_fixture_tests::{command, fixture};
use super::segment::segment;
use super::{apply, calibrate, Command};
use estimator::sim::handheld::{
    logger_unit, simulate_hand, write_logger_csv, HandSpec, LoggerLayout,
};
use recording::testkit::{write_mcap, LogSample};
use shared::rng::Rng;
use shared::OutputUnit;
use std::path::Path;

/// What a damaged log gave: the positions found, the calibration's (name, value, 1σ), and the
/// repairs `segment` said.
struct Run {
    positions: usize,
    parameters: Vec<(String, f64, f64)>,
    warnings: Vec<String>,
}

fn run(dir: &Path, input: &Path, flags: &str) -> Run {
    let d = dir.display();
    let line = format!(
        "host segment -q --input {} --out {d}/s {flags}",
        input.display()
    );
    let Command::Segment(a) = command(&line) else {
        panic!("{line}")
    };
    let out = segment(&a).unwrap_or_else(|e| panic!("{}: {e}", input.display()));
    let Command::Calibrate(c) = command(&format!("host calibrate --input {d}/s --out-dir {d}/cal"))
    else {
        panic!()
    };
    let cal = calibrate::calibrate(&c, true).unwrap_or_else(|e| panic!("{}: {e}", input.display()));
    let notes: Vec<String> = out
        .recording
        .reader_warnings(recording::session::import::Places::InFile)
        .iter()
        .map(ToString::to_string)
        .filter(|w| w.contains("repaired"))
        .collect();
    Run {
        positions: out.plan.segments.len(),
        parameters: cal.parameters,
        warnings: notes,
    }
}

/// Every accelerometer parameter of `damaged` within the clean calibration's 1σ of the clean value.
fn agree(clean: &Run, damaged: &Run, case: &str) {
    assert_eq!(clean.positions, damaged.positions, "{case}: positions");
    for ((name, v0, s0), (_, v, _)) in clean.parameters.iter().zip(&damaged.parameters) {
        if name.starts_with("gyro") {
            continue;
        }
        assert!(
            (v - v0).abs() <= s0.max(1e-12),
            "{case}: {name} {v} against {v0} ± {s0}"
        );
    }
}

/// The byte offsets of the IMU messages' `TimeUS` in a DataFlash log (each message's length from
/// its `FMT`, as pymavlink's DFReader walks the file).
fn dataflash_imu_stamps(bytes: &[u8]) -> Vec<usize> {
    let mut lengths = [0usize; 256];
    lengths[0x80] = 89;
    let (mut imu, mut pos, mut out) = (None, 0usize, Vec::new());
    while pos + 3 <= bytes.len() && bytes[pos] == 0xA3 && bytes[pos + 1] == 0x95 {
        let ty = bytes[pos + 2];
        if ty == 0x80 {
            lengths[bytes[pos + 3] as usize] = bytes[pos + 4] as usize;
            if &bytes[pos + 5..pos + 8] == b"IMU" {
                imu = Some(bytes[pos + 3]);
            }
        } else if Some(ty) == imu {
            out.push(pos + 3);
        }
        pos += lengths[ty as usize].max(1);
    }
    out
}

/// One flipped bit in the `TimeUS` of the middle IMU message of the DataFlash fixture (pymavlink's
/// file): that sample is re-timed and the calibration is the clean one's; `apply` writes every row.
#[test]
fn one_flipped_stamp_bit_in_a_dataflash_log_costs_nothing() {
    let tmp = tempfile::tempdir().unwrap();
    let clean = run(&tmp.path().join("clean"), &fixture("hand.bin"), "");
    let mut bytes = std::fs::read(fixture("hand.bin")).unwrap();
    let stamps = dataflash_imu_stamps(&bytes);
    assert_eq!(stamps.len(), 6000, "IMU messages");
    let at = stamps[3000];
    bytes[at + 4] ^= 0x08; // bit 35 of TimeUS: 9.5 hours later
    let damaged_path = tmp.path().join("flipped.bin");
    std::fs::write(&damaged_path, &bytes).unwrap();
    let damaged = run(&tmp.path().join("flipped"), &damaged_path, "");
    agree(&clean, &damaged, "flipped bit");
    assert!(
        damaged
            .warnings
            .iter()
            .any(|w| w.contains("1 isolated stamp(s)") && w.contains("IMU sample 3001")),
        "{:?}",
        damaged.warnings
    );
    let out = tmp.path().join("applied.csv");
    let line = format!(
        "host apply --calibration {}/flipped/cal/calibration.toml --input {} --out {}",
        tmp.path().display(),
        damaged_path.display(),
        out.display()
    );
    let Command::Apply(a) = command(&line) else {
        panic!()
    };
    apply::run(&a, true).unwrap();
    let rows = std::fs::read_to_string(&out).unwrap().lines().count() - 1;
    assert_eq!(rows, 6000);
}

/// Rows as a logger CSV in m/s² and rad/s, as `host simulate-hand --gyro-unit rad/s` writes them.
fn csv(path: &Path, rows: &[(f64, [f64; 3], [f64; 3])]) {
    let layout = LoggerLayout {
        gyro_deg_s: false,
        ..LoggerLayout::default()
    };
    write_logger_csv(path, rows, &layout).unwrap();
}

const CSV_FLAGS: &str = "--time-column t --acc-unit m/s2 --gyro-unit rad/s";

/// ±1 ms of stamp jitter at 200 Hz, every row written twice, rows newest first: each segments and
/// calibrates as the clean file does, and says what it repaired.
#[test]
fn jitter_repeated_rows_and_reversed_rows_calibrate_as_the_clean_log() {
    let tmp = tempfile::tempdir().unwrap();
    let sim = simulate_hand(
        &logger_unit(OutputUnit::MetresPerSecondSquared),
        &HandSpec::standard(2),
    );
    let rows: Vec<_> = sim.rows.iter().take(24_000).copied().collect();
    let p = |name: &str| tmp.path().join(name);
    csv(&p("clean.csv"), &rows);
    let clean = run(&p("clean"), &p("clean.csv"), CSV_FLAGS);
    let mut rng = Rng::new(9, 1);
    let jittered: Vec<_> = rows
        .iter()
        .map(|&(t, a, g)| (t + rng.range(-1e-3, 1e-3), a, g))
        .collect();
    let twice: Vec<_> = rows.iter().flat_map(|&r| [r, r]).collect();
    let mut reversed = rows.clone();
    reversed.reverse();
    for (name, rows, said) in [
        ("jitter", jittered, None),
        ("twice", twice, Some("24000 exact repeat(s)")),
        ("reversed", reversed, Some("written newest first")),
    ] {
        csv(&p(&format!("{name}.csv")), &rows);
        let damaged = run(&p(name), &p(&format!("{name}.csv")), CSV_FLAGS);
        if name == "jitter" {
            // The stamps move, the values do not: the same positions, and the rate is the clean one.
            assert_eq!(clean.positions, damaged.positions, "jitter");
            assert!(damaged.warnings.is_empty(), "{:?}", damaged.warnings);
        } else {
            agree(&clean, &damaged, name);
        }
        if let Some(said) = said {
            assert!(
                damaged.warnings.iter().any(|w| w.contains(said)),
                "{name}: {:?}",
                damaged.warnings
            );
        }
    }
}

/// A ROS 2 bag recorded in simulated time: the first `header.stamp` is 0 and the bag's log time
/// is the wall clock. Every message is read on the stamps, as the clean bag is.
#[test]
fn a_bag_in_simulated_time_reads_on_its_stamps() {
    let tmp = tempfile::tempdir().unwrap();
    let sim = simulate_hand(
        &logger_unit(OutputUnit::MetresPerSecondSquared),
        &HandSpec::standard(4),
    );
    let samples: Vec<LogSample> = sim
        .rows
        .iter()
        .take(24_000)
        .map(|&(t, a, g)| LogSample {
            t_s: t - sim.rows[0].0,
            acc: a.map(|x| x as f32),
            gyro: g.map(|x| x as f32),
            temp_c: 25.0,
        })
        .collect();
    assert_eq!(samples[0].t_s, 0.0);
    let bag = tmp.path().join("sim-time.mcap");
    std::fs::write(&bag, write_mcap(&samples, None, 1.7e9)).unwrap();
    let wall = tmp.path().join("wall.mcap");
    let later: Vec<LogSample> = samples
        .iter()
        .map(|s| LogSample {
            t_s: s.t_s + 1.7e9,
            ..*s
        })
        .collect();
    std::fs::write(&wall, write_mcap(&later, None, 0.01)).unwrap();
    let clean = run(&tmp.path().join("wall"), &wall, "");
    let damaged = run(&tmp.path().join("sim"), &bag, "");
    agree(&clean, &damaged, "simulated time");
}

/// A ULog whose `sensor_accel.temperature` is NaN (a driver without a temperature reading), in the
/// first fifth of the log or throughout: the same positions as with its readings, the rows kept;
/// throughout, the log reads as one without temperature, which `apply` with a temperature model
/// then refuses instead of evaluating the model at its reference temperature.
#[test]
fn nan_temperatures_cost_no_rows_and_no_positions() {
    let tmp = tempfile::tempdir().unwrap();
    let sim = simulate_hand(
        &logger_unit(OutputUnit::MetresPerSecondSquared),
        &HandSpec::standard(5),
    );
    let samples: Vec<LogSample> = sim
        .rows
        .iter()
        .take(24_000)
        .enumerate()
        .map(|(k, &(t, a, g))| LogSample {
            t_s: t,
            acc: a.map(|x| x as f32),
            gyro: g.map(|x| x as f32),
            temp_c: 30.0 + 2e-5 * k as f32,
        })
        .collect();
    let write = |name: &str, nan_upto: usize| {
        let mut s = samples.clone();
        s[..nan_upto].iter_mut().for_each(|x| x.temp_c = f32::NAN);
        let path = tmp.path().join(name);
        std::fs::write(&path, recording::testkit::write_ulog(&s, None)).unwrap();
        path
    };
    let clean = run(&tmp.path().join("clean"), &write("clean.ulg", 0), "");
    let fifth = run(&tmp.path().join("fifth"), &write("fifth.ulg", 4_800), "");
    agree(&clean, &fifth, "first fifth NaN");
    let all = write("all.ulg", samples.len());
    let none = run(&tmp.path().join("all"), &all, "");
    assert_eq!(none.positions, clean.positions);
    let plan = std::fs::read_to_string(tmp.path().join("all/s/plan.toml")).unwrap();
    assert!(!plan.contains("temp_c"), "{plan}");
    // The simulated unit with a temperature model (thermal-mems.toml's coefficients).
    let thermal = std::fs::read_to_string(
        Path::new(env!("CARGO_MANIFEST_DIR")).join("units/thermal-mems.toml"),
    )
    .unwrap();
    let section =
        &thermal[thermal.find("[temperature]").unwrap()..thermal.find("[thermal]").unwrap()];
    let unit = tmp.path().join("thermal-unit.toml");
    let truth = std::fs::read_to_string(fixture("hand.truth.toml")).unwrap();
    std::fs::write(&unit, format!("{truth}\n{section}")).unwrap();
    let out = tmp.path().join("applied.csv");
    let apply_line = |input: &Path| {
        format!(
            "host apply --calibration {} --input {} --out {} --force",
            unit.display(),
            input.display(),
            out.display()
        )
    };
    let Command::Apply(a) = command(&apply_line(&all)) else {
        panic!()
    };
    let e = apply::run(&a, true).unwrap_err().to_string();
    assert!(
        e.contains("temperature model") && e.contains("--temperature-c"),
        "{e}"
    );
    // With a fifth of the readings missing: every row written.
    let Command::Apply(a) = command(&apply_line(&tmp.path().join("fifth.ulg"))) else {
        panic!()
    };
    apply::run(&a, true).unwrap();
    let rows = std::fs::read_to_string(&out).unwrap().lines().count() - 1;
    assert_eq!(rows, 24_000);
}

/// Advice names only options that exist for the input: a DataFlash log whose gyro is logged in °/s
/// where the format says rad/s has no `--gyro-unit` to give.
#[test]
fn advice_on_a_binary_log_names_no_text_option() {
    let tmp = tempfile::tempdir().unwrap();
    let sim = simulate_hand(
        &logger_unit(OutputUnit::MetresPerSecondSquared),
        &HandSpec::standard(8),
    );
    let samples: Vec<LogSample> = sim
        .rows
        .iter()
        .take(24_000)
        .map(|&(t, a, g)| LogSample {
            t_s: t,
            acc: a.map(|x| x as f32),
            gyro: g.map(|x| x.to_degrees() as f32),
            temp_c: 25.0,
        })
        .collect();
    let path = tmp.path().join("deg.bin");
    std::fs::write(&path, recording::testkit::write_dataflash(&samples)).unwrap();
    let line = format!(
        "host segment -q --input {} --out {}/s",
        path.display(),
        tmp.path().display()
    );
    let Command::Segment(a) = command(&line) else {
        panic!()
    };
    let e = segment(&a).err().expect("refused").to_string();
    assert!(
        e.contains("ArduPilot DataFlash log's gyro") && !e.contains("--gyro-unit"),
        "{e}"
    );
}
