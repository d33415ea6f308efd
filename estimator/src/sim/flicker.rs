//! Flicker (1/f) bias noise for the simulator: a sum of first-order Gauss–Markov processes with time
//! constants spread evenly in log τ, which has a 1/f spectrum between its shortest and longest time
//! constant (Keshner, "1/f noise", Proc. IEEE 70(3), 1982).
//!
//! With `m` processes per decade, each of variance `σ²` and one-sided spectrum `4σ²τ/(1 + (2πfτ)²)`,
//! the sum's spectrum is `h₋₁/f` with `h₋₁ = m σ²/ln 10`, whose Allan variance is flat at
//! `2 ln 2 · h₋₁`. Bias instability `B` is conventionally defined by that floor,
//! `σ_A = √(2 ln 2/π) · B ≈ 0.664 B` (IEEE Std 952), so `σ = B·√(ln 10/(π m))`.

use shared::rng::Rng;

/// Time constants span 10^MIN_DECADE .. 10^MAX_DECADE s.
const MIN_DECADE: i32 = -2;
const MAX_DECADE: i32 = 4;
/// Processes per decade.
const PER_DECADE: usize = 2;

/// One axis's flicker process.
#[derive(Clone, Debug)]
pub struct Flicker {
    /// Per process: (a = e^{−dt/τ}, innovation σ·√(1 − a²), state).
    poles: Vec<(f64, f64, f64)>,
}

impl Flicker {
    /// A process of bias instability `b` (any unit) at sample interval `dt_s`, started at its
    /// stationary distribution. Processes with τ below a sample are left out (they are white noise).
    pub fn new(b: f64, dt_s: f64, rng: &mut Rng) -> Flicker {
        let sigma =
            b * (std::f64::consts::LN_10 / (std::f64::consts::PI * PER_DECADE as f64)).sqrt();
        let n = (MAX_DECADE - MIN_DECADE) as usize * PER_DECADE + 1;
        let poles = (0..n)
            .map(|k| {
                let tau = 10f64.powf(f64::from(MIN_DECADE) + k as f64 / PER_DECADE as f64);
                (tau, libm::exp(-dt_s / tau))
            })
            .filter(|(tau, _)| *tau > dt_s)
            .map(|(_, a)| (a, sigma * (1.0 - a * a).sqrt(), sigma * rng.normal()))
            .collect();
        Flicker { poles }
    }

    /// The next value.
    pub fn next(&mut self, rng: &mut Rng) -> f64 {
        let mut sum = 0.0;
        for (a, q, x) in &mut self.poles {
            *x = *a * *x + *q * rng.normal();
            sum += *x;
        }
        sum
    }
}
