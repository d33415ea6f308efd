//! Per-sample compensation: the inverse model of docs/model.md §3 (paper eq. 16–17), with the gyro's
//! correction (§8) and the temperature model (§9), in the per-sample form of §10.
//!
//! Built once from a [`Calibration`] (settings → precomputed state → one call per sample, as in x-io
//! Fusion): every square root, trigonometric function and division happens in [`Compensator::new`],
//! in `f64`, or in [`Compensator::refresh`] (a few times a second, `f32`), and the per-sample calls
//! are straight-line `f32` multiply-adds with no branch on data.
//!
//! Per sample, with `k_i d_i = ω̇·p_i + (a_i·ω)(q_i·ω) − |ω|² s_i` (docs/model.md §10):
//!
//! ```text
//! ω   = c + G⁻¹ w,  c = −G⁻¹ b          gyro correction (§8), G⁻¹ and c precomputed: 9 multiply-adds
//! f_O = g·K_A · (U − u0 − K d)          K_A = (K A)⁻¹, the exact inverse (never a transpose)
//! ```
//!
//! Operation count of [`Compensator::compensate`]: `U − u0` 3 subtractions; `|ω|²` 3; per axis
//! `ω̇·p_i` 3, `a_i·ω` 3, `q_i·ω` 3, two products and one subtraction, and the subtraction from `U − u0`
//! (12 per axis, 36); `K_A·v` 9. Total 51 multiply-adds (48 fused-multiply-add-able), against the ~50 of
//! docs/model.md §10. The static-only path [`Compensator::compensate_static`] is 12, the gyro
//! correction [`Compensator::correct_rate`] 9 multiply-adds.
//!
//! Temperature (§9): `u0(T) = u0 + P(ΔT)`, `M(T) = diag(1 + s(T))·M`, so `K_A(T) = K_A·diag(1/(1+s))`
//! (column `j` scaled) and `k_i(T) = k_i (1 + s_i)` scales the lever-arm terms `p_i, q_i, s_i` of
//! accelerometer `i`; the gyro bias is `b(T) = b + B(ΔT)`. [`Compensator::refresh`] recomputes exactly
//! these from the reference values (3 divisions); outside the valid range it evaluates the polynomials
//! at the nearest end (a fitted cubic is not extrapolated) and reports [`TemperatureState::Clamped`],
//! which the firmware turns into a flag on its outputs.

use crate::linalg::{self, RowMajor3};
use crate::params::{Calibration, ParamsError};
use crate::sensor_models::{
    poly_no_constant, GyroError, TemperatureModel, TemperatureModelError, MAX_GYRO_BIAS_RAD_S,
    MAX_TEMPERATURE_DEGREE,
};
use crate::units::{BodyAngularAccel, BodyRate, BodySpecificForce, SensorOutputs};

/// Which lever-arm terms the per-sample path applies (docs/model.md §4.6: the ω̇ term must be switchable).
#[derive(
    Clone,
    Copy,
    Debug,
    PartialEq,
    Eq,
    serde::Serialize,
    serde::Deserialize,
    postcard::experimental::max_size::MaxSize,
)]
pub enum LeverMode {
    /// Static compensation only (no gyro needed).
    Off,
    /// Centripetal and cross terms from ω; the tangential ω̇ term off (the paper's eq. 17 with ω̇ = 0).
    RateOnly,
    /// All terms, with ω̇ from a filtered estimator.
    RateAndAcceleration,
}

/// Why a calibration cannot be turned into a compensator.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum CompensatorError {
    /// The parameters themselves are unusable.
    Params(ParamsError),
    /// `K·A` is singular or too badly conditioned to invert (1-norm condition number given).
    IllConditioned {
        /// ‖M‖₁‖M⁻¹‖₁ (infinite when singular).
        condition: f64,
    },
    /// The gravity value is not a plausible local gravity (m/s²).
    Gravity,
    /// The gyro correction is unusable.
    Gyro(GyroError),
    /// The temperature model is unusable.
    Temperature(TemperatureModelError),
    /// A value the device computes with does not fit its `f32` arithmetic (see `MAX_DEVICE_MAGNITUDE`).
    OutOfDeviceRange,
}

impl core::fmt::Display for CompensatorError {
    fn fmt(&self, f: &mut core::fmt::Formatter<'_>) -> core::fmt::Result {
        match self {
            CompensatorError::Params(e) => e.fmt(f),
            CompensatorError::IllConditioned { condition } => write!(
                f,
                "K·A is singular or ill-conditioned (condition number {condition:.3e}, limit {MAX_CONDITION:.0})"
            ),
            CompensatorError::Gravity => write!(
                f,
                "local gravity outside {MIN_GRAVITY_M_S2}..{MAX_GRAVITY_M_S2} m/s²"
            ),
            CompensatorError::Gyro(e) => e.fmt(f),
            CompensatorError::Temperature(e) => e.fmt(f),
            CompensatorError::OutOfDeviceRange => write!(
                f,
                "a calibration value is beyond what the device's f32 arithmetic carries (magnitudes {MIN_DEVICE_MAGNITUDE:e}..{MAX_DEVICE_MAGNITUDE:e})"
            ),
        }
    }
}

/// Lets a host error name this one as its `source()`.
impl core::error::Error for CompensatorError {}

/// Largest accepted 1-norm condition number of `K·A`. A near-orthogonal unit has about 1.1; 100 means
/// sensing axes within a few degrees of each other, which no usable unit has.
pub(crate) const MAX_CONDITION: f64 = 100.0;
/// Plausible local gravity range, m/s² (Earth's surface spans 9.76..9.84).
pub(crate) const MIN_GRAVITY_M_S2: f64 = 9.7;
/// See [`MIN_GRAVITY_M_S2`].
pub(crate) const MAX_GRAVITY_M_S2: f64 = 9.9;
/// Largest magnitude of any precomputed `f32` constant (and of the zero biases). The per-sample path
/// multiplies a constant by at most two inputs (`s_i·|ω|²`, with |ω| ≤ 10³ rad/s; outputs ≤ 2²⁴ LSB),
/// so 10²⁰ keeps every intermediate below 10³² — far from `f32::MAX` ≈ 3.4·10³⁸ — while no real unit
/// comes near it. A CRC-valid blob with a bias of 10³⁰⁰ is refused instead of turning into ∞.
pub(crate) const MAX_DEVICE_MAGNITUDE: f64 = 1e20;
/// Smallest magnitude of a non-zero entry of `g·K_A` and `G⁻¹`: below it `f32` loses precision
/// (subnormals start at 1.2·10⁻³⁸) or flushes to zero, which would silently drop an axis.
pub(crate) const MIN_DEVICE_MAGNITUDE: f64 = 1e-30;

