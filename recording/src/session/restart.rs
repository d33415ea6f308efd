//! Logs joined one after the other, each with its own clock: the time stamps restart (at 0, or
//! wherever the next logger started) and step on evenly from there. Sorted into time order, the
//! two logs' samples would be interleaved into one that jumps between two attitudes every sample;
//! read as what they are, each later log is moved to follow the one before it, a gap apart, and
//! said so (`super::repair`, rule 0).

use super::import::GAP_PERIODS;

/// Samples after a step back that must step evenly forward for it to be a log's start, not a
/// stamp (or a short burst of stamps) damaged: a quarter of a second at 256 Hz.
const RESTART_RUN: usize = 64;
/// Samples before it that must step evenly: the end of the log before.
const BEFORE_RUN: usize = 4;
/// A step is even within this many periods.
const EVEN_PERIODS: f64 = 1.5;
/// Periods between a log and the next once joined: more than a gap ([`GAP_PERIODS`]), so that no
/// still interval spans the join and no turn is integrated across it.
pub(crate) const JOIN_PERIODS: f64 = 2.0 * GAP_PERIODS;

/// A log's start found inside the samples: its place (the sample's index in the file), the
/// stamp it was read with and the time it was moved by, s.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Restart {
    /// The first sample of the later log (0-based place in the file).
    pub index: usize,
    /// Its stamp as read, s.
    pub read_s: f64,
    /// The time added to it and every sample after it, s.
    pub moved_s: f64,
}

/// The restarts in `order` (samples in reading order: place, time) at median step `dt`, each
/// later log moved to start [`JOIN_PERIODS`] after the one before it ends; the restarts found.
pub(crate) fn join_restarts(order: &mut [(usize, f64)], dt: f64) -> Vec<Restart> {
    let even = |w: &[(usize, f64)]| {
        w.windows(2)
            .all(|p| p[1].1 - p[0].1 > 0.0 && p[1].1 - p[0].1 <= EVEN_PERIODS * dt)
    };
    let mut found = Vec::new();
    let mut moved = 0.0;
    for r in BEFORE_RUN..order.len() {
        order[r].1 += moved;
        let back = order[r - 1].1 - order[r].1;
        if back <= GAP_PERIODS * dt
            || r + RESTART_RUN > order.len()
            || !even(&order[r - BEFORE_RUN..r])
        {
            continue;
        }
        // The run after it, not yet moved.
        let run: Vec<(usize, f64)> = order[r..r + RESTART_RUN]
            .iter()
            .enumerate()
            .map(|(k, &(i, t))| (i, if k == 0 { t } else { t + moved }))
            .collect();
        if !even(&run) {
            continue;
        }
        let shift = back + JOIN_PERIODS * dt;
        found.push(Restart {
            index: order[r].0,
            read_s: order[r].1 - moved,
            moved_s: moved + shift,
        });
        order[r].1 += shift;
        moved += shift;
    }
    found
}

#[cfg(test)]
mod tests {
    use super::*;

    fn order(t: &[f64]) -> Vec<(usize, f64)> {
        t.iter().copied().enumerate().collect()
    }

    #[test]
    fn two_logs_joined_follow_each_other_and_a_damaged_stamp_or_a_short_burst_is_no_restart() {
        let dt = 0.005;
        let first: Vec<f64> = (0..1000).map(|k| k as f64 * dt).collect();
        let mut t = first.clone();
        t.extend(first.iter().map(|x| x + 0.5));
        let mut o = order(&t);
        let found = join_restarts(&mut o, dt);
        assert_eq!(found.len(), 1, "{found:?}");
        assert_eq!(found[0].index, 1000);
        assert_eq!(found[0].read_s, 0.5);
        // The second log starts JOIN_PERIODS after the first one's last sample.
        let join = o[1000].1 - o[999].1;
        assert!((join - JOIN_PERIODS * dt).abs() < 1e-9, "{join}");
        assert!(o.windows(2).all(|w| w[1].1 > w[0].1));
        // A stamp that jumps back and returns, and 20 stamps back by a second: not a restart.
        for burst in [1, 20] {
            let mut t = first.clone();
            t[500..500 + burst].iter_mut().for_each(|x| *x -= 1.0);
            let mut o = order(&t);
            assert!(join_restarts(&mut o, dt).is_empty(), "{burst}");
            assert_eq!(o, order(&t));
        }
    }
}
