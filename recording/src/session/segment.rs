//! Still intervals (and constant-rate spins) in one continuous recording, and what they are worth:
//! the detection behind `host segment`.
//!
//! A sample is quiet when the variance of the accelerometer and of the gyro over a centred sliding
//! window are both below thresholds learnt from the recording itself: a multiple of the window
//! variance of its quietest stretch (a low percentile over all windows, so one lucky window does not
//! set it). Quiet runs with a steady gyro near the still bias are still positions; quiet runs turning
//! steadily faster than [`SegmentOptions::spin_min_rate_deg_s`] are spins. Runs split by a short
//! disturbance in the same direction are joined, edges are trimmed, and runs shorter than the
//! minimum are dropped (counted). This is how imu_tk's static detector works, with thresholds from the
//! data instead of a user's guess.

use super::import::{Recording, TimeJump, TimeOrigin};
use crate::spelling::{Spelling, UserOption};
use shared::linalg;
use shared::OutputUnit;

/// Detection settings.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct SegmentOptions {
    /// Sliding window, s.
    pub window_s: f64,
    /// Shortest still interval kept (after trimming), s.
    pub min_still_s: f64,
    /// Trimmed from each end of an interval, s.
    pub trim_s: f64,
    /// Threshold = this² × the quietest stretch's window variance.
    pub threshold_factor: f64,
    /// Percentile of the window variances taken as the quietest stretch's.
    pub quiet_percentile: f64,
    /// A quiet run whose mean rate exceeds the still bias by this much is a spin, °/s.
    pub spin_min_rate_deg_s: f64,
    /// Two positions closer than this are the same position, degrees.
    pub same_position_deg: f64,
    /// How the caller names its options in messages.
    pub spelling: Spelling,
}

impl Default for SegmentOptions {
    fn default() -> Self {
        SegmentOptions {
            window_s: 0.4,
            min_still_s: 1.0,
            trim_s: 0.15,
            threshold_factor: 3.0,
            quiet_percentile: 0.1,
            spin_min_rate_deg_s: 10.0,
            same_position_deg: 10.0,
            spelling: Spelling::Flags,
        }
    }
}

/// Fewest distinct still positions for the intrinsic parameters from gravity's magnitude alone (nine
/// unknowns: 3 biases, 3 scales, 3 non-orthogonalities; docs/model.md §7).
pub const MIN_POSITIONS: usize = 9;
/// Recommended number of positions (the built-in `hand` plan).
pub(crate) const RECOMMENDED_POSITIONS: usize = 24;
/// A body direction (±x, ±y, ±z) with no position within this angle is missing, degrees.
pub const FACE_COVERAGE_DEG: f64 = 50.0;
/// Fewer than [`MIN_POSITIONS`] positions are taken as the six faces of a cube when each lies within
/// this angle of a body axis once the biases and scales the faces themselves give are taken out,
/// degrees: a face placed by hand up to 5° off, seen through axes a degree or two off.
pub const SIX_FACE_DEG: f64 = 7.5;
/// A still position's raw direction labels it with its nearest body axis only within this angle,
/// degrees: a consumer MEMS unit's biases of up to 100 mg on two axes move it 8°, a 5° placement as
/// much again; 25° keeps every label unambiguous (the axes are 90° apart).
pub const FACE_LABEL_DEG: f64 = 25.0;

/// What the still positions are.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum PositionSet {
    /// At least [`MIN_POSITIONS`] distinct positions: each free or snapped to a near axis.
    Spread,
    /// The six faces of a cube (all six present, each within [`SIX_FACE_DEG`] of its body axis once
    /// the faces' own biases and scales are out): nominal ups with an attitude prior, docs/model.md
    /// §7.1.
    SixFaces,
}

/// What an interval is.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum IntervalKind {
    /// Held still.
    Still,
    /// Turning steadily about a fixed axis.
    Spin,
}

/// One detected interval.
#[derive(Clone, Debug, PartialEq)]
pub struct Interval {
    /// Still or spin.
    pub kind: IntervalKind,
    /// First row.
    pub start: usize,
    /// One past the last row.
    pub end: usize,
    /// Time of the first row, s.
    pub start_s: f64,
    /// Last minus first row's time, s.
    pub duration_s: f64,
    /// Mean accelerometer output, output unit.
    pub mean_acc: [f64; 3],
    /// Its standard deviation per axis, output unit.
    pub std_acc: [f64; 3],
    /// Mean gyro rate, rad/s.
    pub mean_gyro_rad_s: [f64; 3],
    /// Its standard deviation per axis, rad/s.
    pub std_gyro_rad_s: [f64; 3],
    /// Rough direction of gravity ("up"), unit vector from the uncalibrated outputs.
    pub direction: [f64; 3],
}

