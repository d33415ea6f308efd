//! Why a session cannot be read or written.

use super::plan::{PlanError, RecordingVersion};
use super::{COLUMNS_TEMPERATURE, PLAN_FILE, SAMPLES_HEADER};
use std::path::PathBuf;

/// Why a session cannot be read or written. Every message names the file, the place and the fix.
#[derive(Debug, thiserror::Error)]
pub enum RecordingError {
    /// `plan.toml` is missing or unusable.
    #[error(transparent)]
    Plan(#[from] PlanError),
    /// An I/O failure on `path`.
    #[error("{}", .path.display())]
    Io {
        /// The file.
        path: PathBuf,
        /// What failed.
        source: std::io::Error,
    },
    /// The first line is not the header of the plan's version.
    #[error(fmt = header_message)]
    Header {
        /// The file.
        path: PathBuf,
        /// The line found.
        found: String,
        /// 1-based column of the first difference.
        column: usize,
        /// The plan's recording version, whose header was expected.
        version: RecordingVersion,
    },
    /// A row without exactly the plan's version's number of fields (eight, or nine with `temp_c`).
    #[error(
        "{} line {line}: {found} fields, expected {} ({}); fix or delete the line",
        .path.display(),
        .version.samples_header().split(',').count(),
        .version.samples_header()
    )]
    FieldCount {
        /// The file.
        path: PathBuf,
        /// 1-based line number.
        line: u64,
        /// Fields found.
        found: usize,
        /// The plan's recording version.
        version: RecordingVersion,
    },
    /// A field that is not a number (NaN and inf are numbers: those rows are counted and left out).
    #[error(
        "{} line {line}, column {column} ({}): '{text}' is not a number; \
         fix the value or write NaN to have the row left out",
        .path.display(),
        COLUMNS_TEMPERATURE
            .get(.column.wrapping_sub(1))
            .copied()
            .unwrap_or("?")
    )]
    Number {
        /// The file.
        path: PathBuf,
        /// 1-based line number.
        line: u64,
        /// 1-based column number.
        column: usize,
        /// The text found (shortened).
        text: String,
    },
    /// A line longer than [`crate::limits::MAX_LINE_BYTES`] (not a recording, or a damaged one).
    #[error(
        "{} line {line} is longer than {} bytes without a line end: this is not a recording \
         ({SAMPLES_HEADER}, one row per line); check the file",
        .path.display(),
        crate::limits::MAX_LINE_BYTES
    )]
    LineTooLong {
        /// The file.
        path: PathBuf,
        /// 1-based line number.
        line: u64,
    },
    /// Bytes that are not UTF-8 text.
    #[error(
        "{} line {line} has bytes that are not UTF-8 text: the file is damaged or is not a \
         recording; check the file",
        .path.display()
    )]
    NotText {
        /// The file.
        path: PathBuf,
        /// 1-based line number.
        line: u64,
    },
    /// A row names a segment the plan does not have.
    #[error(
        "{} line {line}: segment '{name}' is not in {PLAN_FILE}; add a [[segment]] with \
         name = \"{name}\" to the plan, or remove its rows",
        .path.display()
    )]
    UnknownSegment {
        /// The file.
        path: PathBuf,
        /// 1-based line number of its first row.
        line: u64,
        /// The segment name.
        name: String,
    },
    /// The file has a header but no usable row.
    #[error(
        "{} has no data rows after its header: nothing to calibrate from",
        .0.display()
    )]
    NoRows(PathBuf),
    /// The last line has no line end: the recording (or its copy) was cut short.
    #[error(
        "{} line {line} has no line end: the recording (or its copy) was cut short, so its \
         last row may be wrong and rows may be missing; record or copy it again (or, if \
         every segment is complete, delete that line)",
        .path.display()
    )]
    CutShort {
        /// The file.
        path: PathBuf,
        /// 1-based number of the unfinished line.
        line: u64,
    },
    /// The time stamps step at another rate than the plan's `sample_rate_hz`.
    #[error(
        "{}: the time stamps of segment '{segment}' step at {} Hz, the plan's \
         sample_rate_hz is {} Hz: the time column is in another unit or scale, or the plan's \
         rate is wrong; fix whichever is wrong",
        .path.display(),
        rate_text(*.stamps_hz),
        rate_text(*.plan_hz)
    )]
    TimeBase {
        /// The file.
        path: PathBuf,
        /// The segment whose stamps disagree.
        segment: String,
        /// Rate implied by its stamps, Hz.
        stamps_hz: f64,
        /// The plan's rate, Hz.
        plan_hz: f64,
    },
    /// [`super::SessionWriter`] was asked for a segment the plan does not have.
    #[error(
        "cannot record segment '{0}': it is not in the session's plan; add it to the plan first"
    )]
    WriterSegment(String),
    /// A row written with (or without) a temperature to a recording whose plan says otherwise.
    #[error(fmt = writer_temperature_message)]
    WriterTemperature {
        /// The plan's recording version, which has `temp_c` or not.
        version: RecordingVersion,
    },
    /// [`super::SessionWriter::create`] would overwrite an existing recording.
    #[error(
        "{} already exists; choose another directory or allow overwriting (--force)",
        .0.display()
    )]
    Exists(PathBuf),
}

/// [`RecordingError::WriterTemperature`]'s message: what the plan's version asks for.
fn writer_temperature_message(
    version: &RecordingVersion,
    f: &mut std::fmt::Formatter<'_>,
) -> std::fmt::Result {
    if version.has_temperature() {
        write!(
            f,
            "this recording's plan has format_version = {version}: every row needs the unit's \
             temperature"
        )
    } else {
        write!(
            f,
            "this recording's plan has format_version = {version}, which holds no temperature: \
             set format_version = {} to record temp_c",
            RecordingVersion::V3Temperature
        )
    }
}

/// [`RecordingError::Header`]'s message: the header the plan's version expects and, when the file
/// looks like the other version, the plan change that would read it.
fn header_message(
    path: &std::path::Path,
    found: &str,
    column: &usize,
    version: &RecordingVersion,
    f: &mut std::fmt::Formatter<'_>,
) -> std::fmt::Result {
    write!(
        f,
        "{} line 1, column {column}: the header is '{}' but must be exactly '{}' (recording format \
         {version}, from {PLAN_FILE}'s format_version); fix the first line",
        path.display(),
        shorten(found),
        version.samples_header(),
    )?;
    match (version.has_temperature(), found.ends_with(",temp_c")) {
        (false, true) => write!(
            f,
            ", or set format_version = {} in the plan to read temp_c",
            RecordingVersion::V3Temperature
        ),
        (true, false) => write!(
            f,
            ", or set format_version = {} in the plan (no temperature)",
            RecordingVersion::V2Attitudes
        ),
        _ => Ok(()),
    }
}

/// A field as quoted in a message: at most 60 characters.
pub(crate) fn shorten(s: &str) -> String {
    if s.chars().count() > 60 {
        format!("{}…", s.chars().take(60).collect::<String>())
    } else {
        s.to_string()
    }
}

/// A rate in a message: three decimals within the range a recording has, else
/// [`crate::limits::short_number`] (never a 300-digit number).
fn rate_text(hz: f64) -> String {
    if (1e-3..1e6).contains(&hz.abs()) {
        format!("{hz:.3}")
    } else {
        crate::limits::short_number(hz)
    }
}
