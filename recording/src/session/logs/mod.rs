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
mod retime;
pub mod ulog;
pub mod vehicle;
mod windows;

pub use ardupilot::UndoError;
pub use error::{ForeignFormat, ImuError, LogError};
use keep::{Admit, Keep, Keeper, PassReport};
pub use keep::{DEFAULT_MAX_SAMPLES, MAX_BLOCKS, MAX_MOVE_S};
use retime::{retime_note, Retime};
pub use windows::{read_log_windows, LogRead, LogScale, LogWindows, Window};

use super::import::{
    gyro_mid_scale_note, read_logger_keeping, ImportError, ImportOptions, Recording, TimeOrigin,
    GAP_PERIODS, MIN_SESSION_ROWS,
};
use super::repair::{median_step, repair_rows_saying, repair_times, run_rate_hz, TimeRepairs};
use crate::spelling::{Spelling, UserOption};
use shared::OutputUnit;
use std::fs::File;
use std::io::{BufRead, BufReader, Read};
use std::path::Path;
use std::sync::{Arc, Mutex};

/// What to take from a log: the text reader's columns, time and units (text files only), the IMU
/// instance (ULog's `multi_id`, DataFlash's `I`) and the MCAP topic.
#[derive(Clone, Debug, PartialEq)]
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
    /// What to tell the user.
    pub warnings: Vec<String>,
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
            let (mut rec, mut notes, params) =
                dataflash::read_with_params(r, instance, keep, source.rate_hz).map_err(|e| {
                    LogError::DataFlash {
                        path: p(),
                        source: e.spelled(sp),
                    }
                })?;
            let undone = ardupilot::undo(&mut rec, &params, instance)
                .map_err(|source| LogError::NotUndone { path: p(), source })?;
            notes.extend(undone);
            (rec, notes)
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
    let mut recording = recording;
    if format != LogFormat::Text {
        recording.time_origin = Some(TimeOrigin::LoggerStamps(format.name()));
    }
    if recording.len() < 2 && !matches!(keep, Keep::Survey(_)) {
        return Err(LogError::NoRecording {
            path: p(),
            rows: recording.len(),
        });
    }
    Ok(LogFile {
        recording,
        format,
        warnings,
    })
}

/// One IMU stream sample as a binary log holds it: time s, x y z, and the temperature if logged.
#[derive(Clone, Copy, Debug, PartialEq)]
pub(crate) struct StreamSample {
    pub t_s: f64,
    pub v: [f64; 3],
    pub temp_c: Option<f64>,
}

/// Collects one stream's samples as its [`Keep`] says.
#[derive(Debug, Default)]
pub(crate) struct Stream {
    pub samples: Vec<StreamSample>,
    /// Samples left out for a value that is not finite.
    pub non_finite: usize,
    keeper: Keeper,
    /// Each sample re-timed at a given rate ([`LogSource::rate_hz`]).
    retime: Option<Retime>,
}

/// More samples than the stream's budget ([`Keep::All`]), which is given.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub(crate) struct TooMany(pub usize);

impl Stream {
    /// An empty stream that keeps what `keep` says.
    pub fn new(keep: &Keep) -> Stream {
        Stream {
            keeper: Keeper::new(keep),
            ..Stream::default()
        }
    }

    /// Re-times every sample from now on at `rate_hz` (none: the stamps as they are).
    pub fn retime(&mut self, rate_hz: Option<f64>) {
        self.retime = rate_hz.map(Retime::new);
    }

    /// The given rate and the rate the stamps imply, when re-timed.
    pub fn rates_hz(&self) -> Option<(f64, Option<f64>)> {
        self.retime
            .as_ref()
            .map(|r| (r.rate_hz, r.implied_rate_hz()))
    }

    pub fn push(&mut self, mut s: StreamSample) -> Result<(), TooMany> {
        if let Some(r) = self.retime.as_mut() {
            s.t_s = r.next(s.t_s);
        }
        if !(s.t_s.is_finite() && s.v.iter().all(|x| x.is_finite())) {
            self.non_finite += 1;
            return Ok(());
        }
        let admit = self.keeper.admit(s.t_s, &s.v, self.samples.len());
        if let Some(t) = s.temp_c {
            self.keeper.temperature(t);
        }
        match admit {
            Admit::Keep => self.samples.push(s),
            Admit::Pass => {}
            Admit::TooMany(max) => return Err(TooMany(max)),
        }
        Ok(())
    }