/// `v` as `f32`, or an error when it is non-finite or beyond [`MAX_DEVICE_MAGNITUDE`].
fn device_f32(v: f64) -> Result<f32, CompensatorError> {
    if v.is_finite() && v.abs() <= MAX_DEVICE_MAGNITUDE {
        Ok(v as f32)
    } else {
        Err(CompensatorError::OutOfDeviceRange)
    }
}

fn device_f32_3(v: &[f64; 3]) -> Result<[f32; 3], CompensatorError> {
    Ok([device_f32(v[0])?, device_f32(v[1])?, device_f32(v[2])?])
}

fn device_f32_33(m: &RowMajor3) -> Result<[[f32; 3]; 3], CompensatorError> {
    Ok([
        device_f32_3(&m[0])?,
        device_f32_3(&m[1])?,
        device_f32_3(&m[2])?,
    ])
}

/// A gain matrix whose non-zero entries must also stay clear of `f32` underflow.
fn device_gain_33(m: &RowMajor3) -> Result<[[f32; 3]; 3], CompensatorError> {
    let tiny = m
        .iter()
        .flatten()
        .any(|v| *v != 0.0 && v.abs() < MIN_DEVICE_MAGNITUDE);
    if tiny {
        return Err(CompensatorError::OutOfDeviceRange);
    }
    device_f32_33(m)
}

/// Where the temperature model stands after the latest [`Compensator::refresh`].
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum TemperatureState {
    /// The calibration has no temperature model: nothing to refresh, nothing to flag.
    NotModelled,
    /// A model exists but no valid temperature has been given yet: the reference values apply.
    NoReading,
    /// Refreshed at a temperature within the valid range.
    InRange,
    /// The temperature was outside the valid range: refreshed at the nearest end of the range.
    Clamped,
}

impl TemperatureState {
    /// True when outputs should carry a temperature flag (a model exists but was not applied at the
    /// actual temperature).
    pub fn is_flagged(self) -> bool {
        matches!(
            self,
            TemperatureState::NoReading | TemperatureState::Clamped
        )
    }
}

/// Three `f32` polynomials without constant term, row `i` = `c1, c2, c3` (see [`poly_no_constant`]).
pub(crate) type Poly32 = [[f32; MAX_TEMPERATURE_DEGREE]; 3];

/// The reference values and polynomials [`Compensator::refresh`] starts from (all `f32`), public for
/// code generators that reproduce the refresh in another language (the host's C export).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct ThermalConstants {
    /// `T_ref`, °C.
    pub reference_c: f32,
    /// The valid range, °C: a temperature outside it is clamped to it.
    pub range_c: [f32; 2],
    /// `u0` at `T_ref`, output unit.
    pub zero_bias_out: [f32; 3],
    /// `g·(K A)⁻¹` at `T_ref`, m/s² per output unit, row-major.
    pub ka_m_s2_per_out: [[f32; 3]; 3],
    /// `p_i` at `T_ref`.
    pub p: [[f32; 3]; 3],
    /// `q_i` at `T_ref`.
    pub q: [[f32; 3]; 3],
    /// `s_i` at `T_ref`.
    pub s: [f32; 3],
    /// The gyro bias `b` at `T_ref`, rad/s, gyro axes.
    pub gyro_bias_rad_s: [f32; 3],
    /// Row `i`: `c1, c2, c3` of the zero bias's `P_i(ΔT)`, output unit per °C^k.
    pub zero_bias_poly: Poly32,
    /// Row `i`: the relative scale's `S_i(ΔT)`, 1 per °C^k.
    pub scale_poly: Poly32,
    /// Row `j`: the gyro bias's `B_j(ΔT)`, rad/s per °C^k.
    pub gyro_bias_poly: Poly32,
}

/// `c1·x + c2·x² + c3·x³` in `f32` (Horner), the device's form of [`poly_no_constant`].
#[inline(always)]
fn poly32(c: &[f32; MAX_TEMPERATURE_DEGREE], x: f32) -> f32 {
    x * (c[0] + x * (c[1] + x * c[2]))
}

/// The gyro's correction in the affine form the device evaluates, `ω = c + G⁻¹ w` with
/// `c = −G⁻¹ b(T)` (docs/model.md §8).
#[derive(Clone, Copy, Debug, PartialEq)]
struct GyroInverse {
    /// `c = −G⁻¹ b(T)`, rad/s, body axes.
    offset_rad_s: [f32; 3],
    /// `G⁻¹`, row-major.
    inv: [[f32; 3]; 3],
    /// `b(T)`, rad/s, gyro axes: what `c` is recomputed from.
    bias_rad_s: [f32; 3],
}

/// Precomputed state of the inverse model. `f32` throughout, fixed size, `Copy`.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Compensator {
    /// `p_i = k_i (r_i × a_i)/g`, output unit per rad/s².
    p: [[f32; 3]; 3],
    /// `a_i`, unit sensing directions.
    a: [[f32; 3]; 3],
    /// `q_i = k_i r_i / g`, output unit per (rad/s)² per unit of `a_i·ω`.
    q: [[f32; 3]; 3],
    /// `s_i = k_i (a_i·r_i)/g`, output unit per (rad/s)².
    s: [f32; 3],
    /// `u0(T)`, output unit.
    zero_bias_out: [f32; 3],
    /// `g·(K A)⁻¹` at the current temperature, m/s² per output unit, row-major.
    ka_m_s2_per_out: [[f32; 3]; 3],
    /// `G⁻¹` and `b(T)` of the gyro.
    gyro: GyroInverse,
    /// False for a perfect gyro without temperature drift: [`Compensator::correct_rate`] is skipped.
    gyro_corrected: bool,
    mode: LeverMode,
    thermal: Option<ThermalConstants>,
    temperature: TemperatureState,
}

