//! The `no_std` core of the accelerometer calibrator, shared by the host calibrator and the firmware.
//!
//! It holds the measurement model of `docs/model.md` and nothing that does I/O or allocates:
//!
//! - [`units`]: the quantities that cross module boundaries, each carrying its unit and frame;
//! - [`params`]: the calibration in the paper's form (Table 1 and Table 3) and in the fitted form
//!   `M = K·A`, with the conversions of `docs/model.md` §4.2;
//! - [`sensor_models`]: the gyro's correction and the temperature model (docs/model.md §8, §9);
//! - [`rng`]: the one random number generator (simulators, Monte Carlo runs, tests), seeded and
//!   the same on every platform;
//! - [`forward`]: the forward model `U = K A f_O + K d + u0` (paper eq. 13–15), used by every simulator;
//! - [`compensator`]: the per-sample inverse model (paper eq. 16, `docs/model.md` §3), the same
//!   bits on the PC and on the Cortex-M4F;
//! - [`omega_dot`]: the filtered angular-acceleration estimator of `docs/model.md` §4.6;
//! - `trig`: `libm::cos` bit for bit without the large-argument reduction (installation angles);
//! - [`blob`]: the versioned, CRC-protected parameter blob written to the device;
//! - [`wire`]: the host↔device messages and their COBS framing;
//! - [`chain`] (with `std` only, as it allocates): an error and its causes as one line, how every
//!   crate above renders an error for a person.
#![cfg_attr(not(any(test, feature = "std")), no_std)]
#![deny(missing_docs)]

pub mod blob;
#[cfg(feature = "std")]
pub mod chain;
pub mod compensator;
pub mod forward;
pub mod linalg;
pub mod omega_dot;
pub mod params;
pub mod rng;
pub mod sensor_models;
pub(crate) mod trig;
pub mod units;
pub mod wire;

pub use compensator::{Compensator, LeverMode, TemperatureState};
pub use params::{Calibration, FittedStatic, LeverArms, OutputUnit, ReferencePoint, StaticParams};
pub use sensor_models::{GyroCorrection, TemperatureModel};
pub use units::{BodyAngularAccel, BodyRate, BodySpecificForce, SensorOutputs, UnitId};

/// Standard gravity (m/s²), the default when the user gives no local value (`docs/model.md` §5).
pub const STANDARD_GRAVITY_M_S2: f64 = 9.80665;
