//! `cos` of a moderate argument, bit for bit `libm::cos` without its large-argument reduction.
//!
//! [`crate::StaticParams::sensing_directions`] takes nine cosines of installation angles, which lie
//! in 0..180° for any real unit. `libm::cos` reduces every argument above 2²⁰·π/2 with the
//! Payne–Hanek reduction (`rem_pio2_large` and its 2/π table), which the firmware carried, inlined
//! into `to_fitted`, for angles that never occur: about 4 KiB of the QEMU image. [`cos_moderate`]
//! is `libm::cos` for `|x| < 2²⁰·π/2` — the same kernels and constants, the same Cody–Waite
//! reduction, the same operations in the same order, so it returns the same bits on every target
//! (checked against `libm::cos` by the tests below) — and refuses the rest with `None`.
//!
//! From the `libm` crate 0.2.16 (`src/math/{cos,rem_pio2,k_cos,k_sin}.rs`, MIT licence), which
//! derives them from FreeBSD's msun:
//!
//! > Copyright (C) 1993 by Sun Microsystems, Inc. All rights reserved.
//! >
//! > Developed at SunPro, a Sun Microsystems, Inc. business. Permission to use, copy, modify, and
//! > distribute this software is freely granted, provided that this notice is preserved.
//!
//! (`rem_pio2` optimized by Bruce D. Evans.)

/// `|x|`'s upper word at or above this: beyond 2²⁰·π/2, where the Cody–Waite reduction in three
/// parts of π/2 stops being exact and `libm` switches to Payne–Hanek. [`cos_moderate`] refuses it.
const MODERATE_LIMIT_HI: u32 = 0x4139_21fb;

/// Largest installation angle (degrees, either sign) whose cosine [`cos_moderate`] gives: 2²⁰·90°
/// less a margin for the rounding of the conversion to radians.
pub(crate) const MAX_ANGLE_DEG: f64 = 94_000_000.0;

/// `libm::cos(x)` bit for bit for `|x| < 2²⁰·π/2` (about 1.6·10⁶ rad, 9.4·10⁷°); `None` above it
/// and for NaN or infinite `x`.
pub(crate) fn cos_moderate(x: f64) -> Option<f64> {
    let ix = (x.to_bits() >> 32) as u32 & 0x7fff_ffff;
    if ix <= 0x3fe9_21fb {
        // |x| ≲ π/4: no reduction.
        if ix < 0x3e46_a09e && x as i32 == 0 {
            // |x| < 2⁻²⁷·√2.
            return Some(1.0);
        }
        return Some(k_cos(x, 0.0));
    }
    if ix >= MODERATE_LIMIT_HI {
        return None;
    }
    let (n, y0, y1) = rem_pio2(x, ix);
    Some(match n & 3 {
        0 => k_cos(y0, y1),
        1 => -k_sin(y0, y1),
        2 => -k_cos(y0, y1),
        _ => k_sin(y0, y1),
    })
}

/// 1.5 / f64::EPSILON: adding and subtracting it rounds to an integer.
const TO_INT: f64 = 1.5 / f64::EPSILON;
/// 53 bits of 2/π.
const INV_PIO2: f64 = f64::from_bits(0x3FE4_5F30_6DC9_C883);
/// The first 33 bits of π/2.
const PIO2_1: f64 = f64::from_bits(0x3FF9_21FB_5440_0000);
/// π/2 − PIO2_1.
const PIO2_1T: f64 = f64::from_bits(0x3DD0_B461_1A62_6331);
/// The second 33 bits of π/2.
const PIO2_2: f64 = f64::from_bits(0x3DD0_B461_1A60_0000);
/// π/2 − (PIO2_1 + PIO2_2).
const PIO2_2T: f64 = f64::from_bits(0x3BA3_198A_2E03_7073);
/// The third 33 bits of π/2.
const PIO2_3: f64 = f64::from_bits(0x3BA3_198A_2E00_0000);
/// π/2 − (PIO2_1 + PIO2_2 + PIO2_3).
const PIO2_3T: f64 = f64::from_bits(0x397B_839A_2520_49C1);

