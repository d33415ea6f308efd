//! The simulated device: the firmware's own device-agnostic logic (request handler, sampling pipeline,
//! A/B parameter store, virtual sensor) running in-process on virtual time, behind a [`Transport`].
//!
//! It is the same code the QEMU board runs, so `--port sim` exercises the real protocol handling,
//! chunked blob writes, validation against the unit id, storage and reset; only the UART and the
//! interrupt are replaced. Time is virtual: samples are produced as fast as the host asks for them,
//! so a 15-minute plan runs in seconds, unless [`SimDevice::pace_real_time`] holds each sample back
//! until its real time (`host monitor`, which shows a live device and must not race through hours of
//! virtual time and megabytes of output in a few seconds). The line is rate-limited like a 921 600 Bd UART (about 92 bytes
//! per millisecond), so a window too short for the link shows up as dropped frames, as on a board.
//!
//! Fault injection for the end-to-end tests: [`SimDevice::stop_answering_after_samples`] (a device that
//! dies mid-segment) and [`SimDevice::inject_line_garbage`] (noise on the device→host line); for
//! `host bringup`'s tests, [`SimDevice::sample_at_hz`] (a part sampling at another rate than the
//! identity says) and [`SimDevice::stick_axis`] (an accelerometer axis whose output never changes).

use super::client::{LinkError, Transport};
use super::sim_hand::{HandCue, HandMove, SimHand};
use firmware::imu::alignment::Alignment;
use firmware::pipeline::Pipeline;
use firmware::protocol::{BoardEvent, Controller, DeviceInfo, LinkService};
use firmware::storage::{AbStore, RamNorFlash};
use firmware::virtual_sensor::VirtualSensor;
use firmware::ByteLink;
use shared::wire::{Board, ImuInit, ImuPart, ImuStatus};
use shared::{Calibration, LeverMode, UnitId};
use std::collections::VecDeque;
use std::time::{Duration, Instant};

/// The simulated device's unit identifier.
pub const SIM_UNIT_ID: UnitId = UnitId(*b"SIM-PAPER-01");
/// Its sampling rate, Hz.
pub(crate) const SIM_SAMPLE_RATE_HZ: u32 = 1000;
/// UART bytes per sample at 921 600 Bd (10 bits per byte) and 1 kHz.
const LINE_BYTES_PER_SAMPLE: u32 = 92;
/// Virtual time the device may run inside one `receive` call before reporting silence.
const MAX_SAMPLES_PER_RECEIVE: u32 = 20_000;
const FLASH_ERASE: usize = 4096;
const OUTPUT_QUEUE: usize = 16;

type Store = AbStore<RamNorFlash<'static, FLASH_ERASE>>;

/// The nominal sensitivity a digital part at its configured range reports for a unit in counts:
/// the power of two nearest its scales' mean (a part's ranges give 2048, 4096, 8192 or 16384
/// counts per g; a unit's own scales are a few tenths of a percent off it). 0 for a unit in volts.
fn nominal_lsb_per_g(truth: &Calibration) -> u32 {
    if truth.statics.output_unit != shared::OutputUnit::Lsb {
        return 0;
    }
    let mean = truth
        .statics
        .scale_out_per_g
        .iter()
        .map(|s| s.abs())
        .sum::<f64>()
        / 3.0;
    if !(1.0..2.0e9).contains(&mean) {
        return 0;
    }
    1u32 << (mean.log2().round() as u32)
}

/// Byte queues standing in for the UART.
#[derive(Default)]
struct Line {
    to_device: VecDeque<u8>,
    to_host: VecDeque<u8>,
    budget: u32,
}

impl ByteLink for Line {
    fn try_read(&mut self) -> Option<u8> {
        self.to_device.pop_front()
    }
    fn try_write(&mut self, byte: u8) -> bool {
        if self.budget == 0 {
            return false;
        }
        self.budget -= 1;
        self.to_host.push_back(byte);
        true
    }
}

/// The in-process device.
pub struct SimDevice {
    info: DeviceInfo,
    truth: Calibration,
    service: Option<LinkService<Store>>,
    pipeline: Pipeline<OUTPUT_QUEUE>,
    sensor: VirtualSensor,
    line: Line,
    samples: u64,
    dies_at_sample: Option<u64>,
    resets: u32,
    /// Real-time pacing: the wall-clock instant and sample count it started at.
    pace: Option<(Instant, u64)>,
    /// The hand that turns a device without a table (`SimDevice::hand_held`).
    hand: Option<(SimHand, HandCue)>,
    /// Paced at this rate instead of the identity's (a planted fault).
    actual_rate_hz: Option<u32>,
    /// This accelerometer axis reads one fixed value (a planted fault).
    stuck_axis: Option<usize>,
    /// The unit's outputs turned by this rotation (a planted fault: a board description whose
    /// IMU rotation is wrong).
    turned: Option<Alignment>,
    /// Each gyro reading held for this many samples (a planted fault: a part that holds its
    /// output, as the ICM-42688-P's AFSR does), with the reading held and its age.
    hold_gyro: Option<(u32, [f32; 3], u32)>,
}

