//! Self-test on request: a healthy part passes, a part whose response is 0.3 of its factory value
//! fails on both sensors, one at 1.6 fails on the accelerometer only (its window is 0.5–1.5); the
//! FIFO runs again afterwards, the first sample flagged as following lost data.

use super::*;
use crate::imu::ImuFlags;

fn self_test_with_gain(gain: f64) -> crate::imu::icm42688::SelfTestReport {
    let mut imu = started(Config::DEFAULT);
    imu.device_mut().generator().still = true;
    imu.device_mut().self_test_gain = gain;
    let report = imu.self_test().unwrap();
    assert_eq!(imu.device_mut().violations, 0);
    // Back to the configuration, sampling into the FIFO.
    drain_all(&mut imu);
    run_samples(&mut imu, 3);
    let after = drain_all(&mut imu);
    assert_eq!(after.len(), 3);
    assert!(after[0].flags.has(ImuFlags::DATA_LOST));
    report
}

#[test]
fn healthy_part_passes() {
    let r = self_test_with_gain(1.0);
    assert!(r.passed(), "{r:?}");
    // At rest and noise-free, the response is the factory value for the model's codes, to the
    // rounding of the averages.
    for a in r.gyro.iter().chain(r.accel.iter()) {
        assert!((a.response_lsb - a.otp_lsb).abs() <= 1.0, "{a:?}");
    }
    assert!((r.gyro_offset_dps[0] - 0.5).abs() < 0.01, "{r:?}");
}

#[test]
fn weak_part_fails_both_sensors() {
    let r = self_test_with_gain(0.3);
    assert!(!r.passed());
    assert!(r.gyro.iter().all(|a| !a.pass), "{r:?}");
    assert!(r.accel.iter().all(|a| !a.pass), "{r:?}");
}

#[test]
fn strong_accelerometer_response_fails() {
    let r = self_test_with_gain(1.6);
    assert!(!r.passed());
    assert!(
        r.gyro.iter().all(|a| a.pass),
        "the gyro's limit is only a minimum"
    );
    assert!(r.accel.iter().all(|a| !a.pass), "{r:?}");
}
