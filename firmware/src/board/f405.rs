//! An STM32F405 flight controller built from its description in [`crate::boards`] (IMU and bus,
//! CS and interrupt pins, IMU rotation, LED, pins never to touch, crystal): the SpeedyBee F405 V4
//! (ICM-42688-P, LED PC13, IMU turned CW90) by default, the V5 (the V4's IMU pins, IMU turned
//! CW270, LED PA15, PC13 the 9 V BEC switch: never driven) with feature `speedybee-v5`, the V3
//! (BMI270, LED PC8) with `speedybee-v3`. The facts are checked against Betaflight's and
//! ArduPilot's board files in `boards::tests`.
//!
//! | signal | V4 pin | Betaflight name | use here |
//! |---|---|---|---|
//! | IMU SCK / SDI (MISO) / SDO (MOSI) | PA5 / PA6 / PA7 | `SPI1_SCK_PIN`, `SPI1_SDI_PIN`, `SPI1_SDO_PIN` | SPI1, mode 3, `BOARD.imu_spi` (21 MHz for the ICM-42688-P) |
//! | IMU CS | PA4 | `GYRO_1_CS_PIN` | GPIO, active low |
//! | IMU INT1 | PC4 | `GYRO_1_EXTI_PIN` | EXTI4, rising edge: FIFO watermark |
//! | status LED | `BOARD.led` (V4 PC13, V5 PA15, V3 PC8) | `LED0_PIN` | GPIO, lit when low (see the README for its states) |
//! | USB D− / D+ | PA11 / PA12 | (the F405's OTG FS pins) | USB CDC-ACM, the host link |
//! | crystal | 8 MHz | `SYSTEM_HSE_MHZ 8` | HSE → PLL: 168 MHz core, 48 MHz USB |
//! | IMU mounting | `BOARD.alignment` | `GYRO_1_ALIGN` | every sample rotated into the board's axes ([`IMU_ALIGNMENT`]) |
//!
//! DMA (RM0090 Table 43, DMA2 request mapping): SPI1_RX on DMA2 stream 2 channel 3, SPI1_TX on DMA2
//! stream 3 channel 3. Stream 0 — SPI1_RX's other choice — is left to ADC1, as the board's Betaflight
//! definition assigns it (`ADC1_DMA_OPT 0`).
//!
//! Flash: sector 0 holds the vector table, the 16 KiB sectors 1 and 2 the calibration A/B store,
//! sectors 3 on the code (`memory-f405.x`, [`crate::flash_layout`]).

use shared::wire::{Board, ImuInit, ImuPart as WirePart, ImuStatus};
use shared::OutputUnit;

use crate::boards::{self, BoardDesc};
use crate::imu::alignment::Alignment;
use crate::imu::icm42688::{AccelRange, Config, Odr};

pub use super::stm32_common::store;
use super::stm32_common::unit_id;
use crate::link::PacketStager;
use crate::protocol::DeviceInfo;
use crate::ByteLink;

#[cfg(all(feature = "speedybee-v3", feature = "speedybee-v5"))]
compile_error!("choose one board: `speedybee-v3` or `speedybee-v5` (neither: the V4)");

/// The board this firmware is built for.
#[cfg(feature = "speedybee-v3")]
pub const BOARD: BoardDesc = boards::SPEEDYBEE_F405_V3;
/// The board this firmware is built for.
#[cfg(feature = "speedybee-v5")]
pub const BOARD: BoardDesc = boards::SPEEDYBEE_F405_V5;
/// The board this firmware is built for.
#[cfg(not(any(feature = "speedybee-v3", feature = "speedybee-v5")))]
pub const BOARD: BoardDesc = boards::SPEEDYBEE_F405_V4;

// A description whose LED is a reserved pin, whose pins collide or whose bus is too fast for its
// part does not build.
const _: () = assert!(BOARD.check().is_ok());

