//! The per-sample path: gyro correction, ω̇ estimate, compensation, window statistics and the output
//! queue (docs/model.md §10).
//!
//! The gyro's rate is corrected first (`ω = G⁻¹(w − b)`, docs/model.md §8), and the corrected rate
//! feeds the ω̇ estimator, the lever-arm terms and the compensated frames; raw frames keep the gyro's
//! own output, which is what the host calibrates the gyro from. Temperature readings arrive at the
//! board's pace through [`Pipeline::set_temperature`] (not per sample): each is averaged into the
//! window's `mean_temp_c`, and at most [`TEMPERATURE_REFRESH_HZ`] times a second it refreshes the
//! compensator's temperature-dependent terms (docs/model.md §9).
//!
//! [`Pipeline::on_sample`] runs at sampling priority (a timer interrupt) for every sample. It never
//! touches the link: finished frames go into a fixed-size queue ([`Pipeline::pop_output`] is called by
//! the link service in the main loop). When the queue is full the *frame* is dropped and counted
//! (`dropped_frames`, and [`SampleFlags::FRAMES_DROPPED`] on the next frame that gets through);
//! samples are never dropped. Saturated and non-finite samples are flagged and left out of the
//! statistics; a non-finite gyro sample also restarts the ω̇ estimator so NaN never enters its state.

use heapless::Deque;
use shared::compensator::Compensator;
use shared::omega_dot::OmegaDotEstimator;
use shared::wire::{
    CompensatedSample, CompensatedWindow, DeviceToHost, RawSample, RawWindow, SampleFlags,
    StreamKind, StreamRequest,
};

use crate::stats::WindowAccumulator;

mod feed;
#[cfg(test)]
mod feed_tests;
mod run;
#[cfg(test)]
mod run_tests;
mod step;

pub use feed::PipelineFeed;

/// Corner frequency of the ω̇ filter as a fraction of the sample rate (20 Hz at 1 kHz, `docs/model.md` §4.6).
pub const OMEGA_DOT_CORNER_FRACTION: f32 = 0.02;
/// Largest accepted window (or decimation factor): 2²⁴ samples, 28 minutes at 10 kHz.
pub const MAX_WINDOW_SAMPLES: u32 = 1 << 24;
/// Most compensator refreshes per second from temperature readings: a unit's temperature changes
/// over seconds, and a refresh (about 150 instructions with 3 divisions) need not run per sample.
pub const TEMPERATURE_REFRESH_HZ: u32 = 4;

/// One sample as read from the sensors.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct Sample {
    /// Accelerometer outputs, sensor axes, output unit (V or LSB).
    pub raw: [f32; 3],
    /// Gyro rate, body axes, rad/s.
    pub rate_rad_s: [f32; 3],
    /// Some channel sat at its range limit.
    pub saturated: bool,
}

impl Sample {
    /// All six values are finite.
    #[inline(always)]
    pub fn is_finite(&self) -> bool {
        all_finite(&self.raw, &self.rate_rad_s)
    }
}

/// What [`Pipeline::on_sample`] reads of a sample: implemented by [`Sample`] and by a digital
/// IMU's decoded sample (`imu::ImuSample`), so that a board hands either over as it is, without
/// copying it into the other form on the per-sample path.
pub trait SampleView {
    /// Accelerometer outputs, sensor axes, output unit (V or LSB).
    fn raw(&self) -> &[f32; 3];
    /// Gyro rate, body axes, rad/s.
    fn rate_rad_s(&self) -> &[f32; 3];
    /// Some channel sat at its range limit.
    fn saturated(&self) -> bool;
    /// All six values are finite. A source that knows this without looking at the values (a
    /// digital IMU's sample, finite unless the part marked it invalid) says so more cheaply.
    #[inline(always)]
    fn finite(&self) -> bool {
        all_finite(self.raw(), self.rate_rad_s())
    }
    /// Finite, unsaturated and following no loss: a sample [`Pipeline::on_run`] takes.
    #[inline(always)]
    fn clean(&self) -> bool {
        self.finite() && !self.saturated()
    }
}