    /// The finite samples read, whether kept or not.
    pub fn count(&self) -> usize {
        self.keeper.count()
    }
}

/// The accelerometer's samples with the gyro's rate at their times (linear interpolation between
/// the gyro's two neighbouring samples; an accelerometer sample outside the gyro's time span, or
/// further than `max_gap_s` from a gyro sample on either side, is left out). Logs with one message
/// for both (ULog's `sensor_combined`, DataFlash's `IMU`) give the two streams the same times, and
/// the interpolation returns the gyro sample itself. Each stream's time stamps are first mended by
/// [`repair`](crate::session::repair)'s rules, so that a damaged stamp costs at most its sample.
/// The streams are consumed, each dropped once mended, so that no more than one copy of a
/// stream is held at a time (`keep`).
pub(crate) fn pair(mut acc: Stream, mut gyro: Stream, max_gap_s: f64) -> (Recording, Vec<String>) {
    if acc.keeper.report() {
        return (Recording::default(), Vec::new());
    }
    let (acc_s, acc_rep) = repaired(std::mem::take(&mut acc.samples), &acc.keeper);
    let (g, gyro_rep) = repaired(std::mem::take(&mut gyro.samples), &gyro.keeper);
    let own = acc.keeper.keep().own();
    let n = acc_s.len();
    let mut rec = Recording {
        acc_unit: Some(OutputUnit::MetresPerSecondSquared),
        t_s: Vec::with_capacity(n),
        acc: Vec::with_capacity(n),
        gyro_rad_s: Vec::with_capacity(n),
        ..Recording::default()
    };
    let with_temp = acc_s.iter().any(|s| s.temp_c.is_some());
    let mut temps = Vec::with_capacity(if with_temp { n } else { 0 });
    let (mut j, mut unpaired) = (0usize, 0usize);
    for a in &acc_s {
        while j + 1 < g.len() && g[j + 1].t_s <= a.t_s {
            j += 1;
        }
        let Some(w) = interpolate(&g, j, a.t_s, max_gap_s) else {
            unpaired += usize::from(own.is_none_or(|(lo, hi)| lo <= a.t_s && a.t_s < hi));
            continue;
        };
        rec.t_s.push(a.t_s);
        rec.acc.push(a.v);
        rec.gyro_rad_s.push(w);
        if with_temp {
            temps.push(a.temp_c.unwrap_or(f64::NAN));
        }
    }
    rec.skipped_rows = acc.non_finite;
    rec.rate_hz = run_rate_hz(&rec.t_s);
    if with_temp {
        rec.temp_c = Some(temps);
    }
    let mut warnings = match own {
        None => temperature_notes(&mut rec),
        // A window says its temperatures and the samples it leaves unpaired on the log's scale
        // (`windows`).
        Some(_) => {
            if let Keep::Span { report, .. } = acc.keeper.keep() {
                if let Ok(mut r) = report.lock() {
                    r.unpaired = (unpaired, max_gap_s);
                }
            }
            unpaired = 0;
            Vec::new()
        }
    };
    if acc_rep == gyro_rep {
        if !acc_rep.is_empty() {
            rec.time_repairs.push(("IMU sample", acc_rep));
        }
    } else {
        for (name, r) in [("accelerometer sample", acc_rep), ("gyro sample", gyro_rep)] {
            if !r.is_empty() {
                rec.time_repairs.push((name, r));
            }
        }
    }
    warnings.extend(unpaired_note(unpaired, max_gap_s));
    if own.is_none() {
        warnings.extend(acc.rates_hz().map(retime_note));
    }
    if gyro.non_finite > 0 {
        warnings.push(format!(
            "{} gyro sample(s) with NaN or infinite values left out (the rate interpolated \
             between their neighbours)",
            gyro.non_finite
        ));
    }
    (rec, warnings)
}

/// The accelerometer samples left out for want of a gyro sample within `max_gap_s`, said.
pub(crate) fn unpaired_note(unpaired: usize, max_gap_s: f64) -> Option<String> {
    (unpaired > 0).then(|| {
        format!(
            "{unpaired} accelerometer sample(s) with no gyro sample within {:.0} ms left out",
            max_gap_s * 1e3
        )
    })
}

