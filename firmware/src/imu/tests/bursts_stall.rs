//! The F405's burst chain (`imu_bursts`) run against the register model as the board runs it —
//! INT1's rising edge starts a chain, each burst's completion decides the next, a 10 ms timer
//! ticks the reader — with one interrupt lost: a DMA completion that never comes, or a watermark
//! edge missed. Without the timer the part is never read again; with it reading resumes within
//! 100 ms of the loss, the gap flagged on the first sample after it. And a part that resets under
//! the board (a brown-out): the stall restart alone never reads it again; with the register check
//! the board runs after each stall (`imu::icm42688::check`), it is started again and read.
//! And a register changed while the FIFO keeps flowing (a flipped bit: the samples decode, at the
//! wrong scale): no stall ever comes, and only the periodic check (one register per 100 ms in the
//! chain, `imu_bursts`, "The register check") finds it and starts the part again.

use super::*;
use crate::imu::icm42688::check::{check_and_heal, checked_registers, restart, Checked};
use crate::imu::icm42688::regs::{ACCEL_CONFIG0, READ};
use crate::imu::icm42688::{AccelRange, Core, Odr, BATCH_PACKETS};
use crate::imu::ImuFlags;
use crate::imu_bursts::{Burst, BurstReader, InFlight, CHECK_PERIOD_MS, NO_SAMPLE, STALL_TICK_MS};
use embedded_hal::spi::{Operation, SpiDevice};

/// The F405's configuration (`board::f405::IMU_CONFIG`): 8 kHz, watermark 8 packets.
const CFG: Config = Config {
    odr: Odr::Hz8000,
    accel_range: AccelRange::G4,
    watermark_packets: 8,
    ..Config::DEFAULT
};

/// One ODR period at 8 kHz, ns.
const STEP_NS: u64 = 125_000;

/// Which interrupt is lost.
#[derive(Clone, Copy, PartialEq)]
enum Loss {
    /// The next burst's DMA completion.
    Completion,
    /// The next rising edge of INT1.
    Edge,
}

struct Board {
    part: Model,
    in_flight: InFlight,
    reader: BurstReader,
    /// The burst on the wire.
    wire: Option<Burst>,
    int1_was: bool,
    now_ns: u64,
    out: [ImuSample; BATCH_PACKETS],
    /// Samples handed on, with the time they were.
    got: Vec<(u64, ImuSample)>,
    /// The timer ticks the reader.
    ticking: bool,
    lose: Option<Loss>,
    lost_at_ns: Option<u64>,
    restarts: u32,
    /// After each stall, the register check and, on a mismatch, the part started again; and the
    /// periodic check's mismatch acted on (off: ignored).
    checking: bool,
    /// Parts started again (after a stall or by the periodic check).
    heals: u32,
    /// When each was started again.
    heal_times: Vec<u64>,
    /// Of those, by the periodic check, with the time.
    periodic_heals: Vec<u64>,
}

impl Board {
    fn new(ticking: bool) -> Board {
        let gen = TestGen {
            still: true,
            ..Default::default()
        };
        let imu = Icm42688::new(Icm42688Model::new(gen), CFG).expect("configured");
        Board {
            part: imu.release(),
            in_flight: InFlight::new(),
            reader: BurstReader::new(Core::new(CFG).unwrap()),
            wire: None,
            int1_was: false,
            now_ns: 0,
            out: [NO_SAMPLE; BATCH_PACKETS],
            got: Vec::new(),
            ticking,
            lose: None,
            lost_at_ns: None,
            restarts: 0,
            checking: true,
            heals: 0,
            heal_times: Vec::new(),
            periodic_heals: Vec::new(),
        }
    }

    /// The part loses power and comes back: every register at its reset value.
    fn brown_out(&mut self) {
        let gen = TestGen {
            still: true,
            ..Default::default()
        };
        self.part = Icm42688Model::new(gen);
    }

