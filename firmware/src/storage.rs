//! Power-cut-safe parameter storage: an A/B scheme on any `embedded-storage` NOR flash.
//!
//! The store owns two equal slots (each a whole number of erase blocks: on the STM32 boards the
//! 16 KiB sectors 1 and 2, `crate::flash_layout`; on QEMU a RAM region outside the ELF). A slot holds one record:
//!
//! ```text
//! offset 0   u32  RECORD_MAGIC          offset 8   u16  blob length n, u16 0xFFFF
//! offset 4   u32  sequence number       offset 12  u32  CRC-32 of bytes 0..12 and the blob
//! offset 16  n bytes blob, padded with 0xFF to the commit alignment
//! then       u32  COMMIT_MAGIC (its own program operation, written last)
//! ```
//!
//! Writing a new blob erases the slot that does *not* hold the newest valid record (unless the
//! record's bytes there are already blank), programs the record, programs the commit word, and
//! reads it back. A board erases that spare slot ahead, at power-on before sampling starts
//! ([`AbStore::prepare`]): a sector erase stalls every flash read of a single-bank STM32F4 — the
//! CPU's instruction fetches included — for up to half a second, so a write that finds its slot blank
//! only programs (16 µs a word) and sampling runs on through it. A record counts only with its commit word,
//! a matching CRC and a plausible length; at boot the valid record with the newer sequence number
//! (wrapping comparison) wins. A power cut at any step therefore leaves the old record untouched in
//! the other slot: the device boots with the old or the new calibration, never none and never a
//! corrupt one (tested below by cutting a simulated flash at every program/erase step, with the cut
//! step half-applied).
//!
//! Why not `sequential-storage`: its version 8 is async-only (an executor and an async NOR adapter on
//! both boards) and assumes uniform erase blocks, while the STM32F4's sectors are 16/64/128 KiB; a
//! calibration is written a handful of times in a unit's life, so wear levelling buys nothing here.

use embedded_storage::nor_flash::{
    ErrorType, NorFlash, NorFlashError, NorFlashErrorKind, ReadNorFlash,
};
use shared::blob::{Crc32, BLOB_MAX_LEN};

/// First word of a record.
pub const RECORD_MAGIC: u32 = 0x4143_5331; // "ACS1"
/// Commit word, programmed after the record.
pub const COMMIT_MAGIC: u32 = 0x4F4B_4F4B; // "OKOK"
const HEADER_LEN: usize = 16;
/// Largest program granularity supported (bytes).
const MAX_ALIGN: usize = 16;

/// Why the store failed.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum StoreError {
    /// The flash reported an error (or a power cut stopped it).
    Flash,
    /// The blob is empty or larger than [`BLOB_MAX_LEN`].
    BadLength,
    /// The read-back after writing did not match.
    Verify,
    /// The flash geometry does not fit two slots of a record.
    Geometry,
}

/// The firmware's view of its calibration storage.
pub trait CalStore {
    /// Copies the newest valid stored blob into `out` and returns its length (`None` if there is none).
    fn load(&mut self, out: &mut [u8; BLOB_MAX_LEN]) -> Result<Option<usize>, StoreError>;
    /// Stores a new blob; on error the previously stored blob is still the one [`Self::load`] returns.
    fn store(&mut self, blob: &[u8]) -> Result<(), StoreError>;
}

#[derive(Clone, Copy)]
struct Found {
    slot: u32,
    seq: u32,
    len: usize,
}

/// The A/B store over `F`, using flash offsets `base .. base + 2·slot_size`.
pub struct AbStore<F> {
    flash: F,
    base: u32,
    slot_size: u32,
}

fn align_up(n: usize, a: usize) -> usize {
    n.div_ceil(a) * a
}

impl<F: NorFlash> AbStore<F> {
    /// Program alignment of records: at least 4 bytes, at least the flash's write and read sizes.
    const ALIGN: usize = {
        let w = if F::WRITE_SIZE > 4 { F::WRITE_SIZE } else { 4 };
        if F::READ_SIZE > w {
            F::READ_SIZE
        } else {
            w
        }
    };

