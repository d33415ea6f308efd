//! Time stamps as host-stamped loggers write them: a serial reader or a ROS driver stamps each
//! sample when the host reads it, and the host reads them in bursts, so that many samples share (or
//! nearly share) a stamp and then a gap follows. The median step of such stamps is the host's read
//! loop, not the sensor's period (2 ms for a sensor at 99.3 Hz), and a still stretch looks like
//! motion through a sample's wrong time.
//!
//! The sensor's period is the slope of a robust fit of stamp against sample index: the median over
//! the log of `(t[i + k] − t[i]) / k`, with `k` spanning several bursts, which neither a burst nor an
//! occasional gap moves. Where most steps are far shorter than that period and the rest are gaps of
//! several periods, the stamps are bursts: each piece between real dropouts is re-timed on the
//! fitted period from the piece's mean offset, and the log says so with both rates.

/// A step shorter than this part of the fitted period is within a burst.
const IN_BURST: f64 = 0.5;
/// A step longer than this many fitted periods ends a burst.
const BURST_GAP: f64 = 2.0;
/// Fewest samples in which bursts are looked for.
const MIN_SAMPLES: usize = 32;

/// Bursts found and re-timed.
#[derive(Clone, Debug, PartialEq)]
pub struct Bursts {
    /// Bursts found (runs of samples between two gaps).
    pub bursts: usize,
    /// The rate the fit of stamp against index gives, Hz.
    pub fitted_rate_hz: f64,
    /// The rate the median step would have given, Hz (infinite where it is zero).
    pub median_step_hz: f64,
    /// Pieces re-timed on their own (split at real dropouts).
    pub pieces: usize,
}

impl Bursts {
    /// Said for the user; `what` names a sample ("data row", "IMU sample").
    pub fn describe(&self, what: &str) -> String {
        let median = if self.median_step_hz.is_finite() {
            format!("{:.1} Hz", self.median_step_hz)
        } else {
            "no rate at all (a zero step)".to_string()
        };
        format!(
            "the time stamps come in {} bursts (samples sharing or nearly sharing a stamp, then a \
             gap, as a host stamps what it reads in batches): the {what}s are re-timed at the \
             {:.3} Hz a fit of stamp against sample index gives (their median step would say {median})",
            self.bursts, self.fitted_rate_hz
        )
    }
}

fn median(mut v: Vec<f64>) -> Option<f64> {
    if v.is_empty() {
        return None;
    }
    v.sort_by(f64::total_cmp);
    Some(v[v.len() / 2])
}

/// The period a robust fit of stamp against sample index gives, s: the median of
/// `(t[i + k] − t[i]) / k` over the log, `k` a sixteenth of it (at most 512 samples).
pub(crate) fn fitted_period_s(t_s: &[f64]) -> Option<f64> {
    let n = t_s.len();
    if n < 4 {
        return None;
    }
    let k = (n / 16).clamp(1, 512);
    let stride = ((n - k) / 20_000).max(1);
    let slopes: Vec<f64> = (0..n - k)
        .step_by(stride)
        .map(|i| (t_s[i + k] - t_s[i]) / k as f64)
        .filter(|d| *d > 0.0)
        .collect();
    median(slopes)
}

/// The period from the first samples of bursts a sixteenth of the log apart: the median of
/// `(t[s_(b+L)] − t[s_b]) / (s_(b+L) − s_b)`, which a dropout moves only for the pairs that span it.
fn burst_period_s(t_s: &[f64], starts: &[usize]) -> Option<f64> {
    let lag = (starts.len() / 16).max(1);
    let slopes: Vec<f64> = starts
        .iter()
        .zip(starts.iter().skip(lag))
        .map(|(&a, &b)| (t_s[b] - t_s[a]) / (b - a) as f64)
        .filter(|d| *d > 0.0)
        .collect();
    median(slopes)
}

