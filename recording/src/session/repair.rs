//! The time repair every reader's samples pass through before they are paired and segmented (text,
//! ULog, DataFlash and MCAP alike), by stated rules (docs/robustness.md, "Damaged time stamps"):
//!
//! 0. Logs joined one after the other, the stamps restarting, are read as such: each later log is
//!    moved to follow the one before it (`super::restart`).
//! 1. A log written newest first (most steps negative) is read in reverse.
//! 2. An isolated stamp that jumps away and comes back (a flipped bit, a logger's glitch) is that
//!    sample's error: where the neighbours on both sides agree where it should be and it is more
//!    than 1.5 periods from there, it is re-timed from them; at either end of the log, where one
//!    side has no neighbours, a stamp more than a gap away from them is dropped.
//! 3. A local reordering (messages swapped in a recorder's queue) is sorted.
//! 4. An exact repeat (the same stamp and the same values) is dropped; samples with a repeated stamp
//!    but their own values are spread evenly up to the next stamp.
//! 5. Jitter is kept; the rate is the mean over the steps that are no gap (`run_rate_hz`), which
//!    neither jitter nor a dropout biases; a real gap (more than [`GAP_PERIODS`] periods) stays a
//!    gap, and segmentation neither spans nor integrates across it.
//!
//! The rule these keep: **a damaged sample costs at most that sample**, never the rest of the log.
//! Every repair is counted and its first places named.

use super::import::GAP_PERIODS;
use super::restart::join_restarts;
pub use super::restart::Restart;

/// Neighbours on each side that say where a sample should be.
const NEIGHBOURS: usize = 4;
/// A stamp further than this many periods from where its neighbours put it is that sample's error.
const OUTLIER_PERIODS: f64 = 1.5;
/// Places named per kind of repair.
const PLACES: usize = 3;

/// What the repair did, by kind; indices are the samples' places in the file (0-based).
#[derive(Clone, Debug, Default, PartialEq)]
pub struct TimeRepairs {
    /// The log was written newest first and is read in reverse.
    pub reversed: bool,
    /// Isolated stamps re-timed from their neighbours: (index, stamp read, time given), s.
    pub retimed: Vec<(usize, f64, f64)>,
    /// Isolated stamps at an end of the log, dropped: (index, stamp read), s.
    pub dropped: Vec<(usize, f64)>,
    /// Samples moved by the sort of a local reordering.
    pub reordered: usize,
    /// Exact repeats dropped (index).
    pub repeats: Vec<usize>,
    /// Samples with a repeated stamp and values of their own, spread up to the next stamp (index).
    pub spread: Vec<usize>,
    /// Stamps that came in bursts, re-timed from the fit of stamp against index.
    pub bursts: Option<super::bursts::Bursts>,
    /// Where a log joined after another starts, its stamps restarting (rule 0).
    pub restarts: Vec<Restart>,
}

impl TimeRepairs {
    /// Samples the repair left out (each a damaged one).
    pub fn lost(&self) -> usize {
        self.dropped.len() + self.repeats.len()
    }

    /// Whether nothing was repaired.
    pub fn is_empty(&self) -> bool {
        *self == TimeRepairs::default()
    }

    /// The repairs said for the user, `what` naming a sample ("message", "data row"), with the
    /// first places of each kind (1-based, as a person counts them).
    pub fn describe(&self, what: &str) -> Option<String> {
        self.said(Some(what))
    }

    /// The repairs said by kind and count alone, for the samples of one window of a long log,
    /// whose places in the file are not known.
    pub fn count(&self) -> Option<String> {
        self.said(None)
    }

