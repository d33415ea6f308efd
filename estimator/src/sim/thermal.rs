//! The simulated unit's temperature (docs/model.md §9): a thermal chamber following the plan's
//! set-points (soak steps `temp_c`, ramps to `temp_end_c`), the unit's die following the chamber with
//! a first-order lag, the unit's temperature sensor following the die with its own lag, noise and
//! quantisation, and the truth temperature model moving the zero biases and scale factors with the
//! die's temperature.
//!
//! The lags matter because the estimator only sees the sensor: a sensor that lags the die makes a
//! ramp's bias look shifted in temperature, which a soak step (waiting until both settle) avoids.

use super::session::SimulateError;
use crate::unit_file::UnitFile;
use recording::session::SegmentPlan;
use serde::{Deserialize, Serialize};
use shared::rng::Rng;
use shared::sensor_models::{poly_no_constant, TemperatureModel};

/// The chamber temperature before the first set-point, °C.
pub(crate) const ROOM_C: f64 = 25.0;

/// How the unit's temperature is simulated (`[thermal]` in a unit file; every field has a default).
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(default, deny_unknown_fields)]
pub struct ThermalSim {
    /// Time constant of the die following the chamber, s; 0: the die is the chamber.
    pub die_time_constant_s: f64,
    /// Time constant of the temperature sensor following the die, s; 0: no lag.
    pub sensor_lag_s: f64,
    /// White noise of the temperature reading, 1σ, °C.
    pub sensor_noise_c: f64,
    /// Quantisation step of the temperature reading, °C; 0: none.
    pub sensor_quantum_c: f64,
}

impl Default for ThermalSim {
    /// A settled unit (no lag) with a sensor of 0.02 °C noise and 1/16 °C steps (typical of the
    /// digital sensors in MEMS parts).
    fn default() -> Self {
        ThermalSim {
            die_time_constant_s: 0.0,
            sensor_lag_s: 0.0,
            sensor_noise_c: 0.02,
            sensor_quantum_c: 0.0625,
        }
    }
}

impl ThermalSim {
    /// The `[thermal]` table of a unit file, or the defaults.
    pub(crate) fn from_unit_file(unit: &UnitFile) -> Result<ThermalSim, SimulateError> {
        let sim = match unit.other.get("thermal") {
            Some(v) => v
                .clone()
                .try_into()
                .map_err(|e| SimulateError::ThermalTable(Box::new(e)))?,
            None => ThermalSim::default(),
        };
        sim.validate()?;
        Ok(sim)
    }

    /// Every value finite and non-negative.
    pub(crate) fn validate(&self) -> Result<(), SimulateError> {
        let v = [
            self.die_time_constant_s,
            self.sensor_lag_s,
            self.sensor_noise_c,
            self.sensor_quantum_c,
        ];
        if v.iter().all(|x| x.is_finite() && *x >= 0.0) {
            Ok(())
        } else {
            Err(SimulateError::ThermalValues)
        }
    }
}

/// The chamber set-point of `seg` at `t_local_s` into it, or `None` when the segment sets none.
pub(crate) fn chamber_c(seg: &SegmentPlan, t_local_s: f64) -> Option<f64> {
    let start = seg.temp_c?;
    Some(match (seg.temp_end_c, seg.duration_s) {
        (Some(end), Some(d)) if d > 0.0 => start + (end - start) * (t_local_s / d).min(1.0),
        _ => start,
    })
}

/// The chamber, die and sensor temperatures as a session runs.
#[derive(Clone, Debug)]
pub(crate) struct ThermalState {
    sim: ThermalSim,
    chamber_c: f64,
    die_c: f64,
    sensor_c: f64,
    rng: Rng,
}

impl ThermalState {
    /// Everything at the first set-point of the plan (a unit soaked before the session starts), or
    /// at [`ROOM_C`].
    pub fn new(sim: &ThermalSim, first_c: Option<f64>, rng: Rng) -> ThermalState {
        let t = first_c.unwrap_or(ROOM_C);
        ThermalState {
            sim: sim.clone(),
            chamber_c: t,
            die_c: t,
            sensor_c: t,
            rng,
        }
    }

    /// Advances by `dt_s` with the chamber at `chamber_c` (`None`: unchanged); returns the die's
    /// temperature and the sensor's reading, °C.
    pub fn step(&mut self, chamber_c: Option<f64>, dt_s: f64) -> (f64, f64) {
        if let Some(c) = chamber_c {
            self.chamber_c = c;
        }
        let follow = |tau: f64| {
            if tau > 0.0 {
                1.0 - (-dt_s / tau).exp()
            } else {
                1.0
            }
        };
        self.die_c += (self.chamber_c - self.die_c) * follow(self.sim.die_time_constant_s);
        self.sensor_c += (self.die_c - self.sensor_c) * follow(self.sim.sensor_lag_s);
        let mut reading = self.sensor_c;
        if self.sim.sensor_noise_c > 0.0 {
            reading += self.sim.sensor_noise_c * self.rng.normal();
        }
        let q = self.sim.sensor_quantum_c;
        if q > 0.0 {
            reading = (reading / q).round() * q;
        }
        (self.die_c, reading)
    }
}

