//! [`Compensator::compensate`] on an ARM hard-float target (the Cortex-M4F), in line: the 42
//! constants in six block loads (`vldmia` with write-back, in the order `Compensator`'s `repr(C)`
//! fields lie), the three inputs in three, 51 multiply-adds and one block store — 61 instructions
//! where compiled code spends one `vldr` per constant besides (about 95 in place, measured with
//! firmware/scripts/bench-qemu.sh). Each operation is the Rust reference's
//! (`compensate_reference`), in its order: every product rounded before its addition or
//! subtraction (`vmla.f32`/`vmls.f32` are not fused), so the results are identical bit for bit,
//! which the QEMU test vectors check (`compensation_full_matches_pc`,
//! `compensation_rate_only_matches_pc`, `compensation_after_temperature_refresh_matches_pc`).
//!
//! As in the gyro correction (`GyroInverse::correct`), operands pass through memory (this
//! toolchain's inline assembly takes no single-precision FPU register operands on this target) and
//! the FPU registers used are declared clobbered.

use super::Compensator;

// The block loads read the fields as one run of `f32`: p, a, q (nine each), s, u0 (three each),
// K_A (nine), with no padding between them.
const _: () = {
    use core::mem::{align_of, offset_of};
    assert!(offset_of!(Compensator, p) == 0);
    assert!(offset_of!(Compensator, a) == 9 * 4);
    assert!(offset_of!(Compensator, q) == 18 * 4);
    assert!(offset_of!(Compensator, s) == 27 * 4);
    assert!(offset_of!(Compensator, zero_bias_out) == 30 * 4);
    assert!(offset_of!(Compensator, ka_m_s2_per_out) == 33 * 4);
    assert!(
        align_of::<Compensator>() >= 4,
        "vldmia needs word alignment"
    );
};

impl Compensator {
    /// `K_A (U − u0 − k d)` with `k_i d_i = ω̇·p_i + (a_i·ω)(q_i·ω) − |ω|² s_i` (paper eq. 16).
    ///
    /// Registers: ω s0–s2, ω̇ s3–s5, |ω|² s29; p_i (then a_i, then s and u0) s6–s14; the three
    /// `k_i d_i` and then `v_i` s15–s17; q_i (then K_A) s18–s26; `a_i·ω`, `q_i·ω` s27, s28;
    /// U s12–s14 once a is used; the result s0–s2.
    #[inline(always)]
    pub(super) fn compensate_block(&self, u: &[f32; 3], w: &[f32; 3], wd: &[f32; 3]) -> [f32; 3] {
        let mut out = core::mem::MaybeUninit::<[f32; 3]>::uninit();
        // SAFETY: `out` has room for three `f32`, all written below.
        unsafe {
            self.compensate_to(u, w, wd, out.as_mut_ptr().cast());
            out.assume_init()
        }
    }

    /// [`Compensator::compensate_block`] written where the caller wants it (no copy of the result).
    #[inline(always)]
    pub(super) fn compensate_block_into(
        &self,
        u: &[f32; 3],
        w: &[f32; 3],
        wd: &[f32; 3],
        out: &mut [f32; 3],
    ) {
        // SAFETY: `out` is three writable, aligned `f32` that no input can alias (`&mut`).
        unsafe { self.compensate_to(u, w, wd, out.as_mut_ptr()) }
    }

