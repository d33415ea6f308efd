//! How much of a log the readers keep in memory, so that the memory `segment` needs does not grow
//! with the file (docs/robustness.md, "Peak memory of `segment` on a large log").
//!
//! A log of up to the budget ([`DEFAULT_MAX_SAMPLES`] for `segment`) per stream is kept whole. A
//! longer one is read three times, each pass streaming the file:
//!
//! 1. the first pass stops at the budget ([`Keep::All`]);
//! 2. the survey ([`Keep::Survey`]) keeps each stream's block statistics only, at most
//!    [`MAX_BLOCKS`] blocks, merged pairwise as the log goes on;
//! 3. the extract ([`Keep::Within`]) keeps the samples whose time lies in the regions the survey
//!    found ([`Survey::regions`]): the accelerometer's quiet stretches (a still position, or a
//!    spin on a table) with a margin, and the moves between two of them shorter than
//!    [`MAX_MOVE_S`] (the turns). Long flights, walks and drives between them are what is left
//!    out; a calibration uses none of it. The extract keeps at most the budget too: what lies
//!    beyond it is named.
//!
//! The survey locates; it decides nothing. The still intervals are found on the samples kept, by
//! the same rules as on a short log (`super::super::segment`).

use crate::session::import::MAX_ROWS;
use crate::session::note::Note;
use crate::spelling::{Spelling, UserOption};
use std::sync::{Arc, Mutex};

/// Samples kept per stream by default: about 50 MB for the whole of `segment` (measured at about
/// 200 bytes per sample: the samples, their repair, the window statistics), so that it stays within
/// 64 MiB. That is 4 min 10 s at 1 kHz of still positions and turns.
pub const DEFAULT_MAX_SAMPLES: usize = 250_000;

/// Most blocks a survey holds; two neighbours are merged when it is full (about 2.5 MB).
pub const MAX_BLOCKS: usize = 1 << 15;

/// A move longer than this between two quiet stretches is no turn of a calibration (a flight, a
/// walk): it is left out of a long log.
pub const MAX_MOVE_S: f64 = 60.0;

/// The variance, summed over three axes, that no still unit exceeds, (m/s²)²: 20 mg per axis, the
/// segmentation's own limit (`super::super::segment`).
pub(crate) const STILL_VAR_M2_S4: f64 =
    3.0 * (0.02 * shared::STANDARD_GRAVITY_M_S2) * (0.02 * shared::STANDARD_GRAVITY_M_S2);

/// Seconds kept around each quiet stretch: the segmentation's windows and trims reach beyond the
/// stretch a block found.
const MARGIN_S: f64 = 2.0;

/// Samples in a survey's first blocks.
const FIRST_BLOCK: usize = 16;

/// What a stream keeps of its samples.
#[derive(Clone, Debug)]
pub(crate) enum Keep {
    /// Every sample, refusing more than `max` ([`super::TooMany`]).
    All {
        /// The budget.
        max: usize,
    },
    /// Block statistics only; the accelerometer's regions are put in the report when the reader
    /// pairs its streams.
    Survey(Arc<Mutex<PassReport>>),
    /// The samples whose time lies in one of `regions` (sorted, disjoint, s), the first `max`;
    /// what the accelerometer's stream left out is put in the report.
    Within {
        /// Start and end of each region kept.
        regions: Arc<[(f64, f64)]>,
        /// The budget.
        max: usize,
        /// Where the accelerometer's [`LeftOut`] goes.
        report: Arc<Mutex<PassReport>>,
    },
    /// The samples whose time lies in `lo..hi` (s), refusing more than `max` ([`super::TooMany`]):
    /// one window of a log read window by window (`super::windows`).
    Span {
        /// The first time kept.
        lo: f64,
        /// The first time no longer kept.
        hi: f64,
        /// The budget.
        max: usize,
        /// The window's own times (`lo..hi` without the margins), s: what the pass says of its
        /// samples (their repairs, those left unpaired) is said of these only, so that every
        /// sample is said of in one window.
        own: (f64, f64),
        /// Where the accelerometer's counts go (`Keeper::report`, [`super::pair`]).
        report: Arc<Mutex<PassReport>>,
    },
}

