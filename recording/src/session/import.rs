//! A real logger's CSV: one continuous, unlabelled recording (a hand-held session) with a header row,
//! named columns in any order, extra columns ignored, time from a column or from a sample rate, and the
//! units the user states. `host segment` cuts it into a session (`super::segment`).
//!
//! The accelerometer's values are kept in the logger's own unit (it becomes the session's
//! `output_unit`, so the fitted bias and scale are in that unit); the gyro is converted to rad/s, the
//! session format's unit. The rows kept are held in memory (the gyro fit integrates every turn), so
//! they are bounded as the caller's keeper says (`super::logs`; at most [`MAX_ROWS`]), and every
//! line is bounded ([`MAX_LINE_BYTES`]). The header and the rows are read by `rows`.

use super::note::Note;
use crate::limits::short_number;
use crate::spelling::{Spelling, UserOption};
use shared::OutputUnit;

mod gravity;
mod lines;
mod notes;
mod rows;
mod stretches;
pub mod time;

use super::logs::keep::{Keep, Keeper, STILL_VAR_M2_S4};
use super::repair::{run_rate_hz, TimeRepairs};
use lines::Counted;
pub use notes::Places;
use rows::{read_header, Layout, Rows, Time};
use std::fs::File;
use std::io::{BufRead, BufReader};
use std::path::{Path, PathBuf};
pub(crate) use stretches::Resume;
pub use time::six_digits;
pub use time::{detect_time_unit, say_time_jumps, TimeJump, TimeOrigin, TimeUnit, GAP_PERIODS};
use time::{MAX_RATE_HZ, MAX_SPAN_DAYS, MIN_RATE_HZ, MIN_SPAN_S};

/// Longest accepted line, bytes: a logger's row is well under 1 KiB; a file with no line ends (or a
/// binary file) must not be read into memory whole.
pub const MAX_LINE_BYTES: usize = 64 * 1024;

/// A text file with more lines longer than [`MAX_LINE_BYTES`] than this is refused: not a damaged
/// logger's CSV but something else.
pub(crate) const MAX_OVERLONG_LINES: usize = 100;
/// Most rows held: 4 million rows (about 190 MB) is 67 minutes at 1 kHz, far more than a hand-held
/// session needs.
pub const MAX_ROWS: usize = 4_000_000;
/// Fewest rows (or samples) of a recording that `segment` cuts into a session: a second at 100 Hz,
/// shorter than one still position.
pub(crate) const MIN_SESSION_ROWS: usize = 100;
/// The default accelerometer and gyro column names, x y z each.
pub const DEFAULT_COLUMNS: [&str; 6] = ["acc_x", "acc_y", "acc_z", "gyr_x", "gyr_y", "gyr_z"];

/// The gyro's unit in the logger's file.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum GyroUnit {
    /// Degrees per second.
    DegPerS,
    /// Radians per second.
    RadPerS,
}

impl GyroUnit {
    /// Parses "deg/s" or "rad/s".
    pub fn parse(s: &str) -> Option<GyroUnit> {
        match s {
            "deg/s" | "dps" | "°/s" => Some(GyroUnit::DegPerS),
            "rad/s" => Some(GyroUnit::RadPerS),
            _ => None,
        }
    }

    /// rad/s per unit.
    pub fn to_rad_s(self) -> f64 {
        match self {
            GyroUnit::DegPerS => std::f64::consts::PI / 180.0,
            GyroUnit::RadPerS => 1.0,
        }
    }

    /// "deg/s" or "rad/s".
    pub fn symbol(self) -> &'static str {
        match self {
            GyroUnit::DegPerS => "deg/s",
            GyroUnit::RadPerS => "rad/s",
        }
    }
}

/// Whether a unit, as given for either sensor, is raw counts: "LSB", "lsb" or "counts".
pub fn names_counts(s: &str) -> bool {
    matches!(s, "LSB" | "lsb" | "counts")
}

/// Why a gyro's unit and nominal scale, as given, do not go together.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum GyroUnitFault {
    /// Counts without their nominal scale.
    NeedsScale,
    /// A nominal scale for a gyro not in counts.
    ScaleNotCounts,
    /// None of the units read.
    Unknown,
}

/// A gyro's unit as given and its nominal scale (counts per °/s): counts need the scale and are
/// then read in °/s through it; no other unit takes one.
pub fn gyro_unit_and_scale(
    unit: &str,
    lsb_per_dps: Option<f64>,
) -> Result<(GyroUnit, Option<f64>), GyroUnitFault> {
    match (names_counts(unit), lsb_per_dps) {
        (true, Some(lsb)) => Ok((GyroUnit::DegPerS, Some(lsb))),
        (true, None) => Err(GyroUnitFault::NeedsScale),
        (false, Some(_)) => Err(GyroUnitFault::ScaleNotCounts),
        (false, None) => GyroUnit::parse(unit)
            .map(|u| (u, None))
            .ok_or(GyroUnitFault::Unknown),
    }
}

/// Parses an accelerometer unit as the command line spells it: "m/s2", "g", "LSB" or "V".
pub fn parse_acc_unit(s: &str) -> Option<OutputUnit> {
    match s {
        "m/s2" | "m/s^2" | "m/s²" => Some(OutputUnit::MetresPerSecondSquared),
        "g" => Some(OutputUnit::StandardGravity),
        _ if names_counts(s) => Some(OutputUnit::Lsb),
        "V" | "v" => Some(OutputUnit::Volts),
        _ => None,
    }
}

/// Where each sample's time comes from.
#[derive(Clone, Debug, PartialEq)]
pub enum TimeSource {
    /// A column holding time stamps (in the options' `time_unit`, or detected).
    Column(String),
    /// Row number / rate (any index column is then ignored).
    RateHz(f64),
}

