//! Which windows of a recording are at rest, judged by the sensor's own noise: the test behind
//! [`super::segment::find_intervals`].
//!
//! Each stream's noise floor is measured where the recording is quietest, however short that
//! stretch: the recording is cut into blocks of one window, and the floor is the median spread of
//! the blocks that are consistent with the quietest ones (a truncated median, iterated from the
//! third quietest block until it settles), so a 2 s rest in a 10-minute flight sets it as surely as
//! a 10-minute still does, and one lucky block does not. The floor's white part comes from
//! sample-to-sample differences (MAD, which slow motion barely touches); their ratio to the spread
//! says how correlated the samples are (a sensor's low-pass filter), and so how many independent
//! samples a window holds.
//!
//! A window is a **table rest** when, on both streams, its spread is consistent with the floor (a
//! χ² test at `LEVEL_Z`, one-sided) and the means of its two halves agree within the floor's
//! noise (χ² with 3 degrees of freedom at the same level). A window that fails only because a hand
//! holds it is a **hand-held rest** when it has a person's tremor and nothing more: its spread
//! exceeds the floor by at most `HAND_ACC_MG` and `HAND_GYRO_DEG_S`, its accelerometer mean
//! moves by at most `HAND_DRIFT_MG` between its halves and its mean rate is within
//! `HAND_RATE_DEG_S` of the gyro's rest output (a turn, however slow, moves gravity across the
//! accelerometers and turns the gyro). A session may hold both kinds: a run of quiet windows is a
//! table rest when most of its windows are, and a hand's rest keeps its length however many
//! steady moments it holds (`quiet`); a hand's tremor that pushes a window or two just past the
//! limits does not cut its rest in two.

/// One-sided normal quantile of the tests' level, 10⁻⁴ per window (each window is tested, so a long
/// rest is not cut by chance).
pub(crate) const LEVEL_Z: f64 = 3.719;
/// The same level as a χ² quantile with three degrees of freedom (the halves' means).
const CHI2_3_LEVEL: f64 = 21.11;
/// Hand-held rest: the accelerometer spread beyond the floor a person's tremor adds, mg (rms over
/// the three axes; a tremor of a few mg of linear acceleration and a wobble of a tenth of a
/// degree, and up to 12 mg in a real hand-held MPU-6050 session, `fixtures/corpus/`). A drift of
/// the attitude is judged apart (`HAND_DRIFT_MG`), so a looser spread lets in no turn.
pub(crate) const HAND_ACC_MG: f64 = 15.0;
/// Hand-held rest: the gyro spread beyond the floor a person's tremor adds, °/s (rms over the
/// three axes; tremor is 0.5–2 °/s).
pub(crate) const HAND_GYRO_DEG_S: f64 = 3.0;
/// Hand-held rest: how far the accelerometer mean may move between a window's halves, mg (the
/// gravity vector turned by 0.3°).
pub(crate) const HAND_DRIFT_MG: f64 = 5.0;
/// Hand-held rest: how far the window's mean rate may be from the gyro's rest output, °/s.
pub(crate) const HAND_RATE_DEG_S: f64 = 2.0;

/// Running sums of one stream (values and squared successive differences, per axis) for any
/// window's mean, spread and white noise in O(1).
pub(crate) struct Stream {
    x0: [f64; 3],
    s: Vec<[f64; 3]>,
    s2: Vec<[f64; 3]>,
    d2: Vec<[f64; 3]>,
}

impl Stream {
    pub(crate) fn new(x: &[[f64; 3]]) -> Stream {
        let x0 = x.first().copied().unwrap_or([0.0; 3]);
        let mut s = Vec::with_capacity(x.len() + 1);
        let mut s2 = Vec::with_capacity(x.len() + 1);
        let mut d2 = Vec::with_capacity(x.len());
        let (mut a, mut b, mut c) = ([0.0; 3], [0.0; 3], [0.0; 3]);
        s.push(a);
        s2.push(b);
        d2.push(c);
        for (i, v) in x.iter().enumerate() {
            for j in 0..3 {
                let d = v[j] - x0[j];
                a[j] += d;
                b[j] += d * d;
                if i > 0 {
                    let e = v[j] - x[i - 1][j];
                    c[j] += e * e;
                }
            }
            s.push(a);
            s2.push(b);
            if i > 0 {
                d2.push(c);
            }
        }
        Stream { x0, s, s2, d2 }
    }

