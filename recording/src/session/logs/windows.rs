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
//! A window's pass does not read the file from its start: the survey marks where the reader can
//! resume (`super::resume`), and each window reads only the stretches between marks whose
//! samples' times reach it, so that the time grows with the file's size, not its square. It keeps
//! the same samples, and says the same, as a pass over the whole file
//! ([`LogWindows::without_marks`] is that pass, for the tests).
//!
//! What is said of the log is said on the log's scale, decided once for the whole log and applied
//! by each window ([`LogScale`]): whether it has temperatures (the survey counts the readings), the
//! places of the samples a repair names (counted in the file, not in the window), the gaps and
//! their rows (counted in the rows written, across the windows' edges), the samples left unpaired
//! and the temperatures missing. Each window says only what it found of its own times, so that
//! every sample is said of once.
//!
//! What a window cannot see is the rest of the log: a stamp damaged so far that it lands outside
//! its own window's reach (the window's times and the margin) is not among that window's samples;
//! where it lands, it is an isolated stamp at an end of what that pass keeps, left out by the
//! repair's end rule (`crate::session::repair`, rule 2), or not read at all. That is the window
//! rule: such a sample is left out, where a whole read re-times it, and the samples it costs are
//! counted against the survey's and said ([`LogScale::notes`]).

use super::keep::{Keep, PassReport};
use super::resume::{mark_every, SharedResume};
use super::{
    first_pass, read_pass, resume_pass, temperature_note, unpaired_note, FirstPass, LogError,
    LogFile, LogSource,
};
use crate::session::import::{say_time_jumps, Recording, TimeJump, GAP_PERIODS};
use crate::session::note::Note;
use crate::session::repair::{Restart, TimeRepairs};
use std::collections::HashMap;
use std::path::{Path, PathBuf};
use std::sync::{Arc, Mutex};

/// Periods read on either side of a window: more than the repair's neighbours and its gap, and
/// the gyro samples either side of the window's first and last accelerometer sample.
pub(crate) const MARGIN_PERIODS: f64 = 64.0;

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
    /// The survey's accelerometer samples (finite).
    surveyed: usize,
    /// Whether the log has a temperature reading anywhere: each window then has temperatures
    /// (NaN where it has none), else none.
    temperatures: bool,
    /// The survey found a temperature field without a reading anywhere.
    no_readings: bool,
    /// Where each window's stretch of the file begins, from the survey (`None`: a format without
    /// marks, whose windows each read the whole file; `super::resume`).
    resume: Option<SharedResume>,
}

/// One window of a long log read: its samples (their time repairs said on the log's scale, with
/// their places in the file) and what it says on the log's scale ([`LogScale`]).
#[derive(Debug)]
pub struct Window {
    /// The window's samples and what the reader noticed (less what [`LogScale`] says).
    pub log: LogFile,
    /// Its accelerometer samples left out for want of a gyro sample, and the gap allowed, s.
    unpaired: (usize, f64),
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
    pub fn read(&self, k: usize) -> Result<Option<Window>, LogError> {
        let (lo, hi) = self.span(k);
        let report = Arc::new(Mutex::new(PassReport::default()));
        let keep = Keep::Span {
            lo: lo - self.margin_s,
            hi: hi + self.margin_s,
            max: self.max,
            own: (lo, hi),
            report: Arc::clone(&report),
        };
        let pass = match &self.resume {
            Some(resume) => resume_pass(
                &self.path,
                &self.source,
                resume,
                &keep,
                self.seconds_per_unit,
            ),
            None => read_pass(&self.path, &self.source, &keep, self.seconds_per_unit),
        };
        let mut log = match pass {
            Err(LogError::NoRecording { .. }) => return Ok(None),
            r => r?,
        };
        let rec = &mut log.recording;
        within_span(rec, lo, hi);
        match (&rec.temp_c, self.temperatures) {
            (_, false) => rec.temp_c = None,
            (None, true) => rec.temp_c = Some(vec![f64::NAN; rec.len()]),
            (Some(_), true) => {}
        }
        let unpaired = report.lock().map(|r| r.unpaired).unwrap_or_default();
        Ok(Some(Window { log, unpaired }))
    }

