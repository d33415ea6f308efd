//! Register-level model of the LSM6DSO (ST DS12140; register numbers from `imu::lsm6dso::regs`):
//! WHO_AM_I 0x6C (settable), SW_RESET, the rate and range registers, sampling while both sensors
//! run (at CTRL1_XL's rate), the data scaled by the range (0.061·2^k mg and 8.75·2^k m°/s per LSB),
//! the FIFO of tagged 7-byte words — per slot a time stamp word (25 µs per LSB), a gyro and an
//! accelerometer word (in alternating order, as the part gives no order within a slot) with the
//! 2-bit slot counter, a temperature word at 52 Hz (256 LSB/°C around 25 °C) — in FIFO mode (stop when full:
//! a word that does not fit is dropped, its slot counted in [`Lsm6dsoModel::dropped`], and
//! FIFO_OVR_LATCHED set until FIFO_STATUS2 is read), the watermark and overrun on INT1.

use embedded_hal::spi::{ErrorType, Operation, SpiDevice};
use heapless::Deque;

use super::{quantize, BusFault, Generator};
use crate::imu::lsm6dso::regs::*;

/// FIFO depth of the model, words.
pub const FIFO_WORDS: usize = 512;

/// The model.
pub struct Lsm6dsoModel<G> {
    gen: G,
    regs: [u8; 128],
    fifo: Deque<[u8; WORD_LEN], FIFO_WORDS>,
    overrun_latched: bool,
    time_ns: u64,
    next_sample_ns: u64,
    slot: u32,
    /// WHO_AM_I's value.
    pub who_am_i: u8,
    /// Every transaction fails while set.
    pub fail_spi: bool,
    /// Slots produced.
    pub samples: u32,
    /// Slots that lost at least one word to a full FIFO (the first 64).
    pub dropped: heapless::Vec<u32, 64>,
}

/// The driver's register addresses as `u8` constants, for the model's `match`es on the address
/// byte it receives (a pattern must be a constant, not `Reg::X as u8`).
mod addr {
    use crate::imu::lsm6dso::regs::Reg;
    pub const WHO_AM_I: u8 = Reg::WHO_AM_I as u8;
    pub const FIFO_STATUS1: u8 = Reg::FIFO_STATUS1 as u8;
    pub const FIFO_STATUS2: u8 = Reg::FIFO_STATUS2 as u8;
    pub const FIFO_DATA_OUT_TAG: u8 = Reg::FIFO_DATA_OUT_TAG as u8;
    pub const CTRL3_C: u8 = Reg::CTRL3_C as u8;
}

impl<G: Generator> Lsm6dsoModel<G> {
    /// A part just powered on.
    pub fn new(gen: G) -> Self {
        let mut regs = [0u8; 128];
        regs[CTRL3_C as usize] = 0x04;
        Lsm6dsoModel {
            gen,
            regs,
            fifo: Deque::new(),
            overrun_latched: false,
            time_ns: 0,
            next_sample_ns: 0,
            slot: 0,
            who_am_i: WHO_AM_I_VALUE,
            fail_spi: false,
            samples: 0,
            dropped: heapless::Vec::new(),
        }
    }

    /// A register's value.
    pub fn register(&self, reg: impl Into<u8>) -> u8 {
        self.regs[reg.into() as usize & 0x7F]
    }

    /// Words in the FIFO.
    pub fn fifo_words(&self) -> usize {
        self.fifo.len()
    }

    /// INT1: the FIFO threshold (INT1_FIFO_TH) or an overrun (INT1_FIFO_OVR).
    pub fn int1(&self) -> bool {
        let r = self.regs[INT1_CTRL as usize];
        (r & (1 << 3) != 0 && self.fifo.len() >= self.watermark())
            || (r & (1 << 4) != 0 && self.overrun_latched)
    }

    fn watermark(&self) -> usize {
        usize::from(self.regs[FIFO_CTRL1 as usize])
            | (usize::from(self.regs[FIFO_CTRL2 as usize] & 1) << 8)
    }

    fn period_ns(&self) -> Option<u64> {
        let xl = self.regs[CTRL1_XL as usize] >> 4;
        let g = self.regs[CTRL2_G as usize] >> 4;
        // Codes 4..=8: 104 Hz doubling to 1.66 kHz (exact periods: 25 µs × 384 / 2^(k−4)).
        if !(4..=8).contains(&xl) || g != xl {
            return None;
        }
        Some(9_600_000 >> (xl - 4))
    }

    /// Lets `ns` of the part's time pass.
    pub fn advance_ns(&mut self, ns: u64) {
        let end = self.time_ns + ns;
        while let Some(p) = self.period_ns() {
            if self.next_sample_ns > end {
                break;
            }
            self.time_ns = self.next_sample_ns;
            self.sample();
            self.next_sample_ns += p;
        }
        self.time_ns = end;
        if self.period_ns().is_none() {
            self.next_sample_ns = end;
        }
    }

    /// Time until the next slot, ns.
    pub fn until_next_sample_ns(&self) -> u64 {
        self.next_sample_ns.saturating_sub(self.time_ns)
    }