/// The outputs of a unit whose parameters follow `model` at `die_c`, from its outputs `raw` at the
/// reference temperature (docs/model.md §9): `U(T) = u0 + P(ΔT) + (1 + S(ΔT))·(U_ref − u0)`; the
/// relative scale multiplies every term of row `i` of the forward model, lever-arm terms included.
pub(crate) fn outputs_at(
    model: &TemperatureModel,
    zero_bias_out: &[f64; 3],
    raw: &[f64; 3],
    die_c: f64,
) -> [f64; 3] {
    let dt = die_c - model.reference_c;
    std::array::from_fn(|i| {
        let gain = 1.0 + poly_no_constant(&model.scale_rel_per_c[i], dt);
        zero_bias_out[i]
            + poly_no_constant(&model.zero_bias_out_per_c[i], dt)
            + gain * (raw[i] - zero_bias_out[i])
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    fn seg(temp_c: Option<f64>, temp_end_c: Option<f64>) -> SegmentPlan {
        SegmentPlan {
            name: "s".into(),
            up_b: [0.0, 0.0, 1.0],
            rate_deg_s: 0.0,
            rate_end_deg_s: None,
            duration_s: Some(100.0),
            table_centre_m: None,
            mount: None,
            temp_c,
            temp_end_c,
            ..Default::default()
        }
    }

    #[test]
    fn ramps_and_soaks_follow_the_plan() {
        assert_eq!(chamber_c(&seg(None, None), 10.0), None);
        assert_eq!(chamber_c(&seg(Some(-20.0), None), 10.0), Some(-20.0));
        assert_eq!(chamber_c(&seg(Some(0.0), Some(50.0)), 50.0), Some(25.0));
        assert_eq!(chamber_c(&seg(Some(0.0), Some(50.0)), 150.0), Some(50.0));
    }

    #[test]
    fn die_and_sensor_lag_like_first_order_systems() {
        let sim = ThermalSim {
            die_time_constant_s: 10.0,
            sensor_lag_s: 0.0,
            sensor_noise_c: 0.0,
            sensor_quantum_c: 0.0,
        };
        let mut st = ThermalState::new(&sim, Some(0.0), Rng::new(1, 9));
        let mut die = 0.0;
        for _ in 0..10_000 {
            die = st.step(Some(10.0), 1e-3).0;
        }
        // After one time constant: 1 − 1/e of the step.
        let expected = 10.0 * (1.0 - (-1.0f64).exp());
        assert!((die - expected).abs() < 1e-6, "{die} vs {expected}");
        // A lagging sensor reads below a rising die.
        let sim = ThermalSim {
            sensor_lag_s: 5.0,
            ..sim
        };
        let mut st = ThermalState::new(&sim, Some(0.0), Rng::new(1, 9));
        let (die, reading) = st.step(Some(10.0), 1.0);
        assert!(reading < die && die < 10.0, "{reading} {die}");
    }

    #[test]
    fn readings_are_quantised_and_noisy_around_the_die() {
        let mut st = ThermalState::new(&ThermalSim::default(), Some(40.0), Rng::new(3, 9));
        let readings: Vec<f64> = (0..10_000).map(|_| st.step(None, 1e-3).1).collect();
        assert!(readings.iter().all(|r| (r / 0.0625).fract() == 0.0));
        let mean = readings.iter().sum::<f64>() / readings.len() as f64;
        assert!((mean - 40.0).abs() < 0.01, "{mean}");
        assert!(readings.iter().any(|r| *r != 40.0));
    }

    #[test]
    fn the_truth_model_moves_bias_and_scale_with_the_die() {
        let model = TemperatureModel {
            reference_c: 25.0,
            valid_range_c: [-20.0, 60.0],
            zero_bias_out_per_c: [[1e-3, 0.0, 0.0], [0.0; 3], [0.0; 3]],
            scale_rel_per_c: [[0.0; 3], [1e-4, 0.0, 0.0], [0.0; 3]],
            gyro_bias_rad_s_per_c: None,
        };
        let u0 = [2.0, 2.0, 2.0];
        let raw = [2.5, 2.5, 2.5];
        assert_eq!(outputs_at(&model, &u0, &raw, 25.0), raw);
        let hot = outputs_at(&model, &u0, &raw, 35.0);
        assert!((hot[0] - 2.51).abs() < 1e-12);
        assert!((hot[1] - (2.0 + 0.5 * 1.001)).abs() < 1e-12);
        assert_eq!(hot[2], 2.5);
    }
}
