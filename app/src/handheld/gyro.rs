//! The gyro of a hand-held session (docs/model.md §8): fitted from the hand turns between still
//! positions ([`fit`]), accepted or refused ([`problems`], `estimate::gyro_check`), and kept beside
//! the session as `gyro.toml` (`file_text`, [`read`]) for `host calibrate --input`.

use super::table_turn::find_table_turns;
use estimator::estimate::gyro::GyroEstimate;
use estimator::estimate::handheld_gyro::{
    fit_handheld_gyro, still_bias, HandGyroError, HandGyroFit, TableTurn, Turn, DETERMINED_1SIGMA,
    MIN_EQUATIONS,
};
use estimator::estimate::{calibrate_session_stats, gyro_check, EstimateError, EstimateOptions};
use estimator::unit_file::GyroSection;
use recording::session::from_recording::stats_for;
use recording::session::import::{six_digits, Recording, TimeOrigin};
use recording::session::segment::{PositionSet, Segmentation};
use recording::session::Plan;
use recording::spelling::{Spelling, UserOption};
use shared::linalg::{self, RowMajor3};
use std::path::{Path, PathBuf};

/// The gyro result's file in the session directory.
pub const GYRO_FILE: &str = "gyro.toml";

/// Why the hand-held gyro could not be fitted or read.
#[derive(Debug, thiserror::Error)]
pub enum HandGyroFileError {
    /// The session's accelerometer fit, which gives gravity's directions, failed.
    #[error(transparent)]
    Estimate(#[from] EstimateError),
    /// That fit is singular.
    #[error("the session's accelerometer fit is singular: gravity's directions at the still positions are unknown")]
    Singular,
    /// The gyro's unit is wrong (the turns are 57× or 1/57 of gravity's).
    #[error(transparent)]
    Unit(HandGyroError),
    /// `gyro.toml` cannot be read.
    #[error("cannot read {}", .path.display())]
    Io {
        /// The file.
        path: PathBuf,
        /// The cause.
        #[source]
        source: std::io::Error,
    },
    /// `gyro.toml` is not valid.
    #[error("{} is not valid: {message}", .path.display())]
    Invalid {
        /// The file.
        path: PathBuf,
        /// What the parser said.
        message: String,
    },
}

/// The gyro fit on the hand turns and the whole table turns ([`super::table_turn`]), with gravity
/// directions from the session's own accelerometer calibration, leaving out the turns `dropped`
/// ([`dropped_turns`]: cut by a time jump, or clipped by the gyro's range). A wrong gyro unit is an
/// error; too few turns only leave the gyro uncalibrated.
pub fn fit(
    rec: &Recording,
    seg: &Segmentation,
    plan: &Plan,
    dropped: &[DroppedTurn],
    spelling: Spelling,
) -> Result<Result<HandGyroFit, HandGyroError>, HandGyroFileError> {
    // Too few turns for any gyro: said before the accelerometer fit, which a gyro it cannot have
    // must not wait on (or fail for).
    // (An upper bound on the turns the fit will use: `fit_handheld_gyro` applies the same rule to
    // those that no time jump cuts.)
    let whole: Vec<(usize, i32)> = find_table_turns(rec, seg)
        .iter()
        .filter_map(|f| Some((f.after_still, f.used()?)))
        .collect();
    let hand = seg
        .stills
        .len()
        .saturating_sub(1)
        .saturating_sub(whole.len());
    if 2 * hand + 3 * whole.len() < MIN_EQUATIONS {
        return Ok(Err(HandGyroError::TooFewTurns {
            turns: hand,
            table_turns: whole.len(),
        }));
    }
    let stats = stats_for(rec, seg, plan);
    let options = EstimateOptions {
        compare_methods: false,
        ..EstimateOptions::new(spelling)
    };
    let outcome = calibrate_session_stats(plan, &stats, &options)?;
    let m = outcome.fitted.m_out_per_g;
    let minv = linalg::inverse(&m).ok_or(HandGyroFileError::Singular)?;
    let up = |iv: &recording::session::segment::Interval| {
        let d: [f64; 3] =
            core::array::from_fn(|j| iv.mean_acc[j] - outcome.fitted.zero_bias_out[j]);
        let f = linalg::mat_vec(&minv, &d);
        let n = linalg::norm(&f);
        f.map(|c| c / n)
    };
    let turns: Vec<Turn> = seg
        .stills
        .windows(2)
        .enumerate()
        .filter(|(k, _)| {
            !dropped.iter().any(|d| d.after_still == k + 1)
                && !whole.iter().any(|(after, _)| after == k)
        })
        .map(|(_, w)| Turn {
            from_row: w[0].end - 1,
            to_row: w[1].start,
            up_before_b: up(&w[0]),
            up_after_b: up(&w[1]),
        })
        .collect();
    let table: Vec<TableTurn> = whole
        .iter()
        .map(|&(k, turns)| {
            let (a, b) = (&seg.stills[k], &seg.stills[k + 1]);
            let sum: [f64; 3] = core::array::from_fn(|j| up(a)[j] + up(b)[j]);
            TableTurn {
                from_row: a.end - 1,
                to_row: b.start,
                up_b: sum.map(|c| c / linalg::norm(&sum)),
                turns,
            }
        })
        .collect();
    let means: Vec<([f64; 3], usize)> = seg
        .stills
        .iter()
        .map(|s| (s.mean_gyro_rad_s, s.end - s.start))
        .collect();
    let fitted = fit_handheld_gyro(
        &turns,
        &table,
        &rec.t_s,
        &rec.gyro_rad_s,
        still_bias(&means),
        angle_random_walk(rec, seg),
        spelling,
    );
    match fitted {
        Err(e @ HandGyroError::UnitMismatch { .. }) => Err(HandGyroFileError::Unit(e)),
        r => Ok(r),
    }
}

/// The gyro's angle random walk, rad/√s: the median over the still intervals of their per-sample
/// noise (rms over the axes) times the square root of the sample period, white noise assumed.
fn angle_random_walk(rec: &Recording, seg: &Segmentation) -> f64 {
    let mut per_sample: Vec<f64> = seg
        .stills
        .iter()
        .map(|s| linalg::norm(&s.std_gyro_rad_s) / 3f64.sqrt())
        .collect();
    per_sample.sort_by(f64::total_cmp);
    per_sample
        .get(per_sample.len() / 2)
        .map_or(0.0, |s| s / rec.rate_hz.max(f64::MIN_POSITIVE).sqrt())
}

/// A turn left out of the gyro fit: its rotation cannot be integrated.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct DroppedTurn {
    /// The still interval before it (1-based, as in the table).
    pub after_still: usize,
    /// The turn's start, s.
    pub start_s: f64,
    /// Why.
    pub cause: DropCause,
}

