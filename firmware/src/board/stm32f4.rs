//! The STM32F446RE Nucleo-64 board: three analog accelerometers on ADC1, an L3GD20H/I3G4250D gyro
//! on SPI1, USART2 to the PC (the ST-LINK virtual COM port), the calibration in the 16 KiB flash sectors 1 and 2 (`crate::flash_layout`).
//!
//! Pin map (Arduino header names in brackets):
//!
//! | signal               | pin  | header | peripheral        |
//! |----------------------|------|--------|-------------------|
//! | accelerometer x out  | PA0  | A0     | ADC1_IN0          |
//! | accelerometer y out  | PA1  | A1     | ADC1_IN1          |
//! | accelerometer z out  | PA4  | A2     | ADC1_IN4          |
//! | gyro SCK             | PA5  | D13    | SPI1_SCK, 5.625 MHz (LD2 shares it) |
//! | gyro SDO (MISO)      | PA6  | D12    | SPI1_MISO         |
//! | gyro SDA (MOSI)      | PA7  | D11    | SPI1_MOSI         |
//! | gyro CS              | PB6  | D10    | GPIO, active low  |
//! | PC link TX / RX      | PA2 / PA3 | (ST-LINK VCP) | USART2, 921 600 Bd, 8N1 |
//!
//! Sampling (RTIC 2, see `src/bin/stm32f4.rs` and the README): TIM2's update event (TRGO) triggers
//! one ADC1 scan — the three accelerometers (56-cycle sample time) and the on-chip temperature sensor
//! (480 cycles, ≥ 10 µs as the datasheet asks) — which DMA2 stream 0 (channel 0) moves to memory as
//! 32-bit words ([`AdcWords`]); the stream's transfer-complete interrupt takes the analog watchdog's
//! range-end flag ([`take_watchdog_flag`]), reads the gyro (7 bytes on SPI1), converts the sample
//! (`firmware::conversion`) and runs the pipeline. The gyro's output rate is 800 Hz: above that,
//! samples repeat its last value.
//!
//! ADC clock, from the clock tree: HSE 8 MHz → PLL → SYSCLK 180 MHz; APB2 is limited to 90 MHz, so
//! PCLK2 = 180 / 2 = 90 MHz ([`PCLK2_HZ`], asked of the HAL and checked at boot); the ADC prescaler
//! (ADC_CCR.ADCPRE) divides it by 4: 22.5 MHz ([`ADC_CLOCK_HZ`]), within the STM32F446's 36 MHz limit
//! (datasheet DS10693, ADC characteristics, f_ADC at V_DDA 2.4–3.6 V). The HAL's default prescaler
//! (÷2) would give 45 MHz. One scan: 3 × (56 + 12) + (480 + 12) = 696 ADC cycles = 30.9 µs.

use shared::wire::Board;
use shared::OutputUnit;
use stm32f4xx_hal::adc::Adc;
use stm32f4xx_hal::dma::traits::{DMASet, PeriAddress};
use stm32f4xx_hal::dma::{PeripheralToMemory, Stream0};
use stm32f4xx_hal::pac::{ADC1, DMA2};

pub use super::stm32_common::store;
use super::stm32_common::unit_id;
use crate::conversion::{adc_sr_clear, ADC_SR_AWD};
use crate::protocol::DeviceInfo;

// The clock tree, the ADC clock and the UART's baud rate, computed and checked against their
// limits at compile time in `clock_tree::nucleo` (with the gyro's SPI clock).
pub use crate::clock_tree::nucleo::{
    ADC_CLOCK_HZ, ADC_CLOCK_MAX_HZ, ADC_PRESCALER, BAUD, PCLK2_HZ, SYSCLK_HZ,
};

