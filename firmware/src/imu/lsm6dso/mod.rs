//! ST LSM6DSO driver over embedded-hal 1.0 `SpiDevice`, behind the same [`ImuSource`] as the
//! ICM-42688-P: the second part that proves the abstraction.
//!
//! Why this part rather than the BMI088: its one FIFO carries both sensors, the temperature and
//! the time stamp, so a drain yields time-aligned samples exactly as the trait promises; the
//! BMI088's accelerometer and gyro are separate dies with separate FIFOs and clocks, whose samples
//! would have to be paired by resampling. And its FIFO is a different kind of format from the
//! ICM's fixed packets — tagged 7-byte words, one sensor per word, in no fixed order within a
//! sampling slot — so the trait is not shaped around one part.
//!
//! Register numbers and fields from the datasheet (ST DS12140, §8 "Register mapping" and §9
//! "Register description"; the FIFO section for the tags):
//! WHO_AM_I 0x0F = 0x6C; CTRL3_C SW_RESET; CTRL1_XL / CTRL2_G rate and range; FIFO_CTRL1–4
//! watermark, batch data rates, time stamp decimation, temperature batching, FIFO mode (stop when
//! full); INT1_CTRL the FIFO threshold and overrun on INT1; FIFO_STATUS1/2 the word count and the
//! latched overrun; FIFO_DATA_OUT_TAG and six data bytes per word (little-endian).
//!
//! Gaps: a word's TAG_CNT (its slot, modulo 4) that changes before both sensors of a slot arrived
//! drops the incomplete slot and flags the next sample; an overrun flags the first sample after
//! the words present (stop-when-full keeps the oldest); the time stamp words (one per slot, 25 µs
//! per LSB) give the number of slots lost. Self-test is not implemented for this part.

use embedded_hal::spi::{Operation, SpiDevice};

use crate::imu::{lost_between, Drained, ImuFlags, ImuSample, ImuSource};

/// Registers and fields (DS12140 §8–§9). A register is a variant of [`regs::Reg`], which knows its
/// address; the driver's reads and writes take a `Reg`. The variants are re-exported under the
/// datasheet's names (`regs::CTRL3_C`); fields and values stay plain consts.
pub mod regs {
    /// An LSM6DSO register (§8 register map; one flat address space as the driver uses it: the
    /// embedded-function and sensor-hub pages behind FUNC_CFG_ACCESS are never opened). Variants
    /// are the datasheet's names, so that a register is found by the name its tables give it.
    #[allow(non_camel_case_types)]
    #[derive(Clone, Copy, Debug, PartialEq, Eq)]
    #[repr(u8)]
    pub enum Reg {
        /// FIFO_CTRL1: watermark \[7:0\] in words.
        FIFO_CTRL1 = 0x07,
        /// FIFO_CTRL2: WTM8 (bit 0).
        FIFO_CTRL2 = 0x08,
        /// FIFO_CTRL3: BDR_GY \[7:4\], BDR_XL \[3:0\].
        FIFO_CTRL3 = 0x09,
        /// FIFO_CTRL4: DEC_TS_BATCH \[7:6\], ODR_T_BATCH \[5:4\], FIFO_MODE \[2:0\].
        FIFO_CTRL4 = 0x0A,
        /// INT1_CTRL: INT1_FIFO_OVR (4), INT1_FIFO_TH (3).
        INT1_CTRL = 0x0D,
        /// WHO_AM_I.
        WHO_AM_I = 0x0F,
        /// CTRL1_XL: ODR_XL \[7:4\], FS_XL \[3:2\].
        CTRL1_XL = 0x10,
        /// CTRL2_G: ODR_G \[7:4\], FS_G \[3:2\].
        CTRL2_G = 0x11,
        /// CTRL3_C: BDU (6), IF_INC (2), SW_RESET (0); reset value 0x04.
        CTRL3_C = 0x12,
        /// CTRL4_C: I2C_disable (2).
        CTRL4_C = 0x13,
        /// CTRL10_C: TIMESTAMP_EN (5).
        CTRL10_C = 0x19,
        /// FIFO_STATUS1: DIFF_FIFO \[7:0\]; FIFO_STATUS2 follows.
        FIFO_STATUS1 = 0x3A,
        /// FIFO_STATUS2: FIFO_WTM_IA (7), FIFO_OVR_IA (6), FIFO_FULL_IA (5), FIFO_OVR_LATCHED (3,
        /// cleared by reading), DIFF_FIFO \[9:8\] (1:0).
        FIFO_STATUS2 = 0x3B,
        /// FIFO_DATA_OUT_TAG, then X_L .. Z_H (0x79–0x7E); a burst rolls back to 0x78.
        FIFO_DATA_OUT_TAG = 0x78,
    }