/// Core clock, Hz (the F405's maximum; `clock_tree::f405`, where the SPI clock is computed from it
/// and checked against the ICM-42688-P's 24 MHz at compile time: 84 MHz APB2 / 4 = 21 MHz).
pub use crate::clock_tree::f405::SYSCLK_HZ;
/// Crystal, Hz (`SYSTEM_HSE_MHZ 8` on the three boards).
pub const HSE_HZ: u32 = BOARD.hse_hz;
/// The ICM-42688-P's configuration: 8 kHz (its highest rate), ±4 g (0.12 mg per count: hand-held
/// and rate-table motion stay well inside it; a sample beyond it is flagged saturated) and ±2000 °/s
/// (the protocol's table rates reach 30 rad/s ≈ 1720 °/s), 258 Hz anti-alias filters, 16-byte
/// packets, the accelerometer in counts (the calibration's output unit on this board). A watermark of
/// 8 packets: one FIFO read per millisecond, 8 samples each.
pub const IMU_CONFIG: Config = Config {
    odr: Odr::Hz8000,
    accel_range: AccelRange::G4,
    watermark_packets: 8,
    ..Config::DEFAULT
};
/// How the board mounts its IMU (Betaflight's `GYRO_1_ALIGN`: V4 CW90, V5 CW270, V3 none).
/// `burst_done` rotates every sample into the board's
/// axes (x toward the board's arrow, y to its left, z up out of its top) before the pipeline, so
/// the streams and the calibration are in the board's frame, the one the operator sees.
pub const IMU_ALIGNMENT: Alignment = BOARD.alignment;
/// Output queue length, frames.
pub const OUTPUT_QUEUE: usize = 16;
/// USB vendor and product id: pid.codes' test VID/PID for open-source projects
/// (<https://pid.codes/1209/0001/>); a product would register its own PID there.
pub const USB_VID_PID: (u16, u16) = (0x1209, 0x0001);

/// What `Identify` reports.
pub fn info(sample_rate_hz: u32) -> DeviceInfo {
    DeviceInfo {
        unit_id: unit_id(),
        board: Board::Stm32f4,
        sample_rate_hz,
        virtual_table: false,
        // IMU_CONFIG keeps the accelerometer in counts.
        output_unit: OutputUnit::Lsb,
    }
}

/// The part's start for `Health`, from the driver's result.
pub fn imu_status<E>(result: &Result<(), crate::imu::icm42688::Error<E>>) -> ImuStatus {
    use crate::imu::icm42688::Error;
    let (who_am_i, init) = match result {
        Ok(()) => (0x47, ImuInit::Ok),
        Err(Error::WrongDevice(v)) => (*v, ImuInit::WrongDevice),
        Err(Error::Spi(_)) => (0, ImuInit::BusError),
        Err(_) => (0x47, ImuInit::ConfigRejected),
    };
    ImuStatus {
        part: WirePart::Icm42688P,
        who_am_i,
        init,
    }
}

/// The BMI270's configuration on the F405 V3: 1.6 kHz, ±4 g (the driver's default).
pub const BMI270_CONFIG: crate::imu::bmi270::Config = crate::imu::bmi270::Config::DEFAULT;

/// The BMI270's start for `Health`, from the driver's result.
pub fn bmi270_status<E>(result: &Result<(), crate::imu::bmi270::Error<E>>) -> ImuStatus {
    use crate::imu::bmi270::Error;
    let (chip_id, init) = match result {
        Ok(()) => (0x24, ImuInit::Ok),
        Err(Error::WrongDevice(v)) => (*v, ImuInit::WrongDevice),
        Err(Error::Spi(_)) => (0, ImuInit::BusError),
        Err(_) => (0x24, ImuInit::ConfigRejected),
    };
    ImuStatus {
        part: WirePart::Bmi270,
        who_am_i: chip_id,
        init,
    }
}

/// The independent watchdog's period, ms: four times the longest the idle loop may block, a store
/// slot's erase (`flash_layout::SLOT_ERASE_MAX_MS`, 500 ms), which leaves margin for the LSI's
/// spread (17–47 kHz against its nominal 32 kHz, DS8626 Table 35: a period up to 1.5× short).
pub const WATCHDOG_MS: u32 = 4 * crate::flash_layout::SLOT_ERASE_MAX_MS;

