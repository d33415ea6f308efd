//! Device-agnostic firmware logic of the accelerometer calibrator.
//!
//! Everything here is `no_std`, allocation-free and compiles (and is unit-tested) on the PC; a board
//! only wires its peripherals to the small traits below and calls into these modules:
//!
//! - [`pipeline`]: the per-sample path — ω̇ estimate, compensation, window statistics, output queue.
//!   It runs at sampling priority (an interrupt) and never touches the link.
//! - [`protocol`]: frame reception, the request handler ([`protocol::Controller`]) and the link
//!   service that moves queued frames to the link without blocking.
//! - [`storage`]: the A/B parameter store on any `embedded-storage` NOR flash (power-cut safe).
//! - [`stats`]: window statistics (count, mean, variance) with f32 per sample and f64 per block.
//! - [`virtual_sensor`]: the shared forward model of a unit on a virtual rate table (QEMU board).
//! - [`die_temperature`]: the STM32F4's on-chip temperature sensor, code to °C (Nucleo board).
//! - [`gyro`]: an SPI gyro driver generic over `embedded_hal::spi::SpiDevice` (STM32 board).
//! - [`imu`]: digital IMUs read from their FIFO (`ImuSource`): ICM-42688-P and LSM6DSO drivers,
//!   and their register-level models (`imu::sim`, PC tests and the QEMU board).
//! - [`paper_unit`]: the paper's unit (Tables 1 and 3), the QEMU board's virtual unit.
//! - [`testvectors`]: PC-computed compensation vectors, checked bit for bit on the target.
//!
//! The board modules under [`board`] exist only for `target_os = "none"` with a board feature.
#![cfg_attr(not(test), no_std)]
#![deny(missing_docs)]

pub mod die_temperature;
pub mod gyro;
pub mod imu;
pub mod paper_unit;
pub mod pipeline;
pub mod protocol;
pub mod stats;
pub mod storage;
pub mod testvectors;
pub mod virtual_sensor;

#[cfg(target_os = "none")]
pub mod board;

pub use pipeline::{Pipeline, Sample};
pub use protocol::{BoardEvent, Controller, DeviceInfo, LinkService};
pub use storage::{AbStore, CalStore, RamNorFlash, StoreError};

/// Firmware version reported by `Identify` (major, minor, patch).
pub const FIRMWARE_VERSION: [u8; 3] = [0, 1, 0];

/// A source of the three accelerometer outputs, in the calibration's output unit.
pub trait AccelSource {
    /// The latest outputs (V or LSB) and whether any channel sat at its range limit.
    fn read_outputs(&mut self) -> ([f32; 3], bool);
}

/// A gyro giving the body rate, rad/s, in body axes.
pub trait Gyro {
    /// Why a read failed.
    type Error;
    /// The latest rate and whether any axis sat at its range limit.
    fn read_rate(&mut self) -> Result<([f32; 3], bool), Self::Error>;
}

/// A free-running tick counter (SysTick, DWT, a timer), for time stamps and cost measurements.
pub trait Clock {
    /// Ticks per second.
    const HZ: u32;
    /// Current tick count (wrapping).
    fn ticks(&mut self) -> u32;
}

/// A byte link that never blocks: the firmware's view of its UART.
pub trait ByteLink {
    /// One received byte, if any is waiting.
    fn try_read(&mut self) -> Option<u8>;
    /// Sends one byte if the transmitter has room; false when it is full (try again later).
    fn try_write(&mut self, byte: u8) -> bool;
}

/// Any `embedded-io` serial port with readiness queries is a [`ByteLink`].
pub struct EioLink<T>(pub T);

impl<T> ByteLink for EioLink<T>
where
    T: embedded_io::Read + embedded_io::ReadReady + embedded_io::Write + embedded_io::WriteReady,
{
    fn try_read(&mut self) -> Option<u8> {
        if !self.0.read_ready().unwrap_or(false) {
            return None;
        }
        let mut b = [0u8; 1];
        match self.0.read(&mut b) {
            Ok(1) => Some(b[0]),
            _ => None,
        }
    }

    fn try_write(&mut self, byte: u8) -> bool {
        self.0.write_ready().unwrap_or(false) && matches!(self.0.write(&[byte]), Ok(1))
    }
}

/// Any `embedded-hal-nb` serial port (e.g. an `stm32f4xx-hal` USART) is a [`ByteLink`]. Receive
/// errors (overrun, framing) read as "no byte"; the frame they break is answered as malformed.
pub struct NbLink<T>(pub T);

impl<T> ByteLink for NbLink<T>
where
    T: embedded_hal_nb::serial::Read<u8> + embedded_hal_nb::serial::Write<u8>,
{
    fn try_read(&mut self) -> Option<u8> {
        self.0.read().ok()
    }

    fn try_write(&mut self, byte: u8) -> bool {
        self.0.write(byte).is_ok()
    }
}

/// Reads one [`Sample`] from an accelerometer source and a gyro. A failed gyro read gives a
/// non-finite rate, so the sample is flagged and left out of the statistics (never a panic).
#[inline]
pub fn read_sample<A: AccelSource, G: Gyro>(accel: &mut A, gyro: &mut G) -> Sample {
    let (raw, sat_a) = accel.read_outputs();
    let (rate_rad_s, sat_g) = gyro.read_rate().unwrap_or(([f32::NAN; 3], false));
    Sample {
        raw,
        rate_rad_s,
        saturated: sat_a || sat_g,
    }
}