/// How to read a logger's CSV.
#[derive(Clone, Debug, PartialEq)]
pub struct ImportOptions {
    /// acc x, y, z, gyro x, y, z column names.
    pub columns: [String; 6],
    /// Time stamps.
    pub time: TimeSource,
    /// The accelerometer's unit (kept as the output unit).
    pub acc_unit: OutputUnit,
    /// The gyro's unit (converted to rad/s).
    pub gyro_unit: GyroUnit,
    /// The time column's unit; `None`: detected ([`detect_time_unit`]).
    pub time_unit: Option<TimeUnit>,
    /// Counts subtracted from each accelerometer axis before anything else (an unsigned output's
    /// mid-scale zero, e.g. 32768), in the accelerometer's unit.
    pub acc_offset: [f64; 3],
    /// The gyro logs counts at this nominal scale, LSB per °/s (the gyro fit finds the true one);
    /// `gyro_unit` is then ignored.
    pub gyro_lsb_per_dps: Option<f64>,
    /// Counts subtracted from each gyro axis before it is scaled (an unsigned output's mid-scale
    /// zero rate), with a gyro in counts. The gyro's calibration is then of the counts less it, and
    /// a reading of the log for `apply` gives the same offset.
    pub gyro_offset: [f64; 3],
    /// The column with the unit's temperature, °C. A row whose temperature is not a number (a
    /// driver without a reading, an empty field) keeps its values: only its temperature is missing.
    pub temp_column: Option<String>,
    /// Lines before the header to skip (a logger's preamble); 0: the header is found.
    pub skip_lines: u64,
    /// How the caller names these options in messages.
    pub spelling: Spelling,
}

impl ImportOptions {
    /// The default column names with the given time source and units, the messages spelled as the
    /// caller spells its options.
    pub fn new(
        time: TimeSource,
        acc_unit: OutputUnit,
        gyro_unit: GyroUnit,
        spelling: Spelling,
    ) -> ImportOptions {
        ImportOptions {
            columns: DEFAULT_COLUMNS.map(String::from),
            time,
            acc_unit,
            gyro_unit,
            time_unit: None,
            acc_offset: [0.0; 3],
            gyro_lsb_per_dps: None,
            gyro_offset: [0.0; 3],
            temp_column: None,
            skip_lines: 0,
            spelling,
        }
    }

    /// rad/s per unit of the gyro's column.
    fn gyro_rad_s_per_unit(&self) -> f64 {
        match self.gyro_lsb_per_dps {
            Some(lsb) => GyroUnit::DegPerS.to_rad_s() / lsb,
            None => self.gyro_unit.to_rad_s(),
        }
    }
}

/// A continuous recording in memory.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct Recording {
    /// Time of each row, s.
    pub t_s: Vec<f64>,
    /// Accelerometer outputs, the logger's unit, less `acc_offset`.
    pub acc: Vec<[f64; 3]>,
    /// Gyro rates, rad/s, gyro axes.
    pub gyro_rad_s: Vec<[f64; 3]>,
    /// The accelerometer's unit.
    pub acc_unit: Option<OutputUnit>,
    /// Median sample rate, Hz.
    pub rate_hz: f64,
    /// Rows left out because a value was NaN or infinite.
    pub skipped_rows: usize,
    /// The last line, left out because it has no line end (the file was cut short).
    pub unterminated_line: Option<u64>,
    /// Lines longer than [`MAX_LINE_BYTES`], left out (damaged lines; at most
    /// `MAX_OVERLONG_LINES`).
    pub overlong_lines: Vec<u64>,
    /// Counts subtracted from each accelerometer axis on reading (the session is written with them
    /// added back, so that the calibration applies to the logger's own outputs).
    pub acc_offset: [f64; 3],
    /// The time column's unit, and whether it was detected (else given); `None`: from a rate.
    pub time_unit: Option<(TimeUnit, bool)>,
    /// The unit's temperature at each row, °C, where the log has it (binary logs, `super::logs`).
    pub temp_c: Option<Vec<f64>>,
    /// The time stamps' repairs ([`super::repair`]), per stream: what a sample is called there
    /// ("data row", "IMU sample", "accelerometer sample", "gyro sample") and what was done.
    pub time_repairs: Vec<(&'static str, TimeRepairs)>,
    /// The stream read is already corrected by a vehicle's own calibration (PX4's
    /// `sensor_combined`): its name. A calibration made from it would be a residual.
    pub corrected_by: Option<&'static str>,
    /// Where the times come from (`None`: built in memory).
    pub time_origin: Option<TimeOrigin>,
    /// The gyro was logged in counts and converted at this nominal scale, LSB per °/s.
    pub gyro_lsb_per_dps: Option<f64>,
    /// What reading a text file found and did beyond the rows themselves: a preamble skipped, a
    /// header-less file, rows with one stream missing.
    pub read_notes: Vec<Note>,
}