    /// A store over two slots of `slot_size` bytes starting at flash offset `base`.
    pub fn new(flash: F, base: u32, slot_size: u32) -> Result<Self, StoreError> {
        let need = align_up(HEADER_LEN + BLOB_MAX_LEN, Self::ALIGN) + Self::ALIGN;
        let erase = F::ERASE_SIZE as u32;
        let ok = Self::ALIGN <= MAX_ALIGN
            && MAX_ALIGN % Self::ALIGN == 0
            && erase > 0
            && base % erase == 0
            && slot_size % erase == 0
            && slot_size as usize >= need
            && (base as usize + 2 * slot_size as usize) <= flash.capacity();
        if !ok {
            return Err(StoreError::Geometry);
        }
        Ok(AbStore {
            flash,
            base,
            slot_size,
        })
    }

    /// Gives the flash back.
    pub fn into_inner(self) -> F {
        self.flash
    }

    fn slot_addr(&self, slot: u32) -> u32 {
        self.base + slot * self.slot_size
    }

    fn read(&mut self, addr: u32, out: &mut [u8]) -> Result<(), StoreError> {
        self.flash.read(addr, out).map_err(|_| StoreError::Flash)
    }

    /// Reads and checks the record of `slot`; with `out`, also copies its blob.
    fn check_slot(
        &mut self,
        slot: u32,
        out: Option<&mut [u8; BLOB_MAX_LEN]>,
    ) -> Result<Option<Found>, StoreError> {
        let a = self.slot_addr(slot);
        let mut h = [0u8; HEADER_LEN];
        self.read(a, &mut h)?;
        let word = |i: usize| u32::from_le_bytes([h[i], h[i + 1], h[i + 2], h[i + 3]]);
        let len = usize::from(u16::from_le_bytes([h[8], h[9]]));
        if word(0) != RECORD_MAGIC || len == 0 || len > BLOB_MAX_LEN {
            return Ok(None);
        }
        let commit_at = a + align_up(HEADER_LEN + len, Self::ALIGN) as u32;
        let mut c = [0u8; MAX_ALIGN];
        self.read(commit_at, &mut c[..Self::ALIGN])?;
        if u32::from_le_bytes([c[0], c[1], c[2], c[3]]) != COMMIT_MAGIC {
            return Ok(None);
        }
        // Whole aligned words (the padding after the blob is part of the record).
        let mut blob = [0u8; BLOB_MAX_LEN + MAX_ALIGN];
        self.read(
            a + HEADER_LEN as u32,
            &mut blob[..align_up(len, Self::ALIGN)],
        )?;
        let mut digest = Crc32::new();
        digest.update(&h[..12]);
        digest.update(&blob[..len]);
        if digest.finish() != word(12) {
            return Ok(None);
        }
        if let Some(out) = out {
            out[..len].copy_from_slice(&blob[..len]);
        }
        Ok(Some(Found {
            slot,
            seq: word(4),
            len,
        }))
    }

    /// Bytes a record of a `len`-byte blob occupies, commit word included.
    fn record_len(len: usize) -> usize {
        align_up(HEADER_LEN + len, Self::ALIGN) + Self::ALIGN
    }

    /// The first `n` bytes of `slot` read as erased (0xFF).
    fn blank(&mut self, slot: u32, n: usize) -> Result<bool, StoreError> {
        let a = self.slot_addr(slot);
        let mut buf = [0u8; 64];
        let mut pos = 0;
        while pos < n {
            let k = (n - pos).min(buf.len());
            self.read(a + pos as u32, &mut buf[..k])?;
            if buf[..k].iter().any(|b| *b != 0xFF) {
                return Ok(false);
            }
            pos += k;
        }
        Ok(true)
    }

    /// The slot the next write goes to and its sequence number.
    fn next_slot(&mut self) -> Result<(u32, u32), StoreError> {
        Ok(match self.newest()? {
            Some(f) => (1 - f.slot, f.seq.wrapping_add(1)),
            None => (0, 1),
        })
    }

    /// Erases ahead: the slot the next write goes to, unless the room of the longest record there
    /// is already blank. Returns whether it erased. A board calls it at power-on, before sampling
    /// starts (the erase stalls a single-bank STM32F4's CPU for about a second), so that a
    /// calibration written later only programs. Never call it from an interrupt.
    pub fn prepare(&mut self) -> Result<bool, StoreError> {
        let (slot, _) = self.next_slot()?;
        if self.blank(slot, Self::record_len(BLOB_MAX_LEN))? {
            return Ok(false);
        }
        let a = self.slot_addr(slot);
        self.flash
            .erase(a, a + self.slot_size)
            .map_err(|_| StoreError::Flash)?;
        Ok(true)
    }

