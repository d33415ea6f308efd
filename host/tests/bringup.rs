//! `host bringup` against the simulated device: a healthy unit passes every check it can make
//! (gravity too once it is calibrated); each planted fault — the part sampling at 800 Hz while it
//! states 1000, an accelerometer axis stuck — fails the one check that names it, with its cause;
//! and the command itself (`host bringup --port sim`) passes, exit status 0.

use device::bringup::{bringup, bringup_with, names, Bringup, Verdict};
use device::bringup_motion::TableOperator;
use device::sim::{SimDevice, SIM_UNIT_ID};
use device::DeviceClient;
use firmware::imu::alignment::Alignment;
use shared::blob::ParameterBlob;
use shared::params::PAPER_UNIT;
use std::process::Command;
use std::time::Duration;

const MEASURE: Duration = Duration::from_millis(1500);

fn run(calibrated: bool, plant: impl FnOnce(&mut SimDevice)) -> Bringup {
    let dev = SimDevice::new(PAPER_UNIT).unwrap();
    let mut c = DeviceClient::new(dev, Duration::from_secs(2));
    if calibrated {
        let (buf, n) = ParameterBlob {
            unit_id: SIM_UNIT_ID,
            calibration: PAPER_UNIT,
            created_unix_s: 1,
        }
        .to_bytes()
        .unwrap();
        c.write_calibration(&buf[..n]).unwrap();
    }
    plant(c.transport_mut());
    c.transport_mut().pace_real_time();
    bringup(&mut c, MEASURE).unwrap()
}

fn failed(r: &Bringup) -> Vec<&'static str> {
    r.checks
        .iter()
        .filter(|c| c.verdict == Verdict::Fail)
        .map(|c| c.name)
        .collect()
}

#[test]
fn a_healthy_unit_passes() {
    let r = run(false, |_| {});
    assert!(r.passed(), "{:#?}", r.checks);
    let rate = r.check(names::RATE).unwrap();
    assert_eq!(rate.verdict, Verdict::Pass, "{rate:?}");
    // Uncalibrated and analog: no scale to check gravity with.
    assert_eq!(r.check(names::GRAVITY).unwrap().verdict, Verdict::Skipped);
    let r = run(true, |_| {});
    assert!(r.passed(), "{:#?}", r.checks);
    assert_eq!(r.check(names::GRAVITY).unwrap().verdict, Verdict::Pass);
    // identity, part, samples, rate, losses, temperature, axes, gravity, flat, noise, gyro at
    // rest, nose up and repeats (skipped: nobody to move the board), counters.
    assert_eq!(r.checks.len(), 14);
}

#[test]
fn a_wrong_sample_rate_is_named() {
    let r = run(false, |d| d.sample_at_hz(800));
    assert_eq!(failed(&r), [names::RATE], "{:#?}", r.checks);
    let c = r.check(names::RATE).unwrap();
    assert!(c.detail.contains("1000 Hz stated"), "{c:?}");
    assert!(
        c.cause.as_deref().unwrap().contains("output data rate"),
        "{c:?}"
    );
}

#[test]
fn a_stuck_axis_is_named() {
    let r = run(false, |d| d.stick_axis(1));
    assert_eq!(failed(&r), [names::AXES], "{:#?}", r.checks);
    let c = r.check(names::AXES).unwrap();
    assert!(c.detail.contains("accelerometer y"), "{c:?}");
    assert!(c.cause.as_deref().unwrap().contains("stuck axis"), "{c:?}");
}

#[test]
fn the_command_passes_on_the_simulated_device() {
    let out = Command::new(env!("CARGO_BIN_EXE_host"))
        .args(["bringup", "--port", "sim", "--seconds", "1"])
        .output()
        .unwrap();
    let stdout = String::from_utf8_lossy(&out.stdout);
    assert!(
        out.status.success(),
        "{stdout}\n{}",
        String::from_utf8_lossy(&out.stderr)
    );
    assert!(stdout.contains("PASS  sample rate"), "{stdout}");
    assert!(!stdout.contains("FAIL"), "{stdout}");
}

/// The single-package unit in counts (2048 LSB/g, ±16 g): its gravity is checked against its own
/// counts per g (which the device states in its health report), not the F405's 8192.
#[test]
fn a_unit_in_counts_is_checked_against_its_own_counts_per_g() {
    let r = run_unit(SINGLE_PACKAGE, |_| {}, false);
    let g = r.check(names::GRAVITY).unwrap();
    assert_eq!(g.verdict, Verdict::Pass, "{g:?}");
    assert!(g.detail.contains("2048 per g"), "{g:?}");
    assert!(r.passed(), "{:#?}", r.checks);
    let out = Command::new(env!("CARGO_BIN_EXE_host"))
        .args([
            "bringup",
            "--port",
            "sim",
            "--sim-unit",
            SINGLE_PACKAGE,
            "--seconds",
            "1",
        ])
        .output()
        .unwrap();
    let stdout = String::from_utf8_lossy(&out.stdout);
    assert!(out.status.success(), "{stdout}");
    assert!(stdout.contains("PASS  gravity at rest"), "{stdout}");
}

const SINGLE_PACKAGE: &str = concat!(env!("CARGO_MANIFEST_DIR"), "/units/single-package.toml");

