//! The QEMU mps2-an386 board: CMSDK UART0, the virtual sensor sampled from SysTick, and the
//! calibration store on a RAM region outside the ELF image.
//!
//! The storage region `CALSTORE` (see `memory-qemu.x`) is a memory region with no output section in
//! it, so it is not part of any loaded ELF segment: QEMU restores loaded segments on a system reset
//! (its "ROM" blobs), but leaves this region alone, so a stored calibration survives
//! `HostToDevice::Reset` (`SCB::sys_reset`) exactly as flash would. It starts as zeros when QEMU
//! starts (no valid record: uncalibrated).

use shared::wire::Board;
use shared::LeverMode;

use crate::paper_unit::QEMU_UNIT_ID;
use crate::protocol::DeviceInfo;
use crate::storage::{AbStore, RamNorFlash};

/// Sampling rate of the virtual sensor, Hz (SysTick at 25 MHz / 25 000).
pub const SAMPLE_RATE_HZ: u32 = 1000;
/// Core clock of mps2-an386 (SysTick's processor clock), Hz.
pub const CORE_CLOCK_HZ: u32 = 25_000_000;
/// Output queue length, frames.
pub const OUTPUT_QUEUE: usize = 16;
/// Erase block of the RAM "flash": the STM32F446's 128 KiB sector, so both boards use the same layout.
pub const ERASE_SIZE: usize = 128 * 1024;
/// Lever-arm mode at boot.
pub const BOOT_LEVER_MODE: LeverMode = LeverMode::RateAndAcceleration;

/// What `Identify` reports.
pub const INFO: DeviceInfo = DeviceInfo {
    unit_id: QEMU_UNIT_ID,
    board: Board::QemuMps2An386,
    sample_rate_hz: SAMPLE_RATE_HZ,
    virtual_table: true,
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
