//! An ADC board's sample conversion: the accelerometers' ADC codes and the gyro's words to a
//! pipeline [`Sample`], with its range-end flag. This is the Nucleo's per-sample conversion.
//!
//! The inputs come in the form the hardware delivers, so that no instruction is spent reshaping
//! them:
//!
//! - **The ADC scan's codes as 32-bit words.** The DMA reads ADC_DR as words; its upper half is zero
//!   in independent mode (RM0390 §13.13.14). One `vldmia` takes all three codes and
//!   `vcvt.f32.u32` converts each exactly.
//! - **The gyro's words in the upper half of 32-bit words** ([`gyro_word`], the word as a Q16.16
//!   value, assembled from the SPI bytes at no extra cost). The FPU's fixed-point conversion
//!   (`vcvt.f32.s32 #16`) gives the word exactly. A saturating add and a saturating subtract of one
//!   LSB (`qadd`, `qsub`) set the sticky Q flag exactly for 32767 and −32768, the range ends.
//! - **Whether a code sat at 0 or at full scale, from the ADC itself.** Its analog watchdog guards
//!   every regular channel with the thresholds of [`watchdog_thresholds`]: it flags a conversion
//!   below the low threshold or above the high one (RM0390 §13.3.7), which is exactly a code at
//!   either end. The board reads and clears the flag ([`ADC_SR_AWD`]) once per scan.
//!
//! On the Cortex-M4F the conversion is one assembly block of 28 instructions (the benchmark's
//! "sample conversion" line). Elsewhere it is [`Scaling::reference`], the definition the
//! QEMU test checks the block against bit for bit. Both make one rounding per value, in the
//! multiply: every conversion before it is exact.

#[cfg(target_arch = "arm")]
use core::mem::MaybeUninit;

use crate::pipeline::Sample;

/// The ADC status register's analog watchdog flag (ADC_SR bit 0, cleared by writing 0). Being
/// bit 0, `status & ADC_SR_AWD` is already 0 or 1.
pub const ADC_SR_AWD: u32 = 1;

/// ADC_SR's overrun flag (bit 5, cleared by writing 0).
pub const ADC_SR_OVR: u32 = 1 << 5;

/// ADC_SR's flags, bits 5:0 (OVR, STRT, JSTRT, JEOC, EOC, AWD: each cleared by writing 0, left as
/// it is by writing 1); bits 31:6 are reserved, kept at 0.
pub const ADC_SR_FLAGS: u32 = 0x3F;

/// The word to write to ADC_SR to clear `flags` and no other: 0 at their bits, 1 at the other
/// flags. One write, never a read-modify-write: a read-modify-write (the HAL's `modify`) writes
/// back as 0 every flag that was still 0 when it read, so a flag the ADC raises between its read
/// and its write (the next scan's EOC, the watchdog's AWD) is lost.
pub const fn adc_sr_clear(flags: u32) -> u32 {
    ADC_SR_FLAGS & !flags
}

/// The analog watchdog's (low, high) thresholds that flag exactly a code at 0 or at `adc_max`:
/// the watchdog flags a code below the low or above the high threshold.
pub const fn watchdog_thresholds(adc_max: u16) -> (u16, u16) {
    (1, adc_max - 1)
}

/// A gyro word as the conversion takes it: in the upper half of a 32-bit word (Q16.16).
#[inline(always)]
pub const fn gyro_word(w: i16) -> i32 {
    (w as i32) << 16
}

/// [`gyro_word`] of a word sent low byte first (the L3GD20H's OUT_x_L, OUT_x_H): the bytes land
/// in the upper half directly.
#[inline(always)]
pub const fn gyro_word_from_le(low: u8, high: u8) -> i32 {
    i32::from_le_bytes([0, 0, low, high])
}

/// The conversion's two scales, precomputed from the board's configuration. `repr(C)`: the
/// assembly block loads both with one `vldmia`.
#[repr(C)]
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Scaling {
    /// Volts per ADC code (V_ref / 4095 for a 12-bit ADC).
    pub volts_per_code: f32,
    /// rad/s per gyro LSB (the data sheet's sensitivity at the configured full scale).
    pub rad_s_per_lsb: f32,
}

/// One LSB of a [`gyro_word`]: the exact scale of the FPU's fixed-point conversion with 16
/// fraction bits.
const Q16_LSB: f32 = 1.0 / 65536.0;