    fn newest(&mut self) -> Result<Option<Found>, StoreError> {
        let a = self.check_slot(0, None)?;
        let b = self.check_slot(1, None)?;
        Ok(match (a, b) {
            (Some(a), Some(b)) => {
                // Wrapping comparison: b is newer if it is ahead of a by less than half the range.
                if b.seq.wrapping_sub(a.seq) as i32 > 0 {
                    Some(b)
                } else {
                    Some(a)
                }
            }
            (a, b) => a.or(b),
        })
    }
}

impl<F: NorFlash> CalStore for AbStore<F> {
    fn load(&mut self, out: &mut [u8; BLOB_MAX_LEN]) -> Result<Option<usize>, StoreError> {
        match self.newest()? {
            Some(f) => Ok(self.check_slot(f.slot, Some(out))?.map(|f| f.len)),
            None => Ok(None),
        }
    }

    fn store(&mut self, blob: &[u8]) -> Result<(), StoreError> {
        if blob.is_empty() || blob.len() > BLOB_MAX_LEN {
            return Err(StoreError::BadLength);
        }
        let (slot, seq) = self.next_slot()?;
        let a = self.slot_addr(slot);
        // Erased ahead (`prepare`): program at once. A blank record area is all a record needs; a
        // slot cut during a program is not blank there, one cut during its erase is either not
        // blank or erased where the record goes.
        if !self.blank(slot, Self::record_len(blob.len()))? {
            self.flash
                .erase(a, a + self.slot_size)
                .map_err(|_| StoreError::Flash)?;
        }
        // Header and blob, padded; programmed in pieces of a small stack buffer.
        let mut h = [0xFFu8; HEADER_LEN];
        h[0..4].copy_from_slice(&RECORD_MAGIC.to_le_bytes());
        h[4..8].copy_from_slice(&seq.to_le_bytes());
        h[8..10].copy_from_slice(&(blob.len() as u16).to_le_bytes());
        let mut digest = Crc32::new();
        digest.update(&h[..12]);
        digest.update(blob);
        h[12..16].copy_from_slice(&digest.finish().to_le_bytes());
        let body_len = align_up(HEADER_LEN + blob.len(), Self::ALIGN);
        let mut buf = [0xFFu8; 64];
        let mut pos = 0;
        while pos < body_len {
            let n = (body_len - pos).min(buf.len());
            for (k, b) in buf[..n].iter_mut().enumerate() {
                let at = pos + k;
                *b = if at < HEADER_LEN {
                    h[at]
                } else if at - HEADER_LEN < blob.len() {
                    blob[at - HEADER_LEN]
                } else {
                    0xFF
                };
            }
            self.flash
                .write(a + pos as u32, &buf[..n])
                .map_err(|_| StoreError::Flash)?;
            pos += n;
        }
        let mut c = [0xFFu8; MAX_ALIGN];
        c[..4].copy_from_slice(&COMMIT_MAGIC.to_le_bytes());
        self.flash
            .write(a + body_len as u32, &c[..Self::ALIGN])
            .map_err(|_| StoreError::Flash)?;
        // Read back: the new record must now be the newest and equal the blob.
        let mut back = [0u8; BLOB_MAX_LEN];
        match self.load(&mut back)? {
            Some(n) if n == blob.len() && back[..n] == *blob => Ok(()),
            _ => Err(StoreError::Verify),
        }
    }
}

/// Error of [`RamNorFlash`] (out-of-bounds or misaligned access).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct RamFlashError(NorFlashErrorKind);

impl NorFlashError for RamFlashError {
    fn kind(&self) -> NorFlashErrorKind {
        self.0
    }
}

/// NOR-flash semantics over a RAM buffer: erase sets bytes to 0xFF, programming can only clear bits.
/// The QEMU board's "flash" (its code memory is RAM) and a test double.
pub struct RamNorFlash<'a, const ERASE: usize> {
    mem: &'a mut [u8],
}

impl<'a, const ERASE: usize> RamNorFlash<'a, ERASE> {
    /// Flash semantics over `mem`.
    pub fn new(mem: &'a mut [u8]) -> Self {
        RamNorFlash { mem }
    }

    fn range(&self, offset: u32, len: usize) -> Result<core::ops::Range<usize>, RamFlashError> {
        let start = offset as usize;
        match start.checked_add(len) {
            Some(end) if end <= self.mem.len() => Ok(start..end),
            _ => Err(RamFlashError(NorFlashErrorKind::OutOfBounds)),
        }
    }
}