    pub use Reg::*;

    impl Reg {
        /// The register's address (SPI address byte, bit 7 clear).
        pub const fn addr(self) -> u8 {
            self as u8
        }
    }

    /// The address, for the register-level model's tables.
    impl From<Reg> for u8 {
        fn from(r: Reg) -> u8 {
            r as u8
        }
    }

    /// SPI read bit.
    pub const READ: u8 = 0x80;
    /// The LSM6DSO's WHO_AM_I.
    pub const WHO_AM_I_VALUE: u8 = 0x6C;
    /// FIFO_STATUS2: FIFO_OVR_LATCHED.
    pub const FIFO_OVR_LATCHED: u8 = 1 << 3;
    /// Tag: gyro, not compressed.
    pub const TAG_GYRO: u8 = 0x01;
    /// Tag: accelerometer, not compressed.
    pub const TAG_ACCEL: u8 = 0x02;
    /// Tag: temperature.
    pub const TAG_TEMPERATURE: u8 = 0x03;
    /// Tag: time stamp.
    pub const TAG_TIMESTAMP: u8 = 0x04;
    /// Bytes per FIFO word.
    pub const WORD_LEN: usize = 7;
}

use regs::*;

/// Output data rate of both sensors (ODR_XL / ODR_G codes).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Odr {
    /// 104 Hz.
    Hz104 = 4,
    /// 208 Hz.
    Hz208 = 5,
    /// 416 Hz.
    Hz416 = 6,
    /// 833 Hz.
    Hz833 = 7,
    /// 1.66 kHz.
    Hz1666 = 8,
}

impl Odr {
    /// The rate, Hz (rounded).
    pub fn hz(self) -> u32 {
        match self {
            Odr::Hz104 => 104,
            Odr::Hz208 => 208,
            Odr::Hz416 => 416,
            Odr::Hz833 => 833,
            Odr::Hz1666 => 1666,
        }
    }
    /// The period in 25 µs time-stamp ticks.
    pub fn period_ticks(self) -> u16 {
        384 >> (self as u16 - 4)
    }
}

/// Accelerometer range (FS_XL codes: 00 ±2 g, 10 ±4 g, 11 ±8 g, 01 ±16 g).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum AccelRange {
    /// ±2 g, 0.061 mg/LSB.
    G2 = 0,
    /// ±4 g, 0.122 mg/LSB.
    G4 = 2,
    /// ±8 g, 0.244 mg/LSB.
    G8 = 3,
    /// ±16 g, 0.488 mg/LSB.
    G16 = 1,
}

/// Gyro range (FS_G codes).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum GyroRange {
    /// ±250 °/s, 8.75 m°/s per LSB.
    Dps250 = 0,
    /// ±500 °/s, 17.5 m°/s per LSB.
    Dps500 = 1,
    /// ±1000 °/s, 35 m°/s per LSB.
    Dps1000 = 2,
    /// ±2000 °/s, 70 m°/s per LSB.
    Dps2000 = 3,
}

impl GyroRange {
    /// m°/s per LSB.
    pub fn mdps_per_lsb(self) -> f32 {
        8.75 * (1u32 << self as u32) as f32
    }
}

