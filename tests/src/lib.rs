//! Support for the end-to-end tests of host and firmware together (the tests are in `tests/tests/`).

use device::sim::SimDevice;
use device::DeviceClient;
use shared::Calibration;
use std::time::Duration;

/// The paper's unit (the simulated device's truth).
pub fn paper_unit() -> Calibration {
    shared::params::PAPER_UNIT
}

/// A client connected to a fresh simulated device of the paper's unit.
pub fn sim_client() -> DeviceClient<SimDevice> {
    let dev = SimDevice::new(paper_unit()).expect("simulated device boots");
    DeviceClient::new(dev, Duration::from_millis(500))
}

/// Largest |a − b| over the nine entries.
pub fn max_abs_diff(a: &[[f64; 3]; 3], b: &[[f64; 3]; 3]) -> f64 {
    (0..3)
        .flat_map(|i| (0..3).map(move |j| (i, j)))
        .map(|(i, j)| (a[i][j] - b[i][j]).abs())
        .fold(0.0, f64::max)
}

pub mod qemu;
