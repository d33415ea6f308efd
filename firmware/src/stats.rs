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

/// Running accumulator of one window. `repr(C)`: the reference and the block sums lie first, in
/// one run of `f32` that the M4F form of [`WindowAccumulator::add`] reads in one block load.
#[derive(Clone, Copy, Debug)]
#[repr(C)]
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
        self.add_with(x, Self::add_sums);
    }

    /// [`Self::add`] with the block sums in Rust on every target: what the QEMU tests compare the
    /// M4F form with.
    #[inline(always)]
    pub fn add_compiled(&mut self, x: &[f32; N]) {
        self.add_with(x, Self::add_reference);
    }

    #[inline(always)]
    fn add_with(&mut self, x: &[f32; N], sums: fn(&mut Self, &[f32; N])) {
        // One counter and one branch per sample: the window's first sample and each block's end
        // take the out-of-line path.
        // (`x` stays out of the call: passing its address would make the caller store the sample
        // to memory on every call.)
        if self.block_left == 0 && self.next_block() {
            self.reference = *x;
        }
        sums(self, x);
        self.block_left -= 1;
    }

    /// The block sums of one sample: the M4F block for 6 channels, else the reference.
    #[inline(always)]
    fn add_sums(&mut self, x: &[f32; N]) {
        #[cfg(all(target_arch = "arm", target_abi = "eabihf"))]
        if N == 6 {
            self.add6_block(x);
            return;
        }
        self.add_reference(x);
    }

    /// The block sums of one sample in Rust: the reference (the PC, other targets, other channel
    /// counts); the M4F form for 6 channels rounds identically, which the QEMU tests check bit for
    /// bit (`window_block_matches_reference`).
    #[inline(always)]
    fn add_reference(&mut self, x: &[f32; N]) {
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

    /// The block sums of one 6-channel sample on the M4F, in line: the reference and both block
    /// sums (18 `f32`) in one block load, the sample in another, the reference's 18 operations
    /// (`d = x − r`, `Σd += d`, `Σd² += d·d`, each product rounded before its addition) and one
    /// block store: 22 instructions where compiled code moves each value on its own (about 50
    /// in place, firmware/scripts/bench-qemu.sh). Operands through memory, the FPU registers used
    /// declared clobbered, as in `shared::Compensator`'s blocks.
    #[cfg(all(target_arch = "arm", target_abi = "eabihf"))]
    #[inline(always)]
    fn add6_block(&mut self, x: &[f32; N]) {
        const {
            use core::mem::offset_of;
            assert!(offset_of!(WindowAccumulator<6>, reference) == 0);
            assert!(offset_of!(WindowAccumulator<6>, block_sum) == 6 * 4);
            assert!(offset_of!(WindowAccumulator<6>, block_sq) == 12 * 4);
        };
        // SAFETY: called for N == 6 only: reads the 18 `f32` at the start of `self` (offsets
        // checked above) and the six of `x`, writes the twelve block sums; all 4-byte aligned
        // `f32`. Touches no stack; s0–s23 are declared clobbered and the pointer register is an
        // in-out temporary. Not `preserves_flags`: the arithmetic sets the FPSCR's cumulative
        // exception flags, and `adds` the APSR's.
        unsafe {
            core::arch::asm!(
                "vldmia {a}, {{s0-s17}}",
                "vldmia {x}, {{s18-s23}}",
                "vsub.f32 s18, s18, s0",
                "vsub.f32 s19, s19, s1",
                "vsub.f32 s20, s20, s2",
                "vsub.f32 s21, s21, s3",
                "vsub.f32 s22, s22, s4",
                "vsub.f32 s23, s23, s5",
                "vadd.f32 s6, s6, s18",
                "vadd.f32 s7, s7, s19",
                "vadd.f32 s8, s8, s20",
                "vadd.f32 s9, s9, s21",
                "vadd.f32 s10, s10, s22",
                "vadd.f32 s11, s11, s23",
                "vmla.f32 s12, s18, s18",
                "vmla.f32 s13, s19, s19",
                "vmla.f32 s14, s20, s20",
                "vmla.f32 s15, s21, s21",
                "vmla.f32 s16, s22, s22",
                "vmla.f32 s17, s23, s23",
                "adds {a}, #24",
                "vstmia {a}, {{s6-s17}}",
                a = inout(reg) (self as *mut Self) => _,
                x = in(reg) x.as_ptr(),
                out("s0") _, out("s1") _, out("s2") _, out("s3") _, out("s4") _,
                out("s5") _, out("s6") _, out("s7") _, out("s8") _, out("s9") _,
                out("s10") _, out("s11") _, out("s12") _, out("s13") _, out("s14") _,
                out("s15") _, out("s16") _, out("s17") _, out("s18") _, out("s19") _,
                out("s20") _, out("s21") _, out("s22") _, out("s23") _,
                options(nostack),
            );
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