/// The driver's configuration.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Config {
    /// Output data rate and batch data rate of both sensors.
    pub odr: Odr,
    /// Accelerometer range.
    pub accel_range: AccelRange,
    /// Gyro range.
    pub gyro_range: GyroRange,
    /// Watermark, FIFO words (1..=511; a slot takes 3 words, a temperature word now and then).
    pub watermark_words: u16,
    /// Calibration output unit per accelerometer LSB (1 for counts).
    pub accel_out_per_lsb: f32,
    /// Added to the scaled accelerometer output.
    pub accel_out_offset: f32,
}

impl Config {
    /// 833 Hz, ±8 g, ±2000 °/s, watermark 30 words (10 slots), counts.
    pub const DEFAULT: Config = Config {
        odr: Odr::Hz833,
        accel_range: AccelRange::G8,
        gyro_range: GyroRange::Dps2000,
        watermark_words: 30,
        accel_out_per_lsb: 1.0,
        accel_out_offset: 0.0,
    };
}

/// Driver errors.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Error<E> {
    /// The SPI transfer failed.
    Spi(E),
    /// WHO_AM_I read this, not 0x6C.
    WrongDevice(u8),
    /// The watermark is 0 or above 511 words.
    BadWatermark,
    /// The output unit factor or offset is not finite, or the largest code's output would not be.
    BadUnit,
}

impl<E: core::fmt::Debug> core::fmt::Display for Error<E> {
    fn fmt(&self, f: &mut core::fmt::Formatter<'_>) -> core::fmt::Result {
        match self {
            Error::Spi(e) => write!(
                f,
                "LSM6DSO: SPI transfer failed ({e:?}); check wiring and chip select"
            ),
            Error::WrongDevice(id) => write!(f, "LSM6DSO: WHO_AM_I reads {id:#04x}, expected 0x6c"),
            Error::BadWatermark => write!(f, "LSM6DSO: the watermark must be 1..=511 words"),
            Error::BadUnit => write!(
                f,
                "LSM6DSO: the accelerometer unit factor and offset must be finite, and finite at full scale"
            ),
        }
    }
}

/// The configuration's register writes, in order (sensors last, so the FIFO starts clean).
pub fn configure_writes(cfg: &Config) -> [(Reg, u8); 9] {
    let odr = cfg.odr as u8;
    [
        (CTRL3_C, 0x44), // BDU, IF_INC
        (CTRL4_C, 0x04), // I²C off
        (FIFO_CTRL1, (cfg.watermark_words & 0xFF) as u8),
        (FIFO_CTRL2, (cfg.watermark_words >> 8) as u8 & 1),
        (FIFO_CTRL3, (odr << 4) | odr), // both sensors batched at their ODR
        // A time stamp every slot, the temperature at 52 Hz, FIFO mode (stop when full).
        (FIFO_CTRL4, (0b01 << 6) | (0b11 << 4) | 0b001),
        (INT1_CTRL, (1 << 4) | (1 << 3)),
        (CTRL10_C, 1 << 5),
        (CTRL1_XL, (odr << 4) | ((cfg.accel_range as u8) << 2)),
    ]
}

/// Words read per FIFO transfer at most.
pub const BATCH_WORDS: usize = 48;

/// The pairing of tagged words into samples, and the gap checks.
pub struct Pairing {
    accel_per_lsb: f32,
    accel_offset: f32,
    gyro_rad_s_per_lsb: f32,
    period_ticks: u16,
    /// The slot's first sensor, converted as its word arrived: a slot may span two drains, and a
    /// word converted at once needs its three codes in registers only, not stored and reloaded.
    pending: [f32; 3],
    temp_c: f32,
    timestamp: u16,
    /// The time stamp of the last sample emitted (valid once [`EMITTED`] is set).
    last_emitted: u16,
    /// The pairing state as bit fields ([`SLOT_MASK`], [`HAVE_GYRO`], [`HAVE_ACCEL`],
    /// [`LOST_PENDING`], [`EMITTED`], [`PENDING_SATURATED`]): one word, so that the per-word loop
    /// keeps it in one register where separate fields (slot, sensors present, lost, `Option` of
    /// the last time stamp) were spilled to the stack.
    state: u32,
    gap_after_words: i32,
}