/// Why a turn cannot be integrated.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum DropCause {
    /// The time stamps jump during it (a gap, a repeat or a step back): the first jump.
    Jump(recording::session::import::TimeJump),
    /// The gyro reads its extreme on `axis` during it: a rate beyond its range was cut there.
    Saturated {
        /// The axis, 0..3.
        axis: usize,
        /// Its extreme, rad/s.
        level_rad_s: f64,
    },
}

impl std::fmt::Display for DroppedTurn {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        write!(
            f,
            "the turn after still interval #{} (from t = {:.3} s) is left out of the gyro fit: ",
            self.after_still, self.start_s,
        )?;
        match self.cause {
            DropCause::Jump(jump) => write!(
                f,
                "the time stamps jump by {:+.3} s after data row {} (t = {:.3} s) during it",
                jump.step_s,
                jump.row + 1,
                jump.t_s
            ),
            DropCause::Saturated { axis, level_rad_s } => write!(
                f,
                "the gyro's {} axis reads its extreme, ±{:.1} °/s, during it (the turn was faster \
                 than the gyro's range: turn more slowly, or set a wider range)",
                ["x", "y", "z"][axis.min(2)],
                level_rad_s.to_degrees()
            ),
        }
    }
}

/// Each gyro axis's extreme where the recording holds it at least [`CLIPPED_SAMPLES`] times: a
/// rate cut at the gyro's range (a measured rate peaks once; a range clips it flat).
fn gyro_clip_levels(rec: &Recording) -> [Option<f64>; 3] {
    core::array::from_fn(|j| {
        let m = rec
            .gyro_rad_s
            .iter()
            .map(|w| w[j].abs())
            .fold(0.0, f64::max);
        let at = rec
            .gyro_rad_s
            .iter()
            .filter(|w| w[j].abs() >= m * (1.0 - CLIP_TOLERANCE))
            .count();
        (m > 0.0 && at >= CLIPPED_SAMPLES).then_some(m)
    })
}