impl SampleView for Sample {
    #[inline(always)]
    fn raw(&self) -> &[f32; 3] {
        &self.raw
    }
    #[inline(always)]
    fn rate_rad_s(&self) -> &[f32; 3] {
        &self.rate_rad_s
    }
    #[inline(always)]
    fn saturated(&self) -> bool {
        self.saturated
    }
}

/// All six values are finite.
#[inline(always)]
#[allow(clippy::eq_op)] // `x - x` is the point: 0 for finite x, NaN otherwise
fn all_finite(r: &[f32; 3], w: &[f32; 3]) -> bool {
    // `x - x == 0` is false exactly for NaN and ±inf; one comparison chain, no library call.
    let s = (r[0] - r[0])
        + (r[1] - r[1])
        + (r[2] - r[2])
        + (w[0] - w[0])
        + (w[1] - w[1])
        + (w[2] - w[2]);
    s == 0.0
}

/// A change to the pipeline, decided by the request handler in the main loop.
// The compensator travels by value (no allocator on the device to box it), once per calibration or
// lever-mode change: the size difference costs stack there, never per sample.
#[allow(clippy::large_enum_variant)]
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum PipelineCommand {
    /// Start or change the stream (the window restarts).
    Stream(StreamRequest),
    /// Stop streaming.
    StopStream,
    /// Apply this compensator from now on (`None`: uncalibrated). The window restarts.
    Compensator(Option<Compensator>),
}

/// The per-sample state. `Q` is the output queue length in frames.
pub struct Pipeline<const Q: usize> {
    compensator: Option<Compensator>,
    omega_dot: OmegaDotEstimator,
    stream: Option<StreamRequest>,
    index: u64,
    window_first: u64,
    in_window: u32,
    rejected: u32,
    window_flags: u8,
    acc: WindowAccumulator<6>,
    out: Deque<DeviceToHost, Q>,
    dropped: u32,
    drop_pending: bool,
    temp_sum_c: f32,
    temp_readings: u32,
    latest_temp_c: f32,
    refresh_interval: u64,
    last_refresh: Option<u64>,
}

/// The ω̇ update, one copy out of line for the paths that can afford a call: `on_sample` (the ADC
/// board's path, a digital IMU's flagged samples) and the run loops other than the full
/// compensation's (`run.rs`), which keeps its own in line. With [`window_add`] and
/// `Pipeline::body_rate_into_outlined`, 1.6 KiB less of the QEMU image for 20 to 45 instructions
/// more per sample on those paths (README "Measured figures").
#[inline(never)]
pub(crate) fn omega_dot_update(e: &mut OmegaDotEstimator, rate: &[f32; 3]) {
    e.update(rate);
}

/// The window accumulation of a 6-channel sample, one copy out of line: see [`omega_dot_update`].
#[inline(never)]
pub(crate) fn window_add(acc: &mut WindowAccumulator<6>, x: &[f32; 6]) {
    acc.add(x);
}

impl<const Q: usize> Pipeline<Q> {
    /// A pipeline for samples at `sample_rate_hz` (≥ 100 Hz), uncalibrated and not streaming.
    pub fn new(sample_rate_hz: u32) -> Self {
        let fs = sample_rate_hz.max(100) as f32;
        let omega_dot = match OmegaDotEstimator::new(fs, fs * OMEGA_DOT_CORNER_FRACTION) {
            Ok(e) => e,
            // Unreachable for fs ≥ 100: the corner is 2 % of fs. Keep a valid fallback anyway.
            Err(_) => OmegaDotEstimator::new(1000.0, 20.0).unwrap_or_else(|_| unreachable()),
        };
        Pipeline {
            compensator: None,
            omega_dot,
            stream: None,
            index: 0,
            window_first: 0,
            in_window: 0,
            rejected: 0,
            window_flags: 0,
            acc: WindowAccumulator::new(),
            out: Deque::new(),
            dropped: 0,
            drop_pending: false,
            temp_sum_c: 0.0,
            temp_readings: 0,
            latest_temp_c: f32::NAN,
            refresh_interval: u64::from(sample_rate_hz.max(100) / TEMPERATURE_REFRESH_HZ),
            last_refresh: None,
        }
    }

