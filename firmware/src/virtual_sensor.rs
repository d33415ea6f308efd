//! The QEMU board's virtual sensor: the shared forward model ([`shared::forward::ForwardModel`]) of a
//! unit on a virtual single-axis rate table whose attitude, rate and angular acceleration the host
//! sets (`HostToDevice::SetVirtualTable`). Sampled at a fixed rate, it gives the outputs (V) and the
//! gyro rate (rad/s) with small deterministic noise, saturating like real parts.
//!
//! The table turns about the vertical, so "up" is constant in body axes and `ω = rate(t)·up` with
//! `rate(t) = rate₀ + α·t`, t counted in samples since the table was set (virtual time).
//!
//! The unit's imperfections are those of its [`Calibration`] (the truth): the gyro outputs
//! `w = G ω + b(T)` with its `gyro` section (docs/model.md §8), and with a `temperature` section the
//! outputs follow the thermal model of docs/model.md §9 at the die temperature,
//! `U(T) = u0 + P(ΔT) + diag(1 + s(T))·(U_ref − u0)` — bias tempco with quadratic terms, scale tempco,
//! gyro bias drift. The die temperature is set in software ([`VirtualSensor::set_temperature`],
//! `HostToDevice::SetVirtualTemperature`); the unit's temperature *sensor* reads it through a
//! first-order lag ([`VirtualSensor::set_thermal_lag_s`], none by default), as a sensor beside the die
//! does.

use shared::forward::{ForwardModel, TableState};
use shared::linalg;
use shared::sensor_models::{
    poly_no_constant, GyroCorrection, TemperatureModel, TEMPERATURE_LIMITS_C,
};
use shared::wire::VirtualTable;
use shared::Calibration;

use crate::pipeline::{Pipeline, Sample, TEMPERATURE_REFRESH_HZ};

/// Output range of the virtual accelerometers, volts (a 0–5 V analog part).
pub const OUTPUT_RANGE_V: (f32, f32) = (0.0, 5.0);
/// Full scale of a virtual accelerometer whose outputs are not volts (a digital part's counts, or
/// its m/s² or g), g either side of its zero bias: a MEMS IMU's ±16 g range.
pub const DIGITAL_FULL_SCALE_G: f64 = 16.0;
/// Output noise of such a part, g (the analog part's ≈ 0.5 mg).
pub const DIGITAL_NOISE_G: f64 = 5.0e-4;
/// Gyro range, rad/s (±2000 °/s).
pub const GYRO_RANGE_RAD_S: f32 = 34.9;
/// Standard deviation of the output noise, volts (≈ 0.5 mg at 0.4 V/g).
pub const OUTPUT_NOISE_V: f32 = 2.0e-4;
/// Standard deviation of the gyro noise, rad/s (≈ 0.06 °/s).
pub const GYRO_NOISE_RAD_S: f32 = 1.0e-3;
/// Largest table rate accepted, rad/s (the rate ramp is clamped here too).
pub const MAX_TABLE_RATE_RAD_S: f32 = 30.0;

/// Die temperature at power-on, °C.
pub const POWER_ON_TEMPERATURE_C: f32 = 25.0;

/// A unit on a virtual rate table.
pub struct VirtualSensor {
    model: ForwardModel,
    table: VirtualTable,
    /// A tilt under way: the body-axis rate `ω` (rad/s) of a turn through O, "up" the table's
    /// `up_b` (set by the caller sample by sample). Cleared by [`Self::set_table`].
    #[cfg(any(test, feature = "hand-tilt"))]
    tilt: Option<[f64; 3]>,
    samples_since_set: u32,
    sample_period_s: f64,
    noise_state: u32,
    noise_on: bool,
    gyro: GyroCorrection,
    thermal: Option<TemperatureModel>,
    zero_bias_out: [f64; 3],
    die_temp_c: f64,
    sensor_temp_c: f64,
    /// Fraction of the die–sensor difference the sensor closes per sample (1: no lag).
    lag_step: f64,
    /// `P(ΔT)`, `1 + s(T)`, `b(T)` at the die temperature.
    bias_shift_out: [f64; 3],
    gain: [f64; 3],
    gyro_bias_rad_s: [f64; 3],
    samples: u32,
    sample_rate_hz: u32,
    /// Each output's clamp (its saturation), in the unit's output unit.
    output_range: [(f32, f32); 3],
    /// Each output's noise σ, in the unit's output unit.
    output_noise: [f32; 3],
}

/// Why a table setting was refused.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct BadTable;

