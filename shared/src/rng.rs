//! The one random number generator of the host: the simulator's noise, the tests' Monte Carlo runs
//! and random units all draw from it. xoshiro256++ seeded by SplitMix64 with one stream per noise
//! source, normal deviates by the polar method with `libm`'s logarithm: the bytes of a simulated
//! session depend only on the inputs and the seed, not on the platform or on a dependency's version.
//! (A crate such as `rand` does not promise the same stream across its versions, which a seeded
//! recording relies on.)

/// xoshiro256++ (Blackman and Vigna), seeded through SplitMix64: small, fast, and fixed forever, so
/// that a seed names the same session on every machine.
#[derive(Clone, Debug)]
pub struct Rng {
    s: [u64; 4],
    spare: Option<f64>,
}

fn splitmix64(x: &mut u64) -> u64 {
    *x = x.wrapping_add(0x9E37_79B9_7F4A_7C15);
    let mut z = *x;
    z = (z ^ (z >> 30)).wrapping_mul(0xBF58_476D_1CE4_E5B9);
    z = (z ^ (z >> 27)).wrapping_mul(0x94D0_49BB_1331_11EB);
    z ^ (z >> 31)
}

impl Rng {
    /// Stream `stream` of seed `seed` (different streams are independent for all practical purposes).
    pub fn new(seed: u64, stream: u64) -> Rng {
        let mut x = seed ^ stream.wrapping_mul(0xD605_BBB5_8C8A_BBDD);
        let s = [
            splitmix64(&mut x),
            splitmix64(&mut x),
            splitmix64(&mut x),
            splitmix64(&mut x),
        ];
        Rng { s, spare: None }
    }

    /// Next 64 random bits.
    pub fn next_u64(&mut self) -> u64 {
        let s = &mut self.s;
        let result = s[0].wrapping_add(s[3]).rotate_left(23).wrapping_add(s[0]);
        let t = s[1] << 17;
        s[2] ^= s[0];
        s[3] ^= s[1];
        s[1] ^= s[2];
        s[0] ^= s[3];
        s[2] ^= t;
        s[3] = s[3].rotate_left(45);
        result
    }

    /// Uniform on (−1, 1), never exactly 0 or ±1.
    fn symmetric(&mut self) -> f64 {
        ((self.next_u64() >> 11) as f64 + 0.5) * (2.0 / (1u64 << 53) as f64) - 1.0
    }

    /// Uniform on (0, 1), never exactly 0 or 1.
    pub fn uniform(&mut self) -> f64 {
        ((self.next_u64() >> 11) as f64 + 0.5) / (1u64 << 53) as f64
    }

    /// Uniform on (`lo`, `hi`).
    pub fn range(&mut self, lo: f64, hi: f64) -> f64 {
        lo + (hi - lo) * self.uniform()
    }

    /// A direction uniform on the unit sphere.
    pub fn unit_vector(&mut self) -> [f64; 3] {
        let v = [self.normal(), self.normal(), self.normal()];
        let n = crate::linalg::norm(&v);
        v.map(|c| c / n)
    }

    /// A standard normal deviate (Marsaglia's polar method).
    pub fn normal(&mut self) -> f64 {
        if let Some(z) = self.spare.take() {
            return z;
        }
        loop {
            let a = self.symmetric();
            let b = self.symmetric();
            let s = a * a + b * b;
            if s < 1.0 && s > 0.0 {
                let f = libm::sqrt(-2.0 * libm::log(s) / s);
                self.spare = Some(b * f);
                return a * f;
            }
        }
    }
}