/// The temperature model's parts in `f32`, checked over the valid range against the gyro bias limit
/// and the device's range.
fn thermal_polynomials(
    t: &TemperatureModel,
    gyro_bias_rad_s: &[f64; 3],
) -> Result<(Poly32, Poly32, Poly32), CompensatorError> {
    t.check().map_err(CompensatorError::Temperature)?;
    let gb = t.gyro_bias_polynomials();
    for temp in t.check_points() {
        for j in 0..3 {
            let b = gyro_bias_rad_s[j] + poly_no_constant(&gb[j], temp - t.reference_c);
            if b.abs() > MAX_GYRO_BIAS_RAD_S {
                return Err(CompensatorError::Gyro(GyroError::BiasOutOfRange));
            }
            device_f32(poly_no_constant(
                &t.zero_bias_out_per_c[j],
                temp - t.reference_c,
            ))?;
        }
    }
    Ok((
        device_f32_33(&t.zero_bias_out_per_c)?,
        device_f32_33(&t.scale_rel_per_c)?,
        device_f32_33(&gb)?,
    ))
}

/// A copy of a [`Compensator`]'s precomputed constants (see its fields for the meaning of each).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct CompensatorConstants {
    /// `u0`, output unit.
    pub zero_bias_out: [f32; 3],
    /// `g·(K A)⁻¹`, m/s² per output unit, row-major.
    pub ka_m_s2_per_out: [[f32; 3]; 3],
    /// `a_i`, unit sensing directions.
    pub a: [[f32; 3]; 3],
    /// `p_i = k_i (r_i × a_i)/g`, zero unless the ω̇ term is on.
    pub p: [[f32; 3]; 3],
    /// `q_i = k_i r_i / g`, zero when the lever terms are off.
    pub q: [[f32; 3]; 3],
    /// `s_i = k_i (a_i·r_i)/g`, zero when the lever terms are off.
    pub s: [f32; 3],
    /// The gyro's `c = −G⁻¹ b(T)`, rad/s, body axes.
    pub gyro_offset_rad_s: [f32; 3],
    /// The gyro's `G⁻¹`, row-major.
    pub gyro_inv: [[f32; 3]; 3],
    /// False for a perfect gyro without temperature drift: the rate passes through unchanged.
    pub gyro_corrected: bool,
}

impl Compensator {
    /// Precomputes the inverse model. Fails on unusable parameters (including values the device's
    /// `f32` arithmetic cannot carry) instead of producing NaN or ∞ later.
    pub fn new(cal: &Calibration, mode: LeverMode) -> Result<Compensator, CompensatorError> {
        let g = cal.gravity_m_s2;
        if !(MIN_GRAVITY_M_S2..=MAX_GRAVITY_M_S2).contains(&g) {
            return Err(CompensatorError::Gravity);
        }
        let (fitted, _) = cal.statics.to_fitted().map_err(CompensatorError::Params)?;
        let (k, a) = fitted.decompose().map_err(CompensatorError::Params)?;
        if !cal.lever_arms.r_m.iter().flatten().all(|v| v.is_finite()) {
            return Err(CompensatorError::Params(ParamsError::NonFinite));
        }
        let condition = linalg::condition_number_1(&fitted.m_out_per_g);
        let inv = match linalg::inverse(&fitted.m_out_per_g) {
            Some(inv) if condition <= MAX_CONDITION => inv,
            _ => return Err(CompensatorError::IllConditioned { condition }),
        };
        let gyro = cal.gyro.unwrap_or(crate::GyroCorrection::PERFECT);
        let gyro_inv = gyro.checked_inverse().map_err(CompensatorError::Gyro)?;
        let lever_on = mode != LeverMode::Off;
        let tangential_on = mode == LeverMode::RateAndAcceleration;
        let r = &cal.lever_arms.r_m;
        let scale = |i: usize, on: bool| if on { k[i] / g } else { 0.0 };
        let p: RowMajor3 = core::array::from_fn(|i| {
            linalg::cross(&r[i], &a[i]).map(|v| v * scale(i, tangential_on))
        });
        let q: RowMajor3 = core::array::from_fn(|i| r[i].map(|v| v * scale(i, lever_on)));
        let s: [f64; 3] = core::array::from_fn(|i| linalg::dot(&a[i], &r[i]) * scale(i, lever_on));
        let mut c = Compensator {
            zero_bias_out: device_f32_3(&fitted.zero_bias_out)?,
            ka_m_s2_per_out: device_gain_33(&inv.map(|row| row.map(|v| v * g)))?,
            a: device_f32_33(&a)?,
            p: device_f32_33(&p)?,
            q: device_f32_33(&q)?,
            s: device_f32_3(&s)?,
            gyro: GyroInverse::new(device_gain_33(&gyro_inv)?, device_f32_3(&gyro.bias_rad_s)?),
            gyro_corrected: cal.gyro.is_some()
                || cal
                    .temperature
                    .is_some_and(|t| t.gyro_bias_rad_s_per_c.is_some()),
            mode,
            thermal: None,
            temperature: TemperatureState::NotModelled,
        };
        if let Some(t) = &cal.temperature {
            let (zero_bias_poly, scale_poly, gyro_bias_poly) =
                thermal_polynomials(t, &gyro.bias_rad_s)?;
            c.thermal = Some(ThermalConstants {
                reference_c: t.reference_c as f32,
                range_c: t.valid_range_c.map(|v| v as f32),
                zero_bias_out: c.zero_bias_out,
                ka_m_s2_per_out: c.ka_m_s2_per_out,
                p: c.p,
                q: c.q,
                s: c.s,
                gyro_bias_rad_s: c.gyro.bias_rad_s,
                zero_bias_poly,
                scale_poly,
                gyro_bias_poly,
            });
            c.temperature = TemperatureState::NoReading;
        }
        Ok(c)
    }