    /// The bytes a full-duplex burst brings back (the address byte's slot first).
    fn transfer(&mut self, b: Burst) -> Vec<u8> {
        let mut rx = vec![0xFF; b.len()];
        let r = if b.tx[0] & READ != 0 {
            self.part
                .transaction(&mut [Operation::Write(&b.tx[..1]), Operation::Read(&mut rx[1..])])
        } else {
            self.part.transaction(&mut [Operation::Write(b.tx)])
        };
        r.expect("the model's bus");
        rx
    }

    /// One ODR period of the board.
    fn step(&mut self) {
        self.now_ns += STEP_NS;
        self.part.advance_ns(STEP_NS);
        let tick_ns = u64::from(STALL_TICK_MS) * 1_000_000;
        if self.ticking && self.now_ns % tick_ns == 0 {
            if let Some(b) = self.reader.on_tick(&self.in_flight) {
                self.restarts += 1;
                if self.checking {
                    // As the board does after a stall: the check over the blocking bus first.
                    match check_and_heal(&mut self.part, CFG).expect("the model's bus") {
                        Checked::Intact => {}
                        Checked::Restarted { core, .. } => {
                            self.heals += 1;
                            self.heal_times.push(self.now_ns);
                            self.reader.replace_core(core);
                        }
                    }
                }
                self.wire = Some(b);
            }
        }
        let int1 = self.part.int1();
        if int1 && !self.int1_was {
            if self.lose == Some(Loss::Edge) {
                self.lose = None;
                self.lost_at_ns = Some(self.now_ns);
            } else if let Some(b) = self.in_flight.on_watermark() {
                self.wire = Some(b);
            }
        }
        while let Some(b) = self.wire.take() {
            let rx = self.transfer(b);
            if self.lose == Some(Loss::Completion) {
                // The bytes moved, but the completion interrupt never comes.
                self.lose = None;
                self.lost_at_ns = Some(self.now_ns);
                break;
            }
            let done = self.reader.on_complete(&rx, &mut self.out, &self.in_flight);
            for s in &self.out[..done.samples] {
                self.got.push((self.now_ns, *s));
            }
            self.wire = done.next;
            if done.mismatch.is_some() {
                // As `burst_done` does: the part started again over the blocking bus (or, with
                // the checks off, reading goes on as if nothing were wrong).
                if !self.checking {
                    self.wire = self.reader.resume_after_heal(None, &self.in_flight);
                    continue;
                }
                let core = restart(&mut self.part, CFG).ok();
                self.heals += 1;
                self.heal_times.push(self.now_ns);
                self.periodic_heals.push(self.now_ns);
                self.wire = self.reader.resume_after_heal(core, &self.in_flight);
            }
        }
        self.int1_was = self.part.int1();
    }

    fn run_ms(&mut self, ms: u64) {
        for _ in 0..ms * 1_000_000 / STEP_NS {
            self.step();
        }
    }

    /// Samples handed on after `t_ns`.
    fn after(&self, t_ns: u64) -> Vec<(u64, ImuSample)> {
        self.got
            .iter()
            .filter(|(t, _)| *t > t_ns)
            .copied()
            .collect()
    }
}

#[test]
fn steady_reading_never_restarts() {
    let mut b = Board::new(true);
    b.run_ms(500);
    assert_eq!(b.restarts, 0);
    // 8 samples per millisecond, within the one read in flight at the end.
    assert!(b.got.len() >= 3990, "{}", b.got.len());
    assert!(b.got.iter().all(|(_, s)| !s.flags.has(ImuFlags::DATA_LOST)));
}

/// Loses `loss` at 200 ms, runs to 600 ms; the time the interrupt was lost.
fn lose_at_200_ms(b: &mut Board, loss: Loss) -> u64 {
    b.run_ms(200);
    b.lose = Some(loss);
    b.run_ms(400);
    b.lost_at_ns.expect("the interrupt was lost")
}