/// The unique ID (`unit_id`) as 24 hex digits in `out`.
pub fn unique_id_hex(out: &'static mut [u8; 24]) -> &'static str {
    crate::health::hex_into(&unit_id().0, out)
}

/// USB full-speed bulk packet, bytes.
const USB_PACKET: usize = 64;

/// The CDC-ACM port as the link service's [`ByteLink`]. Outgoing bytes are staged up to a full USB
/// packet ([`PacketStager`]) and handed to the class in one write ([`UsbLink::flush`], after each
/// link-service round). Reads come from the class's own receive buffer, which `UsbDevice::poll`
/// fills.
pub struct UsbLink<'a, B: usb_device::bus::UsbBus> {
    /// The CDC-ACM class.
    pub serial: usbd_serial::SerialPort<'a, B>,
    staged: PacketStager<USB_PACKET>,
}

impl<'a, B: usb_device::bus::UsbBus> UsbLink<'a, B> {
    /// Around the class.
    pub fn new(serial: usbd_serial::SerialPort<'a, B>) -> Self {
        UsbLink {
            serial,
            staged: PacketStager::new(),
        }
    }

    /// Hands the staged bytes to the class (as many as it takes; the rest stay staged).
    pub fn flush(&mut self) {
        let serial = &mut self.serial;
        self.staged.flush(|b| serial.write(b).unwrap_or(0));
    }

    /// Nothing staged and the class's write buffer empty (the last answer is on its way out).
    pub fn is_drained(&mut self) -> bool {
        self.staged.is_empty() && self.serial.flush().is_ok()
    }
}

impl<B: usb_device::bus::UsbBus> ByteLink for UsbLink<'_, B> {
    fn try_read(&mut self) -> Option<u8> {
        let mut b = [0u8; 1];
        matches!(self.serial.read(&mut b), Ok(1)).then_some(b[0])
    }

    fn try_write(&mut self, byte: u8) -> bool {
        let serial = &mut self.serial;
        self.staged.push(byte, |b| serial.write(b).unwrap_or(0))
    }
}

/// The LED pin's GPIO port registers (RM0090 §8.4: GPIOA at 0x4002_0000, one port every 0x400).
const LED_PORT: usize = 0x4002_0000 + 0x400 * BOARD.led.port_index() as usize;
/// GPIOx_MODER, GPIOx_ODR and GPIOx_BSRR offsets (RM0090 §8.4.1, §8.4.6, §8.4.7).
const MODER: usize = 0x00;
const ODR: usize = 0x14;
const BSRR: usize = 0x18;
/// The LED's bit in its port.
const LED_BIT: u32 = 1 << BOARD.led.n;

/// Makes the LED pin (`BOARD.led`, never a reserved pin: `BOARD.check`) a dark push-pull output.
/// Its port's clock must be on (the HAL's `split` of GPIOA and GPIOC, the LED ports of the three
/// boards). Only the LED's own bits are written: the rest of the port belongs to the HAL.
pub fn init_led() {
    set_led(false);
    // SAFETY: read-modify-write of the LED pin's two MODER bits (01: general-purpose output) in
    // init, before any task runs; OTYPER and OSPEEDR keep their reset values (push-pull, low).
    unsafe {
        let moder = (LED_PORT + MODER) as *mut u32;
        let shift = 2 * u32::from(BOARD.led.n);
        let v = core::ptr::read_volatile(moder);
        core::ptr::write_volatile(moder, (v & !(0b11 << shift)) | (0b01 << shift));
    }
}

/// Lights or darkens the status LED with one atomic BSRR write, so the idle loop and the sampling
/// task may both drive it.
pub fn set_led(lit: bool) {
    let low = lit == BOARD.led_lit_low;
    // SAFETY: a BSRR write is atomic and touches only the LED's bit.
    unsafe {
        core::ptr::write_volatile(
            (LED_PORT + BSRR) as *mut u32,
            if low { LED_BIT << 16 } else { LED_BIT },
        )
    };
}