/// Samples at a gyro axis's extreme that say it was clipped there.
const CLIPPED_SAMPLES: usize = 3;

/// How close to the extreme a clipped sample is: a two's-complement range's two ends differ by
/// one count in 32 768 (3·10⁻⁵).
const CLIP_TOLERANCE: f64 = 1e-4;

/// The turns between consecutive still intervals that [`fit`] leaves out, with their place.
pub fn dropped_turns(rec: &Recording, seg: &Segmentation) -> Vec<DroppedTurn> {
    let jumps = rec.jumps();
    let clip = gyro_clip_levels(rec);
    seg.stills
        .windows(2)
        .enumerate()
        .filter_map(|(k, w)| {
            let (lo, hi) = (w[0].end - 1, w[1].start + 1);
            let jump = jumps
                .iter()
                .find(|j| j.row >= lo && j.row + 1 < hi)
                .map(|j| DropCause::Jump(*j));
            let saturated = || {
                rec.gyro_rad_s
                    .get(lo..hi.min(rec.len()))?
                    .iter()
                    .find_map(|g| {
                        (0..3).find_map(|axis| {
                            let level = clip[axis]?;
                            (g[axis].abs() >= level * (1.0 - CLIP_TOLERANCE)).then_some(
                                DropCause::Saturated {
                                    axis,
                                    level_rad_s: level,
                                },
                            )
                        })
                    })
            };
            Some(DroppedTurn {
                after_still: k + 1,
                start_s: rec.t_s[lo],
                cause: jump.or_else(saturated)?,
            })
        })
        .collect()
}

/// Why a hand-turn gyro fit is refused ([`estimator::estimate::gyro_check`]): an implausible `G`, or
/// turns no `G` explains (an rms misfit over `max_misfit_deg`, `plausible_misfit_deg`). Empty:
/// accepted.
pub fn problems(fit: &HandGyroFit, max_misfit_deg: f64, sp: Spelling) -> Vec<String> {
    let mut problems: Vec<String> =
        gyro_check::misfit_problem(fit.rms_residual_deg, fit.turns, max_misfit_deg)
            .into_iter()
            .collect();
    problems.extend(gyro_check::matrix_problems_spelled(&fit.matrix, sp));
    problems
}

/// An accepted fit whose only problems are entries of `G` that its turns do not determine (a
/// plausible `G` lies within 3σ of every entry) is no calibration, and no contradiction either:
/// the gyro is then absent, saying why ([`HandGyroError::NotDetermined`]). `max_misfit_deg` is
/// `plausible_misfit_deg`. A misfit of the turns
/// is evidence whatever `G`'s 1σ, and a `G` implausible beyond its 3σ too: both stay refusals.
/// (`sp` only spells the problems counted here, which are not shown.)
pub fn undetermined(
    fit: HandGyroFit,
    max_misfit_deg: f64,
    sp: Spelling,
) -> Result<HandGyroFit, HandGyroError> {
    let worst = fit
        .matrix_1sigma
        .iter()
        .flatten()
        .fold(0.0f64, |m, s| m.max(*s));
    let not_determined = || HandGyroError::NotDetermined {
        turns: fit.turns,
        worst_1sigma_pct: 100.0 * worst,
    };
    if gyro_check::matrix_problems_spelled(&fit.matrix, sp).is_empty()
        || gyro_check::misfit_problem(fit.rms_residual_deg, fit.turns, max_misfit_deg).is_some()
    {
        return Ok(fit);
    }
    // The matrix within 3σ of the fit that is nearest the identity.
    let nearest: RowMajor3 = core::array::from_fn(|i| {
        core::array::from_fn(|j| {
            let d = fit.matrix[i][j] - f64::from(u8::from(i == j));
            let reach = 3.0 * fit.matrix_1sigma[i][j];
            fit.matrix[i][j] - d.clamp(-reach, reach)
        })
    });
    if !gyro_check::matrix_problems_spelled(&nearest, sp).is_empty() {
        return Ok(fit);
    }
    Err(not_determined())
}