    /// Mean of rows `lo..hi` per axis.
    fn mean(&self, lo: usize, hi: usize) -> [f64; 3] {
        let n = (hi - lo) as f64;
        core::array::from_fn(|j| self.x0[j] + (self.s[hi][j] - self.s[lo][j]) / n)
    }

    /// Variance of rows `lo..hi` about their mean, per axis.
    pub(crate) fn var(&self, lo: usize, hi: usize) -> [f64; 3] {
        let n = (hi - lo) as f64;
        let m: [f64; 3] = core::array::from_fn(|j| (self.s[hi][j] - self.s[lo][j]) / n);
        core::array::from_fn(|j| ((self.s2[hi][j] - self.s2[lo][j]) / n - m[j] * m[j]).max(0.0))
    }

    /// White noise of rows `lo..hi` per axis: half the mean square of successive differences.
    fn white(&self, lo: usize, hi: usize) -> [f64; 3] {
        let n = (hi - lo - 1).max(1) as f64;
        core::array::from_fn(|j| (self.d2[hi - 1][j] - self.d2[lo][j]) / (2.0 * n))
    }
}

/// One stream's noise at rest, measured from the recording.
#[derive(Clone, Copy, Debug, PartialEq)]
pub(crate) struct Floor {
    /// Spread of a window at rest, per axis (variance about the window's mean), squared unit.
    pub var: [f64; 3],
    /// Its white part, per axis (from successive differences), squared unit.
    pub white: [f64; 3],
    /// Independent samples per window sample (1 for white noise, less for filtered noise).
    pub independence: f64,
    /// The stream's mean at rest, per axis (median over the floor's blocks).
    pub rest_mean: [f64; 3],
    /// The magnitude of its mean from `centre` (median over the floor's blocks).
    pub rest_norm: f64,
}

impl Floor {
    /// The floor's rms over the three axes.
    pub fn rms(&self) -> f64 {
        self.var.iter().sum::<f64>().sqrt()
    }

    /// The white part's rms over the three axes.
    pub fn white_rms(&self) -> f64 {
        self.white.iter().sum::<f64>().sqrt()
    }

    /// Each axis's variances at least `min_var` (a quantised output still at rest has none).
    pub(crate) fn at_least(self, min_var: f64) -> Floor {
        Floor {
            var: self.var.map(|v| v.max(min_var)),
            white: self.white.map(|v| v.max(min_var)),
            ..self
        }
    }
}

/// Upper χ² quantile over its degrees of freedom `k` at normal quantile `z` (Wilson–Hilferty).
fn chi2_ratio(k: f64, z: f64) -> f64 {
    let a = 2.0 / (9.0 * k.max(1.0));
    (1.0 - a + z * a.sqrt()).powi(3)
}

fn median(mut v: Vec<f64>) -> f64 {
    v.sort_by(f64::total_cmp);
    match v.len() {
        0 => 0.0,
        n if n % 2 == 1 => v[n / 2],
        n => 0.5 * (v[n / 2 - 1] + v[n / 2]),
    }
}

