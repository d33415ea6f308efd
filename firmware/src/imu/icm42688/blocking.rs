//! The blocking form over `embedded_hal::spi::SpiDevice`: moves the bytes [`Core`] and the step
//! lists ask for (its text, shared with the async form, is in `form.rs`).

use embedded_hal::spi::{Operation, SpiDevice};

use super::form::{done, driver};
use super::regs::*;
use super::self_test::{self, SelfTestReport, SensorUnderTest};
use super::{
    check_identity, configure_steps, Config, Core, Error, FifoBuffer, Step, BATCH_PACKETS,
    IDENTIFY_READS, IDENTIFY_RETRY_US, POWER_UP_STEPS, RESET_STEPS,
};
use crate::imu::{Drained, ImuSample, ImuSource};

driver!(
    /// ICM-42688-P on a blocking SPI device (mode 0 or 3, up to 24 MHz).
    Icm42688, SpiDevice, ImuSource, [], done
);
