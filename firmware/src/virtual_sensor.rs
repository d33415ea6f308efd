//! The QEMU board's virtual sensor: the shared forward model ([`shared::forward::ForwardModel`]) of a
//! unit on a virtual single-axis rate table whose attitude, rate and angular acceleration the host
//! sets (`HostToDevice::SetVirtualTable`). Sampled at a fixed rate, it gives the outputs (V) and the
//! gyro rate (rad/s) with small deterministic noise, saturating like real parts.
//!
//! The table turns about the vertical, so "up" is constant in body axes and `ω = rate(t)·up` with
//! `rate(t) = rate₀ + α·t`, t counted in samples since the table was set (virtual time).
//!
//! Temperature (docs/model.md §9): the unit sits in a virtual chamber whose temperature the board
//! sets ([`VirtualSensor::set_ambient_c`], "heating in software"); the die follows it with a
//! first-order lag of [`DIE_TIME_CONSTANT_S`], the unit's temperature sensor reads the die, and a
//! calibration with a temperature model moves the outputs' biases and scale factors with the die.

use shared::forward::{ForwardModel, TableState};
use shared::sensor_models::{poly_no_constant, TemperatureModel, TEMPERATURE_LIMITS_C};
use shared::wire::VirtualTable;
use shared::Calibration;

use crate::pipeline::Sample;

/// Output range of the virtual accelerometers, volts (a 0–5 V analog part).
pub const OUTPUT_RANGE_V: (f32, f32) = (0.0, 5.0);
/// Gyro range, rad/s (±2000 °/s).
pub const GYRO_RANGE_RAD_S: f32 = 34.9;
/// Standard deviation of the output noise, volts (≈ 0.5 mg at 0.4 V/g).
pub const OUTPUT_NOISE_V: f32 = 2.0e-4;
/// Standard deviation of the gyro noise, rad/s (≈ 0.06 °/s).
pub const GYRO_NOISE_RAD_S: f32 = 1.0e-3;
/// Largest table rate accepted, rad/s (the rate ramp is clamped here too).
pub const MAX_TABLE_RATE_RAD_S: f32 = 30.0;
/// Time constant of the die following the chamber, s.
pub const DIE_TIME_CONSTANT_S: f64 = 2.0;
/// The chamber's temperature at start, °C.
pub const START_TEMPERATURE_C: f32 = 25.0;

/// A unit on a virtual rate table.
pub struct VirtualSensor {
    model: ForwardModel,
    table: VirtualTable,
    samples_since_set: u32,
    sample_period_s: f64,
    noise_state: u32,
    noise_on: bool,
    thermal: Option<TemperatureModel>,
    ambient_c: f64,
    die_c: f64,
    /// Fraction of the chamber–die difference the die closes per sample.
    die_follow: f64,
}

/// Why a table setting was refused.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct BadTable;

impl VirtualSensor {
    /// The unit `cal` at rest with z up, sampled at `sample_rate_hz`; `None` if `cal` is unusable.
    pub fn new(cal: &Calibration, sample_rate_hz: u32, noise: bool) -> Option<Self> {
        let model = ForwardModel::new(cal).ok()?;
        let period_s = 1.0 / f64::from(sample_rate_hz.max(1));
        Some(VirtualSensor {
            thermal: cal.temperature,
            ambient_c: f64::from(START_TEMPERATURE_C),
            die_c: f64::from(START_TEMPERATURE_C),
            die_follow: (period_s / DIE_TIME_CONSTANT_S).min(1.0),
            model,
            table: VirtualTable {
                up_b: [0.0, 0.0, 1.0],
                rate_rad_s: 0.0,
                accel_rad_s2: 0.0,
            },
            samples_since_set: 0,
            sample_period_s: 1.0 / f64::from(sample_rate_hz.max(1)),
            noise_state: 0x1234_5678,
            noise_on: noise,
        })
    }

    /// Checks and normalises a table setting: `up_b` finite and not zero, rates finite and bounded.
    pub fn check_table(t: &VirtualTable) -> Result<VirtualTable, BadTable> {
        let u = t.up_b.map(f64::from);
        let n2 = u[0] * u[0] + u[1] * u[1] + u[2] * u[2];
        let ok = n2.is_finite()
            && n2 > 1e-6
            && t.rate_rad_s.is_finite()
            && t.accel_rad_s2.is_finite()
            && t.rate_rad_s.abs() <= MAX_TABLE_RATE_RAD_S
            && t.accel_rad_s2.abs() <= 1000.0;
        if !ok {
            return Err(BadTable);
        }
        let n = libm::sqrt(n2);
        Ok(VirtualTable {
            up_b: u.map(|v| (v / n) as f32),
            ..*t
        })
    }

    /// Sets the table (time restarts at zero). Refuses a setting [`Self::check_table`] refuses.
    pub fn set_table(&mut self, t: &VirtualTable) -> Result<(), BadTable> {
        self.table = Self::check_table(t)?;
        self.samples_since_set = 0;
        Ok(())
    }

    /// The current table setting.
    pub fn table(&self) -> VirtualTable {
        self.table
    }