    /// [`TimeRepairs::describe`], the places of each kind only where `what` names the samples.
    pub(crate) fn said(&self, what: Option<&str>) -> Option<String> {
        if self.is_empty() {
            return None;
        }
        // " (message 12 stamped …, …)" where the places are known.
        let at = |list: String| match what {
            Some(_) => format!(" ({list})"),
            None => String::new(),
        };
        // Without places, the samples are a window's, whose ends are not the log's.
        let end = if what.is_some() { "log" } else { "window" };
        let what = what.unwrap_or_default();
        let mut parts = Vec::new();
        if self.reversed {
            parts.push("the log was written newest first: read in reverse".to_string());
        }
        if !self.restarts.is_empty() {
            let places = places(self.restarts.iter(), |r| {
                format!(
                    "{what} {} stamped {:.6} s, moved {:+.6} s",
                    r.index + 1,
                    r.read_s,
                    r.moved_s
                )
            });
            parts.push(format!(
                "the stamps restart {} time(s), as in logs joined one after the other: each later \
                 log is read after the one before it, {} periods after its last sample{}",
                self.restarts.len(),
                super::restart::JOIN_PERIODS,
                at(places)
            ));
        }
        if !self.retimed.is_empty() {
            let places = places(self.retimed.iter(), |&(i, read, given)| {
                format!(
                    "{what} {} stamped {read:.6} s, re-timed to {given:.6} s",
                    i + 1
                )
            });
            parts.push(format!(
                "{} isolated stamp(s) that jumped and came back re-timed from their neighbours{}",
                self.retimed.len(),
                at(places)
            ));
        }
        if !self.dropped.is_empty() {
            let places = places(self.dropped.iter(), |&(i, read)| {
                format!("{what} {} stamped {read:.6} s", i + 1)
            });
            parts.push(format!(
                "{} stamp(s) at an end of the {end} far from their neighbours left out{}",
                self.dropped.len(),
                at(places)
            ));
        }
        if self.reordered > 0 {
            parts.push(format!(
                "{} sample(s) out of order sorted into time order",
                self.reordered
            ));
        }
        if !self.repeats.is_empty() {
            let places = places(self.repeats.iter(), |&i| format!("{what} {}", i + 1));
            parts.push(format!(
                "{} exact repeat(s) (same stamp, same values) left out{}",
                self.repeats.len(),
                at(places)
            ));
        }
        if !self.spread.is_empty() {
            let places = places(self.spread.iter(), |&i| format!("{what} {}", i + 1));
            parts.push(format!(
                "{} sample(s) with a repeated stamp but values of their own spread evenly up to \
                 the next stamp{}",
                self.spread.len(),
                at(places)
            ));
        }
        if let Some(b) = &self.bursts {
            parts.push(b.describe(if what.is_empty() { "sample" } else { what }));
        }
        Some(format!("time stamps repaired: {}", parts.join("; ")))
    }
}

fn places<'a, T: 'a>(items: impl Iterator<Item = &'a T>, f: impl Fn(&T) -> String) -> String {
    let v: Vec<&T> = items.collect();
    let mut s: Vec<String> = v.iter().take(PLACES).map(|x| f(x)).collect();
    if v.len() > PLACES {
        s.push("…".into());
    }
    s.join(", ")
}

