//! Still intervals (and constant-rate spins) in one continuous recording, and what they are worth:
//! the detection behind `host segment`.
//!
//! A sample is quiet when the window centred on it is at rest as the sensor's own noise says
//! ([`super::rest`]: a table rest's spread consistent with the noise floor measured from the
//! recording, or a hand-held rest's tremor and nothing more), or within the user's fixed limits
//! (`--still-threshold`). Quiet runs with a steady gyro near the still bias are still positions;
//! quiet runs turning steadily faster than [`SegmentOptions::spin_min_rate_deg_s`] are spins. Runs
//! split by a short disturbance in the same direction are joined, edges are trimmed, and runs
//! shorter than the minimum are dropped (counted). This is how imu_tk's static detector works, with
//! the thresholds from the sensor's noise instead of a user's guess.

use super::import::{Recording, TimeJump, TimeOrigin};
use super::rest::{self, Floor, Judge, Rest, Stream};
use crate::spelling::{Spelling, Syntax, UserOption};
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
    /// Fixed limits on a still window's rms over the axes instead of the noise floor's: the
    /// accelerometer's in mg (of the measured gravity) and the gyro's in °/s.
    pub still_threshold: Option<StillThreshold>,
    /// The caller has the fixed limits' option (`segment`; `apply` and `noise` do not): a "no
    /// still interval" message names it.
    pub offer_still_threshold: bool,
    /// A quiet run whose mean rate exceeds the still bias by this much is a spin, °/s.
    pub spin_min_rate_deg_s: f64,
    /// Two positions closer than this are the same position, degrees.
    pub same_position_deg: f64,
    /// How the caller names its options in messages.
    pub spelling: Spelling,
}

/// Two positions closer than this are the same position by default, degrees
/// ([`SegmentOptions::same_position_deg`]).
pub const SAME_POSITION_DEG: f64 = 10.0;

impl SegmentOptions {
    /// The default detection, its messages spelled as the caller spells its options.
    pub fn new(spelling: Spelling) -> SegmentOptions {
        SegmentOptions {
            window_s: 0.4,
            min_still_s: 1.0,
            trim_s: 0.15,
            still_threshold: None,
            offer_still_threshold: false,
            spin_min_rate_deg_s: 10.0,
            same_position_deg: SAME_POSITION_DEG,
            spelling,
        }
    }
}

/// Only for tests (feature `testkit`): [`SegmentOptions::new`] with the neutral test spelling.
#[cfg(any(test, feature = "testkit"))]
impl Default for SegmentOptions {
    fn default() -> Self {
        SegmentOptions::new(Spelling::default())
    }
}

/// A user's fixed limits on a still window's spread (`--still-threshold MG,DEG_S`).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct StillThreshold {
    /// The accelerometer's rms over the axes, mg of the measured gravity.
    pub acc_mg: f64,
    /// The gyro's rms over the axes, °/s.
    pub gyro_deg_s: f64,
}

