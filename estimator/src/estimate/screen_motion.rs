//! Static segments that moved (`screen`'s motion stage): each is compared with the other static
//! segments, whose median gyro rate is the gyro's bias and whose median noise is the sensors' at
//! rest, and left out with the figure that failed and its limit.

use super::screen::{exclude, median};
use super::{EstimateOptions, Exclusion, ExclusionReason, ScreenFigure, SegmentKind, SessionSeg};
use recording::session::{Plan, SegmentStats};
use shared::linalg;
use shared::params::axis_name;

/// Per-axis medians over the used static segments: the gyro's mean rate, the gyro's and the
/// accelerometers' noise.
struct StaticMedians {
    /// Median mean gyro rate (the gyro's bias as the static majority shows it).
    w: [f64; 3],
    /// Median gyro noise.
    sw: [f64; 3],
    /// Median accelerometer noise.
    su: [f64; 3],
    /// Whether there are enough static segments (three) to judge noise against the others.
    enough: bool,
}

impl StaticMedians {
    /// The medians over the segments `statics`.
    fn of(segs: &[SessionSeg], statics: &[usize]) -> StaticMedians {
        let w: [f64; 3] = core::array::from_fn(|j| {
            median(
                statics
                    .iter()
                    .map(|&k| segs[k].stats.mean_w_rad_s[j])
                    .collect(),
            )
        });
        let sw: [f64; 3] = core::array::from_fn(|j| {
            median(statics.iter().map(|&k| segs[k].stats.std_w()[j]).collect())
        });
        let su: [f64; 3] = core::array::from_fn(|j| {
            median(statics.iter().map(|&k| segs[k].stats.std_u()[j]).collect())
        });
        StaticMedians {
            w,
            sw,
            su,
            enough: statics.len() >= 3,
        }
    }
}

/// Leaves out static segments that moved: compared with the other static segments (the gyro's bias
/// and the accelerometers' noise are whatever the static majority shows).
pub(super) fn screen_motion(
    plan: &Plan,
    segs: &mut [SessionSeg],
    options: &EstimateOptions,
    excluded: &mut Vec<Exclusion>,
) {
    let statics: Vec<usize> = (0..segs.len())
        .filter(|&k| segs[k].used && segs[k].kind == SegmentKind::Static)
        .collect();
    if statics.is_empty() {
        return;
    }
    let med = StaticMedians::of(segs, &statics);
    let placed = !plan.segments.iter().any(|s| !s.is_static());
    for &k in &statics {
        let held = placed || plan.segments[segs[k].plan_idx].is_free();
        if let Some((detail, figure)) = motion(&segs[k].stats, &med, options, held) {
            let reason = ExclusionReason::Motion { detail, figure };
            exclude(segs, k, plan, reason, excluded);
        }
    }
}

/// The mean rate a position held by hand may show, rad/s (the rest detector's limit for a hand):
/// a drift that shortens the mean specific force by θ²/24, under 0.1 mg for 3° (docs/model.md §7).
const HELD_RATE_RAD_S: f64 = 2.0 * std::f64::consts::PI / 180.0;

/// Why a static segment's statistics `st` show motion against the static medians, if they do: the
/// cause and the figure that failed with its limit.
///
/// A position `held` by a person (free, or in a session without a table's spins) shows a tremor
/// (1 °/s against a table's 0.3 °/s) that leaves its mean specific force, all the fit takes,
/// where it was: no sign of motion. A mean rate beyond [`HELD_RATE_RAD_S`] still is.
fn motion(
    st: &SegmentStats,
    med: &StaticMedians,
    options: &EstimateOptions,
    held: bool,
) -> Option<(String, ScreenFigure)> {
    let dw: [f64; 3] = core::array::from_fn(|j| st.mean_w_rad_s[j] - med.w[j]);
    let rate = linalg::norm(&dw);
    let rate_limit = (options.motion_rate_threshold_rad_s).max(HELD_RATE_RAD_S * f64::from(held));
    if rate > rate_limit {
        return Some((
            "the gyro turned (its mean rate departs from the static segments')".into(),
            ScreenFigure {
                what: "mean gyro rate off the static segments' median".into(),
                value: rate.to_degrees(),
                limit: rate_limit.to_degrees(),
                unit: "°/s",
                at_most: true,
            },
        ));
    }
    if !med.enough {
        return None;
    }
    let sw = st.std_w();
    let su = st.std_u();
    let ratio = |what: String, value: f64| ScreenFigure {
        what,
        value,
        limit: options.motion_noise_ratio,
        unit: "×",
        at_most: true,
    };
    for j in 0..3 {
        let floor = 0.01f64.to_radians();
        if !held && sw[j] > options.motion_noise_ratio * med.sw[j] && sw[j] > floor {
            return Some((
                format!(
                    "gyro {} noise {:.3} °/s, above the other static segments'",
                    axis_name(j),
                    sw[j].to_degrees()
                ),
                ratio(
                    format!("gyro {} noise over the static median", axis_name(j)),
                    sw[j] / med.sw[j],
                ),
            ));
        }
        if med.su[j] > 0.0 && su[j] > options.motion_noise_ratio * med.su[j] {
            return Some((
                format!(
                    "accelerometer {} noisier than the other static segments (vibration or motion)",
                    axis_name(j)
                ),
                ratio(
                    format!(
                        "accelerometer {} noise over the static median",
                        axis_name(j)
                    ),
                    su[j] / med.su[j],
                ),
            ));
        }
    }
    None
}
