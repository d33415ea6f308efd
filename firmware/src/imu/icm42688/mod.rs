//! TDK InvenSense ICM-42688-P driver over SPI: embedded-hal 1.0 `SpiDevice` ([`Icm42688`]) and
//! embedded-hal-async `SpiDevice` ([`Icm42688Async`]), one register logic for both.
//!
//! What it does (datasheet DS-000347 sections in [`regs`]):
//!
//! - soft reset and identify (WHO_AM_I 0x47);
//! - output data rate and full scale of both sensors, the anti-alias filters (§5.3 table);
//! - the FIFO in stop-on-full mode with accel, gyro, temperature and the 1 µs ODR time stamp, as
//!   16-byte packets 3 or 20-bit packets 4 ([`FifoFormat`]), decoded by [`fifo`];
//! - a watermark interrupt on INT1 (latched, push-pull, active high; FIFO full on INT1 too);
//! - FIFO overflow: in stop-on-full mode the packets in the FIFO are the ones *before* the gap, so
//!   when INT_STATUS reports FIFO_FULL the sample after the packets present is flagged
//!   [`ImuFlags::DATA_LOST`]; independently every time stamp is checked against the previous one
//!   and a jump of more than one period flags the sample with the number of periods lost;
//! - a FIFO that reads back out of step (a header that is not the configured packet's) is flushed
//!   and reported as [`Error::FifoCorrupt`]; the next sample is flagged as following lost data;
//! - self-test on request ([`self_test`]).
//!
//! The register sequences are data ([`Step`] lists built by [`configure_steps`]) and the
//! decisions are methods of [`Core`]: the blocking and async drivers only move bytes.

pub mod check;
pub mod fifo;
pub mod regs;
pub mod self_test;

mod asynch;
mod blocking;
mod form;

pub use asynch::Icm42688Async;
pub use blocking::Icm42688;
pub use fifo::Scale;
pub use self_test::SelfTestReport;

use crate::imu::{lost_between, ImuFlags, ImuSample};
use regs::*;

/// Full-scale range of the accelerometer (ACCEL_FS_SEL, §14.31).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum AccelRange {
    /// ±16 g, 2048 LSB/g.
    G16 = 0,
    /// ±8 g, 4096 LSB/g.
    G8 = 1,
    /// ±4 g, 8192 LSB/g.
    G4 = 2,
    /// ±2 g, 16384 LSB/g.
    G2 = 3,
}

impl AccelRange {
    /// 16-bit LSB per g.
    pub fn lsb_per_g(self) -> f32 {
        2048.0 * (1u32 << self as u32) as f32
    }
}

/// Full-scale range of the gyro (GYRO_FS_SEL, §14.30).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum GyroRange {
    /// ±2000 °/s, 16.4 LSB/(°/s).
    Dps2000 = 0,
    /// ±1000 °/s, 32.8 LSB/(°/s).
    Dps1000 = 1,
    /// ±500 °/s, 65.5 LSB/(°/s).
    Dps500 = 2,
    /// ±250 °/s, 131 LSB/(°/s).
    Dps250 = 3,
    /// ±125 °/s, 262 LSB/(°/s).
    Dps125 = 4,
}

impl GyroRange {
    /// 16-bit LSB per °/s (the datasheet's nominal sensitivities, §3.1).
    pub fn lsb_per_dps(self) -> f32 {
        match self {
            GyroRange::Dps2000 => 16.4,
            GyroRange::Dps1000 => 32.8,
            GyroRange::Dps500 => 65.5,
            GyroRange::Dps250 => 131.0,
            GyroRange::Dps125 => 262.0,
        }
    }
}

/// Output data rate of both sensors (GYRO_ODR / ACCEL_ODR codes, §14.30–14.31).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Odr {
    /// 8 kHz.
    Hz8000 = 3,
    /// 4 kHz.
    Hz4000 = 4,
    /// 2 kHz.
    Hz2000 = 5,
    /// 1 kHz.
    Hz1000 = 6,
    /// 500 Hz.
    Hz500 = 15,
    /// 200 Hz.
    Hz200 = 7,
    /// 100 Hz.
    Hz100 = 8,
}

