//! The STM32F446RE Nucleo-64 board: three analog accelerometers on ADC1, an L3GD20H/I3G4250D gyro
//! on SPI1, USART2 to the PC (the ST-LINK virtual COM port), the calibration in flash sectors 6/7.
//!
//! Pin map (Arduino header names in brackets):
//!
//! | signal               | pin  | header | peripheral        |
//! |----------------------|------|--------|-------------------|
//! | accelerometer x out  | PA0  | A0     | ADC1_IN0          |
//! | accelerometer y out  | PA1  | A1     | ADC1_IN1          |
//! | accelerometer z out  | PA4  | A2     | ADC1_IN4          |
//! | gyro SCK             | PA5  | D13    | SPI1_SCK (LD2 shares it) |
//! | gyro SDO (MISO)      | PA6  | D12    | SPI1_MISO         |
//! | gyro SDA (MOSI)      | PA7  | D11    | SPI1_MOSI         |
//! | gyro CS              | PB6  | D10    | GPIO, active low  |
//! | PC link TX / RX      | PA2 / PA3 | (ST-LINK VCP) | USART2, 921 600 Bd, 8N1 |
//!
//! Sampling: TIM2's update interrupt at [`SAMPLE_RATE_HZ`] (1–10 kHz, compile-time) starts three ADC
//! conversions (56-cycle sample time, ~3 µs each at 21 MHz ADC clock) and one 7-byte SPI read, then
//! runs the pipeline. The gyro's output rate is 800 Hz: above that, samples repeat its last value.

use embedded_storage::nor_flash::{ErrorType, NorFlash, ReadNorFlash};
use shared::units::UnitId;
use shared::wire::Board;
use stm32f4xx_hal::flash::{Error as FlashError, FlashExt, LockedFlash};

use crate::protocol::DeviceInfo;
use crate::storage::AbStore;

/// Sampling rate, Hz (1000..=10000; change and rebuild).
pub const SAMPLE_RATE_HZ: u32 = 1000;
const _: () = assert!(SAMPLE_RATE_HZ >= 1000 && SAMPLE_RATE_HZ <= 10_000);
/// Core clock, Hz.
pub const SYSCLK_HZ: u32 = 180_000_000;
/// UART baud rate.
pub const BAUD: u32 = 921_600;
/// Output queue length, frames.
pub const OUTPUT_QUEUE: usize = 16;
/// Flash offset (from 0x0800_0000) of the calibration store: sectors 6 and 7 (see memory.x).
pub const STORE_OFFSET: u32 = 0x4_0000;
/// Size of one store slot: one 128 KiB sector.
pub const SLOT_SIZE: u32 = 0x2_0000;
/// ADC reference voltage (Nucleo: VDDA = 3.3 V).
pub const VREF_V: f32 = 3.3;

/// The chip's 96-bit unique ID (reference manual §39.1), the unit identifier.
pub fn unit_id() -> UnitId {
    let base = 0x1FFF_7A10 as *const u8;
    // SAFETY: the factory-programmed, read-only unique ID area of the STM32F4.
    UnitId(core::array::from_fn(|i| unsafe {
        core::ptr::read_volatile(base.add(i))
    }))
}

/// What `Identify` reports.
pub fn info() -> DeviceInfo {
    DeviceInfo {
        unit_id: unit_id(),
        board: Board::Stm32f4,
        sample_rate_hz: SAMPLE_RATE_HZ,
        virtual_table: false,
    }
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

/// The board's calibration store.
pub type Store = AbStore<F4Flash>;

/// The A/B store on sectors 6 and 7.
pub fn store(flash: LockedFlash) -> Option<Store> {
    AbStore::new(F4Flash(flash), STORE_OFFSET, SLOT_SIZE).ok()
}
