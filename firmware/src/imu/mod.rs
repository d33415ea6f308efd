//! The inertial sensors' drivers. Digital IMUs read from their FIFO: what a board's sampling task
//! needs from any of them ([`ImuSource`], [`ImuSourceAsync`]), and the drivers behind it; and the
//! analog-accelerometer board's separate SPI gyro ([`l3gd20h`]), read one sample at a time.
//!
//! - [`alignment`]: how a board mounts its IMU, and each sample rotated into the board's axes.
//! - [`bmi270`]: Bosch BMI270 over SPI: its configuration upload checked by INTERNAL_STATUS,
//!   data-ready reads with time-stamp gap detection, the register check with re-init.
//! - [`icm42688`]: TDK InvenSense ICM-42688-P over SPI (blocking and async), FIFO packets 3 and 4,
//!   watermark interrupt on INT1, overflow detection, self-test.
//! - [`lsm6dso`]: ST LSM6DSO over SPI, its FIFO of tagged words, the same trait.
//! - [`l3gd20h`]: ST L3GD20H / I3G4250D gyro over SPI (the STM32F446 Nucleo board), generic over
//!   `embedded_hal::spi::SpiDevice`, with typed errors.
//! - `sim` (PC tests, and the QEMU board with the `imu-sim` feature): register-level models of
//!   both parts as `SpiDevice`s, fed by a sample generator.
//!
//! A driver hands out [`ImuSample`]s: the accelerometer in the calibration's output unit (the part's
//! LSB counts as `f32`, times the board's [`ImuSample`] unit factor — 1 for a real board, whose
//! calibration is made in counts), the gyro in rad/s in the part's axes (a board turns both into
//! its own axes, the body axes of the calibration, with [`alignment`]), the die temperature in °C and the part's own time stamp. Nothing is lost silently:
//! a sample that follows dropped ones carries [`ImuFlags::DATA_LOST`] and the count, a sample with an
//! axis at its range limit [`ImuFlags::SATURATED`], and a sample the part marked invalid (it does so
//! while a sensor starts) has NaN values and [`ImuFlags::INVALID`], which the pipeline leaves out.

pub mod alignment;
pub mod bmi270;
pub mod icm42688;
pub mod l3gd20h;
pub mod lsm6dso;
#[cfg(any(test, feature = "imu-sim"))]
pub mod sim;
#[cfg(test)]
pub(crate) mod tests;

/// Flags of one [`ImuSample`].
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct ImuFlags(pub u8);

impl ImuFlags {
    /// An accelerometer or gyro axis sat at its full-scale code.
    pub const SATURATED: u8 = 1;
    /// Samples were lost right before this one (FIFO overflow, or a FIFO flushed after a corrupt
    /// read); [`ImuSample::lost_before`] says how many, when the time stamps tell.
    pub const DATA_LOST: u8 = 2;
    /// The part marked a sensor's data invalid (its values are NaN).
    pub const INVALID: u8 = 4;

    /// True when `bit` is set.
    #[inline(always)]
    pub fn has(self, bit: u8) -> bool {
        self.0 & bit != 0
    }
}

/// One decoded sample. Its six values are finite unless [`ImuFlags::INVALID`] is set: the pipeline
/// reads finiteness from the flag, so a sample made by hand with a non-finite value must carry it.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct ImuSample {
    /// Accelerometer, the part's axes, in the calibration's output unit (LSB counts times the
    /// driver's configured unit per LSB).
    pub accel_out: [f32; 3],
    /// Gyro, the part's axes, rad/s.
    pub gyro_rad_s: [f32; 3],
    /// Die temperature, °C.
    pub temp_c: f32,
    /// The part's time stamp of this sample (its own clock, wrapping; ICM-42688-P: µs).
    pub timestamp: u16,
    /// Samples lost right before this one, estimated from the time stamps (0 when none, or when
    /// the loss is known from an overflow flag only; [`ImuFlags::DATA_LOST`] is then still set).
    pub lost_before: u16,
    /// See [`ImuFlags`].
    pub flags: ImuFlags,
}

/// What one drain call did.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct Drained {
    /// Samples written to the front of the output slice.
    pub samples: usize,
    /// The FIFO held more than the slice had room for: call again.
    pub more: bool,
}

/// A digital IMU read from its FIFO (blocking form).
pub trait ImuSource {
    /// Why a drain failed.
    type Error;
    /// Moves decoded samples, oldest first, from the part's FIFO into `out`.
    fn drain(&mut self, out: &mut [ImuSample]) -> Result<Drained, Self::Error>;
    /// The configured output data rate, Hz.
    fn sample_rate_hz(&self) -> u32;
}

/// A digital IMU read from its FIFO (async form, for an executor's sampling task).
#[allow(async_fn_in_trait)] // used with concrete types by a board's task, never as `dyn`
pub trait ImuSourceAsync {
    /// Why a drain failed.
    type Error;
    /// Moves decoded samples, oldest first, from the part's FIFO into `out`.
    async fn drain(&mut self, out: &mut [ImuSample]) -> Result<Drained, Self::Error>;
    /// The configured output data rate, Hz.
    fn sample_rate_hz(&self) -> u32;
}

/// Samples lost between two time stamps `period` ticks apart on a wrapping 16-bit clock: the
/// whole periods beyond the first, rounded to the nearest (0 for consecutive samples). Shared by the
/// drivers' gap detection.
#[inline(always)]
pub(crate) fn lost_between(previous: u16, current: u16, period: u16) -> u16 {
    let dt = current.wrapping_sub(previous);
    // Round dt/period: exact integer arithmetic, no division per sample when dt is one period.
    if dt <= period + period / 2 {
        return 0;
    }
    ((u32::from(dt) + u32::from(period) / 2) / u32::from(period.max(1))).saturating_sub(1) as u16
}
