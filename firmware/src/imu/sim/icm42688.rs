//! Register-level model of the ICM-42688-P (DS-000347; register numbers from
//! `imu::icm42688::regs`, the behaviour written here from the datasheet's descriptions):
//!
//! - four banks of registers with their reset values, REG_BANK_SEL, WHO_AM_I 0x47 (settable, to
//!   test a wrong part), soft reset (every register back to reset, FIFO emptied, RESET_DONE_INT,
//!   no access for 1 ms), FIFO_FLUSH;
//! - sampling while both sensors are in low-noise mode, at GYRO_CONFIG0's ODR: the data registers
//!   (16 bits at the range registers' sensitivity, big-endian) and, unless in bypass mode, the FIFO
//!   (packet 3, or packet 4 with FIFO_HIRES_EN: 18-bit accel and 19-bit gyro at ±16 g / ±2000 °/s,
//!   16-bit temperature) with the absolute time stamp in 1 µs or (TMST_RES) 16 µs ticks; 2 KiB, stop-on-full: a packet that does
//!   not fit is dropped, counted in [`Icm42688Model::dropped`] by its sample number, and sets
//!   FIFO_FULL_INT; FIFO_THS_INT while the count (records with FIFO_COUNT_REC) reaches the
//!   watermark; INT_STATUS cleared on read; INT1 as INT_SOURCE0 routes it;
//! - the adaptive full-scale range switch (AFSR, INTF_CONFIG1 bits 7:6, on at reset): while it is
//!   on, a gyro rate crossing ±[`AFSR_SWITCH_DPS`] on any axis holds the gyro output at its last
//!   value for [`Icm42688Model::afsr_hold_ns`] (1.5 ms: the 1–2 ms stalls that Betaflight's and
//!   ArduPilot's drivers turn AFSR off for); off when the field reads 01 (`regs::AFSR_DISABLE`);
//! - the first samples after the sensors start are marked invalid (−32768 / −524288), as the part
//!   does while they settle ([`Icm42688Model::invalid_after_start`]);
//! - the self-test response: with SELF_TEST_CONFIG's axis bits set, the factory response for the
//!   part's code (`2620/2^(3−FS)·1.01^(code−1)` LSB at the self-test ranges), times
//!   [`Icm42688Model::self_test_gain`] (1 for a healthy part). In the PC tests only: the firmware
//!   runs no self-test, so the QEMU image's model leaves the response out (0.6 KiB);
//! - a part still starting: WHO_AM_I reads 0x00 for its first
//!   [`Icm42688Model::who_am_i_wrong_reads`] reads (each read counted in `who_am_i_reads`);
//! - rule checks: a register write within 200 µs of starting the gyro, any access within 1 ms of
//!   power-on (the model's time 0) or of a soft reset, or a write to a read-only register counts in
//!   [`Icm42688Model::violations`].

use embedded_hal::spi::{ErrorType, Operation, SpiDevice};
use heapless::Deque;

use super::{quantize, BusFault, Generator, Truth};
use crate::imu::icm42688::regs::*;

/// Dropped sample numbers remembered (the first ones).
pub const DROP_LOG: usize = 64;

/// The gyro rate, °/s, at which the AFSR switches range (and the output stalls).
pub const AFSR_SWITCH_DPS: f64 = 100.0;

