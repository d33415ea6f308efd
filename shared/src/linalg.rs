//! Small fixed-size helpers over nalgebra, for the once-per-calibration `f64` work.
//!
//! Matrices cross module boundaries as plain row-major `[[f64; 3]; 3]` (row `i` = accelerometer `i`),
//! the layout used on the wire and in files; nalgebra types stay inside functions.

use nalgebra::{Matrix3, Vector3};

/// Row-major 3×3 matrix: `m[i][j]` is row `i`, column `j`.
pub type RowMajor3 = [[f64; 3]; 3];

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

/// Euclidean norm (exact, libm).
pub fn norm(a: &[f64; 3]) -> f64 {
    libm::sqrt(dot(a, a))
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
pub fn condition_number_1(m: &RowMajor3) -> f64 {
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
