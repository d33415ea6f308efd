//! Reading the ICM-42688-P's FIFO as a chain of full-duplex SPI bursts that DMA moves, with the
//! driver's own decisions ([`Core`]) in between — the board only starts streams and toggles CS.
//!
//! Per watermark interrupt (INT1, latched until INT_STATUS is read):
//!
//! 1. **status**: 4 bytes from INT_STATUS — INT_STATUS, FIFO_COUNTH, FIFO_COUNTL (clears INT1;
//!    `Core::plan_read` notes an overflow and sizes the read);
//! 2. **FIFO**: 1 + n·packet bytes from FIFO_DATA (n ≤ [`BATCH_PACKETS`]), decoded by
//!    `Core::decode` (time-stamp gaps and overflow flagged on the samples); if the FIFO held more,
//!    back to 1 at once;
//! 3. **flush** (only after a FIFO read out of step): SIGNAL_PATH_RESET ← FIFO_FLUSH; the next
//!    sample is flagged as following lost data;
//! 4. **register check** (every [`CHECK_PERIOD_MS`], at the end of a chain, and at the end of the
//!    chain after a failure): one configured register read back, 2 bytes
//!    ([`crate::imu::icm42688::check::RegisterCheck`], round robin).
//!
//! **The register check** is PX4's (`ICM42688P.cpp`, `RunImpl`: one register per bank read back
//! between FIFO reads when more than 100 ms passed since the last check, or right after a failure;
//! `Reset()` on a mismatch). Here it is one more burst of the chain, so it costs no CPU wait and
//! never meets a FIFO read on the bus: the chain still holds the bus, a watermark meanwhile only
//! notes a status read to follow. A register that differs ends the chain's bursts with
//! [`Completed::mismatch`] while the chain keeps the bus; the board starts the part again over the
//! CPU-driven bus (`imu::icm42688::check::restart`), counts a re-init, and hands the fresh state to
//! [`BurstReader::resume_after_heal`], which frees the bus. A changed register is found within one
//! round of the list (at most [`crate::imu::icm42688::check::MAX_CHECKED`] × 100 ms, plus a
//! watermark interval for the chain to end), whether or not the FIFO keeps flowing (tested on the
//! PC: `imu::tests::bursts_stall`). Cost: a 2-byte burst and two interrupts ten times a second.
//!
//! **A chain that stalls.** If one interrupt of the chain is lost (a DMA completion that never
//! comes, or a watermark edge missed while INT1 is latched high), nothing would ever read the part
//! again: the chain stays "under way", INT1 stays high and gives no new edge. A board ticks the
//! reader every [`STALL_TICK_MS`] from a timer ([`BurstReader::on_tick`]); after more than
//! [`STALL_TIMEOUT_MS`] without a completed burst (a watermark comes every millisecond or so) it
//! starts over as PX4's ICM42688P driver does from its "backup schedule as a watchdog timeout"
//! (`ICM42688P.cpp`, `RunImpl`, `ScheduleDelayed(100_ms)`, commit 00d281a): the FIFO flushed, then
//! INT_STATUS read, which releases INT1; the next sample is flagged as following lost data. Reading
//! resumes within 100 ms of the lost interrupt (tested on the PC against the register model:
//! `imu::tests::bursts_stall`).
//!
//! The same bytes the blocking driver's `drain` moves (`imu::icm42688::Icm42688`), so the register
//! model tests of the driver cover the protocol; the tests here cover the chaining.

use core::sync::atomic::{AtomicU8, Ordering};

use crate::imu::icm42688::check::RegisterCheck;
use crate::imu::icm42688::regs::{
    FIFO_DATA, FIFO_FLUSH, INT_STATUS, PACKET4_LEN, READ, SIGNAL_PATH_RESET,
};
use crate::imu::icm42688::{Core, BATCH_PACKETS};
use crate::imu::{ImuFlags, ImuSample};

/// Longest burst: the address byte and a batch of the largest packets.
pub const BURST_MAX: usize = 1 + BATCH_PACKETS * PACKET4_LEN;

