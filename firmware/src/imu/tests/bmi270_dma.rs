//! The F405 V3's BMI270 reading by DMA (`imu::bmi270::dma`) run against the register model as the
//! board runs it: each rising edge of INT1 (data ready) starts a burst through the
//! `InFlight`, each burst's completion decodes the frame and may start the next (the register
//! check's read), a 10 ms timer ticks the reader. Samples as the blocking driver's; a lost DMA
//! completion recovered by the stall timer; a brown-out (data ready stops) and a register changed
//! while data flows both found by the periodic register check and healed by a re-init.

use super::{code, TestGen};
use crate::imu::bmi270::dma::{Bmi270Bursts, CHECK_PERIOD_MS, SAMPLE_CMD};
use crate::imu::bmi270::regs::{ACC_RANGE, READ};
use crate::imu::bmi270::{Bmi270, Config};
use crate::imu::sim::{Bmi270Model, Generator};
use crate::imu::{ImuFlags, ImuSample};
use crate::imu_bursts::{Burst, InFlight, STALL_TICK_MS};
use embedded_hal::spi::{Operation, SpiDevice};

/// The board's time step, ns (a fifth of the 625 µs period).
const STEP_NS: u64 = 125_000;

struct Board {
    part: Bmi270Model<TestGen>,
    in_flight: InFlight,
    reader: Bmi270Bursts,
    wire: Option<Burst>,
    int1_was: bool,
    now_ns: u64,
    got: Vec<(u64, ImuSample)>,
    /// The next DMA completion never comes.
    lose_completion: bool,
    /// The register check's mismatch acted on (off: ignored).
    healing: bool,
    /// When the part was started again.
    heals: Vec<u64>,
    /// How many samples had been handed on then.
    heals_after: Vec<usize>,
    /// Bursts moved, and the bytes of the largest.
    bursts: u32,
}

impl Board {
    fn new() -> Board {
        let gen = TestGen {
            still: true,
            ..Default::default()
        };
        let imu = Bmi270::new(Bmi270Model::new(gen), Config::DEFAULT).expect("started");
        Board {
            part: imu.release(),
            in_flight: InFlight::with_command(&SAMPLE_CMD),
            reader: Bmi270Bursts::new(&Config::DEFAULT),
            wire: None,
            int1_was: false,
            now_ns: 0,
            got: Vec::new(),
            lose_completion: false,
            healing: true,
            heals: Vec::new(),
            heals_after: Vec::new(),
            bursts: 0,
        }
    }

    /// A full-duplex burst: what comes back (the address byte's slot first).
    fn transfer(&mut self, b: Burst) -> Vec<u8> {
        assert!(b.tx[0] & READ != 0, "the reader only reads");
        assert_eq!(b.len(), self.reader.expected_len());
        self.bursts += 1;
        let mut rx = vec![0xFF; b.len()];
        self.part
            .transaction(&mut [Operation::Write(&b.tx[..1]), Operation::Read(&mut rx[1..])])
            .expect("the model's bus");
        rx
    }

    fn step(&mut self) {
        self.now_ns += STEP_NS;
        self.part.advance_ns(STEP_NS);
        if self.now_ns % (u64::from(STALL_TICK_MS) * 1_000_000) == 0 {
            if let Some(b) = self.reader.on_tick(&self.in_flight) {
                self.wire = Some(b);
            }
        }
        let int1 = self.part.int1();
        if int1 && !self.int1_was {
            if let Some(b) = self.in_flight.on_watermark() {
                self.wire = Some(b);
            }
        }
        while let Some(b) = self.wire.take() {
            let rx = self.transfer(b);
            if self.lose_completion {
                self.lose_completion = false;
                break;
            }
            let mut s = ImuSample::default();
            let done = self.reader.on_complete(&rx, &mut s, &self.in_flight);
            if done.sample {
                self.got.push((self.now_ns, s));
            }
            self.wire = done.next;
            if done.mismatch.is_some() {
                // As the board's completion task: the part started again over the polled bus.
                let started = self.healing && Bmi270::new(&mut self.part, Config::DEFAULT).is_ok();
                if started {
                    self.heals.push(self.now_ns);
                    self.heals_after.push(self.got.len());
                }
                // A data-ready edge during the start stays pending in the EXTI (the bus lock
                // masks its interrupt) and is taken when the lock ends: the bus is still held.
                if self.part.int1() {
                    assert_eq!(self.in_flight.on_watermark(), None);
                }
                self.wire = self.reader.resume_after_heal(started, &self.in_flight);
            }
        }
        self.int1_was = self.part.int1();
    }

    fn run_ms(&mut self, ms: u64) {
        for _ in 0..ms * 1_000_000 / STEP_NS {
            self.step();
        }
    }

    /// The samples handed on after the first heal.
    fn healed(&self) -> Vec<ImuSample> {
        self.got[self.heals_after[0]..]
            .iter()
            .map(|(_, s)| *s)
            .collect()
    }