/// A gyro that reads `k`× on every axis and fits its turns (`gyro_check::common_scale`): a
/// result, not a contradiction. The turns cannot tell a nominal scale that is off (which the
/// calibration corrects) from a time base that is (which it must not), so the note names both, each
/// with the figure it implies, in the terms of the recording's own input (docs/model.md §8).
pub fn common_scale_note(fit: &HandGyroFit, rec: &Recording, sp: Spelling) -> Option<String> {
    let k = gyro_check::common_scale(&fit.matrix)?;
    let diag: Vec<String> = (0..3)
        .map(|i| format!("{:+.1} %", (fit.matrix[i][i] - 1.0) * 100.0))
        .collect();
    let scale = match rec.gyro_lsb_per_dps {
        Some(lsb) => format!(
            "the gyro's nominal scale is off: the turns imply {} LSB per °/s where \
             {} gave {}",
            six_digits(lsb * k),
            sp.name(UserOption::GyroLsbPerDps),
            six_digits(lsb)
        ),
        None => format!(
            "the gyro's nominal scale is off: its values are {k:.4}× the true rates (the conversion \
             its logger applied)"
        ),
    };
    let rate = rec.rate_hz;
    let (time, fix) = match rec.time_origin {
        Some(TimeOrigin::RateGiven(hz)) => (
            format!(
                "the rate given is: the rows would have to come at {:.3} Hz, not the {}",
                hz * k,
                sp.given(UserOption::RateHz, hz)
            ),
            format!("give the true {}", sp.name(UserOption::RateHz)),
        ),
        Some(TimeOrigin::TimeColumn) => (
            format!(
                "the time column is: its stamps would have to step at {:.3} Hz, not {rate:.3} Hz",
                rate * k
            ),
            format!("fix the time column (or {})", sp.name(UserOption::TimeUnit)),
        ),
        Some(TimeOrigin::LoggerStamps(format)) => (
            format!(
                "the {format} log's stamps are: they would have to step at {:.3} Hz, not \
                 {rate:.3} Hz",
                rate * k
            ),
            "re-time the log".to_string(),
        ),
        None => (
            format!(
                "the time base is: the samples would have to come at {:.3} Hz, not {rate:.3} Hz",
                rate * k
            ),
            "fix the time stamps".to_string(),
        ),
    };
    Some(format!(
        "gyro scale {} on all three axes, and the {} turns fit it (rms misfit {:.3}°): either {scale}, \
         which this calibration corrects, or {time}, which it must not correct; if the time stamps \
         are what is wrong, {fix} and segment again",
        diag.join(", "),
        fit.turns,
        fit.rms_residual_deg
    ))
}

/// The largest plausible rms misfit of the hand turns, degrees: 1° (`gyro_check::MAX_TURN_MISFIT_DEG`),
/// or in a six-face session its face prior when larger. Its ups are the calibrated accelerometer's,
/// whose non-orthogonality is only as good as the faces' placement (docs/model.md §7.1): when whole
/// table turns fix the gyro's scales, the angle between two faces can no longer be absorbed by the
/// gyro's `G`, and the hand turns are off by that much (docs/model.md §7.2).
pub(crate) fn plausible_misfit_deg(position_set: PositionSet, plan: &Plan) -> f64 {
    let faces = match position_set {
        PositionSet::SixFaces => plan
            .segments
            .iter()
            .filter_map(|s| s.attitude_sigma_deg)
            .fold(0.0, f64::max),
        PositionSet::Spread => 0.0,
    };
    gyro_check::MAX_TURN_MISFIT_DEG.max(faces)
}