/// What a survey or an extract found, handed back from inside a reader.
#[derive(Clone, Debug, Default)]
pub(crate) struct PassReport {
    /// The survey's regions.
    pub regions: Option<Vec<(f64, f64)>>,
    /// The survey itself, for a caller that cuts the log into windows (`super::windows`).
    pub survey: Option<Survey>,
    /// Samples between the marks a survey sets for the windows' passes (0: none;
    /// `super::resume`).
    pub marks_every: usize,
    /// The survey's marks and end state (`super::resume`).
    pub resume: Option<super::resume::SharedResume>,
    /// What the extract left out of the accelerometer's stream.
    pub left_out: Option<LeftOut>,
    /// The survey's count of the accelerometer's samples with a temperature field, and of those
    /// with a reading (finite).
    pub temperatures: (usize, usize),
    /// A window's accelerometer samples of its own times left out for want of a gyro sample,
    /// and the gap allowed, s.
    pub unpaired: (usize, f64),
}

impl Keep {
    /// Whether `t_s` lies outside a window's span (never, for the other kinds).
    fn outside_span(&self, t_s: f64) -> bool {
        matches!(self, Keep::Span { lo, hi, .. } if !(*lo <= t_s && t_s < *hi))
    }

    /// The times a window's pass keeps, its margins included (`lo..hi`, s); every time for the
    /// other kinds.
    pub fn reach(&self) -> (f64, f64) {
        match self {
            Keep::Span { lo, hi, .. } => (*lo, *hi),
            _ => (f64::NEG_INFINITY, f64::INFINITY),
        }
    }

    /// A window's own times (`None`: not a window's pass).
    pub fn own(&self) -> Option<(f64, f64)> {
        match self {
            Keep::Span { own, .. } => Some(*own),
            _ => None,
        }
    }
}

impl Default for Keep {
    /// Everything, up to [`MAX_ROWS`].
    fn default() -> Keep {
        Keep::All { max: MAX_ROWS }
    }
}

/// Decides, sample by sample, what a stream (or a text file's rows) keeps: the one place the
/// [`Keep`] rules are applied.
#[derive(Debug, Default)]
pub(crate) struct Keeper {
    keep: Keep,
    survey: Survey,
    left_out: LeftOut,
    /// The variance, summed over the axes, that a still unit never exceeds, in the stream's unit
    /// (0: unknown, the quietest blocks alone decide).
    still_var: f64,
    /// A window's pass: each sample kept, its place among the stream's finite samples in the file
    /// (0-based), so that what is said of it names its place in the log.
    places: Vec<usize>,
    /// A survey: the samples with a temperature field, and those with a reading.
    temperatures: (usize, usize),
    /// A survey: the least and greatest time of the samples admitted since the last mark
    /// (`super::resume`).
    times: Option<(f64, f64)>,
    /// A survey asked for marks (`super::resume`): only it keeps the times and counts below.
    marking: bool,
    /// A text file's survey: the rows with a finite time, whatever their values (a window's pass
    /// counts each it passes over as seen, [`Keeper::passes`]).
    timed: usize,
    /// A text file's rows left out for a time that is not finite.
    untimed: usize,
}

/// What [`Keeper::admit`] says of a sample.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(crate) enum Admit {
    /// Keep it.
    Keep,
    /// Leave it out (surveyed, outside the regions, or beyond the budget).
    Pass,
    /// More than the budget of [`Keep::All`], which is given: the pass fails.
    TooMany(usize),
}

impl Keeper {
    /// A keeper of a stream in m/s².
    pub fn new(keep: &Keep) -> Keeper {
        let marking = match keep {
            Keep::Survey(report) => report.lock().is_ok_and(|r| r.marks_every > 0),
            _ => false,
        };
        Keeper {
            keep: keep.clone(),
            still_var: STILL_VAR_M2_S4,
            marking,
            ..Keeper::default()
        }
    }

    /// A keeper of a stream whose still limit is `still_var` in its own unit.
    pub fn with_still_var(keep: &Keep, still_var: f64) -> Keeper {
        Keeper {
            still_var,
            ..Keeper::new(keep)
        }
    }