    /// The lever-arm mode this compensator was built with.
    pub fn mode(&self) -> LeverMode {
        self.mode
    }

    /// Where the temperature model stands (see [`TemperatureState`]).
    pub fn temperature_state(&self) -> TemperatureState {
        self.temperature
    }

    /// Recomputes the temperature-dependent terms for the unit's temperature `temp_c` (°C): zero
    /// biases, the columns of `K_A`, the lever-arm terms and the gyro bias (docs/model.md §9, §10).
    /// Call it a few times a second, not per sample; it divides three times. Without a temperature
    /// model it does nothing. A non-finite temperature leaves the terms unchanged and returns
    /// [`TemperatureState::NoReading`]; one outside the valid range is clamped to it and returns
    /// [`TemperatureState::Clamped`]. Never produces a non-finite term: the polynomials were checked
    /// over the whole range when the calibration loaded.
    pub fn refresh(&mut self, temp_c: f32) -> TemperatureState {
        let Some(th) = &self.thermal else {
            return TemperatureState::NotModelled;
        };
        if !temp_c.is_finite() {
            self.temperature = TemperatureState::NoReading;
            return self.temperature;
        }
        let [lo, hi] = th.range_c;
        let clamped = temp_c.clamp(lo, hi);
        let dt = clamped - th.reference_c;
        let mut gyro_bias_rad_s = [0.0; 3];
        for i in 0..3 {
            self.zero_bias_out[i] = th.zero_bias_out[i] + poly32(&th.zero_bias_poly[i], dt);
            gyro_bias_rad_s[i] = th.gyro_bias_rad_s[i] + poly32(&th.gyro_bias_poly[i], dt);
            let gain = 1.0 + poly32(&th.scale_poly[i], dt);
            let inv_gain = 1.0 / gain;
            for r in 0..3 {
                self.ka_m_s2_per_out[r][i] = th.ka_m_s2_per_out[r][i] * inv_gain;
                self.p[i][r] = th.p[i][r] * gain;
                self.q[i][r] = th.q[i][r] * gain;
            }
            self.s[i] = th.s[i] * gain;
        }
        self.gyro.set_bias(gyro_bias_rad_s);
        self.temperature = if clamped == temp_c {
            TemperatureState::InRange
        } else {
            TemperatureState::Clamped
        };
        self.temperature
    }

    /// The body rate from the gyro's output, `ω = G⁻¹(w − b)` (docs/model.md §8), evaluated as
    /// `c + G⁻¹ w` with `c = −G⁻¹ b(T)` precomputed: 9 multiply-adds, skipped for a perfect gyro (a
    /// configuration branch, not a data branch), which therefore passes `w` through bit for bit.
    #[inline(always)]
    pub fn correct_rate(&self, w_rad_s: &[f32; 3]) -> BodyRate {
        if !self.gyro_corrected {
            return BodyRate { rad_s: *w_rad_s };
        }
        BodyRate {
            rad_s: self.gyro.correct(w_rad_s),
        }
    }

    /// Specific force at the reference point from outputs, the (corrected) body rate and angular
    /// acceleration (paper eq. 16). With [`LeverMode::Off`] the gyro inputs have no effect (their
    /// constants are 0).
    ///
    /// Written out per axis (not as a loop) so that it is straight-line code at any optimisation level:
    /// the firmware builds this crate for size.
    #[inline(always)]
    pub fn compensate(
        &self,
        u: &SensorOutputs,
        omega: &BodyRate,
        omega_dot: &BodyAngularAccel,
    ) -> BodySpecificForce {
        BodySpecificForce {
            m_s2: self.compensate_raw(&u.raw, &omega.rad_s, &omega_dot.rad_s2),
        }
    }

    /// [`Compensator::compensate`] on the values where they lie (outputs in the output unit, rate
    /// rad/s, angular acceleration rad/s²), returning the specific force (m/s²): the device's
    /// per-sample path passes its decoded sample and the ω̇ estimator's state without building the
    /// typed values. Each sum runs left to right, each product rounded before its addition (Rust never fuses `a * b + c`; the
    /// Cortex-M4F's `vmla.f32`/`vmls.f32` are not fused either): the same bits on the PC and on the
    /// device, which the QEMU test vectors check (`compensation_*_matches_pc`).
    #[inline(always)]
    pub fn compensate_raw(&self, u: &[f32; 3], w: &[f32; 3], wd: &[f32; 3]) -> [f32; 3] {
        let w2 = w[0] * w[0] + w[1] * w[1] + w[2] * w[2];
        let v = [
            self.lever_corrected(0, u, w, wd, w2),
            self.lever_corrected(1, u, w, wd, w2),
            self.lever_corrected(2, u, w, wd, w2),
        ];
        mat_vec32(&self.ka_m_s2_per_out, &v)
    }

    /// `U_i − u0_i − k_i d_i` with `k_i d_i = ω̇·p_i + (a_i·ω)(q_i·ω) − |ω|² s_i`.
    #[inline(always)]
    fn lever_corrected(&self, i: usize, u: &[f32; 3], w: &[f32; 3], wd: &[f32; 3], w2: f32) -> f32 {
        let p = &self.p[i];
        let q = &self.q[i];
        let a = &self.a[i];
        let tangential = wd[0] * p[0] + wd[1] * p[1] + wd[2] * p[2];
        let a_w = a[0] * w[0] + a[1] * w[1] + a[2] * w[2];
        let q_w = q[0] * w[0] + q[1] * w[1] + q[2] * w[2];
        let k_d = tangential + a_w * q_w - w2 * self.s[i];
        u[i] - self.zero_bias_out[i] - k_d
    }

