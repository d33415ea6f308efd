//! Bounds on everything that sizes work or memory: the longest line, the largest text file, and the
//! range of every numeric option. Each input is checked before any work is done (or any device is
//! written), so a wrong file or a wrong number gets a clear error at once instead of a process that
//! grows until it is killed.

use std::io::Read;
use std::path::Path;

/// Longest line of `samples.csv`, bytes. A row is eight fields of at most ~25 characters and a
/// segment name; 4 KiB leaves room for names and spaces, and bounds the reader's carry buffer.
pub const MAX_LINE_BYTES: usize = 4096;

/// Most segments one recording may name (a real plan has hundreds); bounds what a reader keeps per
/// segment name.
pub const MAX_SEGMENTS: usize = 10_000;

/// Largest plan, unit or calibration file, bytes. The biggest real plan (hundreds of segments) is a
/// few tens of kB.
pub(crate) const MAX_TEXT_FILE_BYTES: u64 = 4 << 20;

/// Highest sample rate a plan may declare, Hz.
pub const MAX_SAMPLE_RATE_HZ: f64 = 100_000.0;

/// Sample rates `simulate-hand` writes, Hz (the command line's `--rate-hz` and Python's `rate_hz`):
/// from a slow logger's to a fast IMU's FIFO.
pub const SIMULATED_HAND_RATE_HZ: (f64, f64) = (20.0, 10_000.0);

/// Longest planned segment, s (one day).
pub const MAX_SEGMENT_DURATION_S: f64 = 86_400.0;

/// Most rows one simulated segment may have (duration × rate): 10⁹ rows ≈ 150 GB of text.
pub(crate) const MAX_SEGMENT_ROWS: f64 = 1e9;

/// Largest table rate a plan may name, °/s (a rate table turning 20 rev/s is already extreme; the
/// lever-arm terms grow as ω², so a typo like 1e9 °/s would make every model term overflow).
pub const MAX_RATE_DEG_S: f64 = 7200.0;

/// Lowest sample rate of a logger recording, Hz (one sample every 1000 s is no hand-held session; a
/// smaller rate is a typo that would make every time in the result astronomical).
pub const MIN_LOGGER_RATE_HZ: f64 = 1e-3;

/// A number as people read it: plain between 10⁻³ and 10⁶, else in exponent form (`1e300`, never
/// three hundred digits).
pub(crate) fn short_number(v: f64) -> String {
    if v.is_finite() && v != 0.0 && !(1e-3..1e6).contains(&v.abs()) {
        format!("{v:e}")
    } else {
        format!("{v}")
    }
}

/// Why a command-line number is refused by one of the range parsers below ([`real`], [`whole_u32`],
/// [`whole_u64`]); clap prints it after the option's name and the value given.
#[derive(Clone, Debug, PartialEq, thiserror::Error)]
pub enum OptionRangeError {
    /// Not a number at all (or not a whole one, for a count).
    #[error("not a {kind}: give a number in {range}")]
    NotANumber {
        /// "number" or "whole number".
        kind: &'static str,
        /// The accepted range, as text.
        range: String,
    },
    /// A number outside the option's range (NaN and ±inf are outside every range).
    #[error("{value} is out of range: give a number in {range}")]
    OutOfRange {
        /// The value read, as `short_number` prints it.
        value: String,
        /// The accepted range, as text.
        range: String,
    },
}

/// The range of a real-valued option, `[min, max]`. A quantity that must be > 0 (a rate, a σ, a
/// duration) gets the smallest value that still means something as `min`, never an open 0: a
/// `1e-300` accepted would print as three hundred digits later.
#[derive(Clone, Copy, Debug, PartialEq)]
pub(crate) struct RealRange {
    /// Lower bound (included).
    pub min: f64,
    /// Upper bound (included).
    pub max: f64,
}

impl RealRange {
    /// `value` is finite and inside.
    pub fn contains(&self, value: f64) -> bool {
        value.is_finite() && (self.min..=self.max).contains(&value)
    }

    /// Checks a value read from a file or given in code (the command line is checked by [`real`]).
    pub fn check(&self, value: f64) -> Result<f64, OptionRangeError> {
        if self.contains(value) {
            Ok(value)
        } else {
            Err(OptionRangeError::OutOfRange {
                value: short_number(value),
                range: self.to_string(),
            })
        }
    }

    /// Parses a command-line value.
    pub fn parse(&self, text: &str) -> Result<f64, OptionRangeError> {
        let value: f64 = text
            .trim()
            .parse()
            .map_err(|_| OptionRangeError::NotANumber {
                kind: "number",
                range: self.to_string(),
            })?;
        self.check(value)
    }
}

impl std::fmt::Display for RealRange {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        write!(
            f,
            "[{}, {}]",
            short_number(self.min),
            short_number(self.max)
        )
    }
}

/// The clap value parser of a real option in `[min, max]`: NaN, ±inf and values outside are a usage
/// error (exit 2) naming the option and the range, before any work. Every real option uses this
/// (`host/tests/option_sweep.rs` refuses a plain `f64` parser).
pub fn real(
    min: f64,
    max: f64,
) -> impl Fn(&str) -> Result<f64, OptionRangeError> + Clone + Send + Sync + 'static {
    let range = RealRange { min, max };
    move |text: &str| range.parse(text)
}

