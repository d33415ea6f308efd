//! The gyro's correction (docs/model.md §8) and the temperature model (docs/model.md §9): the two
//! optional parts of a [`crate::Calibration`] beyond the accelerometers' static and lever-arm terms.
//!
//! Both are checked here once, in `f64`, with typed errors; the per-sample and per-refresh `f32` forms
//! live in [`crate::compensator`].

use crate::linalg::{self, RowMajor3};
use postcard::experimental::max_size::MaxSize;
use serde::{Deserialize, Serialize};

/// Highest degree of a temperature polynomial.
pub const MAX_TEMPERATURE_DEGREE: usize = 3;
/// Largest accepted gyro bias, rad/s (57 °/s; an L3GD20H's zero-rate level is ±25 °/s at ±2000 °/s).
pub(crate) const MAX_GYRO_BIAS_RAD_S: f64 = 1.0;
/// Accepted range of each row norm of `G`: the gyro reports rad/s already, so its sensitivity is
/// within a factor of two of one unless the part or its setting is wrong.
pub(crate) const GYRO_ROW_NORM_RANGE: (f64, f64) = (0.5, 2.0);
/// Largest accepted 1-norm condition number of `G` (a pure rotation has at most 3).
pub(crate) const MAX_GYRO_CONDITION: f64 = 10.0;
/// Temperatures a model may cover, °C (beyond any electronics' rating).
pub const TEMPERATURE_LIMITS_C: (f64, f64) = (-100.0, 200.0);
/// Accepted range of the relative scale `1 + s(T)` over the valid range.
pub(crate) const SCALE_FACTOR_RANGE: (f64, f64) = (0.5, 2.0);

/// The gyro's measurement model `w = G·ω_body + b` (docs/model.md §8).
///
/// `G` is general: scale factors on its diagonal, axis misalignment and the gyro triad's alignment to
/// the body (accelerometer) frame off it. The device applies the inverse `ω = G⁻¹(w − b)`, with `G⁻¹`
/// computed once when the calibration loads.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize, MaxSize)]
pub struct GyroCorrection {
    /// `G`, row-major, dimensionless (gyro output per body rate): row `i` is gyro axis `i`.
    pub matrix: RowMajor3,
    /// `b`, the gyro's output at rest at the reference temperature, rad/s, gyro axes.
    pub bias_rad_s: [f64; 3],
}

impl GyroCorrection {
    /// A perfect gyro: `G = I`, `b = 0` (what an absent gyro section means).
    pub const PERFECT: GyroCorrection = GyroCorrection {
        matrix: [[1.0, 0.0, 0.0], [0.0, 1.0, 0.0], [0.0, 0.0, 1.0]],
        bias_rad_s: [0.0; 3],
    };

    /// Checks plausibility and returns `G⁻¹` (the exact inverse, never a transpose).
    pub fn checked_inverse(&self) -> Result<RowMajor3, GyroError> {
        let values = self.matrix.iter().flatten().chain(&self.bias_rad_s);
        if !values.copied().all(f64::is_finite) {
            return Err(GyroError::NonFinite);
        }
        for (i, row) in self.matrix.iter().enumerate() {
            let n = linalg::norm(row);
            if !(GYRO_ROW_NORM_RANGE.0..=GYRO_ROW_NORM_RANGE.1).contains(&n) {
                return Err(GyroError::ScaleOutOfRange { axis: i as u8 });
            }
        }
        if self
            .bias_rad_s
            .iter()
            .any(|b| b.abs() > MAX_GYRO_BIAS_RAD_S)
        {
            return Err(GyroError::BiasOutOfRange);
        }
        let condition = linalg::condition_number_1(&self.matrix);
        match linalg::inverse(&self.matrix) {
            Some(inv) if condition <= MAX_GYRO_CONDITION => Ok(inv),
            _ => Err(GyroError::IllConditioned),
        }
    }
}

/// Why a gyro correction cannot be used.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum GyroError {
    /// A value is NaN or infinite.
    NonFinite,
    /// Row `axis` of `G` has a norm outside `GYRO_ROW_NORM_RANGE`.
    ScaleOutOfRange {
        /// 0 = x, 1 = y, 2 = z.
        axis: u8,
    },
    /// A bias exceeds `MAX_GYRO_BIAS_RAD_S` (at some temperature of the valid range).
    BiasOutOfRange,
    /// `G` is singular or its condition number exceeds `MAX_GYRO_CONDITION`.
    IllConditioned,
}

