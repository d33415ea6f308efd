//! Board glue (target only): each board wires its peripherals to the crate's traits.

use core::cell::RefCell;
use cortex_m::interrupt::Mutex;
use shared::wire::DeviceToHost;

use crate::pipeline::{Pipeline, PipelineCommand};
use crate::protocol::PipelineAccess;

#[cfg(feature = "board-qemu")]
pub mod cmsdk_uart;
#[cfg(feature = "board-qemu")]
pub mod qemu;
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
