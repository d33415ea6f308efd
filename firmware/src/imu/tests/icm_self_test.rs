//! Self-test on request: a healthy part passes, a part whose response is 0.3 of its factory value
//! fails on both sensors, one at 1.6 fails on the accelerometer only (its window is 0.5–1.5); the
//! FIFO runs again afterwards, the first sample flagged as following lost data.

use super::*;
use crate::imu::icm42688::Error;
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

/// While it measures, the part is at TDK's self-test setting (`icm42688::self_test`'s module doc):
/// range and 1 kHz, the UI filter 3rd order at ODR/10, only the sensor under test on; afterwards
/// the filter registers are back at their values and both sensors sample again.
#[test]
fn tdk_setting_while_measuring() {
    use crate::imu::icm42688::regs::*;
    let r = self_test_with_gain(1.0);
    assert!(r.passed(), "{r:?}");
    let m = started_model_after_self_test();
    // [GYRO_CONFIG0, ACCEL_CONFIG0, GYRO_CONFIG1, GYRO_ACCEL_CONFIG0, ACCEL_CONFIG1, PWR_MGMT0,
    //  SELF_TEST_CONFIG] at the last read of each sensor's data (its self-test on).
    let [gyro, accel] = m.config_at_data_read;
    assert_eq!(gyro[0], (3 << 5) | 6, "gyro ±250 °/s, 1 kHz");
    assert_eq!(gyro[2] & GYRO_UI_FILT_ORD_MASK, GYRO_UI_FILT_ORD_3RD);
    assert_eq!(
        gyro[3] & GYRO_UI_FILT_BW_MASK,
        4,
        "gyro UI filter at ODR/10"
    );
    assert_eq!(gyro[5] & 0x0F, PWR_GYRO_LOW_NOISE, "the gyro alone");
    assert_eq!(gyro[6], ST_GYRO_ALL);
    assert_eq!(accel[1], (2 << 5) | 6, "accelerometer ±4 g, 1 kHz");
    assert_eq!(accel[4] & ACCEL_UI_FILT_ORD_MASK, ACCEL_UI_FILT_ORD_3RD);
    assert_eq!(
        accel[3] & ACCEL_UI_FILT_BW_MASK,
        4 << 4,
        "accelerometer UI filter at ODR/10"
    );
    assert_eq!(
        accel[5] & 0x0F,
        PWR_ACCEL_LOW_NOISE,
        "the accelerometer alone"
    );
    assert_eq!(accel[6], ST_ACCEL_ALL);
    // Restored: the reset values of the UI filter registers, both sensors on, self-test off.
    assert_eq!(m.register(0, GYRO_CONFIG1), 0x16);
    assert_eq!(m.register(0, GYRO_ACCEL_CONFIG0), 0x11);
    assert_eq!(m.register(0, ACCEL_CONFIG1), 0x0D);
    assert_eq!(m.register(0, PWR_MGMT0) & 0x0F, PWR_LOW_NOISE);
    assert_eq!(m.register(0, SELF_TEST_CONFIG), 0);
}

fn started_model_after_self_test() -> Model {
    let mut imu = started(Config::DEFAULT);
    imu.device_mut().generator().still = true;
    imu.self_test().unwrap();
    assert_eq!(imu.device_mut().violations, 0);
    imu.release()
}

/// Each sample is read once, when DATA_RDY says it is new, whatever the part's clock: 3 % slow or
/// fast, no read finds the previous sample again (a driver reading every 1 ms of the board's time
/// reads about 6 stale samples of 200 in each phase with the part 3 % slow), and the part passes.
#[test]
fn data_ready_paces_the_reads() {
    for ppm in [30_000, -30_000, 0] {
        let mut imu = started(Config::DEFAULT);
        imu.device_mut().generator().still = true;
        imu.device_mut().clock_ppm = ppm;
        let r = imu.self_test().unwrap();
        assert!(r.passed(), "{ppm} ppm: {r:?}");
        assert_eq!(imu.device_mut().stale_data_reads, [0, 0], "{ppm} ppm");
    }
}

/// A part that stops flagging new samples (here its clock 20 times slow: 200 samples would take
/// 4 s) ends the self-test with `NoDataReady` instead of averaging stale data.
#[test]
fn no_data_ready_is_an_error() {
    let mut imu = started(Config::DEFAULT);
    imu.device_mut().clock_ppm = 19_000_000;
    assert!(matches!(imu.self_test(), Err(Error::NoDataReady)));
}
