//! An ADC board's sample conversion: the accelerometers' ADC codes and the gyro's words to a
//! pipeline [`Sample`], with its range-end flag. This is the Nucleo's per-sample conversion.
//!
//! The inputs come in the form the hardware delivers, so that no instruction is spent reshaping
//! them:
//!
//! - **The ADC scan's codes as 32-bit words.** The DMA reads ADC_DR as words; its upper half is zero
//!   in independent mode (RM0390 §13.13.14), and each code converts to `f32` exactly.
//! - **The gyro's words in the upper half of 32-bit words** ([`gyro_word`], the word as a Q16.16
//!   value, assembled from the SPI bytes at no extra cost). Converted and scaled by 2⁻¹⁶ (the
//!   FPU's fixed-point conversion, `vcvt.f32.s32 #16`), that gives the word exactly.
//! - **Whether a code sat at 0 or at full scale, from the ADC itself.** Its analog watchdog guards
//!   every regular channel with the thresholds of [`watchdog_thresholds`]: it flags a conversion
//!   below the low threshold or above the high one (RM0390 §13.3.7), which is exactly a code at
//!   either end. The board reads and clears the flag ([`ADC_SR_AWD`]) once per scan.
//!
//! [`Scaling::convert`] makes one rounding per value, in the multiply: every conversion before it
//! is exact. [`Scaling::reference`] defines the same values another way (each product in `f64`,
//! where it is exact, then rounded once), which the QEMU test checks the device's conversion
//! against bit for bit.

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

/// The conversion's two scales, precomputed from the board's configuration.
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

/// A [`gyro_word`]'s upper half `v` as `v + 32767` in `u32`: the two range ends are the only
/// words at or above [`AT_RANGE_END`] (−32768 gives `u32::MAX`, 32767 gives 65 534, the others
/// 0..=65 533), so one comparison of the largest of three tests them all.
#[inline(always)]
fn end_key(q: i32) -> u32 {
    ((q >> 16) + 32767) as u32
}

/// An [`end_key`] at or above this: the word sat at a range end.
const AT_RANGE_END: u32 = 65_534;

impl Scaling {
    /// The sample of the scan's codes `adc`, the gyro's words `gyro` ([`gyro_word`]) and whether
    /// the ADC's watchdog saw a code at either end of its range in this scan: outputs in volts,
    /// rates in rad/s, saturated when a code or a gyro word sat at a range end.
    ///
    /// Scaling by 2⁻¹⁶ is exact, so converting then scaling rounds once, in the multiply (the
    /// conversion of a gyro word, whose lower half is 0, is exact). Written out per value:
    /// straight-line code at opt-level "s".
    #[inline(always)]
    pub fn convert(&self, adc: &[u32; 3], gyro: &[i32; 3], adc_at_end: bool) -> Sample {
        let (kv, kg) = (self.volts_per_code, self.rad_s_per_lsb);
        Sample {
            raw: [adc[0] as f32 * kv, adc[1] as f32 * kv, adc[2] as f32 * kv],
            rate_rad_s: [
                (gyro[0] as f32 * Q16_LSB) * kg,
                (gyro[1] as f32 * Q16_LSB) * kg,
                (gyro[2] as f32 * Q16_LSB) * kg,
            ],
            saturated: adc_at_end
                | (end_key(gyro[0]).max(end_key(gyro[1])).max(end_key(gyro[2])) >= AT_RANGE_END),
        }
    }

    /// What [`Scaling::convert`] must give, defined another way: each value converted through
    /// `f64` and its product with the scale formed in `f64`, where the product of two `f32` is
    /// exact (48 significant bits), then rounded once to `f32` (the correctly rounded `f32`
    /// product); the range ends from the word's upper half as an `i16`. On the M4F this runs in
    /// soft-float, so the QEMU test compares the FPU's conversion with an independent one.
    pub fn reference(&self, adc: &[u32; 3], gyro: &[i32; 3], adc_at_end: bool) -> Sample {
        let product = |x: f64, k: f32| (f64::from(x as f32) * f64::from(k)) as f32;
        Sample {
            raw: adc.map(|c| product(f64::from(c), self.volts_per_code)),
            rate_rad_s: gyro.map(|q| product(f64::from(q) / 65536.0, self.rad_s_per_lsb)),
            saturated: adc_at_end
                || gyro
                    .iter()
                    .any(|&q| matches!((q >> 16) as i16, i16::MIN | i16::MAX)),
        }
    }
}

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