/// Why a logger's file cannot be imported; each says what to do.
#[derive(Debug, thiserror::Error)]
pub enum ImportError {
    /// Not readable.
    #[error("cannot read {path}")]
    Io {
        /// The file.
        path: PathBuf,
        /// The cause.
        source: std::io::Error,
    },
    /// No header line.
    #[error("{0} is empty: a logger's CSV needs a header line naming its columns")]
    Empty(PathBuf),
    /// The first line is numbers and the columns are asked for by name.
    #[error(
        "line {line}, the first, is {fields} numbers: the file has no header; give its columns by \
         index (0-based), e.g. {} and {} (or {})",
        .spelling.given(UserOption::Columns, "0,1,2,3,4,5"),
        .spelling.given(UserOption::TimeColumn, "6"),
        .spelling.given(UserOption::RateHz, "HZ")
    )]
    NoHeader {
        /// 1-based line.
        line: u64,
        /// Its fields.
        fields: usize,
        /// The caller's names of the options.
        spelling: Spelling,
    },
    /// A needed column is not in the header; the advice names the option that asked for it.
    #[error(
        "column '{name}' is not in the header ({found}); {}",
        missing_column_advice(*.option, *.spelling)
    )]
    MissingColumn {
        /// The column asked for.
        name: String,
        /// The header's columns.
        found: String,
        /// The option that named the column (`Columns`, `TimeColumn` or `TempColumn`).
        option: UserOption,
        /// The caller's names of the options.
        spelling: Spelling,
    },
    /// A line longer than [`MAX_LINE_BYTES`].
    #[error(
        "line {line} is longer than {MAX_LINE_BYTES} bytes: not a logger's CSV (or no line ends)"
    )]
    LineTooLong {
        /// 1-based line.
        line: u64,
    },
    /// More lines longer than [`MAX_LINE_BYTES`] than a damaged file has.
    #[error(
        "line {line} is the {}th line longer than {MAX_LINE_BYTES} bytes: not a logger's CSV",
        MAX_OVERLONG_LINES + 1
    )]
    OverlongLines {
        /// 1-based line.
        line: u64,
    },
    /// A field is not a number.
    #[error("line {line}, column '{column}': '{text}' is not a number; fix or delete the line")]
    NotANumber {
        /// 1-based line.
        line: u64,
        /// Column name.
        column: String,
        /// The field.
        text: String,
    },
    /// A row with fewer fields than the header.
    #[error("line {line} has {fields} fields, the header {header}; fix or delete the line")]
    ShortRow {
        /// 1-based line.
        line: u64,
        /// Fields found.
        fields: usize,
        /// Header fields.
        header: usize,
    },
    /// More rows than are read into memory at once.
    #[error("more than {max} rows, the most this reads into memory at once: cut the recording")]
    TooManyRows {
        /// The budget.
        max: usize,
        /// The time column's unit as the rows read so far tell it (detected or given); `None`:
        /// from a rate, or not told.
        time_unit: Option<TimeUnit>,
    },
    /// Too few rows for a session.
    #[error(
        "only {0} usable rows: a hand-held session needs minutes of data (24 positions of 3–5 s)"
    )]
    TooFewRows(usize),
    /// Too few rows to tell a step of time from them.
    #[error("only {0} usable rows: too few to read as a recording (at least 2)")]
    NoRecording(usize),
    /// The rate is not a positive finite number.
    #[error(
        "{} is not a sample rate: give the logger's rate in Hz, e.g. {}",
        .0.given(UserOption::RateHz, .1),
        .0.given(UserOption::RateHz, 102.4)
    )]
    BadRate(Spelling, f64),
    /// No time unit (s, ms, µs, ns) makes the time column's steps and span a logger's.
    #[error(
        "the time column steps by a median {} and spans {} of its unit: in no unit (s, ms, µs, ns) \
         is that a logger's rate ({MIN_RATE_HZ}–{MAX_RATE_HZ} Hz) over a recording of {MIN_SPAN_S} s \
         to {MAX_SPAN_DAYS} days{given}; give {} instead of {}",
        six_digits(*.step),
        six_digits(*.span),
        .spelling.given(UserOption::RateHz, "HZ"),
        .spelling.name(UserOption::TimeColumn)
    )]
    TimeUnit {
        /// The median step, in the column's unit.
        step: f64,
        /// Last minus first time stamp, in the column's unit.
        span: f64,
        /// What the time unit the user gave ([`UserOption::TimeUnit`]) reads the rate as, or empty.
        given: String,
        /// The caller's names of the options.
        spelling: Spelling,
    },
    /// The time unit given ([`UserOption::TimeUnit`]) makes no logger's rate of the time column, and another unit does.
    #[error(
        "the time column steps by a median {} and spans {} of its unit: {} reads \
         that as {given_reading}, no logger's; in {fits} it reads as {fits_reading}: give \
         {}",
        six_digits(*.step),
        six_digits(*.span),
        .spelling.given(UserOption::TimeUnit, .given),
        .spelling.given(UserOption::TimeUnit, .fits)
    )]
    TimeUnitGiven {
        /// The median step, in the column's unit.
        step: f64,
        /// Last minus first time stamp, in the column's unit.
        span: f64,
        /// The unit given.
        given: &'static str,
        /// What it makes of the column ("1e6 Hz over 0.12 s").
        given_reading: String,
        /// The unit that fits.
        fits: &'static str,
        /// What that makes of it.
        fits_reading: String,
        /// The caller's names of the options.
        spelling: Spelling,
    },
    /// More than one time unit fits the time column.
    #[error(
        "the time column steps by a median {} over a span of {}: that reads as {}; say which with \
         {}",
        six_digits(*.step),
        six_digits(*.span),
        .readings.join(" or "),
        .spelling.given(UserOption::TimeUnit, "s|ms|us|ns")
    )]
    TimeUnitAmbiguous {
        /// The median step, in the column's unit.
        step: f64,
        /// Last minus first time stamp.
        span: f64,
        /// Each reading ("100 Hz for 10 min in s").
        readings: Vec<String>,
        /// The caller's names of the options.
        spelling: Spelling,
    },
    /// Counts from an unsigned output whose zero force sits at mid-scale, given without the offset.
    #[error(
        "every accelerometer sample sits near {} counts on each axis, the mid-scale of an unsigned \
         {bits}-bit output: its zero force reads there, not at 0 counts; give {} (counts \
         subtracted from each axis before anything else)",
        short_number(*.offset),
        .spelling.given(UserOption::AccOffset, short_number(*.offset))
    )]
    MidScale {
        /// The mid-scale value, counts.
        offset: f64,
        /// The output's bits.
        bits: u32,
        /// The caller's names of the options.
        spelling: Spelling,
    },
    /// Gravity's magnitude does not fit the stated accelerometer unit.
    #[error(
        "the accelerometer's median magnitude is {} {unit}{}: the unit is wrong{hint}; give the \
         right {} (m/s2, g, LSB or V)",
        short_number(*.median),
        expected.map_or(String::new(), |e| format!(", but gravity is {} {unit}", short_number(e))),
        .spelling.name(UserOption::AccUnit)
    )]
    UnitMismatch {
        /// Median |acc|.
        median: f64,
        /// The stated unit.
        unit: &'static str,
        /// Gravity in that unit (none for counts and volts).
        expected: Option<f64>,
        /// A guess at the right unit.
        hint: String,
        /// The caller's names of the options.
        spelling: Spelling,
    },
}

