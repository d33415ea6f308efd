//! The logs people have, read into one [`Recording`] (time in s, the accelerometer in m/s², the gyro
//! in rad/s, the unit's temperature where the log has it): a logger's text file (CSV, tab- or
//! white-space separated, [`super::import`]), a PX4 ULog ([`ulog`]), an ArduPilot DataFlash log
//! ([`dataflash`]) and a ROS 2 bag in MCAP ([`mcap`]). The format is told by the file's first bytes,
//! not its name: a renamed `.bin` or a `.log` that is really a ULog reads the same.
//!
//! Every reader streams the file, and every length field is bounded before anything is allocated
//! for it. What a reader keeps is bounded too: a log of more samples than the budget is read
//! again, and only its quiet stretches and the turns between them are kept (`keep`), so that
//! the memory needed does not grow with the file. A binary log's samples can be re-timed at a
//! given rate (`retime`).

mod ardupilot;
pub mod dataflash;
mod error;
pub(crate) mod keep;
pub mod mcap;
pub(crate) mod resume;
mod retime;
mod stream;
pub mod ulog;
pub mod vehicle;
mod windows;

pub use ardupilot::UndoError;
pub use error::{ForeignFormat, ImuError, LogError};
use keep::{Keep, Keeper, PassReport};
pub use keep::{DEFAULT_MAX_SAMPLES, MAX_BLOCKS, MAX_MOVE_S};
pub(crate) use stream::{pair, pair_streams, Stream, StreamAt, StreamSample, TooMany};
pub(crate) use windows::MARGIN_PERIODS;
pub use windows::{read_log_windows, LogRead, LogScale, LogWindows, Window};

use super::import::{
    gyro_mid_scale_note, read_logger_keeping, read_logger_window, ImportError, ImportOptions,
    Recording, TimeOrigin, MIN_SESSION_ROWS,
};
use super::note::Note;
use super::repair::repair_rows_saying;
use crate::spelling::{Spelling, UserOption};
use std::fs::File;
use std::io::{BufRead, BufReader, Read};
use std::path::Path;
use std::sync::{Arc, Mutex};

/// What to take from a log: the text reader's columns, time and units (text files only), the IMU
/// instance (ULog's `multi_id`, DataFlash's `I`) and the MCAP topic. The default reads a binary log
/// as it states itself: its first IMU, its only Imu topic, its own stamps. It has a default only in
/// tests (feature `testkit`, with the neutral test spelling): a caller gives its own spelling.
#[derive(Clone, Debug, PartialEq)]
#[cfg_attr(any(test, feature = "testkit"), derive(Default))]
pub struct LogSource {
    /// How to read a text file; `None`: the log must be a binary format that states its units.
    pub text: Option<ImportOptions>,
    /// Which IMU of a vehicle with several (default: the first, instance 0).
    pub instance: Option<u8>,
    /// The MCAP topic with the `sensor_msgs/msg/Imu` messages (default: the only one).
    pub topic: Option<String>,
    /// How the caller names these options in messages.
    pub spelling: Spelling,
    /// A binary log's samples re-timed at this rate, Hz (`--rate-hz`): each stream's n-th sample
    /// at its first stamp plus n periods, for a logger whose stamps are the host's (a ROS driver's
    /// bursts) rather than the sensor's. A text file's rate is its [`ImportOptions`]'s.
    pub rate_hz: Option<f64>,
}

impl LogSource {
    /// A binary log read as its format states it (its first IMU, its only topic, its own stamps),
    /// its options named in the caller's `spelling`.
    pub fn new(spelling: Spelling) -> LogSource {
        LogSource {
            text: None,
            instance: None,
            topic: None,
            spelling,
            rate_hz: None,
        }
    }
}

/// The formats read.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum LogFormat {
    /// A logger's text file (CSV or white-space separated).
    Text,
    /// PX4 ULog.
    Ulog,
    /// ArduPilot DataFlash (`.bin`).
    DataFlash,
    /// MCAP (a ROS 2 bag).
    Mcap,
}

