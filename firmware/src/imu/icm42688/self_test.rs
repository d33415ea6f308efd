//! Self-test (DS-000347, its self-test section; the procedure and limits of TDK's reference driver,
//! `Icm426xxSelfTest.c` in the InvenSense eMD): with the sensor at a fixed setting (gyro ±250 °/s,
//! accelerometer ±4 g, 1 kHz), average its output over 200 samples with self-test off and on; the
//! response |on − off| of each axis is compared with the factory value derived from the part's
//! self-test code (XG/YG/ZG_ST_DATA in bank 1, XA/YA/ZA_ST_DATA in bank 2):
//!
//! `ST_OTP = 2620 / 2^(3 − FS_SEL) · 1.01^(code − 1)` LSB (FS_SEL 3 for the gyro at ±250 °/s, 2 for
//! the accelerometer at ±4 g).
//!
//! Pass: gyro response / ST_OTP > 0.5; accelerometer 0.5 < response / ST_OTP < 1.5. A code of 0
//! (no factory value) falls back to absolute limits: gyro response ≥ 60 °/s, accelerometer 50 to
//! 1200 mg. The gyro's offset with self-test off must also be within ±20 °/s.
//!
//! The measurement follows TDK's reference driver: `Ixm42xxx/Ixm42xxxSelfTest.c` in TDK's public
//! repository `InvenSenseInc/public.mcu.iim42652` (commit 5033be4; the same procedure as the
//! ICM-426xx eMD's `Icm426xxSelfTest.c`, which differs only in testing the accelerometer at ±4 g,
//! as here, rather than the IIM-42652's ±2 g). Lines 36–44: the setting — range, 1 kHz, the UI
//! filter of 3rd order at a bandwidth of ODR/10, for both sensors; lines 197–212 (gyro) and
//! 292–307 (accelerometer): those fields written by read-modify-write before measuring; lines
//! 389–423: only the sensor under test in low-noise mode, 60 ms (gyro) or 25 ms (accelerometer) to
//! settle, and after the self-test is switched on 200 ms (gyro) or 25 ms; lines 426–457: a sample
//! read only when INT_STATUS says DATA_RDY, samples at −32768 discarded, 200 of them; lines
//! 482–520: the registers saved before and restored after. PX4's, ArduPilot's and Betaflight's
//! ICM-42688-P drivers run no self-test, so TDK's is the procedure followed.
//!
//! The evaluation is a pure function of the averages and the codes, run after the measurement
//! (never per sample; it uses `libm::pow`).

use super::regs::*;
use super::Step;

/// Samples averaged per phase.
pub const SAMPLES: u32 = 200;
/// Wait between two reads of INT_STATUS while waiting for DATA_RDY: a quarter of the 1 kHz
/// period, so that consecutive samples are read and none twice.
pub const POLL_WAIT_NS: u32 = 250_000;
/// INT_STATUS reads before a phase gives up (`Error::NoDataReady`): twice the time 200 samples
/// take at 1 kHz (TDK's driver gives 300 reads 1 ms apart).
pub const MAX_POLLS: u32 = 2 * SAMPLES * 4;
/// Gyro LSB per °/s at ±250 °/s.
pub const GYRO_ST_LSB_PER_DPS: f32 = 131.0;
/// Accelerometer LSB per g at ±4 g.
pub const ACCEL_ST_LSB_PER_G: f32 = 8192.0;

/// Which sensor is under test.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum SensorUnderTest {
    /// The gyro.
    Gyro,
    /// The accelerometer.
    Accel,
}

impl SensorUnderTest {
    /// First of its six data registers.
    pub fn data_register(self) -> Bank0 {
        match self {
            SensorUnderTest::Gyro => GYRO_DATA_X1,
            SensorUnderTest::Accel => ACCEL_DATA_X1,
        }
    }
    /// First of its three self-test code registers, with their bank (gyro: bank 1, §15;
    /// accelerometer: bank 2, §16).
    pub fn code_register(self) -> Register {
        match self {
            SensorUnderTest::Gyro => XG_ST_DATA.reg(),
            SensorUnderTest::Accel => XA_ST_DATA.reg(),
        }
    }
}