/// Toggles the status LED.
pub fn toggle_led() {
    // SAFETY: a read of the LED port's output register.
    let high = unsafe { core::ptr::read_volatile((LED_PORT + ODR) as *const u32) } & LED_BIT != 0;
    set_led(high == BOARD.led_lit_low);
}

/// The LED's meaning while samples flow (called twice a second by the sampling task): steadily lit
/// when a calibration is applied, blinking at 1 Hz when uncalibrated. Without samples it stays dark,
/// or blinks at 4 Hz when the IMU did not answer at boot (idle loop).
pub fn show_state(calibrated: bool) {
    if calibrated {
        set_led(true);
    } else {
        toggle_led();
    }
}

/// The "1200-baud touch": a host that sets the CDC line coding to 1200 Bd (`stty -F /dev/ttyACM0
/// 1200`) asks for the ST system bootloader (USB DFU), as Arduino's boards do. The protocol's own
/// messages are unchanged.
pub const BOOTLOADER_BAUD: u32 = 1200;

/// Whether the host asked for the bootloader through the line coding.
pub fn bootloader_requested<B: usb_device::bus::UsbBus>(
    serial: &usbd_serial::SerialPort<'_, B>,
) -> bool {
    serial.line_coding().data_rate() == BOOTLOADER_BAUD
}

/// Survives a system reset (not zeroed by cortex-m-rt: `.uninit`): the bootloader request.
#[link_section = ".uninit.BOOTLOADER_REQUEST"]
static mut BOOTLOADER_REQUEST: core::mem::MaybeUninit<u32> = core::mem::MaybeUninit::uninit();
const BOOTLOADER_MAGIC: u32 = 0xB007_10AD;
/// The F405's system memory (ST bootloader, AN2606): its vector table.
const SYSTEM_MEMORY: u32 = 0x1FFF_0000;

/// Marks the request and resets: the next boot jumps to the bootloader from a clean chip (USB off,
/// clocks at reset values), as the bootloader expects.
pub fn reboot_into_bootloader() -> ! {
    // SAFETY: a plain store to a static no other code holds a reference to.
    unsafe {
        core::ptr::addr_of_mut!(BOOTLOADER_REQUEST)
            .write(core::mem::MaybeUninit::new(BOOTLOADER_MAGIC))
    };
    cortex_m::peripheral::SCB::sys_reset()
}

/// First thing at boot: if the previous run asked for the bootloader, clear the request and jump to
/// the ST system bootloader (system memory mapped at 0, its stack pointer and reset vector).
pub fn enter_bootloader_if_requested() {
    let request = core::ptr::addr_of_mut!(BOOTLOADER_REQUEST).cast::<u32>();
    // SAFETY: reads and clears a word of `.uninit` RAM (any value is a valid u32).
    let requested = unsafe {
        let v = core::ptr::read_volatile(request);
        core::ptr::write_volatile(request, 0);
        v == BOOTLOADER_MAGIC
    };
    if !requested {
        return;
    }
    // SAFETY: right after reset no peripheral is in use; SYSCFG's clock and the memory remap are
    // what the bootloader expects (system memory at 0), then control passes to it for good.
    unsafe {
        // No interrupt of this firmware may reach the bootloader: every NVIC line off and not
        // pending (RTIC enables its lines before init), then interrupts globally on, as the
        // bootloader expects after a reset.
        let nvic = &*cortex_m::peripheral::NVIC::PTR;
        for i in 0..nvic.icer.len() {
            nvic.icer[i].write(u32::MAX);
            nvic.icpr[i].write(u32::MAX);
        }
        cortex_m::interrupt::enable();
        let rcc = &*stm32f4xx_hal::pac::RCC::ptr();
        rcc.apb2enr().modify(|_, w| w.syscfgen().set_bit());
        // The clock reaches SYSCFG a few cycles after the enable's write: a dsb before the first
        // access, as the HAL's own enable does (stm32f4xx-hal 0.23 src/rcc/f4/enable.rs:12-13,
        // "erratum 2.1.13 (DM00037591)", the F40x errata's delay after an RCC peripheral clock
        // enable). Without it the MEMRMP write may be lost and the bootloader jump read flash.
        cortex_m::asm::dsb();
        let syscfg = &*stm32f4xx_hal::pac::SYSCFG::ptr();
        syscfg.memrmp().modify(|_, w| w.mem_mode().system_flash());
        cortex_m::asm::bootload(SYSTEM_MEMORY as *const u32)
    }
}