/// `gyro.toml`: the `[gyro]` table of a calibration file (the keys of the table gyro calibration) with a
/// comment saying where it comes from.
pub(crate) fn file_text(fit: &HandGyroFit) -> String {
    #[derive(serde::Serialize)]
    struct File {
        gyro: GyroSection,
    }
    let gyro = GyroSection {
        bias_rad_s: fit.bias_rad_s,
        matrix: fit.matrix,
        bias_rad_s_1sigma: Some(fit.bias_1sigma_rad_s),
        matrix_1sigma: Some(fit.matrix_1sigma),
    };
    format!(
        "# The gyro from {} hand turns between still positions (rms misfit {:.4}°) and {} whole turns on a\n\
         # table (docs/model.md §7.2): w = matrix·ω_body + bias\n\
         # (docs/model.md §8), body axes of this session's accelerometer calibration. `host calibrate\n\
         # --input` adds it to calibration.toml. 1σ entries above 1e-3: not determined by the turns.\n{}",
        fit.turns,
        fit.rms_residual_deg,
        fit.table_turns,
        toml::to_string_pretty(&File { gyro }).unwrap_or_default()
    )
}

/// The gyro `host segment` fitted from the hand turns (`DIR/gyro.toml`), as the estimator's gyro
/// estimate, for a session whose own plan does not estimate the gyro. `None` without the file.
pub fn read(dir: &Path) -> Result<Option<GyroEstimate>, HandGyroFileError> {
    let path = dir.join(GYRO_FILE);
    let text = match recording::limits::read_text_bounded(&path) {
        Ok(text) => text,
        Err(e) if e.kind() == std::io::ErrorKind::NotFound => return Ok(None),
        Err(source) => return Err(HandGyroFileError::Io { path, source }),
    };
    parse(&text, &path).map(Some)
}

/// The gyro estimate of a `gyro.toml` text (`file_text`) named `path` in messages: what [`read`]
/// gives for that file, for a session held in memory (`super::in_memory`).
pub fn parse(text: &str, path: &Path) -> Result<GyroEstimate, HandGyroFileError> {
    #[derive(serde::Deserialize)]
    struct File {
        gyro: GyroSection,
    }
    let f: File = toml::from_str(text).map_err(|e| HandGyroFileError::Invalid {
        path: path.to_path_buf(),
        message: e.to_string(),
    })?;
    let g = f.gyro;
    let matrix_1sigma = g.matrix_1sigma.unwrap_or([[f64::INFINITY; 3]; 3]);
    let names = ["x", "y", "z"];
    let undetermined = (0..9)
        .filter(|&k| {
            let s = matrix_1sigma[k / 3][k % 3];
            s.is_nan() || s > DETERMINED_1SIGMA
        })
        .map(|k| format!("G[{}][{}]", names[k / 3], names[k % 3]))
        .collect();
    Ok(GyroEstimate {
        matrix: g.matrix,
        matrix_1sigma,
        bias_rad_s: g.bias_rad_s,
        bias_rad_s_1sigma: g.bias_rad_s_1sigma.unwrap_or([f64::INFINITY; 3]),
        table_rate_scale: None,
        undetermined,
    })
}

#[cfg(test)]
mod tests {
    use super::*;
    use estimator::sim::handheld::{logger_unit, simulate_hand, HandSpec};
    use recording::session::from_recording::plan_for;
    use recording::session::segment::{find_intervals, SegmentOptions};
    use recording::testkit::SPELLING;
    use shared::OutputUnit;

