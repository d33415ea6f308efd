//! FIFO packet decode (DS-000347 §6.1 "Packet structure", §6.2 "FIFO header"), with big-endian data
//! (INTF_CONFIG0 SENSOR_DATA_ENDIAN, the reset value).
//!
//! Packet 3, 16 bytes: header, ACCEL X1 X0 Y1 Y0 Z1 Z0, GYRO X1 .. Z0, TEMP (8 bit), TIMESTAMP H L.
//! Packet 4, 20 bytes (FIFO_HIRES_EN): header, ACCEL \[19:12\] \[11:4\] per axis, GYRO likewise,
//! TEMP (16 bit), TIMESTAMP H L, then one byte per axis: accel \[3:0\] in bits 7:4, gyro \[3:0\] in 3:0.
//! In packet 4 the accelerometer carries 18 bits (bits 1:0 are 0, 8192 LSB/g) and the gyro 19 bits
//! (bit 0 is 0, 131 LSB/°/s), at ±16 g and ±2000 °/s whatever the range registers say (§6.1).
//!
//! The empty marker: a 16-bit value of −32768 (0x8000) or a 20-bit value of −524288 means the
//! sensor's data are invalid (it is starting up); the sample's values are then NaN and it is
//! flagged [`ImuFlags::INVALID`]. An axis at its largest code (±32767; ±524284 accel, ±524286 gyro
//! in 20 bits) is flagged [`ImuFlags::SATURATED`].
//!
//! Per sample on the device: no division, no branch per axis (the checks are folded into flag bits).

use super::regs::{INVALID_16, INVALID_20};
use crate::imu::{ImuFlags, ImuSample};

/// Scaling from codes to the output units, precomputed from the configuration.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Scale {
    /// Accelerometer output unit per raw code as read from the packet (packet 4: per 20-bit code,
    /// i.e. a quarter of the 18-bit LSB).
    pub accel_out_per_code: f32,
    /// Added to the scaled accelerometer value (0 for counts).
    pub accel_out_offset: f32,
    /// rad/s per raw gyro code (packet 4: per 20-bit code, half the 19-bit LSB).
    pub gyro_rad_s_per_code: f32,
}

/// Packet 3 temperature: °C per LSB of the 8-bit field (§6.1: T = TEMP/2.07 + 25).
pub const TEMP8_C_PER_LSB: f32 = 1.0 / 2.07;
/// Packet 4 and data-register temperature: °C per LSB of the 16-bit field (T = TEMP/132.48 + 25).
pub const TEMP16_C_PER_LSB: f32 = 1.0 / 132.48;
/// Temperature at a zero code, °C.
pub const TEMP_OFFSET_C: f32 = 25.0;

#[inline(always)]
fn be16(p: &[u8], i: usize) -> i16 {
    i16::from_be_bytes([p[i], p[i + 1]])
}

/// A 20-bit value from its \[19:12\] and \[11:4\] bytes and the \[3:0\] nibble, sign-extended.
#[inline(always)]
fn be20(p: &[u8], i: usize, nibble: u8) -> i32 {
    // The 16 high bits as a signed value, shifted up by 4: sign extension for free.
    (i32::from(be16(p, i)) << 4) | i32::from(nibble & 0x0F)
}

/// Negative exactly when `v` is at or beyond ±`max` (a saturated axis, or the invalid marker below
/// −max): `v + max − 1 < 0` below, `max − 1 − v < 0` above. Two operations and no compare, so that
/// the six axes' checks fold into one OR and one sign test. (|v| < 2²⁰: no overflow.)
#[inline(always)]
fn extreme(v: i32, max: i32) -> i32 {
    (v + (max - 1)) | ((max - 1) - v)
}

/// Codes of one packet, before scaling: accelerometer and gyro x, y, z, and their full-scale codes.
struct Codes {
    a: (i32, i32, i32),
    g: (i32, i32, i32),
    max: [i32; 2],
    invalid: i32,
}