/// SPI1 driven by the CPU between the DMA's bursts: the register check after a stall and the
/// part's start again (`imu::icm42688::check`), after a stall or when the periodic check's burst
/// found a register changed (the chain still holds the bus then). Each byte is written to the data register once
/// the transmit buffer is empty and read back once received, with 8-bit access, as the HAL's own
/// blocking transfer does (stm32f4xx-hal 0.23 `src/spi.rs`, `check_send`, `check_read`,
/// `FrameSize for u8`: `dr8`); the DMA requests SPI1 raises meanwhile go to streams that are
/// off. Every wait is bounded: a bus that never answers is an error, not a hang.
pub struct PolledSpi1;

/// A wait of [`PolledSpi1`] ran out.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct SpiTimeout;

impl embedded_hal::spi::Error for SpiTimeout {
    fn kind(&self) -> embedded_hal::spi::ErrorKind {
        embedded_hal::spi::ErrorKind::Other
    }
}

/// Polls of a status flag before [`SpiTimeout`]: a byte takes 0.4 µs at 21 MHz, a poll a few
/// cycles at 168 MHz.
const SPI_POLLS: u32 = 10_000;

fn poll_until(mut ready: impl FnMut() -> bool) -> Result<(), SpiTimeout> {
    for _ in 0..SPI_POLLS {
        if ready() {
            return Ok(());
        }
    }
    Err(SpiTimeout)
}

impl PolledSpi1 {
    fn exchange(&mut self, out: u8) -> Result<u8, SpiTimeout> {
        // SAFETY: SPI1's registers, used only by the task that holds the bus while no DMA burst
        // runs (the stall task, after the chain was taken over; the completion task, after the
        // check's burst, while the chain holds the bus).
        let spi = unsafe { &*stm32f4xx_hal::pac::SPI1::ptr() };
        poll_until(|| spi.sr().read().txe().bit_is_set())?;
        spi.dr8().write(|w| w.dr().set(out));
        poll_until(|| spi.sr().read().rxne().bit_is_set())?;
        Ok(spi.dr8().read().dr().bits())
    }
}

impl embedded_hal::spi::ErrorType for PolledSpi1 {
    type Error = SpiTimeout;
}

impl embedded_hal::spi::SpiBus for PolledSpi1 {
    fn read(&mut self, words: &mut [u8]) -> Result<(), SpiTimeout> {
        for w in words.iter_mut() {
            *w = self.exchange(0)?;
        }
        Ok(())
    }

    fn write(&mut self, words: &[u8]) -> Result<(), SpiTimeout> {
        for &w in words {
            self.exchange(w)?;
        }
        Ok(())
    }

    fn transfer(&mut self, read: &mut [u8], write: &[u8]) -> Result<(), SpiTimeout> {
        for i in 0..read.len().max(write.len()) {
            let b = self.exchange(write.get(i).copied().unwrap_or(0))?;
            if let Some(r) = read.get_mut(i) {
                *r = b;
            }
        }
        Ok(())
    }

    fn transfer_in_place(&mut self, words: &mut [u8]) -> Result<(), SpiTimeout> {
        for w in words.iter_mut() {
            *w = self.exchange(*w)?;
        }
        Ok(())
    }

    fn flush(&mut self) -> Result<(), SpiTimeout> {
        // SAFETY: as in `exchange`.
        let spi = unsafe { &*stm32f4xx_hal::pac::SPI1::ptr() };
        poll_until(|| spi.sr().read().bsy().bit_is_clear())
    }
}