/// Status burst: the address, then INT_STATUS, FIFO_COUNTH, FIFO_COUNTL come back.
pub static STATUS_CMD: [u8; 4] = [INT_STATUS as u8 | READ, 0, 0, 0];
/// FIFO burst (sent as its first 1 + n bytes): the address, then dummy bytes while packets come back.
pub static FIFO_CMD: [u8; BURST_MAX] = {
    let mut c = [0u8; BURST_MAX];
    c[0] = FIFO_DATA as u8 | READ;
    c
};
/// FIFO flush: a register write.
pub static FLUSH_CMD: [u8; 2] = [SIGNAL_PATH_RESET as u8, FIFO_FLUSH];
/// The register check's one-register reads, by address: the address with the read bit, then a
/// dummy byte while the value comes back (the ICM-42688-P sends no dummy byte before it).
pub static REG_READ_CMD: [[u8; 2]; 128] = {
    let mut c = [[0u8; 2]; 128];
    let mut r = 0;
    while r < 128 {
        c[r][0] = r as u8 | READ;
        r += 1;
    }
    c
};
/// The register check's period, ms (PX4's 100 ms).
pub const CHECK_PERIOD_MS: u32 = 100;

/// An all-zero sample, to initialise the decoded-sample buffer (`ImuSample::default` is not const).
pub const NO_SAMPLE: ImuSample = ImuSample {
    accel_out: [0.0; 3],
    gyro_rad_s: [0.0; 3],
    temp_c: 0.0,
    timestamp: 0,
    lost_before: 0,
    flags: ImuFlags(0),
};

/// A burst to put on the wire: `tx` out, as many bytes back into the receive buffer.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Burst {
    /// The bytes to send (a prefix of one of the command statics).
    pub tx: &'static [u8],
}

impl Burst {
    /// Bytes on the wire.
    pub fn len(&self) -> usize {
        self.tx.len()
    }

    /// Never: a burst has at least its address byte.
    pub fn is_empty(&self) -> bool {
        self.tx.is_empty()
    }
}

#[derive(Clone, Copy, Debug, PartialEq, Eq)]
enum Phase {
    Status,
    Fifo {
        bytes: usize,
        more: bool,
    },
    Flush,
    /// The flush of a stalled chain's restart; a status read follows.
    Restart,
    /// The register check's read of `reg`, which must hold `expected`.
    Check {
        reg: u8,
        expected: u8,
    },
    /// The check found a register changed: the board starts the part again, the chain keeps the
    /// bus until [`BurstReader::resume_after_heal`].
    Heal,
}

/// A chain without a completed burst for longer than this is presumed stalled, ms (or four
/// watermark intervals, if longer: a slow configuration's chains are that far apart).
pub const STALL_TIMEOUT_MS: u32 = 80;
/// How often a board calls [`BurstReader::on_tick`], ms: a stall is acted on between 80 and
/// 90 ms after the last completed burst, and reading resumes at the next watermark.
pub const STALL_TICK_MS: u32 = 10;

/// Whether a burst chain runs: set by the watermark interrupt, ended by the completion task. An
/// atomic, so the watermark interrupt never waits for the completion task.
///
/// A watermark that arrives while a chain runs is remembered: INT1 is latched until INT_STATUS is
/// read, so if the chain ended without reading it again, INT1 would stay high with no new edge and
/// reading would stop for good. The chain then reads the status once more instead of ending.
///
/// The BMI270's data-ready reading (`imu::bmi270::dma`) uses it too, with its sample burst as the
/// command an interrupt starts ([`Self::with_command`]).
pub struct InFlight {
    state: AtomicU8,
    /// The burst an interrupt starts (and a chain's end, when one came meanwhile).
    cmd: &'static [u8],
}

const IDLE: u8 = 0;
const BUSY: u8 = 1;
const BUSY_AND_PENDING: u8 = 2;

impl InFlight {
    /// Idle; an interrupt starts the status burst.
    pub const fn new() -> Self {
        Self::with_command(&STATUS_CMD)
    }