    /// A finite sample at `t_s` (s) with accelerometer `acc`, when `kept` are already kept.
    pub fn admit(&mut self, t_s: f64, acc: &[f64; 3], kept: usize) -> Admit {
        self.left_out.read += 1;
        match &self.keep {
            Keep::All { max } if kept >= *max => Admit::TooMany(*max),
            Keep::All { .. } => Admit::Keep,
            Keep::Survey(_) => {
                self.survey.push(t_s, acc);
                self.note_time(t_s);
                Admit::Pass
            }
            Keep::Within { regions, max, .. } => {
                if !within(regions, t_s) {
                    self.left_out.outside += 1;
                    Admit::Pass
                } else if kept >= *max {
                    self.left_out.over_budget += 1;
                    self.left_out.first_over_s.get_or_insert(t_s);
                    Admit::Pass
                } else {
                    Admit::Keep
                }
            }
            Keep::Span { max, .. } => match self.keep.outside_span(t_s) {
                true => Admit::Pass,
                false if kept >= *max => Admit::TooMany(*max),
                false => {
                    self.places.push(self.left_out.read - 1);
                    Admit::Keep
                }
            },
        }
    }

    /// The temperature of the sample last admitted, counted by a survey (whether the log has
    /// readings decides each window's, `super::windows`).
    pub fn temperature(&mut self, temp_c: f64) {
        if matches!(self.keep, Keep::Survey(_)) {
            self.temperatures.0 += 1;
            self.temperatures.1 += usize::from(temp_c.is_finite());
        }
    }

    /// What this stream keeps.
    pub fn keep(&self) -> &Keep {
        &self.keep
    }

    /// A window's pass: the place in the file of each sample kept (see `places`).
    pub fn places(&self) -> &[usize] {
        &self.places
    }

    /// Whether a sample is left out on its time alone, `time_s` telling it (s; `None`: no
    /// finite time, which the whole sample's reading then says): outside a window's span
    /// ([`Keep::Span`]; it is then counted as seen). Only a window's pass asks for the time, so
    /// a text reader reads the rest of a row it leaves out in no pass.
    pub fn passes(&mut self, time_s: impl FnOnce() -> Option<f64>) -> bool {
        if !matches!(self.keep, Keep::Span { .. }) {
            return false;
        }
        let outside = time_s().is_some_and(|t| self.keep.outside_span(t));
        self.left_out.read += usize::from(outside);
        outside
    }

    /// The finite samples seen, whether kept or not.
    pub fn count(&self) -> usize {
        self.left_out.read
    }

    /// Goes on as if `read` finite samples had been seen: a window's pass resumed at a mark
    /// (`super::resume`), or finished with the count of the whole file.
    pub fn resume_count(&mut self, read: usize) {
        self.left_out.read = read;
    }

    /// A text file's survey: a row whose time (s) is `time_s` (`None`: not finite), whatever its
    /// values, so that a mark's times reach every row a window's pass would pass over or keep.
    pub fn row_time(&mut self, time_s: impl FnOnce() -> Option<f64>) {
        if !self.marking {
            return;
        }
        if let Some(t_s) = time_s() {
            self.timed += 1;
            self.note_time(t_s);
        }
    }

    /// A survey that sets marks: `t_s` among the times since the last mark.
    fn note_time(&mut self, t_s: f64) {
        if self.marking {
            let times = self.times.get_or_insert((t_s, t_s));
            *times = (times.0.min(t_s), times.1.max(t_s));
        }
    }

    /// A text file's survey: the rows with a finite time so far ([`Keeper::row_time`]).
    pub fn timed(&self) -> usize {
        self.timed
    }

    /// A text file's row left out for a time that is not finite.
    pub fn untimed_row(&mut self) {
        self.untimed += 1;
    }

    /// The rows left out for a time that is not finite, so far.
    pub fn untimed(&self) -> usize {
        self.untimed
    }

    /// A survey: the least and greatest time of the samples admitted since the last call.
    pub fn take_times(&mut self) -> (f64, f64) {
        self.times.take().unwrap_or(super::resume::NO_TIMES)
    }