impl<const ERASE: usize> ErrorType for RamNorFlash<'_, ERASE> {
    type Error = RamFlashError;
}

impl<const ERASE: usize> ReadNorFlash for RamNorFlash<'_, ERASE> {
    const READ_SIZE: usize = 1;

    fn read(&mut self, offset: u32, bytes: &mut [u8]) -> Result<(), Self::Error> {
        let r = self.range(offset, bytes.len())?;
        bytes.copy_from_slice(&self.mem[r]);
        Ok(())
    }

    fn capacity(&self) -> usize {
        self.mem.len()
    }
}

impl<const ERASE: usize> NorFlash for RamNorFlash<'_, ERASE> {
    const WRITE_SIZE: usize = 4;
    const ERASE_SIZE: usize = ERASE;

    fn erase(&mut self, from: u32, to: u32) -> Result<(), Self::Error> {
        if from > to || from as usize % ERASE != 0 || to as usize % ERASE != 0 {
            return Err(RamFlashError(NorFlashErrorKind::NotAligned));
        }
        let r = self.range(from, (to - from) as usize)?;
        self.mem[r].fill(0xFF);
        Ok(())
    }

    fn write(&mut self, offset: u32, bytes: &[u8]) -> Result<(), Self::Error> {
        if offset as usize % 4 != 0 || bytes.len() % 4 != 0 {
            return Err(RamFlashError(NorFlashErrorKind::NotAligned));
        }
        let r = self.range(offset, bytes.len())?;
        for (m, b) in self.mem[r].iter_mut().zip(bytes) {
            *m &= *b;
        }
        Ok(())
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::paper_unit::{self, QEMU_UNIT_ID};
    use shared::blob::{decode_for_unit, ParameterBlob};

    /// A NOR flash that loses power after `budget` program/erase steps. A step is one erase of one
    /// block or one program of one `W`-byte word. The step that is cut is half-applied (half of the
    /// block erased; the word programmed with only some of its bits cleared); every later operation
    /// fails, as after the power is gone.
    struct CutFlash<const W: usize, const E: usize> {
        mem: std::vec::Vec<u8>,
        budget: Option<usize>,
        steps: usize,
        erases: usize,
    }

    #[derive(Debug)]
    struct Cut;
    impl NorFlashError for Cut {
        fn kind(&self) -> NorFlashErrorKind {
            NorFlashErrorKind::Other
        }
    }

    impl<const W: usize, const E: usize> CutFlash<W, E> {
        fn new(blocks: usize) -> Self {
            CutFlash {
                mem: std::vec![0u8; blocks * E], // never-erased flash: arbitrary (zero) content
                budget: None,
                steps: 0,
                erases: 0,
            }
        }
        /// Counts a step; `Ok(true)` = do it fully, `Ok(false)` = this is the cut step.
        fn step(&mut self) -> Result<bool, Cut> {
            self.steps += 1;
            match self.budget {
                Some(b) if self.steps > b + 1 => Err(Cut),
                Some(b) if self.steps == b + 1 => Ok(false),
                _ => Ok(true),
            }
        }
    }

    impl<const W: usize, const E: usize> ErrorType for CutFlash<W, E> {
        type Error = Cut;
    }
    impl<const W: usize, const E: usize> ReadNorFlash for CutFlash<W, E> {
        const READ_SIZE: usize = 1;
        fn read(&mut self, offset: u32, bytes: &mut [u8]) -> Result<(), Cut> {
            let o = offset as usize;
            bytes.copy_from_slice(&self.mem[o..o + bytes.len()]);
            Ok(())
        }
        fn capacity(&self) -> usize {
            self.mem.len()
        }
    }
    impl<const W: usize, const E: usize> NorFlash for CutFlash<W, E> {
        const WRITE_SIZE: usize = W;
        const ERASE_SIZE: usize = E;
        fn erase(&mut self, from: u32, to: u32) -> Result<(), Cut> {
            assert!(from as usize % E == 0 && to as usize % E == 0);
            for block in (from as usize..to as usize).step_by(E) {
                self.erases += 1;
                if self.step()? {
                    self.mem[block..block + E].fill(0xFF);
                } else {
                    self.mem[block..block + E / 2].fill(0xFF);
                    return Err(Cut);
                }
            }
            Ok(())
        }
        fn write(&mut self, offset: u32, bytes: &[u8]) -> Result<(), Cut> {
            assert!(offset as usize % W == 0 && bytes.len() % W == 0);
            for (k, word) in bytes.chunks(W).enumerate() {
                let at = offset as usize + k * W;
                if self.step()? {
                    for (m, b) in self.mem[at..at + W].iter_mut().zip(word) {
                        *m &= *b;
                    }
                } else {
                    for (m, b) in self.mem[at..at + W].iter_mut().zip(word) {
                        *m &= *b | 0x5A;
                    }
                    return Err(Cut);
                }
            }
            Ok(())
        }
    }

    /// Three distinct valid blobs of the QEMU unit (different creation times).
    fn blobs() -> [std::vec::Vec<u8>; 3] {
        core::array::from_fn(|i| {
            let (buf, n) = ParameterBlob {
                unit_id: QEMU_UNIT_ID,
                calibration: paper_unit::calibration(),
                created_unix_s: 1_800_000_000 + i as u64,
            }
            .to_bytes()
            .unwrap();
            buf[..n].to_vec()
        })
    }

    fn boot<const W: usize, const E: usize>(mem: &[u8]) -> Option<std::vec::Vec<u8>> {
        let mut f = CutFlash::<W, E>::new(0);
        f.mem = mem.to_vec();
        let mut s = AbStore::new(f, 0, E as u32).unwrap();
        let mut out = [0u8; BLOB_MAX_LEN];
        let got = s.load(&mut out).unwrap().map(|n| out[..n].to_vec());
        if let Some(b) = &got {
            // Whatever boots must be a valid blob of this unit, never a corrupt one.
            decode_for_unit(b, QEMU_UNIT_ID).expect("booted blob is valid");
        }
        got
    }

    /// Cuts the power at every step of writing `new` over the state `before`, checking that each cut
    /// boots `old` or `new`; returns the step count of an uncut write.
    fn cut_everywhere<const W: usize, const E: usize>(
        before: &[u8],
        old: Option<&[u8]>,
        new: &[u8],
    ) -> usize {
        let mut n = 0;
        loop {
            let mut f = CutFlash::<W, E>::new(0);
            f.mem = before.to_vec();
            f.budget = Some(n);
            let mut s = AbStore::new(f, 0, E as u32).unwrap();
            let result = s.store(new);
            let mem = s.into_inner().mem;
            let booted = boot::<W, E>(&mem);
            if result.is_ok() {
                assert_eq!(booted.as_deref(), Some(new), "completed write boots new");
                return n;
            }
            assert!(
                booted.as_deref() == old || booted.as_deref() == Some(new),
                "cut at step {n}: booted neither old nor new"
            );
            // And after the cut, a later write still succeeds and wins.
            let mut f = CutFlash::<W, E>::new(0);
            f.mem = mem;
            let mut s = AbStore::new(f, 0, E as u32).unwrap();
            s.store(new).unwrap();
            assert_eq!(boot::<W, E>(&s.into_inner().mem).as_deref(), Some(new));
            n += 1;
        }
    }

    fn power_cut_at_every_step<const W: usize, const E: usize>() {
        let [a, b, c] = blobs();
        let empty = CutFlash::<W, E>::new(2).mem;
        assert_eq!(boot::<W, E>(&empty), None);
        let steps = cut_everywhere::<W, E>(&empty, None, &a);
        assert!(steps > 10, "{steps}");
        // State with A stored; then B over it; then C over A+B (the A slot is reused).
        let mut s = AbStore::new(CutFlash::<W, E>::new(2), 0, E as u32).unwrap();
        s.store(&a).unwrap();
        let with_a = s.into_inner().mem;
        cut_everywhere::<W, E>(&with_a, Some(&a), &b);
        let mut s = AbStore::new(
            CutFlash::<W, E> {
                mem: with_a,
                budget: None,
                steps: 0,
                erases: 0,
            },
            0,
            E as u32,
        )
        .unwrap();
        s.store(&b).unwrap();
        let with_ab = s.into_inner().mem;
        assert_eq!(boot::<W, E>(&with_ab).as_deref(), Some(&b[..]));
        cut_everywhere::<W, E>(&with_ab, Some(&b), &c);
    }

    #[test]
    fn power_cut_at_every_step_byte_writes() {
        power_cut_at_every_step::<1, 1024>();
    }

    #[test]
    fn power_cut_at_every_step_word_writes() {
        power_cut_at_every_step::<8, 2048>();
    }

    #[test]
    fn sequence_numbers_wrap() {
        let [a, b, _] = blobs();
        let mut s = AbStore::new(CutFlash::<4, 1024>::new(2), 0, 1024).unwrap();
        s.store(&a).unwrap();
        // Forge slot 0's sequence to u32::MAX (re-sign the CRC), then store b: it gets seq 0 and wins.
        let mut mem = s.into_inner().mem;
        mem[4..8].copy_from_slice(&u32::MAX.to_le_bytes());
        // (Re-signed with the `crc` crate's table-driven CRC-32: the store's bitwise one must agree.)
        let table = crc::Crc::<u32>::new(&crc::CRC_32_ISO_HDLC);
        let mut d = table.digest();
        d.update(&mem[..12]);
        d.update(&a);
        mem[12..16].copy_from_slice(&d.finalize().to_le_bytes());
        assert_eq!(boot::<4, 1024>(&mem).as_deref(), Some(&a[..]));
        let mut s = AbStore::new(
            CutFlash::<4, 1024> {
                mem,
                budget: None,
                steps: 0,
                erases: 0,
            },
            0,
            1024,
        )
        .unwrap();
        s.store(&b).unwrap();
        let mem = s.into_inner().mem;
        assert_eq!(
            u32::from_le_bytes(mem[1024 + 4..1024 + 8].try_into().unwrap()),
            0
        );
        assert_eq!(boot::<4, 1024>(&mem).as_deref(), Some(&b[..]));
    }

    #[test]
    fn bad_lengths_and_geometry_are_refused() {
        let mut s = AbStore::new(CutFlash::<4, 1024>::new(2), 0, 1024).unwrap();
        assert_eq!(s.store(&[]), Err(StoreError::BadLength));
        assert_eq!(s.store(&[0; BLOB_MAX_LEN + 1]), Err(StoreError::BadLength));
        assert!(AbStore::new(CutFlash::<4, 128>::new(4), 0, 128).is_err()); // slot too small
        assert!(AbStore::new(CutFlash::<4, 1024>::new(1), 0, 1024).is_err()); // no room for B
    }

    /// Erased ahead at power-on, a store only programs; the store after it erases (its slot holds
    /// the first record) unless the board prepared again; a power cut during `prepare` boots the
    /// stored blob.
    #[test]
    fn prepared_slots_are_programmed_without_an_erase() {
        let [a, b, _] = blobs();
        let mut s = AbStore::new(CutFlash::<4, 1024>::new(2), 0, 1024).unwrap();
        assert_eq!(s.prepare(), Ok(true));
        assert_eq!(s.prepare(), Ok(false), "already blank: no second erase");
        s.store(&a).unwrap();
        assert_eq!(s.flash.erases, 1, "the store erased");
        s.store(&b).unwrap();
        assert_eq!(
            s.flash.erases, 2,
            "slot 1 was never erased: the store must erase it"
        );
        assert_eq!(s.prepare(), Ok(true));
        assert_eq!(s.flash.erases, 3);
        s.store(&a).unwrap();
        assert_eq!(s.flash.erases, 3, "prepared: the store erased");
        // A cut half-way through `prepare`'s erase leaves the newest record (a) in force.
        let mem = s.into_inner().mem;
        let mut f = CutFlash::<4, 1024>::new(0);
        f.mem = mem;
        f.budget = Some(0);
        let mut s = AbStore::new(f, 0, 1024).unwrap();
        assert!(s.prepare().is_err());
        assert_eq!(
            boot::<4, 1024>(&s.into_inner().mem).as_deref(),
            Some(&a[..])
        );
    }

    #[test]
    fn ram_flash_has_nor_semantics() {
        let mut mem = [0u8; 4096];
        let mut f = RamNorFlash::<2048>::new(&mut mem);
        f.erase(0, 2048).unwrap();
        f.write(0, &[0xF0, 0x0F, 0xFF, 0x00]).unwrap();
        f.write(0, &[0x3C, 0xFF, 0xFF, 0xFF]).unwrap();
        let mut b = [0u8; 4];
        f.read(0, &mut b).unwrap();
        assert_eq!(b, [0x30, 0x0F, 0xFF, 0x00]);
        assert!(f.write(2, &[0; 4]).is_err());
        assert!(f.erase(0, 100).is_err());
        assert!(f.read(4094, &mut b).is_err());
        let mut s = AbStore::new(f, 0, 2048).unwrap();
        let [a, _, _] = blobs();
        s.store(&a).unwrap();
        let mut out = [0u8; BLOB_MAX_LEN];
        assert_eq!(s.load(&mut out).unwrap(), Some(a.len()));
    }
}
