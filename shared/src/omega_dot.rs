//! Angular-acceleration estimate `ω̇` from a gyro stream at a fixed rate (`docs/model.md` §4.6).
//!
//! Differencing gyro samples at kHz rates amplifies their noise by `f_s·√2`, so the difference is
//! smoothed by two cascaded one-pole low-pass sections with the same coefficient `β`:
//!
//! ```text
//! x_n = f_s (ω_n − ω_{n−1});   y_n = y_{n−1} + β (x_n − y_{n−1});   ω̇_n = z_n = z_{n−1} + β (y_n − z_{n−1})
//! ```
//!
//! with `β = 1 − exp(−2π f_c / f_s)` for a corner frequency `f_c`. Its properties, stated here and
//! checked by the tests:
//!
//! - **Latency** (group delay at low frequency): `0.5 + 2(1 − β)/β` samples — half a sample from the
//!   backward difference, `(1 − β)/β` from each pole. A ramp in ω̇ is reproduced exactly after that lag;
//!   a constant ω̇ has no bias.
//! - **Noise gain**: for white gyro noise of standard deviation σ (rad/s), the output's standard deviation
//!   is `σ · f_s · β² · √(Σ h_k²)` with `h` the impulse response of `(1 − z⁻¹)/(1 − (1−β) z⁻¹)²`; see
//!   [`OmegaDotEstimator::noise_gain_per_s`]. At 1 kHz with f_c = 20 Hz it is about 22 /s, so 0.1 °/s of
//!   gyro noise becomes 0.04 rad/s² of ω̇ noise: times a 1 cm lever arm, 40 µg (against a few mg for
//!   the raw difference, `docs/model.md` §4.6). The latency there is 15.4 samples (15 ms).
//!
//! Per sample: 3 axes × (1 subtraction, 1 multiplication, 2 × (1 subtraction + 1 multiply-add)), no
//! division and no branch on data. To turn the ω̇ term off, build the compensator with
//! [`crate::LeverMode::RateOnly`].

/// Filtered backward-difference estimator of `ω̇`, fixed-size state.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct OmegaDotEstimator {
    sample_rate_hz: f32,
    beta: f32,
    /// What the difference is scaled by: `f_s`, or 0 for the first sample after [`Self::new`] or
    /// [`Self::reset`] (which only starts the difference: the stages are zero then, so they stay
    /// zero). A factor rather than a branch or a select per axis on the per-sample path.
    difference_gain_hz: f32,
    previous_rad_s: [f32; 3],
    stage1: [f32; 3],
    stage2: [f32; 3],
}

/// Why an estimator cannot be built.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum OmegaDotError {
    /// Sample rate not positive and finite, or corner frequency not below Nyquist.
    BadFrequencies,
}

impl core::fmt::Display for OmegaDotError {
    fn fmt(&self, f: &mut core::fmt::Formatter<'_>) -> core::fmt::Result {
        write!(f, "ω̇ filter needs 0 < corner frequency < sample rate / 2")
    }
}

/// Lets a host error name this one as its `source()`.
impl core::error::Error for OmegaDotError {}

impl OmegaDotEstimator {
    /// An estimator for gyro samples at `sample_rate_hz`, smoothing above `corner_hz`.
    pub fn new(sample_rate_hz: f32, corner_hz: f32) -> Result<Self, OmegaDotError> {
        let ok = sample_rate_hz.is_finite()
            && corner_hz.is_finite()
            && sample_rate_hz > 0.0
            && corner_hz > 0.0
            && corner_hz < sample_rate_hz / 2.0;
        if !ok {
            return Err(OmegaDotError::BadFrequencies);
        }
        let beta = 1.0
            - libm::exp(
                -2.0 * core::f64::consts::PI * f64::from(corner_hz) / f64::from(sample_rate_hz),
            );
        Ok(OmegaDotEstimator {
            sample_rate_hz,
            beta: beta as f32,
            difference_gain_hz: 0.0,
            previous_rad_s: [0.0; 3],
            stage1: [0.0; 3],
            stage2: [0.0; 3],
        })
    }

