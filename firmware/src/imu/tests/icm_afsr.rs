//! The adaptive full-scale range switch (AFSR): on at reset (INTF_CONFIG1 = 0x91), it holds the
//! gyro output for 1–2 ms whenever the rate crosses about ±100 °/s (the stalls Betaflight's
//! `accgyro_spi_icm426xx.c` and ArduPilot turn it off for). A ramp through 100 °/s read through
//! the driver: repeated gyro samples with AFSR left on; none once the driver has turned it off.

use super::*;
use crate::imu::icm42688::regs::{INTF_CONFIG1, READ};
use crate::imu::icm42688::Odr;
use embedded_hal::spi::{Operation, SpiDevice};

/// Gyro x from 50 °/s up by 0.125 °/s per sample (2.05 LSB at ±2000 °/s: every code differs
/// from the one before), at rest otherwise.
struct Ramp {
    k: u32,
}

impl Generator for Ramp {
    fn next(&mut self) -> Truth {
        let w = 50.0 + 0.125 * f64::from(self.k);
        self.k += 1;
        Truth {
            accel_g: [0.0, 0.0, 1.0],
            gyro_dps: [w, 0.0, 0.0],
            temp_c: 25.0,
        }
    }
}

/// 8 kHz: 1 ms is 8 samples.
const CFG: Config = Config {
    odr: Odr::Hz8000,
    watermark_packets: 16,
    ..Config::DEFAULT
};

/// Runs the ramp from 50 to 150 °/s (800 samples) and returns the gyro x codes read back, in
/// LSB at ±2000 °/s (16.4 LSB/(°/s), the datasheet's sensitivity).
fn ramp_codes(imu: &mut Icm42688<Icm42688Model<Ramp>>) -> Vec<i32> {
    let mut codes = Vec::new();
    let mut buf = [ImuSample::default(); 16];
    for _ in 0..800 / 16 {
        let m = imu.device_mut();
        for _ in 0..16 {
            let dt = m.until_next_sample_ns();
            m.advance_ns(dt.max(1));
        }
        let d = imu.drain(&mut buf).expect("drain");
        for s in &buf[..d.samples] {
            if !s.flags.has(crate::imu::ImuFlags::INVALID) {
                let dps = f64::from(s.gyro_rad_s[0]).to_degrees();
                codes.push((dps * 16.4).round() as i32);
            }
        }
    }
    codes
}

/// Lengths of the runs of repeated codes (a run of n equal codes counts n − 1).
fn repeats(codes: &[i32]) -> usize {
    codes.windows(2).filter(|w| w[0] == w[1]).count()
}

#[test]
fn driver_turns_afsr_off_and_the_ramp_never_stalls() {
    let mut imu = Icm42688::new(Icm42688Model::new(Ramp { k: 0 }), CFG).expect("starts");
    // Betaflight's write over the reset value: (0x91 & !0xC0) | 0x40.
    assert_eq!(imu.device_mut().register(0, INTF_CONFIG1), 0x51);
    let codes = ramp_codes(&mut imu);
    assert!(codes.len() > 700, "{}", codes.len());
    assert_eq!(repeats(&codes), 0, "repeated gyro samples");
}

#[test]
fn afsr_left_on_stalls_the_gyro_for_1_to_2_ms_at_100_dps() {
    let mut imu = Icm42688::new(Icm42688Model::new(Ramp { k: 0 }), CFG).expect("starts");
    // Back to the reset value, as a driver that never touches INTF_CONFIG1 leaves it.
    imu.device_mut()
        .transaction(&mut [Operation::Write(&[INTF_CONFIG1 as u8 & !READ, 0x91])])
        .unwrap();
    let codes = ramp_codes(&mut imu);
    let n = repeats(&codes);
    // 1–2 ms of an 8 kHz output: 8 to 16 samples equal to the one before the switch.
    assert!((8..=16).contains(&n), "{n} repeated samples");
    // All of them where the rate crosses 100 °/s (1640 LSB).
    let first = codes.windows(2).position(|w| w[0] == w[1]).unwrap();
    assert!(
        (codes[first] - 1640).abs() <= 3,
        "stall at {} LSB",
        codes[first]
    );
}
