//! `host bringup` against the simulated device: a healthy unit passes every check it can make
//! (gravity too once it is calibrated); each planted fault — the part sampling at 800 Hz while it
//! states 1000, an accelerometer axis stuck — fails the one check that names it, with its cause;
//! and the command itself (`host bringup --port sim`) passes, exit status 0.

use host::device::bringup::{bringup, names, Bringup, Verdict};
use host::device::sim::{SimDevice, SIM_UNIT_ID};
use host::device::DeviceClient;
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
    assert_eq!(r.checks.len(), 8);
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