/// Why a temperature setting was refused.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct BadTemperature;

impl VirtualSensor {
    /// The unit `cal` at rest with z up, sampled at `sample_rate_hz`; `None` if `cal` is unusable.
    pub fn new(cal: &Calibration, sample_rate_hz: u32, noise: bool) -> Option<Self> {
        let model = ForwardModel::new(cal).ok()?;
        // The paper's analog part swings 0–5 V; a unit calibrated in another unit is a digital
        // part, whose range and noise follow its own scale (else its counts would all clamp).
        let st = &cal.statics;
        let analog = st.output_unit == shared::OutputUnit::Volts;
        let output_range = core::array::from_fn(|i| {
            let half = DIGITAL_FULL_SCALE_G * libm::fabs(st.scale_out_per_g[i]);
            match analog {
                true => OUTPUT_RANGE_V,
                false => (
                    (st.zero_bias_out[i] - half) as f32,
                    (st.zero_bias_out[i] + half) as f32,
                ),
            }
        });
        let output_noise = core::array::from_fn(|i| match analog {
            true => OUTPUT_NOISE_V,
            false => (DIGITAL_NOISE_G * libm::fabs(st.scale_out_per_g[i])) as f32,
        });
        Some(
            VirtualSensor {
                model,
                table: VirtualTable {
                    up_b: [0.0, 0.0, 1.0],
                    rate_rad_s: 0.0,
                    accel_rad_s2: 0.0,
                },
                #[cfg(any(test, feature = "hand-tilt"))]
                tilt: None,
                samples_since_set: 0,
                sample_period_s: 1.0 / f64::from(sample_rate_hz.max(1)),
                noise_state: 0x1234_5678,
                noise_on: noise,
                gyro: cal.gyro.unwrap_or(GyroCorrection::PERFECT),
                thermal: cal.temperature,
                zero_bias_out: cal.statics.zero_bias_out,
                die_temp_c: 0.0,
                sensor_temp_c: f64::from(POWER_ON_TEMPERATURE_C),
                lag_step: 1.0,
                bias_shift_out: [0.0; 3],
                gain: [1.0; 3],
                gyro_bias_rad_s: [0.0; 3],
                samples: 0,
                sample_rate_hz: sample_rate_hz.max(1),
                output_range,
                output_noise,
            }
            .at_temperature(POWER_ON_TEMPERATURE_C),
        )
    }

    fn at_temperature(mut self, t: f32) -> Self {
        self.set_temperature(t);
        self
    }

    /// Checks a die temperature: finite and within `TEMPERATURE_LIMITS_C`.
    pub fn check_temperature(temp_c: f32) -> Result<f32, BadTemperature> {
        let t = f64::from(temp_c);
        if t.is_finite() && (TEMPERATURE_LIMITS_C.0..=TEMPERATURE_LIMITS_C.1).contains(&t) {
            Ok(temp_c)
        } else {
            Err(BadTemperature)
        }
    }

    /// Heats or cools the die to `temp_c` at once (the temperature sensor follows with the lag).
    /// Outside the truth model's valid range the polynomials are extrapolated: the unit does drift
    /// there, only the calibration does not know how.
    pub fn set_temperature(&mut self, temp_c: f32) {
        let Ok(t) = Self::check_temperature(temp_c) else {
            return;
        };
        self.die_temp_c = f64::from(t);
        if self.lag_step >= 1.0 {
            self.sensor_temp_c = self.die_temp_c; // no lag: the sensor reads the die
        }
        let m = self.thermal;
        let dt = m.map_or(0.0, |m| self.die_temp_c - m.reference_c);
        for i in 0..3 {
            let (shift, scale, drift) = m.map_or((0.0, 0.0, 0.0), |m| {
                (
                    poly_no_constant(&m.zero_bias_out_per_c[i], dt),
                    poly_no_constant(&m.scale_rel_per_c[i], dt),
                    poly_no_constant(&m.gyro_bias_polynomials()[i], dt),
                )
            });
            self.bias_shift_out[i] = shift;
            self.gain[i] = 1.0 + scale;
            self.gyro_bias_rad_s[i] = self.gyro.bias_rad_s[i] + drift;
        }
    }

    /// The time constant of the temperature sensor's lag behind the die, seconds (0: none).
    pub fn set_thermal_lag_s(&mut self, tau_s: f32) {
        let tau = f64::from(tau_s);
        // Exact discretisation of dT/dt = (T_die − T)/τ over one sample period.
        self.lag_step = if tau > 0.0 {
            1.0 - libm::exp(-self.sample_period_s / tau)
        } else {
            1.0
        };
    }