/// The detection's result.
#[derive(Clone, Debug, PartialEq)]
pub struct Segmentation {
    /// Still intervals, in time order.
    pub stills: Vec<Interval>,
    /// Spins, in time order.
    pub spins: Vec<Interval>,
    /// Quiet runs dropped for being shorter than the minimum.
    pub short_dropped: usize,
    /// Accelerometer threshold, standard deviation (sum over axes), output unit.
    pub acc_threshold: f64,
    /// Gyro threshold, standard deviation (sum over axes), rad/s.
    pub gyro_threshold_rad_s: f64,
    /// Gravity's magnitude in the output unit (median over quiet windows, from the unit's zero).
    pub gravity_out: f64,
}

/// Why the recording cannot be made into a session; each says what to record instead.
#[derive(Debug, thiserror::Error)]
pub enum SegmentError {
    /// The samples are already corrected by the vehicle's calibration.
    #[error(
        "the log's IMU samples are {0}, which the vehicle has already corrected with its own \
         calibration: a calibration made from them would be a residual, and exported as \
         CAL_ACC0_* it would replace the vehicle's offsets with it. Log the sensor's raw topics \
         (sensor_accel and sensor_gyro, at the sensor's rate: PX4's SDLOG_PROFILE \
         'high rate' or logger_topics.txt) and record the session again"
    )]
    AlreadyCorrected(&'static str),
    /// Nothing in the recording is still.
    #[error(
        "no still interval: the quietest stretch of the recording moves ({acc_mg:.1} mg, \
         {gyro_deg_s:.2} °/s rms) or no quiet run lasts {min_s} s; hold the unit still for 3–5 s in \
         each of about {RECOMMENDED_POSITIONS} positions, turning it in 1–3 s between them{hint}"
    )]
    NoStill {
        /// A likelier cause, if the data suggest one.
        hint: String,
        /// Quietest accelerometer noise, mg (of the measured gravity).
        acc_mg: f64,
        /// Quietest gyro noise, °/s.
        gyro_deg_s: f64,
        /// Minimum still duration, s.
        min_s: f64,
    },
    /// Too few distinct positions.
    #[error(
        "{found} still interval(s) in {distinct} distinct position(s): at least {MIN_POSITIONS} \
         distinct positions are needed ({RECOMMENDED_POSITIONS} recommended), or the six faces of a \
         cube, each within {FACE_LABEL_DEG}° of a body axis as read and {SIX_FACE_DEG}° once the \
         faces' own biases and scales are taken out; record {more} more, each at least \
         {same_deg:.0}° from the others{faces}"
    )]
    TooFewPositions {
        /// Still intervals found.
        found: usize,
        /// Distinct positions among them.
        distinct: usize,
        /// How many more to record for the minimum.
        more: usize,
        /// Same-position angle, degrees.
        same_deg: f64,
        /// Which directions are missing, as text.
        faces: String,
    },
    /// Face labels given for a number of still intervals other than the number found.
    #[error(
        "{given} face label(s) given for {found} still interval(s): give one label per still \
         interval, in the order found (x+, x-, y+, y-, z+ or z-)"
    )]
    FaceLabelCount {
        /// Labels given.
        given: usize,
        /// Still intervals found.
        found: usize,
    },
    /// The labels given miss a face: an axis's bias and scale need both of its faces.
    #[error(
        "the face labels given have no {0}: each axis's bias and scale need both of its faces"
    )]
    FaceMissing(&'static str),
    /// A still interval does not read as the face it is labelled, even with the faces' own biases
    /// and scales taken out.
    #[error(
        "still interval {still} is labelled {label} but reads {angle_deg:.1}° from it once the \
         faces' own biases and scales are taken out (at most {SIX_FACE_DEG}°): its direction is \
         ({:+.3}, {:+.3}, {:+.3}); check the labels' order",
        .direction[0],
        .direction[1],
        .direction[2]
    )]
    FaceLabelContradicted {
        /// 1-based still interval.
        still: usize,
        /// Its label.
        label: &'static str,
        /// Its raw direction.
        direction: [f64; 3],
        /// The angle from its label, bias and scale removed, degrees.
        angle_deg: f64,
    },
}

/// Running sums for window statistics in O(1) per window.
struct Prefix {
    s: Vec<[f64; 3]>,
    s2: Vec<[f64; 3]>,
}

