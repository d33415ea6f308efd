//! The per-sample work, written once: the gyro correction and the ω̇ update of every sample
//! ([`Pipeline::rate_step`]), the compensation and accumulation of a clean sample in a window
//! stream ([`Pipeline::window_step`]) and the window's count and close
//! ([`Pipeline::count_in_window`]).
//!
//! [`Pipeline::on_sample`] and the run loops (`run.rs`) both call these, so that a run's frames are
//! the per-sample path's by construction, not only by test (`run_tests.rs` still compares them).
//! A step is instantiated per route `R`: a run loop passes its route, fixed for the run, and the
//! compiler folds the route's tests away; `on_sample` passes [`PER_SAMPLE`] and reads its
//! configuration per sample.

use shared::compensator::LeverMode;
use shared::units::SensorOutputs;
use shared::wire::{StreamKind, StreamRequest};

use super::{omega_dot_update, window_add, Pipeline};

// The routes: what a clean sample costs besides the gyro correction and the ω̇ update. The first
// five are the run loops' (`run.rs`), decided once per run.

/// Not streaming: nothing besides.
pub(super) const IDLE: u8 = 0;
/// Raw windows: the accelerometer's outputs and the gyro's own rate.
pub(super) const RAW_WINDOW: u8 = 1;
/// Compensated windows, uncalibrated: the outputs passed through, the rate as the gyro gives it.
pub(super) const UNCALIBRATED_WINDOW: u8 = 2;
/// Compensated windows, lever arms off: the static compensation.
pub(super) const STATIC_WINDOW: u8 = 3;
/// Compensated windows with the lever-arm terms: the full compensation, the digital IMU's
/// budgeted path.
pub(super) const FULL_WINDOW: u8 = 4;
/// `on_sample`'s, for any stream: the stream kind and the compensator read per sample, the
/// out-of-line copies called.
pub(super) const PER_SAMPLE: u8 = 5;

impl<const Q: usize> Pipeline<Q> {
    /// The route of a compensated window's sample under the compensator in force.
    #[inline(always)]
    pub(super) fn compensated_route(&self) -> u8 {
        match &self.compensator {
            None => UNCALIBRATED_WINDOW,
            Some(c) if c.mode() == LeverMode::Off => STATIC_WINDOW,
            Some(_) => FULL_WINDOW,
        }
    }

    /// The specific force (m/s²) of a finite sample on a compensated route, or the raw outputs
    /// passed through when uncalibrated. `route` is a constant in the run loops, which keep their
    /// copy in line.
    #[inline(always)]
    fn compensate_as(
        &self,
        route: u8,
        raw: &[f32; 3],
        rate: &[f32; 3],
        omega_dot: &[f32; 3],
    ) -> [f32; 3] {
        match (route, &self.compensator) {
            (STATIC_WINDOW, Some(c)) => c.compensate_static(&SensorOutputs { raw: *raw }).m_s2,
            (FULL_WINDOW, Some(c)) => c.compensate_raw(raw, rate, omega_dot),
            _ => *raw,
        }
    }

    /// [`Pipeline::compensate_as`] on the compensator's route, out of line: `on_sample` needs it
    /// for windows and decimated samples alike, and the run loops (`run.rs`), the digital IMU's
    /// per-sample path, have their own copies in line (0.4 KiB of the QEMU image; the ADC path's
    /// call costs about 40 instructions per sample of its 0.5 % budget's 900).
    #[inline(never)]
    pub(super) fn compensate(
        &self,
        raw: &[f32; 3],
        rate: &[f32; 3],
        omega_dot: &[f32; 3],
    ) -> [f32; 3] {
        self.compensate_as(self.compensated_route(), raw, rate, omega_dot)
    }

    /// Every sample's first step: the body rate into `rate` (the gyro's output corrected by the
    /// calibration), then the ω̇ update, or its restart for a non-finite sample so that NaN never
    /// enters its state. The full compensation's route, the digital IMU's budgeted path, keeps the
    /// correction and the update in line; the others call the out-of-line copies.
    #[inline(always)]
    pub(super) fn rate_step<const R: u8>(
        &mut self,
        gyro: &[f32; 3],
        finite: bool,
        rate: &mut [f32; 3],
    ) {
        if R == FULL_WINDOW {
            self.body_rate_into(gyro, rate);
        } else {
            self.body_rate_into_outlined(gyro, rate);
        }
        if !finite {
            self.omega_dot.reset();
        } else if R == FULL_WINDOW {
            self.omega_dot.update(rate);
        } else {
            omega_dot_update(&mut self.omega_dot, rate);
        }
    }

    /// A clean sample into the window, after [`Pipeline::rate_step`]: `x` is the window's sample,
    /// built in place, whose second half holds the body rate (on every route but [`RAW_WINDOW`],
    /// which keeps it apart). The compensation writes the first half; a raw window's sample is the
    /// outputs and the gyro's own rate. Then the accumulation (in line on the full compensation's
    /// route, as [`Pipeline::rate_step`]'s steps) and [`Pipeline::count_in_window`].
    #[inline(always)]
    pub(super) fn window_step<const R: u8>(
        &mut self,
        raw: &[f32; 3],
        gyro: &[f32; 3],
        x: &mut [f32; 6],
        req: StreamRequest,
        index: impl FnOnce() -> u64,
        in_window: &mut u32,
    ) {
        let Some((f, r)) = halves(x) else {
            return;
        };
        if R == RAW_WINDOW || (R == PER_SAMPLE && req.kind == StreamKind::RawWindows) {
            *f = *raw;
            *r = *gyro;
        } else if R == PER_SAMPLE {
            *f = self.compensate(raw, r, self.omega_dot.estimate());
        } else {
            *f = self.compensate_as(R, raw, r, self.omega_dot.estimate());
        }
        if R == FULL_WINDOW {
            self.acc.add(x);
        } else {
            window_add(&mut self.acc, x);
        }
        self.count_in_window(req, index, in_window);
    }

    /// A sample counted in the window (clean or rejected), and the window closed when full.
    /// `in_window` is the window's count and `index` gives the sample index after the sample, both
    /// kept in registers by a run and written back where `close_window` reads them. `index` is
    /// asked for only when the window closes: the 64-bit sum of a run's start and count, formed
    /// at every sample, cost the full compensation's loop 8 instructions per sample.
    #[inline(always)]
    pub(super) fn count_in_window(
        &mut self,
        req: StreamRequest,
        index: impl FnOnce() -> u64,
        in_window: &mut u32,
    ) {
        *in_window += 1;
        if *in_window >= req.window_samples {
            self.index = index();
            self.in_window = *in_window;
            self.close_window(req.kind);
            *in_window = self.in_window;
        }
    }
}

/// The two halves of a window's sample, as arrays (always `Some`: the lengths are constants).
#[inline(always)]
pub(super) fn halves(x: &mut [f32; 6]) -> Option<(&mut [f32; 3], &mut [f32; 3])> {
    let (a, b) = x.split_at_mut(3);
    Some((a.try_into().ok()?, b.try_into().ok()?))
}