    /// Hands what this stream (the accelerometer's) found to the pass's report: the survey's
    /// regions, or what the extract left out. `true`: a survey, which keeps no samples.
    pub fn report(&self) -> bool {
        match &self.keep {
            Keep::All { .. } | Keep::Span { .. } => false,
            Keep::Survey(report) => {
                if let Ok(mut r) = report.lock() {
                    r.regions = Some(self.survey.regions(self.still_var));
                    r.survey = Some(self.survey.clone());
                    r.temperatures = self.temperatures;
                }
                true
            }
            Keep::Within { report, .. } => {
                if let Ok(mut r) = report.lock() {
                    r.left_out = Some(self.left_out);
                }
                false
            }
        }
    }
}

/// What a stream left out under [`Keep::Within`].
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub(crate) struct LeftOut {
    /// Finite samples read.
    pub read: usize,
    /// Outside every region.
    pub outside: usize,
    /// Inside a region but beyond the budget.
    pub over_budget: usize,
    /// The time of the first sample beyond the budget.
    pub first_over_s: Option<f64>,
}

/// What a long log's extract left out, for the user: always that only the quiet stretches and the
/// turns were kept, and, when they held more than the budget, from when on they were cut.
pub(crate) fn left_out_note(
    l: &LeftOut,
    max: usize,
    regions: usize,
    option: Option<UserOption>,
    spelling: Spelling,
) -> Vec<Note> {
    let mut notes = vec![Note::LongLogKept {
        read: l.read,
        max,
        kept: l.read - l.outside - l.over_budget,
        regions,
        outside: l.outside,
    }];
    if let Some(from_s) = l.first_over_s {
        notes.push(Note::LongLogOverBudget {
            max,
            over_budget: l.over_budget,
            from_s,
            needed: l.read - l.outside,
            option,
            spelling,
        });
    }
    notes
}

/// Whether `t_s` lies in one of the sorted, disjoint `regions`.
pub(crate) fn within(regions: &[(f64, f64)], t_s: f64) -> bool {
    let k = regions.partition_point(|r| r.1 < t_s);
    regions.get(k).is_some_and(|r| r.0 <= t_s)
}

/// Count, mean and sum of squared deviations of x y z over some samples, and their time span.
#[derive(Clone, Copy, Debug, PartialEq)]
struct Block {
    t_lo: f64,
    t_hi: f64,
    n: f64,
    mean: [f64; 3],
    m2: [f64; 3],
}

impl Block {
    /// The statistics of `samples` (at least one). The span leaves out the earliest and latest
    /// stamp when there are three or more, so that one damaged stamp cannot stretch it.
    fn of(samples: &[(f64, [f64; 3])]) -> Block {
        let n = samples.len() as f64;
        let mean: [f64; 3] =
            core::array::from_fn(|j| samples.iter().map(|s| s.1[j]).sum::<f64>() / n);
        let m2 = core::array::from_fn(|j| samples.iter().map(|s| (s.1[j] - mean[j]).powi(2)).sum());
        let mut t: Vec<f64> = samples.iter().map(|s| s.0).collect();
        t.sort_by(f64::total_cmp);
        let cut = usize::from(t.len() >= 3);
        Block {
            t_lo: t[cut],
            t_hi: t[t.len() - 1 - cut],
            n,
            mean,
            m2,
        }
    }

    /// The two blocks as one (the parallel variance formula of Chan, Golub and LeVeque).
    fn merge(a: &Block, b: &Block) -> Block {
        let n = a.n + b.n;
        let d: [f64; 3] = core::array::from_fn(|j| b.mean[j] - a.mean[j]);
        Block {
            t_lo: a.t_lo.min(b.t_lo),
            t_hi: a.t_hi.max(b.t_hi),
            n,
            mean: core::array::from_fn(|j| a.mean[j] + d[j] * b.n / n),
            m2: core::array::from_fn(|j| a.m2[j] + b.m2[j] + d[j] * d[j] * a.n * b.n / n),
        }
    }

    /// The variance summed over the three axes.
    fn var(&self) -> f64 {
        self.m2.iter().sum::<f64>() / self.n
    }
}

/// A stream's block statistics, in the order the samples came, in bounded memory.
#[derive(Clone, Debug, Default)]
pub(crate) struct Survey {
    blocks: Vec<Block>,
    pending: Vec<(f64, [f64; 3])>,
    per_block: usize,
}