/// The floor of `stream` (rows `0..n`) from blocks of `w` rows, its mean's magnitude taken from
/// `centre`; `None` when the recording holds no whole block.
pub(crate) fn floor(stream: &Stream, n: usize, w: usize, centre: &[f64; 3]) -> Option<Floor> {
    let blocks: Vec<(usize, usize)> = (0..n / w.max(1)).map(|k| (k * w, k * w + w)).collect();
    if blocks.is_empty() || w < 3 {
        return None;
    }
    let score: Vec<f64> = blocks
        .iter()
        .map(|&(lo, hi)| stream.var(lo, hi).iter().sum())
        .collect();
    let mut sorted = score.clone();
    sorted.sort_by(f64::total_cmp);
    // One axis's spread over w samples, at the level of the selection: generous, so filtered
    // (correlated) noise is not cut short.
    let c = chi2_ratio((w - 1) as f64, 3.09);
    let mut f = sorted[2.min(sorted.len() - 1)];
    let mut chosen: Vec<usize> = Vec::new();
    for _ in 0..60 {
        chosen = (0..blocks.len()).filter(|&k| score[k] <= c * f).collect();
        let next = median(chosen.iter().map(|&k| score[k]).collect());
        if (next - f).abs() <= 1e-9 * f.max(f64::MIN_POSITIVE) {
            break;
        }
        f = next;
    }
    let per_axis = |g: &dyn Fn(usize, usize) -> [f64; 3], j: usize| {
        median(
            chosen
                .iter()
                .map(|&k| g(blocks[k].0, blocks[k].1)[j])
                .collect(),
        )
    };
    let var: [f64; 3] = core::array::from_fn(|j| per_axis(&|lo, hi| stream.var(lo, hi), j));
    let white: [f64; 3] = core::array::from_fn(|j| per_axis(&|lo, hi| stream.white(lo, hi), j));
    let rest_mean = core::array::from_fn(|j| per_axis(&|lo, hi| stream.mean(lo, hi), j));
    let rest_norm = median(
        chosen
            .iter()
            .map(|&k| {
                let m = stream.mean(blocks[k].0, blocks[k].1);
                (0..3)
                    .map(|j| (m[j] - centre[j]).powi(2))
                    .sum::<f64>()
                    .sqrt()
            })
            .collect(),
    );
    // AR(1) noise with lag-one correlation ρ: white/var = 1 − ρ, and n(1 − ρ)/(1 + ρ) of n samples
    // are independent.
    let (sv, sw) = (var.iter().sum::<f64>(), white.iter().sum::<f64>());
    let r = if sv > 0.0 {
        (sw / sv).clamp(0.0, 1.0)
    } else {
        1.0
    };
    Some(Floor {
        var,
        white,
        independence: (r / (2.0 - r)).max(4.0 / w as f64),
        rest_mean,
        rest_norm,
    })
}

/// How the windows are judged.
#[derive(Clone, Copy, Debug)]
pub(crate) enum Judge {
    /// By the floors (table rests) and a hand's tremor (hand-held rests).
    Noise {
        /// The accelerometer's floor.
        acc: Floor,
        /// The gyro's floor.
        gyro: Floor,
        /// Gravity, output unit (for the hand's limits in mg).
        g_out: f64,
    },
    /// By fixed limits on the window's rms over the axes: accelerometer (output unit), gyro
    /// (rad/s), as the user gave them.
    Fixed {
        /// Accelerometer limit, output unit.
        acc: f64,
        /// Gyro limit, rad/s.
        gyro_rad_s: f64,
    },
}

impl Judge {
    /// The largest table-rest spread the floor allows, rms over the axes: accelerometer (output
    /// unit) and gyro (rad/s), for windows of `w` rows.
    pub(crate) fn limits(&self, w: usize) -> (f64, f64) {
        match *self {
            Judge::Noise { acc, gyro, .. } => (
                (acc.var.iter().sum::<f64>() * spread_ratio(&acc, w)).sqrt(),
                (gyro.var.iter().sum::<f64>() * spread_ratio(&gyro, w)).sqrt(),
            ),
            Judge::Fixed { acc, gyro_rad_s } => (acc, gyro_rad_s),
        }
    }