/// The model.
pub struct Icm42688Model<G> {
    gen: G,
    banks: [[u8; 128]; 4],
    bank: usize,
    fifo: Deque<u8, FIFO_BYTES>,
    status: u8,
    latched_count: u16,
    time_ns: u64,
    next_sample_ns: u64,
    busy_until_ns: u64,
    no_write_until_ns: u64,
    since_start: u32,
    /// Any gyro axis above [`AFSR_SWITCH_DPS`] at the last sample (the AFSR's range).
    afsr_high: bool,
    afsr_hold_until_ns: u64,
    held_gyro_dps: [f64; 3],
    /// How long a range switch of the AFSR holds the gyro output, ns.
    pub afsr_hold_ns: u64,
    /// WHO_AM_I's value (0x47).
    pub who_am_i: u8,
    /// WHO_AM_I reads 0x00 for this many reads first (a part still starting).
    pub who_am_i_wrong_reads: u32,
    /// WHO_AM_I reads so far.
    pub who_am_i_reads: u32,
    /// Samples marked invalid after the sensors start.
    pub invalid_after_start: u32,
    /// Scale of the self-test response (1: healthy; 0.3: a failing part).
    pub self_test_gain: f64,
    /// Self-test codes: gyro x, y, z (bank 1), accelerometer x, y, z (bank 2).
    pub self_test_codes: [u8; 6],
    /// Every transaction fails with [`BusFault`] while set.
    pub fail_spi: bool,
    /// Samples produced since the start (each one's number is its index here).
    pub samples: u32,
    /// Numbers of the samples dropped because the FIFO was full (the first [`DROP_LOG`]).
    pub dropped: heapless::Vec<u32, DROP_LOG>,
    /// Datasheet rules broken by the host (see the module doc).
    pub violations: u32,
    /// The last truth sampled.
    pub last_truth: Truth,
    /// The part's clock error, ppm (positive: slow, each ODR period that much longer): its
    /// oscillator is not the board's timer. (This and the two read records below are the PC
    /// tests' instruments, not in the QEMU image.)
    #[cfg(test)]
    pub clock_ppm: i32,
    /// Reads of a sensor's data registers that found no new sample since the last read of them
    /// (gyro, accelerometer): a host reading on a timer instead of DATA_RDY.
    #[cfg(test)]
    pub stale_data_reads: [u32; 2],
    /// At the last read of each sensor's data registers (gyro, accelerometer): GYRO_CONFIG0,
    /// ACCEL_CONFIG0, GYRO_CONFIG1, GYRO_ACCEL_CONFIG0, ACCEL_CONFIG1, PWR_MGMT0, SELF_TEST_CONFIG.
    #[cfg(test)]
    pub config_at_data_read: [[u8; 7]; 2],
    /// A sample not yet read from each sensor's data registers (gyro, accelerometer).
    #[cfg(test)]
    fresh: [bool; 2],
}

/// The driver's register addresses as `u8` constants, for the model's `match`es on the address
/// byte it receives (a pattern must be a constant, not `Bank0::X as u8`).
mod addr {
    use crate::imu::icm42688::regs::{Bank0, Bank1, Bank2};
    pub const TEMP_DATA1: u8 = Bank0::TEMP_DATA1 as u8;
    #[cfg(test)]
    pub const ACCEL_DATA_X1: u8 = Bank0::ACCEL_DATA_X1 as u8;
    #[cfg(test)]
    pub const GYRO_DATA_X1: u8 = Bank0::GYRO_DATA_X1 as u8;
    pub const DEVICE_CONFIG: u8 = Bank0::DEVICE_CONFIG as u8;
    pub const INT_STATUS: u8 = Bank0::INT_STATUS as u8;
    pub const FIFO_COUNTH: u8 = Bank0::FIFO_COUNTH as u8;
    pub const FIFO_DATA: u8 = Bank0::FIFO_DATA as u8;
    pub const SIGNAL_PATH_RESET: u8 = Bank0::SIGNAL_PATH_RESET as u8;
    pub const PWR_MGMT0: u8 = Bank0::PWR_MGMT0 as u8;
    pub const WHO_AM_I: u8 = Bank0::WHO_AM_I as u8;
    pub const XG_ST_DATA: u8 = Bank1::XG_ST_DATA as u8;
    pub const XA_ST_DATA: u8 = Bank2::XA_ST_DATA as u8;
}

fn reset_banks() -> [[u8; 128]; 4] {
    let mut b = [[0u8; 128]; 4];
    // Reset values of the registers the driver touches (§13, §15, §16 register maps).
    for (reg, v) in [
        (DRIVE_CONFIG, 0x05),
        (INTF_CONFIG0, 0x30),
        (INTF_CONFIG1, 0x91),
        (GYRO_CONFIG0, 0x06),
        (ACCEL_CONFIG0, 0x06),
        (GYRO_CONFIG1, 0x16),
        (GYRO_ACCEL_CONFIG0, 0x11),
        (ACCEL_CONFIG1, 0x0D),
        (TMST_CONFIG, 0x23),
        (FSYNC_CONFIG, 0x10),
        (INT_CONFIG1, 0x10),
        (INT_SOURCE0, 0x10),
    ] {
        b[0][reg as usize] = v;
    }
    b[1][GYRO_CONFIG_STATIC2 as usize] = 0xA0;
    b
}