impl Survey {
    pub fn push(&mut self, t_s: f64, v: &[f64; 3]) {
        if self.per_block == 0 {
            self.per_block = FIRST_BLOCK;
        }
        self.pending.push((t_s, *v));
        if self.pending.len() >= self.per_block {
            self.close_block();
        }
    }

    fn close_block(&mut self) {
        if self.pending.is_empty() {
            return;
        }
        self.blocks.push(Block::of(&self.pending));
        self.pending.clear();
        if self.blocks.len() >= MAX_BLOCKS {
            self.blocks = self
                .blocks
                .chunks(2)
                .map(|c| c[1..].iter().fold(c[0], |a, b| Block::merge(&a, b)))
                .collect();
            self.per_block *= 2;
        }
    }

    /// The samples surveyed.
    pub fn count(&self) -> usize {
        let closed: f64 = self.blocks.iter().map(|b| b.n).sum();
        closed as usize + self.pending.len()
    }

    /// The blocks closed and the one still open.
    fn all_blocks(&self) -> Vec<Block> {
        let mut blocks = self.blocks.clone();
        if !self.pending.is_empty() {
            blocks.push(Block::of(&self.pending));
        }
        blocks
    }

    /// Where to cut the log into windows of about `per_window` samples each, along the blocks in
    /// time order: the start of each window after the first (increasing, s; a window's last block
    /// holding less than half `per_window` joins the one before), and the period the blocks show
    /// (the median of their spans per step, s; `None` when no block of four samples or more has a
    /// span).
    pub fn window_starts(&self, per_window: usize) -> (Vec<f64>, Option<f64>) {
        let mut blocks = self.all_blocks();
        blocks.retain(|b| b.t_lo.is_finite() && b.t_hi.is_finite());
        blocks.sort_by(|a, b| a.t_lo.total_cmp(&b.t_lo));
        let per_window = per_window as f64;
        let mut starts: Vec<f64> = Vec::new();
        let mut n = 0.0;
        for b in &blocks {
            if n >= per_window && starts.last().is_none_or(|&s| b.t_lo > s) {
                starts.push(b.t_lo);
                n = 0.0;
            }
            n += b.n;
        }
        if n < 0.5 * per_window {
            starts.pop();
        }
        // A block's span leaves out its first and last stamp (`Block::of`): n − 3 steps.
        let mut steps: Vec<f64> = blocks
            .iter()
            .filter(|b| b.n >= 4.0 && b.t_hi > b.t_lo)
            .map(|b| (b.t_hi - b.t_lo) / (b.n - 3.0))
            .collect();
        steps.sort_by(f64::total_cmp);
        (starts, steps.get(steps.len() / 2).copied())
    }