/// SPI1's two DMA2 streams, programmed per burst (RM0090 §10.5): stream 2 channel 3 receives
/// (peripheral → memory, transfer-complete and transfer-error interrupts), stream 3 channel 3 sends
/// (memory → peripheral, no interrupt: the receive side finishes last). Register-level because a
/// burst's length changes with the FIFO count, while the HAL's `Transfer` takes its length from a
/// fixed buffer type.
pub struct SpiDma {
    _dma: stm32f4xx_hal::dma::StreamsTuple<stm32f4xx_hal::pac::DMA2>,
}

/// Stream 2's flags in LIFCR/LISR: FEIF2, DMEIF2, TEIF2, HTIF2, TCIF2 (bits 16, 18–21).
const STREAM2_FLAGS: u32 = 0x003D_0000;
/// Stream 3's flags: bits 22, 24–27.
const STREAM3_FLAGS: u32 = STREAM2_FLAGS << 6;
const TCIF2: u32 = 1 << 21;
const TEIF2: u32 = 1 << 19;
/// CR: channel 3, memory increment, transfer-complete (and error) interrupt, enable.
const CR_CHSEL3: u32 = 3 << 25;
const CR_MINC: u32 = 1 << 10;
const CR_DIR_M2P: u32 = 0b01 << 6;
const CR_TCIE_TEIE: u32 = (1 << 4) | (1 << 2);
const CR_EN: u32 = 1;
/// Receive at high priority, send at medium: the receiver must never fall behind the sender.
const CR_PL_HIGH: u32 = 0b10 << 16;
const CR_PL_MEDIUM: u32 = 0b01 << 16;

/// SPI1's DMA and the IMU's chip select (PA4 on every SpeedyBee F405), which a burst holds low.
pub type ImuBus = (
    SpiDma,
    stm32f4xx_hal::gpio::PA4<stm32f4xx_hal::gpio::Output<stm32f4xx_hal::gpio::PushPull>>,
);

/// Starts burst `b` on the bus: CS low and both streams started, `rx` its receive buffer. Both
/// F405 binaries' interrupts start their bursts through this (the ICM-42688-P's chain, the
/// BMI270's data-ready frames).
pub fn start_burst(bus: &mut ImuBus, b: crate::imu_bursts::Burst, rx: RxBuf) {
    let (dma, cs) = bus;
    cs.set_low();
    // SAFETY: bursts are at most the buffer's size; `rx` is read only by the completion task after
    // this burst ends, and the commands are statics.
    unsafe { dma.start(&b.tx[..b.len().min(rx.capacity())], rx.ptr()) };
}

/// Hands SPI1 to its DMA streams once the part is started: whatever the start left in the
/// receiver (and its overrun flag) is dropped first, so that the first byte the RX stream moves is
/// the first of a burst. Then SPI1's DMA requests are enabled (`Spi::use_dma().txrx()`).
pub fn spi1_to_dma(spi: stm32f4xx_hal::spi::Spi<stm32f4xx_hal::pac::SPI1>) {
    drain_spi1_receiver();
    let _ = spi.use_dma().txrx();
}

/// Drops whatever is in SPI1's receiver and its overrun flag (RM0090 §28.4.8: OVR clears on a read
/// of DR then SR): at the hand-over to DMA, and before a stalled chain starts again, so that the
/// RX stream's first byte is the burst's first. Only while the bus is idle (CS high).
pub fn drain_spi1_receiver() {
    // SAFETY: two reads of SPI1's data and status registers; the bus is idle.
    unsafe {
        let regs = &*stm32f4xx_hal::pac::SPI1::ptr();
        let _ = regs.dr().read();
        let _ = regs.sr().read();
    }
}

/// How a burst ended.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum BurstEnd {
    /// All bytes received.
    Complete,
    /// The DMA reported a bus error: the chain is abandoned (the next watermark starts again).
    Error,
}

impl SpiDma {
    /// Takes DMA2 (the HAL enables and resets its clock); SPI1's DMA requests must be enabled
    /// (`Spi::use_dma().txrx()`).
    pub fn new(dma: stm32f4xx_hal::dma::StreamsTuple<stm32f4xx_hal::pac::DMA2>) -> Self {
        SpiDma { _dma: dma }
    }