/// Sampling rate, Hz: the gyro's output data rate, so that each ADC scan reads one new gyro sample
/// (at 1 kHz against its 800 Hz, one read in five repeated the previous sample).
pub const SAMPLE_RATE_HZ: u32 = crate::imu::l3gd20h::ODR_HZ;
const _: () = assert!(SAMPLE_RATE_HZ >= 100 && SAMPLE_RATE_HZ <= 10_000);
/// ADC cycles of one scan: three accelerometers at 56 + 12, the temperature sensor at 480 + 12.
pub const SCAN_ADC_CYCLES: u32 = 3 * (56 + 12) + (480 + 12);
// The scan must finish well within a sample period (here: half of it).
const _: () = assert!(SCAN_ADC_CYCLES as u64 * SAMPLE_RATE_HZ as u64 * 2 <= ADC_CLOCK_HZ as u64);
/// What `Health` reports of the part: analog accelerometers on the ADC, no identity register
/// (their outputs are volts: no counts per g).
pub const ANALOG_ACCELEROMETERS: shared::wire::ImuStatus = shared::wire::ImuStatus {
    part: shared::wire::ImuPart::Analog,
    who_am_i: 0,
    init: shared::wire::ImuInit::NotApplicable,
};
/// Output queue length, frames.
pub const OUTPUT_QUEUE: usize = 16;
/// ADC reference voltage (Nucleo: VDDA = 3.3 V).
pub const VREF_V: f32 = 3.3;

/// Largest code of the 12-bit ADC.
pub const ADC_MAX: u16 = 4095;

/// ADC1 as the scan's DMA source of 32-bit words: the stream reads ADC_DR as words (PSIZE = MSIZE
/// = 32 bits), whose upper half is zero in independent mode, so the conversion loads the codes
/// with one instruction (`firmware::conversion`). The HAL's own `Adc` transfers half-words.
pub struct AdcWords(pub Adc<ADC1>);

// SAFETY: the address is ADC1's data register, read by the stream as the 32-bit register it is.
unsafe impl PeriAddress for AdcWords {
    type MemSize = u32;
    fn address(&self) -> u32 {
        self.0.data_register_address()
    }
}

// SAFETY: DMA2 stream 0, channel 0 is ADC1's request (RM0390, DMA2 request mapping), as for the
// HAL's `Adc`.
unsafe impl DMASet<Stream0<DMA2>, 0, PeripheralToMemory> for AdcWords {}

/// Guards every regular channel of ADC1 with its analog watchdog at the thresholds that flag
/// exactly a code at 0 or at [`ADC_MAX`] (`firmware::conversion::watchdog_thresholds`); the flag is
/// read and cleared once per scan by [`take_watchdog_flag`]. No interrupt: the scan's task polls.
/// Called once while the scan is set up.
pub fn guard_range_ends() {
    // SAFETY: only ADC1's watchdog thresholds and enables, which the HAL never touches.
    let adc = unsafe { &*ADC1::ptr() };
    let (low, high) = crate::conversion::watchdog_thresholds(ADC_MAX);
    adc.ltr().write(|w| w.lt().set(low));
    adc.htr().write(|w| w.ht().set(high));
    adc.cr1()
        .modify(|_, w| w.awdsgl().clear_bit().awden().set_bit().awdie().clear_bit());
}

/// Whether ADC1's watchdog saw a code at either end since the last call, clearing its flag. One
/// load per scan; the store only when it was set.
#[inline(always)]
pub fn take_watchdog_flag() -> bool {
    // SAFETY: reads ADC1's status register and clears only its watchdog bit (its bits are cleared
    // by writing 0; a 1 leaves them as they are). The HAL never touches that bit.
    let adc = unsafe { &*ADC1::ptr() };
    let set = adc.sr().read().bits() & ADC_SR_AWD != 0;
    if set {
        clear_adc_flags(ADC_SR_AWD);
    }
    set
}

/// Clears ADC1's status `flags` (`firmware::conversion::ADC_SR_*`) with one write of
/// [`adc_sr_clear`], never a read-modify-write, which would also clear a flag raised between
/// its read and its write.
#[inline(always)]
pub fn clear_adc_flags(flags: u32) {
    // SAFETY: one write to ADC1's status register: 0 at `flags`, 1 (no effect) at the other flags,
    // 0 at the reserved bits.
    let adc = unsafe { &*ADC1::ptr() };
    adc.sr().write(|w| unsafe { w.bits(adc_sr_clear(flags)) });
}

/// What `Identify` reports.
pub fn info() -> DeviceInfo {
    DeviceInfo {
        unit_id: unit_id(),
        board: Board::Stm32f4,
        sample_rate_hz: SAMPLE_RATE_HZ,
        virtual_table: false,
        output_unit: OutputUnit::Volts,
    }
}