    /// Feeds one gyro sample and returns the current `ω̇` estimate (rad/s²) where it lies, in the
    /// estimator (a per-sample caller reads it there, without a copy). The first sample only
    /// starts the difference (its difference is scaled by 0: no branch at all).
    #[inline(always)]
    pub fn update(&mut self, omega_rad_s: &[f32; 3]) -> &[f32; 3] {
        // Per axis written out: straight-line code at any optimisation level (the firmware builds
        // this crate for size). Each product rounded before its addition (Rust never fuses
        // `a * b + c`): the same bits on the PC and on the device (`omega_dot_matches_pc`).
        let gain = self.difference_gain_hz;
        self.axis(0, omega_rad_s[0], gain);
        self.axis(1, omega_rad_s[1], gain);
        self.axis(2, omega_rad_s[2], gain);
        self.previous_rad_s = *omega_rad_s;
        self.difference_gain_hz = self.sample_rate_hz;
        &self.stage2
    }

    #[inline(always)]
    fn axis(&mut self, j: usize, omega_rad_s: f32, gain_hz: f32) {
        // Both finite (the pipeline resets rather than feed a non-finite rate): 0·(ω − ω₋₁) is 0.
        let x = (omega_rad_s - self.previous_rad_s[j]) * gain_hz;
        self.stage1[j] += self.beta * (x - self.stage1[j]);
        self.stage2[j] += self.beta * (self.stage1[j] - self.stage2[j]);
    }

    /// The current `ω̇` estimate (rad/s²), what the last [`Self::update`] returned (0 after
    /// [`Self::reset`]), in place.
    #[inline(always)]
    pub fn estimate(&self) -> &[f32; 3] {
        &self.stage2
    }

    /// Restarts from no history (after a gap in the stream).
    pub fn reset(&mut self) {
        self.difference_gain_hz = 0.0;
        self.stage1 = [0.0; 3];
        self.stage2 = [0.0; 3];
    }

    /// Smoothing coefficient β.
    pub fn beta(&self) -> f32 {
        self.beta
    }

    /// Group delay at low frequency, in samples: `0.5 + 2(1 − β)/β`.
    pub fn latency_samples(&self) -> f64 {
        let b = f64::from(self.beta);
        0.5 + 2.0 * (1.0 - b) / b
    }

    /// Group delay at low frequency, seconds.
    pub fn latency_s(&self) -> f64 {
        self.latency_samples() / f64::from(self.sample_rate_hz)
    }

