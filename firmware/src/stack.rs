//! Stack high-water mark by painting: at boot every free word of the stack region is filled with
//! [`PAINT`]; later, the lowest word that no longer holds it bounds the deepest the stack has ever
//! reached (the stack grows down, from `_stack_start` towards `_stack_end` in cortex-m-rt's
//! `link.x`).
//!
//! The scan is device-agnostic (a word reader, so the board can use volatile reads of the real
//! region and the PC tests a plain array). It can under-report only if a frame reserved stack that it
//! never wrote *and* wrote nothing below it — the usual limit of painting; it never over-reports.

/// The paint word: unlikely as a return address (odd high bits, not a Thumb code address in flash or
/// RAM) and as a saved float.
pub const PAINT: u32 = 0xC5AC_CE55;

/// Paints `words` words through `write(i, PAINT)`, `i` in `0..words` (index 0 = the region's lowest
/// address).
pub fn paint(words: usize, mut write: impl FnMut(usize, u32)) {
    for i in 0..words {
        write(i, PAINT);
    }
}

/// Bytes of the region ever used: the region's size minus the painted words still intact at its
/// bottom. `read(i)` gives word `i` (0 = lowest address) of a region of `words` words, the whole
/// stack from its bottom (`_stack_end`) to its top (`_stack_start`).
pub fn used_bytes(words: usize, read: impl Fn(usize) -> u32) -> usize {
    let untouched = (0..words).take_while(|&i| read(i) == PAINT).count();
    (words - untouched) * 4
}

/// Keeps the largest [`used_bytes`] seen, so a board can log it only when it grows.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct HighWater {
    max_bytes: usize,
}

impl HighWater {
    /// Nothing measured yet.
    pub const fn new() -> Self {
        HighWater { max_bytes: 0 }
    }

    /// The mark so far, bytes.
    pub fn bytes(&self) -> usize {
        self.max_bytes
    }

    /// Records a measurement; `Some(new mark)` when it exceeds the previous one.
    pub fn record(&mut self, used_bytes: usize) -> Option<usize> {
        (used_bytes > self.max_bytes).then(|| {
            self.max_bytes = used_bytes;
            used_bytes
        })
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn measures_the_deepest_write_not_the_last() {
        // A 64-word "stack" whose top 4 words were live when it was painted.
        let mut mem = [0u32; 64];
        paint(60, |i, v| mem[i] = v);
        assert_eq!(used_bytes(64, |i| mem[i]), 16, "only the unpainted top");
        // A call 20 words deep (words 40..60 written), then it returns: the top stays live.
        for w in &mut mem[40..60] {
            *w = 0x0800_1235;
        }
        assert_eq!(used_bytes(64, |i| mem[i]), 24 * 4);
        // A deeper call that writes only its lowest word (a large uninitialised array above it)
        // still counts to its bottom.
        mem[10] = 0;
        assert_eq!(used_bytes(64, |i| mem[i]), 54 * 4);
    }

    #[test]
    fn untouched_and_exhausted_regions() {
        let mut mem = [0u32; 16];
        paint(16, |i, v| mem[i] = v);
        assert_eq!(used_bytes(16, |i| mem[i]), 0);
        mem[0] = 1; // the very bottom word: the whole region was used (overflow imminent)
        assert_eq!(used_bytes(16, |i| mem[i]), 64);
    }

    #[test]
    fn high_water_reports_only_growth() {
        let mut h = HighWater::new();
        assert_eq!(h.record(100), Some(100));
        assert_eq!(h.record(80), None);
        assert_eq!(h.record(100), None);
        assert_eq!(h.record(104), Some(104));
        assert_eq!(h.bytes(), 104);
    }
}