    /// The regions to keep (see the module docs): sorted, disjoint, s. `still_var`: the variance,
    /// summed over the axes, that a still unit never exceeds in the stream's unit.
    pub fn regions(&self, still_var: f64) -> Vec<(f64, f64)> {
        let blocks = self.all_blocks();
        if blocks.is_empty() {
            return Vec::new();
        }
        // The noise at rest is the quietest blocks' (no percentile: in a long log the still
        // positions may be a thousandth of it); the fourth quietest that moves at all, so that a
        // few blocks of a stuck or quantised output do not set it. A block is quiet within 10× that
        // noise's σ, or within the still limit the segmentation itself allows.
        let mut vars: Vec<f64> = blocks.iter().map(Block::var).filter(|&v| v > 0.0).collect();
        vars.sort_by(f64::total_cmp);
        let noise = vars.get(3).or(vars.last()).copied().unwrap_or(0.0);
        let quiet = |b: &Block| b.var() <= (100.0 * noise).max(still_var);
        let mut spans: Vec<(f64, f64)> = Vec::new();
        let mut run: Option<(f64, f64)> = None;
        for b in &blocks {
            run = match (quiet(b), run) {
                (true, None) => Some((b.t_lo, b.t_hi)),
                (true, Some((lo, hi))) => Some((lo.min(b.t_lo), hi.max(b.t_hi))),
                (false, Some(r)) => {
                    spans.push(r);
                    None
                }
                (false, None) => None,
            };
        }
        spans.extend(run);
        spans.retain(|s| s.0.is_finite() && s.1.is_finite());
        spans.sort_by(|a, b| a.0.total_cmp(&b.0));
        let mut regions: Vec<(f64, f64)> = Vec::with_capacity(spans.len());
        for (lo, hi) in spans {
            let (lo, hi) = (lo - MARGIN_S, hi + MARGIN_S);
            match regions.last_mut() {
                Some(last) if lo - last.1 <= MAX_MOVE_S => last.1 = last.1.max(hi),
                _ => regions.push((lo, hi)),
            }
        }
        regions
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn merged_blocks_have_the_statistics_of_their_samples() {
        let s: Vec<(f64, [f64; 3])> = (0..10)
            .map(|k| {
                let x = f64::from(k);
                (x * 0.1, [x, x * x, 9.8 - x])
            })
            .collect();
        let whole = Block::of(&s);
        let merged = Block::merge(&Block::of(&s[..3]), &Block::of(&s[3..]));
        for j in 0..3 {
            assert!((whole.mean[j] - merged.mean[j]).abs() < 1e-12);
            assert!((whole.m2[j] - merged.m2[j]).abs() < 1e-9 * whole.m2[j].max(1.0));
        }
        // By hand: x = 0..9 has mean 4.5 and Σ(x − 4.5)² = 82.5.
        assert!((merged.mean[0] - 4.5).abs() < 1e-12 && (merged.m2[0] - 82.5).abs() < 1e-9);
    }

    #[test]
    fn one_damaged_stamp_does_not_stretch_a_block() {
        let mut s: Vec<(f64, [f64; 3])> = (0..16).map(|k| (f64::from(k), [0.0; 3])).collect();
        s[7].0 = 1e9;
        let b = Block::of(&s);
        assert_eq!((b.t_lo, b.t_hi), (1.0, 15.0));
    }

    /// Rest, a 2 s turn, rest, a 100 s flight, rest: three quiet stretches, the first two joined by
    /// their turn, the flight left out. Memory stays within the block bound on a long log.
    #[test]
    fn the_regions_are_the_quiet_stretches_and_the_short_moves_between_them() {
        let rate = 100.0;
        let mut survey = Survey::default();
        let mut k = 0u64;
        let mut push = |seconds: f64, moving: bool, survey: &mut Survey| {
            for _ in 0..(seconds * rate) as u64 {
                let t = k as f64 / rate;
                // A deterministic wobble: noise of 1e-3 at rest, 1.0 when moving.
                let w = ((k * 2_654_435_761) % 1000) as f64 / 1000.0 - 0.5;
                let a = if moving { 1.0 } else { 1e-3 };
                survey.push(t, &[a * w, -a * w, 9.8 + a * w]);
                k += 1;
            }
        };
        push(10.0, false, &mut survey);
        push(2.0, true, &mut survey);
        push(10.0, false, &mut survey);
        push(100.0, true, &mut survey);
        push(10.0, false, &mut survey);
        let regions = survey.regions(STILL_VAR_M2_S4);
        assert_eq!(regions.len(), 2, "{regions:?}");
        assert!(regions[0].0 <= 0.2 && regions[0].1 >= 21.8, "{regions:?}");
        assert!(regions[0].1 < 30.0, "the flight is left out: {regions:?}");
        assert!(regions[1].0 <= 122.2 && regions[1].0 > 110.0, "{regions:?}");
        assert!(within(&regions, 11.0) && !within(&regions, 60.0) && within(&regions, 125.0));
    }

    #[test]
    fn a_survey_holds_at_most_its_block_bound() {
        let mut survey = Survey::default();
        for k in 0..(MAX_BLOCKS * FIRST_BLOCK * 3) {
            survey.push(k as f64 * 1e-3, &[0.0, 0.0, 9.8]);
        }
        assert!(survey.blocks.len() < MAX_BLOCKS);
        assert!(survey.pending.capacity() <= survey.per_block.max(FIRST_BLOCK) * 2);
        assert_eq!(survey.per_block, FIRST_BLOCK * 4);
        let n: f64 = survey.blocks.iter().map(|b| b.n).sum::<f64>() + survey.pending.len() as f64;
        assert_eq!(n as usize, MAX_BLOCKS * FIRST_BLOCK * 3);
    }
}