/// Why a simulated device cannot be built.
#[derive(Debug, thiserror::Error)]
pub enum SimError {
    /// The truth calibration is unusable for the forward model.
    #[error("the simulated unit's parameters are unusable")]
    BadUnit,
    /// The simulated flash could not be formatted.
    #[error("the simulated flash could not be set up")]
    Storage,
}

impl SimDevice {
    /// A device whose sensor is the unit `truth` (noise on), with empty flash.
    pub fn new(truth: Calibration) -> Result<SimDevice, SimError> {
        Self::with_unit_id(truth, SIM_UNIT_ID)
    }

    /// A device without a table, held in a simulated hand (`sim_hand`) that turns it when its cue
    /// ([`SimDevice::hand_cue`]) asks: the hand-held procedure's device.
    pub fn hand_held(truth: Calibration) -> Result<SimDevice, SimError> {
        let mut dev = Self::with_unit_id(truth, SIM_UNIT_ID)?;
        dev.info.board = Board::SimulatedHand;
        dev.info.virtual_table = false;
        dev.hand = Some(SimHand::new(SIM_SAMPLE_RATE_HZ));
        let service = dev.service.take().and_then(|s| s.controller.into_store());
        if let Some(store) = service {
            dev.boot(store);
        }
        Ok(dev)
    }

    /// The cue of the hand holding the device, if one does.
    pub fn hand_cue(&self) -> Option<HandCue> {
        self.hand.as_ref().map(|(_, cue)| cue.clone())
    }

    /// The same with another unit identifier.
    pub(crate) fn with_unit_id(truth: Calibration, unit_id: UnitId) -> Result<SimDevice, SimError> {
        // The flash lives as long as the process, like a board's; 8 KiB per simulated device.
        let mem: &'static mut [u8] = Box::leak(vec![0xFFu8; 2 * FLASH_ERASE].into_boxed_slice());
        let store = AbStore::new(RamNorFlash::new(mem), 0, FLASH_ERASE as u32)
            .map_err(|_| SimError::Storage)?;
        let info = DeviceInfo {
            unit_id,
            board: Board::Simulated,
            sample_rate_hz: SIM_SAMPLE_RATE_HZ,
            virtual_table: true,
            output_unit: truth.statics.output_unit,
        };
        let sensor =
            VirtualSensor::new(&truth, SIM_SAMPLE_RATE_HZ, true).ok_or(SimError::BadUnit)?;
        let mut dev = SimDevice {
            info,
            truth,
            service: None,
            pipeline: Pipeline::new(SIM_SAMPLE_RATE_HZ),
            sensor,
            line: Line::default(),
            samples: 0,
            dies_at_sample: None,
            resets: 0,
            pace: None,
            hand: None,
            actual_rate_hz: None,
            stuck_axis: None,
            turned: None,
            hold_gyro: None,
        };
        dev.boot(store);
        Ok(dev)
    }

    fn boot(&mut self, store: Store) {
        let mut controller = Controller::boot(self.info, store, LeverMode::RateAndAcceleration);
        controller.set_imu(
            ImuStatus {
                part: ImuPart::Virtual,
                who_am_i: 0,
                init: ImuInit::NotApplicable,
            },
            nominal_lsb_per_g(&self.truth),
        );
        self.pipeline = Pipeline::new(SIM_SAMPLE_RATE_HZ);
        if let Some(c) = controller.compensator() {
            self.pipeline
                .apply(firmware::pipeline::PipelineCommand::Compensator(Some(c)));
        }
        self.service = Some(LinkService::new(controller));
    }

    /// The unit the sensor simulates (the truth the tests compare against).
    pub fn truth(&self) -> &Calibration {
        &self.truth
    }

    /// Samples produced since power-on.
    pub fn samples(&self) -> u64 {
        self.samples
    }

    /// How many times the device restarted.
    #[cfg(test)]
    pub(crate) fn resets(&self) -> u32 {
        self.resets
    }

    /// After `n` more samples the device goes silent for good (as if unplugged).
    pub fn stop_answering_after_samples(&mut self, n: u64) {
        self.dies_at_sample = Some(self.samples + n);
    }

    /// Puts `bytes` on the device→host line, between frames.
    pub fn inject_line_garbage(&mut self, bytes: &[u8]) {
        self.line.to_host.extend(bytes);
    }