    /// Idle; an interrupt starts `cmd`.
    pub const fn with_command(cmd: &'static [u8]) -> Self {
        InFlight {
            state: AtomicU8::new(IDLE),
            cmd,
        }
    }

    /// The watermark interrupt: the status burst to start, or `None` while a chain runs (it will
    /// read the status again before it ends).
    #[inline]
    pub fn on_watermark(&self) -> Option<Burst> {
        // Single core: the completion task cannot run between the load and the store (it has a
        // lower priority than the watermark interrupt, the only caller).
        match self.state.load(Ordering::Acquire) {
            IDLE => {
                self.state.store(BUSY, Ordering::Release);
                Some(Burst { tx: self.cmd })
            }
            _ => {
                self.state.store(BUSY_AND_PENDING, Ordering::Release);
                None
            }
        }
    }

    /// A stalled chain's restart takes the bus, whatever the state was (the watermark interrupt
    /// then only notes a pending status read).
    pub(crate) fn take_over(&self) {
        self.state.store(BUSY, Ordering::Release);
    }

    /// The chain has nothing more to read: it ends, or goes on with a status read if a watermark
    /// came meanwhile.
    pub(crate) fn end(&self) -> Option<Burst> {
        match self
            .state
            .compare_exchange(BUSY, IDLE, Ordering::AcqRel, Ordering::Acquire)
        {
            Ok(_) => None,
            Err(_) => {
                self.state.store(BUSY, Ordering::Release);
                Some(Burst { tx: self.cmd })
            }
        }
    }
}

impl Default for InFlight {
    fn default() -> Self {
        Self::new()
    }
}

/// A register the check found changed.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Mismatch {
    /// The register (bank 0).
    pub reg: u8,
    /// The value the configuration wrote.
    pub expected: u8,
    /// What it read.
    pub read: u8,
}

/// What one completed burst gave.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Completed {
    /// Samples decoded into the front of the output slice.
    pub samples: usize,
    /// The next burst of the chain (`None`: the chain ended, the bus is free).
    pub next: Option<Burst>,
    /// The FIFO read back out of step (this header); a flush burst follows.
    pub corrupt_header: Option<u8>,
    /// The register check found this register changed: the part must be started again, then
    /// [`BurstReader::resume_after_heal`] (the chain keeps the bus meanwhile; `next` is `None`).
    pub mismatch: Option<Mismatch>,
}

/// The completion side of the chain: owns the driver's [`Core`].
pub struct BurstReader {
    core: Core,
    phase: Phase,
    /// Time since the last completed burst, ms (in [`STALL_TICK_MS`] steps).
    quiet_ms: u32,
    /// [`STALL_TIMEOUT_MS`], or four watermark intervals if longer.
    stall_after_ms: u32,
    /// The configured registers, one read back per check.
    check: RegisterCheck,
    /// Time since the last register check, ms (in [`STALL_TICK_MS`] steps); a check is due at
    /// [`CHECK_PERIOD_MS`].
    since_check_ms: u32,
}

impl BurstReader {
    /// Around a configured driver's state (the part already configured over the blocking bus).
    pub fn new(core: Core) -> Self {
        let cfg = *core.config();
        let watermark_ms = u32::from(cfg.watermark_packets) * u32::from(cfg.odr.period_us()) / 1000;
        BurstReader {
            core,
            phase: Phase::Status,
            quiet_ms: 0,
            stall_after_ms: STALL_TIMEOUT_MS.max(4 * watermark_ms),
            check: RegisterCheck::new(&cfg),
            since_check_ms: 0,
        }
    }

    /// The configured rate, Hz.
    pub fn sample_rate_hz(&self) -> u32 {
        self.core.sample_rate_hz()
    }

    /// Bytes of the burst on the wire (what [`Self::on_complete`] will want back).
    pub fn expected_len(&self) -> usize {
        match self.phase {
            Phase::Status => STATUS_CMD.len(),
            Phase::Fifo { bytes, .. } => 1 + bytes,
            Phase::Flush | Phase::Restart => FLUSH_CMD.len(),
            Phase::Check { .. } | Phase::Heal => 2,
        }
    }