    /// Samples handed on at `t_ns` or later.
    fn after(&self, t_ns: u64) -> Vec<ImuSample> {
        self.got
            .iter()
            .filter(|(t, _)| *t >= t_ns)
            .map(|(_, s)| *s)
            .collect()
    }
}

/// Samples in `span_ms` at 1.6 kHz, less one for the edges.
fn at_rate(span_ms: u64) -> usize {
    (span_ms * 1600 / 1000 - 1) as usize
}

#[test]
fn every_data_ready_is_one_burst_and_one_sample() {
    let mut b = Board::new();
    let mut gen = TestGen {
        still: true,
        ..Default::default()
    };
    let t = gen.next();
    b.run_ms(1000);
    assert!(b.got.len() >= at_rate(1000), "{}", b.got.len());
    assert!(b.heals.is_empty());
    // One sample burst per sample, and the register check's reads, one per 100 ms.
    let checks = b.bursts as usize - b.got.len();
    assert!((9..=10).contains(&checks), "{checks} checks");
    let acc = t.accel_g.map(|g| code(g * 8192.0, 32767) as f32);
    let rad_per_lsb = 2000.0f32 / 32768.0 * core::f32::consts::PI / 180.0;
    let gyr = t
        .gyro_dps
        .map(|d| code(d * 16.384, 32767) as f32 * rad_per_lsb);
    let temp = 23.0 + code((t.temp_c - 23.0) * 512.0, 32767) as f32 / 512.0;
    for w in b.got.windows(2) {
        let s = w[1].1;
        assert_eq!((s.accel_out, s.gyro_rad_s, s.temp_c), (acc, gyr, temp));
        assert_eq!(s.flags, ImuFlags(0));
        assert_eq!(s.timestamp.wrapping_sub(w[0].1.timestamp), 16);
    }
}

#[test]
fn a_lost_completion_is_recovered_by_the_stall_timer() {
    let mut b = Board::new();
    b.run_ms(200);
    b.lose_completion = true;
    let lost_at = b.now_ns + 1;
    b.run_ms(400);
    let after = b.after(lost_at);
    let resumed = b
        .got
        .iter()
        .find(|(t, _)| *t > lost_at)
        .expect("read again")
        .0;
    assert!(
        resumed - lost_at <= 100_000_000,
        "{} ms",
        (resumed - lost_at) / 1_000_000
    );
    assert!(after[0].flags.has(ImuFlags::DATA_LOST));
    assert!(after[1..].iter().all(|s| s.flags == ImuFlags(0)));
    assert!(b.heals.is_empty(), "an intact part is not started again");
}

#[test]
fn a_brown_out_is_found_and_the_part_started_again() {
    let mut b = Board::new();
    b.run_ms(200);
    b.part.brown_out();
    let at = b.now_ns;
    b.run_ms(800);
    assert_eq!(b.heals.len(), 1);
    // Data ready stops: the stall timer's burst (80–90 ms), then the check right after it.
    assert!(
        b.heals[0] - at <= 100_000_000,
        "{} ms",
        (b.heals[0] - at) / 1_000_000
    );
    let after = b.healed();
    assert!(after[0].flags.has(ImuFlags::DATA_LOST));
    assert!(after.len() >= at_rate((b.now_ns - b.heals[0]) / 1_000_000));
}

#[test]
fn without_the_heal_a_brown_out_stops_reading_for_good() {
    let mut b = Board::new();
    b.healing = false;
    b.run_ms(200);
    b.part.brown_out();
    let at = b.now_ns;
    b.run_ms(800);
    assert!(b.after(at).is_empty());
}

#[test]
fn a_range_changed_while_data_flows_is_found_by_the_periodic_check() {
    let mut b = Board::new();
    // After the check of ACC_RANGE (the second register, at 200 ms): the next round finds it.
    b.run_ms(205);
    // ±4 g becomes ±16 g: data ready goes on, 1 g reads 2048 counts.
    b.part
        .transaction(&mut [Operation::Write(&[ACC_RANGE as u8, 0x03])])
        .expect("the model's bus");
    let at = b.now_ns;
    b.run_ms(1500);
    assert_eq!(b.heals.len(), 1);
    let bound = (8 * u64::from(CHECK_PERIOD_MS) + 1) * 1_000_000;
    assert!(
        b.heals[0] - at <= bound,
        "{} ms",
        (b.heals[0] - at) / 1_000_000
    );
    let z = |s: &ImuSample| s.accel_out[2];
    let wrong: Vec<_> = b
        .got
        .iter()
        .filter(|(t, _)| *t > at + 1_000_000 && *t < b.heals[0])
        .collect();
    assert!(!wrong.is_empty() && wrong.iter().all(|(_, s)| z(s) == 2048.0));
    let after = b.healed();
    assert!(after[0].flags.has(ImuFlags::DATA_LOST));
    assert!(after.iter().all(|s| z(s) == 8192.0));
    assert!(after.len() >= at_rate((b.now_ns - b.heals[0]) / 1_000_000));
}