impl Odr {
    /// The rate, Hz.
    pub fn hz(self) -> u32 {
        match self {
            Odr::Hz8000 => 8000,
            Odr::Hz4000 => 4000,
            Odr::Hz2000 => 2000,
            Odr::Hz1000 => 1000,
            Odr::Hz500 => 500,
            Odr::Hz200 => 200,
            Odr::Hz100 => 100,
        }
    }

    /// The sample period in 1 µs time-stamp ticks.
    pub fn period_us(self) -> u16 {
        (1_000_000 / self.hz()) as u16
    }
}

/// Anti-alias filter 3 dB bandwidth (§5.3 table: AAF_DELT, AAF_DELTSQR, AAF_BITSHIFT).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum AntiAlias {
    /// 258 Hz: DELT 6, DELTSQR 36, BITSHIFT 10.
    Hz258,
    /// 536 Hz: DELT 12, DELTSQR 144, BITSHIFT 8.
    Hz536,
    /// 997 Hz: DELT 21, DELTSQR 440, BITSHIFT 6.
    Hz997,
    /// 1962 Hz: DELT 37, DELTSQR 1376, BITSHIFT 4.
    Hz1962,
    /// Filter bypassed (AAF_DIS).
    Off,
}

impl AntiAlias {
    /// (DELT, DELTSQR, BITSHIFT) of the datasheet's table; `None` when off.
    pub fn coefficients(self) -> Option<(u8, u16, u8)> {
        match self {
            AntiAlias::Hz258 => Some((6, 36, 10)),
            AntiAlias::Hz536 => Some((12, 144, 8)),
            AntiAlias::Hz997 => Some((21, 440, 6)),
            AntiAlias::Hz1962 => Some((37, 1376, 4)),
            AntiAlias::Off => None,
        }
    }
}

/// Which FIFO packet (§6.1).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum FifoFormat {
    /// Packet 3: 16 bytes, 16-bit data, 8-bit temperature (0.48 °C).
    Packet3,
    /// Packet 4: 20 bytes, 18-bit accel and 19-bit gyro at ±16 g / ±2000 °/s, 16-bit temperature.
    Packet4HighRes,
}

impl FifoFormat {
    /// Bytes per packet.
    pub const fn packet_len(self) -> usize {
        match self {
            FifoFormat::Packet3 => PACKET3_LEN,
            FifoFormat::Packet4HighRes => PACKET4_LEN,
        }
    }
}

/// The driver's configuration.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Config {
    /// Output data rate (both sensors).
    pub odr: Odr,
    /// Accelerometer range (packet 4 runs at ±16 g whatever this says: must be `G16` there).
    pub accel_range: AccelRange,
    /// Gyro range (packet 4: must be `Dps2000`).
    pub gyro_range: GyroRange,
    /// Accelerometer anti-alias filter.
    pub accel_aaf: AntiAlias,
    /// Gyro anti-alias filter.
    pub gyro_aaf: AntiAlias,
    /// FIFO packet.
    pub fifo: FifoFormat,
    /// Watermark, packets (1..=the FIFO's capacity): INT1 rises when the FIFO holds this many.
    pub watermark_packets: u16,
    /// Calibration output unit per accelerometer LSB (of the format's resolution: 16-bit for packet
    /// 3, 18-bit for packet 4): 1 for counts.
    pub accel_out_per_lsb: f32,
    /// Added to the scaled accelerometer output (0 for counts).
    pub accel_out_offset: f32,
}