/// What to give for a column the header lacks: the option that named it, and only that one.
fn missing_column_advice(option: UserOption, spelling: Spelling) -> String {
    match option {
        UserOption::TempColumn => format!(
            "give the temperature column as it is spelt in the header with {}, or leave {} out",
            spelling.given(UserOption::TempColumn, "NAME"),
            spelling.name(UserOption::TempColumn)
        ),
        _ => format!(
            "name the file's columns with {} (and {})",
            spelling.given(UserOption::Columns, "ACC_X,ACC_Y,ACC_Z,GYR_X,GYR_Y,GYR_Z"),
            spelling.given(UserOption::TimeColumn, "NAME")
        ),
    }
}

/// Reads a logger's CSV (see the module docs).
pub fn read_logger_csv(path: &Path, options: &ImportOptions) -> Result<Recording, ImportError> {
    let io = |source| ImportError::Io {
        path: path.to_path_buf(),
        source,
    };
    let file = File::open(path).map_err(io)?;
    read_logger(BufReader::with_capacity(1 << 20, file), path, options)
}

/// [`read_logger_csv`] on any reader (`path` only names it in messages).
/// A hand-held session's file: fewer than `MIN_SESSION_ROWS` rows are refused for it.
pub fn read_logger<R: BufRead>(
    r: R,
    path: &Path,
    options: &ImportOptions,
) -> Result<Recording, ImportError> {
    let rec = read_logger_keeping(r, path, options, &Keep::default(), 1.0)?;
    if rec.len() < MIN_SESSION_ROWS {
        return Err(ImportError::TooFewRows(rec.len()));
    }
    Ok(rec)
}

/// [`read_logger`] keeping the rows `keep` says (`super::logs::keep`); `seconds_per_unit`: the
/// time column's unit, in which the rows are surveyed and chosen. A survey returns no rows.
pub(crate) fn read_logger_keeping<R: BufRead>(
    r: R,
    path: &Path,
    options: &ImportOptions,
    keep: &Keep,
    seconds_per_unit: f64,
) -> Result<Recording, ImportError> {
    let pass = Pass {
        path,
        options,
        keep,
        seconds_per_unit,
    };
    read_logger_by(Counted::new(r, 0), &pass, stretches::read_surveying)
}

/// One window of a long text log (`keep`, a `Keep::Span`) read from the stretches of `file` the
/// survey's `resume` marks for its times (`super::logs::resume`): the same rows and words as
/// [`read_logger_keeping`] reading the whole file with `keep`.
pub(crate) fn read_logger_window(
    file: &mut File,
    path: &Path,
    options: &ImportOptions,
    keep: &Keep,
    seconds_per_unit: f64,
    resume: &Resume,
) -> Result<Recording, ImportError> {
    let pass = Pass {
        path,
        options,
        keep,
        seconds_per_unit,
    };
    let r = Counted::new(BufReader::with_capacity(1 << 20, file), 0);
    read_logger_by(r, &pass, |r, buf, rows, keeper| {
        stretches::read_stretches(r, buf, rows, keeper, resume, path)
    })
}

/// What a pass over a text file is asked: the file, how to read it, what to keep, and the time
/// column's unit (s).
struct Pass<'a> {
    path: &'a Path,
    options: &'a ImportOptions,
    keep: &'a Keep,
    seconds_per_unit: f64,
}

