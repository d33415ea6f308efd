//! The time column of a logger's file: its unit, detected from the median step and the span or
//! given ([`TimeUnit`]), and where its stamps jump ([`TimeJump`]): gaps, repeats and steps back, which
//! no still interval spans and no turn is integrated across.

use super::{ImportError, Recording};
use crate::limits::short_number;
use crate::session::note::Note;
use crate::spelling::{Spelling, UserOption};

/// The unit of a time column: detected from the median step and the span, or given
/// (`--time-unit`).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum TimeUnit {
    /// Seconds.
    S,
    /// Milliseconds.
    Ms,
    /// Microseconds.
    Us,
    /// Nanoseconds.
    Ns,
}

impl TimeUnit {
    /// Every unit, largest first.
    pub const ALL: [TimeUnit; 4] = [TimeUnit::S, TimeUnit::Ms, TimeUnit::Us, TimeUnit::Ns];

    /// Parses "s", "ms", "us" (or "µs") or "ns".
    pub fn parse(s: &str) -> Option<TimeUnit> {
        match s {
            "s" => Some(TimeUnit::S),
            "ms" => Some(TimeUnit::Ms),
            "us" | "µs" => Some(TimeUnit::Us),
            "ns" => Some(TimeUnit::Ns),
            _ => None,
        }
    }

    /// The unit as `--time-unit` takes it, in plain ASCII ("us" for µs).
    pub fn option(self) -> &'static str {
        match self {
            TimeUnit::Us => "us",
            other => other.symbol(),
        }
    }

    /// Seconds per unit.
    pub fn seconds(self) -> f64 {
        match self {
            TimeUnit::S => 1.0,
            TimeUnit::Ms => 1e-3,
            TimeUnit::Us => 1e-6,
            TimeUnit::Ns => 1e-9,
        }
    }

    /// "s", "ms", "µs" or "ns".
    pub fn symbol(self) -> &'static str {
        match self {
            TimeUnit::S => "s",
            TimeUnit::Ms => "ms",
            TimeUnit::Us => "µs",
            TimeUnit::Ns => "ns",
        }
    }
}

/// Where a recording's times come from: what a wrong time base would have to be wrong in.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum TimeOrigin {
    /// A text file's rows at the rate given (`--rate-hz`), Hz.
    RateGiven(f64),
    /// A text file's time column.
    TimeColumn,
    /// A binary log's own stamps: its format's name.
    LoggerStamps(&'static str),
}

impl TimeOrigin {
    /// A text file's: its time column, or the rate given.
    pub fn of_text(time: &super::TimeSource) -> TimeOrigin {
        match time {
            super::TimeSource::Column(_) => TimeOrigin::TimeColumn,
            super::TimeSource::RateHz(hz) => TimeOrigin::RateGiven(*hz),
        }
    }
}

/// Where the time stamps break: a gap of more than [`GAP_PERIODS`] sample periods, a repeat or a
/// step back, after row `row`.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct TimeJump {
    /// The row before the jump (0-based data row).
    pub row: usize,
    /// Its time, s.
    pub t_s: f64,
    /// The step to the next row, s (≤ 0: a repeat or a step back).
    pub step_s: f64,
}

/// A step longer than this many median periods is a gap: no still interval spans it and no turn is
/// integrated across it (a dropped stretch of a turn would be integrated as a straight line).
pub const GAP_PERIODS: f64 = 5.0;

impl Recording {
    /// The gaps (more than [`GAP_PERIODS`] periods), repeats and backward steps of the time stamps,
    /// in order.
    pub fn jumps(&self) -> Vec<TimeJump> {
        let limit = GAP_PERIODS / self.rate_hz;
        self.t_s
            .windows(2)
            .enumerate()
            .filter(|(_, w)| !(w[1] - w[0] > 0.0 && w[1] - w[0] <= limit))
            .map(|(row, w)| TimeJump {
                row,
                t_s: w[0],
                step_s: w[1] - w[0],
            })
            .collect()
    }

    /// Whether rows `lo..hi` are free of time jumps (`jumps` from [`Recording::jumps`]).
    pub fn continuous(jumps: &[TimeJump], lo: usize, hi: usize) -> bool {
        !jumps.iter().any(|j| j.row >= lo && j.row + 1 < hi)
    }

    /// The time jumps said with their places (the first five), or `None`: no still interval spans
    /// one and no turn is integrated across one.
    pub fn time_jumps(&self) -> Option<Note> {
        let jumps = self.jumps();
        say_time_jumps(&jumps[..jumps.len().min(5)], jumps.len(), self.rate_hz)
    }

    /// Number of samples.
    pub fn len(&self) -> usize {
        self.t_s.len()
    }

    /// No samples.
    pub fn is_empty(&self) -> bool {
        self.t_s.is_empty()
    }
}

/// `count` time jumps of a recording at `rate_hz` said, `named` the first of them (five are named),
/// or `None` when there are none ([`Recording::time_jumps`]; a long log read window by window
/// counts them across its windows, `crate::session::logs`).
pub fn say_time_jumps(named: &[TimeJump], count: usize, rate_hz: f64) -> Option<Note> {
    (count > 0).then(|| Note::TimeJumps {
        named: named.iter().take(5).copied().collect(),
        count,
        rate_hz,
    })
}

