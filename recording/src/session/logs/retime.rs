//! A binary log's samples re-timed at a given rate (`--rate-hz`), for a logger whose stamps are a
//! host's (a ROS driver's bursts) rather than the sensor's: each stream's n-th sample at its first
//! stamp plus n periods, and the rate the stamps themselves imply said beside it.

use crate::session::note::Note;

/// A stream re-timed at a given rate: the n-th sample (every sample read, kept or not, in file
/// order) at `t0 + n/rate`, `t0` from the first finite stamp; the stamps themselves are sampled
/// (at most [`Retime::KEPT`] of them, evenly) for the rate they imply.
#[derive(Debug)]
pub(super) struct Retime {
    pub(super) rate_hz: f64,
    period_s: f64,
    t0: Option<f64>,
    n: u64,
    /// `(n, stamp)` of every `stride`-th sample.
    stamps: Vec<(u64, f64)>,
    stride: u64,
}

impl Retime {
    const KEPT: usize = 4096;

    pub(super) fn new(rate_hz: f64) -> Retime {
        Retime {
            rate_hz,
            period_s: 1.0 / rate_hz,
            t0: None,
            n: 0,
            stamps: Vec::new(),
            stride: 1,
        }
    }

    /// Where the re-timing stands: the first sample's time and the samples re-timed (`resume`).
    pub(super) fn at(&self) -> (Option<f64>, u64) {
        (self.t0, self.n)
    }

    /// Goes on from where [`Retime::at`] stood (the stamps sampled for the implied rate are a
    /// whole pass's only).
    pub(super) fn resume(&mut self, (t0, n): (Option<f64>, u64)) {
        self.t0 = t0;
        self.n = n;
    }

    /// The time of the next sample, whose stamp is `t_s`.
    pub(super) fn next(&mut self, t_s: f64) -> f64 {
        let n = self.n;
        self.n += 1;
        if t_s.is_finite() {
            self.t0.get_or_insert(t_s - n as f64 * self.period_s);
            self.keep_stamp(n, t_s);
        }
        self.t0.unwrap_or(0.0) + n as f64 * self.period_s
    }

    /// Keeps `(n, t_s)` when `n` is on the stride; a full store keeps every other stamp and samples
    /// half as often from then on.
    fn keep_stamp(&mut self, n: u64, t_s: f64) {
        if self.stamps.len() == Self::KEPT {
            let mut k = 0;
            self.stamps.retain(|_| {
                k += 1;
                k % 2 == 1
            });
            self.stride *= 2;
        }
        if n % self.stride == 0 {
            self.stamps.push((n, t_s));
        }
    }

    /// The rate the stamps imply, Hz: the mean of the middle half of the slopes between each
    /// sampled stamp and the one half the samples later (robust to a few damaged stamps; the
    /// mean, not the median, so that bursts' steps average out instead of rounding the slope to
    /// one of two burst-quantised values).
    pub(super) fn implied_rate_hz(&self) -> Option<f64> {
        let half = self.stamps.len() / 2;
        let mut slopes: Vec<f64> = (0..half)
            .map(|i| {
                let ((n0, t0), (n1, t1)) = (self.stamps[i], self.stamps[i + half]);
                (t1 - t0) / (n1 - n0) as f64
            })
            .filter(|s| s.is_finite() && *s > 0.0)
            .collect();
        slopes.sort_by(f64::total_cmp);
        let (lo, hi) = (slopes.len() / 4, slopes.len() - slopes.len() / 4);
        let middle = slopes.get(lo..hi).filter(|m| !m.is_empty())?;
        Some(middle.len() as f64 / middle.iter().sum::<f64>())
    }
}

/// What a log re-timed at a given rate says: that rate beside the one its stamps imply.
pub(super) fn retime_note((given_hz, implied_hz): (f64, Option<f64>)) -> Note {
    Note::Retimed {
        given_hz,
        implied_hz,
    }
}