    /// Sets the chamber's temperature, °C; the die follows it. Refuses a value outside
    /// [`TEMPERATURE_LIMITS_C`] or not finite.
    pub fn set_ambient_c(&mut self, temp_c: f32) -> Result<(), BadTable> {
        let t = f64::from(temp_c);
        if !(TEMPERATURE_LIMITS_C.0..=TEMPERATURE_LIMITS_C.1).contains(&t) {
            return Err(BadTable);
        }
        self.ambient_c = t;
        Ok(())
    }

    /// The unit's temperature sensor: the die's temperature, °C.
    pub fn temperature_c(&self) -> f32 {
        self.die_c as f32
    }

    fn uniform(&mut self) -> f32 {
        // xorshift32: deterministic, cheap; maps to [-0.5, 0.5).
        let mut x = self.noise_state;
        x ^= x << 13;
        x ^= x >> 17;
        x ^= x << 5;
        self.noise_state = x;
        (x >> 8) as f32 * (1.0 / 16_777_216.0) - 0.5
    }

    /// Approximately Gaussian noise of unit standard deviation (sum of 4 uniforms, scaled by √3).
    fn noise(&mut self) -> f32 {
        if !self.noise_on {
            return 0.0;
        }
        (self.uniform() + self.uniform() + self.uniform() + self.uniform()) * 1.732_050_8
    }