    /// The die temperature, °C (what the unit's parameters follow).
    pub fn die_temperature_c(&self) -> f32 {
        self.die_temp_c as f32
    }

    /// What the unit's temperature sensor reads, °C.
    pub fn temperature_c(&self) -> f32 {
        self.sensor_temp_c as f32
    }

    /// One sample period of a board: the next sample through the pipeline, and every
    /// `1/TEMPERATURE_REFRESH_HZ` s a temperature reading first (as the QEMU board and the host's
    /// simulated device do).
    pub fn step<const Q: usize>(&mut self, pipeline: &mut Pipeline<Q>) {
        let every = (self.sample_rate_hz / TEMPERATURE_REFRESH_HZ).max(1);
        if self.samples % every == 0 {
            pipeline.set_temperature(self.temperature_c());
        }
        let s = self.sample();
        pipeline.on_sample(&s);
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
        let n = linalg::sqrt(n2);
        Ok(VirtualTable {
            up_b: u.map(|v| (v / n) as f32),
            ..*t
        })
    }

    /// Sets the table (time restarts at zero). Refuses a setting [`Self::check_table`] refuses.
    pub fn set_table(&mut self, t: &VirtualTable) -> Result<(), BadTable> {
        self.table = Self::check_table(t)?;
        #[cfg(any(test, feature = "hand-tilt"))]
        {
            self.tilt = None;
        }
        self.samples_since_set = 0;
        Ok(())
    }

    /// Turns the unit as a hand does, through O at the body rate `omega_b_rad_s` with "up" where
    /// the table setting puts it: the caller sets both before each sample of a tilt (the
    /// attitude's integration is the host's, so that the firmware carries no trigonometry). The
    /// gyro reads `ω` through the unit's `G`, and the outputs carry the `[ω×]²` of each lever arm
    /// (docs/model.md §4.5). Cleared by [`Self::set_table`]; a rate that is not finite, or faster
    /// than the table's limit, is refused.
    #[cfg(any(test, feature = "hand-tilt"))]
    pub fn set_tilt(&mut self, omega_b_rad_s: [f32; 3]) -> Result<(), BadTable> {
        let w = omega_b_rad_s.map(f64::from);
        let n2 = linalg::dot(&w, &w);
        let max = f64::from(MAX_TABLE_RATE_RAD_S);
        if !n2.is_finite() || n2 > max * max {
            return Err(BadTable);
        }
        self.tilt = Some(w);
        Ok(())
    }

    /// The body's motion now: a tilt's, or the table's.
    #[cfg(any(test, feature = "hand-tilt"))]
    fn motion_now(&self, state: &TableState) -> shared::forward::BodyMotion {
        match &self.tilt {
            Some(omega) => self.tilting(omega),
            None => state.motion(self.model.gravity_m_s2),
        }
    }

    /// The body's motion now: the table's (QEMU's image has no room for the hand's tilt).
    #[cfg(not(any(test, feature = "hand-tilt")))]
    fn motion_now(&self, state: &TableState) -> shared::forward::BodyMotion {
        state.motion(self.model.gravity_m_s2)
    }

    /// The body's motion while it turns at `omega` with the table's "up".
    #[cfg(any(test, feature = "hand-tilt"))]
    fn tilting(&self, omega: &[f64; 3]) -> shared::forward::BodyMotion {
        let g = self.model.gravity_m_s2;
        // O stays put: the body's specific force at O is gravity's alone.
        shared::forward::BodyMotion {
            f_o: shared::units::BodySpecificForce {
                m_s2: self.table.up_b.map(|u| g * f64::from(u)),
            },
            omega: shared::units::BodyRate { rad_s: *omega },
            omega_dot: shared::units::BodyAngularAccel { rad_s2: [0.0; 3] },
        }
    }

    /// Multiplies accelerometer `axis`'s output noise by `k` (the host's simulated device: a
    /// planted noisy axis).
    pub fn scale_output_noise(&mut self, axis: usize, k: f32) {
        if let Some(n) = self.output_noise.get_mut(axis) {
            *n *= k;
        }
    }

