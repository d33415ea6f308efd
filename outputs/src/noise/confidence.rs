//! The 1σ of one point of an Allan deviation curve, for plotting it with its error bars (the Python
//! package's `allan`): with `K = n/m` clusters of `m` samples out of `n`, the relative 1σ of the
//! estimated deviation is `1/√(2(K − 1))` (IEEE Std 952-1997, Annex C, eq. C.13; El-Sheimy, Hou and
//! Niu, *Analysis and Modeling of Inertial Sensors Using Allan Variance*, IEEE TIM 57(1), 2008,
//! eq. 13). It is the non-overlapping estimate's; the overlapping one `host noise` computes
//! (`super::allan::overlapping_adev`) is somewhat better, so the bounds are conservative.

/// The relative 1σ of the Allan deviation at cluster size `m` from `n` samples; `None` when fewer
/// than two clusters fit (no deviation there).
pub fn relative_sigma(n: usize, m: usize) -> Option<f64> {
    let clusters = n.checked_div(m)?;
    (clusters >= 2).then(|| 1.0 / (2.0 * (clusters as f64 - 1.0)).sqrt())
}

/// The power-law noise types of a rate signal the fit models, by their exponent `α` of the
/// fractional-frequency spectrum `S_y(f) ∝ f^α` (the convention of Greenhall's EDF and of
/// allantools): white rate noise (the N term) is α = 0, flicker rate noise (B) α = −1, a random
/// walk of the rate (K) α = −2.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum PowerLaw {
    /// α = 0: white rate noise, the Allan variance's `N²/τ`.
    WhiteRate,
    /// α = −1: flicker rate noise, the flat `(2 ln 2/π) B²`.
    FlickerRate,
    /// α = −2: random-walk rate noise, the `K² τ/3`.
    RandomWalkRate,
}

impl PowerLaw {
    /// The three in the order of the fit's terms N, B, K.
    pub const TERMS: [PowerLaw; 3] = [
        PowerLaw::WhiteRate,
        PowerLaw::FlickerRate,
        PowerLaw::RandomWalkRate,
    ];

    fn alpha(self) -> i32 {
        match self {
            PowerLaw::WhiteRate => 0,
            PowerLaw::FlickerRate => -1,
            PowerLaw::RandomWalkRate => -2,
        }
    }
}

/// The largest sum Greenhall's exact form is evaluated with (`J_max` of allantools).
const J_MAX: f64 = 100.0;

/// Greenhall's `sw(t)` (eq. 7) for the exponent `alpha` (0, 1 or 2 here: α + 2 of a rate term, or
/// the rate term's own α through [`sx`]).
fn sw(t: f64, alpha: i32) -> f64 {
    match alpha {
        2 => -t.abs(),
        1 if t == 0.0 => 0.0,
        1 => t * t * t.abs().ln(),
        0 => t.abs().powi(3),
        -1 if t == 0.0 => 0.0,
        -1 => t.powi(4) * t.abs().ln(),
        _ => t.abs().powi(5),
    }
}

/// Greenhall's `sx(t)` (eq. 8) with filter factor `f` (`None`: the limit F → ∞).
fn sx(t: f64, f: Option<f64>, alpha: i32) -> f64 {
    match f {
        None => sw(t, alpha + 2),
        Some(f) => f * f * (2.0 * sw(t, alpha) - sw(t - 1.0 / f, alpha) - sw(t + 1.0 / f, alpha)),
    }
}

/// Greenhall's `sz(t)` (eq. 9) for the Allan variance (d = 2).
fn sz(t: f64, f: Option<f64>, alpha: i32) -> f64 {
    6.0 * sx(t, f, alpha) - 4.0 * sx(t - 1.0, f, alpha) - 4.0 * sx(t + 1.0, f, alpha)
        + sx(t - 2.0, f, alpha)
        + sx(t + 2.0, f, alpha)
}

/// Greenhall's basic sum (eq. 10).
fn basic_sum(j: f64, m: f64, s: f64, f: Option<f64>, alpha: i32) -> f64 {
    let first = sz(0.0, f, alpha).powi(2);
    let second = (1.0 - j / m) * sz(j / s, f, alpha).powi(2);
    let third: f64 = (1..j as usize)
        .map(|i| {
            let i = i as f64;
            2.0 * (1.0 - i / m) * sz(i / s, f, alpha).powi(2)
        })
        .sum();
    first + second + third
}

/// Table 2 of Greenhall (2004) for d = 2: `(a0, a1)` of the unmodified variances' large-`r` form.
fn table2(alpha: i32) -> (f64, f64) {
    match alpha {
        0 => (2.0 / 3.0, 1.0 / 3.0),
        -1 => (0.852, 0.375),
        _ => (1.079, 0.368),
    }
}

