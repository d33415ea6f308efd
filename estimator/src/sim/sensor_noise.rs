//! The simulated sensors' noise (`host simulate`, [`super::session`]): accelerometer white noise, bias
//! random walk, flicker and ADC quantisation; gyro bias, bias random walk, flicker and white noise.
//! Each source draws from its own stream, and only when enabled.

use super::flicker::Flicker;
use super::session::{
    NoiseModel, STREAM_ACCEL, STREAM_FLICKER, STREAM_GYRO, STREAM_GYRO_WALK, STREAM_WALK,
};
use shared::rng::Rng;

/// The sensors' noise sources: each one's size per sample, its own random stream and its running
/// state. A source is drawn from only when enabled, so switching one on or off leaves the others'
/// draws unchanged (the module docs of [`super::session`]).
pub(super) struct SensorNoise {
    /// Accelerometer white noise per sample, output unit, per axis.
    white: [f64; 3],
    /// Accelerometer bias random walk step per sample, output unit, per axis.
    walk: [f64; 3],
    /// ADC quantisation step, output unit (0 = none).
    q: f64,
    /// Gyro white noise per sample, rad/s.
    gyro_sigma: f64,
    /// Fixed gyro bias, rad/s.
    gyro_bias: [f64; 3],
    /// Gyro bias random walk step per sample, rad/s, per axis: an axis draws from the walk's
    /// stream only when its step is above 0.
    gyro_walk: [f64; 3],
    /// Stream of the accelerometer white noise.
    rng_accel: Rng,
    /// Stream of the gyro white noise.
    rng_gyro: Rng,
    /// Stream of the accelerometer bias walk.
    rng_walk: Rng,
    /// Stream shared by the accelerometer's and the gyro's flicker, in that order.
    rng_flicker: Rng,
    /// Stream of the gyro bias walk.
    rng_gyro_walk: Rng,
    /// The accelerometer bias walk so far, per axis.
    drift: [f64; 3],
    /// The gyro bias walk so far, per axis.
    gyro_drift: [f64; 3],
    /// The accelerometer's flicker per axis (empty when off).
    accel_flicker: Vec<Flicker>,
    /// The gyro's flicker per axis (empty when off).
    gyro_flicker: Vec<Flicker>,
}

impl SensorNoise {
    /// The noise of `noise` at sample interval `dt`; `k` is each accelerometer axis's scale factor
    /// (output unit per g), which turns mg into output units.
    pub(super) fn new(noise: &NoiseModel, k: [f64; 3], dt: f64, seed: u64) -> SensorNoise {
        let white: [f64; 3] = k.map(|k| noise.accel_white_mg * 1e-3 * k);
        let walk: [f64; 3] = k.map(|k| noise.accel_bias_walk_mg_sqrt_s * 1e-3 * k * dt.sqrt());
        let mut rng_flicker = Rng::new(seed, STREAM_FLICKER);
        let accel_flicker_b = k.map(|k| noise.accel_flicker_mg * 1e-3 * k);
        let accel_flicker: Vec<Flicker> = (0..3)
            .filter(|_| noise.accel_flicker_mg > 0.0)
            .map(|i| Flicker::new(accel_flicker_b[i], dt, &mut rng_flicker))
            .collect();
        let gyro_flicker_b = noise.gyro_flicker_deg_s.to_radians();
        let gyro_flicker: Vec<Flicker> = (0..3)
            .filter(|_| gyro_flicker_b > 0.0)
            .map(|_| Flicker::new(gyro_flicker_b, dt, &mut rng_flicker))
            .collect();
        SensorNoise {
            white,
            walk,
            q: noise.accel_quantum_out,
            gyro_sigma: noise.gyro_white_deg_s.to_radians(),
            gyro_bias: noise.gyro_bias_deg_s.map(f64::to_radians),
            gyro_walk: noise
                .gyro_bias_walk_axes()
                .map(|k| k.to_radians() * dt.sqrt()),
            rng_accel: Rng::new(seed, STREAM_ACCEL),
            rng_gyro: Rng::new(seed, STREAM_GYRO),
            rng_walk: Rng::new(seed, STREAM_WALK),
            rng_flicker,
            rng_gyro_walk: Rng::new(seed, STREAM_GYRO_WALK),
            drift: [0.0; 3],
            gyro_drift: [0.0; 3],
            accel_flicker,
            gyro_flicker,
        }
    }

    /// Adds the accelerometer's bias walk, flicker and white noise to the outputs `u`, then
    /// quantises them, axis by axis.
    pub(super) fn add_to_accel(&mut self, u: &mut [f64; 3]) {
        for i in 0..3 {
            if self.walk[i] > 0.0 {
                self.drift[i] += self.walk[i] * self.rng_walk.normal();
                u[i] += self.drift[i];
            }
            if let Some(fl) = self.accel_flicker.get_mut(i) {
                u[i] += fl.next(&mut self.rng_flicker);
            }
            if self.white[i] > 0.0 {
                u[i] += self.white[i] * self.rng_accel.normal();
            }
            if self.q > 0.0 {
                u[i] = (u[i] / self.q).round() * self.q;
            }
        }
    }

    /// Adds the gyro's bias (fixed plus `thermal_bias`), bias walk, flicker and white noise to the
    /// rates `w`, axis by axis.
    pub(super) fn add_to_gyro(&mut self, w: &mut [f64; 3], thermal_bias: &[f64; 3]) {
        for i in 0..3 {
            w[i] += self.gyro_bias[i] + thermal_bias[i];
            if self.gyro_walk[i] > 0.0 {
                self.gyro_drift[i] += self.gyro_walk[i] * self.rng_gyro_walk.normal();
                w[i] += self.gyro_drift[i];
            }
            if let Some(fl) = self.gyro_flicker.get_mut(i) {
                w[i] += fl.next(&mut self.rng_flicker);
            }
            if self.gyro_sigma > 0.0 {
                w[i] += self.gyro_sigma * self.rng_gyro.normal();
            }
        }
    }
}
