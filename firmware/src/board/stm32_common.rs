//! What the two STM32F4 boards share: the unit identifier, the internal flash as the calibration
//! store's NOR flash, and the set-up of SPI1 (both boards put their sensor on PA5–PA7). Both chips
//! (F405, F446) have the same first sectors (16 KiB sectors 0–3, where the store lives:
//! [`crate::flash_layout`]) and the unique ID at the same address.

use embedded_storage::nor_flash::{ErrorType, NorFlash, ReadNorFlash};
use shared::units::UnitId;
use stm32f4xx_hal::flash::{Error as FlashError, FlashExt, LockedFlash};
use stm32f4xx_hal::gpio::alt::spi1;
use stm32f4xx_hal::gpio::{PinSpeed as _, Speed};
use stm32f4xx_hal::pac::flash::cr::PSIZE;
use stm32f4xx_hal::pac::FLASH;
use stm32f4xx_hal::pac::SPI1;
use stm32f4xx_hal::rcc::Rcc;
use stm32f4xx_hal::spi::{Mode, Phase, Polarity, Spi, SpiExt};
use stm32f4xx_hal::time::Hertz;

use crate::clock_tree::{PinSpeed, SpiBus};
use crate::flash_layout::{Parallelism, Sector, ERASE_PARALLELISM, SLOT_SIZE, STORE_OFFSET};
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
    const ERASE_SIZE: usize = SLOT_SIZE as usize;

    /// Erases the sectors from `from` to `to` at [`ERASE_PARALLELISM`]. stm32f4xx-hal 0.23 erases at
    /// 8-bit parallelism only (`src/flash.rs:201`), which takes a 16 KiB sector 400 ms typical and
    /// 800 ms at most against 250 and 500 ms at 32-bit (DS8626 Table 40): the slot's erase is the
    /// one time sampling stops, so it is done here, in the reference manual's order (RM0090 §3.6.3,
    /// "Sector Erase": BSY clear, SER and SNB set, then STRT, wait for BSY).
    fn erase(&mut self, from: u32, to: u32) -> Result<(), FlashError> {
        // Unlocked until dropped (the HAL's key sequence, RM0090 §3.5.1).
        let _unlocked = self.0.unlocked();
        // SAFETY: the flash interface's registers, unlocked above and touched by nothing else while
        // this runs (the store is the only writer; the HAL's own operations are not interleaved).
        let regs = unsafe { &*FLASH::ptr() };
        let mut at = from;
        while at < to {
            let sector = Sector::at(at).ok_or(FlashError::ProgrammingSequence)?;
            erase_sector(regs, sector.number)?;
            at = sector.end();
        }
        Ok(())
    }

    fn write(&mut self, offset: u32, bytes: &[u8]) -> Result<(), FlashError> {
        NorFlash::write(&mut self.0.unlocked(), offset, bytes)
    }
}

/// FLASH_CR.PSIZE for a parallelism.
const fn psize(p: Parallelism) -> PSIZE {
    match p {
        Parallelism::X8 => PSIZE::Psize8,
        Parallelism::X16 => PSIZE::Psize16,
        Parallelism::X32 => PSIZE::Psize32,
    }
}

/// One sector erase on the unlocked flash interface; the error flags it raised, as the HAL's error.
fn erase_sector(
    regs: &stm32f4xx_hal::pac::flash::RegisterBlock,
    number: u8,
) -> Result<(), FlashError> {
    while regs.sr().read().bsy().bit_is_set() {}
    // Flags left by an earlier operation would be read as this one's (they clear by writing 1).
    regs.sr().write(|w| {
        w.pgserr().clear_bit_by_one();
        w.pgperr().clear_bit_by_one();
        w.pgaerr().clear_bit_by_one();
        w.wrperr().clear_bit_by_one();
        w.operr().clear_bit_by_one()
    });
    regs.cr().modify(|_, w| {
        w.pg().clear_bit();
        w.psize().variant(psize(ERASE_PARALLELISM));
        // SAFETY: a sector number of this single-bank part (0–11, from the sector table).
        unsafe { w.snb().bits(number) };
        w.ser().set_bit()
    });
    regs.cr().modify(|_, w| w.strt().set_bit());
    while regs.sr().read().bsy().bit_is_set() {}
    regs.cr().modify(|_, w| w.ser().clear_bit());
    let sr = regs.sr().read();
    if sr.pgserr().bit_is_set() {
        Err(FlashError::ProgrammingSequence)
    } else if sr.pgperr().bit_is_set() {
        Err(FlashError::ProgrammingParallelism)
    } else if sr.pgaerr().bit_is_set() {
        Err(FlashError::ProgrammingAlignment)
    } else if sr.wrperr().bit_is_set() {
        Err(FlashError::WriteProtection)
    } else if sr.operr().bit_is_set() {
        Err(FlashError::Operation)
    } else {
        Ok(())
    }
}

/// A board's calibration store.
pub type Store = AbStore<F4Flash>;

/// The A/B store on the 16 KiB sectors 1 and 2 ([`crate::flash_layout`]).
pub fn store(flash: LockedFlash) -> Option<Store> {
    AbStore::new(F4Flash(flash), STORE_OFFSET, SLOT_SIZE).ok()
}