impl LogFormat {
    /// The name people know the format by.
    pub fn name(self) -> &'static str {
        match self {
            LogFormat::Text => "text",
            LogFormat::Ulog => "PX4 ULog",
            LogFormat::DataFlash => "ArduPilot DataFlash",
            LogFormat::Mcap => "MCAP",
        }
    }

    /// The format whose magic bytes start `head` (text when none does: the text reader then says
    /// what is wrong with it).
    pub fn detect(head: &[u8]) -> LogFormat {
        if head.starts_with(&ulog::MAGIC) {
            LogFormat::Ulog
        } else if head.starts_with(&dataflash::MAGIC) {
            LogFormat::DataFlash
        } else if head.starts_with(&mcap::MAGIC) {
            LogFormat::Mcap
        } else {
            LogFormat::Text
        }
    }
}

/// A log read: the recording, its format and what the reader noticed on the way (dropouts,
/// damaged bytes skipped), for the user.
#[derive(Clone, Debug)]
pub struct LogFile {
    /// The samples.
    pub recording: Recording,
    /// The file's format.
    pub format: LogFormat,
    /// What to tell the user, said with `Display`.
    pub warnings: Vec<Note>,
}

/// Reads the whole log at `path` in whatever format its first bytes say (see the module docs), up
/// to [`MAX_ROWS`](super::import::MAX_ROWS) samples per stream, refusing a longer one. A use that
/// needs every sample of a log of any length reads it with [`read_log_windows`] (`apply`); one
/// that needs its still stretches, with [`read_log_within`] (`segment`, `noise`).
pub fn read_log(path: &Path, source: &LogSource) -> Result<LogFile, LogError> {
    read_pass(path, source, &Keep::default(), 1.0)
}

/// [`read_log`] keeping at most `max_samples` samples per stream: a longer log is surveyed and only
/// its quiet stretches and the turns between them are kept (`keep`), the first `max_samples` of
/// them; a warning says what was left out.
///
/// It reads a hand-held session: fewer than `MIN_SESSION_ROWS` samples are refused for it.
pub fn read_log_keeping(
    path: &Path,
    source: &LogSource,
    max_samples: usize,
) -> Result<LogFile, LogError> {
    let log = read_log_within(path, source, max_samples, Some(UserOption::MaxSamples))?;
    let rows = log.recording.len();
    match log.format {
        _ if rows >= MIN_SESSION_ROWS => Ok(log),
        LogFormat::Text => Err(LogError::Text(ImportError::TooFewRows(rows))),
        _ => Err(LogError::TooFewSamples {
            path: path.to_path_buf(),
            rows,
        }),
    }
}

/// [`read_log_keeping`] for a caller whose budget the user sets with `option`, or cannot set
/// (`None`: the warning then names no option).
pub fn read_log_within(
    path: &Path,
    source: &LogSource,
    max_samples: usize,
    option: Option<UserOption>,
) -> Result<LogFile, LogError> {
    let max = max_samples.max(1);
    let (seconds_per_unit, over) = match first_pass(path, source, max)? {
        FirstPass::Whole(log) => return Ok(*log),
        FirstPass::Over {
            seconds_per_unit,
            error,
        } => (seconds_per_unit, error),
    };
    let report = Arc::new(Mutex::new(PassReport::default()));
    let survey = Keep::Survey(Arc::clone(&report));
    read_pass(path, source, &survey, seconds_per_unit)?;
    let regions = report.lock().ok().and_then(|mut r| r.regions.take());
    let Some(regions) = regions else {
        return Err(over);
    };
    let n_regions = regions.len();
    let keep = Keep::Within {
        regions: regions.into(),
        max,
        report: Arc::clone(&report),
    };
    let mut log = read_pass(path, source, &keep, seconds_per_unit)?;
    let left_out = report.lock().ok().and_then(|r| r.left_out);
    if let Some(l) = left_out {
        log.warnings.extend(keep::left_out_note(
            &l,
            max,
            n_regions,
            option,
            source.spelling,
        ));
    }
    Ok(log)
}