    /// A temperature reading of the unit, °C (board pace, a few per second; NaN for a failed read).
    /// It enters the current window's mean, and refreshes the compensator when the last refresh is
    /// at least `1/TEMPERATURE_REFRESH_HZ` old (always for the first reading after a calibration
    /// change).
    pub fn set_temperature(&mut self, temp_c: f32) {
        if temp_c.is_finite() {
            self.temp_sum_c += temp_c;
            self.temp_readings += 1;
        }
        self.latest_temp_c = temp_c;
        let due = self
            .last_refresh
            .is_none_or(|t| self.index.wrapping_sub(t) >= self.refresh_interval);
        if let (true, Some(c)) = (due, self.compensator.as_mut()) {
            if c.refresh(temp_c).is_flagged() {
                self.window_flags |= SampleFlags::TEMPERATURE;
            }
            self.last_refresh = Some(self.index);
        }
    }

    /// Samples were lost before the next one (a digital IMU's FIFO overflowed or was flushed): `n`
    /// of them when the part's time stamps tell, 0 when unknown. The sample index advances by `n`
    /// (indices stay the time base), the lost samples count as rejected in the current window, the
    /// frame is flagged [`SampleFlags::SAMPLES_LOST`], and the ω̇ estimator restarts (a difference
    /// across a gap is not a derivative).
    pub fn on_samples_lost(&mut self, n: u32) {
        self.index += u64::from(n);
        self.omega_dot.reset();
        let Some(req) = self.stream else {
            return;
        };
        self.window_flags |= SampleFlags::SAMPLES_LOST;
        if matches!(
            req.kind,
            StreamKind::RawWindows | StreamKind::CompensatedWindows
        ) {
            self.rejected += n;
            self.in_window += n;
        }
    }

    /// The compensator in force (`None`: uncalibrated), e.g. to read its temperature state.
    pub fn compensator(&self) -> Option<&Compensator> {
        self.compensator.as_ref()
    }

    /// Applies a command from the request handler.
    pub fn apply(&mut self, cmd: PipelineCommand) {
        match cmd {
            PipelineCommand::Stream(req) => self.stream = Some(req),
            PipelineCommand::StopStream => self.stream = None,
            PipelineCommand::Compensator(c) => {
                self.compensator = c;
                self.last_refresh = None;
                // Refresh at once at the latest temperature rather than run at the reference.
                if let (Some(c), true) = (self.compensator.as_mut(), self.latest_temp_c.is_finite())
                {
                    c.refresh(self.latest_temp_c);
                    self.last_refresh = Some(self.index);
                }
            }
        }
        self.restart_window();
    }

    fn restart_window(&mut self) {
        self.in_window = 0;
        self.rejected = 0;
        self.window_flags = 0;
        self.window_first = self.index;
        self.acc = WindowAccumulator::new();
        self.temp_sum_c = 0.0;
        self.temp_readings = 0;
    }

    /// The window's mean temperature: its readings' mean, else the latest reading (NaN if none).
    fn window_temp_c(&self) -> f32 {
        if self.temp_readings > 0 {
            self.temp_sum_c / self.temp_readings as f32
        } else {
            self.latest_temp_c
        }
    }

    /// True when a calibration is applied.
    pub fn is_calibrated(&self) -> bool {
        self.compensator.is_some()
    }

    /// Samples processed since boot.
    pub fn samples(&self) -> u64 {
        self.index
    }

    /// Output frames dropped since boot because the queue was full.
    pub fn dropped_frames(&self) -> u32 {
        self.dropped
    }

    /// The next queued output frame.
    pub fn pop_output(&mut self) -> Option<DeviceToHost> {
        self.out.pop_front()
    }

    /// Frames waiting in the output queue.
    pub fn queued(&self) -> usize {
        self.out.len()
    }

    /// The body rate into `out`: the gyro's output corrected by the calibration (raw when
    /// uncalibrated). `on_sample` and the runs (`run.rs`) both take it from here.
    #[inline(always)]
    fn body_rate_into(&self, gyro_rad_s: &[f32; 3], out: &mut [f32; 3]) {
        match &self.compensator {
            Some(c) => *out = c.correct_rate(gyro_rad_s).rad_s,
            None => *out = *gyro_rad_s,
        }
    }