    /// Called every [`STALL_TICK_MS`] by a board's timer. After more than [`STALL_TIMEOUT_MS`]
    /// (or four watermark intervals) without a completed burst, the restart burst to put on the wire at once, in place of
    /// whatever the stalled chain left there (the FIFO flush; its completion goes on with a status
    /// read). The next sample is flagged as following lost data.
    ///
    /// It also times the register check: one is due [`CHECK_PERIOD_MS`] after the last.
    pub fn on_tick(&mut self, in_flight: &InFlight) -> Option<Burst> {
        self.since_check_ms = self.since_check_ms.saturating_add(STALL_TICK_MS);
        self.quiet_ms = self.quiet_ms.saturating_add(STALL_TICK_MS);
        if self.quiet_ms <= self.stall_after_ms {
            return None;
        }
        self.quiet_ms = 0;
        self.core.corrupted();
        self.phase = Phase::Restart;
        in_flight.take_over();
        Some(Burst { tx: &FLUSH_CMD })
    }

    /// Goes on with `core`, the state of a part started again after a register check found its
    /// configuration lost (`imu::icm42688::check`); the next sample is flagged as following lost
    /// data. The chain's restart burst from [`Self::on_tick`] still goes on the wire.
    pub fn replace_core(&mut self, core: Core) {
        self.core = core;
        self.core.corrupted();
    }

    /// The burst failed on the bus: the chain ends, and since packets may have been lost with it,
    /// the next sample is flagged as following lost data.
    /// A register check is due at the next chain's end (PX4: "immediately following any failure").
    pub fn abandon(&mut self, in_flight: &InFlight) -> Completed {
        self.core.corrupted();
        self.phase = Phase::Status;
        self.since_check_ms = CHECK_PERIOD_MS;
        Completed {
            samples: 0,
            next: in_flight.end(),
            corrupt_header: None,
            mismatch: None,
        }
    }

    /// After [`Completed::mismatch`]: the board started the part again (`Some`: its fresh state;
    /// `None`: the start failed, and the next check, 100 ms on, finds the register changed again
    /// and tries again). The next sample is flagged as following lost data; the chain ends (or
    /// reads the status of a watermark that came meanwhile), freeing the bus.
    pub fn resume_after_heal(&mut self, core: Option<Core>, in_flight: &InFlight) -> Option<Burst> {
        if let Some(core) = core {
            self.core = core;
        }
        self.core.corrupted();
        self.quiet_ms = 0;
        self.phase = Phase::Status;
        in_flight.end()
    }

    /// The chain has nothing more to read: the register check's read if one is due, else the end
    /// (or the status read of a watermark that came meanwhile).
    fn chain_end(&mut self, in_flight: &InFlight) -> Option<Burst> {
        if self.since_check_ms >= CHECK_PERIOD_MS {
            if let Some((reg, expected)) = self.check.current() {
                self.phase = Phase::Check { reg, expected };
                return Some(Burst {
                    tx: &REG_READ_CMD[usize::from(reg & 0x7F)],
                });
            }
        }
        self.phase = Phase::Status;
        in_flight.end()
    }