impl<G: Generator> Icm42688Model<G> {
    /// A part just powered on, sampling `gen`.
    pub fn new(gen: G) -> Self {
        Icm42688Model {
            gen,
            banks: reset_banks(),
            bank: 0,
            fifo: Deque::new(),
            status: INT_RESET_DONE,
            latched_count: 0,
            time_ns: 0,
            next_sample_ns: 0,
            // Power-on: no access for 1 ms.
            busy_until_ns: 1_000_000,
            no_write_until_ns: 0,
            since_start: 0,
            afsr_high: false,
            afsr_hold_until_ns: 0,
            held_gyro_dps: [0.0; 3],
            afsr_hold_ns: 1_500_000,
            who_am_i: WHO_AM_I_VALUE,
            who_am_i_wrong_reads: 0,
            who_am_i_reads: 0,
            invalid_after_start: 1,
            self_test_gain: 1.0,
            self_test_codes: [70, 72, 68, 60, 62, 58],
            fail_spi: false,
            samples: 0,
            dropped: heapless::Vec::new(),
            violations: 0,
            last_truth: Truth::default(),
            #[cfg(test)]
            clock_ppm: 0,
            #[cfg(test)]
            stale_data_reads: [0; 2],
            #[cfg(test)]
            config_at_data_read: [[0; 7]; 2],
            #[cfg(test)]
            fresh: [false; 2],
        }
    }

    /// The generator (e.g. to set the virtual table).
    pub fn generator(&mut self) -> &mut G {
        &mut self.gen
    }

    /// A register's value (bank, address), as the tests read the configuration.
    pub fn register(&self, bank: usize, reg: impl Into<u8>) -> u8 {
        self.banks[bank & 3][reg.into() as usize & 0x7F]
    }

    /// The part's time since power-on, ns.
    pub fn time_ns(&self) -> u64 {
        self.time_ns
    }

    /// FIFO bytes held.
    pub fn fifo_len(&self) -> usize {
        self.fifo.len()
    }

    /// The INT1 pin (active high, as the driver configures it): a latched status bit routed by
    /// INT_SOURCE0 (DRDY bit 3, FIFO_THS bit 2, FIFO_FULL bit 1).
    pub fn int1(&self) -> bool {
        let route = self.banks[0][INT_SOURCE0 as usize];
        let mut pending = 0;
        if route & (1 << 3) != 0 {
            pending |= self.status & INT_DATA_RDY;
        }
        if route & (1 << 2) != 0 {
            pending |= self.status & INT_FIFO_THS;
        }
        if route & (1 << 1) != 0 {
            pending |= self.status & INT_FIFO_FULL;
        }
        pending != 0
    }

    #[cfg(test)]
    fn odr_period_ns(&self) -> u64 {
        let nominal = self.nominal_period_ns();
        nominal.saturating_add_signed(nominal as i64 * i64::from(self.clock_ppm) / 1_000_000)
    }

    #[cfg(not(test))]
    fn odr_period_ns(&self) -> u64 {
        self.nominal_period_ns()
    }

    fn nominal_period_ns(&self) -> u64 {
        match self.banks[0][GYRO_CONFIG0 as usize] & 0x0F {
            1 => 31_250,
            2 => 62_500,
            3 => 125_000,
            4 => 250_000,
            5 => 500_000,
            6 => 1_000_000,
            7 => 5_000_000,
            8 => 10_000_000,
            9 => 20_000_000,
            10 => 40_000_000,
            15 => 2_000_000,
            _ => 1_000_000,
        }
    }

    /// (gyro, accelerometer) in low-noise mode.
    fn sensors_on(&self) -> [bool; 2] {
        let p = self.banks[0][PWR_MGMT0 as usize];
        [p & 0b1100 == 0b1100, p & 0b0011 == 0b0011]
    }

    /// Either sensor on (the self-test runs one alone; sampling runs both).
    fn sampling(&self) -> bool {
        self.sensors_on().contains(&true)
    }

