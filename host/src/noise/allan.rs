//! Overlapping Allan deviation and the fit of the noise terms to it (IEEE Std 952, Annex C).
//!
//! For rate samples `y_k` at interval `τ₀`, with the integrated signal `X_0 = 0`, `X_k = τ₀ Σ_{i<k} y_i`:
//!
//! ```text
//! σ²(mτ₀) = Σ_{k=0}^{N−2m} (X_{k+2m} − 2X_{k+m} + X_k)² / (2 (mτ₀)² (N − 2m + 1))
//! ```
//!
//! which is the estimator `allantools.oadev` uses (its `frequency2phase` and `calc_adev_phase`).
//! Averaging times are octave-spaced, `m = 1, 2, 4, …` while at least 4 independent clusters remain.
//!
//! The fit models `σ²(τ) = N²/τ + (2 ln 2/π) B² + K² τ/3` (white noise density N, bias instability
//! B, random walk K): linear in (N², B², K²), solved by least squares weighted by each point's
//! relative uncertainty (`σ²` has about `√(2/ν)` relative error with ν ≈ (N − 2m)/m clusters).
//! A coefficient the data drive negative is not determined by them: it is dropped, reported as
//! `None`, and the rest refitted.

use serde::{Deserialize, Serialize};

/// One point of an Allan deviation curve.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
pub struct AllanPoint {
    /// Averaging time, s.
    pub tau_s: f64,
    /// Allan deviation, in the signal's unit.
    pub adev: f64,
    /// Number of terms in the sum (N − 2m + 1).
    pub terms: u64,
}

/// Octave-spaced cluster sizes for `n` samples.
pub fn octave_sizes(n: usize) -> Vec<usize> {
    let mut out = Vec::new();
    let mut m = 1usize;
    while 4 * m <= n / 2 {
        out.push(m);
        m *= 2;
    }
    out
}

/// Overlapping Allan deviation of rate samples `y` at `rate_hz` for the cluster sizes `sizes`.
/// `X` is accumulated in f64 after removing the mean, which keeps the second differences exact to
/// rounding even for long records of a large constant (the mean cancels in the differences).
pub fn overlapping_adev(y: &[f64], rate_hz: f64, sizes: &[usize]) -> Vec<AllanPoint> {
    let n = y.len();
    if n == 0 {
        return Vec::new();
    }
    let mean = y.iter().sum::<f64>() / n as f64;
    let tau0 = 1.0 / rate_hz;
    let mut x = Vec::with_capacity(n + 1);
    x.push(0.0);
    let mut acc = 0.0;
    for v in y {
        acc += (v - mean) * tau0;
        x.push(acc);
    }
    sizes
        .iter()
        .filter(|&&m| m >= 1 && 2 * m < n + 1)
        .map(|&m| {
            let terms = n + 1 - 2 * m;
            let mut s = 0.0;
            for k in 0..terms {
                let d = x[k + 2 * m] - 2.0 * x[k + m] + x[k];
                s += d * d;
            }
            let tau = m as f64 * tau0;
            AllanPoint {
                tau_s: tau,
                adev: (s / (2.0 * terms as f64)).sqrt() / tau,
                terms: terms as u64,
            }
        })
        .collect()
}

/// The fitted noise terms of one axis; `None`: not determined by the data.
#[derive(Clone, Copy, Debug, Default, PartialEq, Serialize, Deserialize)]
pub struct NoiseTerms {
    /// White noise density N (unit/√Hz = unit·√s): the −½ slope line at τ = 1 s.
    pub white_density: Option<f64>,
    /// Bias instability B (unit): the flat floor is 0.664 B.
    pub bias_instability: Option<f64>,
    /// Random walk K (unit/√s): the +½ slope line at τ = 3 s.
    pub random_walk: Option<f64>,
}

impl NoiseTerms {
    /// The model's Allan deviation at `tau_s`.
    pub fn adev(&self, tau_s: f64) -> f64 {
        let n = self.white_density.unwrap_or(0.0);
        let b = self.bias_instability.unwrap_or(0.0);
        let k = self.random_walk.unwrap_or(0.0);
        (n * n / tau_s + FLICKER_FACTOR * b * b + k * k * tau_s / 3.0).sqrt()
    }
}

/// `2 ln 2 / π`: Allan variance of flicker noise per B².
pub const FLICKER_FACTOR: f64 = 2.0 * std::f64::consts::LN_2 / std::f64::consts::PI;

