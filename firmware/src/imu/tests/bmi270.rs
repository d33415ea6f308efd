//! The BMI270 driver against its model: the start (dummy reads, soft reset, CHIP_ID, the
//! configuration upload checked by INTERNAL_STATUS), the configured registers as the datasheet's
//! fields and Betaflight's values say, samples bit for bit against the generator quantised here,
//! a missed data ready flagged with its count, no sample read twice, a brown-out found by the
//! register check and healed by a re-init, SPI errors.

use super::{code, TestGen};
use crate::imu::bmi270::regs::*;
use crate::imu::bmi270::{Bmi270, Config, Error};
use crate::imu::sim::{Bmi270Model, BusFault, Generator};
use crate::imu::{ImuFlags, ImuSample, ImuSource};
use core::f32::consts::PI;

type Imu = Bmi270<Bmi270Model<TestGen>>;

fn started() -> Imu {
    Bmi270::new(Bmi270Model::new(TestGen::default()), Config::DEFAULT).unwrap()
}

/// One sample period on the part.
fn tick(imu: &mut Imu) {
    let m = imu.device_mut();
    m.advance_ns(m.until_next_sample_ns().max(1));
}

fn drain_one(imu: &mut Imu) -> Option<ImuSample> {
    let mut buf = [ImuSample::default(); 4];
    let d = imu.drain(&mut buf).unwrap();
    assert!(!d.more);
    (d.samples == 1).then_some(buf[0])
}

#[test]
fn bmi270_starts_with_its_configuration_file() {
    let mut imu = started();
    assert_eq!(imu.chip_id(), 0x24);
    let m = imu.device_mut();
    assert!(m.initialised(), "INTERNAL_STATUS not init_ok");
    // The power-on dummy read and the one after the soft reset; nothing else in I²C mode.
    assert_eq!(m.i2c_mode_accesses, 2);
    // The datasheet's fields: ACC_CONF acc_filter_perf 1, acc_bwp 2 (normal), odr 0x0C (1.6 kHz);
    // ACC_RANGE 1 (±4 g); GYR_CONF filter and noise performance 1, bwp 2, odr 0x0C; GYR_RANGE
    // ±2000 °/s with ois_range; INT_MAP_DATA drdy on INT1; INT1_IO_CTRL output enable, push-pull,
    // active high; PWR_CONF advanced power save off; PWR_CTRL temperature, accelerometer, gyro.
    for (reg, v) in [
        (0x40, 0b1010_1100),
        (0x41, 0x01),
        (0x42, 0b1110_1100),
        (0x43, 0b0000_1000),
        (0x58, 0b0000_0100),
        (0x53, 0b0000_1010),
        (0x7C, 0x02),
        (0x7D, 0b0000_1110),
    ] {
        assert_eq!(m.register(reg), v, "register {reg:#04x}");
    }
    assert_eq!(imu.sample_rate_hz(), 1600);
}

#[test]
fn bmi270_other_parts_are_refused_with_their_id() {
    for id in [0x00, 0xFF, 0x47, 0x6C] {
        let mut m = Bmi270Model::new(TestGen::default());
        m.chip_id = id;
        assert_eq!(
            Bmi270::new(m, Config::DEFAULT).err(),
            Some(Error::WrongDevice(id))
        );
    }
}

/// One byte of the 8 KiB file damaged in transfer: the part reports init_err and the driver
/// refuses to run on it.
#[test]
fn bmi270_a_damaged_upload_is_refused_by_internal_status() {
    let mut m = Bmi270Model::new(TestGen::default());
    m.corrupt_upload_byte = Some(4321);
    assert_eq!(
        Bmi270::new(m, Config::DEFAULT).err(),
        Some(Error::ConfigLoad(INTERNAL_STATUS_INIT_ERR))
    );
}

#[test]
fn bmi270_samples_bit_for_bit() {
    let mut imu = started();
    let mut gen = TestGen::default();
    // Samples the part made during the start (after PWR_CTRL) were never read.
    for _ in 0..imu.device_mut().samples {
        gen.next();
    }
    let rad_per_lsb = 2000.0f32 / 32768.0 * (PI / 180.0);
    let mut prev_time = None;
    for _ in 0..100 {
        tick(&mut imu);
        let s = drain_one(&mut imu).expect("a sample per data ready");
        let t = gen.next();
        let acc = t.accel_g.map(|g| code(g * 8192.0, 32767));
        let gyr = t.gyro_dps.map(|d| code(d * 16.384, 32767));
        assert_eq!(s.accel_out, acc.map(|c| c as f32));
        assert_eq!(s.gyro_rad_s, gyr.map(|c| c as f32 * rad_per_lsb));
        let temp = code((t.temp_c - 23.0) * 512.0, 32767);
        assert_eq!(s.temp_c, 23.0 + temp as f32 / 512.0);
        let saturated = acc.iter().chain(&gyr).any(|c| c.abs() == 32767);
        assert_eq!(s.flags.has(ImuFlags::SATURATED), saturated);
        assert!(!s.flags.has(ImuFlags::DATA_LOST));
        // 1.6 kHz: 625 µs = 16 ticks of 39.0625 µs.
        if let Some(p) = prev_time {
            assert_eq!(s.timestamp.wrapping_sub(p), 16);
        }
        prev_time = Some(s.timestamp);
    }
}

#[test]
fn bmi270_no_sample_is_read_twice_and_a_missed_one_is_counted() {
    let mut imu = started();
    tick(&mut imu);
    assert!(drain_one(&mut imu).is_some());
    assert_eq!(drain_one(&mut imu), None, "the same sample read again");
    let before = imu.device_mut().overwritten;
    for _ in 0..4 {
        tick(&mut imu);
    }
    let s = drain_one(&mut imu).unwrap();
    assert!(s.flags.has(ImuFlags::DATA_LOST));
    assert_eq!(s.lost_before, 3);
    assert_eq!(imu.device_mut().overwritten - before, 3);
}

/// A brown-out resets the part: no sample comes, nothing in the data path says why. The register
/// check finds it within one round of the configured registers; a re-init brings samples back.
#[test]
fn bmi270_register_check_finds_a_brown_out_and_reinit_heals_it() {
    let mut imu = started();
    for _ in 0..8 {
        assert_eq!(imu.check_next_register(), Ok(()));
    }
    tick(&mut imu);
    assert!(drain_one(&mut imu).is_some());
    imu.device_mut().brown_out();
    for _ in 0..10 {
        tick(&mut imu);
        assert_eq!(drain_one(&mut imu), None);
    }
    let found = (0..8).find_map(|_| imu.check_next_register().err());
    assert!(
        matches!(found, Some(Error::RegisterMismatch { .. })),
        "{found:?}"
    );
    imu.reinit().unwrap();
    assert!(imu.device_mut().initialised());
    tick(&mut imu);
    assert!(drain_one(&mut imu).is_some());
    for _ in 0..8 {
        assert_eq!(imu.check_next_register(), Ok(()));
    }
}

#[test]
fn bmi270_spi_errors_reach_the_caller() {
    let mut m = Bmi270Model::new(TestGen::default());
    m.fail_spi = true;
    assert_eq!(
        Bmi270::new(m, Config::DEFAULT).err(),
        Some(Error::Spi(BusFault))
    );
    let mut imu = started();
    imu.device_mut().fail_spi = true;
    let mut buf = [ImuSample::default(); 1];
    assert_eq!(imu.drain(&mut buf).err(), Some(Error::Spi(BusFault)));
    assert_eq!(imu.check_next_register().err(), Some(Error::Spi(BusFault)));
}