    /// The next sample.
    pub fn sample(&mut self) -> Sample {
        let t = f64::from(self.samples_since_set) * self.sample_period_s;
        self.samples_since_set = self.samples_since_set.saturating_add(1);
        let max = f64::from(MAX_TABLE_RATE_RAD_S);
        let rate = (f64::from(self.table.rate_rad_s) + f64::from(self.table.accel_rad_s2) * t)
            .clamp(-max, max);
        let accel = if rate.abs() >= max {
            0.0
        } else {
            f64::from(self.table.accel_rad_s2)
        };
        let state = TableState {
            up_b: self.table.up_b.map(f64::from),
            rate_rad_s: rate,
            accel_rad_s2: accel,
            centre_m: [0.0; 3],
        };
        let motion = state.motion(self.model.gravity_m_s2);
        let mut u = self.model.outputs(&motion);
        self.die_c += (self.ambient_c - self.die_c) * self.die_follow;
        if let Some(th) = &self.thermal {
            // U(T) = u0 + P(ΔT) + (1 + S(ΔT))·(U_ref − u0): the scale moves every term of the row.
            let dt = self.die_c - th.reference_c;
            for i in 0..3 {
                let u0 = self.model.zero_bias_out[i];
                let gain = 1.0 + poly_no_constant(&th.scale_rel_per_c[i], dt);
                u.raw[i] =
                    u0 + poly_no_constant(&th.zero_bias_out_per_c[i], dt) + gain * (u.raw[i] - u0);
            }
        }
        let mut saturated = false;
        let mut raw = [0.0f32; 3];
        let mut rate_out = [0.0f32; 3];
        for i in 0..3 {
            let v = u.raw[i] as f32 + OUTPUT_NOISE_V * self.noise();
            raw[i] = v.clamp(OUTPUT_RANGE_V.0, OUTPUT_RANGE_V.1);
            saturated |= raw[i] != v;
            let w = motion.omega.rad_s[i] as f32 + GYRO_NOISE_RAD_S * self.noise();
            rate_out[i] = w.clamp(-GYRO_RANGE_RAD_S, GYRO_RANGE_RAD_S);
            saturated |= rate_out[i] != w;
        }
        Sample {
            raw,
            rate_rad_s: rate_out,
            saturated,
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::paper_unit;
    use shared::compensator::{Compensator, LeverMode};
    use shared::units::{BodyAngularAccel, BodyRate, SensorOutputs};

    #[test]
    fn spinning_unit_is_compensated_back_to_gravity() {
        let cal = paper_unit::calibration();
        let mut s = VirtualSensor::new(&cal, 1000, false).unwrap();
        s.set_table(&VirtualTable {
            up_b: [1.0, 0.0, 0.0],
            rate_rad_s: 200f32.to_radians(),
            accel_rad_s2: 0.0,
        })
        .unwrap();
        let x = s.sample();
        assert!(!x.saturated);
        let c = Compensator::new(&cal, LeverMode::RateOnly).unwrap();
        let f = c.compensate(
            &SensorOutputs { raw: x.raw },
            &BodyRate {
                rad_s: x.rate_rad_s,
            },
            &BodyAngularAccel::default(),
        );
        assert!((f.m_s2[0] - 9.80665).abs() < 1e-4, "{f:?}");
        assert!(f.m_s2[1].abs() < 1e-4 && f.m_s2[2].abs() < 1e-4, "{f:?}");
        // Static-only leaves the paper's ~11 mg on y.
        let st = c.compensate_static(&SensorOutputs { raw: x.raw });
        assert!(
            (st.m_s2[1].abs() / 9.80665 * 1e3 - 11.19).abs() < 0.05,
            "{st:?}"
        );
    }

    #[test]
    fn ramp_and_saturation_and_bad_tables() {
        let cal = paper_unit::calibration();
        let mut s = VirtualSensor::new(&cal, 1000, true).unwrap();
        assert!(s
            .set_table(&VirtualTable {
                up_b: [0.0, 0.0, 0.0],
                rate_rad_s: 0.0,
                accel_rad_s2: 0.0
            })
            .is_err());
        assert!(s
            .set_table(&VirtualTable {
                up_b: [0.0, f32::NAN, 1.0],
                rate_rad_s: 0.0,
                accel_rad_s2: 0.0
            })
            .is_err());
        s.set_table(&VirtualTable {
            up_b: [0.0, 0.0, 2.0],
            rate_rad_s: 0.0,
            accel_rad_s2: 10.0,
        })
        .unwrap();
        assert_eq!(s.table().up_b, [0.0, 0.0, 1.0]);
        for _ in 0..100 {
            s.sample();
        }
        let x = s.sample();
        // 10 rad/s² for 0.1 s: 1 rad/s about z.
        assert!((x.rate_rad_s[2] - 1.0).abs() < 0.01, "{x:?}");
        // 30 rad/s about a tilted axis: the lever terms (ω² r ≈ 7 m/s²) stay within range; 60 g would not.
        let mut s = VirtualSensor::new(&cal, 1000, false).unwrap();
        s.set_table(&VirtualTable {
            up_b: [1.0, 1.0, 0.0],
            rate_rad_s: 30.0,
            accel_rad_s2: 0.0,
        })
        .unwrap();
        assert!(!s.sample().saturated);
    }

    /// Runs `seconds` of samples through `p`, reading the temperature four times a second, and
    /// returns the last compensated window.
    fn run(
        s: &mut VirtualSensor,
        p: &mut crate::Pipeline<8>,
        seconds: u32,
        read_temperature: bool,
    ) -> shared::wire::CompensatedWindow {
        let mut last = None;
        for k in 0..seconds * 1000 {
            if read_temperature && k % 250 == 0 {
                p.on_temperature(s.temperature_c());
            }
            p.on_sample(&s.sample());
            while let Some(m) = p.pop_output() {
                if let shared::wire::DeviceToHost::CompensatedWindow(w) = m {
                    last = Some(w);
                }
            }
        }
        last.unwrap()
    }

    #[test]
    fn heated_unit_is_compensated_within_50_ug_and_flagged_outside_its_range() {
        use crate::pipeline::PipelineCommand;
        use shared::wire::{SampleFlags, StreamKind, StreamRequest};
        let cal = paper_unit::hot_calibration();
        let mut s = VirtualSensor::new(&cal, 1000, true).unwrap();
        let up = [0.6f32, 0.0, -0.8];
        s.set_table(&VirtualTable {
            up_b: up,
            rate_rad_s: 0.0,
            accel_rad_s2: 0.0,
        })
        .unwrap();
        let mut p = crate::Pipeline::<8>::new(1000);
        let c = Compensator::new(&cal, LeverMode::RateOnly).unwrap();
        p.apply(PipelineCommand::Compensator(Some(c)));
        p.apply(PipelineCommand::Stream(StreamRequest {
            kind: StreamKind::CompensatedWindows,
            window_samples: 4000,
        }));
        // Without a temperature reading the model cannot be applied: flagged.
        let w = run(&mut s, &mut p, 4, false);
        assert!(w.flags.has(SampleFlags::TEMPERATURE), "{w:?}");
        assert!(w.mean_temp_c.is_nan());
        let g = paper_unit::GRAVITY_M_S2 as f32;
        let error_ug = |w: &shared::wire::CompensatedWindow| {
            let e: [f32; 3] = core::array::from_fn(|j| w.mean_m_s2[j] / g - up[j]);
            (e[0] * e[0] + e[1] * e[1] + e[2] * e[2]).sqrt() * 1e6
        };
        let mut plain = Compensator::new(&cal, LeverMode::RateOnly).unwrap();
        for (ambient, in_range) in [(45.0f32, true), (0.0, true), (70.0, false)] {
            s.set_ambient_c(ambient).unwrap();
            // Ten die time constants to settle, then one window.
            let w = run(&mut s, &mut p, 24, true);
            assert!((w.mean_temp_c - ambient).abs() < 0.01, "{w:?}");
            assert_eq!(!w.flags.has(SampleFlags::TEMPERATURE), in_range, "{w:?}");
            std::println!(
                "heated to {ambient} °C: window mean error {:.1} µg, flagged {}",
                error_ug(&w),
                w.flags.has(SampleFlags::TEMPERATURE)
            );
            if in_range {
                assert!(error_ug(&w) < 50.0, "{ambient} °C: {} µg", error_ug(&w));
                // The same data without the temperature refresh is off by milli-g.
                plain.refresh(25.0);
                let raw = s.sample();
                let f = plain.compensate_static(&SensorOutputs { raw: raw.raw });
                let e = (0..3)
                    .map(|j| (f.m_s2[j] / g - up[j]).powi(2))
                    .sum::<f32>()
                    .sqrt();
                assert!(e > 3e-3, "{ambient} °C: {e}");
            }
        }
        assert!(s.set_ambient_c(f32::NAN).is_err());
    }
}