    /// A burst finished; `rx` holds the bytes that came back (as many as were sent). Decoded samples
    /// go to `out` (room for [`BATCH_PACKETS`]).
    pub fn on_complete(
        &mut self,
        rx: &[u8],
        out: &mut [ImuSample; BATCH_PACKETS],
        in_flight: &InFlight,
    ) -> Completed {
        let mut done = Completed {
            samples: 0,
            next: None,
            corrupt_header: None,
            mismatch: None,
        };
        self.quiet_ms = 0;
        let next = match self.phase {
            Phase::Status => {
                let status = [byte(rx, 1), byte(rx, 2), byte(rx, 3)];
                let (bytes, more) = self.core.plan_read(status, BATCH_PACKETS);
                (bytes > 0).then(|| {
                    self.phase = Phase::Fifo { bytes, more };
                    Burst {
                        tx: &FIFO_CMD[..1 + bytes],
                    }
                })
            }
            Phase::Fifo { bytes, more } => {
                let got = rx.len().saturating_sub(1).min(bytes);
                match self.core.decode(&rx[1..1 + got], out) {
                    Ok(n) => {
                        done.samples = n;
                        more.then(|| {
                            self.phase = Phase::Status;
                            Burst { tx: &STATUS_CMD }
                        })
                    }
                    Err(header) => {
                        done.corrupt_header = Some(header);
                        // PX4 checks the registers right after a failure: at this chain's end.
                        self.since_check_ms = CHECK_PERIOD_MS;
                        self.phase = Phase::Flush;
                        Some(Burst { tx: &FLUSH_CMD })
                    }
                }
            }
            Phase::Flush | Phase::Heal => None,
            Phase::Restart => {
                self.phase = Phase::Status;
                Some(Burst { tx: &STATUS_CMD })
            }
            Phase::Check { reg, expected } => {
                self.since_check_ms = 0;
                let read = byte(rx, 1);
                if read != expected {
                    // The chain keeps the bus while the board starts the part again.
                    self.phase = Phase::Heal;
                    done.mismatch = Some(Mismatch {
                        reg,
                        expected,
                        read,
                    });
                    return done;
                }
                self.check.advance();
                None
            }
        };
        done.next = match next {
            Some(b) => Some(b),
            None => self.chain_end(in_flight),
        };
        done
    }
}

