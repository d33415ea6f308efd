//! Runs of clean samples: the per-sample path with its configuration decided once per run.
//!
//! A digital IMU's board hands the pipeline a DMA transfer's samples at once (16 FIFO packets). In a
//! run of clean samples — finite, unsaturated, following no loss: nearly all of them — what the
//! pipeline does per sample depends only on its configuration (stream kind, lever mode, calibrated
//! or not), which cannot change within the run. [`Pipeline::on_run`] picks one of five loops once per
//! run, and each does for each sample exactly what [`Pipeline::on_sample`] does for a clean one, in
//! the same order and with the same arithmetic, so that the frames are bit for bit the per-sample
//! path's (tests in `run_tests.rs`). A run stops at the first sample that is not clean: the caller
//! passes that one to `on_sample`.

use shared::units::SensorOutputs;
use shared::wire::StreamKind;

use super::{omega_dot_update, window_add, Pipeline, SampleView};

/// The five loops: what a clean sample costs besides the gyro correction and the ω̇ update.
const IDLE: u8 = 0;
const RAW_WINDOW: u8 = 1;
const UNCALIBRATED_WINDOW: u8 = 2;
const STATIC_WINDOW: u8 = 3;
const FULL_WINDOW: u8 = 4;

impl<const Q: usize> Pipeline<Q> {
    /// Processes the clean samples at the front of `run` as [`Pipeline::on_sample`] would, calling
    /// `each` on each first (a board's feed adds its temperature there), and returns how many: it
    /// stops at the first sample that is not [`SampleView::clean`]. Returns 0 while a decimated
    /// stream runs (its frames are built per sample: pass those to `on_sample`).
    #[inline(always)]
    pub fn on_run<S: SampleView, F: FnMut(&S)>(&mut self, run: &[S], each: F) -> usize {
        let compensated = match &self.compensator {
            None => UNCALIBRATED_WINDOW,
            Some(c) if c.mode() == shared::LeverMode::Off => STATIC_WINDOW,
            Some(_) => FULL_WINDOW,
        };
        match self.stream.map(|r| r.kind) {
            None => self.run_as::<IDLE, S, F>(run, each),
            Some(StreamKind::RawWindows) => self.run_as::<RAW_WINDOW, S, F>(run, each),
            Some(StreamKind::CompensatedWindows) => match compensated {
                UNCALIBRATED_WINDOW => self.run_as::<UNCALIBRATED_WINDOW, S, F>(run, each),
                STATIC_WINDOW => self.run_as::<STATIC_WINDOW, S, F>(run, each),
                _ => self.run_as::<FULL_WINDOW, S, F>(run, each),
            },
            Some(StreamKind::RawDecimated | StreamKind::CompensatedDecimated) => 0,
        }
    }

    /// One loop: `R` is the route, fixed by the caller from the configuration. The window's sample
    /// is built in place: the gyro correction and the compensation write their results into it.
    #[inline(always)]
    fn run_as<const R: u8, S: SampleView, F: FnMut(&S)>(
        &mut self,
        run: &[S],
        mut each: F,
    ) -> usize {
        let (kind, window) = match self.stream {
            Some(req) => (req.kind, req.window_samples),
            None => (StreamKind::RawWindows, u32::MAX), // IDLE: never read
        };
        // The sample index and the window's count live in registers for the run, written back
        // where `close_window` reads them and at the end.
        let start = self.index;
        let mut in_window = self.in_window;
        let mut n = 0;
        // Specific force (or raw outputs) then rate; the body rate of a raw window's sample apart.
        let mut x = [0f32; 6];
        let mut body_rate = [0f32; 3];
        for s in run {
            if !s.clean() {
                break;
            }
            let Some((f, r)) = halves(&mut x) else {
                break;
            };
            each(s);
            n += 1;
            let (raw, gyro) = (s.raw(), s.rate_rad_s());
            let rate = if R == RAW_WINDOW { &mut body_rate } else { r };
            // The full compensation's loop, the digital IMU's budgeted path, keeps the gyro
            // correction, the ω̇ update and the window accumulation in line; the others call the
            // out-of-line copies.
            if R == FULL_WINDOW {
                self.body_rate_into(gyro, rate);
                self.omega_dot.update(rate);
            } else {
                self.body_rate_into_outlined(gyro, rate);
                omega_dot_update(&mut self.omega_dot, rate);
            }
            match (R, &self.compensator) {
                (IDLE, _) => continue,
                (STATIC_WINDOW, Some(c)) => {
                    *f = c.compensate_static(&SensorOutputs { raw: *raw }).m_s2;
                }
                (FULL_WINDOW, Some(c)) => {
                    *f = c.compensate_raw(raw, rate, self.omega_dot.estimate());
                }
                _ => *f = *raw,
            }
            if R == RAW_WINDOW {
                if let Some((_, r)) = halves(&mut x) {
                    *r = *gyro;
                }
            }
            if R == FULL_WINDOW {
                self.acc.add(&x);
            } else {
                window_add(&mut self.acc, &x);
            }
            in_window += 1;
            if in_window >= window {
                self.index = start + n as u64;
                self.in_window = in_window;
                self.close_window(kind);
                in_window = self.in_window;
            }
        }
        self.index = start + n as u64;
        if R != IDLE {
            self.in_window = in_window;
        }
        n
    }
}

/// The two halves of a window's sample, as arrays (always `Some`: the lengths are constants).
#[inline(always)]
fn halves(x: &mut [f32; 6]) -> Option<(&mut [f32; 3], &mut [f32; 3])> {
    let (a, b) = x.split_at_mut(3);
    Some((a.try_into().ok()?, b.try_into().ok()?))
}