    /// Lets `ns` of the part's time pass: one sample per ODR period while sampling.
    pub fn advance_ns(&mut self, ns: u64) {
        let end = self.time_ns + ns;
        while self.sampling() && self.next_sample_ns <= end {
            self.time_ns = self.next_sample_ns;
            self.sample();
            self.next_sample_ns += self.odr_period_ns();
        }
        self.time_ns = end;
        if !self.sampling() {
            self.next_sample_ns = end;
        }
    }

    /// Time until the next sample, ns (a board's timer waits this long).
    pub fn until_next_sample_ns(&self) -> u64 {
        self.next_sample_ns.saturating_sub(self.time_ns)
    }

    #[cfg(test)]
    fn self_test_response(&self) -> ([f64; 3], [f64; 3]) {
        /// 1.01ⁿ by squaring: the factory formula's power (`imu::icm42688::self_test`) without `libm::pow`,
        /// whose 1.2 KiB the QEMU image, which carries this model, does not need; it agrees with
        /// `pow` to a few ulp, far inside the self-test's 0.5–1.5 bounds.
        fn pow_1_01(mut n: u32) -> f64 {
            let (mut base, mut acc) = (1.01f64, 1.0f64);
            while n > 0 {
                if n & 1 == 1 {
                    acc *= base;
                }
                base *= base;
                n >>= 1;
            }
            acc
        }
        let st = self.banks[0][SELF_TEST_CONFIG as usize];
        let otp = |fs: u32, code: u8| {
            if code == 0 {
                0.0
            } else {
                2620.0 / f64::from(1u32 << (3 - fs)) * pow_1_01(u32::from(code) - 1)
            }
        };
        let mut g = [0.0; 3];
        let mut a = [0.0; 3];
        for i in 0..3 {
            if st & (1 << i) != 0 {
                g[i] = otp(3, self.self_test_codes[i]) / 131.0 * self.self_test_gain;
            }
            if st & (1 << (3 + i)) != 0 {
                a[i] = otp(2, self.self_test_codes[3 + i]) / 8192.0 * self.self_test_gain;
            }
        }
        (g, a)
    }

    fn sample(&mut self) {
        let mut t = self.gen.next();
        self.last_truth = t;
        #[cfg(test)]
        {
            let (st_g, st_a) = self.self_test_response();
            for i in 0..3 {
                t.gyro_dps[i] += st_g[i];
                t.accel_g[i] += st_a[i];
            }
        }
        self.adaptive_range(&mut t);
        let n = self.samples;
        self.samples = self.samples.wrapping_add(1);
        let invalid = self.since_start < self.invalid_after_start;
        self.since_start = self.since_start.saturating_add(1);
        self.write_data_registers(&t, invalid);
        self.status |= INT_DATA_RDY;
        #[cfg(test)]
        {
            self.fresh = [true; 2];
        }
        if self.banks[0][FIFO_CONFIG as usize] >> 6 != 0 {
            self.push_packet(&t, invalid, n);
        }
    }

    /// The AFSR: a range switch (any axis crossing ±[`AFSR_SWITCH_DPS`]) while it is on holds the
    /// gyro output at the last value before the switch for `afsr_hold_ns`.
    fn adaptive_range(&mut self, t: &mut Truth) {
        let on = self.banks[0][INTF_CONFIG1 as usize] & AFSR_MASK != AFSR_DISABLE;
        let high = t.gyro_dps.iter().any(|w| w.abs() > AFSR_SWITCH_DPS);
        if on && high != self.afsr_high {
            self.afsr_hold_until_ns = self.time_ns + self.afsr_hold_ns;
        }
        self.afsr_high = high;
        if on && self.time_ns < self.afsr_hold_until_ns {
            t.gyro_dps = self.held_gyro_dps;
        } else {
            self.held_gyro_dps = t.gyro_dps;
        }
    }