/// Configure for the measurement (TDK's setting, see the module doc): FIFO off, self-test off,
/// the sensor's range and 1 kHz, its UI filter 3rd order at ODR/10, the sensor under test alone
/// in low-noise mode, and its settling time (gyro 60 ms, accelerometer 25 ms).
pub fn enter_steps(sensor: SensorUnderTest) -> [Step; 9] {
    let (config0, fs_odr, config1, ord_mask, ord, bw_mask, power, settle) = match sensor {
        // GYRO_FS_SEL 011 (±250 °/s), GYRO_ODR 0110 (1 kHz).
        SensorUnderTest::Gyro => (
            GYRO_CONFIG0,
            (3 << 5) | 6,
            GYRO_CONFIG1,
            GYRO_UI_FILT_ORD_MASK,
            GYRO_UI_FILT_ORD_3RD,
            GYRO_UI_FILT_BW_MASK,
            PWR_GYRO_LOW_NOISE,
            60_000,
        ),
        // ACCEL_FS_SEL 010 (±4 g), ACCEL_ODR 0110 (1 kHz).
        SensorUnderTest::Accel => (
            ACCEL_CONFIG0,
            (2 << 5) | 6,
            ACCEL_CONFIG1,
            ACCEL_UI_FILT_ORD_MASK,
            ACCEL_UI_FILT_ORD_3RD,
            ACCEL_UI_FILT_BW_MASK,
            PWR_ACCEL_LOW_NOISE,
            25_000,
        ),
    };
    [
        Step::Write(FIFO_CONFIG.reg(), 0),
        Step::Write(SELF_TEST_CONFIG.reg(), 0),
        // FS_SEL 7:5 and ODR 3:0; bit 4 is reserved.
        Step::Update {
            reg: config0.reg(),
            mask: 0xEF,
            value: fs_odr,
        },
        Step::Update {
            reg: config1.reg(),
            mask: ord_mask,
            value: ord,
        },
        Step::Update {
            reg: GYRO_ACCEL_CONFIG0.reg(),
            mask: bw_mask,
            value: UI_FILT_BW_ODR_10 & bw_mask,
        },
        Step::Write(PWR_MGMT0.reg(), 0),
        Step::Write(PWR_MGMT0.reg(), power),
        Step::WaitUs(200),
        Step::WaitUs(settle),
    ]
}

/// The UI filter registers the self-test changes, in address order (one burst saves them).
pub const SAVED_FILTERS: [Bank0; 3] = [GYRO_CONFIG1, GYRO_ACCEL_CONFIG0, ACCEL_CONFIG1];
const _: () = assert!(
    GYRO_ACCEL_CONFIG0 as u8 == GYRO_CONFIG1 as u8 + 1
        && ACCEL_CONFIG1 as u8 == GYRO_CONFIG1 as u8 + 2
);
const _: () = assert!(GYRO_DATA_X1 as u8 == ACCEL_DATA_X1 as u8 + 6);

/// Sensors off, then the saved UI filter registers written back (before the configuration is
/// applied again).
pub fn restore_steps(saved: [u8; 3]) -> [Step; 4] {
    [
        Step::Write(PWR_MGMT0.reg(), 0),
        Step::Write(SAVED_FILTERS[0].reg(), saved[0]),
        Step::Write(SAVED_FILTERS[1].reg(), saved[1]),
        Step::Write(SAVED_FILTERS[2].reg(), saved[2]),
    ]
}

/// Turn the sensor's self-test on and wait for it to settle (gyro 200 ms, accelerometer 25 ms).
/// Run in the bank [`enter_steps`] left selected (bank 0), without selecting it again.
pub fn enable_steps(sensor: SensorUnderTest) -> [Step; 2] {
    match sensor {
        SensorUnderTest::Gyro => [
            Step::Write(SELF_TEST_CONFIG.reg(), ST_GYRO_ALL),
            Step::WaitUs(200_000),
        ],
        SensorUnderTest::Accel => [
            Step::Write(SELF_TEST_CONFIG.reg(), ST_ACCEL_ALL),
            Step::WaitUs(25_000),
        ],
    }
}