    fn sample(&mut self) {
        let t = self.gen.next();
        let n = self.samples;
        self.samples += 1;
        let mg = 0.061 * f64::from(1u32 << fs_xl_power(self.regs[CTRL1_XL as usize] >> 2 & 3));
        let mdps = 8.75 * f64::from(1u32 << (self.regs[CTRL2_G as usize] >> 2 & 3));
        let a = t.accel_g.map(|g| quantize(g * 1000.0 / mg, 32767) as i16);
        let w = t
            .gyro_dps
            .map(|d| quantize(d * 1000.0 / mdps, 32767) as i16);
        if self.regs[FIFO_CTRL4 as usize] & 0b111 == 0 {
            return; // bypass
        }
        let cnt = (self.slot % 4) as u8;
        self.slot += 1;
        let word = |tag: u8, v: [i16; 3]| {
            let mut b = [(tag << 3) | (cnt << 1), 0, 0, 0, 0, 0, 0];
            for i in 0..3 {
                b[1 + 2 * i..3 + 2 * i].copy_from_slice(&v[i].to_le_bytes());
            }
            b
        };
        let (gw, aw) = (word(TAG_GYRO, w), word(TAG_ACCEL, a));
        // The slot's time stamp first, then the temperature (52 Hz batching: one word every ODR/52
        // slots, 19.23 ms), then the sensors in alternating order.
        let mut words = heapless::Vec::<[u8; WORD_LEN], 4>::new();
        let ts = (self.time_ns / 25_000) as u32;
        let mut tsw = [(TAG_TIMESTAMP << 3) | (cnt << 1), 0, 0, 0, 0, 0, 0];
        tsw[1..5].copy_from_slice(&ts.to_le_bytes());
        let _ = words.push(tsw);
        let temp_every = (self.period_ns().map_or(1, |p| 19_230_769 / p)).max(1) as u32;
        if n % temp_every == 0 {
            let code = quantize((t.temp_c - 25.0) * 256.0, 32767) as i16;
            let _ = words.push(word(TAG_TEMPERATURE, [code, 0, 0]));
        }
        let ordered = if n % 2 == 0 { [gw, aw] } else { [aw, gw] };
        let _ = words.extend_from_slice(&ordered);
        let mut lost = false;
        for w in words {
            if self.fifo.push_back(w).is_err() {
                lost = true;
            }
        }
        if lost {
            self.overrun_latched = true;
            let _ = self.dropped.push(n);
        }
    }

    fn read_register(&mut self, reg: u8, word_byte: &mut usize) -> u8 {
        match reg {
            addr::WHO_AM_I => self.who_am_i,
            addr::FIFO_STATUS1 => (self.fifo.len() & 0xFF) as u8,
            addr::FIFO_STATUS2 => {
                let n = self.fifo.len();
                let v = ((n >> 8) & 3) as u8
                    | if self.overrun_latched {
                        FIFO_OVR_LATCHED | (1 << 6)
                    } else {
                        0
                    }
                    | if n >= self.watermark() { 1 << 7 } else { 0 };
                self.overrun_latched = false;
                v
            }
            addr::FIFO_DATA_OUT_TAG..=0x7E => {
                let i = *word_byte;
                let b = self.fifo.front().map_or(0, |w| w[i]);
                *word_byte += 1;
                if *word_byte == WORD_LEN {
                    *word_byte = 0;
                    self.fifo.pop_front();
                }
                b
            }
            r => self.regs[r as usize & 0x7F],
        }
    }

    fn write_register(&mut self, reg: u8, v: u8) {
        if reg == addr::CTRL3_C && v & 1 != 0 {
            // SW_RESET: registers to their reset values, FIFO emptied, sampling stopped.
            self.regs = [0; 128];
            self.regs[CTRL3_C as usize] = 0x04;
            self.fifo.clear();
            self.overrun_latched = false;
            self.slot = 0;
            self.next_sample_ns = self.time_ns;
            return;
        }
        let starting = self.period_ns().is_none();
        self.regs[reg as usize & 0x7F] = v;
        if let (true, Some(p)) = (starting, self.period_ns()) {
            self.next_sample_ns = self.time_ns + p;
        }
    }
}

/// FS_XL code to the power of two of the sensitivity (00 ±2 g, 10 ±4 g, 11 ±8 g, 01 ±16 g).
fn fs_xl_power(code: u8) -> u32 {
    match code & 3 {
        0 => 0,
        2 => 1,
        3 => 2,
        _ => 3,
    }
}

impl<G> ErrorType for Lsm6dsoModel<G> {
    type Error = BusFault;
}

impl<G: Generator> SpiDevice for Lsm6dsoModel<G> {
    fn transaction(&mut self, ops: &mut [Operation<'_, u8>]) -> Result<(), BusFault> {
        if self.fail_spi {
            return Err(BusFault);
        }
        let mut addr: Option<(u8, bool)> = None;
        let mut word_byte = 0usize;
        for op in ops.iter_mut() {
            match op {
                Operation::DelayNs(ns) => self.advance_ns(u64::from(*ns)),
                Operation::Write(w) => {
                    for &b in w.iter() {
                        match addr {
                            None => addr = Some((b & 0x7F, b & READ != 0)),
                            Some((a, false)) => {
                                self.write_register(a, b);
                                addr = Some((next_address(a), false));
                            }
                            Some((_, true)) => {}
                        }
                    }
                }
                Operation::Read(r) => {
                    for b in r.iter_mut() {
                        *b = match addr {
                            Some((a, true)) => {
                                addr = Some((next_address(a), true));
                                self.read_register(a, &mut word_byte)
                            }
                            _ => 0xFF,
                        };
                    }
                }
                _ => {}
            }
        }
        Ok(())
    }
}

/// Auto-increment (IF_INC), rolling from the last FIFO output byte back to its tag.
fn next_address(a: u8) -> u8 {
    if a == 0x7E {
        addr::FIFO_DATA_OUT_TAG
    } else {
        (a + 1) & 0x7F
    }
}