impl Config {
    /// 1 kHz, ±16 g, ±2000 °/s, 258 Hz anti-alias filters, packet 3, watermark 1 packet, counts.
    pub const DEFAULT: Config = Config {
        odr: Odr::Hz1000,
        accel_range: AccelRange::G16,
        gyro_range: GyroRange::Dps2000,
        accel_aaf: AntiAlias::Hz258,
        gyro_aaf: AntiAlias::Hz258,
        fifo: FifoFormat::Packet3,
        watermark_packets: 1,
        accel_out_per_lsb: 1.0,
        accel_out_offset: 0.0,
    };

    /// Packets the FIFO holds.
    pub const fn capacity_packets(&self) -> u16 {
        (FIFO_BYTES / self.fifo.packet_len()) as u16
    }

    /// Checks the combination: watermark within the FIFO, packet 4 only at ±16 g / ±2000 °/s.
    pub fn check(&self) -> Result<(), ConfigError> {
        if self.watermark_packets == 0 || self.watermark_packets > self.capacity_packets() {
            return Err(ConfigError::Watermark);
        }
        let hires = self.fifo == FifoFormat::Packet4HighRes;
        if hires && (self.accel_range != AccelRange::G16 || self.gyro_range != GyroRange::Dps2000) {
            return Err(ConfigError::HighResRange);
        }
        // The largest output, at the largest code (2¹⁷ LSB in packet 4's 18 bits), must be finite:
        // the pipeline takes a sample's finiteness from its INVALID flag (`ImuSample`).
        let largest = self.accel_out_per_lsb.abs() * 131_072.0 + self.accel_out_offset.abs();
        if !largest.is_finite() {
            return Err(ConfigError::Unit);
        }
        Ok(())
    }

    /// Code-to-unit scaling of decoded packets.
    pub fn scale(&self) -> Scale {
        let rad_per_deg = core::f32::consts::PI / 180.0;
        match self.fifo {
            FifoFormat::Packet3 => Scale {
                accel_out_per_code: self.accel_out_per_lsb,
                accel_out_offset: self.accel_out_offset,
                gyro_rad_s_per_code: rad_per_deg / self.gyro_range.lsb_per_dps(),
            },
            // 20-bit codes: accel bits 1:0 and gyro bit 0 are zero (18 and 19 bits of data).
            FifoFormat::Packet4HighRes => Scale {
                accel_out_per_code: self.accel_out_per_lsb * 0.25,
                accel_out_offset: self.accel_out_offset,
                gyro_rad_s_per_code: rad_per_deg / (131.0 * 2.0),
            },
        }
    }
}

/// Why a configuration was refused.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum ConfigError {
    /// The watermark is 0 or above the FIFO's capacity in packets.
    Watermark,
    /// Packet 4 needs ±16 g and ±2000 °/s (the part ignores the range registers there).
    HighResRange,
    /// The output unit factor or offset is not finite, or the largest code's output would not be.
    Unit,
}

/// Driver errors, generic over the SPI error.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Error<E> {
    /// The SPI transfer failed.
    Spi(E),
    /// WHO_AM_I read this, not 0x47: another part, or nothing on the bus (0x00 or 0xFF).
    WrongDevice(u8),
    /// The configuration was refused.
    Config(ConfigError),
    /// A FIFO packet's header was not the configured packet's: the FIFO was flushed (the next
    /// sample is flagged as following lost data).
    FifoCorrupt {
        /// The header byte read.
        header: u8,
    },
    /// During the self-test, INT_STATUS did not flag DATA_RDY for 200 samples within twice their
    /// time: the sensor under test is not sampling.
    NoDataReady,
}

