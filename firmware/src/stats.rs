//! Window statistics: count, mean and (unbiased, n − 1) variance of `N` channels.
//!
//! Per sample the cost is three f32 operations per channel: the deviation from the window's first
//! sample (a per-window reference, so that the sums are of small numbers and `Σd² − (Σd)²/n` does not
//! cancel), its sum and its square's sum. Every [`BLOCK`] samples the f32 block sums are folded into
//! f64 totals, so a window of millions of samples keeps f32 rounding at the level of one block
//! (256 · 2⁻²⁴ ≈ 1.5·10⁻⁵ relative to the block's deviations) and never grows with the window length.

/// Samples per f32 block before folding into the f64 totals.
pub const BLOCK: u32 = 256;

/// Result of a window.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct WindowStats<const N: usize> {
    /// Samples in the statistics.
    pub count: u32,
    /// Mean per channel (0 when `count` is 0).
    pub mean: [f32; N],
    /// Unbiased variance per channel (0 when `count` < 2).
    pub var: [f32; N],
}

/// Running accumulator of one window.
#[derive(Clone, Copy, Debug)]
pub struct WindowAccumulator<const N: usize> {
    reference: [f32; N],
    block_sum: [f32; N],
    block_sq: [f32; N],
    /// Samples the open block still takes (0: none open, or the open one is full).
    block_left: u32,
    /// A block is open (the window has its reference).
    open: bool,
    sum: [f64; N],
    sq: [f64; N],
    /// Samples in the blocks folded into `sum` and `sq`.
    count: u32,
}

impl<const N: usize> Default for WindowAccumulator<N> {
    fn default() -> Self {
        Self::new()
    }
}

impl<const N: usize> WindowAccumulator<N> {
    /// An empty window.
    pub const fn new() -> Self {
        WindowAccumulator {
            reference: [0.0; N],
            block_sum: [0.0; N],
            block_sq: [0.0; N],
            block_left: 0,
            open: false,
            sum: [0.0; N],
            sq: [0.0; N],
            count: 0,
        }
    }

    /// Adds one sample (the caller has checked that it is finite).
    #[inline(always)]
    pub fn add(&mut self, x: &[f32; N]) {
        // One counter and one branch per sample: the window's first sample and each block's end
        // take the out-of-line path.
        // (`x` stays out of the call: passing its address would make the caller store the sample
        // to memory on every call.)
        if self.block_left == 0 && self.next_block() {
            self.reference = *x;
        }
        self.add_sums(x);
        self.block_left -= 1;
    }

    /// The block sums of one sample: `d = x − r`, `Σd += d`, `Σd² += d·d`, each product rounded
    /// before its addition.
    #[inline(always)]
    fn add_sums(&mut self, x: &[f32; N]) {
        // Written out for the pipeline's 6 channels (and 3): straight-line code even at opt-level
        // "s", which the firmware is built with (a loop costs 45 % more instructions there).
        match N {
            3 => {
                self.channel(0, x);
                self.channel(1, x);
                self.channel(2, x);
            }
            6 => {
                self.channel(0, x);
                self.channel(1, x);
                self.channel(2, x);
                self.channel(3, x);
                self.channel(4, x);
                self.channel(5, x);
            }
            _ => {
                for j in 0..N {
                    self.channel(j, x);
                }
            }
        }
    }

    /// Folds the full block, or opens the window's first one: true when the caller's sample is
    /// the window's first (its reference).
    #[inline(never)]
    fn next_block(&mut self) -> bool {
        if self.open {
            self.fold();
            false
        } else {
            self.open = true;
            self.block_left = BLOCK;
            true
        }
    }

    #[inline(always)]
    fn channel(&mut self, j: usize, x: &[f32; N]) {
        let d = x[j] - self.reference[j];
        self.block_sum[j] += d;
        self.block_sq[j] += d * d;
    }

    /// Folds the open block into the f64 totals; the block goes on empty.
    fn fold(&mut self) {
        for j in 0..N {
            self.sum[j] += f64::from(self.block_sum[j]);
            self.sq[j] += f64::from(self.block_sq[j]);
            self.block_sum[j] = 0.0;
            self.block_sq[j] = 0.0;
        }
        self.count += BLOCK - self.block_left;
        self.block_left = BLOCK;
    }

