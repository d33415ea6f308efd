//! Where the STM32F4 boards keep their image and their calibration in the internal flash, and how
//! long the calibration store's erase holds the CPU.
//!
//! The STM32F4's flash has sectors of three sizes (RM0090 §3.3 Table 5; RM0390 §3.3 Table 4 for
//! the F446): sectors 0–3 of 16 KiB, sector 4 of 64 KiB, then 128 KiB sectors. Erasing a sector
//! stalls every read of a single-bank part's flash, the CPU's instruction fetches included, so
//! while it runs no interrupt is served and the IMU's FIFO overflows. The erase time grows with the
//! sector (DS8626 Table 40, "Flash memory programming"): a 128 KiB sector takes 2 s typical and 4 s
//! at most at 8-bit parallelism, a 16 KiB sector 250 ms typical and 500 ms at most at 32-bit.
//!
//! So the calibration's two slots are the 16 KiB sectors 1 and 2, as ArduPilot keeps its storage
//! on its F405 boards (`libraries/AP_HAL_ChibiOS/hwdef/speedybeef4v4/hwdef.dat`:
//! `FLASH_RESERVE_START_KB 48`, `STORAGE_FLASH_PAGE 1`) and Betaflight its configuration in
//! sector 1 (`src/link/stm32_flash_f405.ld`, `FLASH_CONFIG` at 0x0800_4000). The vector table
//! stays in sector 0, where the part boots from; the code starts at sector 3 (cortex-m-rt's
//! `_stext`, set in `memory.x` and `memory-f405.x`). The store erases at 32-bit parallelism
//! (PSIZE = x32, allowed from 2.7 V: RM0090 §3.6.2 Table 7; both boards run at 3.3 V), so a write
//! that must erase blocks sampling for at most [`SLOT_ERASE_MAX_MS`].
//!
//! A tool that writes a flat binary from 0x0800_0000 would fill sectors 1 and 2 with the gap's
//! bytes: `scripts/dfu-images.sh` writes the image as two parts around the store (firmware README,
//! "Flash without a probe").

/// Sizes of the STM32F4's flash sectors 0–11 of a single bank, bytes.
const SECTOR_SIZES: [u32; 12] = [
    16 << 10,
    16 << 10,
    16 << 10,
    16 << 10,
    64 << 10,
    128 << 10,
    128 << 10,
    128 << 10,
    128 << 10,
    128 << 10,
    128 << 10,
    128 << 10,
];

/// One flash sector: its number (FLASH_CR.SNB), its offset from 0x0800_0000 and its size.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Sector {
    /// The sector's number.
    pub number: u8,
    /// Its first byte, from the start of the flash.
    pub offset: u32,
    /// Its size, bytes.
    pub size: u32,
}

impl Sector {
    /// Sector `number` (`None` past sector 11).
    pub const fn numbered(number: u8) -> Option<Sector> {
        if number as usize >= SECTOR_SIZES.len() {
            return None;
        }
        let mut offset = 0;
        let mut i = 0;
        while i < number as usize {
            offset += SECTOR_SIZES[i];
            i += 1;
        }
        Some(Sector {
            number,
            offset,
            size: SECTOR_SIZES[number as usize],
        })
    }

    /// The sector holding `offset` (`None` past sector 11).
    pub fn at(offset: u32) -> Option<Sector> {
        (0..SECTOR_SIZES.len() as u8)
            .filter_map(Sector::numbered)
            .find(|s| offset >= s.offset && offset - s.offset < s.size)
    }

    /// The first byte past the sector.
    pub const fn end(&self) -> u32 {
        self.offset + self.size
    }
}

/// Program/erase parallelism, FLASH_CR.PSIZE (RM0090 §3.6.2).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Parallelism {
    /// Byte at a time: any supply from 1.8 V (stm32f4xx-hal's choice for every operation).
    X8,
    /// Half-word: from 2.1 V.
    X16,
    /// Word: from 2.7 V.
    X32,
}

/// Typical and longest erase of a sector of `size` bytes at `parallelism`, ms (DS8626 Table 40,
/// "Flash memory programming": t_ERASE16KB, t_ERASE64KB, t_ERASE128KB). `None` for a size that is
/// not a sector's.
pub const fn erase_ms(size: u32, parallelism: Parallelism) -> Option<(u32, u32)> {
    use Parallelism::*;
    Some(match (size >> 10, parallelism) {
        (16, X8) => (400, 800),
        (16, X16) => (300, 600),
        (16, X32) => (250, 500),
        (64, X8) => (1200, 2400),
        (64, X16) => (700, 1400),
        (64, X32) => (550, 1100),
        (128, X8) => (2000, 4000),
        (128, X16) => (1300, 2600),
        (128, X32) => (1000, 2000),
        _ => return None,
    })
}

