//! Where a long log's windows begin in the file, so that each window's pass reads its own stretch
//! of the file rather than the whole file again (`windows`): `apply` on a log of twice the size
//! then takes about twice the time, not four times.
//!
//! The survey ([`Keep::Survey`]) sets a [`Mark`] every [`mark_every`] samples: the byte where a
//! message (a record, a line) begins, the reader's state before it (what it must know to read on
//! from there: the format definitions, the subscriptions, each stream's count and re-timing) and
//! the least and greatest time of the samples read from there to the next mark. At its end the
//! survey keeps what the reader found in the whole file (its counts, its notes, the vehicle's
//! parameters): its [`Resume`].
//!
//! A window's pass then reads only the stretches between marks whose samples' times reach its own
//! (with its margin), resuming the reader at each, and finishes with the survey's end state and
//! the samples it kept. A sample outside those stretches has a time outside the window's reach, so
//! that a whole pass would not have kept it either: the window holds the same samples, with the
//! same places in the file, and says the same, as a pass over the whole file.

use super::keep::Keep;
use std::sync::Arc;

/// Marks per budget of samples: a window (half the budget) spans about four stretches, so that a
/// window reads at most about a quarter of a budget more than its own samples at either end.
const MARKS_PER_BUDGET: usize = 8;

/// The samples (summed over a reader's streams) between two marks for a window budget of `max`.
pub(crate) fn mark_every(max: usize) -> usize {
    (max / MARKS_PER_BUDGET).max(16)
}

/// A place in the file a reader can resume from.
#[derive(Clone, Debug)]
pub(crate) struct Mark<M> {
    /// The byte where a message begins.
    pub offset: u64,
    /// The reader's state before it.
    pub state: M,
    /// The least and greatest time of the samples read from here to the next mark, s (the least
    /// greater than the greatest: none).
    pub times: (f64, f64),
}

/// No time at all, for [`Mark::times`].
pub(crate) const NO_TIMES: (f64, f64) = (f64::INFINITY, f64::NEG_INFINITY);

/// `a` and `b` as one span of times.
pub(crate) fn join(a: (f64, f64), b: (f64, f64)) -> (f64, f64) {
    (a.0.min(b.0), a.1.max(b.1))
}

/// The marks a survey sets as it reads.
#[derive(Debug)]
pub(crate) struct Marker<M> {
    every: usize,
    next: usize,
    marks: Vec<Mark<M>>,
}

impl<M> Marker<M> {
    /// A marker for a pass that keeps what `keep` says: a survey asked for marks sets them, any
    /// other pass none.
    pub fn for_keep(keep: &Keep) -> Option<Marker<M>> {
        let Keep::Survey(report) = keep else {
            return None;
        };
        let every = report.lock().map_or(0, |r| r.marks_every);
        (every > 0).then(|| Marker {
            every,
            next: 0,
            marks: Vec::new(),
        })
    }

    /// Whether a mark is due when `read` samples have been read.
    pub fn due(&self, read: usize) -> bool {
        read >= self.next
    }

    /// A mark at `offset` with the reader's `state`; `times`: those of the samples read since the
    /// last mark.
    /// The first mark's times start with those read before it (a header-less text file's first
    /// row), so that a window they reach reads from there.
    pub fn set(&mut self, offset: u64, state: M, times: (f64, f64), read: usize) {
        let first = match self.marks.last_mut() {
            Some(last) => {
                last.times = times;
                NO_TIMES
            }
            None => times,
        };
        self.marks.push(Mark {
            offset,
            state,
            times: first,
        });
        self.next = read + self.every;
    }

    /// The marks, the last one's times those of the samples read since it.
    pub fn finish(mut self, times: (f64, f64)) -> Vec<Mark<M>> {
        if let Some(last) = self.marks.last_mut() {
            last.times = join(last.times, times);
        }
        self.marks
    }
}

/// The stretches of the file a window whose samples lie in `lo..hi` (s, its margin included) must
/// read: each the index of the mark it starts at and the byte it ends before (`None`: the end of
/// the file). Neighbouring stretches are read as one.
pub(crate) fn stretches<M>(marks: &[Mark<M>], lo: f64, hi: f64) -> Vec<(usize, Option<u64>)> {
    let mut out: Vec<(usize, Option<u64>)> = Vec::new();
    let mut open: Option<usize> = None;
    for (i, m) in marks.iter().enumerate() {
        let reaches = m.times.0 < hi && m.times.1 >= lo;
        match (reaches, open) {
            (true, None) => open = Some(i),
            (false, Some(start)) => {
                out.push((start, Some(m.offset)));
                open = None;
            }
            _ => {}
        }
    }
    if let Some(start) = open {
        out.push((start, None));
    }
    out
}

/// What a survey leaves for the windows' passes: its marks and its end state, per format.
#[derive(Debug)]
pub(crate) enum Resume {
    /// A PX4 ULog.
    Ulog(super::ulog::Resume),
    /// An ArduPilot DataFlash log.
    DataFlash(super::dataflash::Resume),
    /// A ROS 2 bag in MCAP.
    Mcap(super::mcap::Resume),
    /// A logger's text file.
    Text(crate::session::import::Resume),
}

/// A survey's [`Resume`], shared by the windows.
pub(crate) type SharedResume = Arc<Resume>;

#[cfg(test)]
mod tests {
    use super::*;

    fn mark(offset: u64, times: (f64, f64)) -> Mark<()> {
        Mark {
            offset,
            state: (),
            times,
        }
    }

    #[test]
    fn a_window_reads_the_stretches_whose_times_reach_it_and_a_far_stamps_one() {
        let marks = [
            mark(10, (0.0, 9.9)),
            mark(100, (10.0, 19.9)),
            // A stamp damaged far ahead: this stretch reaches every later window.
            mark(200, (20.0, 500.0)),
            mark(300, (30.0, 39.9)),
            mark(400, (40.0, 49.9)),
            mark(500, NO_TIMES),
        ];
        assert_eq!(stretches(&marks, -1.0, 12.0), [(0, Some(200))]);
        assert_eq!(
            stretches(&marks, 41.0, 45.0),
            [(2, Some(300)), (4, Some(500))]
        );
        assert_eq!(stretches(&marks, 38.0, 1e9), [(2, Some(500))]);
        assert_eq!(stretches(&marks, f64::NEG_INFINITY, 0.5), [(0, Some(100))]);
        assert!(stretches(&marks, 600.0, 700.0).is_empty());
        assert_eq!(
            stretches(&marks[..5], 45.0, 46.0),
            [(2, Some(300)), (4, None)]
        );
    }
}