/// A text file read by `pass`: its header, its rows as `read` reads them, and what follows
/// from them.
fn read_logger_by<R: BufRead>(
    mut r: Counted<R>,
    pass: &Pass,
    read: impl FnOnce(
        &mut Counted<R>,
        &mut Vec<u8>,
        &Rows,
        &mut Keeper,
    ) -> Result<Recording, ImportError>,
) -> Result<Recording, ImportError> {
    let Pass {
        path,
        options,
        keep,
        seconds_per_unit,
    } = *pass;
    let mut buf = Vec::new();
    let header = read_header(&mut r, &mut buf, path, options)?;
    let header_line = header.line;
    let mut read_notes = Vec::new();
    if header.preamble > 0 {
        read_notes.push(Note::Preamble {
            lines: header.preamble,
            header_line,
            spelling: options.spelling,
        });
    }
    if header.first_row.is_some() {
        read_notes.push(Note::NoHeader { line: header_line });
    }
    if header.first_row.is_none() && rows::all_numbers(&header.names) {
        return Err(ImportError::NoHeader {
            line: header_line,
            fields: header.names.len(),
            spelling: options.spelling,
        });
    }
    let first_row = header.first_row.clone();
    let layout = Layout::new(header.names, header.sep, options)?;
    let still_var = match options.acc_unit {
        OutputUnit::MetresPerSecondSquared => STILL_VAR_M2_S4,
        OutputUnit::StandardGravity => {
            STILL_VAR_M2_S4 / (shared::STANDARD_GRAVITY_M_S2 * shared::STANDARD_GRAVITY_M_S2)
        }
        _ => 0.0,
    };
    let mut keeper = Keeper::with_still_var(keep, still_var);
    let rows = Rows {
        layout: &layout,
        options,
        header_line,
        first_row,
        seconds_per_unit,
    };
    let mut rec = read(&mut r, &mut buf, &rows, &mut keeper)?;
    read_notes.extend(rows::fill_streams(&mut rec));
    rec.read_notes = read_notes;
    if keeper.report() {
        return Ok(Recording::default());
    }
    if rec.len() < 2 {
        return Err(ImportError::NoRecording(rec.len()));
    }
    rec.gyro_lsb_per_dps = options.gyro_lsb_per_dps;
    rec.time_origin = Some(TimeOrigin::of_text(&options.time));
    if let Time::Column(_) = layout.time {
        let unit = match options.time_unit {
            Some(u) => time::fits_time_unit(&rec.t_s, u)
                .then_some(u)
                .ok_or_else(|| time::time_unit_error(&rec.t_s, Some(u), options.spelling))?,
            None => detect_time_unit(&rec.t_s, options.spelling)?,
        };
        let k = unit.seconds();
        rec.t_s.iter_mut().for_each(|t| *t *= k);
        rec.time_unit = Some((unit, options.time_unit.is_none()));
    }
    super::logs::repair_kept_rows(&mut rec, &keeper);
    super::bursts::retime_rows(&mut rec);
    rec.rate_hz = run_rate_hz(&rec.t_s);
    if options.acc_unit == OutputUnit::Lsb && options.acc_offset == [0.0; 3] {
        if let Some((offset, bits)) = mid_scale(&rec.acc) {
            return Err(ImportError::MidScale {
                offset,
                bits,
                spelling: options.spelling,
            });
        }
    }
    for v in &mut rec.acc {
        for j in 0..3 {
            v[j] -= options.acc_offset[j];
        }
    }
    rec.acc_offset = options.acc_offset;
    gravity::check_gravity(&rec, options.acc_unit, options.spelling)?;
    Ok(rec)
}

/// A note when a gyro in counts sits at an unsigned output's mid-scale on every axis and no offset
/// was given: its zero rate, read as a bias of hundreds of °/s, which no device accepts in a
/// calibration. The fit still takes it as a bias (the turns are right); the note names the offset.
pub(crate) fn gyro_mid_scale_note(rec: &Recording, options: &ImportOptions) -> Option<Note> {
    let lsb = options.gyro_lsb_per_dps?;
    if options.gyro_offset != [0.0; 3] || rec.is_empty() {
        return None;
    }
    let per_count = options.gyro_rad_s_per_unit();
    let counts: Vec<[f64; 3]> = rec
        .gyro_rad_s
        .iter()
        .map(|w| w.map(|x| x / per_count))
        .collect();
    let (m, bits) = mid_scale(&counts)?;
    Some(Note::GyroMidScale {
        mid: m,
        bits,
        bias_dps: m / lsb,
        offset: short_number(m),
        spelling: options.spelling,
    })
}

/// The mid-scale value (and bits) of an unsigned output that every sample's axes sit near: all
/// counts in `[0, 2m]` and each axis's median within `m/2` of `m`, for `m = 2^(bits−1)`, 8 to 24
/// bits. Zero-centred counts (signed) have negative values or a median near 0 on some axis.
fn mid_scale(acc: &[[f64; 3]]) -> Option<(f64, u32)> {
    let medians: [f64; 3] = core::array::from_fn(|j| {
        let mut v: Vec<f64> = acc.iter().map(|a| a[j]).collect();
        v.sort_by(f64::total_cmp);
        v[v.len() / 2]
    });
    (8..=24u32).find_map(|bits| {
        let m = f64::from(1u32 << (bits - 1));
        let inside = acc
            .iter()
            .all(|a| a.iter().all(|&x| (0.0..=2.0 * m).contains(&x)));
        let centred = medians.iter().all(|&x| (x - m).abs() < 0.5 * m);
        (inside && centred).then_some((m, bits))
    })
}

#[cfg(test)]
#[path = "import/logger_files_tests.rs"]
mod logger_files_tests;

#[cfg(test)]
mod tests {
    use super::*;

    fn read(text: &str, options: &ImportOptions) -> Result<Recording, ImportError> {
        read_logger(text.as_bytes(), Path::new("test.csv"), options)
    }

    fn rows(n: usize, f: impl Fn(usize) -> String) -> String {
        (0..n).map(|i| f(i) + "\n").collect()
    }

    #[test]
    fn columns_in_any_order_extra_ignored_time_column_g_and_rad_s() {
        let text = format!(
            "temp;gyr_z;time;acc_z;acc_y;acc_x;gyr_y;gyr_x\n{}",
            rows(200, |i| format!(
                "25.0;0.5;{};1.0;0.01;0.02;0.25;0.125",
                i as f64 * 0.01
            ))
        );
        let o = ImportOptions::new(
            TimeSource::Column("time".into()),
            OutputUnit::StandardGravity,
            GyroUnit::RadPerS,
            crate::testkit::SPELLING,
        );
        let rec = read(&text, &o).unwrap();
        assert_eq!(rec.len(), 200);
        assert_eq!(rec.acc[3], [0.02, 0.01, 1.0]);
        assert_eq!(rec.gyro_rad_s[3], [0.125, 0.25, 0.5]);
        assert!((rec.rate_hz - 100.0).abs() < 1e-6);
    }

