//! The virtual unit: a known calibration on a virtual rate table, sampled through the shared forward
//! model with a seeded noise model ([`session`], `host simulate`), and its noise-free segment
//! statistics ([`synth`], which backs the Cramér–Rao prediction and the estimator's tests), drawn
//! from the one random number generator (`shared::rng`).
//!
//! - [`session`]: the virtual unit on a virtual table, row by row, with the table's and the gyro's
//!   errors, drift and quantisation, with `sensor_noise` (each sample's accelerometer and gyro noise);
//!   [`stats`]: its statistics without writing rows.
//! - [`handheld`]: a hand-held session (`host simulate-hand`); [`thermal`]: temperature profiles and
//!   the unit's thermal model; [`flicker`]: 1/f noise.
//! - For tests (here, and with the feature `testkit` for the crates above): `testkit` (the tests' noisy statistics with table errors, and their plans) and `montecarlo` (the
//!   Monte Carlo runs behind the accuracy figures).

pub mod flicker;
pub mod handheld;
#[cfg(any(test, feature = "testkit"))]
pub mod montecarlo;
mod sensor_noise;
pub mod session;
pub mod stats;
pub mod synth;
#[cfg(any(test, feature = "testkit"))]
pub mod testkit;
pub mod thermal;

pub use session::{
    simulate_calibration_to_dir, simulate_rows, simulate_rows_with_temperature, simulate_to_dir,
    simulate_to_dir_with_progress, NoiseModel, SimulateError, SimulationSummary, TRUTH_FILE,
};
pub use stats::{simulate_stats, simulate_unit_stats};