impl Pairing {
    /// For `cfg`.
    pub fn new(cfg: &Config) -> Pairing {
        Pairing {
            accel_per_lsb: cfg.accel_out_per_lsb,
            accel_offset: cfg.accel_out_offset,
            gyro_rad_s_per_lsb: cfg.gyro_range.mdps_per_lsb() * 1e-3 * core::f32::consts::PI
                / 180.0,
            period_ticks: cfg.odr.period_ticks(),
            pending: [0.0; 3],
            temp_c: f32::NAN,
            timestamp: 0,
            last_emitted: 0,
            state: NO_SLOT,
            gap_after_words: -1,
        }
    }

    /// After FIFO_STATUS1/2: the words to read now (at most `room`), whether more stay, and the
    /// overrun noted.
    pub fn plan_read(&mut self, status: [u8; 2], room: usize) -> (usize, bool) {
        let count = usize::from(u16::from_le_bytes([status[0], status[1] & 0x03]));
        if status[1] & FIFO_OVR_LATCHED != 0 {
            self.gap_after_words = count as i32;
        }
        let n = count.min(room);
        (n, count > n)
    }

    /// Feeds one word; returns a sample when it completes a slot ([`Self::word_into`]).
    pub fn word(&mut self, w: &[u8; WORD_LEN]) -> Option<ImuSample> {
        let mut s = ImuSample::default();
        self.word_into(w, &mut s).then_some(s)
    }

    /// Feeds one word; when it completes a slot, writes the sample into `out` and returns true
    /// (`out` untouched otherwise). Written for the per-sample budget (README "Measured figures"):
    /// each sensor word converted as it arrives (the slot's first kept converted), the state in
    /// one word of bit fields, and a word's three range checks folded into one bit
    /// (`full_scale`): 187 instructions per sample before, 144 after (QEMU bench).
    #[inline(always)]
    pub fn word_into(&mut self, w: &[u8; WORD_LEN], out: &mut ImuSample) -> bool {
        if self.gap_after_words >= 0 {
            if self.gap_after_words == 0 {
                self.state |= LOST_PENDING;
            }
            self.gap_after_words -= 1;
        }
        let v = |i: usize| i16::from_le_bytes([w[1 + 2 * i], w[2 + 2 * i]]);
        match w[0] >> 3 {
            TAG_GYRO => {
                let kg = self.gyro_rad_s_per_lsb;
                let (x, y, z) = (v(0), v(1), v(2));
                let values = [f32::from(x) * kg, f32::from(y) * kg, f32::from(z) * kg];
                self.sensor_into(w[0], values, full_scale(x, y, z), out, true)
            }
            TAG_ACCEL => {
                let (k, c) = (self.accel_per_lsb, self.accel_offset);
                let (x, y, z) = (v(0), v(1), v(2));
                let values = [
                    f32::from(x) * k + c,
                    f32::from(y) * k + c,
                    f32::from(z) * k + c,
                ];
                self.sensor_into(w[0], values, full_scale(x, y, z), out, false)
            }
            TAG_TEMPERATURE => {
                self.temp_c = f32::from(v(0)) * (1.0 / 256.0) + 25.0;
                false
            }
            TAG_TIMESTAMP => {
                self.timestamp = u16::from_le_bytes([w[1], w[2]]);
                false
            }
            _ => false, // configuration-change and compressed words: not enabled
        }
    }