    #[test]
    fn sample_index_and_rate_deg_s_converted() {
        let text = format!(
            "sample,acc_x,acc_y,acc_z,gyr_x,gyr_y,gyr_z\n{}",
            rows(300, |i| format!("{i},0,0,9.81,180,0,-90"))
        );
        let o = ImportOptions::new(
            TimeSource::RateHz(102.4),
            OutputUnit::MetresPerSecondSquared,
            GyroUnit::DegPerS,
            crate::testkit::SPELLING,
        );
        let rec = read(&text, &o).unwrap();
        assert_eq!(rec.t_s[102], 102.0 / 102.4);
        assert!((rec.gyro_rad_s[0][0] - std::f64::consts::PI).abs() < 1e-12);
        assert!((rec.gyro_rad_s[0][2] + std::f64::consts::FRAC_PI_2).abs() < 1e-12);
    }

    #[test]
    fn white_space_separated_text_with_comment_lines_reads_like_csv() {
        let body = |sep: &str| {
            rows(200, |i| {
                [
                    format!("{}", i as f64 * 0.01),
                    "0".into(),
                    "0".into(),
                    "9.81".into(),
                ]
                .join(sep)
                    + &format!("{sep}0{sep}0{sep}0")
            })
        };
        let o = ImportOptions::new(
            TimeSource::Column("t".into()),
            OutputUnit::MetresPerSecondSquared,
            GyroUnit::DegPerS,
            crate::testkit::SPELLING,
        );
        let csv = read(
            &format!("t,acc_x,acc_y,acc_z,gyr_x,gyr_y,gyr_z\n{}", body(",")),
            &o,
        )
        .unwrap();
        let text = format!(
            "# logger v2, 100 Hz\n#\n  t   acc_x acc_y  acc_z gyr_x gyr_y gyr_z\n# started\n{}",
            body("   ").replace("\n0.5", "\n# a note\n0.5")
        );
        let spaced = read(&text, &o).unwrap();
        assert_eq!(spaced.t_s, csv.t_s);
        assert_eq!(spaced.acc, csv.acc);
        // Line numbers count the comment lines: a bad field names its real line.
        let bad = text.replacen("9.81", "9.8x", 1);
        let e = read(&bad, &o).unwrap_err().to_string();
        assert!(e.contains("line 5"), "{e}");
    }

    #[test]
    fn a_time_column_in_ms_and_physical_units_as_counts_are_refused() {
        let text = |dt: f64, g: f64| {
            format!(
                "t,acc_x,acc_y,acc_z,gyr_x,gyr_y,gyr_z\n{}",
                rows(300, |i| format!("{},0,0,{g},0,0,0", i as f64 * dt))
            )
        };
        let o = |unit| {
            ImportOptions::new(
                TimeSource::Column("t".into()),
                unit,
                GyroUnit::DegPerS,
                crate::testkit::SPELLING,
            )
        };
        // Steps of 300 over 300 rows: 3.3 mHz in s, 3.3 Hz in ms, 0.09 s long in µs: nothing fits.
        let e = read(&text(300.0, 9.81), &o(OutputUnit::MetresPerSecondSquared)).unwrap_err();
        assert!(e.to_string().contains("in no unit"), "{e}");
        read(&text(0.005, 9.81), &o(OutputUnit::MetresPerSecondSquared)).unwrap();
        let e = read(&text(0.005, 9.81), &o(OutputUnit::Lsb))
            .unwrap_err()
            .to_string();
        assert!(
            e.contains("<AccUnit> m/s2") && e.contains("9.81 LSB:"),
            "{e}"
        );
        let e = read(&text(0.005, 1.0), &o(OutputUnit::Volts))
            .unwrap_err()
            .to_string();
        assert!(e.contains("<AccUnit> g"), "{e}");
        // Counts as counts: 4096 per g.
        read(&text(0.005, 4096.0), &o(OutputUnit::Lsb)).unwrap();
    }

    #[test]
    fn huge_numbers_in_a_file_are_printed_short() {
        let o = ImportOptions::new(
            TimeSource::Column("t".into()),
            OutputUnit::MetresPerSecondSquared,
            GyroUnit::DegPerS,
            crate::testkit::SPELLING,
        );
        let text = format!(
            "t,acc_x,acc_y,acc_z,gyr_x,gyr_y,gyr_z\n{}",
            rows(200, |i| format!("{}e299,0,0,9.81,0,0,0", i + 1))
        );
        let e = read(&text, &o).unwrap_err().to_string();
        assert!(
            e.contains("steps by a median 1e299 and spans 1.99e301"),
            "{e}"
        );
        let text = format!(
            "t,acc_x,acc_y,acc_z,gyr_x,gyr_y,gyr_z\n{}",
            rows(200, |i| format!("{},0,0,1e100,0,0,0", i as f64 * 0.01))
        );
        let e = read(&text, &o).unwrap_err().to_string();
        assert!(e.contains("median magnitude is 1e100 m/s2"), "{e}");
    }

    /// A misspelt temperature column is named with the option that asked for it, and the advice
    /// is that option's, not the accelerometer's columns or the time's.
    #[test]
    fn a_missing_temperature_column_names_its_own_option() {
        let text = format!(
            "acc_x,acc_y,acc_z,gyr_x,gyr_y,gyr_z,temp_c\n{}",
            rows(200, |_| "0,0,9.8,0,0,0,25".into())
        );
        let o = |spelling| ImportOptions {
            temp_column: Some("tmep_c".into()),
            spelling,
            ..ImportOptions::new(
                TimeSource::RateHz(100.0),
                OutputUnit::MetresPerSecondSquared,
                GyroUnit::DegPerS,
                crate::testkit::SPELLING,
            )
        };
        let m = read(&text, &o(crate::testkit::SPELLING))
            .unwrap_err()
            .to_string();
        assert!(
            m.contains("'tmep_c'") && m.contains("<TempColumn> NAME"),
            "{m}"
        );
        assert!(
            !m.contains("<Columns>") && !m.contains("<TimeColumn>"),
            "{m}"
        );
        let m = read(&text, &o(crate::testkit::KEYWORD_SPELLING))
            .unwrap_err()
            .to_string();
        assert!(
            m.contains("<TempColumn>=\"NAME\"") && !m.contains("--"),
            "{m}"
        );
    }