impl Prefix {
    fn new(x: &[[f64; 3]]) -> Prefix {
        let x0 = x.first().copied().unwrap_or([0.0; 3]);
        let mut s = Vec::with_capacity(x.len() + 1);
        let mut s2 = Vec::with_capacity(x.len() + 1);
        let (mut a, mut b) = ([0.0; 3], [0.0; 3]);
        s.push(a);
        s2.push(b);
        for v in x {
            for j in 0..3 {
                let d = v[j] - x0[j];
                a[j] += d;
                b[j] += d * d;
            }
            s.push(a);
            s2.push(b);
        }
        Prefix { s, s2 }
    }

    /// Sum over axes of the variance of rows `lo..hi`.
    fn var(&self, lo: usize, hi: usize) -> f64 {
        let n = (hi - lo) as f64;
        (0..3)
            .map(|j| {
                let m = (self.s[hi][j] - self.s[lo][j]) / n;
                ((self.s2[hi][j] - self.s2[lo][j]) / n - m * m).max(0.0)
            })
            .sum()
    }
}

fn percentile(v: &[f64], q: f64) -> f64 {
    let mut v = v.to_vec();
    v.sort_by(f64::total_cmp);
    v[((v.len() - 1) as f64 * q).round() as usize]
}

fn mean_std(x: &[[f64; 3]]) -> ([f64; 3], [f64; 3]) {
    let n = x.len() as f64;
    let m: [f64; 3] = core::array::from_fn(|j| x.iter().map(|v| v[j]).sum::<f64>() / n);
    let s = core::array::from_fn(|j| {
        (x.iter().map(|v| (v[j] - m[j]).powi(2)).sum::<f64>() / (n - 1.0).max(1.0)).sqrt()
    });
    (m, s)
}

/// A still accelerometer (`acc_mg` of window noise, under 20 mg) beside a gyro that moves 1–200 °/s:
/// 57× a still gyro's 0.02–3 °/s, as a gyro in °/s read as rad/s moves.
pub fn gyro_unit_suspect(acc_mg: f64, gyro_deg_s: f64) -> bool {
    acc_mg < 20.0 && gyro_deg_s > 1.0 && gyro_deg_s < 200.0
}

/// Why nothing is still, when the data suggest a cause: a still accelerometer with a gyro 57× too
/// noisy is a gyro in the wrong unit, said with the option that fixes it where the input has one.
fn no_still_hint(rec: &Recording, acc_mg: f64, gyro_deg_s: f64, sp: Spelling) -> String {
    match rec.time_origin {
        _ if !gyro_unit_suspect(acc_mg, gyro_deg_s) => String::new(),
        // A binary log states its units: no option changes them.
        Some(TimeOrigin::LoggerStamps(format)) => format!(
            "; but the accelerometer is still there: the {format} log's gyro moves \
             {gyro_deg_s:.1} °/s at rest, 57× a still gyro's, as if its logger wrote °/s where \
             the format says rad/s"
        ),
        _ => format!(
            "; but the accelerometer is still there: if the gyro logs deg/s, give {}",
            sp.given(UserOption::GyroUnit, "deg/s")
        ),
    }
}

