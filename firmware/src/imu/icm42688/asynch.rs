//! The async form over `embedded_hal_async::spi::SpiDevice` (a DMA-driven SPI under an executor):
//! the blocking form's byte moves with `.await` (their one text is in `form.rs`); [`Core`] and the
//! step lists decide everything.

use embedded_hal_async::spi::{Operation, SpiDevice};

use super::form::{awaited, driver};
use super::regs::*;
use super::self_test::{self, SelfTestReport, SensorUnderTest};
use super::{
    check_identity, configure_steps, Config, Core, Error, FifoBuffer, Step, BATCH_PACKETS,
    IDENTIFY_READS, IDENTIFY_RETRY_US, POWER_UP_STEPS, RESET_STEPS,
};
use crate::imu::{Drained, ImuSample, ImuSourceAsync};

driver!(
    /// ICM-42688-P on an async SPI device (mode 0 or 3, up to 24 MHz).
    Icm42688Async, SpiDevice, ImuSourceAsync, [async], awaited
);
