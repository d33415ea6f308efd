//! Configuration registers as the datasheet says (DS-000347 §14.30–14.31 for the range and rate
//! fields, §5.3's AAF table, §14.4/§14.38 for the FIFO), written out here per setting, and the
//! refused combinations.

use super::*;
use crate::imu::icm42688::regs::*;
use crate::imu::icm42688::{AccelRange, AntiAlias, ConfigError, Error, FifoFormat, GyroRange, Odr};
use crate::imu::ImuFlags;
use embedded_hal::spi::SpiDevice;

#[test]
fn default_configuration_registers() {
    let mut imu = started(Config::DEFAULT);
    let m = imu.device_mut();
    // ±2000 °/s = FS_SEL 000, ±16 g = 000, 1 kHz = ODR 0110.
    assert_eq!(m.register(0, GYRO_CONFIG0), 0b0000_0110); // FS_SEL 000, ODR 0110
    assert_eq!(m.register(0, ACCEL_CONFIG0), 0b0000_0110); // FS_SEL 000, ODR 0110
                                                           // 258 Hz: DELT 6, DELTSQR 36, BITSHIFT 10 (gyro: bank 1, AAF and notch enabled).
    assert_eq!(m.register(1, GYRO_CONFIG_STATIC2), 0xA0);
    assert_eq!(m.register(1, GYRO_CONFIG_STATIC3), 6);
    assert_eq!(m.register(1, GYRO_CONFIG_STATIC4), 36);
    assert_eq!(m.register(1, GYRO_CONFIG_STATIC5), 10 << 4);
    // Accelerometer: DELT in bits 6:1, ACCEL_AAF_DIS bit 0 clear.
    assert_eq!(m.register(2, ACCEL_CONFIG_STATIC2), 6 << 1);
    assert_eq!(m.register(2, ACCEL_CONFIG_STATIC3), 36);
    assert_eq!(m.register(2, ACCEL_CONFIG_STATIC4), 10 << 4);
    // Stop-on-full; accel, gyro, temperature, time stamp; watermark interrupt while above.
    assert_eq!(m.register(0, FIFO_CONFIG), 0b10 << 6);
    assert_eq!(m.register(0, FIFO_CONFIG1), 0b0010_1111);
    assert_eq!(
        (m.register(0, FIFO_CONFIG2), m.register(0, FIFO_CONFIG3)),
        (1, 0)
    );
    // Count in records, big-endian count and data, I²C off.
    assert_eq!(m.register(0, INTF_CONFIG0), 0b0111_0011);
    // INT1 latched, push-pull, active high; FIFO threshold and full routed to it.
    assert_eq!(m.register(0, INT_CONFIG), 0b111);
    assert_eq!(
        m.register(0, INT_CONFIG1) & (1 << 4),
        0,
        "INT_ASYNC_RESET cleared"
    );
    assert_eq!(m.register(0, INT_SOURCE0), 0b110);
    // At 1 kHz the reset pulse and de-assert settings stand (bits 6:5 = 00).
    assert_eq!(m.register(0, INT_CONFIG1), 0b0000_0000);
    // AFSR off: 01 in bits 7:6 over the reset value 0x91 (Betaflight's write).
    assert_eq!(m.register(0, INTF_CONFIG1), 0x51);
    // Time stamps: TMST_EN (0) on, TMST_FSYNC_EN (1), TMST_DELTA_EN (2), TMST_RES (3: 1 µs) and
    // TMST_TO_REGS_EN (4) off; bit 5 as at reset (0x23).
    assert_eq!(m.register(0, TMST_CONFIG), 0b0010_0001);
    // FSYNC not tagged anywhere: FSYNC_UI_SEL (6:4) = 000 (reset value 0x10 has 001).
    assert_eq!(m.register(0, FSYNC_CONFIG), 0x00);
    assert_eq!(m.register(0, PWR_MGMT0), 0b1111, "both sensors low-noise");
    assert_eq!(
        m.violations, 0,
        "no write within 200 µs of starting the gyro"
    );
}

#[test]
fn other_settings_and_high_resolution() {
    let cfg = Config {
        odr: Odr::Hz8000,
        accel_range: AccelRange::G4,
        gyro_range: GyroRange::Dps500,
        accel_aaf: AntiAlias::Off,
        gyro_aaf: AntiAlias::Hz997,
        watermark_packets: 100,
        ..Config::DEFAULT
    };
    let mut imu = started(cfg);
    let m = imu.device_mut();
    assert_eq!(m.register(0, GYRO_CONFIG0), 0b0100_0011); // FS_SEL 010 (±500 °/s), ODR 0011 (8 kHz)
    assert_eq!(m.register(0, ACCEL_CONFIG0), 0b0100_0011); // FS_SEL 010 (±4 g), ODR 0011 (8 kHz)
                                                           // 997 Hz: DELT 21, DELTSQR 440 = 0x1B8, BITSHIFT 6.
    assert_eq!(m.register(1, GYRO_CONFIG_STATIC3), 21);
    assert_eq!(m.register(1, GYRO_CONFIG_STATIC4), 0xB8);
    assert_eq!(m.register(1, GYRO_CONFIG_STATIC5), (6 << 4) | 0x1);
    assert_eq!(m.register(2, ACCEL_CONFIG_STATIC2) & 1, 1, "accel AAF off");
    // At 8 kHz (§14.43): INT_TPULSE_DURATION 1 (8 µs) and INT_TDEASSERT_DISABLE 1, "required for
    // ODR ≥ 4 kHz"; INT_ASYNC_RESET 0.
    assert_eq!(m.register(0, INT_CONFIG1), 0b0110_0000);
    assert_eq!(
        (m.register(0, FIFO_CONFIG2), m.register(0, FIFO_CONFIG3)),
        (100, 0)
    );

    let hires = Config {
        fifo: FifoFormat::Packet4HighRes,
        ..Config::DEFAULT
    };
    let mut imu = started(hires);
    assert_eq!(imu.device_mut().register(0, FIFO_CONFIG1), 0b0011_1111);
}