/// Finds the still intervals and spins of `rec`.
pub fn find_intervals(
    rec: &Recording,
    options: &SegmentOptions,
) -> Result<Segmentation, SegmentError> {
    let n = rec.len();
    let half = ((options.window_s * rec.rate_hz / 2.0).round() as usize).max(2);
    let (pa, pg) = (Prefix::new(&rec.acc), Prefix::new(&rec.gyro_rad_s));
    let centres: Vec<usize> = (half..n.saturating_sub(half)).collect();
    let var_a: Vec<f64> = centres
        .iter()
        .map(|&i| pa.var(i - half, i + half + 1))
        .collect();
    let var_g: Vec<f64> = centres
        .iter()
        .map(|&i| pg.var(i - half, i + half + 1))
        .collect();
    let no_still = |acc_mg: f64, gyro_deg_s: f64| SegmentError::NoStill {
        // A still accelerometer with a gyro 57× too noisy: the gyro's unit is wrong.
        hint: no_still_hint(rec, acc_mg, gyro_deg_s, options.spelling),
        acc_mg,
        gyro_deg_s,
        min_s: options.min_still_s,
    };
    if centres.is_empty() {
        return Err(no_still(f64::NAN, f64::NAN));
    }
    let quiet_a = percentile(&var_a, options.quiet_percentile);
    let quiet_g = percentile(&var_g, options.quiet_percentile);
    let centre = acc_centre(rec);
    let mut mags: Vec<f64> = centres
        .iter()
        .zip(&var_a)
        .filter(|(_, &v)| v <= quiet_a * 4.0)
        .map(|(&i, _)| linalg::norm(&core::array::from_fn(|j| rec.acc[i][j] - centre[j])))
        .collect();
    mags.sort_by(f64::total_cmp);
    let gravity_out = mags[mags.len() / 2];
    let g_scale = gravity_out.max(f64::MIN_POSITIVE);
    let (acc_mg, gyro_deg_s) = (quiet_a.sqrt() / g_scale * 1e3, quiet_g.sqrt().to_degrees());
    // A still hand-held MEMS unit is far quieter than 20 mg and 1 °/s: above that nothing is still.
    if acc_mg > 20.0 || gyro_deg_s > 1.0 {
        return Err(no_still(acc_mg, gyro_deg_s));
    }
    let f2 = options.threshold_factor.powi(2);
    let thr_a = (quiet_a * f2).max((1e-4 * g_scale).powi(2));
    let thr_g = (quiet_g * f2).max(0.01f64.to_radians().powi(2));
    let quiet: Vec<bool> = var_a
        .iter()
        .zip(&var_g)
        .map(|(a, g)| *a < thr_a && *g < thr_g)
        .collect();
    let jumps = rec.jumps();
    let runs = split_at_jumps(quiet_runs(&quiet, half), &jumps);
    let still_bias = still_bias(rec, &runs);
    let trim = (options.trim_s * rec.rate_hz).round() as usize;
    let min_len = (options.min_still_s * rec.rate_hz).round() as usize;
    let spin_min = options.spin_min_rate_deg_s.to_radians();
    let mut stills: Vec<Interval> = Vec::new();
    let mut spins = Vec::new();
    let mut short_dropped = 0;
    for (lo, hi) in runs {
        let (lo, hi) = (lo + trim, hi.saturating_sub(trim));
        if hi <= lo || hi - lo < min_len {
            short_dropped += 1;
            continue;
        }
        let iv = interval(rec, lo, hi, &centre, &still_bias, spin_min);
        let list = match iv.kind {
            IntervalKind::Still => &mut stills,
            IntervalKind::Spin => &mut spins,
        };
        match list.last_mut() {
            Some(prev)
                if prev.end + 2 * (half + trim) >= lo
                    && same(prev, &iv, 2.0)
                    && Recording::continuous(&jumps, prev.start, hi) =>
            {
                *prev = interval(rec, prev.start, hi, &centre, &still_bias, spin_min);
            }
            _ => list.push(iv),
        }
    }
    if stills.is_empty() {
        return Err(no_still(acc_mg, gyro_deg_s));
    }
    Ok(Segmentation {
        stills,
        spins,
        short_dropped,
        acc_threshold: thr_a.sqrt(),
        gyro_threshold_rad_s: thr_g.sqrt(),
        gravity_out,
    })
}

/// Rows `lo..hi` of runs of quiet window centres (indices into the recording).
fn quiet_runs(quiet: &[bool], half: usize) -> Vec<(usize, usize)> {
    let mut runs = Vec::new();
    let mut start = None;
    for (k, &q) in quiet.iter().chain([false].iter()).enumerate() {
        match (q, start) {
            (true, None) => start = Some(k),
            (false, Some(s)) => {
                runs.push((s + half, k + half));
                start = None;
            }
            _ => {}
        }
    }
    runs
}

/// `runs` cut at the time jumps (`jumps` in row order): no still interval spans a gap, a repeat or
/// a step back of the time stamps.
fn split_at_jumps(runs: Vec<(usize, usize)>, jumps: &[TimeJump]) -> Vec<(usize, usize)> {
    let mut out = Vec::with_capacity(runs.len());
    for (lo, hi) in runs {
        let mut start = lo;
        for j in jumps.iter().filter(|j| j.row >= lo && j.row + 1 < hi) {
            out.push((start, j.row + 1));
            start = j.row + 1;
        }
        out.push((start, hi));
    }
    out
}

/// The gyro's mean over all quiet runs, weighted by length (its bias when most runs are still).
fn still_bias(rec: &Recording, runs: &[(usize, usize)]) -> [f64; 3] {
    let mut means: Vec<[f64; 3]> = runs
        .iter()
        .map(|&(lo, hi)| mean_std(&rec.gyro_rad_s[lo..hi]).0)
        .collect();
    if means.is_empty() {
        return [0.0; 3];
    }
    core::array::from_fn(|j| {
        let mut v: Vec<f64> = means.iter_mut().map(|m| m[j]).collect();
        v.sort_by(f64::total_cmp);
        v[v.len() / 2]
    })
}

