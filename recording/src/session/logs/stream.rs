//! One IMU stream as a binary log holds it: its samples, kept as the pass's [`Keep`] says and
//! re-timed where a rate is given, and two streams (the accelerometer's and the gyro's) mended and
//! paired into one recording.

use super::keep::{Admit, Keep, Keeper};
use super::retime::{retime_note, Retime};
use super::{temperature_notes, unpaired_note, windows};
use crate::session::import::{Recording, GAP_PERIODS};
use crate::session::note::Note;
use crate::session::repair::{median_step, repair_times, run_rate_hz, TimeRepairs};
use shared::OutputUnit;

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
    /// Each sample re-timed at a given rate ([`super::LogSource::rate_hz`]).
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

    /// Where this stream stands: what a window's pass resumes it from (`resume`).
    pub fn at(&self) -> StreamAt {
        StreamAt {
            read: self.keeper.count(),
            non_finite: self.non_finite,
            retime: self.retime.as_ref().map(Retime::at),
        }
    }

    /// Goes on from `at`: a window's pass resumed at a mark, or finished with the counts of the
    /// whole file (`resume`).
    pub fn resume(&mut self, at: &StreamAt) {
        self.keeper.resume_count(at.read);
        self.non_finite = at.non_finite;
        if let (Some(r), Some(a)) = (self.retime.as_mut(), at.retime) {
            r.resume(a);
        }
    }

    /// A survey: the least and greatest time of the samples read since the last call.
    pub fn take_times(&mut self) -> (f64, f64) {
        self.keeper.take_times()
    }
}

/// A stream's counts and re-timing at a point of the file ([`Stream::at`]).
#[derive(Clone, Copy, Debug, Default)]
pub(crate) struct StreamAt {
    read: usize,
    non_finite: usize,
    retime: Option<(Option<f64>, u64)>,
}

/// The accelerometer's samples with the gyro's rate at their times (linear interpolation between
/// the gyro's two neighbouring samples; an accelerometer sample outside the gyro's time span, or
/// further than `max_gap_s` from a gyro sample on either side, is left out). Logs with one message
/// for both (ULog's `sensor_combined`, DataFlash's `IMU`) give the two streams the same times, and
/// the interpolation returns the gyro sample itself. Each stream's time stamps are first mended by
/// [`repair`](crate::session::repair)'s rules, so that a damaged stamp costs at most its sample.
/// The streams are consumed, each dropped once mended, so that no more than one copy of a
/// stream is held at a time (`keep`).
pub(crate) fn pair(mut acc: Stream, mut gyro: Stream, max_gap_s: f64) -> (Recording, Vec<Note>) {
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
        warnings.push(Note::GyroNonFinite {
            count: gyro.non_finite,
        });
    }
    (rec, warnings)
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
    rep.bursts = crate::session::bursts::retime_bursts(&mut times);
    let out = order
        .iter()
        .zip(times)
        .map(|(&(i, _), t_s)| StreamSample { t_s, ..samples[i] })
        .collect();
    (out, rep)
}

/// [`pair`] with the gap allowed between two gyro samples set to five of the gyro's median periods.
pub(crate) fn pair_streams(acc: Stream, gyro: Stream) -> (Recording, Vec<Note>) {
    let gyro_ts: Vec<f64> = gyro.samples.iter().map(|s| s.t_s).collect();
    let rate_hz = 1.0 / median_step(&gyro_ts).unwrap_or(1.0);
    pair(acc, gyro, GAP_PERIODS / rate_hz.max(1.0))
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

/// The finite samples `streams` have read, all told: where a survey's next mark is due
/// (`super::resume`).
pub(crate) fn read_by(streams: &[&Stream]) -> usize {
    streams.iter().map(|s| s.count()).sum()
}

/// A survey: the least and greatest time of the samples `streams` read since the last call.
pub(crate) fn take_times_of<const N: usize>(streams: [&mut Stream; N]) -> (f64, f64) {
    streams.into_iter().fold(super::resume::NO_TIMES, |t, s| {
        super::resume::join(t, s.take_times())
    })
}
