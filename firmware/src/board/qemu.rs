//! The QEMU mps2-an386 board: CMSDK UART0, the virtual sensor seen through an ICM-42688-P
//! register model and its driver (sampled from SysTick), and the calibration store on a RAM region
//! outside the ELF image.
//!
//! The virtual IMU: each SysTick lets 1 ms of the model's time pass (one 1 kHz sample of the
//! virtual unit into its FIFO as a 20-bit packet 4); when its INT1 (FIFO watermark, 1 packet) is
//! up, the driver drains the FIFO over the model's SPI and the samples go through the pipeline —
//! the register traffic, FIFO decode and overflow checks of a real board, on the Cortex-M4F.
//!
//! The storage region `CALSTORE` (see `memory-qemu.x`) is a memory region with no output section in
//! it, so it is not part of any loaded ELF segment: QEMU restores loaded segments on a system reset
//! (its "ROM" blobs), but leaves this region alone, so a stored calibration survives
//! `HostToDevice::Reset` (`SCB::sys_reset`) exactly as flash would. It starts as zeros when QEMU
//! starts (no valid record: uncalibrated).

use embedded_storage::nor_flash::{ErrorType, NorFlash, ReadNorFlash};
use shared::wire::Board;
use shared::LeverMode;
use shared::OutputUnit;

use crate::imu::icm42688::Icm42688;
use crate::imu::sim::Icm42688Model;
use crate::imu::{ImuSample, ImuSource};
use crate::paper_unit::QEMU_UNIT_ID;
use crate::pipeline::Pipeline;
use crate::pipeline::PipelineFeed;
use crate::protocol::DeviceInfo;
use crate::storage::{AbStore, RamNorFlash};
use crate::virtual_sensor::{VirtualSensor, IMU_CONFIG};

extern "C" {
    /// cortex-m-rt's default interrupt handler (its link script provides it).
    fn DefaultHandler();
}

/// The device part of the vector table: mps2-an386's 32 interrupt lines (QEMU's `num-irq` for the
/// board), all to the default handler, since the board enables none (SysTick is a core
/// exception). cortex-m-rt's generic table has 240 entries: 832 bytes of flash more.
#[link_section = ".vector_table.interrupts"]
#[no_mangle]
#[used]
pub static __INTERRUPTS: [unsafe extern "C" fn(); 32] = [DefaultHandler; 32];

/// Sampling rate of the virtual sensor, Hz (SysTick at 25 MHz / 25 000).
pub const SAMPLE_RATE_HZ: u32 = 1000;
/// Core clock of mps2-an386 (SysTick's processor clock), Hz.
pub const CORE_CLOCK_HZ: u32 = 25_000_000;
/// Output queue length, frames.
pub const OUTPUT_QUEUE: usize = 16;
/// Erase block of the RAM "flash": the STM32 boards' store slot (`flash_layout::SLOT_SIZE`, one
/// 16 KiB sector), so all boards use the same layout.
pub const ERASE_SIZE: usize = crate::flash_layout::SLOT_SIZE as usize;
/// Lever-arm mode at boot.
pub const BOOT_LEVER_MODE: LeverMode = LeverMode::RateAndAcceleration;

/// What `Identify` reports.
pub const INFO: DeviceInfo = DeviceInfo {
    unit_id: QEMU_UNIT_ID,
    board: Board::QemuMps2An386,
    sample_rate_hz: SAMPLE_RATE_HZ,
    virtual_table: true,
    // The virtual sensor is the paper's analog unit (its IMU path scales counts back to volts).
    output_unit: OutputUnit::Volts,
};

extern "C" {
    static mut _calstore_start: u8;
    static _calstore_end: u8;
}

/// The board's calibration store.
pub type Store = AbStore<RamNorFlash<'static, ERASE_SIZE>>;

/// The A/B store over the `CALSTORE` region.
///
/// # Safety
/// Call once: the store owns the region.
pub unsafe fn store() -> Option<Store> {
    let start = core::ptr::addr_of_mut!(_calstore_start);
    let len = core::ptr::addr_of!(_calstore_end) as usize - start as usize;
    // SAFETY: the linker script reserves this region for us; nothing else is placed there.
    let mem = unsafe { core::slice::from_raw_parts_mut(start, len) };
    AbStore::new(RamNorFlash::new(mem), 0, (len / 2) as u32).ok()
}

/// The board's IMU: the virtual unit behind the ICM-42688-P model, through the driver.
pub type Imu = Icm42688<Icm42688Model<VirtualSensor>>;

/// The virtual unit behind a started driver (`None` if the driver refuses it).
pub fn imu(sensor: VirtualSensor) -> Option<Imu> {
    Icm42688::new(Icm42688Model::new(sensor), IMU_CONFIG).ok()
}