/// Zero for m/s², g and LSB (their zero is zero force); for volts, the mid-range of the quiet outputs
/// (an analog part's zero is mid-supply).
fn acc_centre(rec: &Recording) -> [f64; 3] {
    if rec.acc_unit != Some(OutputUnit::Volts) {
        return [0.0; 3];
    }
    core::array::from_fn(|j| {
        let (lo, hi) = rec
            .acc
            .iter()
            .fold((f64::INFINITY, f64::NEG_INFINITY), |(lo, hi), v| {
                (lo.min(v[j]), hi.max(v[j]))
            });
        0.5 * (lo + hi)
    })
}

fn interval(
    rec: &Recording,
    lo: usize,
    hi: usize,
    centre: &[f64; 3],
    still_bias: &[f64; 3],
    spin_min_rad_s: f64,
) -> Interval {
    let (mean_acc, std_acc) = mean_std(&rec.acc[lo..hi]);
    let (mean_gyro_rad_s, std_gyro_rad_s) = mean_std(&rec.gyro_rad_s[lo..hi]);
    let rel: [f64; 3] = core::array::from_fn(|j| mean_gyro_rad_s[j] - still_bias[j]);
    let kind = if linalg::norm(&rel) > spin_min_rad_s {
        IntervalKind::Spin
    } else {
        IntervalKind::Still
    };
    let d: [f64; 3] = core::array::from_fn(|j| mean_acc[j] - centre[j]);
    let dn = linalg::norm(&d).max(f64::MIN_POSITIVE);
    Interval {
        kind,
        start: lo,
        end: hi,
        start_s: rec.t_s[lo],
        duration_s: rec.t_s[hi - 1] - rec.t_s[lo],
        mean_acc,
        std_acc,
        mean_gyro_rad_s,
        std_gyro_rad_s,
        direction: d.map(|c| c / dn),
    }
}

/// Angle between two unit vectors, degrees.
pub fn angle_deg(a: &[f64; 3], b: &[f64; 3]) -> f64 {
    linalg::dot(a, b).clamp(-1.0, 1.0).acos().to_degrees()
}

fn same(a: &Interval, b: &Interval, deg: f64) -> bool {
    angle_deg(&a.direction, &b.direction) < deg
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::session::coverage::coverage;

    fn still_at(direction: [f64; 3]) -> Interval {
        let n = linalg::norm(&direction);
        Interval {
            kind: IntervalKind::Still,
            start: 0,
            end: 1,
            start_s: 0.0,
            duration_s: 4.0,
            mean_acc: direction,
            std_acc: [0.0; 3],
            mean_gyro_rad_s: [0.0; 3],
            std_gyro_rad_s: [0.0; 3],
            direction: direction.map(|c| c / n),
        }
    }

    #[test]
    fn six_faces_near_the_axes_are_a_cube_other_few_positions_are_refused() {
        let t = 3f64.to_radians().tan();
        let faces = [
            [1.0, t, 0.0],
            [-1.0, 0.0, t],
            [0.0, 1.0, -t],
            [t, -1.0, 0.0],
            [0.0, t, 1.0],
            [-t, 0.0, -1.0],
        ];
        let stills: Vec<Interval> = faces.iter().map(|d| still_at(*d)).collect();
        let cov = coverage(&stills, 10.0);
        assert_eq!(cov.distinct, 6);
        assert_eq!(cov.check(6, 10.0).unwrap(), PositionSet::SixFaces);
        // A repeated face is still a cube.
        let mut again = stills.clone();
        again.push(still_at(faces[0]));
        assert_eq!(
            coverage(&again, 10.0).check(7, 10.0).unwrap(),
            PositionSet::SixFaces
        );
        // Five faces, or one position 8° off its axis: refused, naming what is missing.
        let e = coverage(&stills[..5], 10.0)
            .check(5, 10.0)
            .unwrap_err()
            .to_string();
        assert!(
            e.contains("six faces of a cube") && e.contains("z down"),
            "{e}"
        );
        let mut tilted = stills.clone();
        tilted[2] = still_at([8f64.to_radians().tan(), 1.0, 0.0]);
        assert!(coverage(&tilted, 10.0).check(6, 10.0).is_err());
    }
}