/// Sums big-endian 16-bit triples.
#[derive(Default)]
pub struct Averager {
    sum: [i64; 3],
    n: i64,
}

impl Averager {
    /// Adds one read of the six data registers, unless an axis reads −32768 (invalid: the
    /// sensor starting), which TDK's driver discards too.
    pub fn add(&mut self, b: &[u8; 6]) {
        let v: [i16; 3] = core::array::from_fn(|i| i16::from_be_bytes([b[2 * i], b[2 * i + 1]]));
        if v.contains(&i16::MIN) {
            return;
        }
        for i in 0..3 {
            self.sum[i] += i64::from(v[i]);
        }
        self.n += 1;
    }

    /// Samples added.
    pub fn count(&self) -> u32 {
        self.n as u32
    }
    /// The mean, LSB (rounded toward zero).
    pub fn mean(&self) -> [i32; 3] {
        let n = self.n.max(1);
        self.sum.map(|s| (s / n) as i32)
    }
}

/// The factory self-test response for a code at a range setting `fs_sel`, LSB.
pub fn otp_lsb(fs_sel: u8, code: u8) -> f32 {
    if code == 0 {
        return 0.0;
    }
    let base = 2620.0 / f64::from(1u32 << (3 - fs_sel.min(3)));
    (base * libm::pow(1.01, f64::from(code) - 1.0)) as f32
}

/// One axis's result.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct AxisResult {
    /// |on − off|, LSB.
    pub response_lsb: f32,
    /// The factory response, LSB (0 when the part has no code).
    pub otp_lsb: f32,
    /// Within the limits.
    pub pass: bool,
}

/// The self-test's findings.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct SelfTestReport {
    /// Gyro x, y, z.
    pub gyro: [AxisResult; 3],
    /// Gyro offset with self-test off, °/s, per axis.
    pub gyro_offset_dps: [f32; 3],
    /// Accelerometer x, y, z.
    pub accel: [AxisResult; 3],
}

impl SelfTestReport {
    /// Every axis of both sensors passed.
    pub fn passed(&self) -> bool {
        let offset_ok = self.gyro_offset_dps.iter().all(|o| o.abs() <= 20.0);
        offset_ok && self.gyro.iter().chain(self.accel.iter()).all(|a| a.pass)
    }

    /// Records a sensor's measurement: the means with self-test off and on, and its codes.
    pub fn set(&mut self, sensor: SensorUnderTest, off: [i32; 3], on: [i32; 3], codes: [u8; 3]) {
        for i in 0..3 {
            let response = (on[i] - off[i]).unsigned_abs() as f32;
            let (fs_sel, otp_fallback_ok) = match sensor {
                SensorUnderTest::Gyro => (3, response >= 60.0 * GYRO_ST_LSB_PER_DPS),
                SensorUnderTest::Accel => {
                    let mg = response / ACCEL_ST_LSB_PER_G * 1000.0;
                    (2, (50.0..=1200.0).contains(&mg))
                }
            };
            let otp = otp_lsb(fs_sel, codes[i]);
            let pass = if otp > 0.0 {
                let ratio = response / otp;
                match sensor {
                    SensorUnderTest::Gyro => ratio > 0.5,
                    SensorUnderTest::Accel => ratio > 0.5 && ratio < 1.5,
                }
            } else {
                otp_fallback_ok
            };
            let r = AxisResult {
                response_lsb: response,
                otp_lsb: otp,
                pass,
            };
            match sensor {
                SensorUnderTest::Gyro => {
                    self.gyro[i] = r;
                    self.gyro_offset_dps[i] = off[i] as f32 / GYRO_ST_LSB_PER_DPS;
                }
                SensorUnderTest::Accel => self.accel[i] = r,
            }
        }
    }
}