/// What the first pass of a log read within a budget found.
pub(super) enum FirstPass {
    /// The log, within the budget (boxed: the other variant is a fraction of its size).
    Whole(Box<LogFile>),
    /// More than the budget: its time stamps' unit, s (a text file's, told from the rows read).
    Over {
        /// Seconds per unit of the time stamps.
        seconds_per_unit: f64,
        /// The budget's refusal, for a caller that cannot read the log otherwise.
        error: LogError,
    },
}

/// The first pass of a read within `max` samples per stream: the whole log, or that it holds more.
pub(super) fn first_pass(
    path: &Path,
    source: &LogSource,
    max: usize,
) -> Result<FirstPass, LogError> {
    match read_pass(path, source, &Keep::All { max }, 1.0) {
        Ok(log) => Ok(FirstPass::Whole(Box::new(log))),
        Err(e) => match e.over_budget(source) {
            Some(seconds_per_unit) => Ok(FirstPass::Over {
                seconds_per_unit,
                error: e,
            }),
            None => Err(e),
        },
    }
}

/// One pass over the file at `path` (a text file's time column in `seconds_per_unit`).
fn read_pass(
    path: &Path,
    source: &LogSource,
    keep: &Keep,
    seconds_per_unit: f64,
) -> Result<LogFile, LogError> {
    let io = |e| LogError::Io {
        path: path.to_path_buf(),
        source: e,
    };
    let file = File::open(path).map_err(io)?;
    let mut r = BufReader::with_capacity(1 << 20, file);
    let head = r.fill_buf().map_err(io)?.to_vec();
    read_keeping(r, &head, path, source, keep, seconds_per_unit)
}

/// [`read_log`] on any reader whose first bytes are `head` (`path` only names it in messages).
pub fn read_log_from<R: BufRead>(
    r: R,
    head: &[u8],
    path: &Path,
    source: &LogSource,
) -> Result<LogFile, LogError> {
    read_keeping(r, head, path, source, &Keep::default(), 1.0)
}

/// The options that do not apply to a file of `format` (text options on a binary log, an instance
/// or a topic where the format has none), and a text file that is binary after all.
fn refuse_options(
    format: LogFormat,
    head: &[u8],
    path: &Path,
    source: &LogSource,
) -> Result<(), LogError> {
    let sp = source.spelling;
    let p = || path.to_path_buf();
    let not_for = |option| LogError::OptionNotForFormat {
        path: p(),
        format,
        option: sp.name(option),
    };
    if format != LogFormat::Text && source.text.is_some() {
        return Err(LogError::TextOptionOnBinary {
            path: p(),
            format,
            option: format!(
                "{}, {} and {}",
                sp.name(UserOption::AccUnit),
                sp.name(UserOption::GyroUnit),
                sp.name(UserOption::TimeColumn),
            ),
        });
    }
    let (instance, topic) = match format {
        LogFormat::Text => (false, false),
        LogFormat::Ulog | LogFormat::DataFlash => (true, false),
        LogFormat::Mcap => (false, true),
    };
    if source.instance.is_some() && !instance {
        return Err(not_for(UserOption::Instance));
    }
    if source.topic.is_some() && !topic {
        return Err(not_for(UserOption::Topic));
    }
    // A NUL byte early on: no text file, and none of the binary formats either.
    if format == LogFormat::Text && head.iter().take(4096).any(|&b| b == 0) {
        let advice = error::ForeignFormat::of(head);
        let head = head.iter().take(8).map(|b| format!("{b:02x}")).collect();
        return Err(LogError::UnknownFormat {
            path: p(),
            head,
            advice,
        });
    }
    Ok(())
}

