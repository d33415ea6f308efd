//! The driver behind an STM32F4 SPI with the "wrong last bit in every received byte" fault (pins at
//! low speed; `imu::sim::LastBitFault`): WHO_AM_I 0x47 reads 0x46 and the driver stops there with a
//! typed identity error naming that byte, before writing any configuration.

use super::*;
use crate::imu::icm42688::{regs, Error};
use crate::imu::sim::LastBitFault;

#[test]
fn last_bit_fault_is_an_identity_error_naming_the_byte_read() {
    let bus = LastBitFault::new(Icm42688Model::new(TestGen::default()));
    let err = match Icm42688::new(bus, Config::DEFAULT) {
        Err(e) => e,
        Ok(_) => panic!("configured a part whose every byte read is wrong"),
    };
    // 0x47 = 0100_0111 with bit 0 taken from the undriven address phase (0).
    assert_eq!(err, Error::WrongDevice(0x46));
    assert!(err.to_string().contains("0x46"), "{err}");
    assert!(err.to_string().contains("bit 0"), "{err}");
}

#[test]
fn nothing_is_configured_under_the_fault() {
    let mut bus = LastBitFault::new(Icm42688Model::new(TestGen::default()));
    // The driver borrows the bus, so the part can be inspected after.
    let _ = Icm42688::new(&mut bus, Config::DEFAULT);
    let m = &bus.inner;
    assert_eq!(m.register(0, regs::PWR_MGMT0), 0, "sensors never started");
    assert_eq!(m.register(0, regs::FIFO_CONFIG), 0, "FIFO left in bypass");
    assert_eq!(m.register(0, regs::GYRO_CONFIG0), 0x06, "reset value");
    // Without the fault the same part starts.
    bus.active = false;
    assert!(Icm42688::new(&mut bus, Config::DEFAULT).is_ok());
}
