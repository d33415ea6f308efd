//! The BMI270 read without the CPU: each data-ready edge starts one full-duplex DMA burst, and its
//! completion decodes the sample — the board only starts streams and toggles CS, as the F405's
//! ICM-42688-P chain does (`crate::imu_bursts`, the same DMA2 streams 2 and 3 on SPI1).
//!
//! **Why data ready and one burst, not the FIFO.** Betaflight reads the BMI270 this way
//! (`src/main/drivers/accgyro/accgyro_spi_bmi270.c`, its default, not `fifoMode`): INT_MAP_DATA
//! maps data ready to INT1, `bmi270ExtiHandler` starts one DMA segment per rising edge
//! (`spiSequence`) reading ACC_X…GYR_Z behind the address and the dummy byte (`IDX_REG`,
//! `IDX_SKIP`), and `bmi270Intcallback`, the segment's completion, marks the data ready. ArduPilot
//! (`libraries/AP_InertialSensor/AP_InertialSensor_BMI270.cpp`, `read_fifo`) polls the FIFO
//! every millisecond instead: fewer transfers, but frames of mixed sensors to pair and 1.6 kHz
//! samples batched behind a 1 ms timer. Here one sample per burst keeps the decode the blocking
//! driver's (one frame, [`Decoder`]), needs no pairing, and costs the CPU two short interrupts per
//! sample instead of the ~50 µs blocking read (about 8 % of the CPU at 1.6 kHz) it replaces.
//!
//! **The frame**: STATUS (0x03) through TEMPERATURE_1 (0x23), 33 registers in one burst after the
//! address and the dummy byte (35 bytes, 53 µs of bus at 5.25 MHz, no CPU): the data-ready bits,
//! the accelerometer, the gyro, SENSORTIME, then EVENT, INT_STATUS_0/1, SC_OUT, WR_GEST_ACT and
//! INTERNAL_STATUS (clear-on-read status of features this firmware does not map: harmless to
//! read), and the temperature. The blocking driver reads the same frame
//! ([`super::Bmi270`]'s drain), so the register model's tests of the driver cover the decode.
//!
//! **The register check** stays PX4's pattern (`BMI088_Accelerometer.cpp` `RunImpl`: one
//! register per check, `if (hrt_elapsed_time(&_last_config_check_timestamp) > 100_ms)`, `Reset()`
//! on a mismatch): every [`CHECK_PERIOD_MS`] the burst after a sample reads one configured register
//! back (3 bytes: address, dummy, value), round robin over `Config::registers`. A mismatch keeps
//! the bus while the board starts the part again over the CPU-driven bus
//! ([`Bmi270Bursts::resume_after_heal`]). A brown-out stops data ready altogether: the stall
//! timer ([`Bmi270Bursts::on_tick`], as the ICM's chain) reads a frame after 80 ms without a
//! completed burst, and the check follows it.

use super::regs::{
    Reg, ACC_X, GYR_X, READ, SENSORTIME_0, STATUS, STATUS_DRDY_ACC, STATUS_DRDY_GYR, TEMPERATURE_0,
    TEMPERATURE_INVALID,
};
use super::Config;
use crate::imu::{lost_between, ImuFlags, ImuSample};
use crate::imu_bursts::{Burst, InFlight, Mismatch, STALL_TICK_MS, STALL_TIMEOUT_MS};

/// Registers of one sample's frame: STATUS through TEMPERATURE_1.
pub const FRAME_LEN: usize = (TEMPERATURE_0 as u8 + 2 - STATUS as u8) as usize;
/// A sample burst on the wire: the address, the dummy byte, the frame.
pub const BURST_LEN: usize = 2 + FRAME_LEN;
/// The sample burst: the address with the read bit, then dummy bytes.
pub static SAMPLE_CMD: [u8; BURST_LEN] = {
    let mut c = [0u8; BURST_LEN];
    c[0] = STATUS as u8 | READ;
    c
};
/// The register check's reads, by address: the address, the dummy byte, the value.
pub static CHECK_CMD: [[u8; 3]; 128] = {
    let mut c = [[0u8; 3]; 128];
    let mut r = 0;
    while r < 128 {
        c[r][0] = r as u8 | READ;
        r += 1;
    }
    c
};
/// The register check's period, ms (PX4's 100 ms): the 8 registers in 0.8 s.
pub const CHECK_PERIOD_MS: u32 = 100;

/// The gyro's scale: ±2000 °/s over 32768 counts, in rad/s per count.
const GYRO_RAD_S_PER_LSB: f32 = 2000.0 / 32768.0 * (core::f32::consts::PI / 180.0);

/// A frame's sample and the gap check between frames.
#[derive(Clone, Debug)]
pub struct Decoder {
    /// One period in SENSORTIME ticks.
    ticks: u16,
    /// The previous sample's SENSORTIME, low 16 bits (`None` before the first).
    last_time: Option<u16>,
    /// The next sample follows a gap of unknown length (a stall, a failed burst, a re-init).
    lost_pending: bool,
}