impl<E: core::fmt::Debug> core::fmt::Display for Error<E> {
    fn fmt(&self, f: &mut core::fmt::Formatter<'_>) -> core::fmt::Result {
        match self {
            Error::Spi(e) => write!(f, "ICM-42688-P: SPI transfer failed ({e:?}); check wiring and chip select"),
            // Only bit 0 wrong: the STM32F4's "wrong last bit in every received byte" of SPI pins
            // left at low speed (stm32f4xx-hal 0.23 src/spi.rs:302-303), not another part.
            Error::WrongDevice(id) if id ^ WHO_AM_I_VALUE == 1 => write!(
                f,
                "ICM-42688-P: WHO_AM_I reads {id:#04x}, expected 0x47: bit 0 wrong, as when the SPI pins are at low speed"
            ),
            Error::WrongDevice(id) => write!(
                f,
                "ICM-42688-P: WHO_AM_I reads {id:#04x}, expected 0x47; check the part and the SPI mode (0 or 3)"
            ),
            Error::Config(c) => write!(f, "ICM-42688-P: configuration refused: {c:?}"),
            Error::FifoCorrupt { header } => write!(
                f,
                "ICM-42688-P: FIFO out of step (header {header:#04x}); flushed, samples were lost"
            ),
            Error::NoDataReady => write!(
                f,
                "ICM-42688-P: no new sample during the self-test; the sensor under test is not sampling"
            ),
        }
    }
}

/// One step of a register sequence. A step names its register with its bank ([`Register`]): the
/// driver writes REG_BANK_SEL (§14.51) before a step whose bank differs from the one the list
/// selected last, and before the first register step of a list, whose bank it does not assume
/// (a list stands alone: it may follow a reset, another list or a bank-1 read).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Step {
    /// Write `value` to register `reg`.
    Write(Register, u8),
    /// Read register `reg`, clear the bits of `mask`, set those of `value`, write it back (for a
    /// register whose other bits the driver leaves as they are).
    Update {
        /// The register.
        reg: Register,
        /// The bits replaced.
        mask: u8,
        /// Their new value (within `mask`).
        value: u8,
    },
    /// Wait this many microseconds.
    WaitUs(u32),
}

impl Step {
    /// The register the step reaches, if any.
    pub const fn register(&self) -> Option<Register> {
        match *self {
            Step::Write(reg, _) | Step::Update { reg, .. } => Some(reg),
            Step::WaitUs(_) => None,
        }
    }
}

/// After power-on, 1 ms before the first access: Betaflight's `icm426xxSpiDetect`
/// (`accgyro_spi_icm426xx.c` line 262, `delay(1); // power-on time`, commit 301d01abc4).
pub const POWER_UP_STEPS: [Step; 1] = [Step::WaitUs(1000)];

/// WHO_AM_I reads at most before the part is refused: the first and 20 retries, 1 ms apart, as
/// Betaflight's `icm426xxSpiDetect` (lines 268-301: `attemptsRemaining = 20`, `delay(1)` before
/// each read, `while (attemptsRemaining--)`, i.e. 21 reads). A part still starting may answer
/// wrongly at first.
pub const IDENTIFY_READS: u32 = 21;

/// Wait before each WHO_AM_I retry, µs.
pub const IDENTIFY_RETRY_US: u32 = 1000;

/// Soft reset: DEVICE_CONFIG.SOFT_RESET_CONFIG, then 1 ms before any access (§14.1).
pub const RESET_STEPS: [Step; 2] = [
    Step::Write(DEVICE_CONFIG.reg(), SOFT_RESET),
    Step::WaitUs(1000),
];

/// Steps in [`configure_steps`].
pub const CONFIGURE_STEPS: usize = 26;

/// INT_CONFIG1 for `odr` (DS-000347 §14.43): INT_ASYNC_RESET (bit 4) cleared "for proper INT1
/// and INT2 pin operation"; at 4 kHz and above INT_TPULSE_DURATION (bit 6) = 1, the 8 µs pulse,
/// and INT_TDEASSERT_DISABLE (bit 5) = 1, no minimum de-assert time — both "required for
/// ODR ≥ 4 kHz" (the 100 µs defaults are for ODR < 4 kHz only), as Betaflight's
/// `accgyro_spi_icm426xx.c` writes them (`ICM426XX_INT_TPULSE_DURATION_8 |
/// ICM426XX_INT_TDEASSERT_DISABLED`, INT_ASYNC_RESET cleared).
pub const fn int_config1(odr: Odr) -> u8 {
    match odr {
        Odr::Hz8000 | Odr::Hz4000 => INT_TPULSE_DURATION_8US | INT_TDEASSERT_DISABLE,
        _ => 0,
    }
}