/// One sample period: 1 ms of the part's time, then, when INT1 is up, the FIFO drained into the
/// pipeline. Returns the samples passed on; a driver error (a corrupt FIFO, flushed) loses the
/// batch, and the next sample is flagged as following lost data.
pub fn sample_period<const Q: usize>(
    imu: &mut Imu,
    feed: &mut PipelineFeed,
    pipeline: &mut Pipeline<Q>,
) -> usize {
    imu.device_mut()
        .advance_ns(1_000_000_000 / u64::from(SAMPLE_RATE_HZ));
    let mut buf = [ImuSample::default(); 4];
    let mut n = 0;
    if !imu.device_mut().int1() {
        return 0;
    }
    // The status read clears INT1: drain until the FIFO says it is empty.
    while let Ok(d) = imu.drain(&mut buf) {
        feed.push_all(&buf[..d.samples], pipeline);
        n += d.samples;
        if !d.more || d.samples == 0 {
            break;
        }
    }
    n
}

/// How long the STM32 boards' flash stalls the CPU for a store slot's erase, ms: its longest
/// (`flash_layout::SLOT_ERASE_MAX_MS`, DS8626's t_ERASE16KB at 32-bit parallelism).
pub const SECTOR_ERASE_STALL_MS: u32 = crate::flash_layout::SLOT_ERASE_MAX_MS;

/// Milliseconds a [`StallingFlash`] stalled the CPU and no sampling interrupt has caught up with
/// yet: the part's own clock ran on, so the next sample period lets that much more of the model's
/// time pass (and its FIFO overflow, as a real part's would).
pub static STALLED_MS: core::sync::atomic::AtomicU32 = core::sync::atomic::AtomicU32::new(0);

/// Erases done by a [`StallingFlash`].
pub static FLASH_ERASES: core::sync::atomic::AtomicU32 = core::sync::atomic::AtomicU32::new(0);

/// Flash operations done in handler mode (an interrupt or exception) by a [`StallingFlash`].
pub static FLASH_OPS_IN_HANDLER: core::sync::atomic::AtomicU32 =
    core::sync::atomic::AtomicU32::new(0);

/// The QEMU model of a single-bank STM32F4's flash timing over a RAM flash, for the on-target
/// tests: an erase stalls the CPU — modelled as interrupts masked — for
/// [`SECTOR_ERASE_STALL_MS`] SysTick periods of 1 ms (QEMU's code memory is RAM and never stalls);
/// a program is too short to matter at 1 kHz (16 µs a word) and is not delayed. Every operation
/// made in handler mode is counted in [`FLASH_OPS_IN_HANDLER`].
pub struct StallingFlash<const ERASE: usize>(pub RamNorFlash<'static, ERASE>);

impl<const ERASE: usize> StallingFlash<ERASE> {
    fn count_handler_mode() {
        if cortex_m::peripheral::SCB::vect_active()
            != cortex_m::peripheral::scb::VectActive::ThreadMode
        {
            FLASH_OPS_IN_HANDLER.fetch_add(1, core::sync::atomic::Ordering::Relaxed);
        }
    }
}

impl<const ERASE: usize> ErrorType for StallingFlash<ERASE> {
    type Error = crate::storage::RamFlashError;
}

impl<const ERASE: usize> ReadNorFlash for StallingFlash<ERASE> {
    const READ_SIZE: usize = 1;
    fn read(&mut self, offset: u32, bytes: &mut [u8]) -> Result<(), Self::Error> {
        self.0.read(offset, bytes)
    }
    fn capacity(&self) -> usize {
        self.0.capacity()
    }
}

impl<const ERASE: usize> NorFlash for StallingFlash<ERASE> {
    const WRITE_SIZE: usize = 4;
    const ERASE_SIZE: usize = ERASE;
    fn erase(&mut self, from: u32, to: u32) -> Result<(), Self::Error> {
        Self::count_handler_mode();
        FLASH_ERASES.fetch_add(1, core::sync::atomic::Ordering::Relaxed);
        cortex_m::interrupt::free(|_| {
            // SAFETY: reads of SysTick's control register (which clears its COUNTFLAG); SysTick's
            // own set-up is not changed.
            let csr = || unsafe { (*cortex_m::peripheral::SYST::PTR).csr.read() };
            if csr() & 1 != 0 {
                let mut wraps = 0;
                while wraps < SECTOR_ERASE_STALL_MS {
                    wraps += u32::from(csr() & (1 << 16) != 0);
                }
                STALLED_MS.fetch_add(wraps, core::sync::atomic::Ordering::Relaxed);
            }
            self.0.erase(from, to)
        })
    }
    fn write(&mut self, offset: u32, bytes: &[u8]) -> Result<(), Self::Error> {
        Self::count_handler_mode();
        self.0.write(offset, bytes)
    }
}