/// Re-times `t_s` (sorted) where it comes in bursts (module docs); `None` where it does not.
pub(crate) fn retime_bursts(t_s: &mut [f64]) -> Option<Bursts> {
    let n = t_s.len();
    if n < MIN_SAMPLES {
        return None;
    }
    let p = fitted_period_s(t_s)?;
    let steps: Vec<f64> = t_s.windows(2).map(|w| w[1] - w[0]).collect();
    let m = median(steps.clone())?;
    let gaps: Vec<f64> = steps
        .iter()
        .copied()
        .filter(|d| *d > BURST_GAP * p)
        .collect();
    // Most steps within a burst, and gaps between them at least every 64 samples.
    if m >= IN_BURST * p || gaps.len() * 64 < n {
        return None;
    }
    // Each burst starts a gap after the last; the first samples of bursts far apart fit the
    // period without the bursts' own spread (a burst's samples share its read's stamp).
    let starts: Vec<usize> = (1..n).filter(|&i| steps[i - 1] > BURST_GAP * p).collect();
    let p = burst_period_s(t_s, &starts).unwrap_or(p);
    // A dropout is a gap far longer than the bursts' own.
    let typical = median(gaps.clone())?;
    let dropout = 4.0 * typical + super::import::GAP_PERIODS * p;
    let mut pieces = Vec::new();
    let mut start = 0;
    for (i, d) in steps.iter().enumerate() {
        if *d > dropout {
            pieces.push(start..i + 1);
            start = i + 1;
        }
    }
    pieces.push(start..n);
    for r in &pieces {
        let len = r.len() as f64;
        let offset = r
            .clone()
            .map(|i| t_s[i] - p * (i - r.start) as f64)
            .sum::<f64>()
            / len;
        for i in r.clone() {
            t_s[i] = offset + p * (i - r.start) as f64;
        }
    }
    Some(Bursts {
        bursts: gaps.len() + 1,
        fitted_rate_hz: 1.0 / p,
        median_step_hz: if m > 0.0 { 1.0 / m } else { f64::INFINITY },
        pieces: pieces.len(),
    })
}

/// A text file's rows re-timed where their stamps come in bursts, said beside the file's other
/// time repairs ("data row").
pub(crate) fn retime_rows(rec: &mut super::import::Recording) {
    let Some(b) = retime_bursts(&mut rec.t_s) else {
        return;
    };
    match rec
        .time_repairs
        .iter_mut()
        .find(|(what, _)| *what == "data row")
    {
        Some((_, r)) => r.bursts = Some(b),
        None => rec.time_repairs.push((
            "data row",
            super::repair::TimeRepairs {
                bursts: Some(b),
                ..Default::default()
            },
        )),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A sensor at `rate_hz` read by a host every `every` samples, each read stamped at the host's
    /// clock with 2 ms between the samples of one read (its serial loop), plus a read latency.
    fn host_stamped(n: usize, rate_hz: f64, every: usize) -> Vec<f64> {
        (0..n)
            .map(|i| {
                let read = (i / every + 1) * every;
                let latency = 0.003 * ((i / every * 7919 % 11) as f64 / 10.0);
                read as f64 / rate_hz + latency + 0.002 * (i % every) as f64
            })
            .collect()
    }

    #[test]
    fn bursts_of_host_stamps_are_re_timed_at_the_rate_the_fit_gives() {
        // 10 minutes at 99.3 Hz, read in bursts of 10: the median step is 2 ms (500 Hz).
        let mut t = host_stamped(59_580, 99.3, 10);
        let fastest = 1.0
            / t[1..]
                .iter()
                .zip(&t)
                .map(|(a, b)| a - b)
                .fold(f64::NAN, f64::min);
        assert!(fastest > 400.0, "{fastest}");
        let b = retime_bursts(&mut t).expect("bursts found");
        assert!((b.fitted_rate_hz - 99.3).abs() < 0.01, "{b:?}");
        assert!((b.median_step_hz - 500.0).abs() < 1.0, "{b:?}");
        assert_eq!(b.pieces, 1);
        let steps: Vec<f64> = t.windows(2).map(|w| w[1] - w[0]).collect();
        // Evenly stepped at the fitted period, which is the sensor's within 0.01 Hz (above).
        assert!(steps
            .iter()
            .all(|d| (d * b.fitted_rate_hz - 1.0).abs() < 1e-6));
        let text = b.describe("data row");
        assert!(
            text.contains(&format!("{:.3} Hz", b.fitted_rate_hz)) && text.contains("500.0 Hz"),
            "{text}"
        );
    }

    #[test]
    fn a_dropout_among_bursts_stays_a_gap_and_even_stamps_are_left_alone() {
        let mut t = host_stamped(20_000, 100.0, 8);
        for x in &mut t[10_000..] {
            *x += 3.0;
        }
        let b = retime_bursts(&mut t).expect("bursts found");
        assert_eq!(b.pieces, 2, "{b:?}");
        assert!(
            (t[10_000] - t[9_999] - 3.01).abs() < 0.02,
            "{}",
            t[10_000] - t[9_999]
        );
        // A clean log, and one with jitter, have no bursts.
        let mut even: Vec<f64> = (0..5000).map(|i| i as f64 * 0.01).collect();
        assert_eq!(retime_bursts(&mut even), None);
        let mut jitter: Vec<f64> = (0..5000)
            .map(|i| i as f64 * 0.01 + 0.003 * ((i * 7919 % 13) as f64 / 12.0))
            .collect();
        jitter.sort_by(f64::total_cmp);
        assert_eq!(retime_bursts(&mut jitter), None);
    }
}