    /// [`Pipeline::body_rate_into`], one copy out of line: see [`omega_dot_update`].
    #[inline(never)]
    fn body_rate_into_outlined(&self, gyro_rad_s: &[f32; 3], out: &mut [f32; 3]) {
        self.body_rate_into(gyro_rad_s, out);
    }

    #[inline(always)]
    fn frame_flags(&self, compensated: bool) -> SampleFlags {
        let mut f = self.window_flags;
        match &self.compensator {
            None => f |= SampleFlags::UNCALIBRATED,
            Some(c) if c.temperature_state().is_flagged() => f |= SampleFlags::TEMPERATURE,
            Some(_) => {}
        }
        if !compensated {
            f &= !SampleFlags::TEMPERATURE;
        }
        if self.drop_pending {
            f |= SampleFlags::FRAMES_DROPPED;
        }
        SampleFlags(f)
    }

    #[inline(never)]
    fn emit(&mut self, msg: DeviceToHost) {
        if self.out.push_back(msg).is_err() {
            self.dropped = self.dropped.wrapping_add(1);
            self.drop_pending = true;
        } else {
            self.drop_pending = false;
        }
    }

    /// Processes one sample. Cost: ω̇ update, at most one compensation, one accumulation; a frame is
    /// built only when a window closes. The steps a clean sample shares with the runs (`run.rs`)
    /// are `step.rs`'s; what is here is the rejected samples' and the decimated streams'.
    #[inline]
    pub fn on_sample<S: SampleView + ?Sized>(&mut self, s: &S) {
        let (raw, gyro, saturated) = (s.raw(), s.rate_rad_s(), s.saturated());
        let index = self.index;
        self.index += 1;
        let finite = s.finite();
        // The window's sample, built in place as in a run: the rate in its second half.
        let mut x = [0.0; 6];
        let Some((_, rate)) = step::halves(&mut x) else {
            return;
        };
        self.rate_step::<{ step::PER_SAMPLE }>(gyro, finite, rate);
        let Some(req) = self.stream else {
            return;
        };
        let good = finite && !saturated;
        // The flags of a sample left out: computed where one is, not on the common path.
        let sample_flags = || {
            let mut f = 0u8;
            if !finite {
                f |= SampleFlags::NON_FINITE;
            }
            if saturated {
                f |= SampleFlags::SATURATED;
            }
            f
        };
        let next = self.index;
        match req.kind {
            StreamKind::RawWindows | StreamKind::CompensatedWindows => {
                let mut in_window = self.in_window;
                if good {
                    self.window_step::<{ step::PER_SAMPLE }>(
                        raw,
                        gyro,
                        &mut x,
                        req,
                        || next,
                        &mut in_window,
                    );
                } else {
                    self.rejected += 1;
                    self.window_flags |= sample_flags();
                    self.count_in_window(req, || next, &mut in_window);
                }
                self.in_window = in_window;
            }
            StreamKind::RawDecimated | StreamKind::CompensatedDecimated => {
                if self.in_window == 0 {
                    // Keeps a SAMPLES_LOST noted since the previous emitted sample.
                    self.window_flags |= sample_flags();
                    let flags = self.frame_flags(req.kind == StreamKind::CompensatedDecimated);
                    let msg = if req.kind == StreamKind::RawDecimated {
                        DeviceToHost::RawSample(RawSample {
                            index,
                            raw: *raw,
                            rate_rad_s: *gyro,
                            flags,
                        })
                    } else {
                        let rate = [x[3], x[4], x[5]];
                        let f = if finite {
                            self.compensate(raw, &rate, self.omega_dot.estimate())
                        } else {
                            *raw
                        };
                        DeviceToHost::CompensatedSample(CompensatedSample {
                            index,
                            specific_force_m_s2: f,
                            rate_rad_s: rate,
                            flags,
                        })
                    };
                    self.emit(msg);
                    self.window_flags = 0;
                }
                self.in_window += 1;
                if self.in_window >= req.window_samples {
                    self.in_window = 0;
                }
            }
        }
    }

