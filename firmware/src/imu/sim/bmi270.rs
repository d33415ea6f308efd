//! Register-level model of the BMI270 (BST-BMI270-DS000; register numbers from
//! `imu::bmi270::regs`): I²C mode until the first transaction ends (its read data are not the
//! part's), the dummy byte before every read's data, CHIP_ID 0x24 (settable), soft reset, the
//! reset values of the configuration registers, the configuration upload (INIT_ADDR in words,
//! INIT_DATA bursts into an 8 KiB program memory, INIT_CTRL) and INTERNAL_STATUS: "init_ok" 10 ms
//! after INIT_CTRL ← 1 only when the memory holds Bosch's file exactly and advanced power save was
//! off 450 µs before the upload, "init_err" otherwise; sampling only once initialised and both
//! sensors enabled, at ACC_CONF's rate (100·2^(odr − 8) Hz), scaled by the ranges, with DRDY bits
//! cleared by a data read, SENSORTIME (39.0625 µs) and the temperature (1/512 K, 0 at 23 °C).
//! Faults: [`Bmi270Model::brown_out`] (every register back to reset, I²C mode, no program),
//! `fail_spi`, `corrupt_upload_byte`.

use embedded_hal::spi::{ErrorType, Operation, SpiDevice};

use super::{quantize, BusFault, Generator};
use crate::imu::bmi270::regs::*;
use crate::imu::bmi270::CONFIG_FILE;

/// The model.
pub struct Bmi270Model<G> {
    gen: G,
    regs: [u8; 128],
    program: [u8; 8192],
    spi_mode: bool,
    /// INIT_CTRL ← 1 at this time (ns): the status follows 10 ms later.
    init_at_ns: Option<u64>,
    /// Advanced power save was switched off at this time (ns).
    aps_off_at_ns: Option<u64>,
    /// The upload started (first INIT_DATA byte) this long after power save went off (ns).
    upload_after_aps_ns: Option<u64>,
    time_ns: u64,
    next_sample_ns: u64,
    /// CHIP_ID's value.
    pub chip_id: u8,
    /// Every transaction fails while set.
    pub fail_spi: bool,
    /// Flip this byte of the upload as it arrives (a damaged transfer).
    pub corrupt_upload_byte: Option<usize>,
    /// Samples produced.
    pub samples: u32,
    /// Samples overwritten before any read (a data ready missed).
    pub overwritten: u32,
    /// Register accesses while still in I²C mode (a missing dummy read).
    pub i2c_mode_accesses: u32,
    /// Resets (soft or brown-out) so far.
    resets: u32,
}

/// The driver's register addresses as `u8` constants, for the model's `match`es on the address
/// byte it receives (a pattern must be a constant, not `Reg::X as u8`).
mod addr {
    use crate::imu::bmi270::regs::Reg;
    pub const CHIP_ID: u8 = Reg::CHIP_ID as u8;
    pub const INTERNAL_STATUS: u8 = Reg::INTERNAL_STATUS as u8;
    pub const ACC_X: u8 = Reg::ACC_X as u8;
    pub const GYR_X: u8 = Reg::GYR_X as u8;
    pub const CMD: u8 = Reg::CMD as u8;
    pub const INIT_DATA: u8 = Reg::INIT_DATA as u8;
    pub const INIT_CTRL: u8 = Reg::INIT_CTRL as u8;
    pub const PWR_CONF: u8 = Reg::PWR_CONF as u8;
    pub const TEMPERATURE_0: u8 = Reg::TEMPERATURE_0 as u8;
}

impl<G: Generator> Bmi270Model<G> {
    /// A part just powered on.
    pub fn new(gen: G) -> Self {
        let mut m = Bmi270Model {
            gen,
            regs: [0; 128],
            program: [0; 8192],
            spi_mode: false,
            init_at_ns: None,
            aps_off_at_ns: None,
            upload_after_aps_ns: None,
            time_ns: 0,
            next_sample_ns: 0,
            chip_id: CHIP_ID_VALUE,
            fail_spi: false,
            corrupt_upload_byte: None,
            samples: 0,
            overwritten: 0,
            i2c_mode_accesses: 0,
            resets: 0,
        };
        m.reset();
        m
    }

    /// Power lost and back (a brown-out): the configuration and the program are gone.
    pub fn brown_out(&mut self) {
        self.reset();
    }