/// The repaired order: `(index in the file, time s)` of each sample kept, in time order, and what
/// was done. `same(i, j)`: samples `i` and `j` hold the same values (an exact repeat when their
/// stamps are equal too). Non-finite stamps are the reader's to leave out before this.
pub(crate) fn repair_times(
    t_s: &[f64],
    same: impl Fn(usize, usize) -> bool,
) -> (Vec<(usize, f64)>, TimeRepairs) {
    let mut rep = TimeRepairs::default();
    let mut order: Vec<(usize, f64)> = t_s.iter().copied().enumerate().collect();
    if order.len() < 3 {
        return (order, rep);
    }
    let back = t_s.windows(2).filter(|w| w[1] < w[0]).count();
    let forward = t_s.windows(2).filter(|w| w[1] > w[0]).count();
    if back > forward {
        order.reverse();
        rep.reversed = true;
    }
    let times: Vec<f64> = order.iter().map(|s| s.1).collect();
    let Some(dt) = median_step(&times) else {
        return (order, rep);
    };
    // The period to 9 digits: the median step of a clean log is its period give or take the last
    // bits of the stamps' subtraction, which differ between a whole log and a window of it; a
    // sample re-timed from it is then re-timed alike in both.
    let dt = format!("{dt:.8e}").parse().unwrap_or(dt);
    rep.restarts = join_restarts(&mut order, dt);
    isolated_stamps(&mut order, dt, &mut rep);
    let before: Vec<usize> = order.iter().map(|s| s.0).collect();
    order.sort_by(|a, b| a.1.total_cmp(&b.1));
    rep.reordered = before
        .iter()
        .zip(&order)
        .filter(|(a, b)| **a != b.0)
        .count();
    repeated_stamps(&mut order, &same, &mut rep);
    (order, rep)
}

/// A text file's rows in time order, their stamps mended (`repair_times`; rows whose values
/// and stamps are equal are exact repeats), and the repairs kept with them as "data row"s.
pub fn repair_rows(rec: &mut super::import::Recording) {
    repair_rows_saying(rec, |_, _, repairs| repairs);
}

/// [`repair_rows`], the repairs kept as `say` has them from the repaired order, the stamps read
/// and the repairs (a window of a long log says them on the log's scale, `super::logs`).
pub(crate) fn repair_rows_saying(
    rec: &mut super::import::Recording,
    say: impl FnOnce(&[(usize, f64)], &[f64], TimeRepairs) -> TimeRepairs,
) {
    let temp = |i: usize| rec.temp_c.as_ref().map(|t| t[i].to_bits());
    let (order, repairs) = repair_times(&rec.t_s, |i, j| {
        rec.acc[i] == rec.acc[j] && rec.gyro_rad_s[i] == rec.gyro_rad_s[j] && temp(i) == temp(j)
    });
    let repairs = say(&order, &rec.t_s, repairs);
    rec.t_s = order.iter().map(|s| s.1).collect();
    rec.acc = order.iter().map(|s| rec.acc[s.0]).collect();
    rec.gyro_rad_s = order.iter().map(|s| rec.gyro_rad_s[s.0]).collect();
    if let Some(t) = &rec.temp_c {
        rec.temp_c = Some(order.iter().map(|s| t[s.0]).collect());
    }
    if !repairs.is_empty() {
        rec.time_repairs.push(("data row", repairs));
    }
}

/// The median of the positive steps, s (`None` when no step is).
pub(crate) fn median_step(t_s: &[f64]) -> Option<f64> {
    let mut dt: Vec<f64> = t_s
        .windows(2)
        .map(|w| w[1] - w[0])
        .filter(|d| *d > 0.0)
        .collect();
    if dt.is_empty() {
        return None;
    }
    dt.sort_by(f64::total_cmp);
    Some(dt[dt.len() / 2])
}

/// Where the neighbours `js` put sample `i` (the median of their stamps moved by `dt` per place).
fn predicted(order: &[(usize, f64)], i: usize, js: std::ops::Range<usize>, dt: f64) -> Option<f64> {
    let mut p = [0.0; NEIGHBOURS];
    let mut n = 0;
    for j in js.take(NEIGHBOURS) {
        p[n] = order[j].1 + (i as f64 - j as f64) * dt;
        n += 1;
    }
    let p = &mut p[..n];
    p.sort_by(f64::total_cmp);
    let m = n / 2;
    match n {
        0 => None,
        _ if n % 2 == 1 => Some(p[m]),
        _ => Some(0.5 * (p[m - 1] + p[m])),
    }
}