/// The register writes that configure the part for `cfg` (checked before), in order: sensors off,
/// interface, AFSR off, anti-alias filters (banks 1 and 2), ranges and rates, time stamps and
/// FSYNC off, FIFO, INT1, FIFO
/// flushed, sensors on in low-noise mode (then 200 µs without writes, §14.29).
pub fn configure_steps(cfg: &Config) -> [Step; CONFIGURE_STEPS] {
    let aaf = |a: AntiAlias| a.coefficients().unwrap_or((0, 0, 0));
    let (gd, gsq, gsh) = aaf(cfg.gyro_aaf);
    let (ad, asq, ash) = aaf(cfg.accel_aaf);
    let gyro_off = cfg.gyro_aaf == AntiAlias::Off;
    let accel_off = cfg.accel_aaf == AntiAlias::Off;
    let hires = if cfg.fifo == FifoFormat::Packet4HighRes {
        FIFO_HIRES_EN
    } else {
        0
    };
    let wm = cfg.watermark_packets;
    [
        Step::Write(PWR_MGMT0.reg(), 0),
        Step::Write(
            INTF_CONFIG0.reg(),
            FIFO_COUNT_REC | FIFO_COUNT_ENDIAN | SENSOR_DATA_ENDIAN | UI_SIFS_DISABLE_I2C,
        ),
        // The adaptive full-scale switch off: it holds the gyro output for 1–2 ms whenever the rate
        // crosses about ±100 °/s, which a rate table does on every turn. Read-modify-write as
        // Betaflight does it (`accgyro_spi_icm426xx.c` 416-420, see `regs::AFSR_DISABLE`).
        Step::Update {
            reg: INTF_CONFIG1.reg(),
            mask: AFSR_MASK,
            value: AFSR_DISABLE,
        },
        // Reset value 0xA0 with GYRO_AAF_DIS (bit 1) as configured, the notch filter left on.
        Step::Write(GYRO_CONFIG_STATIC2.reg(), 0xA0 | ((gyro_off as u8) << 1)),
        Step::Write(GYRO_CONFIG_STATIC3.reg(), gd),
        Step::Write(GYRO_CONFIG_STATIC4.reg(), (gsq & 0xFF) as u8),
        Step::Write(GYRO_CONFIG_STATIC5.reg(), (gsh << 4) | (gsq >> 8) as u8),
        Step::Write(ACCEL_CONFIG_STATIC2.reg(), (ad << 1) | accel_off as u8),
        Step::Write(ACCEL_CONFIG_STATIC3.reg(), (asq & 0xFF) as u8),
        Step::Write(ACCEL_CONFIG_STATIC4.reg(), (ash << 4) | (asq >> 8) as u8),
        Step::Write(
            GYRO_CONFIG0.reg(),
            ((cfg.gyro_range as u8) << 5) | cfg.odr as u8,
        ),
        Step::Write(
            ACCEL_CONFIG0.reg(),
            ((cfg.accel_range as u8) << 5) | cfg.odr as u8,
        ),
        // Time stamps as the decoder reads them, every field set by name rather than left at its
        // reset value: absolute (not deltas), 1 µs resolution (`Odr::period_us` is in 1 µs
        // ticks), FSYNC time stamps off. FSYNC itself off (FSYNC_UI_SEL 000, not the reset value
        // 001). TDK's reference driver does both at start-up (Icm426xxDriver_HL.c,
        // inv_icm426xx_init, lines 1913-1923: "Deactivate FSYNC by default", then the time-stamp
        // resolution set explicitly; it picks 16 µs, this driver 1 µs).
        Step::Update {
            reg: TMST_CONFIG.reg(),
            mask: TMST_FIELDS,
            value: TMST_EN,
        },
        Step::Update {
            reg: FSYNC_CONFIG.reg(),
            mask: FSYNC_UI_SEL_MASK,
            value: 0,
        },
        Step::Write(FIFO_CONFIG.reg(), 0), // bypass while the FIFO is set up
        Step::Write(FIFO_CONFIG1.reg(), FIFO_WM_GT_TH | hires | FIFO_PACKET3_EN),
        Step::Write(FIFO_CONFIG2.reg(), (wm & 0xFF) as u8),
        Step::Write(FIFO_CONFIG3.reg(), (wm >> 8) as u8),
        // INT1 latched until INT_STATUS is read, push-pull, active high.
        Step::Write(INT_CONFIG.reg(), 0b111),
        Step::Write(INT_CONFIG1.reg(), int_config1(cfg.odr)),
        Step::Write(INT_SOURCE0.reg(), INT1_FIFO_THS_FULL),
        Step::Write(SELF_TEST_CONFIG.reg(), 0),
        Step::Write(FIFO_CONFIG.reg(), FIFO_MODE_STOP_ON_FULL),
        Step::Write(SIGNAL_PATH_RESET.reg(), FIFO_FLUSH),
        Step::Write(PWR_MGMT0.reg(), PWR_LOW_NOISE),
        Step::WaitUs(200),
    ]
}

