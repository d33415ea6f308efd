//! Bounds on everything that sizes work or memory: the longest line, the largest text file, and the
//! range of every numeric option. Each input is checked before any work is done (or any device is
//! written), so a wrong file or a wrong number gets a clear error at once instead of a process that
//! grows until it is killed.

use std::io::Read;
use std::path::Path;

/// Longest line of `samples.csv`, bytes. A row is eight fields of at most ~25 characters and a
/// segment name; 4 KiB leaves room for names and spaces, and bounds the reader's carry buffer.
pub const MAX_LINE_BYTES: usize = 4096;

/// Largest plan, unit or calibration file, bytes. The biggest real plan (hundreds of segments) is a
/// few tens of kB.
pub const MAX_TEXT_FILE_BYTES: u64 = 4 << 20;

/// Longest replayed navigation run (`--duration-s`), s: one hour.
pub const MAX_NAVIGATION_DURATION_S: f64 = 3600.0;

/// Highest sample rate a plan may declare, Hz.
pub const MAX_SAMPLE_RATE_HZ: f64 = 100_000.0;

/// Longest planned segment, s (one day).
pub const MAX_SEGMENT_DURATION_S: f64 = 86_400.0;

/// Most rows one simulated segment may have (duration × rate): 10⁹ rows ≈ 150 GB of text.
pub const MAX_SEGMENT_ROWS: f64 = 1e9;

/// Longest wait for one answer of a device, s.
pub const MAX_TIMEOUT_S: f64 = 3600.0;

/// Most samples in one streamed window.
pub const MAX_WINDOW: u32 = 1_000_000;

/// Largest verification tolerance, mg (a tolerance above 1 g checks nothing).
pub const MAX_TOLERANCE_MG: f64 = 1000.0;

/// Largest table rate a plan may name, °/s (a rate table turning 20 rev/s is already extreme; the
/// lever-arm terms grow as ω², so a typo like 1e9 °/s would make every model term overflow).
pub const MAX_RATE_DEG_S: f64 = 7200.0;

/// Why a number is refused.
#[derive(Clone, Debug, PartialEq)]
pub struct RangeError {
    /// The option or field, as the user spells it.
    pub name: String,
    /// The value given.
    pub value: f64,
    /// The accepted range, as text.
    pub range: String,
}

impl std::fmt::Display for RangeError {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        let v = self.value;
        if v.is_finite() && v != 0.0 && !(1e-3..1e6).contains(&v.abs()) {
            write!(f, "{} = {v:e}", self.name)?;
        } else {
            write!(f, "{} = {v}", self.name)?;
        }
        write!(f, " is out of range: give a number in {}", self.range)
    }
}

impl std::error::Error for RangeError {}

/// `value` must be finite and in `(0, max]`.
pub fn positive_at_most(name: &str, value: f64, max: f64) -> Result<f64, RangeError> {
    if value.is_finite() && value > 0.0 && value <= max {
        Ok(value)
    } else {
        Err(RangeError {
            name: name.into(),
            value,
            range: format!("(0, {max}]"),
        })
    }
}

/// `value` must be an integer in `1..=max`.
pub fn count_in(name: &str, value: u32, max: u32) -> Result<u32, RangeError> {
    if (1..=max).contains(&value) {
        Ok(value)
    } else {
        Err(RangeError {
            name: name.into(),
            value: value.into(),
            range: format!("1..={max}"),
        })
    }
}

/// Reads at most `max` bytes of `path`; a longer file (or an endless one such as `/dev/zero`) is an
/// `InvalidData` error naming the limit, after reading `max + 1` bytes only.
pub fn read_bounded(path: &Path, max: u64) -> std::io::Result<Vec<u8>> {
    let file = std::fs::File::open(path)?;
    let mut bytes = Vec::new();
    file.take(max + 1).read_to_end(&mut bytes)?;
    if bytes.len() as u64 > max {
        return Err(std::io::Error::new(
            std::io::ErrorKind::InvalidData,
            format!("longer than {max} bytes: not a file of this kind"),
        ));
    }
    Ok(bytes)
}

/// [`read_bounded`] with [`MAX_TEXT_FILE_BYTES`], as UTF-8 text; bytes that are not UTF-8 are an
/// `InvalidData` error naming the line.
pub fn read_text_bounded(path: &Path) -> std::io::Result<String> {
    let bytes = read_bounded(path, MAX_TEXT_FILE_BYTES)?;
    String::from_utf8(bytes).map_err(|e| {
        let good = &e.as_bytes()[..e.utf8_error().valid_up_to()];
        let line = 1 + good.iter().filter(|&&b| b == b'\n').count();
        std::io::Error::new(
            std::io::ErrorKind::InvalidData,
            format!("line {line} has bytes that are not UTF-8 text: not a text file of this kind"),
        )
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn numbers_out_of_range_name_the_option_and_the_range() {
        for v in [f64::NAN, 0.0, -5.0, 1e7, f64::INFINITY] {
            let e = positive_at_most("--duration-s", v, 3600.0).unwrap_err();
            assert!(e.to_string().contains("--duration-s") && e.to_string().contains("(0, 3600]"));
        }
        assert_eq!(positive_at_most("x", 60.0, 3600.0), Ok(60.0));
        assert!(count_in("--window", 0, 10).is_err());
        assert_eq!(count_in("--window", 10, 10), Ok(10));
    }

    #[test]
    fn endless_and_non_text_files_are_refused_quickly() {
        let started = std::time::Instant::now();
        let e = read_text_bounded(Path::new("/dev/zero")).unwrap_err();
        assert!(e.to_string().contains("longer than"), "{e}");
        assert!(started.elapsed().as_secs_f64() < 1.0);
        let dir = tempfile::tempdir().unwrap();
        let p = dir.path().join("t");
        std::fs::write(&p, b"a = 1\nb = \"\xff\"\n").unwrap();
        let e = read_text_bounded(&p).unwrap_err().to_string();
        assert!(e.contains("line 2") && e.contains("not UTF-8"), "{e}");
    }
}