/// The text of [`Note::TimeJumps`]: `count` jumps at `rate_hz`, `named` the first of them.
pub(crate) fn jumps_text(named: &[TimeJump], count: usize, rate_hz: f64) -> String {
    let kind = |j: &TimeJump| match j.step_s {
        0.0 => "repeat",
        s if s < 0.0 => "step back",
        _ => "gap",
    };
    let places: Vec<String> = named
        .iter()
        .take(5)
        .map(|j| {
            format!(
                "{} of {:+.3} s after data row {} (t = {:.3} s)",
                kind(j),
                j.step_s,
                j.row + 1,
                j.t_s
            )
        })
        .collect();
    format!(
        "the time stamps jump {count} time(s) (a gap of more than {GAP_PERIODS} periods of {:.4} \
         s, a repeat or a step back): {}{}; no still interval spans one and no turn is integrated \
         across one",
        1.0 / rate_hz,
        places.join("; "),
        if count > 5 { "; …" } else { "" }
    )
}

/// Shortest recording a time unit may make of the time column, s: a hand-held session is minutes
/// long; read in too large a unit, a 1 kHz log in µs spans 1000× too long, in too small a unit
/// 1000× too short.
pub(super) const MIN_SPAN_S: f64 = 0.5;
/// Longest, days.
pub(super) const MAX_SPAN_DAYS: f64 = 7.0;

/// The median step and the span of raw time stamps, both unmoved by a few damaged stamps (the
/// span is the samples' count times the median step) and by the log's direction (a log written
/// newest first steps back by the same steps).
fn step_and_span(t: &[f64]) -> (f64, f64) {
    let step = 1.0 / median_rate(t);
    (step, step * t.len().saturating_sub(1) as f64)
}

/// Whether time stamps in `unit` give a logger's rate over a plausible span.
pub(super) fn fits_time_unit(t: &[f64], unit: TimeUnit) -> bool {
    let (step, span) = step_and_span(t);
    let rate_hz = 1.0 / (step * unit.seconds());
    let span_s = span * unit.seconds();
    (MIN_RATE_HZ..=MAX_RATE_HZ).contains(&rate_hz)
        && (MIN_SPAN_S..=MAX_SPAN_DAYS * 86_400.0).contains(&span_s)
}

/// The one time unit (s, ms, µs, ns) in which the median step is a logger's rate and the span a
/// recording's; refused when none or several fit.
pub fn detect_time_unit(t: &[f64], spelling: Spelling) -> Result<TimeUnit, ImportError> {
    let fits: Vec<TimeUnit> = TimeUnit::ALL
        .into_iter()
        .filter(|&u| fits_time_unit(t, u))
        .collect();
    match fits[..] {
        [one] => Ok(one),
        [] => Err(time_unit_error(t, None, spelling)),
        _ => {
            let (step, span) = step_and_span(t);
            Err(ImportError::TimeUnitAmbiguous {
                step,
                span,
                readings: fits
                    .iter()
                    .map(|u| {
                        format!(
                            "{} Hz over {} s in {}",
                            six_digits(1.0 / (step * u.seconds())),
                            six_digits(span * u.seconds()),
                            u.symbol()
                        )
                    })
                    .collect(),
                spelling,
            })
        }
    }
}

pub(super) fn time_unit_error(
    t: &[f64],
    given: Option<TimeUnit>,
    spelling: Spelling,
) -> ImportError {
    let (step, span) = step_and_span(t);
    let reading = |u: TimeUnit| {
        format!(
            "{} Hz over {} s",
            six_digits(1.0 / (step * u.seconds())),
            six_digits(span * u.seconds())
        )
    };
    let fits: Vec<TimeUnit> = TimeUnit::ALL
        .into_iter()
        .filter(|&u| fits_time_unit(t, u))
        .collect();
    if let (Some(given), &[fits]) = (given, &fits[..]) {
        return ImportError::TimeUnitGiven {
            step,
            span,
            given: given.option(),
            given_reading: reading(given),
            fits: fits.option(),
            fits_reading: reading(fits),
            spelling,
        };
    }
    ImportError::TimeUnit {
        step,
        span,
        given: given.map_or(String::new(), |u| {
            format!(
                " ({} gives {} Hz)",
                spelling.given(UserOption::TimeUnit, u.symbol()),
                six_digits(1.0 / (step * u.seconds()))
            )
        }),
        spelling,
    }
}

/// `x` to six significant digits, as `short_number` prints it (a median step of 0.01 read from
/// text is 0.009999999999999787).
pub fn six_digits(x: f64) -> String {
    short_number(format!("{x:.5e}").parse().unwrap_or(x))
}

/// The median rate of the steps, forward or back (repeats are not the rate).
pub(super) fn median_rate(t_s: &[f64]) -> f64 {
    let mut dt: Vec<f64> = t_s
        .windows(2)
        .map(|w| (w[1] - w[0]).abs())
        .filter(|d| *d > 0.0)
        .collect();
    if dt.is_empty() {
        return f64::NAN;
    }
    dt.sort_by(f64::total_cmp);
    1.0 / dt[dt.len() / 2]
}

/// Slowest rate a time unit may make of a logger's time stamps, Hz: an IMU log for calibration samples
/// at tens of Hz at least; read in too large a unit, a time column reads 1000× slower.
pub(super) const MIN_RATE_HZ: f64 = 5.0;

/// Fastest, Hz: above the fastest IMU output data rates (32 kHz), and below 100 kHz, which a 100 Hz log
/// in seconds would read as in ms.
pub(super) const MAX_RATE_HZ: f64 = 5e4;