/// A still accelerometer's floor is under this, mg: above it nothing in the recording is still.
pub(crate) const MAX_ACC_FLOOR_MG: f64 = 20.0;
/// A still gyro's floor (a hand's tremor included) is under this, °/s: above it nothing is still.
pub(crate) const MAX_GYRO_FLOOR_DEG_S: f64 = 5.0;

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
pub(crate) const FACE_LABEL_DEG: f64 = 25.0;

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
        "no still interval: {why}; the recording's quietest stretch has an accelerometer spread of \
         {acc_mg:.2} mg and a gyro spread of {gyro_deg_s:.3} °/s rms ({gyro_white_deg_s:.3} °/s of \
         it white noise), and a window is still within {acc_limit_mg:.2} mg and \
         {gyro_limit_deg_s:.3} °/s{hand}; hold the unit still for 3–5 s in each of about \
         {RECOMMENDED_POSITIONS} positions, turning it in 1–3 s between them{advice}"
    )]
    NoStill {
        /// What was missing.
        why: String,
        /// The fixed limits' option where the caller has it, then a likelier cause where the
        /// data suggest one.
        advice: String,
        /// The accelerometer's floor, mg of the measured gravity (rms over the axes).
        acc_mg: f64,
        /// The gyro's floor, °/s (rms over the axes).
        gyro_deg_s: f64,
        /// Its white part, °/s.
        gyro_white_deg_s: f64,
        /// The accelerometer limit of a still window, mg.
        acc_limit_mg: f64,
        /// The gyro limit of a still window, °/s.
        gyro_limit_deg_s: f64,
        /// The hand-held rest's limits, as text (none with fixed limits).
        hand: String,
    },
    /// The recording is shorter than one window.
    #[error(
        "no still interval: the recording has {rows} sample(s), fewer than one {window_s} s window \
         ({window_rows} samples); record at least {min_s} s of rest in each position"
    )]
    TooShort {
        /// Samples in the recording.
        rows: usize,
        /// Samples in one window.
        window_rows: usize,
        /// The window, s.
        window_s: f64,
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

fn mean_std(x: &[[f64; 3]]) -> ([f64; 3], [f64; 3]) {
    let n = x.len() as f64;
    let m: [f64; 3] = core::array::from_fn(|j| x.iter().map(|v| v[j]).sum::<f64>() / n);
    let s = core::array::from_fn(|j| {
        (x.iter().map(|v| (v[j] - m[j]).powi(2)).sum::<f64>() / (n - 1.0).max(1.0)).sqrt()
    });
    (m, s)
}

/// A still accelerometer (a floor under `MAX_ACC_FLOOR_MG`) beside a gyro whose floor is above
/// `MAX_GYRO_FLOOR_DEG_S` (more than any hand shakes) and under 200 °/s: 57× a still gyro's
/// 0.02–3 °/s, as a gyro in °/s read as rad/s moves. A rad/s gyro held in a hand (0.5–2 °/s of
/// tremor) is under the floor's limit, so it is never taken for one.
pub fn gyro_unit_suspect(acc_mg: f64, gyro_deg_s: f64) -> bool {
    acc_mg < MAX_ACC_FLOOR_MG && gyro_deg_s > MAX_GYRO_FLOOR_DEG_S && gyro_deg_s < 200.0
}

/// Why nothing is still, when the data suggest a cause: a still accelerometer with a gyro 57× too
/// noisy is a gyro in the wrong unit, said with the option that fixes it where the input has one.
fn no_still_hint(rec: &Recording, figures: (f64, f64, f64), sp: Spelling) -> String {
    let (acc_mg, gyro_deg_s, _) = figures;
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

/// ", or give --still-threshold MG,DEG_S …" where the caller has that option, else nothing.
fn still_threshold_advice(options: &SegmentOptions) -> String {
    if !options.offer_still_threshold {
        return String::new();
    }
    let value = match options.spelling.syntax() {
        Syntax::Flags => "MG,DEG_S",
        Syntax::Keywords => "(MG, DEG_S)",
    };
    format!(
        ", or give {} (mg, °/s) if a rest moves more than that",
        options.spelling.given(UserOption::StillThreshold, value)
    )
}

/// The streams' noise floors (the accelerometer's mean magnitude at rest is gravity's).
fn floors(rec: &Recording, a: &Stream, g: &Stream, w: usize) -> Option<(Floor, Floor)> {
    let n = rec.len();
    let fa = rest::floor(a, n, w, &acc_centre(rec))?;
    let fg = rest::floor(g, n, w, &[0.0; 3])?;
    let g_out = fa.rest_norm.max(f64::MIN_POSITIVE);
    // A quantised output at rest may not move at all: the floors are at least 0.1 mg and
    // 0.01 °/s (rms over the axes), as a tool cannot tell a rest from a finer one.
    Some((
        fa.at_least((1e-4 * g_out).powi(2) / 3.0),
        fg.at_least(0.01f64.to_radians().powi(2) / 3.0),
    ))
}

/// How windows are judged: the user's fixed limits, or the floors'.
fn judge(options: &SegmentOptions, fa: &Floor, fg: &Floor) -> Judge {
    let g_out = fa.rest_norm.max(f64::MIN_POSITIVE);
    match options.still_threshold {
        Some(t) => Judge::Fixed {
            acc: t.acc_mg * 1e-3 * g_out,
            gyro_rad_s: t.gyro_deg_s.to_radians(),
        },
        None => Judge::Noise {
            acc: *fa,
            gyro: *fg,
            g_out,
        },
    }
}

/// The noise floors a recording's rest is judged by: a long log read window by window judges every
/// window by the quietest window's floors, as a whole read judges it by the quietest stretch of
/// the whole log, so that a window without a rest does not take its own quietest motion for one.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct RestFloors {
    acc: Floor,
    gyro: Floor,
}

impl RestFloors {
    /// Each stream's quieter floor of the two (its rms over the axes).
    pub fn quieter(self, other: RestFloors) -> RestFloors {
        let pick = |a: Floor, b: Floor| if b.rms() < a.rms() { b } else { a };
        RestFloors {
            acc: pick(self.acc, other.acc),
            gyro: pick(self.gyro, other.gyro),
        }
    }
}

/// The noise floors of `rec` with the windows `options` sets; `None` when it holds no whole window.
pub fn rest_floors(rec: &Recording, options: &SegmentOptions) -> Option<RestFloors> {
    let w = 2 * half_window(rec, options) + 1;
    let (sa, sg) = (Stream::new(&rec.acc), Stream::new(&rec.gyro_rad_s));
    floors(rec, &sa, &sg, w).map(|(acc, gyro)| RestFloors { acc, gyro })
}

fn half_window(rec: &Recording, options: &SegmentOptions) -> usize {
    ((options.window_s * rec.rate_hz / 2.0).round() as usize).max(2)
}

/// Finds the still intervals and spins of `rec`.
pub fn find_intervals(
    rec: &Recording,
    options: &SegmentOptions,
) -> Result<Segmentation, SegmentError> {
    find_intervals_by(rec, options, None)
}

/// [`find_intervals`] judging rest by `floors` (those of the whole log a window of `rec` is of)
/// instead of the floors of `rec` itself, when given.
pub fn find_intervals_by(
    rec: &Recording,
    options: &SegmentOptions,
    floors_given: Option<&RestFloors>,
) -> Result<Segmentation, SegmentError> {
    let n = rec.len();
    let half = half_window(rec, options);
    let w = 2 * half + 1;
    let (sa, sg) = (Stream::new(&rec.acc), Stream::new(&rec.gyro_rad_s));
    let own = match floors_given {
        Some(f) if n >= w => Some((f.acc, f.gyro)),
        _ => floors(rec, &sa, &sg, w),
    };
    let Some((fa, fg)) = own else {
        return Err(SegmentError::TooShort {
            rows: n,
            window_rows: w,
            window_s: options.window_s,
            min_s: options.min_still_s,
        });
    };
    let judge = judge(options, &fa, &fg);
    let gravity_out = fa.rest_norm.max(f64::MIN_POSITIVE);
    let (thr_a, thr_g) = judge.limits(w);
    let figures = (
        fa.rms() / gravity_out * 1e3,
        fg.rms().to_degrees(),
        fg.white_rms().to_degrees(),
    );
    let no_still = |why: String| SegmentError::NoStill {
        why,
        // A still accelerometer with a gyro 57× too noisy: the gyro's unit is wrong.
        advice: still_threshold_advice(options) + &no_still_hint(rec, figures, options.spelling),
        acc_mg: figures.0,
        gyro_deg_s: figures.1,
        gyro_white_deg_s: figures.2,
        acc_limit_mg: thr_a / gravity_out * 1e3,
        gyro_limit_deg_s: thr_g.to_degrees(),
        hand: match judge {
            Judge::Fixed { .. } => String::new(),
            Judge::Noise { .. } => format!(
                " on a table, or within {} mg and {} °/s more than that in a hand",
                rest::HAND_ACC_MG,
                rest::HAND_GYRO_DEG_S
            ),
        },
    };
    // A still hand-held MEMS unit is far quieter than this: above it nothing is still.
    if options.still_threshold.is_none()
        && (figures.0 > MAX_ACC_FLOOR_MG || figures.1 > MAX_GYRO_FLOOR_DEG_S)
    {
        return Err(no_still(format!(
            "even the quietest stretch moves more than a still unit (at most {MAX_ACC_FLOOR_MG} mg \
             and {MAX_GYRO_FLOOR_DEG_S} °/s)"
        )));
    }
    let kinds: Vec<Rest> = (half..n.saturating_sub(half))
        .map(|i| judge.rest(&sa, &sg, i - half, i + half + 1))
        .collect();
    let hand_edge = (rest::HAND_EDGE_S * rec.rate_hz).round() as usize;
    let quiet = rest::quiet(&kinds, hand_edge);
    let runs = split_at_jumps(quiet_runs(&quiet, half), &rec.jumps());
    let (stills, spins, short_dropped) = intervals(rec, runs, options, half + hand_edge);
    if stills.is_empty() {
        return Err(no_still(format!(
            "no window at rest lasts {} s",
            options.min_still_s
        )));
    }
    Ok(Segmentation {
        stills,
        spins,
        short_dropped,
        acc_threshold: thr_a,
        gyro_threshold_rad_s: thr_g,
        gravity_out,
    })
}

/// The still intervals and spins of the quiet `runs` (rows), and how many were too short: each
/// run trimmed, its kind told by its mean rate, and a run joined to the last of its kind when a
/// short disturbance split one position (within two `edge`s, the window's half and a hand-held
/// run's edge, and two trims of each other). The length a position needs is judged once its pieces
/// are joined: a hand's rest broken by a jolt or two into pieces each shorter than
/// `min_still_s` is one rest, not several too short to keep; a short piece that nothing joins is
/// dropped.
fn intervals(
    rec: &Recording,
    runs: Vec<(usize, usize)>,
    options: &SegmentOptions,
    edge: usize,
) -> (Vec<Interval>, Vec<Interval>, usize) {
    let jumps = rec.jumps();
    let still_bias = still_bias(rec, &runs);
    let trim = (options.trim_s * rec.rate_hz).round() as usize;
    let min_len = (options.min_still_s * rec.rate_hz).round() as usize;
    let spin_min = options.spin_min_rate_deg_s.to_radians();
    let centre = acc_centre(rec);
    let mut stills: Vec<Interval> = Vec::new();
    let mut spins = Vec::new();
    let mut short_dropped = 0;
    let short = |iv: &Interval| iv.end - iv.start < min_len;
    for (lo, hi) in runs {
        let (lo, hi) = (lo + trim, hi.saturating_sub(trim));
        if hi <= lo {
            short_dropped += 1;
            continue;
        }
        let iv = interval(rec, lo, hi, &centre, &still_bias, spin_min);
        let list = match iv.kind {
            IntervalKind::Still => &mut stills,
            IntervalKind::Spin => &mut spins,
        };
        let joins = |prev: &Interval| {
            prev.end + 2 * (edge + trim) >= lo
                && same(prev, &iv, 2.0)
                && Recording::continuous(&jumps, prev.start, hi)
        };
        // A short piece stays only for a piece of the same position to join it.
        if list.last().is_some_and(|prev| !joins(prev) && short(prev)) {
            list.pop();
            short_dropped += 1;
        }
        match list.last_mut() {
            Some(prev) if joins(prev) => {
                *prev = interval(rec, prev.start, hi, &centre, &still_bias, spin_min);
            }
            _ => list.push(iv),
        }
    }
    for list in [&mut stills, &mut spins] {
        let before = list.len();
        list.retain(|iv| !short(iv));
        short_dropped += before - list.len();
    }
    (stills, spins, short_dropped)
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

/// The gyro's mean over all quiet runs, the median weighted by their lengths (its bias when most of
/// the quiet time is still, however a spin's run is cut).
fn still_bias(rec: &Recording, runs: &[(usize, usize)]) -> [f64; 3] {
    let means: Vec<([f64; 3], usize)> = runs
        .iter()
        .map(|&(lo, hi)| (mean_std(&rec.gyro_rad_s[lo..hi]).0, hi - lo))
        .collect();
    let total: usize = means.iter().map(|m| m.1).sum();
    core::array::from_fn(|j| {
        let mut v: Vec<(f64, usize)> = means.iter().map(|m| (m.0[j], m.1)).collect();
        v.sort_by(|a, b| a.0.total_cmp(&b.0));
        let mut seen = 0;
        for (x, n) in &v {
            seen += n;
            if 2 * seen >= total {
                return *x;
            }
        }
        0.0
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
