//! Power-on, reset and identify: no access within 1 ms of power-on or of a soft reset; WHO_AM_I
//! 0x47 accepted, retried 1 ms apart up to 21 reads while the part answers wrongly (Betaflight's
//! `icm426xxSpiDetect`), anything else refused with its value; a soft reset puts the registers back
//! to their reset values.

use super::*;
use crate::imu::icm42688::{regs, Error};
use crate::imu::ImuSource;

#[test]
fn identifies_and_resets() {
    let mut imu = started(Config::DEFAULT);
    assert_eq!(imu.who_am_i().unwrap(), 0x47);
    // Configured: GYRO_CONFIG0 is not at its reset value 0x06 for this setting.
    let mut cfg = Config::DEFAULT;
    cfg.gyro_range = crate::imu::icm42688::GyroRange::Dps500;
    imu.configure(cfg).unwrap();
    assert_eq!(imu.device_mut().register(0, regs::GYRO_CONFIG0), 0x46);
    imu.reset().unwrap();
    let m = imu.device_mut();
    assert_eq!(m.register(0, regs::GYRO_CONFIG0), 0x06, "reset value");
    assert_eq!(m.register(0, regs::INTF_CONFIG0), 0x30, "reset value");
    assert_eq!(
        m.register(0, regs::FIFO_CONFIG),
        0x00,
        "reset value: bypass"
    );
    assert_eq!(m.fifo_len(), 0);
    assert_eq!(m.violations, 0, "no access within 1 ms of the reset");
}

#[test]
fn wrong_who_am_i_is_refused_with_its_value() {
    for id in [0x00, 0xFF, 0x42, 0x6C] {
        let mut m = Icm42688Model::new(TestGen::default());
        m.who_am_i = id;
        match Icm42688::new(m, Config::DEFAULT) {
            Err(Error::WrongDevice(got)) => assert_eq!(got, id),
            other => panic!("{id:#x}: {:?}", other.err()),
        }
    }
}

#[test]
fn no_access_within_1_ms_of_power_on() {
    let imu = started(Config::DEFAULT);
    let m = imu.release();
    assert_eq!(m.violations, 0);
    assert_eq!(m.who_am_i_reads, 1, "right at the first read");
}

#[test]
fn who_am_i_retried_while_the_part_starts() {
    let mut m = Icm42688Model::new(TestGen::default());
    m.who_am_i_wrong_reads = 5;
    let mut imu = Icm42688::new(m, Config::DEFAULT).expect("identified at the 6th read");
    assert_eq!(imu.device_mut().who_am_i_reads, 6);
    assert_eq!(imu.device_mut().violations, 0);
    // And it runs.
    run_samples(&mut imu, 3);
    let mut buf = [ImuSample::default(); 4];
    assert!(imu.drain(&mut buf).expect("drain").samples > 0);
}

#[test]
fn who_am_i_gives_up_after_21_reads_1_ms_apart() {
    let mut bus = Icm42688Model::new(TestGen::default());
    bus.who_am_i_wrong_reads = 1000;
    assert_eq!(
        Icm42688::new(&mut bus, Config::DEFAULT).err(),
        Some(Error::WrongDevice(0x00))
    );
    assert_eq!(bus.who_am_i_reads, 21);
    // Power-on 1 ms, reset 1 ms, 20 retries 1 ms apart (the model's time is the driver's waits).
    assert_eq!(bus.time_ns(), 22_000_000);
    assert_eq!(bus.register(0, regs::PWR_MGMT0), 0, "never configured");
}
