//! Small fixed-size helpers over nalgebra, for the once-per-calibration `f64` work.
//!
//! Matrices cross module boundaries as plain row-major `[[f64; 3]; 3]` (row `i` = accelerometer `i`),
//! the layout used on the wire and in files; nalgebra types stay inside functions.

use nalgebra::{Matrix3, Vector3};

/// Row-major 3×3 matrix: `m[i][j]` is row `i`, column `j`.
pub type RowMajor3 = [[f64; 3]; 3];

/// The 3×3 identity.
pub const IDENTITY: RowMajor3 = [[1.0, 0.0, 0.0], [0.0, 1.0, 0.0], [0.0, 0.0, 1.0]];

/// nalgebra matrix from row-major rows.
pub fn to_na(m: &RowMajor3) -> Matrix3<f64> {
    Matrix3::from_fn(|i, j| m[i][j])
}

/// Row-major rows from a nalgebra matrix.
pub fn from_na(m: &Matrix3<f64>) -> RowMajor3 {
    core::array::from_fn(|i| core::array::from_fn(|j| m[(i, j)]))
}

/// Dot product.
pub fn dot(a: &[f64; 3], b: &[f64; 3]) -> f64 {
    a[0] * b[0] + a[1] * b[1] + a[2] * b[2]
}

/// Cross product `a × b`.
pub fn cross(a: &[f64; 3], b: &[f64; 3]) -> [f64; 3] {
    [
        a[1] * b[2] - a[2] * b[1],
        a[2] * b[0] - a[0] * b[2],
        a[0] * b[1] - a[1] * b[0],
    ]
}

/// Euclidean norm (the square root correctly rounded: [`sqrt`]).
pub fn norm(a: &[f64; 3]) -> f64 {
    sqrt(dot(a, a))
}

/// `√x`, correctly rounded as IEEE 754 defines it, so the same bits on every target: `libm::sqrt`
/// (the FPU's instruction on the PC) where the FPU has one for `f64`, [`sqrt_digit_by_digit`] on the
/// Cortex-M4F, whose FPU is single precision and where `libm`'s table-driven software form would
/// cost the image 0.8 KiB.
#[inline]
pub fn sqrt(x: f64) -> f64 {
    #[cfg(target_os = "none")]
    return sqrt_digit_by_digit(x);
    #[cfg(not(target_os = "none"))]
    return libm::sqrt(x);
}

/// `√x` digit by digit on the significand (fdlibm's "bit by bit" method in 64-bit words): 54 bits of
/// the root, the last one deciding the rounding to nearest (an exact halfway case cannot occur for a
/// square root). Correctly rounded, so bit for bit `libm::sqrt`; tested against it below. NaN and
/// `x < 0` give NaN, ±0 and +∞ themselves. About 54 iterations of 64-bit integer steps: for the
/// once-per-calibration work only.
pub fn sqrt_digit_by_digit(x: f64) -> f64 {
    if x.is_nan() || x == 0.0 || x == f64::INFINITY {
        return x;
    }
    if x < 0.0 {
        return f64::NAN;
    }
    let bits = x.to_bits();
    let biased = (bits >> 52) as i32; // the sign is 0
    let mut m = bits & ((1 << 52) - 1);
    // x = (m / 2⁵²)·2^exp with m in [2⁵², 2⁵³): subnormals normalised.
    let mut exp = if biased == 0 {
        let shift = m.leading_zeros() - 11;
        m <<= shift;
        -1022 - shift as i32
    } else {
        m |= 1 << 52;
        biased - 1023
    };
    // An even exponent: m in [2⁵², 2⁵⁴).
    if exp & 1 != 0 {
        m <<= 1;
        exp -= 1;
    }
    // q: the root's 54 bits, one per step from the top; r the remainder, doubled each step.
    let mut r = m << 1;
    let (mut q, mut s, mut bit) = (0u64, 0u64, 1u64 << 53);
    while bit != 0 {
        let t = s + bit;
        if t <= r {
            s = t + bit;
            r -= t;
            q += bit;
        }
        r <<= 1;
        bit >>= 1;
    }
    // Round to nearest on the last bit; the significand (with its leading bit, which adds one to
    // the exponent field) may carry into the exponent.
    let significand = (q + (q & 1)) >> 1;
    f64::from_bits((((exp / 2 + 1022) as u64) << 52) + significand)
}

/// `a / |a|`; a zero vector stays zero (divided by the smallest positive number, not by 0).
pub fn unit(a: &[f64; 3]) -> [f64; 3] {
    let n = norm(a).max(f64::MIN_POSITIVE);
    a.map(|c| c / n)
}

/// `m · v` for a row-major matrix.
pub fn mat_vec(m: &RowMajor3, v: &[f64; 3]) -> [f64; 3] {
    [dot(&m[0], v), dot(&m[1], v), dot(&m[2], v)]
}