    /// Samples in the open block.
    fn in_block(&self) -> u32 {
        if self.open {
            BLOCK - self.block_left
        } else {
            0
        }
    }

    /// Samples added so far.
    pub fn count(&self) -> u32 {
        self.count + self.in_block()
    }

    /// The statistics of the window so far; the accumulator restarts empty.
    pub fn finish(&mut self) -> WindowStats<N> {
        if self.open {
            self.fold();
        }
        let n = self.count;
        let nf = f64::from(n);
        let mut out = WindowStats {
            count: n,
            mean: [0.0; N],
            var: [0.0; N],
        };
        if n > 0 {
            for j in 0..N {
                let m = self.sum[j] / nf;
                out.mean[j] = (f64::from(self.reference[j]) + m) as f32;
                if n > 1 {
                    let v = (self.sq[j] - self.sum[j] * m) / (nf - 1.0);
                    out.var[j] = if v > 0.0 { v as f32 } else { 0.0 };
                }
            }
        }
        *self = Self::new();
        out
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use proptest::prelude::*;

    fn reference_stats(xs: &[f64]) -> (f64, f64) {
        let n = xs.len() as f64;
        let m = xs.iter().sum::<f64>() / n;
        let v = xs.iter().map(|x| (x - m) * (x - m)).sum::<f64>() / (n - 1.0);
        (m, v)
    }

    #[test]
    fn empty_and_single_sample_windows() {
        let mut a = WindowAccumulator::<2>::new();
        let s = a.finish();
        assert_eq!(s.count, 0);
        assert_eq!(s.mean, [0.0; 2]);
        a.add(&[2.5, -1.0]);
        let s = a.finish();
        assert_eq!((s.count, s.mean, s.var), (1, [2.5, -1.0], [0.0; 2]));
        // finish() restarted the window.
        assert_eq!(a.count(), 0);
    }

    #[test]
    fn large_offset_small_noise_does_not_cancel() {
        // 2.4 V ± 0.3 mV over a 100 000-sample window: naive f32 Σx² − (Σx)²/n would give garbage.
        let mut a = WindowAccumulator::<1>::new();
        let mut xs = std::vec::Vec::new();
        let mut state = 12345u32;
        for _ in 0..100_000 {
            state ^= state << 13;
            state ^= state >> 17;
            state ^= state << 5;
            let u = (state as f64 / u32::MAX as f64) - 0.5;
            let x = (2.4 + 0.001 * u) as f32;
            xs.push(f64::from(x));
            a.add(&[x]);
        }
        let (m, v) = reference_stats(&xs);
        let s = a.finish();
        assert_eq!(s.count, 100_000);
        assert!((f64::from(s.mean[0]) - m).abs() < 1e-7, "{} {m}", s.mean[0]);
        assert!(
            (f64::from(s.var[0]) / v - 1.0).abs() < 1e-4,
            "{} {v}",
            s.var[0]
        );
    }

    proptest! {
        #[test]
        fn matches_f64_reference(
            xs in prop::collection::vec(-1000.0f32..1000.0, 2..2000),
            offset in -1.0e4f32..1.0e4,
        ) {
            let mut a = WindowAccumulator::<1>::new();
            let vals: std::vec::Vec<f32> = xs.iter().map(|x| x * 1e-3 + offset).collect();
            for x in &vals {
                a.add(&[*x]);
            }
            let wide: std::vec::Vec<f64> = vals.iter().map(|x| f64::from(*x)).collect();
            let (m, v) = reference_stats(&wide);
            let s = a.finish();
            prop_assert_eq!(s.count as usize, vals.len());
            // Mean: f32 output rounding of the offset dominates.
            prop_assert!((f64::from(s.mean[0]) - m).abs() <= 2e-7 * m.abs().max(1.0) + 1e-6);
            // Variance: relative 1e-4 (or absolute for near-constant data).
            prop_assert!((f64::from(s.var[0]) - v).abs() <= 1e-4 * v + 1e-9, "{} vs {}", s.var[0], v);
        }
    }
}