    /// Starts a full-duplex burst: `tx` out of SPI1, as many bytes into `rx`.
    ///
    /// # Safety
    /// `tx` and `rx[..tx.len()]` must stay valid, and `rx` unread and unwritten by the CPU, until
    /// [`Self::finish`] reports the end of this burst.
    pub unsafe fn start(&mut self, tx: &[u8], rx: *mut u8) {
        // SAFETY (whole block): DMA2 streams 2 and 3 belong to this struct (it holds DMA2); SPI1's
        // data register address is fixed.
        unsafe {
            let dma = &*stm32f4xx_hal::pac::DMA2::ptr();
            let dr = (*stm32f4xx_hal::pac::SPI1::ptr()).dr().as_ptr() as u32;
            let len = tx.len() as u32;
            for s in [2usize, 3] {
                dma.st(s).cr().write(|w| w.bits(0));
                while dma.st(s).cr().read().bits() & CR_EN != 0 {}
            }
            dma.lifcr().write(|w| w.bits(STREAM2_FLAGS | STREAM3_FLAGS));
            let rx_st = dma.st(2);
            rx_st.par().write(|w| w.bits(dr));
            rx_st.m0ar().write(|w| w.bits(rx as u32));
            rx_st.ndtr().write(|w| w.bits(len));
            rx_st
                .cr()
                .write(|w| w.bits(CR_CHSEL3 | CR_PL_HIGH | CR_MINC | CR_TCIE_TEIE | CR_EN));
            let tx_st = dma.st(3);
            tx_st.par().write(|w| w.bits(dr));
            tx_st.m0ar().write(|w| w.bits(tx.as_ptr() as u32));
            tx_st.ndtr().write(|w| w.bits(len));
            // Sending starts the clock: only now does the receiver get bytes.
            tx_st
                .cr()
                .write(|w| w.bits(CR_CHSEL3 | CR_PL_MEDIUM | CR_MINC | CR_DIR_M2P | CR_EN));
        }
    }

    /// In the receive stream's interrupt: clears its flags and says how the burst ended (`None`:
    /// a spurious interrupt, the burst is still running).
    pub fn finish(&mut self) -> Option<BurstEnd> {
        // SAFETY: reads and clears DMA2 stream 2/3 flags, which belong to this struct.
        let dma = unsafe { &*stm32f4xx_hal::pac::DMA2::ptr() };
        let flags = dma.lisr().read().bits();
        dma.lifcr()
            .write(|w| unsafe { w.bits(STREAM2_FLAGS | STREAM3_FLAGS) });
        if flags & TEIF2 != 0 {
            Some(BurstEnd::Error)
        } else if flags & TCIF2 != 0 {
            Some(BurstEnd::Complete)
        } else {
            None
        }
    }
}

/// The receive buffer of the bursts, seen through a raw pointer: the DMA writes it between
/// [`SpiDma::start`] and [`SpiDma::finish`], the completion task reads it after.
#[derive(Clone, Copy)]
pub struct RxBuf {
    ptr: *mut u8,
    len: usize,
}

// SAFETY: a pointer to a 'static buffer; who touches it when is the burst protocol above.
unsafe impl Send for RxBuf {}

impl RxBuf {
    /// Over a static buffer (consumed: from now on only the DMA and [`Self::received`] use it).
    pub fn new<const N: usize>(buf: &'static mut [u8; N]) -> Self {
        RxBuf {
            ptr: buf.as_mut_ptr(),
            len: N,
        }
    }

    /// Where the DMA writes.
    pub fn ptr(&self) -> *mut u8 {
        self.ptr
    }

    /// Capacity, bytes.
    pub fn capacity(&self) -> usize {
        self.len
    }

    /// The first `len` bytes received.
    ///
    /// # Safety
    /// Only between a burst's end ([`SpiDma::finish`]) and the next [`SpiDma::start`].
    pub unsafe fn received(&self, len: usize) -> &[u8] {
        core::sync::atomic::compiler_fence(core::sync::atomic::Ordering::Acquire);
        // SAFETY: in bounds; no DMA write is under way (caller's contract).
        unsafe { core::slice::from_raw_parts(self.ptr, len.min(self.len)) }
    }
}