    /// A sensor that is off reads −32768, as one still starting does.
    fn write_data_registers(&mut self, t: &Truth, invalid: bool) {
        let on = self.sensors_on();
        let a_fs = (self.banks[0][ACCEL_CONFIG0 as usize] >> 5) & 3;
        let g_fs = (self.banks[0][GYRO_CONFIG0 as usize] >> 5) & 7;
        let a_lsb = 2048.0 * f64::from(1u32 << a_fs);
        let g_lsb = [16.4, 32.8, 65.5, 131.0, 262.0, 524.3, 1048.6, 2097.2][g_fs as usize];
        let temp = quantize((t.temp_c - 25.0) * 132.48, 32767) as i16;
        let r = &mut self.banks[0];
        r[TEMP_DATA1 as usize..TEMP_DATA1 as usize + 2].copy_from_slice(&temp.to_be_bytes());
        for i in 0..3 {
            let a = if invalid || !on[1] {
                INVALID_16
            } else {
                quantize(t.accel_g[i] * a_lsb, 32767) as i16
            };
            let g = if invalid || !on[0] {
                INVALID_16
            } else {
                quantize(t.gyro_dps[i] * g_lsb, 32767) as i16
            };
            let ai = ACCEL_DATA_X1 as usize + 2 * i;
            r[ai..ai + 2].copy_from_slice(&a.to_be_bytes());
            r[ai + 6..ai + 8].copy_from_slice(&g.to_be_bytes());
        }
    }

    fn push_packet(&mut self, t: &Truth, invalid: bool, n: u32) {
        let hires = self.banks[0][FIFO_CONFIG1 as usize] & FIFO_HIRES_EN != 0;
        let mut p = [0u8; PACKET4_LEN];
        let len = if hires { PACKET4_LEN } else { PACKET3_LEN };
        // TMST_RES: 1 µs or 16 µs ticks.
        let tick_ns = if self.banks[0][TMST_CONFIG as usize] & TMST_RES_16US != 0 {
            16_000
        } else {
            1000
        };
        let ts = ticks_u16(self.time_ns, tick_ns).to_be_bytes();
        if hires {
            p[0] = HEADER_PACKET4;
            for i in 0..3 {
                let a = if invalid {
                    INVALID_20
                } else {
                    quantize(t.accel_g[i] * 8192.0, 131_071) * 4
                };
                let g = if invalid {
                    INVALID_20
                } else {
                    quantize(t.gyro_dps[i] * 131.0, 262_143) * 2
                };
                p[1 + 2 * i..3 + 2 * i].copy_from_slice(&((a >> 4) as i16).to_be_bytes());
                p[7 + 2 * i..9 + 2 * i].copy_from_slice(&((g >> 4) as i16).to_be_bytes());
                p[17 + i] = (((a & 0xF) as u8) << 4) | (g & 0xF) as u8;
            }
            let temp = quantize((t.temp_c - 25.0) * 132.48, 32767) as i16;
            p[13..15].copy_from_slice(&temp.to_be_bytes());
            p[15..17].copy_from_slice(&ts);
        } else {
            p[0] = HEADER_PACKET3;
            p[1..13].copy_from_slice(&self.banks[0][ACCEL_DATA_X1 as usize..][..12]);
            p[13] = quantize((t.temp_c - 25.0) * 2.07, 127) as i8 as u8;
            p[14..16].copy_from_slice(&ts);
        }
        if FIFO_BYTES - self.fifo.len() < len {
            self.status |= INT_FIFO_FULL;
            let _ = self.dropped.push(n);
        } else {
            for b in &p[..len] {
                let _ = self.fifo.push_back(*b);
            }
        }
        let wm = u16::from_le_bytes([
            self.banks[0][FIFO_CONFIG2 as usize],
            self.banks[0][FIFO_CONFIG3 as usize] & 0x0F,
        ]);
        if wm > 0 && self.count() >= wm {
            self.status |= INT_FIFO_THS;
        }
    }

    fn packet_len(&self) -> usize {
        if self.banks[0][FIFO_CONFIG1 as usize] & FIFO_HIRES_EN != 0 {
            PACKET4_LEN
        } else {
            PACKET3_LEN
        }
    }

    /// FIFO_COUNT as the part reports it: records with FIFO_COUNT_REC, else bytes.
    fn count(&self) -> u16 {
        if self.banks[0][INTF_CONFIG0 as usize] & FIFO_COUNT_REC != 0 {
            (self.fifo.len() / self.packet_len()) as u16
        } else {
            self.fifo.len() as u16
        }
    }