    /// From now on, sample `n` is produced no earlier than `n / rate` seconds of wall time after this
    /// call, as a board's ADC would: virtual time runs at real time.
    pub fn pace_real_time(&mut self) {
        self.pace = Some((Instant::now(), self.samples));
    }

    /// A planted fault: paced, the unit samples at `hz` while its identity still says
    /// `SIM_SAMPLE_RATE_HZ` (a wrong crystal or output data rate).
    pub fn sample_at_hz(&mut self, hz: u32) {
        self.actual_rate_hz = Some(hz.max(1));
    }

    /// A planted fault: accelerometer axis `axis` (0–2) reads a fixed 2.5 V from now on (a dead
    /// sensing element or a stuck bit of the data path).
    pub fn stick_axis(&mut self, axis: usize) {
        self.stuck_axis = Some(axis.min(2));
    }

    /// A planted fault: the unit's accelerometer and gyro outputs turned by `a` (a board whose
    /// description gives the wrong IMU rotation).
    pub fn turn_outputs(&mut self, a: Alignment) {
        self.turned = Some(a);
    }

    /// A planted fault: accelerometer axis `axis`'s noise `k` times the others'.
    pub fn noisy_axis(&mut self, axis: usize, k: f32) {
        self.sensor.scale_output_noise(axis, k);
    }

    /// A planted fault: each gyro reading is repeated for `n` samples.
    pub fn hold_gyro_samples(&mut self, n: u32) {
        self.hold_gyro = Some((n.max(1), [0.0; 3], 0));
    }

    /// When paced, the wall-clock instant the next sample is due.
    fn next_sample_due(&self) -> Option<Instant> {
        let (start, first) = self.pace?;
        let n = self.samples + 1 - first;
        let hz = self.actual_rate_hz.unwrap_or(SIM_SAMPLE_RATE_HZ);
        Some(start + Duration::from_secs_f64(n as f64 / f64::from(hz)))
    }

    fn dead(&self) -> bool {
        self.dies_at_sample.is_some_and(|d| self.samples >= d)
    }

    /// One main-loop round: answer requests, move output to the line, act on board events.
    fn poll(&mut self) {
        let Some(service) = self.service.as_mut() else {
            return;
        };
        match service.poll(&mut self.line, &mut self.pipeline) {
            Some(BoardEvent::SetTable(t)) => {
                // Already checked by the controller; a refusal cannot happen here.
                let _ = self.sensor.set_table(&t);
            }
            Some(BoardEvent::SetTemperature(t)) => self.sensor.set_temperature(t),
            Some(BoardEvent::Reset) => {
                self.line.budget = self.line.budget.max(256);
                service.flush(&mut self.line, 1024);
                // The link reads no request while a store job is out: the store is home.
                if let Some(store) = self.service.take().and_then(|s| s.controller.into_store()) {
                    self.resets += 1;
                    self.line.to_device.clear();
                    self.boot(store);
                }
            }
            None => {}
        }
        // The store of a calibration write, as a board's idle loop runs it.
        if let Some(service) = self.service.as_mut() {
            service.run_store_here(&mut self.pipeline);
        }
    }

    /// Runs one sample period; four times a second the unit's temperature too, as the boards do.
    fn step(&mut self) {
        if let Some((hand, _)) = self.hand.as_mut() {
            // The hand's settings are unit vectors and bounded rates: never refused.
            match hand.step(&self.sensor.table()) {
                Some(HandMove::Table(t)) => {
                    let _ = self.sensor.set_table(&t);
                }
                Some(HandMove::Tilt(from, omega_b_rad_s)) => {
                    let _ = self.sensor.set_table(&from);
                    let _ = self.sensor.set_tilt(omega_b_rad_s);
                }
                None => {}
            }
        }
        if self.stuck_axis.is_none() && self.turned.is_none() && self.hold_gyro.is_none() {
            self.sensor.step(&mut self.pipeline);
        } else {
            // `VirtualSensor::step` with the planted faults applied to the sample.
            let every = u64::from(SIM_SAMPLE_RATE_HZ / firmware::pipeline::TEMPERATURE_REFRESH_HZ);
            if self.samples % every.max(1) == 0 {
                self.pipeline.set_temperature(self.sensor.temperature_c());
            }
            let mut s = self.sensor.sample();
            if let Some(axis) = self.stuck_axis {
                s.raw[axis] = 2.5;
            }
            if let Some(a) = self.turned {
                s.raw = a.to_board(s.raw);
                s.rate_rad_s = a.to_board(s.rate_rad_s);
            }
            if let Some((n, held, age)) = self.hold_gyro.as_mut() {
                if *age == 0 {
                    *held = s.rate_rad_s;
                }
                s.rate_rad_s = *held;
                *age = (*age + 1) % *n;
            }
            self.pipeline.on_sample(&s);
        }
        self.samples += 1;
        self.line.budget =
            (self.line.budget + LINE_BYTES_PER_SAMPLE).min(4 * LINE_BYTES_PER_SAMPLE);
        self.poll();
    }
}