    /// How rows `lo..hi` are at rest, if they are.
    pub(crate) fn rest(&self, a: &Stream, g: &Stream, lo: usize, hi: usize) -> Rest {
        match *self {
            Judge::Fixed { acc, gyro_rad_s } => {
                let still = a.var(lo, hi).iter().sum::<f64>() <= acc * acc
                    && g.var(lo, hi).iter().sum::<f64>() <= gyro_rad_s * gyro_rad_s;
                if still {
                    Rest::Table
                } else {
                    Rest::Moving
                }
            }
            Judge::Noise { acc, gyro, g_out } => {
                let w = hi - lo;
                if table_rest(a, &acc, lo, hi) && table_rest(g, &gyro, lo, hi) {
                    Rest::Table
                } else if hand_rest(a, g, (&acc, &gyro), g_out, (lo, hi), w) {
                    Rest::Hand
                } else {
                    Rest::Moving
                }
            }
        }
    }
}

/// What a window is.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(crate) enum Rest {
    /// Moving.
    Moving,
    /// Held in a hand: a tremor and nothing more.
    Hand,
    /// At rest as the floor says (or within the user's limits).
    Table,
}

/// A hand-held rest is told from the slow start of a turn only over a longer stretch than a
/// window: a run of hand-held windows loses this much more at each end, s.
pub(crate) const HAND_EDGE_S: f64 = 0.2;

/// Which window centres are quiet: a run of quiet windows that is mostly table rest loses the
/// hand-held windows at its ends (the start and end of the turns around it, which a tremor's
/// allowance would let in), and a run mostly of hand-held windows loses `hand_edge` at each end. A
/// hand holds still for a moment now and then, so a few table-rest windows inside a hand-held
/// rest do not make it a table rest: cut to them, it would shrink to those moments.
pub(crate) fn quiet(kinds: &[Rest], hand_edge: usize) -> Vec<bool> {
    let mut quiet: Vec<bool> = kinds.iter().map(|k| *k != Rest::Moving).collect();
    bridge_hand_flicker(kinds, &mut quiet, hand_edge);
    let mut a = 0;
    while a < kinds.len() {
        if !quiet[a] {
            a += 1;
            continue;
        }
        let mut b = a;
        while b < kinds.len() && quiet[b] {
            b += 1;
        }
        let tables = kinds[a..b].iter().filter(|k| **k == Rest::Table).count();
        let (lo, hi) = if 2 * tables > b - a {
            let lo = a + kinds[a..b]
                .iter()
                .position(|k| *k == Rest::Table)
                .unwrap_or(0);
            let hi = a
                + kinds[a..b]
                    .iter()
                    .rposition(|k| *k == Rest::Table)
                    .unwrap_or(0)
                + 1;
            (lo, hi)
        } else {
            (a + hand_edge, b.saturating_sub(hand_edge))
        };
        for (k, q) in quiet[a..b].iter_mut().enumerate() {
            *q = a + k >= lo && a + k < hi;
        }
        a = b;
    }
    quiet
}

/// Marks quiet the moving window centres of a gap no longer than `max_gap` between two hand-held
/// ones. Windows overlap: two hand-held windows whose centres are at most half a window apart
/// (the hand's edge is less than that) together cover every sample between them, so nothing
/// between them turned; the windows in the gap failed only by a hair, as a tremor near the limits
/// makes them flicker. A longer gap stays: its pieces are joined, if at all, only where their
/// positions agree (`segment::intervals`).
fn bridge_hand_flicker(kinds: &[Rest], quiet: &mut [bool], max_gap: usize) {
    let mut last_hand: Option<usize> = None;
    for (k, kind) in kinds.iter().enumerate() {
        if *kind != Rest::Hand {
            continue;
        }
        if let Some(h) = last_hand {
            let gap = &kinds[h + 1..k];
            if !gap.is_empty() && gap.len() <= max_gap && gap.iter().all(|g| *g == Rest::Moving) {
                quiet[h + 1..k].iter_mut().for_each(|q| *q = true);
            }
        }
        last_hand = Some(k);
    }
}

/// The χ² bound on a window's spread over the floor's, for windows of `w` rows.
fn spread_ratio(f: &Floor, w: usize) -> f64 {
    let k = 3.0 * (f.independence * w as f64 - 1.0).max(1.0);
    chi2_ratio(k, LEVEL_Z)
}