    /// The precomputed `f32` constants, for code generators that reproduce this per-sample path in
    /// another language (the host's C export) and must hold exactly these values.
    pub fn constants(&self) -> CompensatorConstants {
        CompensatorConstants {
            zero_bias_out: self.zero_bias_out,
            ka_m_s2_per_out: self.ka_m_s2_per_out,
            a: self.a,
            p: self.p,
            q: self.q,
            s: self.s,
            gyro_offset_rad_s: self.gyro.offset_rad_s,
            gyro_inv: self.gyro.inv,
            gyro_corrected: self.gyro_corrected,
        }
    }

    /// What [`Compensator::refresh`] starts from, when there is a temperature model.
    pub fn thermal_constants(&self) -> Option<ThermalConstants> {
        self.thermal
    }

    /// Static-only compensation, `f_O = g·K_A (U − u0)` (paper eq. 6): no gyro needed.
    #[inline(always)]
    pub fn compensate_static(&self, u: &SensorOutputs) -> BodySpecificForce {
        let z = &self.zero_bias_out;
        let v = [u.raw[0] - z[0], u.raw[1] - z[1], u.raw[2] - z[2]];
        BodySpecificForce {
            m_s2: mat_vec32(&self.ka_m_s2_per_out, &v),
        }
    }
}

impl GyroInverse {
    fn new(inv: [[f32; 3]; 3], bias_rad_s: [f32; 3]) -> GyroInverse {
        let mut g = GyroInverse {
            offset_rad_s: [0.0; 3],
            inv,
            bias_rad_s,
        };
        g.set_bias(bias_rad_s);
        g
    }

    /// Sets `b(T)` and its offset `c = −G⁻¹ b(T)`, in `f32` both when a calibration loads and at each
    /// temperature refresh, so that a refresh at the reference temperature changes nothing.
    fn set_bias(&mut self, b: [f32; 3]) {
        let m = &self.inv;
        self.bias_rad_s = b;
        self.offset_rad_s =
            core::array::from_fn(|r| -(m[r][0] * b[0] + m[r][1] * b[1] + m[r][2] * b[2]));
    }

    /// `c + G⁻¹ w`, each row `((c_r + m_r0 w_0) + m_r1 w_1) + m_r2 w_2`: nine multiply-adds, each
    /// product rounded before its addition (Rust never fuses `a * b + c`; the Cortex-M4F's
    /// `vmla.f32` is not fused either), the same bits on the PC and on the device, which the QEMU
    /// test vectors check.
    #[inline(always)]
    fn correct(&self, w: &[f32; 3]) -> [f32; 3] {
        let (c, m) = (&self.offset_rad_s, &self.inv);
        [
            c[0] + m[0][0] * w[0] + m[0][1] * w[1] + m[0][2] * w[2],
            c[1] + m[1][0] * w[0] + m[1][1] * w[1] + m[1][2] * w[2],
            c[2] + m[2][0] * w[0] + m[2][1] * w[1] + m[2][2] * w[2],
        ]
    }
}