impl Decoder {
    /// For `cfg`'s rate, before the first sample.
    pub const fn new(cfg: &Config) -> Self {
        Decoder {
            ticks: cfg.odr.ticks(),
            last_time: None,
            lost_pending: false,
        }
    }

    /// Samples were lost (how many is unknown): the next one is flagged, and its time stamp starts
    /// the gap check again.
    pub fn after_gap(&mut self) {
        self.last_time = None;
        self.lost_pending = true;
    }

    /// The frame's sample, if both sensors had new data ([`Self::decode_into`]).
    pub fn decode(&mut self, f: &[u8; FRAME_LEN]) -> Option<ImuSample> {
        let mut s = ImuSample::default();
        self.decode_into(f, &mut s).then_some(s)
    }

    /// Decodes the frame into `out` if both sensors had new data (false: `out` untouched): counts
    /// as `f32`, the gyro in rad/s, the temperature (1/512 K, 0 at 23 °C; NaN when invalid),
    /// full-scale codes `SATURATED`, a time-stamp gap of more than half a period `DATA_LOST` with
    /// the count. Written for the per-sample budget (README "Measured figures"): fixed offsets
    /// into the frame, the sample written in place, and the six range checks folded into one
    /// comparison (each code plus 32 766 as `u32`: the three full-scale codes ±32 767 and
    /// −32 768 land above 65 532, every other code at or below).
    #[inline(always)]
    pub fn decode_into(&mut self, f: &[u8; FRAME_LEN], out: &mut ImuSample) -> bool {
        const DRDY: u8 = STATUS_DRDY_ACC | STATUS_DRDY_GYR;
        const A: usize = (ACC_X as u8 - STATUS as u8) as usize;
        const G: usize = (GYR_X as u8 - STATUS as u8) as usize;
        const T: usize = (SENSORTIME_0 as u8 - STATUS as u8) as usize;
        const C: usize = (TEMPERATURE_0 as u8 - STATUS as u8) as usize;
        if f[0] & DRDY != DRDY {
            return false;
        }
        let word = |i: usize| i16::from_le_bytes([f[i], f[i + 1]]);
        let key = |v: i16| (i32::from(v) + 32_766) as u32;
        let mut top = 0;
        for k in 0..3 {
            let (a, g) = (word(A + 2 * k), word(G + 2 * k));
            top = top.max(key(a)).max(key(g));
            out.accel_out[k] = f32::from(a);
            out.gyro_rad_s[k] = f32::from(g) * GYRO_RAD_S_PER_LSB;
        }
        let time = u16::from_le_bytes([f[T], f[T + 1]]);
        let temp = word(C);
        out.temp_c = if temp == TEMPERATURE_INVALID {
            f32::NAN
        } else {
            23.0 + f32::from(temp) * (1.0 / 512.0)
        };
        let mut flags = if top > 65_532 { ImuFlags::SATURATED } else { 0 };
        let lost = match self.last_time {
            Some(prev) => lost_between(prev, time, self.ticks),
            None => 0,
        };
        if lost > 0 || self.lost_pending {
            flags |= ImuFlags::DATA_LOST;
            self.lost_pending = false;
        }
        self.last_time = Some(time);
        out.timestamp = time;
        out.lost_before = lost;
        out.flags = ImuFlags(flags);
        true
    }
}

#[derive(Clone, Copy, Debug, PartialEq, Eq)]
enum Phase {
    /// A sample burst (data ready, or the stall timer's).
    Sample,
    /// The register check's read of `reg`, which must hold `expected`.
    Check { reg: Reg, expected: u8 },
    /// A register differed: the board starts the part again; the bus stays taken.
    Heal,
}

/// Samples a board gathers before it runs the pipeline on them (the pipeline feed's
/// runs, `PipelineFeed::push_all`): 8, 5 ms at 1.6 kHz. One sample per run would cost the pipeline's per-run set-up at every
/// sample (the bench's whole BMI270 path: 455.7 instructions a sample in runs of one, over the
/// 420 the budget allows at 8 kHz); the latency is nothing to windows of samples.
pub const BATCH: usize = 8;

/// What one completed burst gave.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Completed {
    /// The frame held a sample, written to the caller's slot (not when neither sensor had new
    /// data, nor for a check burst).
    pub sample: bool,
    /// The next burst to put on the wire (`None`: the bus is free).
    pub next: Option<Burst>,
    /// The register check found this register changed: start the part again, then
    /// [`Bmi270Bursts::resume_after_heal`] (the bus stays taken meanwhile).
    pub mismatch: Option<Mismatch>,
}