/// The unit of `path` on the simulated device, `plant` applied, its virtual table the operator
/// when `posed`.
fn run_unit(path: &str, plant: impl FnOnce(&mut SimDevice), posed: bool) -> Bringup {
    let truth = estimator::unit_file::UnitFile::load(std::path::Path::new(path))
        .unwrap()
        .to_calibration()
        .unwrap();
    let mut c = DeviceClient::new(SimDevice::new(truth).unwrap(), Duration::from_secs(2));
    plant(c.transport_mut());
    c.transport_mut().pace_real_time();
    if posed {
        bringup_with(&mut c, MEASURE, &mut TableOperator).unwrap()
    } else {
        bringup(&mut c, MEASURE).unwrap()
    }
}

#[test]
fn the_part_and_the_counters_are_reported() {
    let r = run(false, |_| {});
    let p = r.check(names::PART).unwrap();
    assert_eq!(p.verdict, Verdict::Pass, "{p:?}");
    assert!(p.detail.contains("Virtual"), "{p:?}");
    let c = r.check(names::COUNTERS).unwrap();
    assert_eq!(c.verdict, Verdict::Pass, "{c:?}");
    assert!(c.detail.contains("lost samples +0"), "{c:?}");
}

/// Every check passes on a healthy unit in counts that is turned nose up and waved.
#[test]
fn a_healthy_unit_passes_the_poses() {
    let r = run_unit(SINGLE_PACKAGE, |_| {}, true);
    assert!(r.passed(), "{:#?}", r.checks);
    for name in [names::FLAT, names::NOSE_UP, names::NOISE, names::REPEATS] {
        assert_eq!(r.check(name).unwrap().verdict, Verdict::Pass, "{name}");
    }
}

/// The V5's mistake: its IMU is turned CW270, described as the V4's CW90 — x and y come out
/// reversed. Flat and top up cannot see it (z is right); nose up reads −1 g on x.
#[test]
fn a_wrong_imu_rotation_fails_nose_up_with_its_cause() {
    let r = run_unit(SINGLE_PACKAGE, |d| d.turn_outputs(Alignment::Cw180), true);
    assert_eq!(failed(&r), [names::NOSE_UP], "{:#?}", r.checks);
    assert_eq!(r.check(names::FLAT).unwrap().verdict, Verdict::Pass);
    let c = r.check(names::NOSE_UP).unwrap();
    assert!(c.cause.as_deref().unwrap().contains("off by 180°"), "{c:?}");
    // Turned by 90°: gravity on y when nose up.
    let r = run_unit(SINGLE_PACKAGE, |d| d.turn_outputs(Alignment::Cw90), true);
    assert_eq!(failed(&r), [names::NOSE_UP], "{:#?}", r.checks);
    let c = r.check(names::NOSE_UP).unwrap();
    assert!(c.cause.as_deref().unwrap().contains("off by 90°"), "{c:?}");
}

/// One accelerometer axis ten times noisier than the others is named.
#[test]
fn a_noisy_axis_is_named() {
    let r = run_unit(SINGLE_PACKAGE, |d| d.noisy_axis(1, 10.0), true);
    assert_eq!(failed(&r), [names::NOISE], "{:#?}", r.checks);
    let c = r.check(names::NOISE).unwrap();
    assert!(
        c.cause.as_deref().unwrap().contains("accelerometer y"),
        "{c:?}"
    );
}

/// A part that holds its gyro output for 12 samples (the ICM-42688-P's AFSR at 8 kHz) is caught
/// while waved.
#[test]
fn held_gyro_samples_are_caught_while_waved() {
    let r = run_unit(SINGLE_PACKAGE, |d| d.hold_gyro_samples(12), true);
    assert_eq!(failed(&r), [names::REPEATS], "{:#?}", r.checks);
    let c = r.check(names::REPEATS).unwrap();
    assert!(c.cause.as_deref().unwrap().contains("AFSR"), "{c:?}");
}

/// What `host bringup` prints for the single-package unit with a planted wrong IMU rotation and
/// a planted noisy axis (the command's own formatting; `cargo test -p host --test bringup --
/// --nocapture` shows it): each FAIL with its likely cause, the rest PASS.
#[test]
fn the_report_of_a_planted_rotation_and_noisy_axis() {
    let r = run_unit(
        SINGLE_PACKAGE,
        |d| {
            d.turn_outputs(Alignment::Cw180);
            d.noisy_axis(0, 10.0);
        },
        true,
    );
    let text = r.to_string();
    println!("{text}");
    assert_eq!(failed(&r), [names::NOISE, names::NOSE_UP], "{text}");
    assert!(text.contains("FAIL  nose up"), "{text}");
    assert!(text.contains("FAIL  noise at rest"), "{text}");
    assert!(text.contains("likely cause: gravity reads on −x"), "{text}");
    assert!(
        text.contains("likely cause: accelerometer x noisier"),
        "{text}"
    );
    assert!(text.contains("PASS  flat, top up"), "{text}");
}

/// The command itself takes the poses on the simulated device's table.
#[test]
fn the_command_poses_the_simulated_board() {
    let out = Command::new(env!("CARGO_BIN_EXE_host"))
        .args([
            "bringup",
            "--port",
            "sim",
            "--sim-unit",
            SINGLE_PACKAGE,
            "--seconds",
            "1",
        ])
        .output()
        .unwrap();
    let stdout = String::from_utf8_lossy(&out.stdout);
    assert!(out.status.success(), "{stdout}");
    assert!(stdout.contains("PASS  nose up"), "{stdout}");
    assert!(
        stdout.contains("PASS  repeated samples while waved"),
        "{stdout}"
    );
}