    #[test]
    fn bad_input_names_the_problem_and_the_fix() {
        let ms2 = ImportOptions::new(
            TimeSource::RateHz(100.0),
            OutputUnit::MetresPerSecondSquared,
            GyroUnit::DegPerS,
            crate::testkit::SPELLING,
        );
        let missing = read("acc_x,acc_y,gyr_x,gyr_y,gyr_z\n1,2,3,4,5\n", &ms2).unwrap_err();
        let m = missing.to_string();
        assert!(m.contains("'acc_z'") && m.contains("<Columns>"), "{m}");

        let g_values = format!(
            "acc_x,acc_y,acc_z,gyr_x,gyr_y,gyr_z\n{}",
            rows(200, |_| "0,0,1.0,0,0,0".into())
        );
        let m = read(&g_values, &ms2).unwrap_err().to_string();
        assert!(m.contains("<AccUnit> g"), "{m}");
        let as_g = ImportOptions {
            acc_unit: OutputUnit::StandardGravity,
            ..ms2.clone()
        };
        let ms2_values = format!(
            "acc_x,acc_y,acc_z,gyr_x,gyr_y,gyr_z\n{}",
            rows(200, |_| "0,0,9.8,0,0,0".into())
        );
        let m = read(&ms2_values, &as_g).unwrap_err().to_string();
        assert!(m.contains("<AccUnit> m/s2"), "{m}");
        let tiny = format!(
            "acc_x,acc_y,acc_z,gyr_x,gyr_y,gyr_z\n{}",
            rows(200, |_| "0,0,0.1,0,0,0".into())
        );
        assert!(matches!(
            read(&tiny, &as_g),
            Err(ImportError::UnitMismatch { .. })
        ));
        let hundred = format!(
            "acc_x,acc_y,acc_z,gyr_x,gyr_y,gyr_z\n{}",
            rows(200, |_| "0,0,100,0,0,0".into())
        );
        assert!(matches!(
            read(&hundred, &as_g),
            Err(ImportError::UnitMismatch { .. })
        ));

        let word = "acc_x,acc_y,acc_z,gyr_x,gyr_y,gyr_z\n0,0,9.8,0,zero,0\n";
        let m = read(word, &ms2).unwrap_err().to_string();
        assert!(m.contains("line 2, column 'gyr_y'"), "{m}");

        let long = format!(
            "acc_x,acc_y,acc_z,gyr_x,gyr_y,gyr_z\n{}",
            "1".repeat(70_000)
        );
        assert!(matches!(
            read(&long, &ms2),
            Err(ImportError::LineTooLong { line: 2 })
        ));
        // One overlong line among rows is a damaged line: left out, named; a hundred and one are
        // not a logger's CSV.
        let rows_around = |long_lines: usize| {
            let mut text = String::from("t,acc_x,acc_y,acc_z,gyr_x,gyr_y,gyr_z\n");
            for i in 0..300 {
                text.push_str(&format!("{},0,0,9.8,0,0,0\n", i as f64 * 0.01));
                if i >= 100 && i < 100 + long_lines {
                    text.push_str(&"9".repeat(70_000));
                    text.push('\n');
                }
            }
            text
        };
        let timed = ImportOptions::new(
            TimeSource::Column("t".into()),
            OutputUnit::MetresPerSecondSquared,
            GyroUnit::RadPerS,
            crate::testkit::SPELLING,
        );
        let rec = read(&rows_around(1), &timed).unwrap();
        assert_eq!(
            (rec.len(), rec.overlong_lines.as_slice()),
            (300, &[103u64][..])
        );
        assert!(matches!(
            read(&rows_around(MAX_OVERLONG_LINES + 1), &timed),
            Err(ImportError::OverlongLines { .. })
        ));

        let no_rate = ImportOptions {
            time: TimeSource::RateHz(0.0),
            ..ms2
        };
        assert!(matches!(
            read(&ms2_values, &no_rate),
            Err(ImportError::BadRate(..))
        ));
    }

    fn timed(unit: OutputUnit) -> ImportOptions {
        ImportOptions::new(
            TimeSource::Column("t".into()),
            unit,
            GyroUnit::DegPerS,
            crate::testkit::SPELLING,
        )
    }