/// Scales and checks the codes into `out` (temperature and time stamp are the caller's).
#[inline(always)]
fn scale_into(c: Codes, s: &Scale, out: &mut ImuSample) {
    // Written out per value: straight-line code at opt-level "s" (no arrays through the stack).
    let ((a0, a1, a2), (g0, g1, g2)) = (c.a, c.g);
    let [am, gm] = c.max;
    let odd = (extreme(a0, am)
        | extreme(a1, am)
        | extreme(a2, am)
        | extreme(g0, gm)
        | extreme(g1, gm)
        | extreme(g2, gm))
        < 0;
    let (ka, ca, kg) = (
        s.accel_out_per_code,
        s.accel_out_offset,
        s.gyro_rad_s_per_code,
    );
    // |code| < 2^20: exact in f32.
    out.accel_out = [
        a0 as f32 * ka + ca,
        a1 as f32 * ka + ca,
        a2 as f32 * ka + ca,
    ];
    out.gyro_rad_s = [g0 as f32 * kg, g1 as f32 * kg, g2 as f32 * kg];
    out.lost_before = 0;
    out.flags = ImuFlags(0);
    if odd {
        mark_extremes(out, &[a0, a1, a2], &[g0, g1, g2], c.invalid, c.max);
    }
}

/// Decodes a packet 3 (16 bytes) into `out`. The header is checked by the caller.
#[inline(always)]
pub fn decode_packet3(p: &[u8; 16], s: &Scale, out: &mut ImuSample) {
    let v = |i: usize| i32::from(be16(p, i));
    let codes = Codes {
        a: (v(1), v(3), v(5)),
        g: (v(7), v(9), v(11)),
        max: [32767, 32767],
        invalid: i32::from(INVALID_16),
    };
    scale_into(codes, s, out);
    out.temp_c = f32::from(p[13] as i8) * TEMP8_C_PER_LSB + TEMP_OFFSET_C;
    out.timestamp = u16::from_be_bytes([p[14], p[15]]);
}

/// Decodes a packet 4 (20 bytes, 20-bit data) into `out`. The header is checked by the caller.
#[inline(always)]
pub fn decode_packet4(p: &[u8; 20], s: &Scale, out: &mut ImuSample) {
    let (ex, ey, ez) = (p[17], p[18], p[19]);
    let codes = Codes {
        a: (
            be20(p, 1, ex >> 4),
            be20(p, 3, ey >> 4),
            be20(p, 5, ez >> 4),
        ),
        g: (be20(p, 7, ex), be20(p, 9, ey), be20(p, 11, ez)),
        max: [524_284, 524_286],
        invalid: INVALID_20,
    };
    scale_into(codes, s, out);
    out.temp_c = f32::from(be16(p, 13)) * TEMP16_C_PER_LSB + TEMP_OFFSET_C;
    out.timestamp = u16::from_be_bytes([p[15], p[16]]);
}

/// The rare path: which extreme codes are the invalid marker (that sensor's values become NaN,
/// flagged INVALID) and which are saturated axes (flagged SATURATED).
#[cold]
#[inline(never)]
fn mark_extremes(out: &mut ImuSample, a: &[i32; 3], g: &[i32; 3], invalid: i32, max: [i32; 2]) {
    let invalid_a = a.contains(&invalid);
    let invalid_g = g.contains(&invalid);
    if invalid_a {
        out.accel_out = [f32::NAN; 3];
    }
    if invalid_g {
        out.gyro_rad_s = [f32::NAN; 3];
    }
    // Anything extreme that is not an invalid marker is at full scale.
    let full = |v: i32, m: i32| v != invalid && (v >= m || v <= -m);
    let saturated = a.iter().any(|&v| full(v, max[0])) || g.iter().any(|&v| full(v, max[1]));
    out.flags.0 |= if invalid_a | invalid_g {
        ImuFlags::INVALID
    } else {
        0
    };
    out.flags.0 |= if saturated { ImuFlags::SATURATED } else { 0 };
}