/// The equivalent degrees of freedom of the overlapping Allan variance at cluster size `m` from
/// `n` rate samples (n + 1 phase points) of the power-law noise `law`: Greenhall's algorithm
/// (C. A. Greenhall and W. J. Riley, "Uncertainty of stability variances based on finite
/// differences", 35th PTTI, 2003; Greenhall, "Estimating the stability of frequency
/// distributions", 2004), case 2 (unmodified variance, α ≤ 0) with d = 2, F = S = m, as allantools
/// computes it (`allantools/ci.py`, `edf_greenhall`, version 2024.6; allantools' `oadev`
/// confidence intervals use it). `None` where no second difference fits.
pub(crate) fn edf_overlapping_adev(law: PowerLaw, m: usize, n: usize) -> Option<f64> {
    let alpha = law.alpha();
    let (m, phase) = (m as f64, n as f64 + 1.0);
    // Filter length L = m/F + m d = 1 + 2m; M = 1 + ⌊S (N − L)/m⌋ second differences.
    let big_m = 1.0 + (phase - 1.0 - 2.0 * m).floor();
    if m < 1.0 || big_m < 1.0 {
        return None;
    }
    let j = big_m.min(3.0 * m);
    let r = big_m / m;
    let inv = if j <= J_MAX {
        // Exact for small m; for 3m > J_max, F → ∞ (variant b).
        let f = (3.0 * m <= J_MAX).then_some(m);
        basic_sum(j, big_m, m, f, alpha) / (sz(0.0, f, alpha).powi(2) * big_m)
    } else if r > 3.0 {
        let (a0, a1) = table2(alpha);
        (a0 - a1 / r) / r
    } else {
        let m_prime = J_MAX / r;
        basic_sum(J_MAX, J_MAX, m_prime, None, alpha) / (sz(0.0, None, alpha).powi(2) * J_MAX)
    };
    (inv > 0.0 && inv.is_finite()).then(|| 1.0 / inv)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_relative_sigma_is_the_standards_formula() {
        // IEEE 952's example: K = 9 clusters give 25 %; 10 000 samples at m = 1 give 0.71 %.
        assert_eq!(relative_sigma(900, 100), Some(0.25));
        assert!((relative_sigma(10_000, 1).unwrap() - 0.007_071).abs() < 1e-6);
        assert_eq!(relative_sigma(100, 60), None);
        assert_eq!(relative_sigma(100, 0), None);
    }

    /// Greenhall's EDF against allantools' own (`allantools.ci.edf_greenhall(alpha, d=2, m, N=n+1,
    /// overlapping=True, modified=False)`, allantools 2024.6, printed to full precision): every
    /// branch of case 2 (the exact sum with F = m and with F → ∞, the large-r table, the short-record
    /// sum) on both a short and a 720 000-sample record.
    #[test]
    fn the_edf_is_allantools_edf_greenhall() {
        let cases: [(PowerLaw, usize, usize, f64); 15] = [
            (PowerLaw::WhiteRate, 1, 1000, 782.030_299_072_743_8),
            (PowerLaw::WhiteRate, 16, 1000, 86.370_102_004_972_62),
            (PowerLaw::WhiteRate, 256, 1000, 3.879_630_664_270_347),
            (PowerLaw::WhiteRate, 1024, 720_000, 1_052.439_500_079_400_2),
            (PowerLaw::WhiteRate, 65_536, 720_000, 14.273_703_718_900_217),
            (PowerLaw::FlickerRate, 1, 720_000, 645_086.542_363_918_3),
            (PowerLaw::FlickerRate, 4, 1000, 282.357_703_970_543_87),
            (PowerLaw::FlickerRate, 32, 720_000, 26_368.160_804_008_923),
            (PowerLaw::FlickerRate, 40, 199, 4.124_580_867_273_417),
            (PowerLaw::FlickerRate, 300, 1000, 2.245_954_085_845_091_3),
            (PowerLaw::RandomWalkRate, 1, 1000, 762.290_490_473_850_8),
            (PowerLaw::RandomWalkRate, 64, 1000, 12.966_105_328_201_303),
            (
                PowerLaw::RandomWalkRate,
                1024,
                720_000,
                650.108_618_240_042_2,
            ),
            (
                PowerLaw::RandomWalkRate,
                65_536,
                720_000,
                8.656_955_140_498_487,
            ),
            (PowerLaw::RandomWalkRate, 300, 1000, 1.663_656_026_479_360_3),
        ];
        for (law, m, n, want) in cases {
            let got = edf_overlapping_adev(law, m, n).unwrap();
            assert!(
                (got / want - 1.0).abs() < 1e-9,
                "{law:?} m {m} n {n}: {got} against {want}"
            );
        }
        assert_eq!(edf_overlapping_adev(PowerLaw::WhiteRate, 600, 1000), None);
        assert_eq!(edf_overlapping_adev(PowerLaw::WhiteRate, 0, 1000), None);
    }
}