/// What the user is told of a text recording read with `options` (a file's or arrays'): its
/// temperature readings (`temperature_notes`) and a gyro in counts at an unsigned output's
/// mid-scale with no offset given.
pub fn text_notes(rec: &mut Recording, options: &ImportOptions) -> Vec<String> {
    let mut notes = temperature_notes(rec);
    notes.extend(gyro_mid_scale_note(rec, options));
    notes
}

/// What the user is told of a recording's temperature readings, the same for every format: none at
/// all (a driver without a temperature sensor: the recording is then read as one without
/// temperature), or some missing (those rows are kept; only the readings enter the temperature
/// statistics, docs/model.md §9).
pub(crate) fn temperature_notes(rec: &mut Recording) -> Vec<String> {
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
pub(crate) fn temperature_note(readings: usize, rows: usize) -> Option<String> {
    if readings == 0 {
        return Some(
            "the temperature is NaN in every sample (a driver without a temperature \
                     reading): read as a log without temperature"
                .to_string(),
        );
    }
    (readings < rows).then(|| {
        format!(
            "{} of {rows} samples have no temperature reading (NaN): those rows are kept, and only \
             the readings enter the temperature statistics",
            rows - readings,
        )
    })
}

/// A stream's samples in time order, their stamps mended ([`repair_times`]); a window's repairs
/// said on the log's scale (`windows::own_repairs`).
fn repaired(samples: Vec<StreamSample>, keeper: &Keeper) -> (Vec<StreamSample>, TimeRepairs) {
    let t: Vec<f64> = samples.iter().map(|s| s.t_s).collect();
    // The temperatures compared bit for bit: a repeat of a sample without a reading (NaN) is a
    // repeat too.
    let temp = |i: usize| samples[i].temp_c.map(f64::to_bits);
    let (order, rep) = repair_times(&t, |i, j| {
        samples[i].v == samples[j].v && temp(i) == temp(j)
    });
    let mut rep = match keeper.keep().own() {
        Some(own) => windows::own_repairs(rep, &order, &t, keeper.places(), own),
        None => rep,
    };
    drop(t);
    let mut times: Vec<f64> = order.iter().map(|s| s.1).collect();
    rep.bursts = super::bursts::retime_bursts(&mut times);
    let out = order
        .iter()
        .zip(times)
        .map(|(&(i, _), t_s)| StreamSample { t_s, ..samples[i] })
        .collect();
    (out, rep)
}

/// [`repair_rows`](crate::session::repair::repair_rows) of a text file's rows kept by `keeper`;
/// a window's repairs said on the log's scale (`windows::own_repairs`).
pub(crate) fn repair_kept_rows(rec: &mut Recording, keeper: &Keeper) {
    repair_rows_saying(rec, |order, t_s, rep| match keeper.keep().own() {
        Some(own) => windows::own_repairs(rep, order, t_s, keeper.places(), own),
        None => rep,
    });
}

/// [`pair`] with the gap allowed between two gyro samples set to five of the gyro's median periods.
pub(crate) fn pair_streams(acc: Stream, gyro: Stream) -> (Recording, Vec<String>) {
    let gyro_ts: Vec<f64> = gyro.samples.iter().map(|s| s.t_s).collect();
    let rate_hz = 1.0 / median_step(&gyro_ts).unwrap_or(1.0);
    pair(acc, gyro, GAP_PERIODS / rate_hz.max(1.0))
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

/// The gyro's rate at `t_s`, between `g[j]` (at or before it) and `g[j + 1]`.
fn interpolate(g: &[StreamSample], j: usize, t_s: f64, max_gap_s: f64) -> Option<[f64; 3]> {
    let a = g.get(j)?;
    if a.t_s == t_s {
        return Some(a.v);
    }
    let b = g.get(j + 1)?;
    if !(a.t_s < t_s && t_s < b.t_s) || b.t_s - a.t_s > max_gap_s {
        return None;
    }
    let f = (t_s - a.t_s) / (b.t_s - a.t_s);
    Some(std::array::from_fn(|k| a.v[k] + f * (b.v[k] - a.v[k])))
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