impl Scaling {
    /// The sample of the scan's codes `adc`, the gyro's words `gyro` ([`gyro_word`]) and whether
    /// the ADC's watchdog saw a code at either end of its range in this scan: outputs in volts,
    /// rates in rad/s, saturated when a code or a gyro word sat at a range end.
    #[inline(always)]
    pub fn convert(&self, adc: &[u32; 3], gyro: &[i32; 3], adc_at_end: bool) -> Sample {
        #[cfg(target_arch = "arm")]
        let sample = self.convert_m4f(adc, gyro, adc_at_end);
        #[cfg(not(target_arch = "arm"))]
        let sample = self.reference(adc, gyro, adc_at_end);
        sample
    }

    /// The definition of [`Scaling::convert`], in plain Rust: the PC's form, and the reference the
    /// M4F's assembly block is checked against.
    #[inline(always)]
    pub fn reference(&self, adc: &[u32; 3], gyro: &[i32; 3], adc_at_end: bool) -> Sample {
        // Scaling by 2⁻¹⁶ is exact, so converting then scaling rounds once, as the FPU's
        // fixed-point conversion does.
        let end = |q: i32| matches!(q >> 16, -32768 | 32767);
        Sample {
            raw: adc.map(|c| c as f32 * self.volts_per_code),
            rate_rad_s: gyro.map(|q| (q as f32 * Q16_LSB) * self.rad_s_per_lsb),
            saturated: adc_at_end || gyro.iter().any(|&q| end(q)),
        }
    }

    /// [`Scaling::convert`] as one assembly block: the three loads, six conversions and six
    /// multiplies of the FPU, one store of the six results; the gyro's range ends as the sticky Q
    /// flag of three saturating adds and subtracts, folded with the ADC's flag into the sample's.
    #[cfg(target_arch = "arm")]
    #[inline(always)]
    fn convert_m4f(&self, adc: &[u32; 3], gyro: &[i32; 3], adc_at_end: bool) -> Sample {
        let mut sample = MaybeUninit::<Sample>::uninit();
        let out = sample.as_mut_ptr();
        // SAFETY: reads the three words of `adc` and of `gyro` and the two `f32` of `self`
        // (`repr(C)`), writes `out`'s six `f32` and its flag at the offsets the assertions below
        // `Sample` fix; all 4-byte aligned. Touches no stack. `msr` clears N, Z, C, V and Q (the
        // constant 0x10000 has bits 31–27 clear) and nothing after it sets N, Z, C or V (`qadd`
        // and `qsub` set only Q), so `APSR >> 27` is Q alone and the stored flag is 0 or 1.
        unsafe {
            core::arch::asm!(
                "mov {one}, #0x10000",
                "msr APSR_nzcvq, {one}",
                "vldmia {adc}, {{s0-s2}}",
                "vldmia {gyr}, {{s3-s5}}",
                "vldmia {k}, {{s6-s7}}",
                "vcvt.f32.u32 s0, s0",
                "vcvt.f32.u32 s1, s1",
                "vcvt.f32.u32 s2, s2",
                "vcvt.f32.s32 s3, s3, #16",
                "vcvt.f32.s32 s4, s4, #16",
                "vcvt.f32.s32 s5, s5, #16",
                "vmul.f32 s0, s0, s6",
                "vmul.f32 s1, s1, s6",
                "vmul.f32 s2, s2, s6",
                "vmul.f32 s3, s3, s7",
                "vmul.f32 s4, s4, s7",
                "vmul.f32 s5, s5, s7",
                "vstmia {out}, {{s0-s5}}",
                "ldm {gyr}, {{r1, r2, r3}}",
                "qadd {t}, r1, {one}",
                "qsub {t}, r1, {one}",
                "qadd {t}, r2, {one}",
                "qsub {t}, r2, {one}",
                "qadd {t}, r3, {one}",
                "qsub {t}, r3, {one}",
                "mrs {t}, APSR",
                "orr {t}, {end}, {t}, lsr #27",
                "strb {t}, [{out}, #24]",
                adc = in(reg) adc.as_ptr(),
                gyr = in(reg) gyro.as_ptr(),
                k = in(reg) self as *const Scaling,
                out = in(reg) out,
                end = in(reg) u32::from(adc_at_end),
                one = out(reg) _,
                t = out(reg) _,
                out("r1") _, out("r2") _, out("r3") _,
                out("s0") _, out("s1") _, out("s2") _, out("s3") _, out("s4") _,
                out("s5") _, out("s6") _, out("s7") _,
                options(nostack),
            );
        }
        // SAFETY: the block wrote every field (the padding after the flag is never read).
        unsafe { sample.assume_init() }
    }
}

