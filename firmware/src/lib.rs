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
//! - [`flash_layout`]: where the STM32 boards keep the image and the store (the store in small
//!   sectors, so its erase stops sampling for at most half a second).
//! - [`boards`]: the flight controllers as data (IMU, bus, pins, IMU rotation, LED, pins never to
//!   touch, crystal), each checked against its Betaflight and ArduPilot board files.
//! - [`clock_start`]: the STM32 boards' clock started without hanging on a missing external
//!   clock (a bounded wait for the HSE, then the HSI).
//! - [`clock_tree`]: the STM32 boards' SPI buses as data (pin speeds; clocks from the HAL's own
//!   divider rules), checked at compile time against the parts' limits.
//! - [`conversion`]: an ADC board's per-sample conversion of the scan's codes and the gyro's words
//!   (Nucleo board).
//! - [`stats`]: window statistics (count, mean, variance) with f32 per sample and f64 per block.
//! - [`virtual_sensor`]: the shared forward model of a unit on a virtual rate table (QEMU board).
//! - [`die_temperature`]: the STM32F4's on-chip temperature sensor, code to °C (Nucleo board).
//! - [`health`]: the error counters and the part's identity the device reports to `Health`.
//! - [`imu`]: digital IMUs read from their FIFO (`ImuSource`): ICM-42688-P and LSM6DSO drivers,
//!   and their register-level models (`imu::sim`, PC tests and the QEMU board).
//! - [`imu_bursts`]: the ICM-42688-P's FIFO read as a chain of DMA bursts (F405 board).
//! - [`link`]: a UART link whose receiver an interrupt drains into a queue (Nucleo board), and the
//!   packet stager of the USB link (F405 board).
//! - [`sampling`]: the sampling tasks' board-independent parts (temperature decimation, ADC scan layout).
//! - [`stack`]: the stack high-water mark by painting.
//! - [`paper_unit`]: the paper's unit (Tables 1 and 3), the QEMU board's virtual unit.
//! - [`testvectors`]: PC-computed compensation vectors, checked bit for bit on the target.
//!
//! The board modules under `board` exist only for `target_os = "none"` with a board feature.
#![cfg_attr(not(test), no_std)]
#![deny(missing_docs)]

pub mod boards;
pub mod clock_start;
pub mod clock_tree;
pub mod conversion;
pub mod die_temperature;
pub mod flash_layout;
#[cfg(feature = "health")]
pub mod health;
pub mod imu;
pub mod imu_bursts;
pub mod link;
pub mod paper_unit;
pub mod pipeline;
pub mod protocol;
pub mod sampling;
pub mod stack;
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

/// A gyro giving its rate words in body axes, converted with the accelerometers' codes
/// ([`conversion::Scaling::convert`]: to rad/s, range ends flagged).
pub trait Gyro {
    /// Why a read failed.
    type Error;
    /// The latest words of x, y, z, each as [`conversion::gyro_word`].
    fn read_words(&mut self) -> Result<[i32; 3], Self::Error>;
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