    /// One sensor word's converted values (`gyro` or accelerometer): kept as the slot's first,
    /// or, when they complete the slot, the sample written into `out` (true).
    #[inline(always)]
    fn sensor_into(
        &mut self,
        head: u8,
        values: [f32; 3],
        saturated: u32,
        out: &mut ImuSample,
        gyro: bool,
    ) -> bool {
        let bit = if gyro { HAVE_GYRO } else { HAVE_ACCEL };
        // The word's slot counter (its bits 1–2) where the state keeps it.
        let slot = (u32::from(head) << SLOT_SHIFT) & SLOT_COUNTER;
        let mut st = self.state;
        if (st ^ slot) & SLOT_MASK != 0 {
            // The previous slot lost a word.
            if st & HAVE_MASK != 0 {
                st |= LOST_PENDING;
            }
            st = (st & !(SLOT_MASK | HAVE_MASK)) | slot;
        }
        let have = st & HAVE_MASK;
        if have == 0 || have == bit {
            // The slot's first sensor (or the same one again, which replaces it).
            self.pending = values;
            self.state = (st & !PENDING_SATURATED) | bit | saturated;
            return false;
        }
        let (mine, other) = if gyro {
            (&mut out.gyro_rad_s, &mut out.accel_out)
        } else {
            (&mut out.accel_out, &mut out.gyro_rad_s)
        };
        *mine = values;
        *other = self.pending;
        let lost = if st & EMITTED != 0 {
            lost_between(self.last_emitted, self.timestamp, self.period_ticks)
        } else {
            0
        };
        self.last_emitted = self.timestamp;
        // The pending bits sit where the flags do.
        let mut flags = ((st | saturated) & (PENDING_SATURATED | LOST_PENDING)) as u8;
        if lost > 0 {
            flags |= ImuFlags::DATA_LOST;
        }
        self.state = (st & SLOT_MASK) | EMITTED;
        out.temp_c = self.temp_c;
        out.timestamp = self.timestamp;
        out.lost_before = lost;
        out.flags = ImuFlags(flags);
        true
    }
}

/// [`PENDING_SATURATED`] (1) when one of a word's three codes is at full scale (±32767, and
/// −32768), 0 otherwise. A code's square plus 65 535 reaches 2³⁰ exactly at full scale (32 766² +
/// 65 535 < 2³⁰ ≤ 32 767² + 65 535 ≤ 2¹⁵·2¹⁵ + 65 535 < 2³¹), so the three fold by OR into one
/// bit: a multiply-add and an OR per code, where a comparison per code costs three or four.
#[inline(always)]
fn full_scale(x: i16, y: i16, z: i16) -> u32 {
    let key = |v: i16| {
        let v = i32::from(v);
        (v * v + 65_535) as u32
    };
    (key(x) | key(y) | key(z)) >> 30
}

/// [`Pairing`]'s state bits. The slot's first sensor had a code at full scale: bit 0, as
/// [`ImuFlags::SATURATED`], so that the flags are taken from the state with one mask.
const PENDING_SATURATED: u32 = ImuFlags::SATURATED as u32;
/// The next sample is flagged DATA_LOST (a slot dropped, or the overrun's gap reached): bit 1, as
/// [`ImuFlags::DATA_LOST`].
const LOST_PENDING: u32 = ImuFlags::DATA_LOST as u32;
/// The slot's sensors present (the tags, 1 and 2, shifted by 3).
const HAVE_GYRO: u32 = 1 << 3;
const HAVE_ACCEL: u32 = 1 << 4;
const HAVE_MASK: u32 = HAVE_GYRO | HAVE_ACCEL;
/// A sample was emitted: `last_emitted` is valid.
const EMITTED: u32 = 1 << 5;
/// The slot counter: the word's first byte's bits 1–2 shifted by this, to bits 9–10.
const SLOT_SHIFT: u32 = 8;
const SLOT_COUNTER: u32 = 0b11 << 9;
/// No slot yet (before the first sensor word): matches no word's counter.
const NO_SLOT: u32 = 1 << 11;
const SLOT_MASK: u32 = SLOT_COUNTER | NO_SLOT;

/// LSM6DSO on a blocking SPI device (mode 3).
pub struct Lsm6dso<SPI> {
    spi: SPI,
    cfg: Config,
    pairing: Pairing,
    buf: [u8; BATCH_WORDS * WORD_LEN],
}

