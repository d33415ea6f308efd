//! Whole turns on a table (docs/model.md §7.2): two consecutive still intervals at the same position
//! (the same face down, gravity where it was) with a large rotation about the vertical between them.
//! The classic six-face bench method turns the unit once about the vertical on each face; the gyro
//! fit (`estimate::handheld_gyro`) takes such a turn as a known angle, `2πk` about the up direction,
//! when the angle turned is within `WHOLE_TURN_TOLERANCE_DEG` of a whole number of turns, and says
//! why it leaves one out otherwise.

use estimator::estimate::handheld_gyro::still_bias;
use recording::session::import::Recording;
use recording::session::segment::{angle_deg, Segmentation};
use shared::linalg;

/// Two still intervals whose gravity directions differ by less than this are at the same position,
/// degrees: a face turned flat on a table keeps its up to the table's flatness (a few hundredths of
/// a degree); more means the unit was tipped or set down on another spot of an uneven bench.
pub(crate) const SAME_UP_DEG: f64 = 1.0;
/// A rotation about the vertical this large between two stills at the same position is a table turn
/// (used or refused), degrees; smaller ones are a nudge, used as an ordinary turn.
pub(crate) const MIN_ANGLE_DEG: f64 = 90.0;
/// The angle turned (from the gyro at its nominal scale, within a few percent) must be this close to
/// a whole number of turns for the number to be sure, degrees.
pub(crate) const WHOLE_TURN_TOLERANCE_DEG: f64 = 20.0;
/// The rotation about horizontal axes over a table turn must be below this, degrees: a unit turned
/// flat on a table barely rocks; more means it was lifted and turned in the hand.
pub(crate) const MAX_OFF_VERTICAL_DEG: f64 = 20.0;

/// Why a table turn is not used as a known angle.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum TableTurnRefusal {
    /// The angle is too far from a whole number of turns for the number to be sure.
    NotWhole {
        /// Distance from the nearest whole number of turns, degrees.
        off_deg: f64,
    },
    /// It turned about a horizontal axis as well: not flat on the table.
    NotAboutVertical,
}

/// A table turn found between two still intervals.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct FoundTableTurn {
    /// The still interval before it (0-based; the table numbers it one more).
    pub after_still: usize,
    /// The turn's start, s.
    pub start_s: f64,
    /// The gyro's integral about the vertical, degrees (nominal scale, still bias removed).
    pub angle_deg: f64,
    /// Its integral about the horizontal axes, degrees.
    pub off_vertical_deg: f64,
    /// The whole turns (signed, right-handed about up), or why it is left out.
    pub verdict: Result<i32, TableTurnRefusal>,
}

impl FoundTableTurn {
    /// The whole turns, if it is used.
    pub fn used(&self) -> Option<i32> {
        self.verdict.ok()
    }
}

impl std::fmt::Display for FoundTableTurn {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        let at = format!(
            "the turn after still interval #{} (from t = {:.3} s) at the same position",
            self.after_still + 1,
            self.start_s
        );
        match self.verdict {
            Ok(k) => write!(
                f,
                "{at}: {k:+} whole turn(s) on the table ({:+.1}° by the uncorrected gyro)",
                self.angle_deg
            ),
            Err(TableTurnRefusal::NotWhole { off_deg }) => write!(
                f,
                "{at} turns {:+.1}° about the vertical, {off_deg:.1}° from a whole number of turns \
                 (at most {WHOLE_TURN_TOLERANCE_DEG}°): the angle turned is not known, so it is not \
                 used as a whole table turn; turn the unit a whole turn flat on the table and set it \
                 back against the same stop",
                self.angle_deg
            ),
            Err(TableTurnRefusal::NotAboutVertical) => write!(
                f,
                "{at} turns {:+.1}° about the vertical and {:.1}° about a horizontal axis (at most \
                 {MAX_OFF_VERTICAL_DEG}°): it was not turned flat on the table, so it is not used as \
                 a whole table turn",
                self.angle_deg, self.off_vertical_deg
            ),
        }
    }
}