    #[test]
    fn the_time_unit_is_detected_or_given_and_ambiguity_refused() {
        // 100 Hz for 20 s written in each unit: read as the same seconds.
        let text = |per_s: f64| {
            let stamp = |i: usize| match per_s {
                1.0 => format!("{}", i as f64 * 0.01),
                _ => format!("{}", i as u64 * (per_s / 100.0) as u64),
            };
            format!(
                "t,acc_x,acc_y,acc_z,gyr_x,gyr_y,gyr_z\n{}",
                rows(2000, |i| format!("{},0,0,9.81,0,0,0", stamp(i)))
            )
        };
        let o = timed(OutputUnit::MetresPerSecondSquared);
        for (per_s, unit) in [
            (1.0, TimeUnit::S),
            (1e3, TimeUnit::Ms),
            (1e6, TimeUnit::Us),
            (1e9, TimeUnit::Ns),
        ] {
            let rec = read(&text(per_s), &o).unwrap();
            assert_eq!(rec.time_unit, Some((unit, true)), "{per_s}");
            assert!(
                (rec.rate_hz - 100.0).abs() < 1e-6,
                "{per_s}: {}",
                rec.rate_hz
            );
            assert!((rec.t_s[1999] - 19.99).abs() < 1e-9);
        }
        // Given: kept, and checked.
        let given = ImportOptions {
            time_unit: Some(TimeUnit::Ms),
            ..o.clone()
        };
        assert_eq!(
            read(&text(1e3), &given).unwrap().time_unit,
            Some((TimeUnit::Ms, false))
        );
        // A unit given that fits no logger, where another does: that one named, not <RateHz>.
        let e = read(&text(1.0), &given).unwrap_err().to_string();
        assert!(
            e.contains("<TimeUnit> ms reads that as 100000 Hz")
                && e.contains("in s it reads as 100 Hz over 19.99 s: give <TimeUnit> s")
                && !e.contains("<RateHz>"),
            "{e}"
        );
        let e = read(&text(1e6), &given).unwrap_err().to_string();
        assert!(e.contains("give <TimeUnit> us"), "{e}");
        // Steps of 0.1 over 200 000 rows: 10 Hz for 5.6 h in s, or 10 kHz for 20 s in ms.
        let long = format!(
            "t,acc_x,acc_y,acc_z,gyr_x,gyr_y,gyr_z\n{}",
            rows(200_000, |i| format!("{},0,0,9.81,0,0,0", i as f64 * 0.1))
        );
        let e = read(&long, &o).unwrap_err().to_string();
        assert!(
            e.contains("in s or 10000 Hz") && e.contains("<TimeUnit>"),
            "{e}"
        );
        let as_ms = ImportOptions {
            time_unit: Some(TimeUnit::Ms),
            ..o
        };
        assert!((read(&long, &as_ms).unwrap().rate_hz - 1e4).abs() < 1e-3);
    }

    #[test]
    fn gaps_are_kept_and_repeats_and_steps_back_repaired_with_their_place() {
        let mut t: Vec<f64> = (0..300).map(|i| i as f64 * 0.01).collect();
        t[100] = t[99]; // a repeated stamp on a row of its own values, after data row 100
        for x in &mut t[200..] {
            *x += 3.0; // a gap of 3 s after data row 200
        }
        t[250] -= 1.0; // an isolated step back at data row 251
        let mut rows: Vec<String> = t
            .iter()
            .enumerate()
            .map(|(i, x)| format!("{x},{},0,9.81,0,0,0\n", i as f64 * 1e-3))
            .collect();
        rows.insert(150, rows[149].clone()); // an exact repeat: data row 151
        let text = format!("t,acc_x,acc_y,acc_z,gyr_x,gyr_y,gyr_z\n{}", rows.concat());
        let rec = read(&text, &timed(OutputUnit::MetresPerSecondSquared)).unwrap();
        assert_eq!(rec.len(), 300);
        assert!(rec.t_s.windows(2).all(|w| w[1] > w[0]));
        let rows: Vec<usize> = rec.jumps().iter().map(|j| j.row).collect();
        assert_eq!(rows, [199]);
        let w = rec.time_jumps().unwrap();
        assert!(
            w.to_string().contains("gap of +3.010 s after data row 200"),
            "{w}"
        );
        let (what, r) = &rec.time_repairs[0];
        assert_eq!(*what, "data row");
        assert_eq!(r.spread, [100]);
        assert_eq!(r.repeats, [150]);
        assert_eq!(r.retimed.len(), 1);
        assert_eq!(r.retimed[0].0, 251);
        assert!((r.retimed[0].2 - 5.5).abs() < 1e-9, "{:?}", r.retimed);
        let said = r.describe(what).unwrap();
        assert!(
            said.contains("data row 252 stamped 4.500000 s, re-timed to 5.500000 s")
                && said
                    .contains("exact repeat(s) (same stamp, same values) left out (data row 151)")
                && said.contains("data row 101"),
            "{said}"
        );
        assert!(Recording::continuous(&rec.jumps(), 100, 200));
        assert!(!Recording::continuous(&rec.jumps(), 150, 201));
    }

    #[test]
    fn counts_at_mid_scale_name_the_offset_and_the_offset_and_gyro_counts_are_applied() {
        // 16-bit unsigned, 8192 counts per g about 32768; a gyro at 16.4 LSB per °/s.
        let text = format!(
            "t,acc_x,acc_y,acc_z,gyr_x,gyr_y,gyr_z\n{}",
            rows(300, |i| format!(
                "{},32790,32700,{},164,-82,0",
                i as f64 * 0.01,
                32768 + 8192
            ))
        );
        let lsb = timed(OutputUnit::Lsb);
        let e = read(&text, &lsb).unwrap_err().to_string();
        assert!(
            e.contains("near 32768 counts")
                && e.contains("16-bit")
                && e.contains("<AccOffset> 32768"),
            "{e}"
        );
        let counts = ImportOptions {
            acc_offset: [32768.0; 3],
            gyro_lsb_per_dps: Some(16.4),
            ..lsb.clone()
        };
        let rec = read(&text, &counts).unwrap();
        assert_eq!(rec.acc[0], [22.0, -68.0, 8192.0]);
        assert_eq!(rec.acc_offset, [32768.0; 3]);
        assert!((rec.gyro_rad_s[0][0] - 10f64.to_radians()).abs() < 1e-12);
        assert!((rec.gyro_rad_s[0][1] + 5f64.to_radians()).abs() < 1e-12);
        // Signed counts are not at mid-scale: no hint, read as given.
        let signed = text.replace(",32790,32700,40960,", ",22,-68,8192,");
        assert_eq!(read(&signed, &lsb).unwrap().acc[0], [22.0, -68.0, 8192.0]);
    }
}