    /// The first byte of a sensor's data registers read (0 gyro, 1 accelerometer).
    #[cfg(test)]
    fn note_data_read(&mut self, k: usize) {
        if !self.fresh[k] {
            self.stale_data_reads[k] += 1;
        }
        self.fresh[k] = false;
        let r = &self.banks[0];
        self.config_at_data_read[k] = [
            GYRO_CONFIG0,
            ACCEL_CONFIG0,
            GYRO_CONFIG1,
            GYRO_ACCEL_CONFIG0,
            ACCEL_CONFIG1,
            PWR_MGMT0,
            SELF_TEST_CONFIG,
        ]
        .map(|a| r[a as usize]);
    }

    fn read_register(&mut self, reg: u8) -> u8 {
        match (self.bank, reg) {
            (1, addr::XG_ST_DATA..=0x61) => {
                return self.self_test_codes[usize::from(reg - addr::XG_ST_DATA)]
            }
            (2, addr::XA_ST_DATA..=0x3D) => {
                return self.self_test_codes[3 + usize::from(reg - addr::XA_ST_DATA)]
            }
            (0, _) => {}
            (b, r) => return self.banks[b][r as usize & 0x7F],
        }
        #[cfg(test)]
        if reg == addr::GYRO_DATA_X1 {
            self.note_data_read(0);
        } else if reg == addr::ACCEL_DATA_X1 {
            self.note_data_read(1);
        }
        let big = self.banks[0][INTF_CONFIG0 as usize] & FIFO_COUNT_ENDIAN != 0;
        match reg {
            addr::INT_STATUS => core::mem::take(&mut self.status),
            addr::FIFO_COUNTH => {
                self.latched_count = self.count();
                let b = self.latched_count.to_be_bytes();
                if big {
                    b[0]
                } else {
                    b[1]
                }
            }
            0x2F => {
                let b = self.latched_count.to_be_bytes();
                if big {
                    b[1]
                } else {
                    b[0]
                }
            }
            addr::FIFO_DATA => self.fifo.pop_front().unwrap_or(0xFF),
            addr::WHO_AM_I => {
                self.who_am_i_reads += 1;
                if self.who_am_i_reads <= self.who_am_i_wrong_reads {
                    0x00
                } else {
                    self.who_am_i
                }
            }
            REG_BANK_SEL => self.bank as u8,
            r => self.banks[0][r as usize & 0x7F],
        }
    }

    fn write_register(&mut self, reg: u8, v: u8) {
        if self.time_ns < self.no_write_until_ns && reg != REG_BANK_SEL {
            self.violations += 1;
        }
        if reg == REG_BANK_SEL {
            self.bank = usize::from(v & 7).min(3);
            return;
        }
        if self.bank != 0 {
            self.banks[self.bank][reg as usize & 0x7F] = v;
            return;
        }
        let read_only =
            (addr::TEMP_DATA1..=addr::FIFO_DATA).contains(&reg) || reg == addr::WHO_AM_I;
        if read_only {
            self.violations += 1;
            return;
        }
        match reg {
            addr::DEVICE_CONFIG if v & SOFT_RESET != 0 => self.soft_reset(),
            addr::SIGNAL_PATH_RESET => {
                if v & FIFO_FLUSH != 0 {
                    self.fifo.clear();
                }
            }
            addr::PWR_MGMT0 => {
                let gyro_was_off = self.banks[0][PWR_MGMT0 as usize] & 0b1100 == 0;
                let starting = !self.sampling();
                self.banks[0][PWR_MGMT0 as usize] = v;
                if gyro_was_off && v & 0b1100 != 0 {
                    self.no_write_until_ns = self.time_ns + 200_000;
                }
                if starting && self.sampling() {
                    self.since_start = 0;
                    self.next_sample_ns = self.time_ns + self.odr_period_ns();
                }
            }
            r => self.banks[0][r as usize & 0x7F] = v,
        }
    }

    fn soft_reset(&mut self) {
        self.banks = reset_banks();
        self.fifo.clear();
        self.status = INT_RESET_DONE;
        self.busy_until_ns = self.time_ns + 1_000_000;
    }
}

