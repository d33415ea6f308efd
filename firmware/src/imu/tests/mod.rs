//! Driver tests against the register-level models, one file per feature (as `lsm303agr-rs`'s
//! `tests/`). The expected values are written out here from the datasheets' numbers (sensitivities,
//! register fields, the AAF table), independently of the driver's and the model's code.

mod alignment;
mod bmi270;
mod bmi270_dma;
mod bursts_stall;
mod icm_afsr;
mod icm_configure;
mod icm_errors;
mod icm_fifo_decode;
mod icm_identify;
mod icm_overflow;
mod icm_self_test;
mod icm_spi_errata;
mod icm_watermark;
mod lsm6dso;

use crate::imu::icm42688::{Config, Icm42688};
use crate::imu::sim::{Generator, Icm42688Model, Truth};
use crate::imu::{ImuSample, ImuSource};

/// A deterministic generator covering each range, beyond full scale on accel x and gyro x.
/// `still`: at rest, z up, a small gyro offset, 25 °C (for the self-test).
#[derive(Clone, Default)]
pub struct TestGen {
    k: u32,
    pub still: bool,
}

impl Generator for TestGen {
    fn next(&mut self) -> Truth {
        let k = self.k;
        self.k += 1;
        if self.still {
            return Truth {
                accel_g: [0.0, 0.0, 1.0],
                gyro_dps: [0.5, -0.25, 0.1],
                temp_c: 25.0,
            };
        }
        let f = |m: u32, o: u32| (k.wrapping_mul(m).wrapping_add(o) % 1000) as f64 / 1000.0 - 0.5;
        Truth {
            accel_g: [f(37, 1) * 36.0, f(53, 7) * 3.0, 1.0 + f(71, 3) * 0.1],
            gyro_dps: [f(29, 5) * 4400.0, f(41, 2) * 500.0, f(13, 9) * 10.0],
            temp_c: 25.0 + f(7, 1) * 40.0,
        }
    }
}

/// The first `n` truths the generator gives.
pub fn truths(n: usize) -> Vec<Truth> {
    let mut g = TestGen::default();
    (0..n).map(|_| g.next()).collect()
}

pub type Model = Icm42688Model<TestGen>;

/// A driver started on a fresh model.
pub fn started(cfg: Config) -> Icm42688<Model> {
    Icm42688::new(Icm42688Model::new(TestGen::default()), cfg).expect("driver starts")
}

/// Lets `n` sample periods pass on the part.
pub fn run_samples(imu: &mut Icm42688<Model>, n: u32) {
    let m = imu.device_mut();
    for _ in 0..n {
        let dt = m.until_next_sample_ns();
        m.advance_ns(dt.max(1));
    }
}

/// Drains the FIFO completely.
pub fn drain_all(imu: &mut Icm42688<Model>) -> Vec<ImuSample> {
    let mut all = Vec::new();
    let mut buf = [ImuSample::default(); 7];
    loop {
        let d = imu.drain(&mut buf).expect("drain");
        all.extend_from_slice(&buf[..d.samples]);
        if !d.more {
            return all;
        }
    }
}

/// Round half away from zero, clamp to ±max: the datasheet's quantisation, written for the tests.
pub fn code(x: f64, max: i32) -> i32 {
    (x.round() as i64).clamp(-(max as i64), max as i64) as i32
}