    #[inline(never)]
    fn close_window(&mut self, kind: StreamKind) {
        let st = self.acc.finish();
        let flags = self.frame_flags(kind == StreamKind::CompensatedWindows);
        let mean_temp_c = self.window_temp_c();
        let m = st.mean;
        let v = st.var;
        let msg = if kind == StreamKind::RawWindows {
            DeviceToHost::RawWindow(RawWindow {
                first_sample: self.window_first,
                count: st.count,
                mean_raw: [m[0], m[1], m[2]],
                var_raw: [v[0], v[1], v[2]],
                mean_rate_rad_s: [m[3], m[4], m[5]],
                var_rate_rad2_s2: [v[3], v[4], v[5]],
                mean_temp_c,
                rejected: self.rejected,
                dropped_frames: self.dropped,
                flags,
            })
        } else {
            DeviceToHost::CompensatedWindow(CompensatedWindow {
                first_sample: self.window_first,
                count: st.count,
                mean_m_s2: [m[0], m[1], m[2]],
                var_m2_s4: [v[0], v[1], v[2]],
                mean_rate_rad_s: [m[3], m[4], m[5]],
                mean_temp_c,
                rejected: self.rejected,
                dropped_frames: self.dropped,
                flags,
            })
        };
        self.emit(msg);
        self.in_window = 0;
        self.rejected = 0;
        self.window_flags = 0;
        self.window_first = self.index;
        self.temp_sum_c = 0.0;
        self.temp_readings = 0;
    }
}

