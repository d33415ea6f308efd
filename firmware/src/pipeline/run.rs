//! Runs of clean samples: the per-sample path with its configuration decided once per run.
//!
//! A digital IMU's board hands the pipeline a DMA transfer's samples at once (16 FIFO packets). In a
//! run of clean samples — finite, unsaturated, following no loss: nearly all of them — what the
//! pipeline does per sample depends only on its configuration (stream kind, lever mode, calibrated
//! or not), which cannot change within the run. [`Pipeline::on_run`] picks one of five loops once per
//! run, and each calls for each sample the steps [`Pipeline::on_sample`] calls for a clean one
//! (`step.rs`, written once), with its route as a constant, so that the frames are bit for bit the
//! per-sample path's (tests in `run_tests.rs`). A run stops at the first sample that is not clean:
//! the caller passes that one to `on_sample`.

use shared::wire::{StreamKind, StreamRequest};

use super::step::{halves, FULL_WINDOW, IDLE, RAW_WINDOW, STATIC_WINDOW, UNCALIBRATED_WINDOW};
use super::{Pipeline, SampleView};

impl<const Q: usize> Pipeline<Q> {
    /// Processes the clean samples at the front of `run` as [`Pipeline::on_sample`] would, calling
    /// `each` on each first (a board's feed adds its temperature there), and returns how many: it
    /// stops at the first sample that is not [`SampleView::clean`]. Returns 0 while a decimated
    /// stream runs (its frames are built per sample: pass those to `on_sample`).
    #[inline(always)]
    pub fn on_run<S: SampleView, F: FnMut(&S)>(&mut self, run: &[S], each: F) -> usize {
        let compensated = self.compensated_route();
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
    /// The full compensation's loop keeps its steps in line, the others call out-of-line copies
    /// (`step.rs`).
    #[inline(always)]
    fn run_as<const R: u8, S: SampleView, F: FnMut(&S)>(
        &mut self,
        run: &[S],
        mut each: F,
    ) -> usize {
        let req = self.stream.unwrap_or(StreamRequest {
            kind: StreamKind::RawWindows, // IDLE: never read
            window_samples: u32::MAX,
        });
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
            let Some((_, r)) = halves(&mut x) else {
                break;
            };
            each(s);
            n += 1;
            let rate = if R == RAW_WINDOW { &mut body_rate } else { r };
            self.rate_step::<R>(s.rate_rad_s(), true, rate);
            if R != IDLE {
                self.window_step::<R>(
                    s.raw(),
                    s.rate_rad_s(),
                    &mut x,
                    req,
                    || start + n as u64,
                    &mut in_window,
                );
            }
        }
        self.index = start + n as u64;
        if R != IDLE {
            self.in_window = in_window;
        }
        n
    }
}