/// The window's spread and the move of its halves' means consistent with the floor.
fn table_rest(s: &Stream, f: &Floor, lo: usize, hi: usize) -> bool {
    let w = hi - lo;
    let v = s.var(lo, hi);
    let t: f64 = (0..3).map(|j| v[j] / f.var[j]).sum::<f64>() / 3.0;
    if t > spread_ratio(f, w) {
        return false;
    }
    let mid = lo + w / 2;
    let (m1, m2) = (s.mean(lo, mid), s.mean(mid, hi));
    // Each half's mean has variance var/(n·independence) with n = w/2.
    let half_n = (f.independence * (w / 2) as f64).max(1.0);
    let z2: f64 = (0..3)
        .map(|j| (m1[j] - m2[j]).powi(2) / (2.0 * f.var[j] / half_n))
        .sum();
    z2 <= CHI2_3_LEVEL
}

/// A person's tremor and nothing more (module docs).
fn hand_rest(
    a: &Stream,
    g: &Stream,
    (fa, fg): (&Floor, &Floor),
    g_out: f64,
    (lo, hi): (usize, usize),
    w: usize,
) -> bool {
    let mg = g_out * 1e-3;
    let va: f64 = a.var(lo, hi).iter().sum();
    let vg: f64 = g.var(lo, hi).iter().sum();
    let hand_g = HAND_GYRO_DEG_S.to_radians();
    if va > fa.var.iter().sum::<f64>() + (HAND_ACC_MG * mg).powi(2)
        || vg > fg.var.iter().sum::<f64>() + hand_g * hand_g
    {
        return false;
    }
    let mid = lo + w / 2;
    let (m1, m2) = (a.mean(lo, mid), a.mean(mid, hi));
    let drift2: f64 = (0..3).map(|j| (m1[j] - m2[j]).powi(2)).sum();
    let noise2: f64 = fa.var.iter().sum::<f64>() * 4.0 / (fa.independence * w as f64).max(1.0);
    if drift2 > CHI2_3_LEVEL / 3.0 * noise2 + (HAND_DRIFT_MG * mg).powi(2) {
        return false;
    }
    let m = g.mean(lo, hi);
    let rate2: f64 = (0..3).map(|j| (m[j] - fg.rest_mean[j]).powi(2)).sum();
    rate2 <= HAND_RATE_DEG_S.to_radians().powi(2)
}

#[cfg(test)]
mod tests {
    use super::*;
    use Rest::{Hand as H, Moving as M, Table as T};

    /// A table rest loses the tremor-allowed windows at its ends (the turns' slow start and end);
    /// a hand-held rest with a steady moment inside keeps its length less the hand's edges, not
    /// just that moment.
    #[test]
    fn a_rest_is_cut_by_what_most_of_it_is() {
        let table = [M, H, T, T, T, T, T, H, M];
        let q = quiet(&table, 1);
        assert_eq!(
            q,
            [false, false, true, true, true, true, true, false, false]
        );
        let hand = [M, H, H, H, T, H, H, H, H, H, M];
        let q = quiet(&hand, 1);
        let kept: Vec<usize> = (0..q.len()).filter(|&k| q[k]).collect();
        assert_eq!(kept, (2..9).collect::<Vec<_>>(), "{q:?}");
    }

    /// A hand-held rest whose windows flicker: a gap of moving windows no longer than the hand's
    /// edge is bridged; a longer one, or one beside a table rest, is not.
    #[test]
    fn a_hand_held_rest_is_not_cut_by_a_flicker() {
        let flicker = [M, H, H, H, H, M, M, H, H, H, H, M];
        let q = quiet(&flicker, 2);
        let kept: Vec<usize> = (0..q.len()).filter(|&k| q[k]).collect();
        assert_eq!(kept, (3..9).collect::<Vec<_>>(), "{q:?}");
        let long_gap = [M, H, H, H, H, M, M, M, H, H, H, H, M];
        let q = quiet(&long_gap, 2);
        assert!(!q[5] && !q[6] && !q[7], "{q:?}");
        let table = [M, T, T, T, M, T, T, T, M];
        assert!(!quiet(&table, 2)[4]);
    }
}
