//! Board-independent pieces of the sampling tasks: the temperature decimator (which the digital
//! IMU's [`crate::pipeline::PipelineFeed`] and the Nucleo's ADC task both use) and the layout of the
//! Nucleo's ADC scan.
//!
//! Both STM32 boards get a temperature with every sample (the ICM-42688-P puts its die temperature in
//! each FIFO packet; the Nucleo's ADC scan converts the on-chip sensor with the accelerometers), but
//! the pipeline wants a few readings a second ([`crate::pipeline::TEMPERATURE_REFRESH_HZ`]): each one
//! enters the window mean and may refresh the compensator. [`TemperatureMean`] averages the
//! per-sample readings over one refresh period — it adds per sample and multiplies once per period,
//! no division on the per-sample path — so the pipeline sees a less noisy reading at its own pace.

use crate::pipeline::TEMPERATURE_REFRESH_HZ;

/// Averages per-sample temperatures over `1/TEMPERATURE_REFRESH_HZ` s. The first reading after
/// [`TemperatureMean::new`] is passed on at once (the compensator is refreshed from the first
/// sample rather than after a period at its reference temperature), then one mean per period.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct TemperatureMean {
    period: u32,
    inv_period: f32,
    /// Readings still to come in the current period.
    left: u32,
    /// The reciprocal of the current period's length (1 for the first reading).
    inv_current: f32,
    sum_c: f32,
}

impl TemperatureMean {
    /// For samples at `sample_rate_hz`: one mean per `sample_rate_hz / TEMPERATURE_REFRESH_HZ`
    /// samples (at least 1).
    pub fn new(sample_rate_hz: u32) -> Self {
        let period = (sample_rate_hz / TEMPERATURE_REFRESH_HZ).max(1);
        TemperatureMean {
            period,
            inv_period: 1.0 / period as f32,
            left: 1,
            inv_current: 1.0,
            sum_c: 0.0,
        }
    }

    /// Samples per mean.
    pub fn period(&self) -> u32 {
        self.period
    }

    /// Adds one sample's temperature, °C. At the end of a period, returns the mean of its
    /// readings — or NaN if any reading was not finite (a failed or implausible read must reach the
    /// pipeline, which flags it, rather than be averaged away).
    ///
    /// Per sample one addition and a count: a non-finite reading makes the sum non-finite (NaN and
    /// ±∞ propagate through addition), so the check is once per period, on the sum.
    #[inline(always)]
    pub fn push(&mut self, temp_c: f32) -> Option<f32> {
        self.sum_c += temp_c;
        self.left -= 1;
        if self.left != 0 {
            return None;
        }
        Some(self.end_period())
    }

    /// Readings that can be added before the one that ends the period (see
    /// [`TemperatureMean::add_run`]).
    #[inline(always)]
    pub fn room(&self) -> usize {
        self.left.saturating_sub(1) as usize
    }

    /// The current period's sum so far, °C: where a run of readings starts adding.
    #[inline(always)]
    pub fn sum_c(&self) -> f32 {
        self.sum_c
    }

    /// [`TemperatureMean::push`] of `readings` readings that do not end the period (at most
    /// [`TemperatureMean::room`]), which the caller has added one by one, in order, to
    /// [`TemperatureMean::sum_c`] to give `sum_c`: the same sum as pushing them, kept in a register
    /// meanwhile.
    #[inline(always)]
    pub fn add_run(&mut self, sum_c: f32, readings: usize) {
        let readings = (readings as u32).min(self.left.saturating_sub(1));
        self.sum_c = sum_c;
        self.left -= readings;
    }

    #[inline(never)]
    fn end_period(&mut self) -> f32 {
        let sum = self.sum_c;
        let mean = if sum.is_finite() {
            sum * self.inv_current
        } else {
            f32::NAN
        };
        self.left = self.period;
        self.inv_current = self.inv_period;
        self.sum_c = 0.0;
        mean
    }
}

/// The Nucleo's regular ADC sequence, in DMA buffer order: the three accelerometers, then the
/// on-chip temperature sensor.
pub const ADC_SCAN_LEN: usize = 4;

/// Splits one ADC scan (DMA buffer order, [`ADC_SCAN_LEN`] codes, each a word as the DMA reads
/// ADC_DR: the code in the lower half, zeros above) into the accelerometer codes and the
/// temperature sensor's code.
#[inline(always)]
pub fn split_scan(scan: &[u32; ADC_SCAN_LEN]) -> ([u32; 3], u16) {
    ([scan[0], scan[1], scan[2]], scan[3] as u16)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_first_reading_at_once_then_one_mean_per_refresh_period() {
        // 8 kHz: a mean every 2000 samples (4 per second).
        let mut t = TemperatureMean::new(8000);
        assert_eq!(t.period(), 2000);
        let mut means = [0.0f32; 3];
        let mut n = 0;
        for i in 0..6000u32 {
            // 30 °C and 20 °C alternating: the first reading is 20 °C, each period after it holds
            // 1000 of each, so its mean is 25 °C exactly.
            let reading = if i % 2 == 0 { 20.0 } else { 30.0 };
            if let Some(m) = t.push(reading) {
                means[n] = m;
                n += 1;
                assert_eq!(i % 2000, 0, "mean at sample {i}");
            }
        }
        assert_eq!(n, 3);
        assert_eq!(means[0], 20.0);
        for m in &means[1..] {
            assert!((m - 25.0).abs() < 1e-3, "{m}");
        }
    }

    #[test]
    fn a_bad_reading_makes_the_period_nan_and_the_next_recovers() {
        for bad in [f32::NAN, f32::INFINITY, f32::NEG_INFINITY] {
            let mut t = TemperatureMean::new(1000);
            assert_eq!(t.period(), 250);
            assert_eq!(t.push(40.0), Some(40.0));
            let mut out = None;
            for i in 0..250 {
                out = t.push(if i == 100 { bad } else { 40.0 });
            }
            assert!(out.is_some_and(f32::is_nan), "{bad}: {out:?}");
            for _ in 0..250 {
                out = t.push(41.0);
            }
            // f32 sum times the reciprocal of the period: a rounding or two from 41.
            assert!(out.is_some_and(|m| (m - 41.0).abs() < 1e-4), "{out:?}");
        }
    }

    #[test]
    fn a_bad_first_reading_is_passed_on_as_nan() {
        let mut t = TemperatureMean::new(1000);
        assert!(t.push(f32::NAN).is_some_and(f32::is_nan));
        assert_eq!(t.push(30.0), None);
    }

    #[test]
    fn slow_rates_still_deliver() {
        let mut t = TemperatureMean::new(2);
        assert_eq!(t.period(), 1);
        assert_eq!(t.push(5.0), Some(5.0));
        assert_eq!(t.push(6.0), Some(6.0));
    }

    #[test]
    fn scan_order() {
        let (c, temp) = split_scan(&[1, 2, 3, 940]);
        assert_eq!(c, [1, 2, 3]);
        assert_eq!(temp, 940);
    }
}