    /// Output noise standard deviation (rad/s²) per unit of white gyro noise standard deviation
    /// (rad/s), from the impulse response (summed until its terms are below 1e-20 of the total).
    pub fn noise_gain_per_s(&self) -> f64 {
        let c = 1.0 - f64::from(self.beta);
        let b = f64::from(self.beta);
        // h_k of (1 − z⁻¹)/(1 − c z⁻¹)²: g_k = (k+1) c^k, h_k = g_k − g_{k−1}.
        let mut sum = 1.0;
        let mut c_pow = 1.0; // c^(k−1)
        let mut k = 1.0;
        loop {
            let h = c_pow * ((k + 1.0) * c - k);
            sum += h * h;
            if h * h < 1e-20 * sum && k > 10.0 {
                break;
            }
            c_pow *= c;
            k += 1.0;
            if k > 1e7 {
                break;
            }
        }
        f64::from(self.sample_rate_hz) * b * b * libm::sqrt(sum)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use proptest::prelude::*;

    #[test]
    fn rejects_bad_frequencies() {
        assert!(OmegaDotEstimator::new(1000.0, 0.0).is_err());
        assert!(OmegaDotEstimator::new(1000.0, 500.0).is_err());
        assert!(OmegaDotEstimator::new(f32::NAN, 10.0).is_err());
        assert!(OmegaDotEstimator::new(1000.0, 20.0).is_ok());
    }

    /// The first sample (after `new`, and after a `reset` that follows a history) gives 0 and only
    /// starts the difference; the second gives the hand-derived `β²·f_s·(ω₁ − ω₀)`.
    #[test]
    fn the_first_sample_after_new_or_reset_only_starts_the_difference() {
        let mut e = OmegaDotEstimator::new(1000.0, 20.0).unwrap();
        let b = f64::from(e.beta());
        for round in 0..2 {
            assert_eq!(*e.update(&[5.0, -3.0, 0.5]), [0.0; 3], "round {round}");
            let out = *e.update(&[5.001, -3.0, 0.4995]);
            let want = [1e-3f64, 0.0, -5e-4].map(|d| b * b * 1000.0 * d);
            for j in 0..3 {
                let tol = 1e-3 * want[j].abs() + 1e-9;
                assert!(
                    (f64::from(out[j]) - want[j]).abs() <= tol,
                    "{out:?} vs {want:?}"
                );
            }
            // A history far from the next start: the reset must not difference across it.
            for _ in 0..50 {
                e.update(&[-40.0, 40.0, 7.0]);
            }
            e.reset();
        }
    }

    #[test]
    fn constant_acceleration_is_unbiased() {
        let fs = 1000.0;
        let mut e = OmegaDotEstimator::new(fs, 20.0).unwrap();
        let alpha = [3.0f64, -1.5, 0.25];
        let mut out = [0.0; 3];
        for n in 0..2000 {
            let t = f64::from(n) / f64::from(fs);
            out = *e.update(&alpha.map(|a| (a * t) as f32));
        }
        for j in 0..3 {
            assert!(
                (f64::from(out[j]) - alpha[j]).abs() < 1e-3 * alpha[j].abs().max(1.0),
                "{out:?}"
            );
        }
    }

    #[test]
    fn ramp_in_acceleration_lags_by_the_stated_latency() {
        // ω = ½ j t²  →  ω̇ = j t. The estimate equals j (t − latency) once the transient has died.
        let fs = 1000.0f32;
        let mut e = OmegaDotEstimator::new(fs, 20.0).unwrap();
        let jerk = 50.0f64;
        let n_end = 3000;
        let mut out = 0.0f32;
        for n in 0..=n_end {
            let t = f64::from(n) / f64::from(fs);
            out = e.update(&[(0.5 * jerk * t * t) as f32, 0.0, 0.0])[0];
        }
        let t_end = f64::from(n_end) / f64::from(fs);
        let measured_latency_s = t_end - f64::from(out) / jerk;
        let stated = e.latency_s();
        assert!(
            (e.latency_samples() - 15.4).abs() < 0.1,
            "docs quote 15.4 samples"
        );
        assert!(
            (measured_latency_s - stated).abs() < 0.02 * stated,
            "{measured_latency_s} vs {stated}"
        );
    }

    #[test]
    fn noise_gain_matches_a_monte_carlo() {
        let fs = 1000.0f32;
        let mut e = OmegaDotEstimator::new(fs, 20.0).unwrap();
        let mut state = 0x9e37_79b9_7f4a_7c15u64;
        let mut uniform = move || {
            // SplitMix64: a fixed, independent noise source for the test.
            state = state.wrapping_add(0x9e37_79b9_7f4a_7c15);
            let mut z = state;
            z = (z ^ (z >> 30)).wrapping_mul(0xbf58_476d_1ce4_e5b9);
            z = (z ^ (z >> 27)).wrapping_mul(0x94d0_49bb_1331_11eb);
            ((z ^ (z >> 31)) >> 11) as f64 / (1u64 << 53) as f64
        };
        let sigma = 0.01f64;
        let n = 200_000;
        let (mut s, mut s2) = (0.0f64, 0.0f64);
        for i in 0..n {
            // Sum of 12 uniforms − 6: unit-variance, near-Gaussian.
            let g: f64 = (0..12).map(|_| uniform()).sum::<f64>() - 6.0;
            let y = f64::from(e.update(&[(sigma * g) as f32, 0.0, 0.0])[0]);
            if i > 1000 {
                s += y;
                s2 += y * y;
            }
        }
        let m = (n - 1001) as f64;
        let std = (s2 / m - (s / m).powi(2)).sqrt();
        let predicted = sigma * e.noise_gain_per_s();
        assert!(
            (std / predicted - 1.0).abs() < 0.03,
            "measured {std}, predicted {predicted}"
        );
        // The figure quoted in the module docs.
        assert!(
            (e.noise_gain_per_s() - 22.2).abs() < 0.1,
            "{}",
            e.noise_gain_per_s()
        );
    }

    proptest! {
        /// Never NaN from finite input, for any rate and corner.
        #[test]
        fn finite_in_finite_out(fs in 100.0f32..20000.0, frac in 0.001f32..0.45, w in prop::array::uniform3(-40.0f32..40.0)) {
            let mut e = OmegaDotEstimator::new(fs, fs * frac).unwrap();
            for _ in 0..10 {
                let out = *e.update(&w);
                prop_assert!(out.iter().all(|v| v.is_finite()));
            }
        }
    }
}