/// `x` less its nearest multiple `n·π/2`, as `y0 + y1`, for π/4 ≲ `|x|` < 2²⁰·π/2 (`ix`: `|x|`'s
/// upper word). `libm`'s `rem_pio2` without its large-argument branch.
fn rem_pio2(x: f64, ix: u32) -> (i32, f64, f64) {
    let near = |k: f64| one_step(x, k);
    if ix <= 0x400f_6a7a {
        // |x| ≲ 5π/4
        if (ix & 0xfffff) == 0x921fb {
            // |x| ≈ π/2 or π: cancellation.
            return medium(x, ix);
        }
        return near(if ix <= 0x4002_d97c { 1.0 } else { 2.0 });
    }
    if ix <= 0x401c_463b {
        // |x| ≲ 9π/4
        if ix <= 0x4015_fdbc {
            // |x| ≲ 7π/4
            if ix == 0x4012_d97c {
                // |x| ≈ 3π/2
                return medium(x, ix);
            }
            return near(3.0);
        }
        if ix == 0x4019_21fb {
            // |x| ≈ 2π
            return medium(x, ix);
        }
        return near(4.0);
    }
    medium(x, ix)
}

/// `x ∓ k·π/2` in one step (π/2 in two parts, 33 bits and the rest: good to 85 bits), for
/// `|x|` ≲ 9π/4 where the subtraction does not cancel; `k` is 1, 2, 3 or 4, of `x`'s sign.
#[inline(never)]
fn one_step(x: f64, k: f64) -> (i32, f64, f64) {
    let (n, p, t) = (k as i32, k * PIO2_1, k * PIO2_1T);
    if x.is_sign_negative() {
        let z = x + p;
        let y0 = z + t;
        (-n, y0, (z - y0) + t)
    } else {
        let z = x - p;
        let y0 = z - t;
        (n, y0, (z - y0) - t)
    }
}

/// The reduction for `|x|` < 2²⁰·π/2: `n = rint(x·2/π)`, then `x − n·π/2` with π/2 in up to three
/// 33-bit parts, as many as the cancellation needs.
#[inline(never)]
fn medium(x: f64, ix: u32) -> (i32, f64, f64) {
    // rint(x/(π/2)), round to nearest.
    let f_n = (x * INV_PIO2 + TO_INT) - TO_INT;
    let n = f_n as i32;
    let mut r = x - f_n * PIO2_1;
    let mut w = f_n * PIO2_1T; // first round, good to 85 bits
    let mut y0 = r - w;
    let ex = (ix >> 20) as i32;
    let ey = (y0.to_bits() >> 52) as i32 & 0x7ff;
    if ex - ey > 16 {
        // second round, good to 118 bits
        let t = r;
        w = f_n * PIO2_2;
        r = t - w;
        w = f_n * PIO2_2T - ((t - r) - w);
        y0 = r - w;
        let ey = (y0.to_bits() >> 52) as i32 & 0x7ff;
        if ex - ey > 49 {
            // third round, good to 151 bits, covers all cases
            let t = r;
            w = f_n * PIO2_3;
            r = t - w;
            w = f_n * PIO2_3T - ((t - r) - w);
            y0 = r - w;
        }
    }
    let y1 = (r - y0) - w;
    (n, y0, y1)
}

/// cos(x + y) on [−π/4, π/4], `y` the tail of `x` (a degree-14 polynomial, Remez error ≤ 2⁻⁵⁸).
fn k_cos(x: f64, y: f64) -> f64 {
    const C1: f64 = f64::from_bits(0x3FA5_5555_5555_554C);
    const C2: f64 = f64::from_bits(0xBF56_C16C_16C1_5177);
    const C3: f64 = f64::from_bits(0x3EFA_01A0_19CB_1590);
    const C4: f64 = f64::from_bits(0xBE92_7E4F_809C_52AD);
    const C5: f64 = f64::from_bits(0x3E21_EE9E_BDB4_B1C4);
    const C6: f64 = f64::from_bits(0xBDA8_FAE9_BE88_38D4);
    let z = x * x;
    let w = z * z;
    let r = z * (C1 + z * (C2 + z * C3)) + w * w * (C4 + z * (C5 + z * C6));
    let hz = 0.5 * z;
    let w = 1.0 - hz;
    w + (((1.0 - w) - hz) + (z * r - x * y))
}