/// `m · v` in `f32`, rows written out.
#[inline(always)]
fn mat_vec32(m: &[[f32; 3]; 3], v: &[f32; 3]) -> [f32; 3] {
    [
        m[0][0] * v[0] + m[0][1] * v[1] + m[0][2] * v[2],
        m[1][0] * v[0] + m[1][1] * v[1] + m[1][2] * v[2],
        m[2][0] * v[0] + m[2][1] * v[1] + m[2][2] * v[2],
    ]
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::forward::{BodyMotion, ForwardModel, TableState};
    use crate::params::tests::{expected, paper_unit};
    use crate::params::{LeverArms, OutputUnit, ReferencePoint, StaticParams};
    use crate::sensor_models::poly_no_constant;
    use proptest::prelude::*;

    fn f32_inputs(
        u: &SensorOutputs<f64>,
        m: &BodyMotion,
    ) -> (SensorOutputs, BodyRate, BodyAngularAccel) {
        (
            SensorOutputs {
                raw: u.raw.map(|v| v as f32),
            },
            BodyRate {
                rad_s: m.omega.rad_s.map(|v| v as f32),
            },
            BodyAngularAccel {
                rad_s2: m.omega_dot.rad_s2.map(|v| v as f32),
            },
        )
    }

    /// Independent f64 reference of the inverse model: solve `(K A) f = U − u0 − K d` by LU, with
    /// `d_i = a_i·W r_i` straight from eq. 11 (no precomputed constants).
    fn reference_inverse(cal: &Calibration, u: &SensorOutputs<f64>, m: &BodyMotion) -> [f64; 3] {
        let (fitted, _) = cal.statics.to_fitted().unwrap();
        let (k, a) = fitted.decompose().unwrap();
        let w = linalg::lever_matrix(&m.omega.rad_s, &m.omega_dot.rad_s2);
        let g = cal.gravity_m_s2;
        let rhs = nalgebra::Vector3::from_fn(|i, _| {
            let d = linalg::dot(&a[i], &linalg::mat_vec(&w, &cal.lever_arms.r_m[i])) / g;
            u.raw[i] - fitted.zero_bias_out[i] - k[i] * d
        });
        let f = linalg::to_na(&fitted.m_out_per_g).lu().solve(&rhs).unwrap();
        [f[0] * g, f[1] * g, f[2] * g]
    }

    #[test]
    fn k_a_and_nabla_b_match_the_reference_values() {
        let cal = paper_unit();
        let e = expected();
        let (fitted, _) = cal.statics.to_fitted().unwrap();
        let ka = linalg::inverse(&fitted.m_out_per_g).unwrap();
        let nabla = linalg::mat_vec(&ka, &fitted.zero_bias_out);
        for i in 0..3 {
            for j in 0..3 {
                assert!(
                    (ka[i][j] - e.k_a_g_per_v[i][j]).abs() < 1e-7,
                    "K_A[{i}][{j}]"
                );
            }
            assert!((nabla[i] - e.nabla_b_g[i]).abs() < 1e-7, "nabla_b[{i}]");
        }
        // And the f32 compensator holds g·K_A.
        let c = Compensator::new(&cal, LeverMode::Off).unwrap();
        for i in 0..3 {
            for j in 0..3 {
                let want = e.k_a_g_per_v[i][j] * cal.gravity_m_s2;
                assert!(
                    (f64::from(c.ka_m_s2_per_out[i][j]) - want).abs() < 2e-6 * want.abs().max(1.0)
                );
            }
        }
    }

    fn spin_error_mg(rate_deg_s: f64) -> [f64; 3] {
        let cal = paper_unit();
        let model = ForwardModel::new(&cal).unwrap();
        let mut t = TableState::at_rest([1.0, 0.0, 0.0]);
        t.rate_rad_s = rate_deg_s.to_radians();
        let motion = t.motion(cal.gravity_m_s2);
        let u = model.outputs(&motion);
        let c = Compensator::new(&cal, LeverMode::Off).unwrap();
        let (u32_, _, _) = f32_inputs(&u, &motion);
        let f = c.compensate_static(&u32_).to_f64();
        core::array::from_fn(|j| (f.m_s2[j] - motion.f_o.m_s2[j]).abs() / cal.gravity_m_s2 * 1e3)
    }

    #[test]
    fn static_only_spin_errors_match_the_reference() {
        let e = expected();
        for (rate, want) in [
            (100.0, e.x_up_spin_error_mg_100dps),
            (200.0, e.x_up_spin_error_mg_200dps),
        ] {
            let got = spin_error_mg(rate);
            for j in 0..3 {
                // The reference values are printed to 1 µg (0.001 mg); f32 adds < 1 µg.
                assert!(
                    (got[j] - want[j]).abs() < 2e-3,
                    "{rate} °/s axis {j}: {got:?} vs {want:?}"
                );
            }
        }
    }

    #[test]
    fn full_compensation_removes_the_spin_error() {
        let cal = paper_unit();
        let model = ForwardModel::new(&cal).unwrap();
        let mut t = TableState::at_rest([1.0, 0.0, 0.0]);
        t.rate_rad_s = 200f64.to_radians();
        let motion = t.motion(cal.gravity_m_s2);
        let (u, w, wd) = f32_inputs(&model.outputs(&motion), &motion);
        let f = Compensator::new(&cal, LeverMode::RateOnly)
            .unwrap()
            .compensate(&u, &w, &wd);
        for j in 0..3 {
            // f32 of a 2.4 V output resolves ~0.3 µg; allow 2 µg.
            let err_g = (f64::from(f.m_s2[j]) - motion.f_o.m_s2[j]) / cal.gravity_m_s2;
            assert!(err_g.abs() < 2e-6, "axis {j}: {err_g}");
        }
    }

    #[test]
    fn mode_off_ignores_the_gyro_and_rate_only_ignores_omega_dot() {
        let cal = paper_unit();
        let u = SensorOutputs {
            raw: [2.8, 2.4, 2.4],
        };
        let w = BodyRate {
            rad_s: [3.0, -1.0, 0.5],
        };
        let wd = BodyAngularAccel {
            rad_s2: [40.0, 10.0, -20.0],
        };
        let off = Compensator::new(&cal, LeverMode::Off).unwrap();
        assert_eq!(off.compensate(&u, &w, &wd), off.compensate_static(&u));
        let rate = Compensator::new(&cal, LeverMode::RateOnly).unwrap();
        assert_eq!(
            rate.compensate(&u, &w, &wd),
            rate.compensate(&u, &w, &BodyAngularAccel::default())
        );
        let full = Compensator::new(&cal, LeverMode::RateAndAcceleration).unwrap();
        assert_ne!(full.compensate(&u, &w, &wd), rate.compensate(&u, &w, &wd));
    }

    #[test]
    fn unusable_calibrations_are_refused() {
        let mut cal = paper_unit();
        cal.gravity_m_s2 = f64::NAN;
        assert_eq!(
            Compensator::new(&cal, LeverMode::Off).unwrap_err(),
            CompensatorError::Gravity
        );
        let mut cal = paper_unit();
        cal.statics.installation_angles_deg[1] = cal.statics.installation_angles_deg[0];
        assert!(matches!(
            Compensator::new(&cal, LeverMode::Off).unwrap_err(),
            CompensatorError::IllConditioned { .. }
        ));
        let mut cal = paper_unit();
        cal.lever_arms.r_m[2][1] = f64::INFINITY;
        assert!(matches!(
            Compensator::new(&cal, LeverMode::RateOnly),
            Err(CompensatorError::Params(_))
        ));
    }

    /// The true gyro output `w = G ω + b(T)` of a body rate (docs/model.md §8), rounded to f32.
    fn gyro_output(
        g: &crate::GyroCorrection,
        t: Option<&TemperatureModel>,
        temp_c: f64,
        omega: &[f64; 3],
    ) -> [f32; 3] {
        let gw = linalg::mat_vec(&g.matrix, omega);
        core::array::from_fn(|i| {
            let drift = t.map_or(0.0, |t| {
                poly_no_constant(&t.gyro_bias_polynomials()[i], temp_c - t.reference_c)
            });
            (gw[i] + g.bias_rad_s[i] + drift) as f32
        })
    }

    /// The true outputs at temperature `temp_c` (docs/model.md §9), from the forward model at the
    /// reference: `U(T) = u0 + P(ΔT) + diag(1 + s(T)) (U_ref − u0)`.
    fn outputs_at(
        cal: &Calibration,
        t: &TemperatureModel,
        temp_c: f64,
        m: &BodyMotion,
    ) -> [f32; 3] {
        let u = ForwardModel::new(cal).unwrap().outputs(m);
        let u0 = cal.statics.zero_bias_out;
        let dt = temp_c - t.reference_c;
        core::array::from_fn(|i| {
            let gain = 1.0 + poly_no_constant(&t.scale_rel_per_c[i], dt);
            (u0[i] + poly_no_constant(&t.zero_bias_out_per_c[i], dt) + gain * (u.raw[i] - u0[i]))
                as f32
        })
    }

    fn spinning_motion(cal: &Calibration) -> BodyMotion {
        let mut t = TableState::at_rest([0.6, -0.48, 0.64]);
        t.rate_rad_s = 250f64.to_radians();
        t.motion(cal.gravity_m_s2)
    }

    #[test]
    fn gyro_correction_recovers_the_body_rate_and_the_compensation() {
        let (gyro, _) = crate::blob::tests::gyro_and_temperature();
        let mut cal = paper_unit();
        cal.gyro = Some(gyro);
        let motion = spinning_motion(&cal);
        let w = gyro_output(&gyro, None, 25.0, &motion.omega.rad_s);
        let c = Compensator::new(&cal, LeverMode::RateOnly).unwrap();
        let omega = c.correct_rate(&w);
        for j in 0..3 {
            // f32 rounding of a 4.4 rad/s rate: a few 1e-7 rad/s.
            assert!(
                (f64::from(omega.rad_s[j]) - motion.omega.rad_s[j]).abs() < 2e-6,
                "{omega:?}"
            );
        }
        let u = ForwardModel::new(&cal).unwrap().outputs(&motion);
        let u = SensorOutputs {
            raw: u.raw.map(|v| v as f32),
        };
        let corrected = c.compensate(&u, &omega, &BodyAngularAccel::default());
        let naive = c.compensate(&u, &BodyRate { rad_s: w }, &BodyAngularAccel::default());
        let err_g = |f: &BodySpecificForce, j: usize| {
            (f64::from(f.m_s2[j]) - motion.f_o.m_s2[j]).abs() / cal.gravity_m_s2
        };
        for j in 0..3 {
            assert!(err_g(&corrected, j) < 2e-6, "axis {j}: {corrected:?}");
        }
        // Without the correction this gyro leaves tens of µg (the size of the effect being fixed).
        assert!((0..3).map(|j| err_g(&naive, j)).fold(0.0, f64::max) > 2e-5);
    }

    #[test]
    fn refresh_follows_the_temperature_model() {
        let (gyro, t) = crate::blob::tests::gyro_and_temperature();
        let mut cal = paper_unit();
        cal.gyro = Some(gyro);
        cal.temperature = Some(t);
        let motion = spinning_motion(&cal);
        let fresh = Compensator::new(&cal, LeverMode::RateOnly).unwrap();
        assert_eq!(fresh.temperature_state(), TemperatureState::NoReading);
        for temp in [-20.0, 0.0, 25.0, 45.0, 60.0] {
            let mut c = fresh;
            assert_eq!(c.refresh(temp as f32), TemperatureState::InRange);
            let u = SensorOutputs {
                raw: outputs_at(&cal, &t, temp, &motion),
            };
            let w = gyro_output(&gyro, Some(&t), temp, &motion.omega.rad_s);
            let omega = c.correct_rate(&w);
            let f = c.compensate(&u, &omega, &BodyAngularAccel::default());
            let stale = fresh.compensate(&u, &fresh.correct_rate(&w), &BodyAngularAccel::default());
            let mut worst = [0.0f64; 2];
            for j in 0..3 {
                assert!((f64::from(omega.rad_s[j]) - motion.omega.rad_s[j]).abs() < 2e-6);
                let e = |f: &BodySpecificForce| {
                    (f64::from(f.m_s2[j]) - motion.f_o.m_s2[j]).abs() / cal.gravity_m_s2
                };
                worst = [worst[0].max(e(&f)), worst[1].max(e(&stale))];
            }
            assert!(worst[0] < 3e-6, "{temp} °C: {} µg", worst[0] * 1e6);
            if temp != 25.0 {
                // Without the refresh the reference values are off by milli-g.
                assert!(worst[1] > 1e-3, "{temp} °C: {}", worst[1]);
            }
        }
        // At the reference the refresh changes nothing, bit for bit.
        let mut c = fresh;
        c.refresh(25.0);
        assert_eq!(
            (c.zero_bias_out, c.ka_m_s2_per_out, c.p, c.q, c.s, c.gyro),
            (
                fresh.zero_bias_out,
                fresh.ka_m_s2_per_out,
                fresh.p,
                fresh.q,
                fresh.s,
                fresh.gyro
            )
        );
    }

    #[test]
    fn refresh_clamps_out_of_range_and_keeps_terms_on_a_bad_reading() {
        let (_, t) = crate::blob::tests::gyro_and_temperature();
        let mut cal = paper_unit();
        cal.temperature = Some(t);
        let mut c = Compensator::new(&cal, LeverMode::RateAndAcceleration).unwrap();
        let mut at_end = c;
        assert_eq!(at_end.refresh(60.0), TemperatureState::InRange);
        assert_eq!(c.refresh(95.0), TemperatureState::Clamped);
        assert!(c.temperature_state().is_flagged());
        assert_eq!(c, {
            let mut e = at_end;
            e.temperature = TemperatureState::Clamped;
            e
        });
        assert_eq!(c.refresh(f32::NAN), TemperatureState::NoReading);
        assert_eq!(c.ka_m_s2_per_out, at_end.ka_m_s2_per_out);
        assert_eq!(at_end.refresh(f32::INFINITY), TemperatureState::NoReading);
        // Without a model nothing happens and nothing is flagged.
        let mut plain = Compensator::new(&paper_unit(), LeverMode::RateOnly).unwrap();
        let before = plain;
        assert_eq!(plain.refresh(-60.0), TemperatureState::NotModelled);
        assert!(!plain.temperature_state().is_flagged());
        assert_eq!(plain, before);
    }

    /// A random but plausible unit: biases, scales in V/g or LSB/g, axes tilted up to 3°, lever arms up
    /// to 3 cm.
    pub(crate) fn arb_unit() -> impl Strategy<Value = Calibration> {
        let lsb = any::<bool>();
        (
            lsb,
            prop::array::uniform3(-1.0f64..1.0),
            prop::array::uniform3(0.8f64..1.25),
            prop::array::uniform3(prop::array::uniform3(-3.0f64..3.0)),
            prop::array::uniform3(prop::array::uniform3(-0.03f64..0.03)),
            9.78f64..9.83,
        )
            .prop_map(|(lsb, bias, scale, tilt, r, g)| {
                let (unit, k0, u00) = if lsb {
                    (OutputUnit::Lsb, 4096.0, 0.0)
                } else {
                    (OutputUnit::Volts, 0.4, 2.5)
                };
                let k0_bias = if lsb { 200.0 } else { 0.1 };
                let angles = core::array::from_fn(|i| {
                    core::array::from_fn(|j| if i == j { 0.0 } else { 90.0 + tilt[i][j] })
                });
                // Make the rows consistent unit vectors: build them from cosines, then read angles back.
                let statics = StaticParams {
                    output_unit: unit,
                    zero_bias_out: bias.map(|b| u00 + b * k0_bias),
                    scale_out_per_g: scale.map(|s| s * k0),
                    installation_angles_deg: angles,
                };
                let statics = statics.to_fitted().unwrap().0.to_paper().unwrap();
                Calibration {
                    statics,
                    lever_arms: LeverArms { r_m: r },
                    reference: ReferencePoint::TableAxis,
                    gravity_m_s2: g,
                    gyro: None,
                    temperature: None,
                }
            })
    }

    /// Random motion: any specific force up to 3 g, rates up to 600 °/s, ω̇ up to 50 rad/s².
    fn arb_motion() -> impl Strategy<Value = BodyMotion> {
        (
            prop::array::uniform3(-30.0f64..30.0),
            prop::array::uniform3(-10.5f64..10.5),
            prop::array::uniform3(-50.0f64..50.0),
        )
            .prop_map(|(f, w, wd)| BodyMotion {
                f_o: BodySpecificForce { m_s2: f },
                omega: BodyRate { rad_s: w },
                omega_dot: BodyAngularAccel { rad_s2: wd },
            })
    }

    proptest! {
        #![proptest_config(ProptestConfig { cases: 2000, ..ProptestConfig::default() })]

        /// Forward model then f32 compensation returns the motion's specific force.
        ///
        /// Bound: the f32 path rounds each output to 2⁻²⁴ relative. For outputs up to |U| ≈ 3 V
        /// (or 2¹⁵ LSB) and ~60 operations, the error stays below 4·10⁻⁶ of the full-scale specific force
        /// (30 m/s² plus the lever term ω²r ≈ 3.3 m/s²); we assert 2·10⁻⁴ m/s² (20 µg).
        #[test]
        fn forward_then_f32_inverse_round_trips(cal in arb_unit(), motion in arb_motion()) {
            let model = ForwardModel::new(&cal).unwrap();
            let u = model.outputs(&motion);
            let (u32_, w, wd) = f32_inputs(&u, &motion);
            let f = Compensator::new(&cal, LeverMode::RateAndAcceleration).unwrap().compensate(&u32_, &w, &wd);
            for j in 0..3 {
                let err = (f64::from(f.m_s2[j]) - motion.f_o.m_s2[j]).abs();
                prop_assert!(err < 2e-4, "axis {} err {} m/s²", j, err);
            }
        }

        /// Random gyro errors (1 % scale, 1° misalignment, 1 °/s bias) and a random temperature in
        /// the model's range: the refreshed, gyro-corrected f32 path returns the true specific force
        /// (the forward model at that temperature, docs/model.md §8–§9), within the bound above.
        #[test]
        fn gyro_and_temperature_round_trip(
            cal in arb_unit(),
            motion in arb_motion(),
            scale in prop::array::uniform3(-0.01f64..0.01),
            mis in prop::array::uniform3(prop::array::uniform3(-0.0175f64..0.0175)),
            bias in prop::array::uniform3(-0.0175f64..0.0175),
            temp in -20.0f64..60.0,
        ) {
            let gyro = crate::GyroCorrection {
                matrix: core::array::from_fn(|i| core::array::from_fn(|j| {
                    if i == j { 1.0 + scale[i] } else { mis[i][j] }
                })),
                bias_rad_s: bias,
            };
            let (_, mut t) = crate::blob::tests::gyro_and_temperature();
            // Relative model: zero-bias terms in proportion to this unit's scale factor.
            let k = cal.statics.scale_out_per_g[0] / 0.4;
            t.zero_bias_out_per_c = t.zero_bias_out_per_c.map(|r| r.map(|c| c * k));
            let cal = Calibration { gyro: Some(gyro), temperature: Some(t), ..cal };
            let mut c = Compensator::new(&cal, LeverMode::RateAndAcceleration).unwrap();
            prop_assert_eq!(c.refresh(temp as f32), TemperatureState::InRange);
            let temp = f64::from(temp as f32);
            let u = SensorOutputs { raw: outputs_at(&cal, &t, temp, &motion) };
            let w = gyro_output(&gyro, Some(&t), temp, &motion.omega.rad_s);
            let wd = BodyAngularAccel { rad_s2: motion.omega_dot.rad_s2.map(|v| v as f32) };
            let f = c.compensate(&u, &c.correct_rate(&w), &wd);
            for j in 0..3 {
                let err = (f64::from(f.m_s2[j]) - motion.f_o.m_s2[j]).abs();
                prop_assert!(err < 2e-4, "axis {} err {} m/s²", j, err);
            }
        }

        /// The f32 compensator against the independent f64 reference on the same (f32-representable)
        /// inputs: same bound as above, so the precomputed cheap form is the same model as eq. 16.
        #[test]
        fn f32_matches_f64_reference(cal in arb_unit(), motion in arb_motion()) {
            let model = ForwardModel::new(&cal).unwrap();
            let u = model.outputs(&motion);
            let (u32_, w, wd) = f32_inputs(&u, &motion);
            let u_rounded = SensorOutputs { raw: u32_.raw.map(f64::from) };
            let m_rounded = BodyMotion {
                f_o: motion.f_o,
                omega: BodyRate { rad_s: w.rad_s.map(f64::from) },
                omega_dot: BodyAngularAccel { rad_s2: wd.rad_s2.map(f64::from) },
            };
            let want = reference_inverse(&cal, &u_rounded, &m_rounded);
            let got = Compensator::new(&cal, LeverMode::RateAndAcceleration).unwrap().compensate(&u32_, &w, &wd);
            for j in 0..3 {
                prop_assert!((f64::from(got.m_s2[j]) - want[j]).abs() < 2e-4);
            }
        }
    }
}