/// Rule 2 of the module docs, in file order.
fn isolated_stamps(order: &mut Vec<(usize, f64)>, dt: f64, rep: &mut TimeRepairs) {
    let n = order.len();
    let tol = OUTLIER_PERIODS * dt;
    let mut fixes: Vec<(usize, Option<f64>)> = Vec::new();
    for i in 0..n {
        let left = predicted(order, i, i.saturating_sub(NEIGHBOURS)..i, dt);
        let right = predicted(order, i, i + 1..(i + 1 + NEIGHBOURS).min(n), dt);
        let t = order[i].1;
        let off = |p: f64| (t - p).abs() > tol;
        let far = |p: f64| (t - p).abs() > GAP_PERIODS * dt;
        match (left, right) {
            (Some(l), Some(r)) if (l - r).abs() <= tol && off(l) && off(r) => {
                fixes.push((i, Some(0.5 * (l + r))));
            }
            // At an end, one side cannot tell a damaged stamp from a dropout: only a stamp further
            // off than a gap is that sample's error (a nearer one stays, a short gap at most).
            (None, Some(p))
                if far(p) && steps_evenly(&order[i + 1..(i + 1 + NEIGHBOURS).min(n)], dt) =>
            {
                fixes.push((i, None));
            }
            (Some(p), None)
                if far(p) && steps_evenly(&order[i.saturating_sub(NEIGHBOURS)..i], dt) =>
            {
                fixes.push((i, None));
            }
            _ => {}
        }
    }
    for &(i, given) in fixes.iter().rev() {
        let (index, read) = order[i];
        match given {
            Some(g) => {
                order[i].1 = g;
                rep.retimed.push((index, read, g));
            }
            None => {
                order.remove(i);
                rep.dropped.push((index, read));
            }
        }
    }
    rep.retimed.reverse();
    rep.dropped.reverse();
}

/// Whether the neighbours on the one side an end sample has step evenly among themselves (so
/// that the sample, not a gap among them, is what is off).
fn steps_evenly(side: &[(usize, f64)], dt: f64) -> bool {
    side.len() >= 2
        && side
            .windows(2)
            .all(|w| w[1].1 - w[0].1 > 0.0 && w[1].1 - w[0].1 <= OUTLIER_PERIODS * dt)
}

/// Rule 4 of the module docs, on the sorted samples.
fn repeated_stamps(
    order: &mut Vec<(usize, f64)>,
    same: &impl Fn(usize, usize) -> bool,
    rep: &mut TimeRepairs,
) {
    let mut out: Vec<(usize, f64)> = Vec::with_capacity(order.len());
    let mut k = 0;
    while k < order.len() {
        let t = order[k].1;
        let mut end = k + 1;
        while end < order.len() && order[end].1 == t {
            end += 1;
        }
        let mut group: Vec<(usize, f64)> = Vec::new();
        for &s in &order[k..end] {
            if group.iter().any(|g| same(g.0, s.0)) {
                rep.repeats.push(s.0);
            } else {
                group.push(s);
            }
        }
        let next = order.get(end).map(|s| s.1);
        match next {
            Some(next) if group.len() > 1 => {
                let step = (next - t) / group.len() as f64;
                for (m, s) in group.iter_mut().enumerate().skip(1) {
                    s.1 = t + m as f64 * step;
                    rep.spread.push(s.0);
                }
                out.extend(group);
            }
            // The last stamp repeated with other values: nothing after it to spread them up to.
            None if group.len() > 1 => {
                rep.repeats.extend(group.iter().skip(1).map(|s| s.0));
                out.push(group[0]);
            }
            _ => out.extend(group),
        }
        k = end;
    }
    *order = out;
}

/// The rate over the steps that are no gap (at most [`GAP_PERIODS`] median periods), each counted
/// as the whole number of periods it spans, Hz (0 for fewer than two samples): a dropout of one
/// sample is two periods, not a slower clock, and jitter averages out, where the median step of
/// jittered stamps is off by a part of the jitter.
pub(crate) fn run_rate_hz(t_s: &[f64]) -> f64 {
    let Some(dt) = median_step(t_s) else {
        return 0.0;
    };
    let (periods, span) = t_s
        .windows(2)
        .map(|w| w[1] - w[0])
        .filter(|d| *d > 0.0 && *d <= GAP_PERIODS * dt)
        .fold((0.0, 0.0), |(n, s), d| {
            (n + (d / dt).round().max(1.0), s + d)
        });
    periods / span
}