/// Fits [`NoiseTerms`] to a curve (needs at least 3 points).
pub fn fit(points: &[AllanPoint]) -> NoiseTerms {
    let basis = |tau: f64| [1.0 / tau, FLICKER_FACTOR, tau / 3.0];
    let mut active = [true; 3];
    loop {
        let idx: Vec<usize> = (0..3).filter(|&i| active[i]).collect();
        if idx.is_empty() || points.len() < idx.len() {
            return NoiseTerms::default();
        }
        // Weighted normal equations on σ², weight = (1/(σ² · rel))², rel ≈ √(2m/(N−2m)).
        let k = idx.len();
        let mut ata = nalgebra::DMatrix::<f64>::zeros(k, k);
        let mut atb = nalgebra::DVector::<f64>::zeros(k);
        for p in points {
            let var = p.adev * p.adev;
            if var.is_nan() || var <= 0.0 {
                continue;
            }
            let clusters = (p.terms as f64 / (p.tau_s / points[0].tau_s)).max(1.0);
            let w = 1.0 / (var * (2.0 / clusters).sqrt());
            let b = basis(p.tau_s);
            let row: Vec<f64> = idx.iter().map(|&i| b[i] * w).collect();
            for r in 0..k {
                atb[r] += row[r] * var * w;
                for c in 0..k {
                    ata[(r, c)] += row[r] * row[c];
                }
            }
        }
        let Some(sol) = ata.lu().solve(&atb) else {
            return NoiseTerms::default();
        };
        if let Some(worst) = (0..k)
            .filter(|&r| sol[r] <= 0.0)
            .min_by(|&a, &b| sol[a].total_cmp(&sol[b]))
        {
            active[idx[worst]] = false;
            continue;
        }
        let mut c = [None; 3];
        for (r, &i) in idx.iter().enumerate() {
            c[i] = Some(sol[r].sqrt());
        }
        return NoiseTerms {
            white_density: c[0],
            bias_instability: c[1],
            random_walk: c[2],
        };
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A case small enough to do by hand: y = [1, 3, 2, 6, 4], τ₀ = 1 s, mean 3.2.
    /// X = [0, −2.2, −2.4, −3.6, −0.8, 0]. m = 1: second differences −0.2−(−2.2)… computed below
    /// from X directly: (X2 − 2X1 + X0) = −2.4 + 4.4 = 2.0; (X3 − 2X2 + X1) = −3.6 + 4.8 − 2.2 = −1.0;
    /// (X4 − 2X3 + X2) = −0.8 + 7.2 − 2.4 = 4.0; (X5 − 2X4 + X3) = 0 + 1.6 − 3.6 = −2.0.
    /// σ² = (4 + 1 + 16 + 4)/(2·4) = 3.125. m = 2: (X4 − 2X2 + X0) = −0.8 + 4.8 = 4.0;
    /// (X5 − 2X3 + X1) = 0 + 7.2 − 2.2 = 5.0; σ² = (16 + 25)/(2·2·4) = 2.5625.
    #[test]
    fn hand_computed_small_case() {
        let p = overlapping_adev(&[1.0, 3.0, 2.0, 6.0, 4.0], 1.0, &[1, 2]);
        assert_eq!(p.len(), 2);
        assert!((p[0].adev - 3.125f64.sqrt()).abs() < 1e-12, "{p:?}");
        assert_eq!(p[0].terms, 4);
        assert!((p[1].adev - 2.5625f64.sqrt()).abs() < 1e-12, "{p:?}");
        assert_eq!(p[1].terms, 2);
    }

    #[test]
    fn fit_recovers_a_noise_free_model_curve_and_drops_absent_terms() {
        let truth = NoiseTerms {
            white_density: Some(2e-3),
            bias_instability: Some(5e-5),
            random_walk: Some(1e-6),
        };
        let pts: Vec<AllanPoint> = (0..20)
            .map(|i| {
                let tau = 0.001 * 2f64.powi(i);
                AllanPoint {
                    tau_s: tau,
                    adev: truth.adev(tau),
                    terms: (4_000_000.0 / 2f64.powi(i)) as u64,
                }
            })
            .collect();
        let f = fit(&pts);
        for (a, b) in [
            (f.white_density, truth.white_density),
            (f.bias_instability, truth.bias_instability),
            (f.random_walk, truth.random_walk),
        ] {
            assert!((a.unwrap() / b.unwrap() - 1.0).abs() < 1e-6, "{f:?}");
        }
        // White noise only: the other two are not determined.
        let white = NoiseTerms {
            white_density: Some(1e-3),
            ..NoiseTerms::default()
        };
        let pts: Vec<AllanPoint> = pts
            .iter()
            .map(|p| AllanPoint {
                adev: white.adev(p.tau_s) * (1.0 + 1e-3 * (p.tau_s * 7.0).sin()),
                ..*p
            })
            .collect();
        let f = fit(&pts);
        assert!(
            (f.white_density.unwrap() / 1e-3 - 1.0).abs() < 2e-3,
            "{f:?}"
        );
        assert!(
            f.bias_instability.is_none() || f.random_walk.is_none(),
            "{f:?}"
        );
    }
}
