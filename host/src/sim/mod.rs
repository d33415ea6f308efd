//! The virtual unit: a known calibration on a virtual rate table, sampled through the shared forward
//! model with a seeded noise model ([`session`], `host simulate`), and its noise-free segment
//! statistics ([`synth`], which backs the Cramér–Rao prediction and the estimator's tests).

pub mod session;
pub mod synth;
#[cfg(test)]
pub(crate) mod testkit;
pub mod thermal;

pub use session::{
    simulate_calibration_to_dir, simulate_rows, simulate_rows_with_temperature, simulate_to_dir,
    simulate_to_dir_with_progress, NoiseModel, Rng, SimulateError, SimulationSummary, TRUTH_FILE,
};