impl core::fmt::Display for GyroError {
    fn fmt(&self, f: &mut core::fmt::Formatter<'_>) -> core::fmt::Result {
        match self {
            GyroError::NonFinite => f.write_str("the gyro correction contains NaN or infinite values"),
            GyroError::ScaleOutOfRange { axis } => write!(
                f,
                "gyro axis {} has a sensitivity outside {}..{} (is the gyro's range setting right?)",
                crate::params::axis_name(usize::from(*axis)),
                GYRO_ROW_NORM_RANGE.0,
                GYRO_ROW_NORM_RANGE.1
            ),
            GyroError::BiasOutOfRange => write!(
                f,
                "a gyro bias exceeds {MAX_GYRO_BIAS_RAD_S} rad/s within the calibrated temperature range"
            ),
            GyroError::IllConditioned => write!(
                f,
                "the gyro matrix is singular or ill-conditioned (limit {MAX_GYRO_CONDITION})"
            ),
        }
    }
}

/// Lets a host error name this one as its `source()`.
impl core::error::Error for GyroError {}

/// Coefficients of a polynomial without constant term, per axis: row `i` holds `c_i1, c_i2, c_i3`, so
/// that the value of axis `i` is `c_i1·ΔT + c_i2·ΔT² + c_i3·ΔT³` with `ΔT = T − T_ref` in °C. A lower
/// degree has zeros at the end. The constant term is the calibration's own value at `T_ref`.
pub(crate) type AxisPolynomials = [[f64; MAX_TEMPERATURE_DEGREE]; 3];

/// How the parameters move with temperature (docs/model.md §9). Every polynomial is zero at
/// `reference_c`, where the calibration's static values and gyro bias hold:
///
/// ```text
/// u0_i(T) = u0_i + P_i(ΔT)               (zero bias, output unit)
/// M(T)    = diag(1 + s(T)) · M,  s_i(T) = S_i(ΔT)   (relative scale; the misalignment stays constant)
/// b_j(T)  = b_j + B_j(ΔT)                (gyro bias, rad/s; zero polynomials when absent)
/// ```
///
/// Outside `valid_range_c` the device evaluates the polynomials at the nearest end of the range and
/// flags its outputs: a fitted cubic is not trusted beyond its data.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize, MaxSize)]
pub struct TemperatureModel {
    /// `T_ref`, °C.
    pub reference_c: f64,
    /// The temperatures the calibration covers, `[low, high]`, °C.
    pub valid_range_c: [f64; 2],
    /// `P_i`: zero bias change, output unit per °C^k.
    pub zero_bias_out_per_c: AxisPolynomials,
    /// `S_i`: relative scale change, 1 per °C^k.
    pub scale_rel_per_c: AxisPolynomials,
    /// `B_j`: gyro bias change, rad/s per °C^k (`None`: the gyro bias does not change).
    pub gyro_bias_rad_s_per_c: Option<AxisPolynomials>,
}

/// Why a temperature model cannot be used.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum TemperatureModelError {
    /// A value is NaN or infinite.
    NonFinite,
    /// The valid range is empty, reversed, beyond [`TEMPERATURE_LIMITS_C`], or does not contain the
    /// reference temperature.
    BadRange,
    /// `1 + s_i(T)` leaves `SCALE_FACTOR_RANGE` somewhere in the valid range, for accelerometer `axis`.
    ScaleOutOfRange {
        /// 0 = x, 1 = y, 2 = z.
        axis: u8,
    },
}

impl core::fmt::Display for TemperatureModelError {
    fn fmt(&self, f: &mut core::fmt::Formatter<'_>) -> core::fmt::Result {
        match self {
            TemperatureModelError::NonFinite => {
                f.write_str("the temperature model contains NaN or infinite values")
            }
            TemperatureModelError::BadRange => write!(
                f,
                "the temperature model's valid range must be low < high within {}..{} °C and contain the reference temperature",
                TEMPERATURE_LIMITS_C.0, TEMPERATURE_LIMITS_C.1
            ),
            TemperatureModelError::ScaleOutOfRange { axis } => write!(
                f,
                "the temperature model takes accelerometer {}'s relative scale outside {}..{} within its valid range",
                crate::params::axis_name(usize::from(*axis)),
                SCALE_FACTOR_RANGE.0,
                SCALE_FACTOR_RANGE.1
            ),
        }
    }
}

/// `c1·x + c2·x² + c3·x³` (Horner).
pub fn poly_no_constant(c: &[f64; MAX_TEMPERATURE_DEGREE], x: f64) -> f64 {
    x * (c[0] + x * (c[1] + x * c[2]))
}

/// Temperatures at which [`TemperatureModel::check`] evaluates the polynomials (ends included).
const CHECK_POINTS: usize = 65;

impl TemperatureModel {
    /// The gyro bias polynomials, zero when absent.
    pub fn gyro_bias_polynomials(&self) -> AxisPolynomials {
        self.gyro_bias_rad_s_per_c.unwrap_or([[0.0; 3]; 3])
    }

