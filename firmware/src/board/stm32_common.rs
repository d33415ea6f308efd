//! What the two STM32F4 boards share: the unit identifier and the internal flash as the calibration
//! store's NOR flash. Both chips (F405, F446) have 128 KiB sectors from sector 5 on and the unique ID
//! at the same address.

use embedded_storage::nor_flash::{ErrorType, NorFlash, ReadNorFlash};
use shared::units::UnitId;
use stm32f4xx_hal::flash::{Error as FlashError, FlashExt, LockedFlash};

use crate::storage::AbStore;

/// The chip's 96-bit unique ID (reference manual §39.1), the unit identifier.
pub fn unit_id() -> UnitId {
    let base = 0x1FFF_7A10 as *const u8;
    // SAFETY: the factory-programmed, read-only unique ID area of the STM32F4.
    UnitId(core::array::from_fn(|i| unsafe {
        core::ptr::read_volatile(base.add(i))
    }))
}

/// The internal flash as a NOR flash that unlocks itself for each program/erase.
pub struct F4Flash(pub LockedFlash);

impl ErrorType for F4Flash {
    type Error = FlashError;
}

impl ReadNorFlash for F4Flash {
    const READ_SIZE: usize = 1;

    fn read(&mut self, offset: u32, bytes: &mut [u8]) -> Result<(), FlashError> {
        ReadNorFlash::read(&mut self.0, offset, bytes)
    }

    fn capacity(&self) -> usize {
        ReadNorFlash::capacity(&self.0)
    }
}

impl NorFlash for F4Flash {
    const WRITE_SIZE: usize = 1;
    const ERASE_SIZE: usize = 128 * 1024;

    fn erase(&mut self, from: u32, to: u32) -> Result<(), FlashError> {
        NorFlash::erase(&mut self.0.unlocked(), from, to)
    }

    fn write(&mut self, offset: u32, bytes: &[u8]) -> Result<(), FlashError> {
        NorFlash::write(&mut self.0.unlocked(), offset, bytes)
    }
}

/// A board's calibration store.
pub type Store = AbStore<F4Flash>;