/// The completion side of the BMI270's bursts: the decoder, the register check and the stall
/// timer. A board's data-ready interrupt starts bursts through an [`InFlight`] made with
/// [`SAMPLE_CMD`] (`InFlight::with_command`).
pub struct Bmi270Bursts {
    decoder: Decoder,
    registers: [(Reg, u8); 8],
    check_next: usize,
    phase: Phase,
    /// Time since the last completed burst, ms.
    quiet_ms: u32,
    /// Time since the last register check, ms.
    since_check_ms: u32,
}

impl Bmi270Bursts {
    /// For a part started with `cfg` (over the blocking bus).
    pub fn new(cfg: &Config) -> Self {
        Bmi270Bursts {
            decoder: Decoder::new(cfg),
            registers: cfg.registers(),
            check_next: 0,
            phase: Phase::Sample,
            quiet_ms: 0,
            since_check_ms: 0,
        }
    }

    /// Bytes of the burst on the wire (what [`Self::on_complete`] wants back).
    pub fn expected_len(&self) -> usize {
        match self.phase {
            Phase::Sample => BURST_LEN,
            Phase::Check { .. } | Phase::Heal => 3,
        }
    }

    /// A burst finished; `rx` holds the bytes that came back (as many as were sent). A sample
    /// goes to `out`.
    pub fn on_complete(
        &mut self,
        rx: &[u8],
        out: &mut ImuSample,
        in_flight: &InFlight,
    ) -> Completed {
        self.quiet_ms = 0;
        let mut done = Completed {
            sample: false,
            next: None,
            mismatch: None,
        };
        match self.phase {
            Phase::Sample => {
                if let Some(Ok(frame)) = rx.get(2..BURST_LEN).map(<&[u8; FRAME_LEN]>::try_from) {
                    done.sample = self.decoder.decode_into(frame, out);
                }
            }
            Phase::Check { reg, expected } => {
                self.since_check_ms = 0;
                let read = rx.get(2).copied().unwrap_or(0);
                if read != expected {
                    self.phase = Phase::Heal;
                    done.mismatch = Some(Mismatch {
                        reg: reg.addr(),
                        expected,
                        read,
                    });
                    return done;
                }
                self.check_next = (self.check_next + 1) % self.registers.len();
            }
            Phase::Heal => {}
        }
        done.next = self.end(in_flight);
        done
    }

    /// The bus is free again, unless the register check is due (its read goes on the wire) or a
    /// data-ready edge came meanwhile (its sample burst).
    fn end(&mut self, in_flight: &InFlight) -> Option<Burst> {
        if self.since_check_ms >= CHECK_PERIOD_MS && self.phase == Phase::Sample {
            let (reg, expected) = self.registers[self.check_next];
            self.phase = Phase::Check { reg, expected };
            return Some(Burst {
                tx: &CHECK_CMD[usize::from(reg.addr() & 0x7F)],
            });
        }
        self.phase = Phase::Sample;
        in_flight.end()
    }

    /// The DMA reported an error: the burst's data are lost (the next sample is flagged), the
    /// register check is due (PX4: right after a failure); the next burst, if any.
    pub fn abandon(&mut self, in_flight: &InFlight) -> Option<Burst> {
        self.decoder.after_gap();
        self.since_check_ms = CHECK_PERIOD_MS;
        self.phase = Phase::Sample;
        in_flight.end()
    }

    /// Every [`STALL_TICK_MS`] from a board's timer: times the register check, and after more
    /// than [`STALL_TIMEOUT_MS`] without a completed burst (a DMA completion lost, or a part that
    /// stopped its data ready — a brown-out) takes the bus over and returns a sample burst to put
    /// on the wire at once; the check follows it, and the next sample is flagged.
    pub fn on_tick(&mut self, in_flight: &InFlight) -> Option<Burst> {
        self.since_check_ms = self.since_check_ms.saturating_add(STALL_TICK_MS);
        self.quiet_ms = self.quiet_ms.saturating_add(STALL_TICK_MS);
        if self.quiet_ms <= STALL_TIMEOUT_MS {
            return None;
        }
        self.quiet_ms = 0;
        self.since_check_ms = CHECK_PERIOD_MS;
        self.decoder.after_gap();
        self.phase = Phase::Sample;
        in_flight.take_over();
        Some(Burst { tx: &SAMPLE_CMD })
    }

    /// After [`Completed::mismatch`]: the board started the part again (`started`: it answered and
    /// took its configuration; if not, the next check, 100 ms on, finds the register changed again
    /// and the board tries again). The next sample is flagged; the bus is free again (or the
    /// burst of a data-ready edge that came meanwhile).
    pub fn resume_after_heal(&mut self, started: bool, in_flight: &InFlight) -> Option<Burst> {
        if started {
            self.check_next = 0;
        }
        self.decoder.after_gap();
        self.quiet_ms = 0;
        self.phase = Phase::Sample;
        in_flight.end()
    }
}
