//! The LSM6DSO behind the same trait, against its model: identify and configure (registers as the
//! datasheet's fields say), tagged words paired into samples bit for bit after scaling whatever
//! their order in a slot, the temperature words, the watermark on INT1, an overrun flagged exactly
//! after the words kept, SPI errors.

use super::{code, TestGen};
use crate::imu::lsm6dso::regs::*;
use crate::imu::lsm6dso::{Config, Error, Lsm6dso};
use crate::imu::sim::{BusFault, Generator, Lsm6dsoModel};
use crate::imu::{ImuFlags, ImuSample, ImuSource};
use core::f32::consts::PI;

type Imu = Lsm6dso<Lsm6dsoModel<TestGen>>;

fn started() -> Imu {
    Lsm6dso::new(Lsm6dsoModel::new(TestGen::default()), Config::DEFAULT).unwrap()
}

fn run(imu: &mut Imu, n: u32) {
    for _ in 0..n {
        let m = imu.device_mut();
        m.advance_ns(m.until_next_sample_ns().max(1));
    }
}

fn drain_all(imu: &mut Imu) -> Vec<ImuSample> {
    let mut all = Vec::new();
    let mut buf = [ImuSample::default(); 5];
    loop {
        let d = imu.drain(&mut buf).unwrap();
        all.extend_from_slice(&buf[..d.samples]);
        if !d.more {
            return all;
        }
    }
}

#[test]
fn identify_and_configuration_registers() {
    let mut imu = started();
    let m = imu.device_mut();
    // 833 Hz = 0111; ±8 g = FS_XL 11; ±2000 °/s = FS_G 11.
    assert_eq!(m.register(CTRL1_XL), 0b0111_1100); // ODR 0111, FS 11
    assert_eq!(m.register(CTRL2_G), 0b0111_1100);
    assert_eq!(
        m.register(FIFO_CTRL3),
        0b0111_0111,
        "both batched at 833 Hz"
    );
    // Time stamp every batch (01), temperature at 52 Hz (11), FIFO mode 001.
    assert_eq!(m.register(FIFO_CTRL4), 0b0111_0001); // 01, 11, 0, 001
    assert_eq!(
        (m.register(FIFO_CTRL1), m.register(FIFO_CTRL2) & 1),
        (30, 0)
    );
    assert_eq!(m.register(INT1_CTRL), 0b0001_1000);
    assert_eq!(m.register(CTRL10_C), 1 << 5);
    assert_eq!(m.register(CTRL3_C), 0x44, "BDU and IF_INC");
    let mut m = Lsm6dsoModel::new(TestGen::default());
    m.who_am_i = 0x47; // an ICM-42688-P's
    assert_eq!(
        Lsm6dso::new(m, Config::DEFAULT).err(),
        Some(Error::WrongDevice(0x47))
    );
    let bad = Config {
        watermark_words: 0,
        ..Config::DEFAULT
    };
    let m = Lsm6dsoModel::new(TestGen::default());
    assert_eq!(Lsm6dso::new(m, bad).err(), Some(Error::BadWatermark));
    // Finite, but infinite at full scale: its samples would be non-finite without the flag.
    for (k, c) in [(f32::NAN, 0.0), (1e35, 0.0), (1.0, f32::INFINITY)] {
        let bad = Config {
            accel_out_per_lsb: k,
            accel_out_offset: c,
            ..Config::DEFAULT
        };
        let m = Lsm6dsoModel::new(TestGen::default());
        assert_eq!(Lsm6dso::new(m, bad).err(), Some(Error::BadUnit), "{k} {c}");
    }
}

#[test]
fn tagged_words_pair_into_samples_bit_for_bit() {
    let mut imu = started();
    run(&mut imu, 60);
    let got = drain_all(&mut imu);
    assert_eq!(got.len(), 60);
    let mut g = TestGen::default();
    let truth: Vec<_> = (0..60).map(|_| g.next()).collect();
    let mut saturated = 0;
    for (k, (s, t)) in got.iter().zip(&truth).enumerate() {
        // ±8 g: 0.244 mg/LSB; ±2000 °/s: 70 m°/s per LSB; temperature 256 LSB/°C (52 Hz: the
        // word of slot 0 and of slot 16 at 833 Hz).
        let a = t.accel_g.map(|g| code(g * 1000.0 / 0.244, 32767));
        let w = t.gyro_dps.map(|d| code(d * 1000.0 / 70.0, 32767));
        assert_eq!(s.accel_out, a.map(|c| c as f32), "#{k}");
        let rad = 70.0f32 * 1e-3 * PI / 180.0;
        assert_eq!(s.gyro_rad_s, w.map(|c| c as f32 * rad), "#{k}");
        let temp_slot = (k / 16) * 16;
        let tc = code((truth[temp_slot].temp_c - 25.0) * 256.0, 32767) as f32 / 256.0 + 25.0;
        assert_eq!(s.temp_c, tc, "#{k}");
        let sat = a.iter().chain(w.iter()).any(|c| c.abs() == 32767);
        assert_eq!(s.flags.has(ImuFlags::SATURATED), sat);
        saturated += sat as u32;
        assert!(!s.flags.has(ImuFlags::DATA_LOST), "#{k}");
        if k > 0 {
            assert_eq!(
                s.timestamp.wrapping_sub(got[k - 1].timestamp),
                48,
                "1.2 ms in 25 µs"
            );
        }
    }
    assert!(saturated > 0);
}

#[test]
fn watermark_on_int1() {
    let mut imu = started();
    // Slot 0 carries a temperature word: 4 words, then 3 per slot: 28 after 9 slots, 31 after 10.
    run(&mut imu, 9);
    assert!(
        !imu.device_mut().int1(),
        "{} words",
        imu.device_mut().fifo_words()
    );
    run(&mut imu, 1);
    assert!(imu.device_mut().int1());
    drain_all(&mut imu);
    assert!(!imu.device_mut().int1());
}

#[test]
fn overrun_flagged_exactly_after_the_words_kept() {
    let mut imu = started();
    run(&mut imu, 200);
    // Slots of 3 words (time stamp, gyro, accel), 4 with the temperature every 16th at 833 Hz:
    // how many fit in the 512 words.
    let (mut words, mut fit) = (0, 0);
    while words + 3 + usize::from(fit % 16 == 0) <= 512 {
        words += 3 + usize::from(fit % 16 == 0);
        fit += 1;
    }
    let dropped: Vec<u32> = imu.device_mut().dropped.to_vec();
    assert_eq!(dropped.first(), Some(&(fit as u32)));
    let mut got = drain_all(&mut imu);
    let kept = got.len();
    assert_eq!(kept, fit);
    run(&mut imu, 3);
    got.extend(drain_all(&mut imu));
    let flagged: Vec<usize> = (0..got.len())
        .filter(|&k| got[k].flags.has(ImuFlags::DATA_LOST))
        .collect();
    assert_eq!(
        flagged,
        vec![kept],
        "the first sample after the gap, and only it"
    );
    // Slots kept..200 were lost: the next kept slot is 200.
    assert_eq!(usize::from(got[kept].lost_before), 200 - kept);
}

#[test]
fn spi_errors_propagate() {
    let mut m = Lsm6dsoModel::new(TestGen::default());
    m.fail_spi = true;
    assert_eq!(
        Lsm6dso::new(m, Config::DEFAULT).err(),
        Some(Error::Spi(BusFault))
    );
    let mut imu = started();
    imu.device_mut().fail_spi = true;
    let mut buf = [ImuSample::default(); 2];
    assert_eq!(imu.drain(&mut buf), Err(Error::Spi(BusFault)));
}