    /// These windows, each read by a pass over the whole file rather than from the survey's
    /// marks: what a read from the marks must equal, sample for sample and word for word.
    pub fn without_marks(self) -> LogWindows {
        LogWindows {
            resume: None,
            ..self
        }
    }

    /// Whether the windows are read from the survey's marks (each its own stretch of the file).
    pub fn marked(&self) -> bool {
        self.resume.is_some()
    }

    /// What is said on the log's scale, to be told each window read in turn.
    pub fn scale(&self) -> LogScale {
        LogScale {
            surveyed: self.surveyed,
            no_readings: self.no_readings,
            ..LogScale::default()
        }
    }
}

/// What a log read window by window says on the log's scale, gathered window by window (see the
/// module docs): the same words a whole read says of the same samples.
#[derive(Debug, Default)]
pub struct LogScale {
    surveyed: usize,
    no_readings: bool,
    rows: usize,
    /// The rate of the first window, Hz: its gaps are five of its periods.
    rate_hz: f64,
    last_t_s: Option<f64>,
    jumps: Vec<TimeJump>,
    jump_count: usize,
    temperatures: (usize, usize),
    unpaired: (usize, f64),
    repairs: Vec<(&'static str, TimeRepairs)>,
}

/// Time jumps named, as a whole read names them.
const JUMPS_NAMED: usize = 5;

impl LogScale {
    /// Window `w`, the next in time order.
    pub fn add(&mut self, w: &Window) {
        let rec = &w.log.recording;
        if self.rate_hz <= 0.0 {
            self.rate_hz = rec.rate_hz;
        }
        let limit = GAP_PERIODS / self.rate_hz;
        for (i, &t_s) in rec.t_s.iter().enumerate() {
            if let Some(last) = self.last_t_s {
                let step_s = t_s - last;
                if !(step_s > 0.0 && step_s <= limit) {
                    self.jump_count += 1;
                    if self.jumps.len() < JUMPS_NAMED {
                        let row = self.rows + i - 1;
                        self.jumps.push(TimeJump {
                            row,
                            t_s: last,
                            step_s,
                        });
                    }
                }
            }
            self.last_t_s = Some(t_s);
        }
        self.rows += rec.len();
        if let Some(t) = &rec.temp_c {
            self.temperatures.0 += t.iter().filter(|t| t.is_finite()).count();
            self.temperatures.1 += t.len();
        }
        self.unpaired.0 += w.unpaired.0;
        if w.unpaired.0 > 0 || self.unpaired.1 == 0.0 {
            self.unpaired.1 = w.unpaired.1;
        }
        for (what, rep) in &rec.time_repairs {
            match self.repairs.iter_mut().find(|(w, _)| w == what) {
                Some((_, all)) => merge(all, rep),
                None => self.repairs.push((what, rep.clone())),
            }
        }
    }

