//! Reset and identify: WHO_AM_I 0x47 accepted, anything else refused with its value; a soft reset
//! puts the registers back to their reset values; the driver keeps the 1 ms after reset.

use super::*;
use crate::imu::icm42688::{regs, Error};

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
