//! FIFO packet decode (DS-000347 §6.1 "Packet structure", §6.2 "FIFO header"), with big-endian data
//! (INTF_CONFIG0 SENSOR_DATA_ENDIAN, the reset value).
//!
//! Packet 3, 16 bytes: header, ACCEL X1 X0 Y1 Y0 Z1 Z0, GYRO X1 .. Z0, TEMP (8 bit), TIMESTAMP H L.
//! Packet 4, 20 bytes (FIFO_HIRES_EN): header, ACCEL [19:12] [11:4] per axis, GYRO likewise,
//! TEMP (16 bit), TIMESTAMP H L, then one byte per axis: accel [3:0] in bits 7:4, gyro [3:0] in 3:0.
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

/// A 20-bit value from its [19:12] and [11:4] bytes and the [3:0] nibble, sign-extended.
#[inline(always)]
fn be20(p: &[u8], i: usize, nibble: u8) -> i32 {
    // The 16 high bits as a signed value, shifted up by 4: sign extension for free.
    (i32::from(be16(p, i)) << 4) | i32::from(nibble & 0x0F)
}

#[inline(always)]
fn flag(cond: bool, bit: u8) -> u8 {
    (cond as u8) * bit
}

/// Decodes a packet 3 (16 bytes). The header is checked by the caller.
#[inline(always)]
pub fn decode_packet3(p: &[u8; 16], s: &Scale) -> ImuSample {
    let a = [be16(p, 1), be16(p, 3), be16(p, 5)];
    let g = [be16(p, 7), be16(p, 9), be16(p, 11)];
    let sat16 = |v: i16| v == i16::MAX || v == -i16::MAX;
    let bad_a = (a[0] == INVALID_16) | (a[1] == INVALID_16) | (a[2] == INVALID_16);
    let bad_g = (g[0] == INVALID_16) | (g[1] == INVALID_16) | (g[2] == INVALID_16);
    let sat = sat16(a[0]) | sat16(a[1]) | sat16(a[2]) | sat16(g[0]) | sat16(g[1]) | sat16(g[2]);
    let acc = |v: i16| f32::from(v) * s.accel_out_per_code + s.accel_out_offset;
    let gyr = |v: i16| f32::from(v) * s.gyro_rad_s_per_code;
    finish(
        [acc(a[0]), acc(a[1]), acc(a[2])],
        [gyr(g[0]), gyr(g[1]), gyr(g[2])],
        f32::from(p[13] as i8) * TEMP8_C_PER_LSB + TEMP_OFFSET_C,
        u16::from_be_bytes([p[14], p[15]]),
        bad_a,
        bad_g,
        sat,
    )
}

/// Decodes a packet 4 (20 bytes, 20-bit data). The header is checked by the caller.
#[inline(always)]
pub fn decode_packet4(p: &[u8; 20], s: &Scale) -> ImuSample {
    let (ex, ey, ez) = (p[17], p[18], p[19]);
    let a = [
        be20(p, 1, ex >> 4),
        be20(p, 3, ey >> 4),
        be20(p, 5, ez >> 4),
    ];
    let g = [be20(p, 7, ex), be20(p, 9, ey), be20(p, 11, ez)];
    const A_MAX: i32 = 524_284;
    const G_MAX: i32 = 524_286;
    let sat_a = |v: i32| (v >= A_MAX) | (v <= -A_MAX);
    let sat_g = |v: i32| (v >= G_MAX) | (v <= -G_MAX);
    let bad_a = (a[0] == INVALID_20) | (a[1] == INVALID_20) | (a[2] == INVALID_20);
    let bad_g = (g[0] == INVALID_20) | (g[1] == INVALID_20) | (g[2] == INVALID_20);
    let sat = sat_a(a[0]) | sat_a(a[1]) | sat_a(a[2]) | sat_g(g[0]) | sat_g(g[1]) | sat_g(g[2]);
    // |v| < 2^20: exact in f32.
    let acc = |v: i32| v as f32 * s.accel_out_per_code + s.accel_out_offset;
    let gyr = |v: i32| v as f32 * s.gyro_rad_s_per_code;
    finish(
        [acc(a[0]), acc(a[1]), acc(a[2])],
        [gyr(g[0]), gyr(g[1]), gyr(g[2])],
        f32::from(be16(p, 13)) * TEMP16_C_PER_LSB + TEMP_OFFSET_C,
        u16::from_be_bytes([p[15], p[16]]),
        bad_a,
        bad_g,
        sat,
    )
}

#[inline(always)]
fn finish(
    mut accel: [f32; 3],
    mut gyro: [f32; 3],
    temp_c: f32,
    timestamp: u16,
    bad_a: bool,
    bad_g: bool,
    sat: bool,
) -> ImuSample {
    // Rare (start-up only): a branch here keeps the common path short.
    if bad_a | bad_g {
        if bad_a {
            accel = [f32::NAN; 3];
        }
        if bad_g {
            gyro = [f32::NAN; 3];
        }
    }
    ImuSample {
        accel_out: accel,
        gyro_rad_s: gyro,
        temp_c,
        timestamp,
        lost_before: 0,
        flags: ImuFlags(flag(sat, ImuFlags::SATURATED) | flag(bad_a | bad_g, ImuFlags::INVALID)),
    }
}