/// Packets read per FIFO transfer at most (a DMA-sized buffer: 16 × 20 bytes).
pub const BATCH_PACKETS: usize = 16;

/// The driver's state and decisions, shared by the blocking and async forms.
pub struct Core {
    cfg: Config,
    scale: Scale,
    period_us: u16,
    /// The previous sample's time stamp, when there is one since the last flush.
    last_timestamp: u16,
    primed: bool,
    /// Packets still to read before the gap of an overflow (stop-on-full keeps the oldest);
    /// negative: no overflow pending.
    gap_after: i32,
    /// The next decoded sample follows lost data.
    lost_pending: bool,
}

/// A FIFO transfer's bytes (the drivers' DMA-sized buffer).
pub type FifoBuffer = [u8; BATCH_PACKETS * PACKET4_LEN];

impl Core {
    /// State for `cfg` (checked).
    pub fn new(cfg: Config) -> Result<Core, ConfigError> {
        cfg.check()?;
        Ok(Core {
            cfg,
            scale: cfg.scale(),
            period_us: cfg.odr.period_us(),
            last_timestamp: 0,
            primed: false,
            gap_after: -1,
            lost_pending: false,
        })
    }

    /// The configuration in force.
    pub fn config(&self) -> &Config {
        &self.cfg
    }

    /// After INT_STATUS, FIFO_COUNTH, FIFO_COUNTL (one burst from INT_STATUS): how many FIFO bytes
    /// to read now for at most `room` samples, and whether more stay behind. Notes an overflow.
    pub fn plan_read(&mut self, status: [u8; 3], room: usize) -> (usize, bool) {
        let count = u16::from_be_bytes([status[1], status[2]]);
        if status[0] & INT_FIFO_FULL != 0 {
            // Stop-on-full: the `count` packets present precede the gap.
            self.gap_after = i32::from(count);
        }
        let n = usize::from(count).min(room).min(BATCH_PACKETS);
        (n * self.cfg.fifo.packet_len(), usize::from(count) > n)
    }

    /// Decodes whole packets of FIFO `bytes` into `out` (as many as both hold). On a header that is
    /// not the configured packet's, returns the header: the caller flushes the FIFO.
    pub fn decode(&mut self, bytes: &[u8], out: &mut [ImuSample]) -> Result<usize, u8> {
        match self.cfg.fifo {
            FifoFormat::Packet3 => self.decode_as::<PACKET3_LEN>(bytes, out, HEADER_PACKET3),
            FifoFormat::Packet4HighRes => self.decode_as::<PACKET4_LEN>(bytes, out, HEADER_PACKET4),
        }
    }