#[test]
fn without_the_timer_a_lost_interrupt_stops_reading_for_good() {
    for loss in [Loss::Completion, Loss::Edge] {
        let mut b = Board::new(false);
        let lost = lose_at_200_ms(&mut b, loss);
        assert!(b.after(lost).is_empty(), "read again without a restart");
    }
}

#[test]
fn a_lost_interrupt_is_recovered_within_100_ms() {
    for loss in [Loss::Completion, Loss::Edge] {
        let mut b = Board::new(true);
        let lost = lose_at_200_ms(&mut b, loss);
        assert_eq!(b.restarts, 1);
        let after = b.after(lost);
        let (resumed, first) = after[0];
        assert!(
            resumed - lost <= 100_000_000,
            "resumed {} ms after the loss",
            (resumed - lost) / 1_000_000
        );
        // The gap is flagged on the first sample after it, and only there.
        assert!(first.flags.has(ImuFlags::DATA_LOST));
        assert!(after[1..]
            .iter()
            .all(|(_, s)| !s.flags.has(ImuFlags::DATA_LOST)));
        // Then 8 samples per millisecond again, their time stamps one period (125 µs) apart.
        let span_ms = (b.now_ns - resumed) / 1_000_000;
        assert!(
            after.len() as u64 >= 8 * span_ms,
            "{} in {span_ms} ms",
            after.len()
        );
        assert!(after
            .windows(2)
            .all(|w| w[1].1.timestamp.wrapping_sub(w[0].1.timestamp) == 125));
    }
}

/// A brown-out at 200 ms, then 600 ms more; samples after it.
fn brown_out_at_200_ms(b: &mut Board) -> Vec<(u64, ImuSample)> {
    b.run_ms(200);
    let at = b.now_ns;
    b.brown_out();
    b.run_ms(600);
    b.after(at)
}

#[test]
fn a_part_that_reset_is_never_read_again_without_the_register_check() {
    let mut b = Board::new(true);
    b.checking = false;
    let after = brown_out_at_200_ms(&mut b);
    assert!(after.is_empty(), "{} samples", after.len());
    assert!(b.restarts >= 5, "{} restarts", b.restarts);
}

#[test]
fn a_part_that_reset_is_started_again_and_read_within_200_ms() {
    let mut b = Board::new(true);
    let at = 200_000_000;
    let after = brown_out_at_200_ms(&mut b);
    assert_eq!(b.heals, 1);
    let (resumed, first) = after[0];
    assert!(
        resumed - at <= 200_000_000,
        "resumed {} ms after the brown-out",
        (resumed - at) / 1_000_000
    );
    assert!(first.flags.has(ImuFlags::DATA_LOST));
    // Then 8 samples per millisecond again.
    let span_ms = (b.now_ns - resumed) / 1_000_000;
    assert!(
        after.len() as u64 >= 8 * span_ms,
        "{} in {span_ms} ms",
        after.len()
    );
}

#[test]
fn an_intact_part_is_not_started_again_after_a_lost_interrupt() {
    for loss in [Loss::Completion, Loss::Edge] {
        let mut b = Board::new(true);
        lose_at_200_ms(&mut b, loss);
        assert_eq!((b.restarts, b.heals), (1, 0));
    }
}

/// One configured register written with another value at 200 ms, while the part runs on; 3 s
/// more. The samples after the write.
fn flip_at_200_ms(b: &mut Board, reg: u8, value: u8) -> Vec<(u64, ImuSample)> {
    b.run_ms(200);
    let at = b.now_ns;
    b.part
        .transaction(&mut [Operation::Write(&[reg, value])])
        .expect("the model's bus");
    b.run_ms(3000);
    b.after(at)
}

/// A round of the check: every checked register once, 100 ms apart, plus a tick and a watermark
/// interval for the chain that carries the read.
fn check_round_ns() -> u64 {
    let n = checked_registers(&CFG).len() as u64;
    (n * u64::from(CHECK_PERIOD_MS) + u64::from(STALL_TICK_MS) + 1) * 1_000_000
}