#[test]
fn refused_combinations() {
    let bad = [
        (
            Config {
                fifo: FifoFormat::Packet4HighRes,
                accel_range: AccelRange::G4,
                ..Config::DEFAULT
            },
            ConfigError::HighResRange,
        ),
        (
            Config {
                watermark_packets: 0,
                ..Config::DEFAULT
            },
            ConfigError::Watermark,
        ),
        (
            Config {
                watermark_packets: 129, // 2048 / 16 = 128 packets
                ..Config::DEFAULT
            },
            ConfigError::Watermark,
        ),
        (
            Config {
                accel_out_per_lsb: f32::NAN,
                ..Config::DEFAULT
            },
            ConfigError::Unit,
        ),
        // Finite, but infinite at full scale: its samples would be non-finite without the flag.
        (
            Config {
                accel_out_per_lsb: 1e34,
                ..Config::DEFAULT
            },
            ConfigError::Unit,
        ),
    ];
    for (cfg, why) in bad {
        let r = Icm42688::new(Icm42688Model::new(TestGen::default()), cfg);
        assert_eq!(r.err(), Some(Error::Config(why)));
    }
}

#[test]
fn time_stamp_resolution_is_set_by_configure() {
    // A part switched to 16 µs time stamps (TMST_RES) behind the driver's back: its time base
    // breaks (the stamps step by 62.5 ticks per millisecond instead of 1000), which the gap check
    // sees as a loss of many samples.
    let mut imu = started(Config::DEFAULT);
    run_samples(&mut imu, 3);
    assert_eq!(drain_all(&mut imu).len(), 3);
    let m = imu.device_mut();
    m.transaction(&mut [embedded_hal::spi::Operation::Write(&[
        TMST_CONFIG as u8,
        0x29,
    ])])
    .unwrap();
    run_samples(&mut imu, 5);
    let got = drain_all(&mut imu);
    assert!(got.iter().any(|s| s.flags.has(ImuFlags::DATA_LOST)));
    // `configure` sets the 1 µs resolution whatever the part held: no gap in what follows.
    imu.configure(Config::DEFAULT).unwrap();
    assert_eq!(imu.device_mut().register(0, TMST_CONFIG) & TMST_RES_16US, 0);
    run_samples(&mut imu, 10);
    let got = drain_all(&mut imu);
    assert_eq!(got.len(), 10);
    // The first follows the flush of the reconfiguration; none after it.
    assert!(got[1..].iter().all(|s| !s.flags.has(ImuFlags::DATA_LOST)));
}

/// Every step list leaves bank 0 selected (its last register is a bank-0 one), which the data
/// path's plain bank-0 reads and the self-test's enable list, run without a select, rely on
/// (`regs`' module doc; REG_BANK_SEL, §14.51). The enable lists name bank-0 registers only.
#[test]
fn step_lists_leave_bank_0_selected() {
    use crate::imu::icm42688::self_test::{
        enable_steps, enter_steps, restore_steps, SensorUnderTest,
    };
    use crate::imu::icm42688::{configure_steps, Step, RESET_STEPS};
    let last_bank = |steps: &[Step]| {
        steps
            .iter()
            .rev()
            .find_map(Step::register)
            .map(|r| r.bank())
    };
    let hires = Config {
        fifo: FifoFormat::Packet4HighRes,
        accel_aaf: AntiAlias::Off,
        ..Config::DEFAULT
    };
    assert_eq!(last_bank(&RESET_STEPS), Some(0));
    assert_eq!(last_bank(&configure_steps(&Config::DEFAULT)), Some(0));
    assert_eq!(last_bank(&configure_steps(&hires)), Some(0));
    assert_eq!(last_bank(&restore_steps([0; 3])), Some(0));
    for sensor in [SensorUnderTest::Gyro, SensorUnderTest::Accel] {
        assert_eq!(last_bank(&enter_steps(sensor)), Some(0));
        assert!(enable_steps(sensor)
            .iter()
            .filter_map(Step::register)
            .all(|r| r.bank() == 0));
    }
}
