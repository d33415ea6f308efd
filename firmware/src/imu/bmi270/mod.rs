//! Bosch BMI270 over embedded-hal 1.0 `SpiDevice`, behind the same [`ImuSource`] as the
//! ICM-42688-P and the LSM6DSO: the SpeedyBee F405 V3's IMU, and many of today's flight
//! controllers'.
//!
//! Register numbers and values from Bosch's datasheet (BST-BMI270-DS000, §5 "Register
//! description") and its Sensor API (`boschsensortec/BMI270_SensorAPI` at 41129fc, `bmi2_defs.h`);
//! the start follows `bmi2.c` and Betaflight's `src/main/drivers/accgyro/accgyro_spi_bmi270.c`
//! (at 1407821):
//!
//! 1. A dummy read of CHIP_ID: the part starts in I²C mode and switches to SPI on the first rising
//!    edge of CSB (`bmi2.c` lines 1904–1907, `bmi2_sec_init`; Betaflight's `bmi270EnableSPI`).
//! 2. Soft reset (CMD ← 0xB6), 2 ms, a dummy read again (`bmi2.c` 2089–2110, `bmi2_soft_reset`).
//! 3. CHIP_ID must read 0x24 (`BMI270_CHIP_ID`), else [`Error::WrongDevice`].
//! 4. Advanced power save off (PWR_CONF ← 0), 450 µs (`bmi2.c` 1984), INIT_CTRL ← 0, the
//!    configuration file — Bosch's 8 KiB microcode, [`CONFIG_FILE`] — burst-written to INIT_DATA
//!    from INIT_ADDR 0 (`bmi2.c` 5568–5640 `write_config_file`, 5684–5695 the address in words;
//!    Betaflight's `bmi270UploadConfig` writes it in one burst), INIT_CTRL ← 1.
//! 5. 20 ms (`BMI2_INTERNAL_STATUS_READ_DELAY_MS`, `bmi2_defs.h` 440), then INTERNAL_STATUS's
//!    message field (bits 3:0, `BMI2_CONFIG_LOAD_STATUS_MASK`) must be 0b0001 "init_ok"
//!    (`BMI2_CONFIG_LOAD_SUCCESS`, `bmi2.c` 2250–2258), else [`Error::ConfigLoad`] with it.
//! 6. The sensors as Betaflight configures them (lines "Configure the accelerometer" … "Enable
//!    the gyro"): ACC_CONF high-performance, normal filter, the rate; ACC_RANGE; GYR_CONF filter
//!    and noise performance, normal filter, the rate; GYR_RANGE ±2000 °/s with the `ois_range` bit
//!    set (Betaflight: "for some reason you have to enable the ois_range bit (bit 3) for 2000dps
//!    as well"); data ready on INT1 (INT_MAP_DATA ← 0x04), INT1 push-pull active high output
//!    (INT1_IO_CTRL ← 0x0A); PWR_CONF ← 0x02; PWR_CTRL ← 0x0E (accelerometer, gyro, temperature).
//!    Each is read back ([`Error::RegisterMismatch`]).
//!
//! SPI reads return one dummy byte before the data (`bmi2.c` 1980–1996; Betaflight "register
//! reads are 16bits with the first byte a dummy value"): every read here skips it.
//!
//! **Data path**: data ready, not the FIFO. Both sensors run at one rate (≤ 1.6 kHz, the
//! accelerometer's highest), so each data-ready gives one time-aligned pair; a drain reads STATUS
//! through TEMPERATURE_1 in one 33-byte burst ([`dma::FRAME_LEN`]: STATUS 0x03, the
//! accelerometer, the gyro, the 24-bit time stamp of 39.0625 µs, …, the 16-bit temperature at
//! 0x22, 1/512 K per LSB, 0 = 23 °C; 0x8000 invalid) — the frame the F405 V3 moves by DMA
//! ([`dma`]), decoded by the same [`dma::Decoder`]. A read without both DRDY bits yields nothing
//! (no sample is read twice); a time stamp more than 1.5 periods after the previous one flags the
//! sample `DATA_LOST` with the count (a data ready missed).
//!
//! **Register check** ([`Bmi270::check_next_register`]): PX4's `RegisterCheck` pattern
//! (`src/drivers/imu/bosch/bmi088/BMI088_Accelerometer.cpp`, `RegisterCheck`, one register per
//! call): the configured registers are read back one at a time; a mismatch (a brown-out resets
//! the part to its defaults, which the data path cannot see) is an error, after which the board
//! calls [`Bmi270::reinit`].
//!
//! Not implemented: the part's self-test (ACC_SELF_TEST / GYR_SELF_TEST_AXES).

pub mod dma;
pub mod regs;

use embedded_hal::spi::{Operation, SpiDevice};

use crate::imu::{Drained, ImuSample, ImuSource};
use dma::{Decoder, FRAME_LEN};
use regs::*;