#[cfg(test)]
mod tests {
    use super::*;

    fn grid(n: usize) -> Vec<f64> {
        (0..n).map(|i| 100.0 + i as f64 * 0.005).collect()
    }

    fn kept(t: &[f64]) -> (Vec<usize>, Vec<f64>, TimeRepairs) {
        let (order, rep) = repair_times(t, |_, _| false);
        (
            order.iter().map(|s| s.0).collect(),
            order.iter().map(|s| s.1).collect(),
            rep,
        )
    }

    #[test]
    fn a_clean_log_is_left_as_it_is() {
        let t = grid(1000);
        let (idx, times, rep) = kept(&t);
        assert!(rep.is_empty(), "{rep:?}");
        assert_eq!(idx, (0..1000).collect::<Vec<_>>());
        assert_eq!(times, t);
    }

    #[test]
    fn a_stamp_that_jumps_and_comes_back_is_re_timed_in_the_middle_and_dropped_at_an_end() {
        for (at, delta) in [(500, 1e6), (500, -50.0), (500, 0.02), (0, 3.0), (999, -3.0)] {
            let mut t = grid(1000);
            t[at] += delta;
            let (idx, times, rep) = kept(&t);
            if at == 0 || at == 999 {
                assert_eq!(rep.dropped, [(at, t[at])], "{at} {delta}");
                assert_eq!(idx.len(), 999);
            } else {
                assert_eq!(rep.retimed.len(), 1, "{rep:?}");
                assert_eq!(idx, (0..1000).collect::<Vec<_>>());
                assert!((times[at] - grid(1000)[at]).abs() < 1e-9);
            }
        }
    }

    #[test]
    fn swaps_are_sorted_repeats_dropped_and_a_reversed_log_read_backwards() {
        let mut t = grid(1000);
        t.swap(10, 11);
        let (idx, _, rep) = kept(&t);
        assert_eq!(rep.reordered, 2);
        assert_eq!(idx.len(), 1000);
        let mut rev = grid(1000);
        rev.reverse();
        let (idx, times, rep) = kept(&rev);
        assert!(rep.reversed && idx.len() == 1000);
        assert!(times.windows(2).all(|w| w[1] > w[0]));
        // Every row twice, with the same values.
        let t: Vec<f64> = grid(1000).iter().flat_map(|&x| [x, x]).collect();
        let (order, rep) = repair_times(&t, |_, _| true);
        assert_eq!(rep.repeats.len(), 1000);
        assert_eq!(order.len(), 1000);
    }

    #[test]
    fn a_repeated_stamp_with_new_values_is_spread_and_jitter_and_gaps_are_kept() {
        let mut t = grid(1000);
        t[300] = t[299];
        let (idx, times, rep) = kept(&t);
        assert_eq!(rep.spread, [300]);
        assert_eq!(idx.len(), 1000);
        assert!(times.windows(2).all(|w| w[1] > w[0]));
        let mut t = grid(1000);
        for (i, x) in t.iter_mut().enumerate() {
            *x += 1e-3 * ((i * 7919 % 13) as f64 / 6.0 - 1.0);
        }
        for x in &mut t[600..] {
            *x += 2.0;
        }
        let (idx, _, rep) = kept(&t);
        assert!(rep.is_empty(), "{rep:?}");
        assert_eq!(idx.len(), 1000);
        assert!(
            (run_rate_hz(&t) - 200.0).abs() < 0.05,
            "{}",
            run_rate_hz(&t)
        );
    }
}