/// [`read_log_from`], each stream keeping what `keep` says.
fn read_keeping<R: BufRead>(
    r: R,
    head: &[u8],
    path: &Path,
    source: &LogSource,
    keep: &Keep,
    seconds_per_unit: f64,
) -> Result<LogFile, LogError> {
    let format = LogFormat::detect(head);
    let sp = source.spelling;
    let p = || path.to_path_buf();
    refuse_options(format, head, path, source)?;
    let (recording, warnings) = match format {
        LogFormat::Text => {
            let options = source
                .text
                .as_ref()
                .ok_or_else(|| LogError::TextNeedsOptions(p(), sp))?;
            let mut rec = read_logger_keeping(r, path, options, keep, seconds_per_unit)?;
            let mut notes = match keep.own() {
                // A window says its temperatures on the log's scale (`windows`).
                None => temperature_notes(&mut rec),
                Some(_) => Vec::new(),
            };
            notes.extend(gyro_mid_scale_note(&rec, options));
            (rec, notes)
        }
        LogFormat::Ulog => {
            let instance = source.instance.unwrap_or(0);
            let imu = ulog::read_keeping(r, instance, keep, source.rate_hz).map_err(|e| {
                LogError::Ulog {
                    path: p(),
                    source: e.spelled(sp),
                }
            })?;
            (imu.0, imu.1)
        }
        LogFormat::DataFlash => {
            let instance = source.instance.unwrap_or(0);
            let read = dataflash::read_with_params(r, instance, keep, source.rate_hz);
            dataflash_undone(read, instance, path, sp)?
        }
        LogFormat::Mcap => {
            let topic = source.topic.as_deref();
            let imu =
                mcap::read_keeping(r, topic, keep, source.rate_hz).map_err(|e| LogError::Mcap {
                    path: p(),
                    source: e.spelled(sp),
                })?;
            (imu.0, imu.1)
        }
    };
    log_file(recording, warnings, format, keep, path)
}

/// A DataFlash log's samples and notes read, the vehicle's own corrections undone.
fn dataflash_undone(
    read: Result<(Recording, Vec<Note>, vehicle::VehicleParams), dataflash::DataFlashError>,
    instance: u8,
    path: &Path,
    sp: Spelling,
) -> Result<(Recording, Vec<Note>), LogError> {
    let p = || path.to_path_buf();
    let (mut rec, mut notes, params) = read.map_err(|e| LogError::DataFlash {
        path: p(),
        source: e.spelled(sp),
    })?;
    let undone = ardupilot::undo(&mut rec, &params, instance)
        .map_err(|source| LogError::NotUndone { path: p(), source })?;
    notes.extend(undone);
    Ok((rec, notes))
}

/// A pass's recording of a binary log stamped by its logger, or its refusal when it kept fewer
/// than two samples.
fn log_file(
    mut recording: Recording,
    warnings: Vec<Note>,
    format: LogFormat,
    keep: &Keep,
    path: &Path,
) -> Result<LogFile, LogError> {
    if format != LogFormat::Text {
        recording.time_origin = Some(TimeOrigin::LoggerStamps(format.name()));
    }
    if recording.len() < 2 && !matches!(keep, Keep::Survey(_)) {
        return Err(LogError::NoRecording {
            path: path.to_path_buf(),
            rows: recording.len(),
        });
    }
    Ok(LogFile {
        recording,
        format,
        warnings,
    })
}

/// One window's pass (`keep`, a [`Keep::Span`]) over the file at `path`, reading only the
/// stretches the survey's `resume` marks for its times (`resume`): the same as [`read_pass`].
fn resume_pass(
    path: &Path,
    source: &LogSource,
    resume: &resume::Resume,
    keep: &Keep,
    seconds_per_unit: f64,
) -> Result<LogFile, LogError> {
    let io = |e| LogError::Io {
        path: path.to_path_buf(),
        source: e,
    };
    let mut file = File::open(path).map_err(io)?;
    let sp = source.spelling;
    let (format, (recording, warnings)) = match resume {
        resume::Resume::Ulog(r) => {
            let instance = source.instance.unwrap_or(0);
            let read = ulog::read_window(&mut file, r, instance, keep, source.rate_hz);
            let read = read.map_err(|e| LogError::Ulog {
                path: path.to_path_buf(),
                source: e.spelled(sp),
            })?;
            (LogFormat::Ulog, read)
        }
        resume::Resume::Text(r) => {
            let options = source
                .text
                .as_ref()
                .ok_or_else(|| LogError::TextNeedsOptions(path.to_path_buf(), sp))?;
            let rec = read_logger_window(&mut file, path, options, keep, seconds_per_unit, r)?;
            // A window says its temperatures on the log's scale (`windows`).
            let notes = gyro_mid_scale_note(&rec, options).into_iter().collect();
            (LogFormat::Text, (rec, notes))
        }
        resume::Resume::Mcap(r) => {
            let topic = source.topic.as_deref();
            let read = mcap::read_window(&mut file, r, topic, keep, source.rate_hz);
            let read = read.map_err(|e| LogError::Mcap {
                path: path.to_path_buf(),
                source: e.spelled(sp),
            })?;
            (LogFormat::Mcap, read)
        }
        resume::Resume::DataFlash(r) => {
            let instance = source.instance.unwrap_or(0);
            let read = dataflash::read_window(&mut file, r, instance, keep, source.rate_hz);
            (
                LogFormat::DataFlash,
                dataflash_undone(read, instance, path, sp)?,
            )
        }
    };
    log_file(recording, warnings, format, keep, path)
}