/// The table turns of `seg`: each pair of consecutive still intervals at the same position (within
/// [`SAME_UP_DEG`]), not cut by a time jump, with at least [`MIN_ANGLE_DEG`] about the vertical
/// between them; used when within [`WHOLE_TURN_TOLERANCE_DEG`] of a whole number of turns and
/// nearly flat, refused otherwise.
pub(crate) fn find_table_turns(rec: &Recording, seg: &Segmentation) -> Vec<FoundTableTurn> {
    let means: Vec<([f64; 3], usize)> = seg
        .stills
        .iter()
        .map(|s| (s.mean_gyro_rad_s, s.end - s.start))
        .collect();
    let (b, _) = still_bias(&means);
    let jumps = rec.jumps();
    seg.stills
        .windows(2)
        .enumerate()
        .filter_map(|(k, w)| {
            let (lo, hi) = (w[0].end - 1, w[1].start);
            if angle_deg(&w[0].direction, &w[1].direction) >= SAME_UP_DEG
                || !Recording::continuous(&jumps, lo, hi + 1)
            {
                return None;
            }
            let up = linalg::unit(&core::array::from_fn(|j| {
                w[0].direction[j] + w[1].direction[j]
            }));
            let mut s = [0.0; 3];
            for i in lo..hi {
                let dt = rec.t_s[i + 1] - rec.t_s[i];
                for (j, sj) in s.iter_mut().enumerate() {
                    *sj += (0.5 * (rec.gyro_rad_s[i][j] + rec.gyro_rad_s[i + 1][j]) - b[j]) * dt;
                }
            }
            let along = linalg::dot(&s, &up);
            let across: [f64; 3] = core::array::from_fn(|j| s[j] - along * up[j]);
            let angle_deg = along.to_degrees();
            if angle_deg.abs() < MIN_ANGLE_DEG {
                return None;
            }
            let off_vertical_deg = linalg::norm(&across).to_degrees();
            let turns = (angle_deg / 360.0).round();
            let off_deg = (angle_deg - 360.0 * turns).abs();
            let verdict = if off_vertical_deg > MAX_OFF_VERTICAL_DEG {
                Err(TableTurnRefusal::NotAboutVertical)
            } else if off_deg > WHOLE_TURN_TOLERANCE_DEG {
                Err(TableTurnRefusal::NotWhole { off_deg })
            } else {
                Ok(turns as i32)
            };
            Some(FoundTableTurn {
                after_still: k,
                start_s: rec.t_s[lo],
                angle_deg,
                off_vertical_deg,
                verdict,
            })
        })
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;
    use recording::session::segment::{find_intervals, SegmentOptions};
    use std::f64::consts::PI;

    /// Still z up for 3 s, then for each angle a turn about z (raised-cosine rate over 3 s) and 3 s
    /// still again, at 200 Hz with 1 mg and 0.05 °/s noise; the gyro reads 1 % high.
    fn turns_on_a_table(angles_deg: &[f64]) -> Recording {
        let mut rng = shared::rng::Rng::new(3, 0);
        let mut rec = Recording {
            acc_unit: Some(shared::OutputUnit::StandardGravity),
            rate_hz: 200.0,
            ..Recording::default()
        };
        let mut push = |rate_deg_s: f64, rec: &mut Recording| {
            let i = rec.t_s.len();
            rec.t_s.push(i as f64 / 200.0);
            rec.acc.push(core::array::from_fn(|j| {
                f64::from(u8::from(j == 2)) + 1e-3 * rng.normal()
            }));
            rec.gyro_rad_s.push(core::array::from_fn(|j| {
                let w = if j == 2 { 1.01 * rate_deg_s } else { 0.0 };
                (w + 0.05 * rng.normal()).to_radians()
            }));
        };
        (0..600).for_each(|_| push(0.0, &mut rec));
        for a in angles_deg {
            for i in 0..600 {
                let s = i as f64 / 600.0;
                push(a / 3.0 * (1.0 - (2.0 * PI * s).cos()), &mut rec);
            }
            (0..600).for_each(|_| push(0.0, &mut rec));
        }
        rec
    }

    #[test]
    fn whole_turns_are_counted_with_their_sign_and_an_ambiguous_angle_is_refused_with_why() {
        let rec = turns_on_a_table(&[360.0, -720.0, 300.0, 30.0]);
        let seg = find_intervals(&rec, &SegmentOptions::default()).unwrap();
        assert_eq!(seg.stills.len(), 5, "{:?}", seg.stills);
        let found = find_table_turns(&rec, &seg);
        // The 30° nudge is no table turn; the others are found in order.
        assert_eq!(found.len(), 3, "{found:?}");
        assert_eq!(found[0].used(), Some(1));
        assert_eq!(found[1].used(), Some(-2));
        assert!((found[1].angle_deg + 1.01 * 720.0).abs() < 1.0, "{found:?}");
        assert_eq!(found[2].after_still, 2);
        let refused = found[2];
        assert!(matches!(
            refused.verdict,
            Err(TableTurnRefusal::NotWhole { off_deg }) if (off_deg - 57.0).abs() < 1.0
        ));
        let text = refused.to_string();
        assert!(
            text.contains("after still interval #3")
                && text.contains("from a whole number of turns")
                && text.contains("not used as a whole table turn"),
            "{text}"
        );
    }
}