    /// Temperatures spanning the valid range evenly, ends included.
    pub fn check_points(&self) -> impl Iterator<Item = f64> + '_ {
        let [lo, hi] = self.valid_range_c;
        (0..CHECK_POINTS).map(move |k| lo + (hi - lo) * k as f64 / (CHECK_POINTS - 1) as f64)
    }

    /// Checks the range and that the relative scale stays plausible over it. The gyro bias and the
    /// device's `f32` range are checked where they are combined with the rest ([`crate::Compensator`]).
    pub fn check(&self) -> Result<(), TemperatureModelError> {
        let numbers = [
            self.reference_c,
            self.valid_range_c[0],
            self.valid_range_c[1],
        ];
        let gyro_bias = self.gyro_bias_polynomials();
        let coefficients = self
            .zero_bias_out_per_c
            .iter()
            .chain(&self.scale_rel_per_c)
            .chain(&gyro_bias)
            .flatten()
            .copied();
        if !numbers.into_iter().chain(coefficients).all(f64::is_finite) {
            return Err(TemperatureModelError::NonFinite);
        }
        let [lo, hi] = self.valid_range_c;
        let (min, max) = TEMPERATURE_LIMITS_C;
        if !(min <= lo && lo < hi && hi <= max && (lo..=hi).contains(&self.reference_c)) {
            return Err(TemperatureModelError::BadRange);
        }
        for t in self.check_points() {
            for (i, c) in self.scale_rel_per_c.iter().enumerate() {
                let g = 1.0 + poly_no_constant(c, t - self.reference_c);
                if !(SCALE_FACTOR_RANGE.0..=SCALE_FACTOR_RANGE.1).contains(&g) {
                    return Err(TemperatureModelError::ScaleOutOfRange { axis: i as u8 });
                }
            }
        }
        Ok(())
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn model() -> TemperatureModel {
        TemperatureModel {
            reference_c: 25.0,
            valid_range_c: [-20.0, 60.0],
            zero_bias_out_per_c: [[1e-4, 1e-6, 0.0]; 3],
            scale_rel_per_c: [[150e-6, 0.0, 0.0]; 3],
            gyro_bias_rad_s_per_c: None,
        }
    }

    #[test]
    fn perfect_gyro_inverts_to_identity() {
        assert_eq!(
            GyroCorrection::PERFECT.checked_inverse().unwrap(),
            GyroCorrection::PERFECT.matrix
        );
    }

    #[test]
    fn implausible_gyros_are_typed_errors() {
        let mut g = GyroCorrection::PERFECT;
        g.bias_rad_s[1] = f64::NAN;
        assert_eq!(g.checked_inverse(), Err(GyroError::NonFinite));
        let mut g = GyroCorrection::PERFECT;
        g.bias_rad_s[2] = 1.5;
        assert_eq!(g.checked_inverse(), Err(GyroError::BiasOutOfRange));
        let mut g = GyroCorrection::PERFECT;
        g.matrix[1] = [0.0, 4.0, 0.0];
        assert_eq!(
            g.checked_inverse(),
            Err(GyroError::ScaleOutOfRange { axis: 1 })
        );
        let mut g = GyroCorrection::PERFECT;
        g.matrix[2] = [1.0, 0.0, 0.0];
        assert_eq!(g.checked_inverse(), Err(GyroError::IllConditioned));
        // An axis permutation (the gyro mounted turned by 90°) is a valid G.
        let mut g = GyroCorrection::PERFECT;
        g.matrix = [[0.0, 1.0, 0.0], [-1.0, 0.0, 0.0], [0.0, 0.0, 1.0]];
        assert!(g.checked_inverse().is_ok());
    }

    #[test]
    fn polynomial_is_zero_at_the_reference_and_horner_matches_powers() {
        let c = [2.0, -0.5, 0.25];
        assert_eq!(poly_no_constant(&c, 0.0), 0.0);
        let x = 3.0;
        assert_eq!(
            poly_no_constant(&c, x),
            2.0 * x - 0.5 * x * x + 0.25 * x * x * x
        );
    }

    #[test]
    fn temperature_model_checks() {
        assert_eq!(model().check(), Ok(()));
        let mut m = model();
        m.valid_range_c = [60.0, -20.0];
        assert_eq!(m.check(), Err(TemperatureModelError::BadRange));
        let mut m = model();
        m.reference_c = 80.0;
        assert_eq!(m.check(), Err(TemperatureModelError::BadRange));
        let mut m = model();
        m.scale_rel_per_c[1] = [0.0, 0.0, 1e-3]; // 1 + 1e-3·(−45)³ < 0 at −20 °C
        assert_eq!(
            m.check(),
            Err(TemperatureModelError::ScaleOutOfRange { axis: 1 })
        );
        let mut m = model();
        m.gyro_bias_rad_s_per_c = Some([[f64::INFINITY, 0.0, 0.0]; 3]);
        assert_eq!(m.check(), Err(TemperatureModelError::NonFinite));
    }
}