/// Bosch's BMI270 configuration file (`bmi270_config_file[]` of `bmi270.c` in Bosch's
/// BMI270_SensorAPI v2.86.1, commit 41129fc), 8192 bytes, BSD-3-Clause: see
/// `LICENSE-BOSCH-BSD-3-Clause.txt` beside it. Uploaded unchanged at every start.
pub static CONFIG_FILE: &[u8; 8192] = include_bytes!("bmi270_config_file.bin");

/// Output data rate of both sensors (ACC_CONF / GYR_CONF odr codes: 100·2^(code − 8) Hz).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Odr {
    /// 800 Hz (0x0B).
    Hz800,
    /// 1600 Hz (0x0C), the accelerometer's highest.
    Hz1600,
}

impl Odr {
    /// The register code.
    pub const fn code(self) -> u8 {
        match self {
            Odr::Hz800 => 0x0B,
            Odr::Hz1600 => 0x0C,
        }
    }

    /// Hz.
    pub const fn hz(self) -> u32 {
        100 << (self.code() - 8)
    }

    /// One period in SENSORTIME ticks (39.0625 µs = 1/25 600 s).
    pub const fn ticks(self) -> u16 {
        (25_600 / self.hz()) as u16
    }
}

/// Accelerometer range (ACC_RANGE codes).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum AccelRange {
    /// ±4 g, 8192 LSB/g (code 0x01).
    G4,
    /// ±16 g, 2048 LSB/g (code 0x03, Betaflight's).
    G16,
}

impl AccelRange {
    /// The register code.
    pub const fn code(self) -> u8 {
        match self {
            AccelRange::G4 => 0x01,
            AccelRange::G16 => 0x03,
        }
    }

    /// Counts per g (32768 / range).
    pub const fn lsb_per_g(self) -> u32 {
        match self {
            AccelRange::G4 => 8192,
            AccelRange::G16 => 2048,
        }
    }
}

/// The driver's configuration.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Config {
    /// Both sensors' rate.
    pub odr: Odr,
    /// Accelerometer range (the gyro is at ±2000 °/s, 16.4 LSB per °/s).
    pub accel_range: AccelRange,
}

impl Config {
    /// 1.6 kHz, ±4 g.
    pub const DEFAULT: Config = Config {
        odr: Odr::Hz1600,
        accel_range: AccelRange::G4,
    };

    /// The registers the start writes after the configuration upload, in order, with their
    /// values (what the register check reads back).
    pub const fn registers(&self) -> [(Reg, u8); 8] {
        [
            // acc_filter_perf (7) | acc_bwp normal (2 << 4) | odr.
            (ACC_CONF, 0x80 | (0x02 << 4) | self.odr.code()),
            (ACC_RANGE, self.accel_range.code()),
            // gyr_filter_perf (7) | gyr_noise_perf (6) | gyr_bwp normal (2 << 4) | odr.
            (GYR_CONF, 0x80 | 0x40 | (0x02 << 4) | self.odr.code()),
            // ±2000 °/s (0) with ois_range (bit 3), as Betaflight's BMI270_VAL_GYRO_RANGE_2000DPS.
            (GYR_RANGE, 0x08),
            (INT_MAP_DATA, INT_MAP_DRDY_INT1),
            (INT1_IO_CTRL, INT1_OUTPUT_PUSH_PULL_HIGH),
            (PWR_CONF, PWR_CONF_PERFORMANCE),
            (PWR_CTRL, PWR_CTRL_ACC_GYR_TEMP),
        ]
    }
}

/// Why the driver failed.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Error<E> {
    /// The SPI transfer failed.
    Spi(E),
    /// CHIP_ID read this, not 0x24.
    WrongDevice(u8),
    /// INTERNAL_STATUS's message after the configuration upload was not "init_ok" (this value).
    ConfigLoad(u8),
    /// A configured register reads another value: the part lost its configuration.
    RegisterMismatch {
        /// The register.
        reg: Reg,
        /// Written.
        expected: u8,
        /// Read back.
        read: u8,
    },
}

/// BMI270 on a blocking SPI device (mode 0 or 3, up to 10 MHz).
pub struct Bmi270<SPI> {
    spi: SPI,
    cfg: Config,
    /// The frame's decode and the gap check.
    decoder: Decoder,
    /// The next register the check reads.
    check_index: usize,
    /// CHIP_ID's last value read.
    chip_id: u8,
}

impl<SPI: SpiDevice> Bmi270<SPI> {
    /// Starts the part (module documentation, steps 1–6).
    pub fn new(spi: SPI, cfg: Config) -> Result<Self, Error<SPI::Error>> {
        let mut imu = Bmi270 {
            spi,
            cfg,
            decoder: Decoder::new(&cfg),
            check_index: 0,
            chip_id: 0,
        };
        imu.reinit()?;
        Ok(imu)
    }

    /// The SPI device (the tests' model).
    pub fn device_mut(&mut self) -> &mut SPI {
        &mut self.spi
    }