/// sin(x + y) on [−π/4, π/4], `y` the tail of `x` (a degree-13 polynomial, Remez error ≤ 2⁻⁵⁸):
/// `libm`'s `k_sin` with a tail (`iy = 1`).
fn k_sin(x: f64, y: f64) -> f64 {
    const S1: f64 = f64::from_bits(0xBFC5_5555_5555_5549);
    const S2: f64 = f64::from_bits(0x3F81_1111_1110_F8A6);
    const S3: f64 = f64::from_bits(0xBF2A_01A0_19C1_61D5);
    const S4: f64 = f64::from_bits(0x3EC7_1DE3_57B1_FE7D);
    const S5: f64 = f64::from_bits(0xBE5A_E5E6_8A2B_9CEB);
    const S6: f64 = f64::from_bits(0x3DE5_D93A_5ACF_D57C);
    let z = x * x;
    let w = z * z;
    let r = S2 + z * (S3 + z * S4) + z * w * (S5 + z * S6);
    let v = z * x;
    x - ((z * (0.5 * y - v * r) - y) - v * S1)
}

#[cfg(test)]
mod tests {
    use super::*;
    use proptest::prelude::*;

    fn same(x: f64) {
        let want = libm::cos(x);
        let got = cos_moderate(x).unwrap_or_else(|| panic!("refused {x:e}"));
        assert_eq!(
            got.to_bits(),
            want.to_bits(),
            "cos({x:e}): {got:e} vs {want:e}"
        );
    }

    /// Every installation angle a unit can have (0..180° and their negatives, in 10⁻⁴° steps, as
    /// `to_radians` converts them), and the whole accepted range in coarser steps.
    #[test]
    fn the_bits_of_libm_over_the_angles_of_a_unit() {
        for k in -1_800_000..=1_800_000 {
            same((f64::from(k) * 1e-4).to_radians());
        }
        let mut d = 180.0f64;
        while d < MAX_ANGLE_DEG {
            same(d.to_radians());
            same((-d).to_radians());
            d *= 1.0001;
        }
        same(MAX_ANGLE_DEG.to_radians());
        same((-MAX_ANGLE_DEG).to_radians());
    }

    /// The reduction's special cases: next to each multiple of π/2 up to 32π (where the one-step
    /// reduction would cancel), at the branch boundaries, and the smallest arguments.
    #[test]
    fn the_bits_of_libm_at_the_reduction_edges() {
        for k in 1..=64 {
            let m = f64::from(k) * core::f64::consts::FRAC_PI_2;
            let mut up = m;
            let mut down = m;
            for _ in 0..64 {
                same(up);
                same(-up);
                same(down);
                same(-down);
                up = f64::from_bits(up.to_bits() + 1);
                down = f64::from_bits(down.to_bits() - 1);
            }
        }
        for hi in [
            0x3e46_a09e,
            0x3fe9_21fb,
            0x3fe9_21fc,
            0x4002_d97c,
            0x4002_d97d,
            0x400f_6a7a,
            0x400f_6a7b,
            0x4012_d97c,
            0x4015_fdbc,
            0x4015_fdbd,
            0x4019_21fb,
            0x401c_463b,
            0x401c_463c,
            MODERATE_LIMIT_HI - 1,
        ] {
            for lo in [0u32, 1, 0x5444_2d18, u32::MAX] {
                let x = f64::from_bits((u64::from(hi) << 32) | u64::from(lo));
                same(x);
                same(-x);
            }
        }
        for x in [0.0, -0.0, 1e-300, 5e-324, 1e-9, 2f64.powi(-27)] {
            same(x);
            same(-x);
        }
    }

    #[test]
    fn refuses_large_and_non_finite_arguments() {
        let limit = f64::from_bits(u64::from(MODERATE_LIMIT_HI) << 32);
        assert_eq!(cos_moderate(limit), None);
        assert_eq!(cos_moderate(-limit), None);
        assert!(cos_moderate(f64::from_bits(limit.to_bits() - 1)).is_some());
        for x in [1e7, 1e300, f64::INFINITY, f64::NEG_INFINITY, f64::NAN] {
            assert_eq!(cos_moderate(x), None, "{x:e}");
        }
        assert!((MAX_ANGLE_DEG * 1.001).to_radians() < limit);
    }

    proptest! {
        #![proptest_config(ProptestConfig::with_cases(20_000))]
        /// Any argument in the accepted range, and any angle in degrees.
        #[test]
        fn the_bits_of_libm_anywhere_in_range(x in -1.6e6f64..1.6e6, deg in -MAX_ANGLE_DEG..MAX_ANGLE_DEG) {
            same(x);
            same(deg.to_radians());
        }
    }
}