fn byte(rx: &[u8], i: usize) -> u8 {
    rx.get(i).copied().unwrap_or(0)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::imu::icm42688::check::checked_registers;
    use crate::imu::icm42688::regs::{HEADER_PACKET3, INT_FIFO_FULL, INT_FIFO_THS, PACKET3_LEN};
    use crate::imu::icm42688::Config;

    /// A packet 3 as the datasheet lays it out (§6.1): header, accel and gyro big-endian, 8-bit
    /// temperature, 16-bit time stamp.
    fn packet(accel: [i16; 3], gyro: [i16; 3], temp: i8, ts: u16) -> [u8; PACKET3_LEN] {
        let mut p = [0u8; PACKET3_LEN];
        p[0] = HEADER_PACKET3;
        for i in 0..3 {
            p[1 + 2 * i..3 + 2 * i].copy_from_slice(&accel[i].to_be_bytes());
            p[7 + 2 * i..9 + 2 * i].copy_from_slice(&gyro[i].to_be_bytes());
        }
        p[13] = temp as u8;
        p[14..16].copy_from_slice(&ts.to_be_bytes());
        p
    }

    /// What comes back for a FIFO burst: the address byte's slot, then the packets.
    fn fifo_rx(packets: &[[u8; PACKET3_LEN]]) -> Vec<u8> {
        let mut rx = vec![0xFF];
        for p in packets {
            rx.extend_from_slice(p);
        }
        rx
    }

    fn reader() -> BurstReader {
        let cfg = Config {
            watermark_packets: 8,
            ..Config::DEFAULT
        };
        BurstReader::new(Core::new(cfg).unwrap())
    }

    #[test]
    fn status_then_counted_fifo_read_then_idle() {
        let busy = InFlight::new();
        let mut r = reader();
        let mut out = [NO_SAMPLE; BATCH_PACKETS];
        let first = busy.on_watermark().expect("idle bus: a burst starts");
        assert_eq!(first.tx, &[INT_STATUS as u8 | READ, 0, 0, 0]);
        assert_eq!(busy.on_watermark(), None, "one chain at a time");
        assert_eq!(r.expected_len(), 4);
        // INT_STATUS: watermark; FIFO_COUNT = 3 records (big-endian).
        let done = r.on_complete(&[0xFF, INT_FIFO_THS, 0, 3], &mut out, &busy);
        assert_eq!(done.samples, 0);
        let fifo = done.next.expect("a FIFO read of the counted packets");
        assert_eq!(fifo.len(), 1 + 3 * PACKET3_LEN);
        assert_eq!(fifo.tx[0], FIFO_DATA as u8 | READ);
        assert_eq!(r.expected_len(), fifo.len());
        // 1 kHz: time stamps 1000 µs apart.
        let pk = [
            packet([2048, -4096, 1], [164, 0, -164], 0, 1000),
            packet([0, 0, 2048], [0, 0, 0], 21, 2000),
            packet([7, 8, 9], [1, 2, 3], -21, 3000),
        ];
        let done = r.on_complete(&fifo_rx(&pk), &mut out, &busy);
        assert_eq!(done.samples, 3);
        assert_eq!(done.corrupt_header, None);
        // The second watermark above came during the chain: one more status read, then the end.
        let status = done.next.expect("the pending watermark's status read");
        assert_eq!(status.tx, &STATUS_CMD[..]);
        let last = r.on_complete(&[0xFF, 0, 0, 0], &mut [NO_SAMPLE; BATCH_PACKETS], &busy);
        assert_eq!(last.next, None, "nothing more waited: the chain ends");
        // Counts (unit 1 per LSB), 16.4 LSB per °/s, 2.07 LSB per °C around 25 °C.
        assert_eq!(out[0].accel_out, [2048.0, -4096.0, 1.0]);
        assert!((out[0].gyro_rad_s[0] - 10f32.to_radians()).abs() < 1e-6);
        assert!((out[1].temp_c - (25.0 + 21.0 / 2.07)).abs() < 1e-4);
        assert_eq!(out[2].timestamp, 3000);
        assert!(out.iter().take(3).all(|s| s.flags.0 == 0));
        assert!(busy.on_watermark().is_some(), "the bus is free again");
    }

    #[test]
    fn a_fuller_fifo_is_read_in_batches_until_empty() {
        let busy = InFlight::new();
        let mut r = reader();
        let mut out = [NO_SAMPLE; BATCH_PACKETS];
        busy.on_watermark();
        let next = r
            .on_complete(&[0xFF, INT_FIFO_THS, 0, 20], &mut out, &busy)
            .next;
        assert_eq!(next.map(|b| b.len()), Some(1 + BATCH_PACKETS * PACKET3_LEN));
        let pk: Vec<_> = (0..BATCH_PACKETS as u16)
            .map(|k| packet([k as i16; 3], [0; 3], 0, 1000 * (k + 1)))
            .collect();
        let done = r.on_complete(&fifo_rx(&pk), &mut out, &busy);
        assert_eq!(done.samples, BATCH_PACKETS);
        assert_eq!(
            done.next.map(|b| b.tx),
            Some(&STATUS_CMD[..]),
            "4 more: status again"
        );
        assert_eq!(busy.on_watermark(), None, "still the same chain");
        let next = r.on_complete(&[0xFF, 0, 0, 4], &mut out, &busy).next;
        assert_eq!(next.map(|b| b.len()), Some(1 + 4 * PACKET3_LEN));
    }

    #[test]
    fn a_watermark_during_a_chain_gets_its_own_status_read() {
        // INT1 is latched: a watermark that came while the chain ran must be read before the chain
        // ends, or INT1 stays high and no edge ever comes again.
        let busy = InFlight::new();
        let mut r = reader();
        let mut out = [NO_SAMPLE; BATCH_PACKETS];
        busy.on_watermark();
        r.on_complete(&[0xFF, INT_FIFO_THS, 0, 1], &mut out, &busy);
        assert_eq!(busy.on_watermark(), None, "during the FIFO read");
        let done = r.on_complete(
            &fifo_rx(&[packet([0; 3], [0; 3], 0, 1000)]),
            &mut out,
            &busy,
        );
        assert_eq!(done.samples, 1);
        assert_eq!(
            done.next.map(|b| b.tx),
            Some(&STATUS_CMD[..]),
            "status read again"
        );
        assert_eq!(r.expected_len(), 4);
        let done = r.on_complete(&[0xFF, 0, 0, 0], &mut out, &busy);
        assert_eq!(done.next, None, "nothing came meanwhile: now it ends");
        assert!(busy.on_watermark().is_some());
    }

    #[test]
    fn empty_status_ends_the_chain() {
        let busy = InFlight::new();
        let mut r = reader();
        let mut out = [NO_SAMPLE; BATCH_PACKETS];
        busy.on_watermark();
        let done = r.on_complete(&[0xFF, 0, 0, 0], &mut out, &busy);
        assert_eq!(done.next, None);
        assert!(busy.on_watermark().is_some());
    }

    #[test]
    fn out_of_step_fifo_is_flushed_and_the_next_sample_flagged() {
        let busy = InFlight::new();
        let mut r = reader();
        let mut out = [NO_SAMPLE; BATCH_PACKETS];
        busy.on_watermark();
        r.on_complete(&[0xFF, INT_FIFO_THS, 0, 1], &mut out, &busy);
        let mut bad = packet([0; 3], [0; 3], 0, 1000);
        bad[0] = 0x12; // not a packet 3 header
        let done = r.on_complete(&fifo_rx(&[bad]), &mut out, &busy);
        assert_eq!(done.corrupt_header, Some(0x12));
        assert_eq!(done.next.map(|b| b.tx), Some(&FLUSH_CMD[..]));
        assert_eq!(r.expected_len(), 2);
        // After a failure the register check runs at once (PX4), its first register's read.
        let (reg, value) = checked_registers(r.core.config())[0];
        let done = r.on_complete(&[0xFF, 0xFF], &mut out, &busy);
        assert_eq!(done.next.map(|b| b.tx), Some(&[reg | READ, 0][..]));
        let done = r.on_complete(&[0xFF, value], &mut out, &busy);
        assert_eq!(done.next, None, "the register held: the chain ends");
        busy.on_watermark();
        r.on_complete(&[0xFF, INT_FIFO_THS, 0, 1], &mut out, &busy);
        let done = r.on_complete(
            &fifo_rx(&[packet([1; 3], [0; 3], 0, 5000)]),
            &mut out,
            &busy,
        );
        assert_eq!(done.samples, 1);
        assert!(
            out[0].flags.has(ImuFlags::DATA_LOST),
            "what follows a flush follows a gap"
        );
    }

    /// Ticks the reader for `ms` (no stall: a burst completes between the ticks).
    fn tick_ms(r: &mut BurstReader, busy: &InFlight, ms: u32) {
        for _ in 0..ms / STALL_TICK_MS {
            assert_eq!(r.on_tick(busy), None);
            r.quiet_ms = 0;
        }
    }

    /// One chain: a watermark, a status read finding one packet, the packet (time stamp `ts`).
    fn chain(r: &mut BurstReader, busy: &InFlight, ts: u16) -> Completed {
        let mut out = [NO_SAMPLE; BATCH_PACKETS];
        assert!(busy.on_watermark().is_some());
        r.on_complete(&[0xFF, INT_FIFO_THS, 0, 1], &mut out, busy);
        r.on_complete(&fifo_rx(&[packet([0; 3], [0; 3], 0, ts)]), &mut out, busy)
    }

    #[test]
    fn every_100_ms_a_chain_ends_with_one_register_read_round_robin() {
        let busy = InFlight::new();
        let mut r = reader();
        let regs = checked_registers(r.core.config());
        let mut out = [NO_SAMPLE; BATCH_PACKETS];
        assert_eq!(chain(&mut r, &busy, 1000).next, None, "no check yet");
        let mut ts = 1000;
        for &(reg, value) in regs.iter().chain(&regs[..2]) {
            tick_ms(&mut r, &busy, CHECK_PERIOD_MS - STALL_TICK_MS);
            ts += 1000;
            assert_eq!(chain(&mut r, &busy, ts).next, None, "99 ms: not yet");
            tick_ms(&mut r, &busy, STALL_TICK_MS);
            ts += 1000;
            let done = chain(&mut r, &busy, ts);
            assert_eq!(done.next.map(|b| b.tx), Some(&[reg | READ, 0][..]));
            assert_eq!(busy.on_watermark(), None, "the check holds the bus");
            let done = r.on_complete(&[0xFF, value], &mut out, &busy);
            assert_eq!(done.mismatch, None);
            // The watermark that came during the check: its status read.
            assert_eq!(done.next.map(|b| b.tx), Some(&STATUS_CMD[..]));
            assert_eq!(r.on_complete(&[0xFF, 0, 0, 0], &mut out, &busy).next, None);
        }
    }

    #[test]
    fn a_changed_register_keeps_the_bus_until_the_part_is_started_again() {
        let busy = InFlight::new();
        let mut r = reader();
        let (reg, value) = checked_registers(r.core.config())[0];
        let mut out = [NO_SAMPLE; BATCH_PACKETS];
        tick_ms(&mut r, &busy, CHECK_PERIOD_MS);
        assert!(chain(&mut r, &busy, 1000).next.is_some());
        let done = r.on_complete(&[0xFF, value ^ 0x40], &mut out, &busy);
        assert_eq!(
            done.mismatch,
            Some(Mismatch {
                reg,
                expected: value,
                read: value ^ 0x40
            })
        );
        assert_eq!(done.next, None);
        assert_eq!(busy.on_watermark(), None, "the bus stays taken");
        let fresh = Core::new(*r.core.config()).unwrap();
        // The watermark during the heal is read; the first sample follows a gap.
        let next = r.resume_after_heal(Some(fresh), &busy);
        assert_eq!(next.map(|b| b.tx), Some(&STATUS_CMD[..]));
        r.on_complete(&[0xFF, INT_FIFO_THS, 0, 1], &mut out, &busy);
        r.on_complete(
            &fifo_rx(&[packet([0; 3], [0; 3], 0, 9000)]),
            &mut out,
            &busy,
        );
        assert!(out[0].flags.has(ImuFlags::DATA_LOST));
        // The same register is read again at the next check.
        tick_ms(&mut r, &busy, CHECK_PERIOD_MS);
        let done = chain(&mut r, &busy, 10_000);
        assert_eq!(done.next.map(|b| b.tx), Some(&[reg | READ, 0][..]));
    }

    #[test]
    fn overflow_and_time_stamp_gap_are_flagged() {
        let busy = InFlight::new();
        let mut r = reader();
        let mut out = [NO_SAMPLE; BATCH_PACKETS];
        busy.on_watermark();
        // FIFO full (stop-on-full): the 2 packets present precede the gap.
        r.on_complete(&[0xFF, INT_FIFO_FULL, 0, 2], &mut out, &busy);
        let pk = [
            packet([0; 3], [0; 3], 0, 1000),
            packet([0; 3], [0; 3], 0, 2000),
        ];
        let done = r.on_complete(&fifo_rx(&pk), &mut out, &busy);
        assert_eq!(done.samples, 2);
        assert!(!out[0].flags.has(ImuFlags::DATA_LOST) && !out[1].flags.has(ImuFlags::DATA_LOST));
        busy.on_watermark();
        r.on_complete(&[0xFF, INT_FIFO_THS, 0, 1], &mut out, &busy);
        // 5 periods later: 4 samples lost.
        let done = r.on_complete(
            &fifo_rx(&[packet([0; 3], [0; 3], 0, 7000)]),
            &mut out,
            &busy,
        );
        assert_eq!(done.samples, 1);
        assert!(out[0].flags.has(ImuFlags::DATA_LOST));
        assert_eq!(out[0].lost_before, 4);
    }

    #[test]
    fn a_failed_burst_ends_the_chain_and_flags_the_next_sample() {
        let busy = InFlight::new();
        let mut r = reader();
        let mut out = [NO_SAMPLE; BATCH_PACKETS];
        busy.on_watermark();
        r.on_complete(&[0xFF, INT_FIFO_THS, 0, 1], &mut out, &busy);
        let done = r.abandon(&busy);
        assert_eq!((done.samples, done.next), (0, None));
        assert_eq!(
            r.expected_len(),
            4,
            "the next chain starts with a status read"
        );
        busy.on_watermark();
        r.on_complete(&[0xFF, INT_FIFO_THS, 0, 1], &mut out, &busy);
        r.on_complete(
            &fifo_rx(&[packet([0; 3], [0; 3], 0, 1000)]),
            &mut out,
            &busy,
        );
        assert!(out[0].flags.has(ImuFlags::DATA_LOST));
    }
}