/// The accelerometer samples left out for want of a gyro sample within `max_gap_s`, said.
pub(crate) fn unpaired_note(unpaired: usize, max_gap_s: f64) -> Option<Note> {
    (unpaired > 0).then_some(Note::Unpaired {
        count: unpaired,
        max_gap_s,
    })
}

/// What the user is told of a text recording read with `options` (a file's or arrays'): its
/// temperature readings (`temperature_notes`) and a gyro in counts at an unsigned output's
/// mid-scale with no offset given.
pub fn text_notes(rec: &mut Recording, options: &ImportOptions) -> Vec<Note> {
    let mut notes = temperature_notes(rec);
    notes.extend(gyro_mid_scale_note(rec, options));
    notes
}

/// What the user is told of a recording's temperature readings, the same for every format: none at
/// all (a driver without a temperature sensor: the recording is then read as one without
/// temperature), or some missing (those rows are kept; only the readings enter the temperature
/// statistics, docs/model.md §9).
pub(crate) fn temperature_notes(rec: &mut Recording) -> Vec<Note> {
    let Some(temps) = &rec.temp_c else {
        return Vec::new();
    };
    let (readings, rows) = (temps.iter().filter(|t| t.is_finite()).count(), temps.len());
    if readings == 0 {
        rec.temp_c = None;
    }
    temperature_note(readings, rows).into_iter().collect()
}

/// [`temperature_notes`] of `readings` temperature readings in `rows` rows.
pub(crate) fn temperature_note(readings: usize, rows: usize) -> Option<Note> {
    if readings == 0 {
        return Some(Note::NoTemperature);
    }
    (readings < rows).then_some(Note::SomeWithoutTemperature {
        missing: rows - readings,
        rows,
    })
}

/// [`repair_rows`](crate::session::repair::repair_rows) of a text file's rows kept by `keeper`;
/// a window's repairs said on the log's scale (`windows::own_repairs`).
pub(crate) fn repair_kept_rows(rec: &mut Recording, keeper: &Keeper) {
    repair_rows_saying(rec, |order, t_s, rep| match keeper.keep().own() {
        Some(own) => windows::own_repairs(rep, order, t_s, keeper.places(), own),
        None => rep,
    });
}

/// "NAME instance I, …" of the IMU messages or topics a log has, or `none` when it has none.
pub(crate) fn list_instances<'a>(seen: impl Iterator<Item = (&'a str, u8)>, none: &str) -> String {
    let found: Vec<String> = seen.map(|(n, i)| format!("{n} instance {i}")).collect();
    if found.is_empty() {
        none.to_string()
    } else {
        found.join(", ")
    }
}

/// Reads exactly `buf.len()` bytes, `Ok(false)` at a clean end of input (no byte read).
pub(crate) fn read_exact_or_end<R: Read>(r: &mut R, buf: &mut [u8]) -> std::io::Result<bool> {
    let mut got = 0;
    while got < buf.len() {
        match r.read(&mut buf[got..]) {
            Ok(0) if got == 0 => return Ok(false),
            Ok(0) => return Err(std::io::ErrorKind::UnexpectedEof.into()),
            Ok(n) => got += n,
            Err(e) if e.kind() == std::io::ErrorKind::Interrupted => {}
            Err(e) => return Err(e),
        }
    }
    Ok(true)
}

#[cfg(test)]
mod tests;