    /// One face round of a six-face session (1° placement) with a whole table turn on each face: the
    /// five hand turns alone leave `G` undetermined (scale 1σ of percents); the table turns' known
    /// angles fix each axis's scale to a few hundredths of a percent.
    #[test]
    fn whole_table_turns_fix_the_gyro_scale_that_one_round_of_hand_turns_leaves_open() {
        let spec = HandSpec {
            table_turns: true,
            ..HandSpec::six_faces(4, 1.0, 1)
        };
        let rec =
            super::super::segmentation_tests::recording(&spec, OutputUnit::MetresPerSecondSquared);
        let seg = find_intervals(&rec, &SegmentOptions::default()).unwrap();
        assert_eq!(seg.stills.len(), 12);
        let faces = recording::session::coverage::six_face_labels(&seg.stills).unwrap();
        let plan = recording::session::from_recording::plan_for_faces(&rec, &seg, &faces, 2.0);
        let fit = fit(&rec, &seg, &plan, &dropped_turns(&rec, &seg), SPELLING)
            .unwrap()
            .unwrap();
        assert_eq!((fit.turns, fit.table_turns), (5, 6));
        let truth = spec.gyro.matrix;
        for i in 0..3 {
            let (e, s) = (fit.matrix[i][i] - truth[i][i], fit.matrix_1sigma[i][i]);
            println!(
                "G[{i}][{i}]: error {:+.4} %, 1σ {:.4} %",
                e * 100.0,
                s * 100.0
            );
            // Each axis's scale: two turns, each good to the stop's 0.1° of 360° (0.028 %).
            assert!(s < 3e-4 && e.abs() < 4.0 * s, "axis {i}: {e} ± {s}");
        }
        assert!(
            fit.undetermined()
                .iter()
                .all(|g| !["G[x][x]", "G[y][y]", "G[z][z]"].contains(&g.as_str())),
            "{:?}",
            fit.undetermined()
        );
        // The table turns' angle errors are the stop's (0.05° in the simulation).
        assert!(
            fit.table_rms_residual_deg < 0.15,
            "{}",
            fit.table_rms_residual_deg
        );
        // A six-face session's hand turns are judged against its face prior (2°), others against 1°.
        assert_eq!(plausible_misfit_deg(PositionSet::SixFaces, &plan), 2.0);
        assert_eq!(plausible_misfit_deg(PositionSet::Spread, &plan), 1.0);
        assert!(
            problems(&fit, 2.0, SPELLING).is_empty(),
            "{:?}",
            problems(&fit, 2.0, SPELLING)
        );
    }

    #[test]
    fn a_turn_across_a_time_gap_is_dropped_and_said_the_others_fit() {
        let spec = HandSpec::standard(4);
        let unit = OutputUnit::MetresPerSecondSquared;
        let sim = simulate_hand(&logger_unit(unit), &spec);
        // Half a second of the first turn lost: its rows removed, the time stamps kept.
        let (t0, t1) = (sim.holds[0].1 + 0.3, sim.holds[0].1 + 0.8);
        let rows: Vec<_> = sim.rows.iter().filter(|r| r.0 < t0 || r.0 > t1).collect();
        let rec = Recording {
            t_s: rows.iter().map(|r| r.0).collect(),
            acc: rows.iter().map(|r| r.1).collect(),
            gyro_rad_s: rows.iter().map(|r| r.2).collect(),
            acc_unit: Some(unit),
            rate_hz: spec.rate_hz,
            ..Recording::default()
        };
        let seg = find_intervals(&rec, &SegmentOptions::default()).unwrap();
        assert_eq!(seg.stills.len(), 24);
        let dropped = dropped_turns(&rec, &seg);
        assert_eq!(dropped.len(), 1, "{dropped:?}");
        assert_eq!(dropped[0].after_still, 1);
        let text = dropped[0].to_string();
        assert!(text.contains("after still interval #1"), "{text}");
        let DropCause::Jump(jump) = dropped[0].cause else {
            panic!("{text}")
        };
        assert!((0.5..0.52).contains(&jump.step_s), "{text}");
        let fit = fit(&rec, &seg, &plan_for(&rec, &seg), &dropped, SPELLING)
            .unwrap()
            .unwrap();
        assert_eq!(fit.turns, 22);
        // The gyro's truth (GyroTruth::half_percent): the remaining turns still find its scale.
        let want = [0.005, -0.005, 0.004];
        for i in 0..3 {
            assert!(
                (fit.scale_rel()[i] - want[i]).abs() < 5e-4,
                "{:?}",
                fit.scale_rel()
            );
        }
    }
}