#[cold]
fn unreachable() -> ! {
    loop {
        core::hint::spin_loop();
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::paper_unit;
    use shared::compensator::{LeverMode, TemperatureState};
    use shared::units::SensorOutputs;
    use shared::units::{BodyAngularAccel, BodyRate};

    fn calibrated(mode: LeverMode) -> Pipeline<8> {
        let mut p = Pipeline::<8>::new(1000);
        let c = Compensator::new(&paper_unit::calibration(), mode).unwrap();
        p.apply(PipelineCommand::Compensator(Some(c)));
        p
    }

    fn stream(p: &mut Pipeline<8>, kind: StreamKind, n: u32) {
        p.apply(PipelineCommand::Stream(StreamRequest {
            kind,
            window_samples: n,
        }));
    }

    const S: Sample = Sample {
        raw: [2.8, 2.4, 2.4],
        rate_rad_s: [0.5, -0.25, 0.125],
        saturated: false,
    };

    #[test]
    fn raw_window_counts_and_excludes_bad_samples() {
        let mut p = calibrated(LeverMode::RateOnly);
        stream(&mut p, StreamKind::RawWindows, 10);
        for i in 0..10 {
            let mut s = S;
            if i == 3 {
                s.raw[1] = f32::NAN;
            }
            if i == 7 {
                s.saturated = true;
            }
            p.on_sample(&s);
        }
        let Some(DeviceToHost::RawWindow(w)) = p.pop_output() else {
            panic!("no window");
        };
        assert_eq!(w.count, 8);
        assert_eq!(w.rejected, 2);
        assert_eq!(w.first_sample, 0);
        assert_eq!(w.mean_raw, S.raw);
        assert_eq!(w.var_raw, [0.0; 3]);
        assert_eq!(w.mean_rate_rad_s, S.rate_rad_s);
        assert!(w.flags.has(SampleFlags::NON_FINITE) && w.flags.has(SampleFlags::SATURATED));
        assert!(!w.flags.has(SampleFlags::UNCALIBRATED));
        assert!(p.pop_output().is_none());
        // The next window is clean and starts at sample 10.
        for _ in 0..10 {
            p.on_sample(&S);
        }
        let Some(DeviceToHost::RawWindow(w)) = p.pop_output() else {
            panic!()
        };
        assert_eq!(
            (w.first_sample, w.count, w.rejected, w.flags.0),
            (10, 10, 0, 0)
        );
    }

    #[test]
    fn compensated_window_equals_the_shared_compensator() {
        let mode = LeverMode::RateOnly;
        let mut p = calibrated(mode);
        stream(&mut p, StreamKind::CompensatedWindows, 4);
        for _ in 0..4 {
            p.on_sample(&S);
        }
        let Some(DeviceToHost::CompensatedWindow(w)) = p.pop_output() else {
            panic!()
        };
        let c = Compensator::new(&paper_unit::calibration(), mode).unwrap();
        let want = c.compensate(
            &SensorOutputs { raw: S.raw },
            &BodyRate {
                rad_s: S.rate_rad_s,
            },
            &BodyAngularAccel::default(),
        );
        assert_eq!(w.mean_m_s2, want.m_s2);
        assert_eq!(w.count, 4);
    }

    #[test]
    fn uncalibrated_flag_on_every_frame_and_identity_passthrough() {
        let mut p = Pipeline::<8>::new(1000);
        stream(&mut p, StreamKind::CompensatedDecimated, 2);
        for _ in 0..4 {
            p.on_sample(&S);
        }
        for _ in 0..2 {
            let Some(DeviceToHost::CompensatedSample(s)) = p.pop_output() else {
                panic!()
            };
            assert!(s.flags.has(SampleFlags::UNCALIBRATED));
            assert_eq!(s.specific_force_m_s2, S.raw);
        }
        assert!(p.pop_output().is_none());
        stream(&mut p, StreamKind::RawWindows, 1);
        p.on_sample(&S);
        let Some(DeviceToHost::RawWindow(w)) = p.pop_output() else {
            panic!()
        };
        assert!(w.flags.has(SampleFlags::UNCALIBRATED));
    }

    #[test]
    fn decimation_sends_every_nth_sample_with_its_index() {
        let mut p = calibrated(LeverMode::Off);
        p.on_sample(&S); // before the stream: index 0, no output
        stream(&mut p, StreamKind::RawDecimated, 3);
        for _ in 0..7 {
            p.on_sample(&S);
        }
        let idx: std::vec::Vec<u64> = core::iter::from_fn(|| p.pop_output())
            .map(|m| match m {
                DeviceToHost::RawSample(s) => s.index,
                other => panic!("{other:?}"),
            })
            .collect();
        assert_eq!(idx, [1, 4, 7]);
    }

    #[test]
    fn full_queue_drops_frames_not_samples_and_reports_it() {
        let mut p = calibrated(LeverMode::RateOnly);
        stream(&mut p, StreamKind::RawWindows, 1);
        for _ in 0..20 {
            p.on_sample(&S);
        }
        assert_eq!(p.samples(), 20);
        assert_eq!(p.queued(), 8);
        assert_eq!(p.dropped_frames(), 12);
        // The queued frames predate the drops.
        let first: std::vec::Vec<_> = core::iter::from_fn(|| p.pop_output()).collect();
        assert_eq!(first.len(), 8);
        // The next frame carries the flag and the count; the one after it is clean again.
        p.on_sample(&S);
        p.on_sample(&S);
        let Some(DeviceToHost::RawWindow(w)) = p.pop_output() else {
            panic!()
        };
        assert!(w.flags.has(SampleFlags::FRAMES_DROPPED));
        assert_eq!(w.dropped_frames, 12);
        assert_eq!(w.first_sample, 20);
        let Some(DeviceToHost::RawWindow(w)) = p.pop_output() else {
            panic!()
        };
        assert!(!w.flags.has(SampleFlags::FRAMES_DROPPED));
        assert_eq!(w.dropped_frames, 12);
    }

    #[test]
    fn nan_gyro_does_not_poison_the_omega_dot_state() {
        let mut p = calibrated(LeverMode::RateAndAcceleration);
        stream(&mut p, StreamKind::CompensatedWindows, 1);
        let mut bad = S;
        bad.rate_rad_s[2] = f32::INFINITY;
        p.on_sample(&bad);
        for _ in 0..5 {
            p.on_sample(&S);
        }
        let frames: std::vec::Vec<_> = core::iter::from_fn(|| p.pop_output()).collect();
        assert_eq!(frames.len(), 6);
        for f in &frames[1..] {
            let DeviceToHost::CompensatedWindow(w) = f else {
                panic!()
            };
            assert!(w.mean_m_s2.iter().all(|v| v.is_finite()), "{w:?}");
            assert_eq!(w.count, 1);
        }
    }

    #[test]
    fn temperature_readings_average_into_windows_refresh_at_most_4_hz_and_flag_compensated_frames()
    {
        let cal = shared::Calibration {
            temperature: Some(paper_unit::typical_thermal_model()),
            ..paper_unit::calibration()
        };
        let mut p = Pipeline::<8>::new(1000);
        p.apply(PipelineCommand::Compensator(
            Compensator::new(&cal, LeverMode::RateOnly).ok(),
        ));
        let state = |p: &Pipeline<8>| p.compensator().unwrap().temperature_state();
        assert_eq!(state(&p), TemperatureState::NoReading);
        stream(&mut p, StreamKind::CompensatedWindows, 500);
        p.set_temperature(30.0);
        assert_eq!(state(&p), TemperatureState::InRange);
        for k in 0..500 {
            if k == 100 {
                // Within 250 samples of the last refresh: averaged, not applied.
                p.set_temperature(80.0);
                assert_eq!(state(&p), TemperatureState::InRange);
            }
            p.on_sample(&S);
        }
        let Some(DeviceToHost::CompensatedWindow(w)) = p.pop_output() else {
            panic!()
        };
        assert_eq!(w.mean_temp_c, 55.0);
        assert!(!w.flags.has(SampleFlags::TEMPERATURE), "{w:?}");
        // The next reading is due: clamped, flagged on compensated frames only.
        p.set_temperature(80.0);
        assert_eq!(state(&p), TemperatureState::Clamped);
        for _ in 0..500 {
            p.on_sample(&S);
        }
        let Some(DeviceToHost::CompensatedWindow(w)) = p.pop_output() else {
            panic!()
        };
        assert!(w.flags.has(SampleFlags::TEMPERATURE));
        assert_eq!(w.mean_temp_c, 80.0);
        stream(&mut p, StreamKind::RawWindows, 10);
        for _ in 0..10 {
            p.on_sample(&S);
        }
        let Some(DeviceToHost::RawWindow(w)) = p.pop_output() else {
            panic!()
        };
        assert!(!w.flags.has(SampleFlags::TEMPERATURE));
        // No reading in a window: the latest one; a board without a sensor: NaN.
        assert_eq!(w.mean_temp_c, 80.0);
        let mut bare = Pipeline::<8>::new(1000);
        stream(&mut bare, StreamKind::RawWindows, 1);
        bare.on_sample(&S);
        let Some(DeviceToHost::RawWindow(w)) = bare.pop_output() else {
            panic!()
        };
        assert!(w.mean_temp_c.is_nan());
    }

    #[test]
    fn compensated_frames_carry_the_corrected_rate_and_raw_frames_the_gyros_own() {
        let cal = shared::Calibration {
            gyro: Some(paper_unit::typical_gyro()),
            ..paper_unit::calibration()
        };
        let c = Compensator::new(&cal, LeverMode::RateOnly).unwrap();
        let mut p = Pipeline::<8>::new(1000);
        p.apply(PipelineCommand::Compensator(Some(c)));
        stream(&mut p, StreamKind::CompensatedDecimated, 1);
        p.on_sample(&S);
        let Some(DeviceToHost::CompensatedSample(x)) = p.pop_output() else {
            panic!()
        };
        assert_eq!(x.rate_rad_s, c.correct_rate(&S.rate_rad_s).rad_s);
        assert_ne!(x.rate_rad_s, S.rate_rad_s);
        let want = c.compensate(
            &SensorOutputs { raw: S.raw },
            &c.correct_rate(&S.rate_rad_s),
            &BodyAngularAccel::default(),
        );
        assert_eq!(x.specific_force_m_s2, want.m_s2);
        stream(&mut p, StreamKind::RawDecimated, 1);
        p.on_sample(&S);
        let Some(DeviceToHost::RawSample(x)) = p.pop_output() else {
            panic!()
        };
        assert_eq!(x.rate_rad_s, S.rate_rad_s);
    }

    #[test]
    fn is_finite_matches_std() {
        for v in [0.0, -1.0, 3e38, f32::NAN, f32::INFINITY, f32::NEG_INFINITY] {
            for slot in 0..6 {
                let mut s = S;
                if slot < 3 {
                    s.raw[slot] = v;
                } else {
                    s.rate_rad_s[slot - 3] = v;
                }
                assert_eq!(s.is_finite(), v.is_finite(), "{v} at {slot}");
            }
        }
    }
}