/// `W = [ω̇×] + [ω×]²` (paper eq. 11), row-major, so that `W r = ω̇ × r + ω × (ω × r)`.
pub fn lever_matrix(omega: &[f64; 3], omega_dot: &[f64; 3]) -> RowMajor3 {
    let w = Vector3::from(*omega);
    let wd = Vector3::from(*omega_dot);
    let m = wd.cross_matrix() + w.cross_matrix() * w.cross_matrix();
    from_na(&m)
}

/// The exact inverse, or `None` when the matrix is singular (never a transpose: `docs/model.md` §4.1).
pub fn inverse(m: &RowMajor3) -> Option<RowMajor3> {
    to_na(m).try_inverse().map(|inv| from_na(&inv))
}

/// 1-norm condition number `‖M‖₁ ‖M⁻¹‖₁` (∞ when singular). Cheap and deterministic: no iteration.
pub(crate) fn condition_number_1(m: &RowMajor3) -> f64 {
    let norm1 = |a: &RowMajor3| {
        (0..3)
            .map(|j| libm::fabs(a[0][j]) + libm::fabs(a[1][j]) + libm::fabs(a[2][j]))
            .fold(0.0, f64::max)
    };
    match inverse(m) {
        Some(inv) => norm1(m) * norm1(&inv),
        None => f64::INFINITY,
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use proptest::prelude::*;

    fn same_sqrt(x: f64) {
        let (got, want) = (sqrt_digit_by_digit(x), libm::sqrt(x));
        assert!(
            got.to_bits() == want.to_bits() || (got.is_nan() && want.is_nan()),
            "sqrt({x:e} = {:#x}): {got:e} vs {want:e}",
            x.to_bits()
        );
    }

    /// Special values, subnormals, powers of two, perfect squares and their neighbours (where the
    /// rounding is closest to halfway), the extremes.
    #[test]
    fn sqrt_digit_by_digit_is_libm_at_the_edges() {
        for x in [
            0.0,
            -0.0,
            1.0,
            2.0,
            0.25,
            -1.0,
            -f64::MIN_POSITIVE,
            f64::INFINITY,
            f64::NEG_INFINITY,
            f64::NAN,
            f64::MAX,
            f64::MIN_POSITIVE,
            f64::from_bits(1),
            f64::from_bits(2),
            f64::from_bits(3),
            f64::from_bits(0x000F_FFFF_FFFF_FFFF),
            f64::EPSILON,
        ] {
            same_sqrt(x);
        }
        for e in -1074i64..1024 {
            // 2^e, subnormal below −1022.
            let p = if e < -1022 {
                1u64 << (e + 1074)
            } else {
                ((e + 1023) as u64) << 52
            };
            same_sqrt(f64::from_bits(p));
            same_sqrt(f64::from_bits(p + 1));
            same_sqrt(f64::from_bits(p - 1));
        }
        let mut k = 1u64;
        while k < 1 << 26 {
            let sq = (k * k) as f64;
            for d in [-2i64, -1, 0, 1, 2] {
                same_sqrt(f64::from_bits(sq.to_bits().wrapping_add_signed(d)));
            }
            k = k * 3 / 2 + 1;
        }
        for b in 0..200_000u64 {
            // Subnormals across their range.
            same_sqrt(f64::from_bits(b.wrapping_mul(0x9E37_79B9_7F4A_7C15) >> 12));
        }
    }

    proptest! {
        #![proptest_config(ProptestConfig::with_cases(100_000))]
        /// Any positive bit pattern.
        #[test]
        fn sqrt_digit_by_digit_is_libm(bits in 0u64..0x7FF0_0000_0000_0000) {
            same_sqrt(f64::from_bits(bits));
        }
    }

    #[test]
    fn lever_matrix_matches_vector_identity() {
        let w = [0.3, -1.2, 2.0];
        let wd = [4.0, 0.5, -3.0];
        let r = [0.01, -0.02, 0.005];
        let lhs = mat_vec(&lever_matrix(&w, &wd), &r);
        let wxr = cross(&w, &r);
        let rhs_t = cross(&wd, &r);
        let rhs_n = cross(&w, &wxr);
        for k in 0..3 {
            assert!((lhs[k] - (rhs_t[k] + rhs_n[k])).abs() < 1e-15);
        }
    }

    #[test]
    fn inverse_and_condition() {
        let m = [[2.0, 0.0, 0.0], [0.0, 4.0, 0.0], [0.0, 0.0, 0.5]];
        let inv = inverse(&m).unwrap();
        assert_eq!(inv, [[0.5, 0.0, 0.0], [0.0, 0.25, 0.0], [0.0, 0.0, 2.0]]);
        assert!((condition_number_1(&m) - 8.0).abs() < 1e-12);
        let singular = [[1.0, 2.0, 3.0], [2.0, 4.0, 6.0], [0.0, 0.0, 1.0]];
        assert!(inverse(&singular).is_none());
        assert!(condition_number_1(&singular).is_infinite());
    }
}
