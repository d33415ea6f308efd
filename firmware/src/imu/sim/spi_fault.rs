//! SPI faults of the bus itself (not of the part), wrapped around any `SpiDevice`, to see what a
//! driver reports when the microcontroller's side goes wrong.
//!
//! [`LastBitFault`]: the "wrong last bit in every received byte" of an STM32F4 SPI whose pins are
//! left at their reset speed (stm32f4xx-hal 0.23 `src/spi.rs:302-303`; the review cites ST's errata
//! ES0182 §2.5.2): bit 0 of each received byte is the one of the byte before it on the wire. The
//! byte before a read's first is the one clocked in while the address went out, which the part does
//! not drive ([`LastBitFault::address_phase`], 0x00). WHO_AM_I 0x47 then reads 0x46.

use embedded_hal::spi::{ErrorType, Operation, SpiDevice};

/// The last-bit fault around a device.
pub struct LastBitFault<D> {
    /// The device on the bus (the part's model).
    pub inner: D,
    /// The fault is present (a board with its SPI pins at low speed).
    pub active: bool,
    /// What MISO carries while the host sends (the address byte): not driven, read as this.
    pub address_phase: u8,
}

impl<D> LastBitFault<D> {
    /// `inner` behind a bus with the fault present.
    pub fn new(inner: D) -> Self {
        LastBitFault {
            inner,
            active: true,
            address_phase: 0x00,
        }
    }
}

impl<D: ErrorType> ErrorType for LastBitFault<D> {
    type Error = D::Error;
}

impl<D: SpiDevice> SpiDevice for LastBitFault<D> {
    fn transaction(&mut self, ops: &mut [Operation<'_, u8>]) -> Result<(), Self::Error> {
        self.inner.transaction(ops)?;
        if !self.active {
            return Ok(());
        }
        // The byte on the wire before the next one received.
        let mut previous = self.address_phase;
        for op in ops.iter_mut() {
            let received: &mut [u8] = match op {
                Operation::Read(r) => r,
                Operation::Transfer(r, _) => r,
                Operation::TransferInPlace(b) => b,
                Operation::Write(w) => {
                    if !w.is_empty() {
                        previous = self.address_phase;
                    }
                    continue;
                }
                Operation::DelayNs(_) => continue,
            };
            for b in received.iter_mut() {
                let true_byte = *b;
                *b = (true_byte & !1) | (previous & 1);
                previous = true_byte;
            }
        }
        Ok(())
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::imu::sim::BusFault;

    /// A device that answers a fixed byte sequence to every read.
    struct Fixed(&'static [u8]);

    impl ErrorType for Fixed {
        type Error = BusFault;
    }

    impl SpiDevice for Fixed {
        fn transaction(&mut self, ops: &mut [Operation<'_, u8>]) -> Result<(), BusFault> {
            for op in ops.iter_mut() {
                if let Operation::Read(r) = op {
                    r.copy_from_slice(&self.0[..r.len()]);
                }
            }
            Ok(())
        }
    }

    #[test]
    fn each_byte_takes_bit_0_of_the_byte_before() {
        let mut bus = LastBitFault::new(Fixed(&[0x47, 0x01, 0x00, 0xFF, 0xFE]));
        let mut r = [0u8; 5];
        bus.transaction(&mut [Operation::Write(&[0xF5]), Operation::Read(&mut r)])
            .unwrap();
        // 0x47 after the undriven address phase (0): 0x46; 0x01 after 0x47 (bit 0 = 1): 0x01;
        // 0x00 after 0x01: 0x01; 0xFF after 0x00: 0xFE; 0xFE after 0xFF: 0xFF.
        assert_eq!(r, [0x46, 0x01, 0x01, 0xFE, 0xFF]);
        bus.active = false;
        bus.transaction(&mut [Operation::Write(&[0xF5]), Operation::Read(&mut r)])
            .unwrap();
        assert_eq!(r, [0x47, 0x01, 0x00, 0xFF, 0xFE]);
    }
}