impl<SPI: SpiDevice> Lsm6dso<SPI> {
    /// Resets the part, checks WHO_AM_I and starts it with `cfg`.
    pub fn new(spi: SPI, cfg: Config) -> Result<Self, Error<SPI::Error>> {
        if cfg.watermark_words == 0 || cfg.watermark_words > 511 {
            return Err(Error::BadWatermark);
        }
        // The largest code's output must be finite: the pipeline takes a sample's finiteness from
        // its INVALID flag (`ImuSample`).
        if !(cfg.accel_out_per_lsb.abs() * 32_768.0 + cfg.accel_out_offset.abs()).is_finite() {
            return Err(Error::BadUnit);
        }
        let mut imu = Lsm6dso {
            spi,
            cfg,
            pairing: Pairing::new(&cfg),
            buf: [0; BATCH_WORDS * WORD_LEN],
        };
        // SW_RESET (with IF_INC kept), then 50 µs before the next access.
        imu.write(CTRL3_C, 0x05)?;
        imu.spi
            .transaction(&mut [Operation::DelayNs(50_000)])
            .map_err(Error::Spi)?;
        let mut id = [0u8];
        imu.read(WHO_AM_I, &mut id)?;
        if id[0] != WHO_AM_I_VALUE {
            return Err(Error::WrongDevice(id[0]));
        }
        for (reg, v) in configure_writes(&cfg) {
            imu.write(reg, v)?;
        }
        let odr = cfg.odr as u8;
        imu.write(CTRL2_G, (odr << 4) | ((cfg.gyro_range as u8) << 2))?;
        Ok(imu)
    }

    /// The configuration in force.
    pub fn config(&self) -> &Config {
        &self.cfg
    }

    /// The SPI device (e.g. a simulated part's clock).
    pub fn device_mut(&mut self) -> &mut SPI {
        &mut self.spi
    }

    fn write(&mut self, reg: Reg, v: u8) -> Result<(), Error<SPI::Error>> {
        self.spi.write(&[reg.addr(), v]).map_err(Error::Spi)
    }

    fn read(&mut self, reg: Reg, buf: &mut [u8]) -> Result<(), Error<SPI::Error>> {
        self.spi
            .transaction(&mut [Operation::Write(&[reg.addr() | READ]), Operation::Read(buf)])
            .map_err(Error::Spi)
    }
}

impl<SPI: SpiDevice> ImuSource for Lsm6dso<SPI> {
    type Error = Error<SPI::Error>;

    /// Reads FIFO_STATUS1/2 (clearing the latched overrun), then up to [`BATCH_WORDS`] words, and
    /// pairs them into samples (a slot's words may span two drains).
    fn drain(&mut self, out: &mut [ImuSample]) -> Result<Drained, Self::Error> {
        let mut status = [0u8; 2];
        self.read(FIFO_STATUS1, &mut status)?;
        // A slot is at least two words: read no more than `out` can take.
        let (words, more) = self
            .pairing
            .plan_read(status, (out.len() * 2).min(BATCH_WORDS));
        let bytes = words * WORD_LEN;
        if bytes > 0 {
            let spi = &mut self.spi;
            spi.transaction(&mut [
                Operation::Write(&[FIFO_DATA_OUT_TAG.addr() | READ]),
                Operation::Read(&mut self.buf[..bytes]),
            ])
            .map_err(Error::Spi)?;
        }
        let mut n = 0;
        for w in self.buf[..bytes].chunks_exact(WORD_LEN) {
            let Ok(w) = <&[u8; WORD_LEN]>::try_from(w) else {
                break;
            };
            let mut spare = ImuSample::default();
            let room = n < out.len();
            let slot = out.get_mut(n).unwrap_or(&mut spare);
            if self.pairing.word_into(w, slot) && room {
                n += 1;
            }
        }
        Ok(Drained { samples: n, more })
    }

    fn sample_rate_hz(&self) -> u32 {
        self.cfg.odr.hz()
    }
}