    fn reset(&mut self) {
        self.resets += 1;
        self.regs = [0; 128];
        // Reset values (datasheet §5.2): ACC_CONF 0xA8, ACC_RANGE 0x02, GYR_CONF 0xA9,
        // PWR_CONF 0x03.
        self.regs[ACC_CONF as usize] = 0xA8;
        self.regs[ACC_RANGE as usize] = 0x02;
        self.regs[GYR_CONF as usize] = 0xA9;
        self.regs[PWR_CONF as usize] = 0x03;
        self.program = [0; 8192];
        self.spi_mode = false;
        self.init_at_ns = None;
        self.aps_off_at_ns = None;
        self.upload_after_aps_ns = None;
        self.next_sample_ns = self.time_ns;
    }

    /// A register's value.
    pub fn register(&self, reg: impl Into<u8>) -> u8 {
        self.regs[reg.into() as usize & 0x7F]
    }

    /// The part holds a running program (the upload succeeded and its status is out).
    pub fn initialised(&self) -> bool {
        self.internal_status() == INTERNAL_STATUS_INIT_OK
    }

    fn internal_status(&self) -> u8 {
        match self.init_at_ns {
            Some(t) if self.time_ns >= t + 10_000_000 => {
                let aps_ok = self.upload_after_aps_ns.is_some_and(|d| d >= 450_000);
                if aps_ok && self.program == *CONFIG_FILE {
                    INTERNAL_STATUS_INIT_OK
                } else {
                    INTERNAL_STATUS_INIT_ERR
                }
            }
            _ => 0,
        }
    }

    /// INT1: data ready mapped and new data waiting.
    pub fn int1(&self) -> bool {
        self.regs[INT_MAP_DATA as usize] & INT_MAP_DRDY_INT1 != 0
            && self.regs[STATUS as usize] & STATUS_DRDY_ACC != 0
    }

    fn period_ns(&self) -> Option<u64> {
        let on = self.regs[PWR_CTRL as usize] & 0x06 == 0x06;
        let code = self.regs[ACC_CONF as usize] & 0x0F;
        if !on || !self.initialised() || !(8..=12).contains(&code) {
            return None;
        }
        Some(10_000_000 >> (code - 8))
    }

    /// Lets `ns` of the part's time pass.
    pub fn advance_ns(&mut self, ns: u64) {
        let end = self.time_ns + ns;
        loop {
            let Some(p) = self.period_ns() else {
                self.next_sample_ns = self.next_sample_ns.max(self.time_ns);
                break;
            };
            if self.next_sample_ns < self.time_ns {
                self.next_sample_ns = self.time_ns + p;
            }
            if self.next_sample_ns > end {
                break;
            }
            self.time_ns = self.next_sample_ns;
            self.sample();
            self.next_sample_ns += p;
        }
        self.time_ns = end;
    }

    /// Time until the next sample, ns.
    pub fn until_next_sample_ns(&self) -> u64 {
        self.next_sample_ns.saturating_sub(self.time_ns)
    }

    fn sample(&mut self) {
        let t = self.gen.next();
        self.samples += 1;
        let lsb_per_g = 32768.0 / f64::from(2u32 << (self.regs[ACC_RANGE as usize] & 3));
        // ±2000 °/s >> gyr_range (ois_range does not change the UI scale).
        let lsb_per_dps =
            32768.0 / (2000.0 / f64::from(1u32 << (self.regs[GYR_RANGE as usize] & 7)));
        let a = t.accel_g.map(|g| quantize(g * lsb_per_g, 32767) as i16);
        let w = t.gyro_dps.map(|d| quantize(d * lsb_per_dps, 32767) as i16);
        if self.regs[STATUS as usize] & STATUS_DRDY_ACC != 0 {
            self.overwritten += 1;
        }
        for i in 0..3 {
            let (ai, gi) = (ACC_X as usize + 2 * i, GYR_X as usize + 2 * i);
            self.regs[ai..ai + 2].copy_from_slice(&a[i].to_le_bytes());
            self.regs[gi..gi + 2].copy_from_slice(&w[i].to_le_bytes());
        }
        let ticks = (self.time_ns * 16 / 625_000) as u32; // 39.0625 µs = 625 000 / 16 ns
        self.regs[SENSORTIME_0 as usize..=SENSORTIME_2 as usize]
            .copy_from_slice(&ticks.to_le_bytes()[..3]);
        let temp = quantize((t.temp_c - 23.0) * 512.0, 32767) as i16;
        self.regs[TEMPERATURE_0 as usize..TEMPERATURE_0 as usize + 2]
            .copy_from_slice(&temp.to_le_bytes());
        self.regs[STATUS as usize] |= STATUS_DRDY_ACC | STATUS_DRDY_GYR;
    }

