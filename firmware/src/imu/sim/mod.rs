//! Register-level models of the IMUs as `embedded_hal::spi::SpiDevice`s, written from the parts'
//! datasheets (register map, reset values, WHO_AM_I, FIFO format, watermark and overflow, scaling,
//! self-test response), driven by a [`Generator`] of physical values. `no_std` and allocation-free:
//! the PC tests drive the drivers against them, and the QEMU board presents its virtual sensor to
//! the firmware through them (feature `imu-sim`), so that driver, FIFO decode and pipeline run on
//! the Cortex-M4F as they would on a board.
//!
//! Faults of the bus rather than the part ([`spi_fault`]) wrap any of them.
//!
//! Time: a model produces one sample per output-data-rate period of *its* time, which advances
//! by the `DelayNs` operations it is given and by [`Icm42688Model::advance_ns`] (a board's timer).

pub mod bmi270;
pub mod icm42688;
pub mod lsm6dso;
pub mod spi_fault;

pub use bmi270::Bmi270Model;
pub use icm42688::Icm42688Model;
pub use lsm6dso::Lsm6dsoModel;
pub use spi_fault::LastBitFault;

/// One sample of the physical quantities a part measures.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct Truth {
    /// Specific force along the part's axes, g.
    pub accel_g: [f64; 3],
    /// Angular rate about the part's axes, °/s.
    pub gyro_dps: [f64; 3],
    /// Die temperature, °C.
    pub temp_c: f64,
}

/// What a model samples: the next value at each output-data-rate period.
pub trait Generator {
    /// The quantities at the next sample instant.
    fn next(&mut self) -> Truth;
}

/// An SPI error a model can be told to produce (to test error propagation).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct BusFault;

impl embedded_hal::spi::Error for BusFault {
    fn kind(&self) -> embedded_hal::spi::ErrorKind {
        embedded_hal::spi::ErrorKind::Other
    }
}

/// Round half away from zero and clamp to ±`max` (the parts' ADC behaviour at full scale).
pub(crate) fn quantize(x: f64, max: i32) -> i32 {
    let r = if x >= 0.0 {
        libm::floor(x + 0.5)
    } else {
        -libm::floor(-x + 0.5)
    };
    if r.is_nan() {
        return 0;
    }
    r.clamp(-f64::from(max), f64::from(max)) as i32
}
