//! The pipeline's side of a digital IMU: how it reads a driver's decoded sample in place
//! ([`SampleView`] for [`ImuSample`]) and how a board's sampling task hands a FIFO read's samples
//! to it ([`PipelineFeed`]). It lives here, not in `imu`, so that the drivers stay a leaf the
//! pipeline uses: they know nothing of the pipeline, and a driver can be built and tested alone.

use super::{Pipeline, SampleView};
use crate::imu::{ImuFlags, ImuSample};
use crate::sampling::TemperatureMean;

/// The pipeline reads a decoded sample in place (no copy into a `pipeline::Sample` per sample).
impl SampleView for ImuSample {
    #[inline(always)]
    fn raw(&self) -> &[f32; 3] {
        &self.accel_out
    }
    #[inline(always)]
    fn rate_rad_s(&self) -> &[f32; 3] {
        &self.gyro_rad_s
    }
    #[inline(always)]
    fn saturated(&self) -> bool {
        self.flags.has(ImuFlags::SATURATED)
    }
    /// The flag, not the six values: a driver's values are integer codes times a factor whose
    /// product with the largest code its configuration check has shown finite, so they are finite
    /// unless the part marked them invalid (then NaN, and flagged).
    #[inline(always)]
    fn finite(&self) -> bool {
        !self.flags.has(ImuFlags::INVALID)
    }
    /// No flag at all: finite, unsaturated, and no loss before it (which `PipelineFeed::push`
    /// reports first).
    #[inline(always)]
    fn clean(&self) -> bool {
        self.flags.0 == 0
    }
}

/// Hands decoded samples to the pipeline as a board's sampling task does: a loss first (so that
/// the pipeline's sample index and ω̇ know of the gap), the part's temperature averaged over each
/// `1/TEMPERATURE_REFRESH_HZ` s of samples ([`TemperatureMean`]), then the sample.
pub struct PipelineFeed {
    temperature: TemperatureMean,
}

impl PipelineFeed {
    /// For samples at `sample_rate_hz`.
    pub fn new(sample_rate_hz: u32) -> Self {
        PipelineFeed {
            temperature: TemperatureMean::new(sample_rate_hz),
        }
    }

    /// A transfer's decoded samples into the pipeline, oldest first: what a board's sampling task
    /// calls once per FIFO read. Out of line, so that the pipeline and the feed stay in registers
    /// across the batch rather than being addressed again for each sample.
    ///
    /// Clean samples go through [`Pipeline::on_run`] in runs that end before the temperature
    /// period's last sample (whose push hands the period's mean to the pipeline first); the others
    /// go one by one through [`PipelineFeed::push`]. Either way each sample gets exactly what `push`
    /// gives it.
    #[inline(never)]
    pub fn push_all<const Q: usize>(&mut self, samples: &[ImuSample], p: &mut Pipeline<Q>) {
        let mut rest = samples;
        while let Some((first, tail)) = rest.split_first() {
            let room = self.temperature.room().min(rest.len());
            let mut sum_c = self.temperature.sum_c();
            let n = p.on_run(&rest[..room], |s| sum_c += s.temp_c);
            self.temperature.add_run(sum_c, n);
            if n == 0 {
                self.push(first, p);
                rest = tail;
            } else {
                rest = &rest[n..];
            }
        }
    }

    /// One decoded sample into the pipeline.
    #[inline(always)]
    pub fn push<const Q: usize>(&mut self, s: &ImuSample, p: &mut Pipeline<Q>) {
        if s.flags.has(ImuFlags::DATA_LOST) {
            p.on_samples_lost(u32::from(s.lost_before));
        }
        if let Some(t) = self.temperature.push(s.temp_c) {
            p.set_temperature(t);
        }
        p.on_sample(s);
    }
}