    fn read_register(&mut self, reg: u8) -> u8 {
        match reg {
            addr::CHIP_ID => self.chip_id,
            addr::INTERNAL_STATUS => self.internal_status(),
            r => {
                // A read of the accelerometer's (gyro's) last byte clears its DRDY bit.
                if r == addr::ACC_X + 5 {
                    self.regs[STATUS as usize] &= !STATUS_DRDY_ACC;
                } else if r == addr::GYR_X + 5 {
                    self.regs[STATUS as usize] &= !STATUS_DRDY_GYR;
                }
                self.regs[r as usize & 0x7F]
            }
        }
    }

    fn write_register(&mut self, reg: u8, v: u8, data_index: &mut usize) {
        match reg {
            addr::CMD if v == CMD_SOFT_RESET => self.reset(),
            addr::INIT_DATA => {
                let addr = 2
                    * (usize::from(self.regs[INIT_ADDR_0 as usize] & 0x0F)
                        | usize::from(self.regs[INIT_ADDR_1 as usize]) << 4);
                let i = addr + *data_index;
                *data_index += 1;
                if self.upload_after_aps_ns.is_none() {
                    self.upload_after_aps_ns =
                        Some(self.aps_off_at_ns.map_or(0, |t| self.time_ns - t));
                }
                if self.regs[INIT_CTRL as usize] == 0 && i < self.program.len() {
                    let flip = if self.corrupt_upload_byte == Some(i) {
                        0x01
                    } else {
                        0
                    };
                    self.program[i] = v ^ flip;
                }
            }
            addr::INIT_CTRL => {
                self.regs[INIT_CTRL as usize] = v;
                self.init_at_ns = (v & 1 != 0).then_some(self.time_ns);
            }
            addr::PWR_CONF => {
                if v & 1 == 0 && self.regs[PWR_CONF as usize] & 1 != 0 {
                    self.aps_off_at_ns = Some(self.time_ns);
                }
                self.regs[PWR_CONF as usize] = v;
            }
            // Read-only: CHIP_ID through INTERNAL_STATUS and the data.
            r if r <= addr::TEMPERATURE_0 + 1 => {}
            r => self.regs[r as usize & 0x7F] = v,
        }
    }
}

impl<G> ErrorType for Bmi270Model<G> {
    type Error = BusFault;
}

impl<G: Generator> SpiDevice for Bmi270Model<G> {
    fn transaction(&mut self, ops: &mut [Operation<'_, u8>]) -> Result<(), BusFault> {
        if self.fail_spi {
            return Err(BusFault);
        }
        // (address, read, dummy byte still due); INIT_DATA does not auto-increment.
        let mut addr: Option<(u8, bool, bool)> = None;
        let mut data_index = 0usize;
        let was_spi = self.spi_mode;
        let resets = self.resets;
        let mut touched = false;
        for op in ops.iter_mut() {
            match op {
                Operation::DelayNs(ns) => self.advance_ns(u64::from(*ns)),
                Operation::Write(w) => {
                    for &b in w.iter() {
                        match addr {
                            None => addr = Some((b & 0x7F, b & READ != 0, true)),
                            Some((a, false, _)) => {
                                touched = true;
                                if was_spi {
                                    self.write_register(a, b, &mut data_index);
                                }
                                let next = if a == addr::INIT_DATA {
                                    a
                                } else {
                                    (a + 1) & 0x7F
                                };
                                addr = Some((next, false, false));
                            }
                            Some((_, true, _)) => {}
                        }
                    }
                }
                Operation::Read(r) => {
                    for b in r.iter_mut() {
                        *b = match addr {
                            // The byte before a read's data is not the register's.
                            Some((a, true, true)) => {
                                addr = Some((a, true, false));
                                0x00
                            }
                            Some((a, true, false)) if was_spi => {
                                touched = true;
                                addr = Some(((a + 1) & 0x7F, true, false));
                                self.read_register(a)
                            }
                            Some((_, true, false)) => {
                                touched = true;
                                0x00
                            }
                            _ => 0xFF,
                        };
                    }
                }
                _ => {}
            }
        }
        if touched && !was_spi {
            self.i2c_mode_accesses += 1;
        }
        // CSB's rising edge at the transaction's end switches the interface to SPI (not the
        // edge that ends a soft reset's write: the part restarts in I²C mode).
        if addr.is_some() && self.resets == resets {
            self.spi_mode = true;
        }
        Ok(())
    }
}