// The assembly block's view of `Sample`: six `f32` in a row, then the flag.
const _: () = assert!(core::mem::offset_of!(Sample, raw) == 0);
const _: () = assert!(core::mem::offset_of!(Sample, rate_rad_s) == 12);
const _: () = assert!(core::mem::offset_of!(Sample, saturated) == 24);

#[cfg(test)]
mod tests {
    use super::*;

    const K: Scaling = Scaling {
        volts_per_code: 3.3 / 4095.0,
        rad_s_per_lsb: 0.070 * core::f32::consts::PI / 180.0,
    };

    fn convert(adc: [u32; 3], gyro: [i16; 3], adc_at_end: bool) -> Sample {
        K.convert(&adc, &gyro.map(gyro_word), adc_at_end)
    }

    #[test]
    fn converts_with_one_rounding_per_value() {
        let s = convert([0, 2048, 4095], [-32767, 1, 32766], false);
        assert_eq!(
            s.raw,
            [0.0, 2048.0 * K.volts_per_code, 4095.0 * K.volts_per_code]
        );
        assert_eq!(
            s.rate_rad_s,
            [
                -32767.0 * K.rad_s_per_lsb,
                K.rad_s_per_lsb,
                32766.0 * K.rad_s_per_lsb
            ]
        );
        // The ADC's ends come from its watchdog, not from the codes.
        assert!(!s.saturated);
        assert!(convert([2048; 3], [0; 3], true).saturated);
    }

    /// The gyro's flag against the plain definition, every word in each slot (the others at 0).
    #[test]
    fn a_gyro_word_at_either_range_end_is_saturated_exactly() {
        for slot in 0..3 {
            for v in i16::MIN..=i16::MAX {
                let mut w = [0i16; 3];
                w[slot] = v;
                let s = convert([2048; 3], w, false);
                assert_eq!(s.saturated, v == i16::MIN || v == i16::MAX, "{w:?}");
                assert_eq!(s.rate_rad_s[slot], f32::from(v) * K.rad_s_per_lsb);
            }
        }
    }

    /// The bytes as the SPI delivers them land where [`gyro_word`] puts the word.
    #[test]
    fn gyro_words_from_the_bytes() {
        for v in [i16::MIN, -300, -1, 0, 1, 2000, i16::MAX] {
            let [low, high] = v.to_le_bytes();
            assert_eq!(gyro_word_from_le(low, high), gyro_word(v));
        }
    }

    /// The watchdog's rule (a code below the low or above the high threshold) with these
    /// thresholds flags exactly the codes at either end, every code of a 12-bit and a 16-bit ADC.
    #[test]
    fn the_watchdog_thresholds_flag_exactly_the_range_ends() {
        for adc_max in [4095u16, u16::MAX] {
            let (low, high) = watchdog_thresholds(adc_max);
            for code in 0..=adc_max {
                let flagged = code < low || code > high;
                assert_eq!(flagged, code == 0 || code == adc_max, "{code} of {adc_max}");
            }
        }
    }

    /// ADC_SR as the hardware treats a write: a flag written 0 is cleared, written 1 unchanged.
    fn write_rc_w0(sr: u32, word: u32) -> u32 {
        sr & word
    }

    #[test]
    fn clearing_the_overrun_keeps_a_flag_raised_after_the_read() {
        const EOC: u32 = 1 << 1;
        let read = ADC_SR_OVR; // what a read-modify-write reads
        let sr = read | ADC_SR_AWD | EOC; // the next scan's flags arrive before its write
        assert_eq!(write_rc_w0(sr, adc_sr_clear(ADC_SR_OVR)), ADC_SR_AWD | EOC);
        // The read-modify-write it replaces (`modify(|_, w| w.ovr().clear_bit())` writes what it
        // read with OVR at 0) clears them too.
        assert_eq!(write_rc_w0(sr, read & !ADC_SR_OVR), 0);
        // The watchdog flag's clear leaves the overrun, and no reserved bit is written 1.
        assert_eq!(write_rc_w0(sr, adc_sr_clear(ADC_SR_AWD)), ADC_SR_OVR | EOC);
        assert_eq!(adc_sr_clear(0) & !ADC_SR_FLAGS, 0);
    }
}
