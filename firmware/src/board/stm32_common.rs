//! What the two STM32F4 boards share: the unit identifier, the internal flash as the calibration
//! store's NOR flash, and the set-up of SPI1 (both boards put their sensor on PA5–PA7). Both chips
//! (F405, F446) have 128 KiB sectors from sector 5 on and the unique ID at the same address.

use embedded_storage::nor_flash::{ErrorType, NorFlash, ReadNorFlash};
use shared::units::UnitId;
use stm32f4xx_hal::flash::{Error as FlashError, FlashExt, LockedFlash};
use stm32f4xx_hal::gpio::alt::spi1;
use stm32f4xx_hal::gpio::{PinSpeed as _, Speed};
use stm32f4xx_hal::pac::SPI1;
use stm32f4xx_hal::rcc::Rcc;
use stm32f4xx_hal::spi::{Mode, Phase, Polarity, Spi, SpiExt};
use stm32f4xx_hal::time::Hertz;

use crate::clock_tree::{PinSpeed, SpiBus};
use crate::storage::AbStore;

/// SPI mode 3 (clock idle high, data captured on the second edge), which both sensors accept.
pub const SPI_MODE_3: Mode = Mode {
    polarity: Polarity::IdleHigh,
    phase: Phase::CaptureOnSecondTransition,
};

/// The HAL's name for a table's pin speed.
const fn hal_speed(s: PinSpeed) -> Speed {
    match s {
        PinSpeed::Low => Speed::Low,
        PinSpeed::Medium => Speed::Medium,
        PinSpeed::High => Speed::High,
        PinSpeed::VeryHigh => Speed::VeryHigh,
    }
}

/// SPI1 as a master in mode 3 at the frequency of the board's `bus` table, its pins first set to
/// the table's output speeds (`clock_tree`, where the HAL's resulting clock and the pin speeds are
/// checked at compile time). The boards set up SPI only through this, so no SPI pin is left at its
/// reset speed (low), under which stm32f4xx-hal 0.23 (`src/spi.rs:302-303`) warns of "the 'wrong
/// last bit in every received byte' problem". Logs an error when the HAL's APB2 clock is not the
/// table's (the SPI clock would then not be the one checked).
pub fn spi1(
    spi: SPI1,
    pins: (
        impl Into<spi1::Sck>,
        impl Into<spi1::Miso>,
        impl Into<spi1::Mosi>,
    ),
    bus: &SpiBus,
    rcc: &mut Rcc,
) -> Spi<SPI1> {
    let apb = rcc.clocks.pclk2().raw();
    if apb != bus.apb_hz {
        defmt::error!(
            "APB2 is {=u32} Hz, not {=u32}: the {=str} SPI clock is not {=u32} Hz",
            apb,
            bus.apb_hz,
            bus.device,
            bus.actual_hz()
        );
    }
    let (mut sck, mut miso, mut mosi) = (pins.0.into(), pins.1.into(), pins.2.into());
    sck.set_speed(hal_speed(bus.pins.sck));
    miso.set_speed(hal_speed(bus.pins.miso));
    mosi.set_speed(hal_speed(bus.pins.mosi));
    let freq = Hertz::from_raw(bus.asked_hz);
    spi.spi((Some(sck), Some(miso), Some(mosi)), SPI_MODE_3, freq, rcc)
}

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