    #[inline(always)]
    fn decode_as<const N: usize>(
        &mut self,
        bytes: &[u8],
        out: &mut [ImuSample],
        want: u8,
    ) -> Result<usize, u8> {
        let mut n = 0;
        for (p, slot) in bytes.chunks_exact(N).zip(out.iter_mut()) {
            let Ok(p) = <&[u8; N]>::try_from(p) else {
                break;
            };
            let header = p[0];
            // Within the counted packets even the empty marker (HEADER_MSG) means out of step:
            // the count was latched before the read, and the FIFO only grows meanwhile.
            if header & HEADER_CHECK_MASK != want {
                self.corrupted();
                return Err(header);
            }
            decode_packet(p, &self.scale, slot);
            n += 1;
        }
        self.mark_batch(&mut out[..n]);
        Ok(n)
    }

    /// The gap checks of a transfer: when its time stamps span exactly its length (to half a
    /// period: each lost sample would add a whole one) after the previous transfer, and no overflow
    /// or flush falls in it, nothing was lost — one check per transfer; otherwise each sample is
    /// checked.
    #[inline(always)]
    fn mark_batch(&mut self, samples: &mut [ImuSample]) {
        let Some(last) = samples.last() else {
            return;
        };
        let n = samples.len() as i32;
        let period = i32::from(self.period_us);
        let expected = n * period;
        let span = i32::from(last.timestamp.wrapping_sub(self.last_timestamp));
        let contiguous = self.primed
            && !self.lost_pending
            && (self.gap_after < 0 || self.gap_after >= n)
            && expected < 32_768
            && (span - expected).abs() <= period / 2;
        if contiguous {
            self.last_timestamp = last.timestamp;
            if self.gap_after >= 0 {
                self.gap_after -= n;
            }
            return;
        }
        for s in samples.iter_mut() {
            self.mark_gaps(s);
        }
    }

    #[inline(always)]
    fn mark_gaps(&mut self, s: &mut ImuSample) {
        let lost = lost_between(self.last_timestamp, s.timestamp, self.period_us);
        self.last_timestamp = s.timestamp;
        let overflow = self.gap_after == 0;
        self.gap_after -= (self.gap_after >= 0) as i32;
        if (lost > 0 && self.primed) | overflow | self.lost_pending {
            s.lost_before = if self.primed { lost } else { 0 };
            s.flags.0 |= ImuFlags::DATA_LOST;
            self.lost_pending = false;
        }
        self.primed = true;
    }

    /// The FIFO was flushed: what is in it now follows a gap of unknown length.
    pub fn corrupted(&mut self) {
        self.lost_pending = true;
        self.gap_after = -1;
        self.primed = false;
    }

    /// The configured rate, Hz.
    pub fn sample_rate_hz(&self) -> u32 {
        self.cfg.odr.hz()
    }
}

/// A packet of either length (the length picks the format).
#[inline(always)]
fn decode_packet<const N: usize>(p: &[u8; N], scale: &Scale, out: &mut ImuSample) {
    if let Ok(p3) = <&[u8; PACKET3_LEN]>::try_from(&p[..]) {
        fifo::decode_packet3(p3, scale, out);
    } else if let Ok(p4) = <&[u8; PACKET4_LEN]>::try_from(&p[..]) {
        fifo::decode_packet4(p4, scale, out);
    }
}

/// The check of WHO_AM_I.
pub fn check_identity<E>(who_am_i: u8) -> Result<(), Error<E>> {
    if who_am_i == WHO_AM_I_VALUE {
        Ok(())
    } else {
        Err(Error::WrongDevice(who_am_i))
    }
}