    /// The current table setting.
    pub fn table(&self) -> VirtualTable {
        self.table
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
        let motion = self.motion_now(&state);
        let u = self.model.outputs(&motion);
        self.samples = self.samples.wrapping_add(1);
        self.sensor_temp_c += (self.die_temp_c - self.sensor_temp_c) * self.lag_step;
        let gw = linalg::mat_vec(&self.gyro.matrix, &motion.omega.rad_s);
        let mut saturated = false;
        let mut raw = [0.0f32; 3];
        let mut rate_out = [0.0f32; 3];
        for i in 0..3 {
            let u0 = self.zero_bias_out[i];
            let u_t = u0 + self.bias_shift_out[i] + self.gain[i] * (u.raw[i] - u0);
            let v = u_t as f32 + self.output_noise[i] * self.noise();
            let (lo, hi) = self.output_range[i];
            raw[i] = v.clamp(lo, hi);
            saturated |= raw[i] != v;
            let w = (gw[i] + self.gyro_bias_rad_s[i]) as f32 + GYRO_NOISE_RAD_S * self.noise();
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

/// The virtual unit as the QEMU board's ICM-42688-P model samples it: its 0–5 V outputs span the
/// part's 18-bit accelerometer codes (0 V and 5 V are the full-scale codes, so the analog clamp is
/// the part's saturation), so that the driver's output, scaled by [`IMU_ACCEL_V_PER_LSB`] and offset
/// by [`IMU_ACCEL_OFFSET_V`], is in volts again (19 µV per LSB, a tenth of the output noise) and the
/// calibration and the host's truth stay those of the paper's unit. The gyro passes in °/s (the
/// part's ±2000 °/s full scale is just beyond the virtual gyro's ±34.9 rad/s clamp).
#[cfg(any(test, feature = "imu-sim"))]
impl crate::imu::sim::Generator for VirtualSensor {
    fn next(&mut self) -> crate::imu::sim::Truth {
        let s = self.sample();
        // g at the largest 18-bit code (131071 LSB at 8192 LSB/g).
        let full_scale_g = 131_071.0 / 8192.0;
        let mid = f64::from(IMU_ACCEL_OFFSET_V);
        crate::imu::sim::Truth {
            accel_g: s.raw.map(|v| (f64::from(v) - mid) / mid * full_scale_g),
            gyro_dps: s.rate_rad_s.map(|w| f64::from(w).to_degrees()),
            temp_c: f64::from(self.temperature_c()),
        }
    }
}

/// Volts per 18-bit accelerometer LSB of the QEMU board's virtual ICM-42688-P.
pub const IMU_ACCEL_V_PER_LSB: f32 = 2.5 / 131_071.0;
/// The output at a zero accelerometer code, V (the middle of the 0–5 V range).
pub const IMU_ACCEL_OFFSET_V: f32 = 2.5;

/// The QEMU board's ICM-42688-P configuration: 1 kHz, 20-bit packets, INT1 at every packet,
/// outputs in volts.
pub const IMU_CONFIG: crate::imu::icm42688::Config = crate::imu::icm42688::Config {
    odr: crate::imu::icm42688::Odr::Hz1000,
    fifo: crate::imu::icm42688::FifoFormat::Packet4HighRes,
    watermark_packets: 1,
    accel_out_per_lsb: IMU_ACCEL_V_PER_LSB,
    accel_out_offset: IMU_ACCEL_OFFSET_V,
    ..crate::imu::icm42688::Config::DEFAULT
};

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

    /// A hand's turn about body x with z up: the gyro reads `G ω + b`, the outputs are the forward
    /// model's with the lever arms' centripetal term; a table setting ends the turn.
    #[test]
    fn a_tilt_turns_the_gyro_and_swings_the_lever_arms() {
        let truth = crate::testvectors::imperfect_unit();
        let mut s = VirtualSensor::new(&truth, 1000, false).unwrap();
        let rate = 90f32.to_radians();
        s.set_tilt([rate, 0.0, 0.0]).unwrap();
        let gyro = truth.gyro.unwrap();
        let x = s.sample();
        for j in 0..3 {
            let want = gyro.matrix[j][0] * f64::from(rate) + gyro.bias_rad_s[j];
            assert!((f64::from(x.rate_rad_s[j]) - want).abs() < 1e-5, "{x:?}");
        }
        let model = shared::forward::ForwardModel::new(&truth).unwrap();
        let g = model.gravity_m_s2;
        let f_o = shared::units::BodySpecificForce {
            m_s2: [0.0, 0.0, g],
        };
        let w = [f64::from(rate), 0.0, 0.0];
        let want = model.outputs(&shared::forward::BodyMotion {
            f_o,
            omega: BodyRate { rad_s: w },
            omega_dot: BodyAngularAccel::default(),
        });
        let still = model.outputs(&shared::forward::BodyMotion {
            f_o,
            ..Default::default()
        });
        for j in 0..3 {
            assert!(
                (f64::from(x.raw[j]) - want.raw[j]).abs() < 1e-5,
                "{x:?} vs {want:?}"
            );
        }
        // The lever arms' centripetal term shows: at rest the outputs differ.
        assert!(
            (0..3).any(|j| (f64::from(x.raw[j]) - still.raw[j]).abs() > 1e-5),
            "{x:?} vs {still:?}"
        );
        s.set_table(&s.table()).unwrap();
        let rest = s.sample();
        assert!((f64::from(rest.rate_rad_s[0]) - gyro.bias_rad_s[0]).abs() < 1e-6);
        assert!(s.set_tilt([f32::NAN, 0.0, 0.0]).is_err());
        assert!(s.set_tilt([100.0, 0.0, 0.0]).is_err());
    }

    #[test]
    fn gyro_errors_thermal_model_and_sensor_lag() {
        let truth = crate::testvectors::imperfect_unit();
        let mut s = VirtualSensor::new(&truth, 1000, false).unwrap();
        assert_eq!(s.temperature_c(), POWER_ON_TEMPERATURE_C);
        // At rest, z up, at the reference temperature: the gyro reads its bias, the outputs the truth.
        let x = s.sample();
        let b = truth.gyro.unwrap().bias_rad_s;
        for j in 0..3 {
            assert!((f64::from(x.rate_rad_s[j]) - b[j]).abs() < 1e-6, "{x:?}");
        }
        let at_ref = x.raw;
        // Heated by 20 °C: z (1 g up) moves by its bias tempco and quadratic term plus 150 ppm/°C
        // of its 0.4 V; x and y (0 g) by their bias terms only.
        s.set_temperature(45.0);
        let hot = s.sample().raw;
        let m = truth.temperature.unwrap();
        for j in 0..3 {
            let c = m.zero_bias_out_per_c[j];
            let k = m.scale_rel_per_c[j][0];
            let g_part = f64::from(at_ref[j]) - truth.statics.zero_bias_out[j];
            let want = c[0] * 20.0 + c[1] * 400.0 + k * 20.0 * g_part;
            let got = f64::from(hot[j]) - f64::from(at_ref[j]);
            assert!((got - want).abs() < 1e-6, "axis {j}: {got} vs {want}");
        }
        // A 2 s sensor lag: after 2 s the reading has closed 1 − 1/e of a 20 °C step.
        s.set_thermal_lag_s(2.0);
        s.set_temperature(65.0);
        assert_eq!(s.temperature_c(), 45.0);
        for _ in 0..2000 {
            s.sample();
        }
        let closed = (s.temperature_c() - 45.0) / 20.0;
        assert!((closed - (1.0 - (-1.0f32).exp())).abs() < 1e-3, "{closed}");
        assert_eq!(s.die_temperature_c(), 65.0);
        assert!(VirtualSensor::check_temperature(f32::NAN).is_err());
        assert!(VirtualSensor::check_temperature(500.0).is_err());
    }

    #[test]
    fn seen_through_the_icm42688_model_the_outputs_are_volts_again() {
        use crate::imu::icm42688::Icm42688;
        use crate::imu::sim::Icm42688Model;
        use crate::imu::{ImuSample, ImuSource};
        let cal = paper_unit::calibration();
        let mut direct = VirtualSensor::new(&cal, 1000, true).unwrap();
        let sensor = VirtualSensor::new(&cal, 1000, true).unwrap();
        let mut imu = Icm42688::new(Icm42688Model::new(sensor), IMU_CONFIG).unwrap();
        let mut buf = [ImuSample::default(); 4];
        let mut seen = 0;
        for k in 0..300 {
            imu.device_mut().advance_ns(1_000_000);
            assert!(imu.device_mut().int1(), "sample {k}: INT1 at the watermark");
            let d = imu.drain(&mut buf).unwrap();
            assert_eq!(d.samples, 1);
            let want = direct.sample();
            if k == 0 {
                continue; // marked invalid by the part
            }
            let got = buf[0];
            for i in 0..3 {
                // One 18-bit LSB is 19 µV; the gyro's 19-bit LSB is 0.13 mrad/s.
                assert!(
                    (got.accel_out[i] - want.raw[i]).abs() < 2.0e-5,
                    "{got:?} {want:?}"
                );
                assert!((got.gyro_rad_s[i] - want.rate_rad_s[i]).abs() < 1.0e-4);
            }
            assert!((got.temp_c - 25.0).abs() < 0.01);
            seen += 1;
        }
        assert_eq!(seen, 299);
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
}