/// The store's first sector; its second slot is the next sector.
pub const STORE_FIRST_SECTOR: u8 = 1;
const STORE_FIRST: Sector = match Sector::numbered(STORE_FIRST_SECTOR) {
    Some(s) => s,
    None => panic!("no such sector"),
};
/// Flash offset (from 0x0800_0000) of the calibration store: sectors 1 and 2.
pub const STORE_OFFSET: u32 = STORE_FIRST.offset;
/// Size of one store slot: one 16 KiB sector.
pub const SLOT_SIZE: u32 = STORE_FIRST.size;
/// Flash offset of the code (cortex-m-rt's `_stext`): sector 3, the first past the store.
pub const CODE_OFFSET: u32 = STORE_OFFSET + 2 * SLOT_SIZE;
/// The parallelism the store erases at.
pub const ERASE_PARALLELISM: Parallelism = Parallelism::X32;
/// The longest a slot's erase holds the CPU (and with it sampling), ms.
pub const SLOT_ERASE_MAX_MS: u32 = match erase_ms(SLOT_SIZE, ERASE_PARALLELISM) {
    Some((_, max)) => max,
    None => panic!("the slot is not one sector"),
};
/// The typical time of a slot's erase, ms.
pub const SLOT_ERASE_TYPICAL_MS: u32 = match erase_ms(SLOT_SIZE, ERASE_PARALLELISM) {
    Some((typical, _)) => typical,
    None => panic!("the slot is not one sector"),
};

#[cfg(test)]
mod tests {
    use super::*;

    /// The longest sampling may stop while a calibration is written: a write that must erase
    /// first (the second write without a restart between) blocks the CPU for one slot's erase.
    const BLOCKED_SAMPLING_LIMIT_MS: u32 = 500;

    #[test]
    fn a_slot_erase_blocks_sampling_at_most_half_a_second() {
        let (_, longest) = erase_ms(SLOT_SIZE, ERASE_PARALLELISM).unwrap();
        assert_eq!(longest, SLOT_ERASE_MAX_MS);
        assert!(
            longest <= BLOCKED_SAMPLING_LIMIT_MS,
            "slot {SLOT_SIZE} bytes at {ERASE_PARALLELISM:?}: {longest} ms"
        );
        // The same sectors at the HAL's 8-bit parallelism would not hold it (800 ms at most).
        let (_, x8) = erase_ms(SLOT_SIZE, Parallelism::X8).unwrap();
        assert!(x8 > BLOCKED_SAMPLING_LIMIT_MS);
    }

    #[test]
    fn the_sector_table_is_the_reference_manuals() {
        // RM0090 Table 5: sector 4 at 0x0801_0000, sector 5 at 0x0802_0000, sector 11 at
        // 0x080E_0000 (128 KiB, the last of 1 MiB).
        assert_eq!(
            Sector::numbered(4).map(|s| (s.offset, s.size)),
            Some((0x1_0000, 64 << 10))
        );
        assert_eq!(Sector::numbered(5).map(|s| s.offset), Some(0x2_0000));
        assert_eq!(Sector::numbered(11).map(|s| s.end()), Some(1 << 20));
        assert_eq!(Sector::numbered(12), None);
        assert_eq!(Sector::at(0x0_BFFF).map(|s| s.number), Some(2));
        assert_eq!(Sector::at(0x0_C000).map(|s| s.number), Some(3));
        assert_eq!(Sector::at(1 << 20), None);
    }

    #[test]
    fn the_store_is_two_whole_sectors_between_the_vectors_and_the_code() {
        let (a, b) = (
            Sector::at(STORE_OFFSET).unwrap(),
            Sector::at(STORE_OFFSET + SLOT_SIZE).unwrap(),
        );
        assert_eq!((a.offset, a.size), (STORE_OFFSET, SLOT_SIZE));
        assert_eq!((b.offset, b.size), (STORE_OFFSET + SLOT_SIZE, SLOT_SIZE));
        assert_eq!(b.end(), CODE_OFFSET);
        // Sector 0, where the part boots from, keeps the vector table.
        assert!(STORE_OFFSET >= SECTOR_SIZES[0]);
        // One record (16-byte header, the largest blob, the commit word) fits a slot.
        assert!(16 + shared::blob::BLOB_MAX_LEN + 16 <= SLOT_SIZE as usize);
    }

    /// A `NAME = 0x…;` assignment in a linker script.
    fn symbol(script: &str, name: &str) -> Option<u32> {
        script.lines().find_map(|line| {
            let rest = line
                .trim()
                .strip_prefix(name)?
                .trim_start()
                .strip_prefix('=')?;
            let hex = rest
                .trim()
                .trim_end_matches(';')
                .trim()
                .strip_prefix("0x")?;
            u32::from_str_radix(&hex.replace('_', ""), 16).ok()
        })
    }

    #[test]
    fn the_linker_scripts_place_the_code_past_the_store() {
        for (file, script) in [
            ("memory.x", include_str!("../../memory.x")),
            ("memory-f405.x", include_str!("../memory-f405.x")),
        ] {
            let flash = 0x0800_0000;
            assert_eq!(
                symbol(script, "_stext"),
                Some(flash + CODE_OFFSET),
                "{file}"
            );
            assert_eq!(
                symbol(script, "_calstore_start"),
                Some(flash + STORE_OFFSET),
                "{file}"
            );
            assert_eq!(
                symbol(script, "_calstore_end"),
                Some(flash + CODE_OFFSET),
                "{file}"
            );
        }
    }
}
