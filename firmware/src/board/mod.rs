//! Board glue (target only): each board wires its peripherals to the crate's traits.

use core::cell::RefCell;
use cortex_m::interrupt::Mutex;
use shared::wire::DeviceToHost;

use crate::pipeline::{Pipeline, PipelineCommand};
use crate::protocol::PipelineAccess;

#[cfg(feature = "board-qemu")]
pub mod cmsdk_uart;
#[cfg(feature = "board-f405")]
pub mod f405;
#[cfg(feature = "board-f405")]
pub mod f405_service;
#[cfg(feature = "board-qemu")]
pub mod qemu;
#[cfg(any(feature = "board-stm32f4", feature = "board-f405"))]
pub mod stm32_common;
#[cfg(feature = "board-stm32f4")]
pub mod stm32f4;

/// The pipeline shared between the sampling interrupt and the main loop. It holds a reference (to a
/// `cortex_m::singleton!`), so that the static is all zeros and lives in `.bss`, not in flash.
pub type SharedPipeline<const Q: usize> = Mutex<RefCell<Option<&'static mut Pipeline<Q>>>>;

/// The main loop's handle on a [`SharedPipeline`]: each access is one short critical section.
pub struct PipelineHandle<const Q: usize>(pub &'static SharedPipeline<Q>);

impl<const Q: usize> PipelineAccess for PipelineHandle<Q> {
    fn apply(&mut self, cmd: PipelineCommand) {
        cortex_m::interrupt::free(|cs| {
            if let Some(p) = self.0.borrow(cs).borrow_mut().as_mut() {
                p.apply(cmd);
            }
        });
    }

    fn pop_output(&mut self) -> Option<DeviceToHost> {
        cortex_m::interrupt::free(|cs| self.0.borrow(cs).borrow_mut().as_mut()?.pop_output())
    }
}

/// An RTIC shared-resource proxy (or anything with `rtic::Mutex`) over the pipeline, seen by the link
/// service: each access is one lock, which raises the priority ceiling (BASEPRI) to the sampling
/// task's only — higher-priority interrupts (the receive queue, the DMA start) still run.
#[cfg(any(feature = "board-stm32f4", feature = "board-f405"))]
pub struct LockedPipeline<M>(pub M);

#[cfg(any(feature = "board-stm32f4", feature = "board-f405"))]
impl<M, const Q: usize> PipelineAccess for LockedPipeline<M>
where
    M: rtic::Mutex<T = &'static mut Pipeline<Q>>,
{
    fn apply(&mut self, cmd: PipelineCommand) {
        self.0.lock(|p| p.apply(cmd));
    }

    fn pop_output(&mut self) -> Option<DeviceToHost> {
        self.0.lock(|p| p.pop_output())
    }
}

extern "C" {
    /// Lowest address of the stack (cortex-m-rt's `link.x`: the end of `.bss`/`.uninit`).
    static _stack_end: u32;
    /// Highest address of the stack (the initial stack pointer).
    static _stack_start: u32;
}

/// Bytes kept unpainted below the painting function's stack pointer (its own callees' frames).
const PAINT_MARGIN_BYTES: usize = 256;

/// Paints the free part of the stack with [`crate::stack::PAINT`]. Call once, first thing at boot
/// (interrupts still disabled): everything below the current stack pointer is unused.
#[inline(never)]
pub fn paint_stack() {
    let sp: usize;
    // SAFETY: reads the stack pointer, nothing else.
    unsafe { core::arch::asm!("mov {}, sp", out(reg) sp, options(nomem, nostack)) };
    let bottom = core::ptr::addr_of!(_stack_end) as usize;
    let top = (sp - PAINT_MARGIN_BYTES) & !3;
    let words = top.saturating_sub(bottom) / 4;
    crate::stack::paint(words, |i, v| {
        // SAFETY: `bottom + 4i` lies below the stack pointer and above the last static: no live
        // object is there.
        unsafe { core::ptr::write_volatile((bottom as *mut u32).add(i), v) }
    });
}

/// The stack's size and the most of it ever used, bytes (see [`crate::stack::used_bytes`]).
pub fn stack_usage() -> (usize, usize) {
    let bottom = core::ptr::addr_of!(_stack_end) as usize;
    let top = core::ptr::addr_of!(_stack_start) as usize;
    let words = (top - bottom) / 4;
    let used = crate::stack::used_bytes(words, |i| {
        // SAFETY: a word of the stack region; volatile, since interrupts may write it meanwhile.
        unsafe { core::ptr::read_volatile((bottom as *const u32).add(i)) }
    });
    (top - bottom, used)
}

/// Measures the stack and logs the mark over defmt when it grew (`stack high-water mark: N of M
/// bytes`); the STM32 boards call it from their idle loop.
pub fn log_stack_growth(high_water: &mut crate::stack::HighWater) {
    let (size, used) = stack_usage();
    if let Some(mark) = high_water.record(used) {
        defmt::info!(
            "stack high-water mark: {=usize} of {=usize} bytes",
            mark,
            size
        );
    }
}