impl<G> ErrorType for Icm42688Model<G> {
    type Error = BusFault;
}

impl<G: Generator> SpiDevice for Icm42688Model<G> {
    fn transaction(&mut self, ops: &mut [Operation<'_, u8>]) -> Result<(), BusFault> {
        if self.fail_spi {
            return Err(BusFault);
        }
        // (address, reading) once the first byte has been sent.
        let mut addr: Option<(u8, bool)> = None;
        for op in ops.iter_mut() {
            if let Operation::DelayNs(ns) = op {
                self.advance_ns(u64::from(*ns));
                continue;
            }
            if self.time_ns < self.busy_until_ns {
                self.violations += 1;
            }
            match op {
                Operation::Write(w) => self.shift_in(&mut addr, w),
                Operation::Read(r) => self.shift_out(&mut addr, r),
                Operation::Transfer(r, w) => {
                    self.shift_in(&mut addr, w);
                    self.shift_out(&mut addr, r);
                }
                Operation::TransferInPlace(b) => self.shift_out(&mut addr, b),
                Operation::DelayNs(_) => {}
            }
        }
        Ok(())
    }
}

/// The async form for the async driver: the model answers at once.
impl<G: Generator> embedded_hal_async::spi::SpiDevice for Icm42688Model<G> {
    async fn transaction(&mut self, ops: &mut [Operation<'_, u8>]) -> Result<(), BusFault> {
        SpiDevice::transaction(self, ops)
    }
}

impl<G: Generator> Icm42688Model<G> {
    fn shift_in(&mut self, addr: &mut Option<(u8, bool)>, bytes: &[u8]) {
        for &b in bytes {
            match *addr {
                None => *addr = Some((b & !READ, b & READ != 0)),
                Some((a, false)) => {
                    self.write_register(a, b);
                    *addr = Some((next_address(a), false));
                }
                Some((_, true)) => {} // bytes clocked out while reading are ignored
            }
        }
    }

    fn shift_out(&mut self, addr: &mut Option<(u8, bool)>, bytes: &mut [u8]) {
        for b in bytes.iter_mut() {
            *b = match *addr {
                Some((a, true)) => {
                    *addr = Some((next_address(a), true));
                    self.read_register(a)
                }
                _ => 0xFF,
            };
        }
    }
}

/// `(t / d) mod 2¹⁶` for a divisor `d` below 2¹⁶ (the time stamp's tick, 1 000 or 16 000 ns), by
/// long division in 16-bit digits with 32-bit divisions: the model needs no 64-bit division
/// routine (0.9 KiB of the QEMU image).
fn ticks_u16(t: u64, d: u32) -> u16 {
    debug_assert!(d > 0 && d < 1 << 16);
    // Each step divides a remainder (below d < 2¹⁶) with the next 16-bit digit appended: below
    // 2³², and its quotient digit below 2¹⁶. Only the last quotient digit is kept.
    let mut r = ((t >> 32) as u32) % d;
    r = ((r << 16) | ((t >> 16) as u32 & 0xFFFF)) % d;
    (((r << 16) | (t as u32 & 0xFFFF)) / d) as u16
}

/// Burst accesses step through the registers, except FIFO_DATA, which a burst keeps popping.
fn next_address(a: u8) -> u8 {
    if a == addr::FIFO_DATA {
        a
    } else {
        (a + 1) & 0x7F
    }
}

#[cfg(test)]
mod tests {
    use super::ticks_u16;
    use proptest::prelude::*;

    #[test]
    fn ticks_at_the_edges() {
        for d in [1, 2, 1000, 16_000, 65_535] {
            for t in [
                0,
                1,
                u64::from(d) - 1,
                u64::from(d),
                u64::MAX,
                u64::MAX - 1,
                1 << 32,
            ] {
                assert_eq!(ticks_u16(t, d), (t / u64::from(d)) as u16, "{t} / {d}");
            }
        }
    }

    proptest! {
        /// The time stamp's ticks as the 64-bit division gives them.
        #[test]
        fn ticks_are_the_64_bit_quotient_mod_2_16(t: u64, d in 1u32..65_536) {
            prop_assert_eq!(ticks_u16(t, d), (t / u64::from(d)) as u16);
        }
    }
}