#[test]
fn a_range_changed_under_a_flowing_fifo_is_found_by_the_periodic_check() {
    let mut b = Board::new(true);
    // ±4 g (FS_SEL 2) at 8 kHz becomes ±16 g (FS_SEL 0): the FIFO flows on, its counts a quarter.
    let expected = b.part.register(0, ACCEL_CONFIG0);
    assert_eq!(expected >> 5, 2, "±4 g configured");
    let after = flip_at_200_ms(&mut b, ACCEL_CONFIG0 as u8, expected & 0x1F);
    // The data path never noticed: no stall, no gap until the part was started again.
    assert_eq!(b.restarts, 0, "no stall");
    assert_eq!(b.periodic_heals.len(), 1, "found and healed once");
    let healed = b.periodic_heals[0];
    let z = |s: &ImuSample| s.accel_out[2];
    // Between the change (and the packets already in the FIFO) and the heal: 1 g in ±16 g counts.
    let wrong: Vec<_> = after
        .iter()
        .filter(|(t, _)| *t > 202_000_000 && *t < healed)
        .collect();
    assert!(!wrong.is_empty());
    assert!(
        wrong
            .iter()
            .all(|(_, s)| (z(s) - 2048.0).abs() < 2.0 && !s.flags.has(ImuFlags::DATA_LOST)),
        "1 g read as 2048 counts, unflagged"
    );
    assert!(
        healed - 200_000_000 <= check_round_ns(),
        "healed {} ms after the change (a round: {} ms)",
        (healed - 200_000_000) / 1_000_000,
        check_round_ns() / 1_000_000
    );
    assert_eq!(
        b.part.register(0, ACCEL_CONFIG0),
        expected,
        "configured again"
    );
    // After the heal: the gap flagged once, then 1 g at ±4 g (8192 counts) again.
    let resumed: Vec<_> = after.iter().filter(|(t, _)| *t > healed).collect();
    assert!(resumed[0].1.flags.has(ImuFlags::DATA_LOST));
    assert!(resumed[1..]
        .iter()
        .all(|(_, s)| !s.flags.has(ImuFlags::DATA_LOST) && (z(s) - 8192.0).abs() < 2.0));
    let span_ms = (b.now_ns - resumed[0].0) / 1_000_000;
    assert!(
        resumed.len() as u64 >= 8 * span_ms,
        "{} in {span_ms} ms",
        resumed.len()
    );
}

#[test]
fn every_checked_register_changed_is_healed_within_a_round() {
    for (reg, value) in checked_registers(&CFG) {
        let mut b = Board::new(true);
        let after = flip_at_200_ms(&mut b, reg, value ^ 0x01);
        assert_eq!(b.heals, 1, "register {reg:#x}: healed once");
        let healed = b.heal_times[0];
        assert!(
            healed - 200_000_000 <= check_round_ns(),
            "register {reg:#x}: healed {} ms after the change",
            (healed - 200_000_000) / 1_000_000
        );
        assert_eq!(b.part.register(0, reg), value, "register {reg:#x} again");
        // Reading goes on at 8 samples per millisecond after the heal.
        let last_s = after
            .iter()
            .filter(|(t, _)| *t > b.now_ns - 1_000_000_000)
            .count();
        assert!(
            last_s >= 7990,
            "register {reg:#x}: {last_s} samples in the last second"
        );
    }
}

#[test]
fn an_intact_part_is_checked_but_never_started_again() {
    let mut b = Board::new(true);
    b.run_ms(3000);
    assert_eq!((b.restarts, b.heals), (0, 0));
    assert!(b.got.len() >= 23_990, "{}", b.got.len());
    assert!(b.got.iter().all(|(_, s)| !s.flags.has(ImuFlags::DATA_LOST)));
}