/// Parses a whole number in `min..=max`.
fn parse_whole(text: &str, min: u64, max: u64) -> Result<u64, OptionRangeError> {
    let range = format!("{min}..={max}");
    let text = text.trim();
    match text.parse::<u64>() {
        Ok(v) if (min..=max).contains(&v) => Ok(v),
        Ok(v) => Err(OptionRangeError::OutOfRange {
            value: v.to_string(),
            range,
        }),
        // A number that is not a whole one in u64 (`-1`, `1e300`, `NaN`) is named as a number.
        Err(_) => match text.parse::<f64>() {
            Ok(v) => Err(OptionRangeError::OutOfRange {
                value: short_number(v),
                range,
            }),
            Err(_) => Err(OptionRangeError::NotANumber {
                kind: "whole number",
                range,
            }),
        },
    }
}

/// The clap value parser of a count or an id in `min..=max` (`u64`): see [`real`].
pub fn whole_u64(
    min: u64,
    max: u64,
) -> impl Fn(&str) -> Result<u64, OptionRangeError> + Clone + Send + Sync + 'static {
    move |text: &str| parse_whole(text, min, max)
}

/// [`whole_u64`] for a `u32` option.
pub fn whole_u32(
    min: u32,
    max: u32,
) -> impl Fn(&str) -> Result<u32, OptionRangeError> + Clone + Send + Sync + 'static {
    move |text: &str| {
        parse_whole(text, min.into(), max.into()).map(|v| u32::try_from(v).unwrap_or(max))
    }
}

/// Why a number is refused.
#[derive(Clone, Debug, PartialEq, thiserror::Error)]
#[error(
    "{} = {} is out of range: give a number in {}",
    .name,
    short_number(*.value),
    .range
)]
pub struct RangeError {
    /// The option or field, as the user spells it.
    pub name: String,
    /// The value given.
    pub value: f64,
    /// The accepted range, as text.
    pub range: String,
}

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

/// [`read_bounded`] with `MAX_TEXT_FILE_BYTES`, as UTF-8 text; bytes that are not UTF-8 are an
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

/// Smallest pass/fail limit, tolerance, σ multiple or noise σ an option may give: a smaller one is
/// zero in every printout and passes no real unit (and a σ of zero makes a prediction singular).
pub const MIN_LIMIT: f64 = 1e-6;

/// Largest pass/fail limit or σ multiple an option may give (a limit of a million mg, degrees-squared
/// or σ checks nothing; a larger number is a typo).
pub const MAX_LIMIT: f64 = 1e6;

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
    fn range_parsers_refuse_what_is_outside_and_print_short_numbers() {
        let rate = real(1e-3, 1e5);
        assert_eq!(rate("200"), Ok(200.0));
        assert_eq!((rate("1e5"), rate("0.001")), (Ok(1e5), Ok(1e-3)));
        for bad in [
            "NaN", "inf", "-inf", "0", "-1", "1e-300", "1e300", "100000.1", "x",
        ] {
            let e = rate(bad).unwrap_err().to_string();
            assert!(
                e.ends_with("give a number in [0.001, 100000]"),
                "{bad}: {e}"
            );
        }
        assert_eq!(
            rate("1e300").unwrap_err().to_string(),
            "1e300 is out of range: give a number in [0.001, 100000]"
        );
        assert_eq!(
            rate("1e-300").unwrap_err().to_string(),
            "1e-300 is out of range: give a number in [0.001, 100000]"
        );
        let closed = real(0.0, 45.0);
        assert_eq!((closed("0"), closed("45")), (Ok(0.0), Ok(45.0)));
        assert!(closed("-0.1").is_err() && closed("45.5").is_err());
        let count = whole_u32(1, 10);
        assert_eq!((count("1"), count("10")), (Ok(1), Ok(10)));
        assert_eq!(
            count("0").unwrap_err().to_string(),
            "0 is out of range: give a number in 1..=10"
        );
        assert_eq!(
            count("1e300").unwrap_err().to_string(),
            "1e300 is out of range: give a number in 1..=10"
        );
        assert_eq!(
            count("ten").unwrap_err().to_string(),
            "not a whole number: give a number in 1..=10"
        );
        assert_eq!(whole_u64(0, u64::MAX)("0"), Ok(0));
        assert_eq!(short_number(1e-300), "1e-300");
        assert_eq!(short_number(0.5), "0.5");
    }

    #[test]
    fn endless_and_non_text_files_are_refused_quickly() {
        // /dev/zero never ends: that this returns at all is the bound (a time limit here would
        // only measure how loaded the machine is).
        let e = read_text_bounded(Path::new("/dev/zero")).unwrap_err();
        assert!(e.to_string().contains("longer than"), "{e}");
        let dir = tempfile::tempdir().unwrap();
        let p = dir.path().join("t");
        std::fs::write(&p, b"a = 1\nb = \"\xff\"\n").unwrap();
        let e = read_text_bounded(&p).unwrap_err().to_string();
        assert!(e.contains("line 2") && e.contains("not UTF-8"), "{e}");
    }
}