    /// What the whole log says: its temperatures, the samples left unpaired, the time repairs
    /// with their places in the file, the samples the window rule left out, and the gaps.
    pub fn notes(mut self) -> Vec<Note> {
        let mut notes = Vec::new();
        if self.no_readings {
            notes.extend(temperature_note(0, self.rows));
        } else if self.temperatures.1 > 0 {
            notes.extend(temperature_note(self.temperatures.0, self.temperatures.1));
        }
        notes.extend(unpaired_note(self.unpaired.0, self.unpaired.1));
        let mut lost_by_repair = 0;
        let last = self.surveyed.saturating_sub(1);
        for (what, rep) in &mut self.repairs {
            // A stamp left out at one window's edge may be re-timed, and written, by another;
            // one left out at a window's edge that is not the log's is the window rule's.
            let written: Vec<usize> = rep.retimed.iter().map(|r| r.0).collect();
            rep.dropped
                .retain(|d| !written.contains(&d.0) && (d.0 == 0 || d.0 == last));
            if *what != "gyro sample" {
                lost_by_repair += rep.lost();
            }
            notes.extend(Note::time_repairs(Some(what), rep));
        }
        let accounted = self.rows + lost_by_repair + self.unpaired.0;
        let lost = self.surveyed.saturating_sub(accounted);
        if lost > 0 {
            notes.push(Note::WindowRule { lost });
        }
        notes.extend(say_time_jumps(&self.jumps, self.jump_count, self.rate_hz));
        notes
    }
}

/// `rep`'s repairs added to `all`'s, in the file's order.
fn merge(all: &mut TimeRepairs, rep: &TimeRepairs) {
    all.reversed |= rep.reversed;
    all.retimed.extend(&rep.retimed);
    all.retimed.sort_by_key(|r| r.0);
    all.dropped.extend(&rep.dropped);
    all.dropped.sort_by_key(|r| r.0);
    all.reordered += rep.reordered;
    all.repeats.extend(&rep.repeats);
    all.repeats.sort_unstable();
    all.spread.extend(&rep.spread);
    all.spread.sort_unstable();
    all.restarts.extend(&rep.restarts);
}

/// A window pass's repairs `rep` said on the log's scale: the samples named by their places in
/// the file (`places`, the keeper's) instead of in the pass, and only those of the window's own
/// times `own` (a sample re-timed or spread into them, an exact repeat or a stamp left out that
/// was read in them, the samples sorted into their order among those kept in them), so that
/// each repair is said by one window. `order`: the repaired order (index in the pass, time);
/// `t_s`: the stamps read.
pub(super) fn own_repairs(
    rep: TimeRepairs,
    order: &[(usize, f64)],
    t_s: &[f64],
    places: &[usize],
    own: (f64, f64),
) -> TimeRepairs {
    let inside = |t: f64| own.0 <= t && t < own.1;
    let place = |i: usize| places.get(i).copied().unwrap_or(i);
    let spread_at: HashMap<usize, f64> = match rep.spread.is_empty() {
        true => HashMap::new(),
        false => order.iter().copied().collect(),
    };
    // A sample sorted into its place: its place in the pass's (reading) order is not its place
    // in time.
    let mut read_order: Vec<usize> = order.iter().map(|s| s.0).collect();
    read_order.sort_unstable();
    if rep.reversed {
        read_order.reverse();
    }
    let reordered = match rep.reordered {
        0 => 0,
        _ => order
            .iter()
            .zip(&read_order)
            .filter(|(s, &r)| inside(s.1) && s.0 != r)
            .count(),
    };
    TimeRepairs {
        bursts: rep.bursts.clone(),
        reversed: rep.reversed,
        retimed: (rep.retimed.iter())
            .filter(|r| inside(r.2))
            .map(|&(i, read, given)| (place(i), read, given))
            .collect(),
        dropped: (rep.dropped.iter())
            .filter(|d| inside(d.1))
            .map(|&(i, read)| (place(i), read))
            .collect(),
        reordered,
        repeats: (rep.repeats.iter())
            .filter(|&&i| t_s.get(i).is_some_and(|&t| inside(t)))
            .map(|&i| place(i))
            .collect(),
        spread: (rep.spread.iter())
            .filter(|i| spread_at.get(i).is_some_and(|&t| inside(t)))
            .map(|&i| place(i))
            .collect(),
        restarts: (rep.restarts.iter())
            .filter(|r| inside(r.read_s + r.moved_s))
            .map(|r| Restart {
                index: place(r.index),
                ..*r
            })
            .collect(),
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
    let report = Arc::new(Mutex::new(PassReport {
        marks_every: mark_every(max),
        ..PassReport::default()
    }));
    read_pass(
        path,
        source,
        &Keep::Survey(Arc::clone(&report)),
        seconds_per_unit,
    )?;
    let (survey, temperatures, resume) = match report.lock() {
        Ok(mut r) => (r.survey.take(), r.temperatures, r.resume.take()),
        Err(_) => (None, (0, 0), None),
    };
    let surveyed = survey.as_ref().map_or(0, |s| s.count());
    let (mut starts, period) = survey.map(|s| s.window_starts(max / 2)).unwrap_or_default();
    starts.insert(0, f64::NEG_INFINITY);
    Ok(LogRead::Windows(LogWindows {
        path: path.to_path_buf(),
        source: source.clone(),
        seconds_per_unit,
        starts,
        margin_s: period.map_or(MARGIN_FALLBACK_S, |p| MARGIN_PERIODS * p),
        max,
        surveyed,
        temperatures: temperatures.1 > 0,
        no_readings: temperatures.0 > 0 && temperatures.1 == 0,
        resume,
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