impl Transport for SimDevice {
    fn send(&mut self, bytes: &[u8]) -> Result<(), LinkError> {
        if !self.dead() {
            self.line.to_device.extend(bytes);
        }
        Ok(())
    }

    fn receive(&mut self, buf: &mut [u8], timeout: Duration) -> Result<usize, LinkError> {
        let give_up = Instant::now() + timeout;
        let mut ran = 0;
        while self.line.to_host.is_empty() && ran < MAX_SAMPLES_PER_RECEIVE && !self.dead() {
            if let Some(due) = self.next_sample_due() {
                // Paced: wait for the sample's real time, but no longer than the caller waits.
                if due > give_up {
                    std::thread::sleep(give_up.saturating_duration_since(Instant::now()));
                    break;
                }
                std::thread::sleep(due.saturating_duration_since(Instant::now()));
            }
            self.step();
            ran += 1;
        }
        let n = buf.len().min(self.line.to_host.len());
        for (slot, byte) in buf.iter_mut().zip(self.line.to_host.drain(..n)) {
            *slot = byte;
        }
        Ok(n)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::client::DeviceClient;
    use shared::blob::ParameterBlob;
    use shared::wire::{CalibrationState, StreamKind, VirtualTable};

    fn client() -> DeviceClient<SimDevice> {
        let truth = shared::params::PAPER_UNIT;
        DeviceClient::new(SimDevice::new(truth).unwrap(), Duration::from_millis(300))
    }

    #[test]
    fn identifies_streams_stores_and_survives_reset() {
        let mut c = client();
        let id = c.identify().unwrap();
        assert_eq!(id.unit_id, SIM_UNIT_ID);
        assert_eq!(id.calibration, CalibrationState::Missing);

        // x up at rest: the raw window mean is the forward model's output (noise averages out).
        c.set_table(VirtualTable {
            up_b: [1.0, 0.0, 0.0],
            rate_rad_s: 0.0,
            accel_rad_s2: 0.0,
        })
        .unwrap();
        c.start_stream(StreamKind::RawWindows, 1000).unwrap();
        let w = c.next_raw_window().unwrap();
        c.stop_stream().unwrap();
        assert_eq!(w.count, 1000);
        let truth = c.transport_mut().truth().statics;
        let want_x = truth.zero_bias_out[0] + truth.scale_out_per_g[0] * 0.999912;
        assert!(
            (f64::from(w.mean_raw[0]) - want_x).abs() < 1e-4,
            "{} vs {want_x}",
            w.mean_raw[0]
        );

        // Write the true calibration, reset, and read it back.
        let blob = ParameterBlob {
            unit_id: SIM_UNIT_ID,
            calibration: *c.transport_mut().truth(),
            created_unix_s: 42,
        };
        let (bytes, n) = blob.to_bytes().unwrap();
        c.write_calibration(&bytes[..n]).unwrap();
        let id = c.reset().unwrap();
        assert_eq!(
            id.calibration,
            CalibrationState::Valid { created_unix_s: 42 }
        );
        assert_eq!(c.read_calibration().unwrap(), bytes[..n].to_vec());
        assert_eq!(c.transport_mut().resets(), 1);
    }

    /// Paced, a second of samples takes a second of wall time (within the scheduler's slack), and
    /// the samples produced follow the wall clock, not the host's appetite.
    #[test]
    fn paced_device_runs_at_real_time() {
        let mut c = client();
        c.identify().unwrap();
        c.transport_mut().pace_real_time();
        let before = c.transport_mut().samples();
        let start = Instant::now();
        c.start_stream(StreamKind::CompensatedWindows, 100).unwrap();
        for _ in 0..5 {
            c.next_compensated_window().unwrap();
        }
        let wall_s = start.elapsed().as_secs_f64();
        let virtual_s = (c.transport_mut().samples() - before) as f64 / 1000.0;
        assert!((0.5..0.75).contains(&virtual_s), "{virtual_s} s of samples");
        assert!(
            (wall_s - virtual_s).abs() < 0.1,
            "wall {wall_s} s, virtual {virtual_s} s"
        );
    }

    #[test]
    fn a_dead_device_times_out_with_a_clear_error() {
        let mut c = client();
        c.identify().unwrap();
        c.transport_mut().stop_answering_after_samples(0);
        let e = c.identify().unwrap_err().to_string();
        assert!(e.contains("stopped answering"), "{e}");
    }
}
