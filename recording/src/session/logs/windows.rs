//! A log read window by window, for a use that needs every sample but not all of them at once
//! (`host apply`): memory bounded by the budget, whatever the file's size (docs/robustness.md,
//! "Peak memory of `segment` on a large log").
//!
//! A log of up to the budget per stream is read whole, as [`super::read_log`] reads it. A longer
//! one is surveyed ([`Keep::Survey`]) and cut, along the survey's blocks in time order, into
//! windows of about half the budget each; each window is then read in a pass of its own
//! ([`Keep::Span`]) with a margin of [`MARGIN_PERIODS`] periods on either side, so that its time
//! repair and the pairing of its streams see the neighbours a whole read would. Only the samples
//! of the window itself are handed on: every sample lies in exactly one window, the first window
//! reaching back and the last forward without bound.
//!
//! What a window cannot see is the rest of the log: a stamp damaged so far that it lands in
//! another window's span is, there, an isolated stamp at an end of what that pass keeps, and is
//! left out by the repair's end rule (`crate::session::repair`, rule 2) instead of being re-timed.

use super::keep::{Keep, PassReport};
use super::{first_pass, read_pass, FirstPass, LogError, LogFile, LogSource};
use crate::session::import::Recording;
use std::path::{Path, PathBuf};
use std::sync::{Arc, Mutex};

/// Periods read on either side of a window: more than the repair's neighbours and its gap, and
/// the gyro samples either side of the window's first and last accelerometer sample.
const MARGIN_PERIODS: f64 = 64.0;

/// The margin when the survey shows no period, s.
const MARGIN_FALLBACK_S: f64 = 1.0;

/// A log read whole, or the windows to read it in.
#[derive(Debug)]
pub enum LogRead {
    /// Within the budget: the whole log.
    Whole(LogFile),
    /// Longer: its windows.
    Windows(LogWindows),
}

/// A log too long to hold at once, cut into time windows ([`LogWindows::read`] each in turn).
#[derive(Debug)]
pub struct LogWindows {
    path: PathBuf,
    source: LogSource,
    seconds_per_unit: f64,
    /// Each window's first time (the first window's is −∞), s.
    starts: Vec<f64>,
    margin_s: f64,
    max: usize,
}

impl LogWindows {
    /// The number of windows.
    pub fn len(&self) -> usize {
        self.starts.len()
    }

    /// Whether there is none (never: a log has at least one window).
    pub fn is_empty(&self) -> bool {
        self.starts.is_empty()
    }

    /// Window `k`'s times, `lo..hi` (s; −∞ and +∞ at the ends).
    pub fn span(&self, k: usize) -> (f64, f64) {
        let lo = self.starts.get(k).copied().unwrap_or(f64::INFINITY);
        let hi = self.starts.get(k + 1).copied().unwrap_or(f64::INFINITY);
        (lo, hi)
    }

    /// Window `k` read: its samples in time order, their stamps repaired with the margin's
    /// neighbours, and what the reader noticed in the pass; `None` where the pass keeps fewer
    /// than two samples (a few stamps far off on their own).
    pub fn read(&self, k: usize) -> Result<Option<LogFile>, LogError> {
        let (lo, hi) = self.span(k);
        let keep = Keep::Span {
            lo: lo - self.margin_s,
            hi: hi + self.margin_s,
            max: self.max,
        };
        let mut log = match read_pass(&self.path, &self.source, &keep, self.seconds_per_unit) {
            Err(LogError::NoRecording { .. }) => return Ok(None),
            r => r?,
        };
        within_span(&mut log.recording, lo, hi);
        Ok(Some(log))
    }
}

/// Reads the log at `path` whole when each stream holds at most `max_samples`, and otherwise
/// cuts it into windows of about half that (see the module docs).
pub fn read_log_windows(
    path: &Path,
    source: &LogSource,
    max_samples: usize,
) -> Result<LogRead, LogError> {
    let max = max_samples.max(2);
    let seconds_per_unit = match first_pass(path, source, max)? {
        FirstPass::Whole(log) => return Ok(LogRead::Whole(*log)),
        FirstPass::Over {
            seconds_per_unit, ..
        } => seconds_per_unit,
    };
    let report = Arc::new(Mutex::new(PassReport::default()));
    read_pass(
        path,
        source,
        &Keep::Survey(Arc::clone(&report)),
        seconds_per_unit,
    )?;
    let survey = report.lock().ok().and_then(|mut r| r.survey.take());
    let (mut starts, period) = survey.map(|s| s.window_starts(max / 2)).unwrap_or_default();
    starts.insert(0, f64::NEG_INFINITY);
    Ok(LogRead::Windows(LogWindows {
        path: path.to_path_buf(),
        source: source.clone(),
        seconds_per_unit,
        starts,
        margin_s: period.map_or(MARGIN_FALLBACK_S, |p| MARGIN_PERIODS * p),
        max,
    }))
}

/// Keeps the rows of `rec` (in time order) whose time lies in `lo..hi`.
fn within_span(rec: &mut Recording, lo: f64, hi: f64) {
    let a = rec.t_s.partition_point(|&t| t < lo);
    let b = rec.t_s.partition_point(|&t| t < hi);
    rec.t_s.truncate(b);
    rec.t_s.drain(..a);
    rec.acc.truncate(b);
    rec.acc.drain(..a);
    rec.gyro_rad_s.truncate(b);
    rec.gyro_rad_s.drain(..a);
    if let Some(t) = &mut rec.temp_c {
        t.truncate(b);
        t.drain(..a);
    }
}
