//! FIFO decode: every sample the model generated comes back bit for bit after scaling, in both
//! packet formats; the start-up samples the part marks invalid are NaN and flagged; axes beyond
//! full scale are flagged saturated; the time stamps step by one period.

use super::*;
use crate::imu::icm42688::FifoFormat;
use crate::imu::ImuFlags;
use core::f32::consts::PI;

/// Accelerometer, gyro (rad/s), temperature (°C), saturated.
type Expected = ([f32; 3], [f32; 3], f32, bool);

/// The expected sample for a truth: (accel, gyro rad/s, temperature, saturated), packet 3 at
/// ±16 g (2048 LSB/g) and ±2000 °/s (16.4 LSB/(°/s)), 8-bit temperature (2.07 LSB/°C).
fn expected_packet3(t: &Truth) -> Expected {
    let a = t.accel_g.map(|g| code(g * 2048.0, 32767));
    let w = t.gyro_dps.map(|d| code(d * 16.4, 32767));
    let sat = a.iter().chain(w.iter()).any(|c| c.abs() == 32767);
    let temp = code((t.temp_c - 25.0) * 2.07, 127) as f32 * (1.0 / 2.07) + 25.0;
    (
        a.map(|c| c as f32),
        w.map(|c| c as f32 * (PI / 180.0 / 16.4)),
        temp,
        sat,
    )
}

/// Packet 4: 18-bit accel at 8192 LSB/g, 19-bit gyro at 131 LSB/(°/s), 16-bit temperature
/// (132.48 LSB/°C). The driver's unit is the 18-bit LSB; the gyro is in rad/s.
fn expected_packet4(t: &Truth) -> Expected {
    let a = t.accel_g.map(|g| code(g * 8192.0, 131_071));
    let w = t.gyro_dps.map(|d| code(d * 131.0, 262_143));
    let sat = a.iter().any(|c| c.abs() == 131_071) || w.iter().any(|c| c.abs() == 262_143);
    let temp = code((t.temp_c - 25.0) * 132.48, 32767) as f32 * (1.0 / 132.48) + 25.0;
    (
        // The driver scales the 20-bit code (4 × the 18-bit one) by a quarter: exact.
        a.map(|c| (4 * c) as f32 * 0.25),
        w.map(|c| (2 * c) as f32 * (PI / 180.0 / (131.0 * 2.0))),
        temp,
        sat,
    )
}

fn check(format: FifoFormat, expected: fn(&Truth) -> Expected) {
    let cfg = Config {
        fifo: format,
        watermark_packets: 50,
        ..Config::DEFAULT
    };
    let mut imu = started(cfg);
    run_samples(&mut imu, 100);
    let got = drain_all(&mut imu);
    assert_eq!(got.len(), 100);
    let truth = truths(100);
    // The first sample after the sensors start is marked invalid by the part.
    assert!(got[0].flags.has(ImuFlags::INVALID));
    assert!(got[0]
        .accel_out
        .iter()
        .chain(got[0].gyro_rad_s.iter())
        .all(|v| v.is_nan()));
    let mut saturated = 0;
    for (k, (s, t)) in got.iter().zip(&truth).enumerate().skip(1) {
        let (a, w, temp, sat) = expected(t);
        assert_eq!(
            s.accel_out.map(f32::to_bits),
            a.map(f32::to_bits),
            "accel #{k}"
        );
        assert_eq!(
            s.gyro_rad_s.map(f32::to_bits),
            w.map(f32::to_bits),
            "gyro #{k}"
        );
        assert_eq!(s.temp_c.to_bits(), temp.to_bits(), "temperature #{k}");
        assert_eq!(s.flags.has(ImuFlags::SATURATED), sat, "saturation #{k}");
        assert!(
            !s.flags.has(ImuFlags::INVALID | ImuFlags::DATA_LOST),
            "#{k}"
        );
        assert_eq!(
            s.timestamp.wrapping_sub(got[k - 1].timestamp),
            1000,
            "1 kHz in µs"
        );
        saturated += sat as usize;
    }
    assert!(
        saturated > 5 && saturated < 60,
        "{saturated} saturated: the ranges are exercised"
    );
}

#[test]
fn packet3_matches_the_generated_samples_bit_for_bit() {
    check(FifoFormat::Packet3, expected_packet3);
}

#[test]
fn packet4_high_resolution_matches_bit_for_bit() {
    check(FifoFormat::Packet4HighRes, expected_packet4);
}

#[test]
fn output_unit_factor_and_offset() {
    // A board whose calibration is in volts: 2.5 V per 131071 LSB around 2.5 V.
    let k = 2.5f32 / 131_071.0;
    let cfg = Config {
        fifo: FifoFormat::Packet4HighRes,
        accel_out_per_lsb: k,
        accel_out_offset: 2.5,
        watermark_packets: 8,
        ..Config::DEFAULT
    };
    let mut imu = started(cfg);
    run_samples(&mut imu, 8);
    let got = drain_all(&mut imu);
    for (s, t) in got.iter().zip(truths(8)).skip(1) {
        for i in 0..3 {
            let c = code(t.accel_g[i] * 8192.0, 131_071);
            let want = (4 * c) as f32 * (k * 0.25) + 2.5;
            assert_eq!(s.accel_out[i].to_bits(), want.to_bits());
        }
    }
}