    /// The SPI device back (a board that reads the part by DMA after starting it).
    pub fn release(self) -> SPI {
        self.spi
    }

    /// CHIP_ID's last value read (for the device's health report).
    pub fn chip_id(&self) -> u8 {
        self.chip_id
    }

    /// The whole start again (after a register check found the configuration lost).
    pub fn reinit(&mut self) -> Result<(), Error<SPI::Error>> {
        self.decoder = Decoder::new(&self.cfg);
        self.check_index = 0;
        self.read_reg(CHIP_ID)?; // to SPI mode
        self.write(CMD, CMD_SOFT_RESET)?;
        self.delay_us(2_000)?;
        self.read_reg(CHIP_ID)?; // to SPI mode again after the reset
        self.chip_id = self.read_reg(CHIP_ID)?;
        if self.chip_id != CHIP_ID_VALUE {
            return Err(Error::WrongDevice(self.chip_id));
        }
        self.write(PWR_CONF, 0x00)?;
        self.delay_us(450)?;
        self.write(INIT_CTRL, 0x00)?;
        self.write(INIT_ADDR_0, 0x00)?;
        self.write(INIT_ADDR_1, 0x00)?;
        self.spi
            .transaction(&mut [
                Operation::Write(&[INIT_DATA.addr()]),
                Operation::Write(CONFIG_FILE),
            ])
            .map_err(Error::Spi)?;
        self.write(INIT_CTRL, 0x01)?;
        self.delay_us(20_000)?;
        let status = self.read_reg(INTERNAL_STATUS)? & INTERNAL_STATUS_MESSAGE;
        if status != INTERNAL_STATUS_INIT_OK {
            return Err(Error::ConfigLoad(status));
        }
        for (reg, v) in self.cfg.registers() {
            self.write(reg, v)?;
            // 1 ms after each write, as Betaflight's `bmi270RegisterWrite(dev, reg, value, 1)`.
            self.delay_us(1_000)?;
        }
        for (reg, expected) in self.cfg.registers() {
            let read = self.read_reg(reg)?;
            if read != expected {
                return Err(Error::RegisterMismatch {
                    reg,
                    expected,
                    read,
                });
            }
        }
        Ok(())
    }

    /// Reads back the next configured register (one per call, round robin): a board calls it
    /// a few times a second and [`Self::reinit`]s on an error.
    pub fn check_next_register(&mut self) -> Result<(), Error<SPI::Error>> {
        let regs = self.cfg.registers();
        let (reg, expected) = regs[self.check_index % regs.len()];
        self.check_index = (self.check_index + 1) % regs.len();
        let read = self.read_reg(reg)?;
        if read != expected {
            return Err(Error::RegisterMismatch {
                reg,
                expected,
                read,
            });
        }
        Ok(())
    }

    fn delay_us(&mut self, us: u32) -> Result<(), Error<SPI::Error>> {
        self.spi
            .transaction(&mut [Operation::DelayNs(us * 1000)])
            .map_err(Error::Spi)
    }

    fn write(&mut self, reg: Reg, v: u8) -> Result<(), Error<SPI::Error>> {
        self.spi.write(&[reg.addr(), v]).map_err(Error::Spi)
    }

    /// `buf.len()` registers from `reg`, the dummy byte skipped.
    fn read(&mut self, reg: Reg, buf: &mut [u8]) -> Result<(), Error<SPI::Error>> {
        let mut dummy = [0u8; 1];
        self.spi
            .transaction(&mut [
                Operation::Write(&[reg.addr() | READ]),
                Operation::Read(&mut dummy),
                Operation::Read(buf),
            ])
            .map_err(Error::Spi)
    }

    fn read_reg(&mut self, reg: Reg) -> Result<u8, Error<SPI::Error>> {
        let mut b = [0u8; 1];
        self.read(reg, &mut b)?;
        Ok(b[0])
    }

    /// One sample if both sensors have new data: the frame in one burst, decoded.
    fn read_sample(&mut self) -> Result<Option<ImuSample>, Error<SPI::Error>> {
        let mut frame = [0u8; FRAME_LEN];
        self.read(STATUS, &mut frame)?;
        Ok(self.decoder.decode(&frame))
    }
}

impl<SPI: SpiDevice> ImuSource for Bmi270<SPI> {
    type Error = Error<SPI::Error>;

    /// The newest sample, if one came since the last drain (data ready: the part keeps one).
    fn drain(&mut self, out: &mut [ImuSample]) -> Result<Drained, Self::Error> {
        if out.is_empty() {
            return Ok(Drained {
                samples: 0,
                more: false,
            });
        }
        let samples = match self.read_sample()? {
            Some(s) => {
                out[0] = s;
                1
            }
            None => 0,
        };
        Ok(Drained {
            samples,
            more: false,
        })
    }

    fn sample_rate_hz(&self) -> u32 {
        self.cfg.odr.hz()
    }
}