    /// The block itself. Safety: `out` must point to three writable, 4-byte aligned `f32`.
    #[inline(always)]
    unsafe fn compensate_to(&self, u: &[f32; 3], w: &[f32; 3], wd: &[f32; 3], out: *mut f32) {
        // SAFETY: reads the 42 `f32` at the start of `self` (checked above) and the three of each
        // input, writes the three at `out` (the caller's promise); all 4-byte aligned. Touches no stack;
        // s0–s29 are declared clobbered, and the constants' pointer register is an in-out
        // temporary (written back by the loads). Not `preserves_flags`: the arithmetic sets the
        // FPSCR's cumulative exception flags.
        unsafe {
            core::arch::asm!(
                "vldmia {w}, {{s0-s2}}",
                "vldmia {wd}, {{s3-s5}}",
                // |ω|² = (ω0·ω0 + ω1·ω1) + ω2·ω2
                "vmul.f32 s29, s0, s0",
                "vmla.f32 s29, s1, s1",
                "vmla.f32 s29, s2, s2",
                // tangential_i = ω̇·p_i
                "vldmia {c}!, {{s6-s14}}",
                "vmul.f32 s15, s3, s6",
                "vmla.f32 s15, s4, s7",
                "vmla.f32 s15, s5, s8",
                "vmul.f32 s16, s3, s9",
                "vmla.f32 s16, s4, s10",
                "vmla.f32 s16, s5, s11",
                "vmul.f32 s17, s3, s12",
                "vmla.f32 s17, s4, s13",
                "vmla.f32 s17, s5, s14",
                // + (a_i·ω)(q_i·ω)
                "vldmia {c}!, {{s6-s14}}",
                "vldmia {c}!, {{s18-s26}}",
                "vmul.f32 s27, s6, s0",
                "vmla.f32 s27, s7, s1",
                "vmla.f32 s27, s8, s2",
                "vmul.f32 s28, s18, s0",
                "vmla.f32 s28, s19, s1",
                "vmla.f32 s28, s20, s2",
                "vmla.f32 s15, s27, s28",
                "vmul.f32 s27, s9, s0",
                "vmla.f32 s27, s10, s1",
                "vmla.f32 s27, s11, s2",
                "vmul.f32 s28, s21, s0",
                "vmla.f32 s28, s22, s1",
                "vmla.f32 s28, s23, s2",
                "vmla.f32 s16, s27, s28",
                "vmul.f32 s27, s12, s0",
                "vmla.f32 s27, s13, s1",
                "vmla.f32 s27, s14, s2",
                "vmul.f32 s28, s24, s0",
                "vmla.f32 s28, s25, s1",
                "vmla.f32 s28, s26, s2",
                "vmla.f32 s17, s27, s28",
                // − |ω|² s_i; v_i = (U_i − u0_i) − k_i d_i
                "vldmia {c}!, {{s6-s11}}",
                "vldmia {u}, {{s12-s14}}",
                "vmls.f32 s15, s29, s6",
                "vmls.f32 s16, s29, s7",
                "vmls.f32 s17, s29, s8",
                "vsub.f32 s12, s12, s9",
                "vsub.f32 s13, s13, s10",
                "vsub.f32 s14, s14, s11",
                "vsub.f32 s15, s12, s15",
                "vsub.f32 s16, s13, s16",
                "vsub.f32 s17, s14, s17",
                // K_A v, rows
                "vldmia {c}, {{s18-s26}}",
                "vmul.f32 s0, s18, s15",
                "vmla.f32 s0, s19, s16",
                "vmla.f32 s0, s20, s17",
                "vmul.f32 s1, s21, s15",
                "vmla.f32 s1, s22, s16",
                "vmla.f32 s1, s23, s17",
                "vmul.f32 s2, s24, s15",
                "vmla.f32 s2, s25, s16",
                "vmla.f32 s2, s26, s17",
                "vstmia {out}, {{s0-s2}}",
                c = inout(reg) (self as *const Compensator) => _,
                w = in(reg) w.as_ptr(),
                wd = in(reg) wd.as_ptr(),
                u = in(reg) u.as_ptr(),
                out = in(reg) out,
                out("s0") _, out("s1") _, out("s2") _, out("s3") _, out("s4") _,
                out("s5") _, out("s6") _, out("s7") _, out("s8") _, out("s9") _,
                out("s10") _, out("s11") _, out("s12") _, out("s13") _, out("s14") _,
                out("s15") _, out("s16") _, out("s17") _, out("s18") _, out("s19") _,
                out("s20") _, out("s21") _, out("s22") _, out("s23") _, out("s24") _,
                out("s25") _, out("s26") _, out("s27") _, out("s28") _, out("s29") _,
                options(nostack),
            );
        }
    }
}
