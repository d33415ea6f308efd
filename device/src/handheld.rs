//! Hand-held mode of `host calibrate --port`: a plan whose static segments have free attitudes (the
//! built-in `hand` plan) on a device without a virtual table. Before each position the operator is
//! told to turn the unit to a new position and hold it; the procedure waits until the unit has moved
//! and is still again, refuses a position too close to an earlier one, and says how many remain and
//! which directions are still missing.
//!
//! The decision logic is `PositionWatcher` (windows in, events out), so it is tested without a
//! device; `wait_for_new_position` only feeds it the device's raw windows.

use super::client::{DeviceClient, LinkError, Transport};
use super::operator::Operator;
use super::procedure::{ProcedureOptions, VerificationPoint};
use crate::view::guide::Coverage;
use recording::session::segment::{angle_deg, MIN_POSITIONS};
use recording::session::Plan;
use shared::linalg;
use shared::wire::{SampleFlags, StreamKind};
use shared::OutputUnit;
use std::collections::VecDeque;

/// Hold needed before a position is taken as still, s.
pub(crate) const STILL_HOLD_S: f64 = 1.0;
/// Longest wait for a new still position, s.
pub(crate) const MAX_WAIT_S: f64 = 300.0;
/// Gyro window means steadier than this over the hold: still, rad/s (0.5 °/s).
pub(crate) const STILL_GYRO_STD_RAD_S: f64 = 0.5 * std::f64::consts::PI / 180.0;
/// Accelerometer window means steadier than this fraction of the output's magnitude: still (2 mg
/// of a zero-centred output).
pub(crate) const STILL_ACC_STD_REL: f64 = 2e-3;
/// Still means a mean rate within this of the gyro's offset (read at the first position), rad/s
/// (1 °/s: 5° over a 5 s position).
const STILL_RATE_RAD_S: f64 = 1.0 * std::f64::consts::PI / 180.0;
/// Before the first position the gyro's offset is unknown: a mean rate above the largest offset a
/// MEMS gyro shows (the L3GD20H's typical zero-rate level is ±25 °/s at ±2000 °/s) is a turn, rad/s.
const GYRO_OFFSET_MAX_RAD_S: f64 = 30.0 * std::f64::consts::PI / 180.0;
/// A turn faster than this since the last position: the unit has moved, rad/s (10 °/s).
const MOVED_RATE_RAD_S: f64 = 10.0 * std::f64::consts::PI / 180.0;

/// What the watcher saw in a window.
#[derive(Clone, Debug, PartialEq)]
pub(crate) enum PositionEvent {
    /// Still at a new position: record it now.
    NewPosition {
        /// Mean output over the hold.
        mean_u: [f64; 3],
    },
    /// Still, but at an earlier position (index) within the given angle: turn elsewhere.
    SameAs {
        /// Earlier position, 0-based.
        index: usize,
        /// Angle to it, degrees.
        angle_deg: f64,
    },
}

/// Watches raw windows for a new still position.
pub(crate) struct PositionWatcher {
    hold: usize,
    zero_centred: bool,
    same_position_deg: f64,
    recent: VecDeque<([f64; 3], [f64; 3])>,
    earlier: Vec<[f64; 3]>,
    moved: bool,
    warned_same: Option<usize>,
    bias_rad_s: Option<[f64; 3]>,
    coverage: Coverage,
}

impl PositionWatcher {
    /// A watcher for windows at `window_rate_hz` of an output in `unit` (m/s², g and counts are zero
    /// at zero force, so a position's direction is its output's; volts are compared by distance).
    pub fn new(unit: OutputUnit, window_rate_hz: f64, same_position_deg: f64) -> PositionWatcher {
        PositionWatcher {
            hold: ((STILL_HOLD_S * window_rate_hz).round() as usize).max(3),
            zero_centred: unit != OutputUnit::Volts,
            same_position_deg,
            recent: VecDeque::new(),
            earlier: Vec::new(),
            moved: false,
            warned_same: None,
            bias_rad_s: None,
            coverage: Coverage::new(unit != OutputUnit::Volts, same_position_deg, &[]),
        }
    }

    /// Takes the plan's aims (its free segments' ups) as targets besides the six faces.
    pub fn set_aims(&mut self, aims: &[[f64; 3]]) {
        let c = &self.coverage;
        self.coverage = Coverage::new(c.zero_centred, c.within_deg, aims);
    }

    /// The positions, their rough directions and the targets (what the live page shows).
    pub fn coverage(&self) -> &Coverage {
        &self.coverage
    }

    /// Positions recorded so far.
    pub fn positions(&self) -> usize {
        self.earlier.len()
    }

    /// Starts waiting for the next position (the unit must move first).
    pub fn start(&mut self) {
        self.recent.clear();
        self.moved = self.earlier.is_empty();
        self.warned_same = None;
    }

    /// Records the position just taken.
    pub(crate) fn accept(&mut self, mean_u: [f64; 3], mean_rate_rad_s: [f64; 3]) {
        self.accept_with_spread(mean_u, mean_rate_rad_s, [0.0; 3]);
    }

    /// Records the position just taken with the 1σ of its mean output per axis (output unit),
    /// which weighs it in the predicted 1σ.
    pub(crate) fn accept_with_spread(
        &mut self,
        mean_u: [f64; 3],
        mean_rate_rad_s: [f64; 3],
        sigma_out: [f64; 3],
    ) {
        self.earlier.push(mean_u);
        self.bias_rad_s.get_or_insert(mean_rate_rad_s);
        self.coverage.add(mean_u, sigma_out);
    }

    fn mean_std(&self, f: impl Fn(&([f64; 3], [f64; 3])) -> [f64; 3]) -> ([f64; 3], f64) {
        let n = self.recent.len() as f64;
        let m: [f64; 3] =
            core::array::from_fn(|j| self.recent.iter().map(|w| f(w)[j]).sum::<f64>() / n);
        let var: f64 = self
            .recent
            .iter()
            .map(|w| {
                let v = f(w);
                (0..3).map(|j| (v[j] - m[j]).powi(2)).sum::<f64>()
            })
            .sum::<f64>()
            / n;
        (m, var.sqrt())
    }

    /// The nearest earlier position and the angle to it, degrees.
    fn nearest(&self, u: &[f64; 3]) -> Option<(usize, f64)> {
        let angle = |a: &[f64; 3]| {
            if self.zero_centred {
                angle_deg(&linalg::unit(a), &linalg::unit(u))
            } else {
                // Chord between the two outputs over the largest chord seen so far (≈ 2 g between
                // opposite positions): a lower bound on the angle, so a repeat is never missed.
                let span = self.span().max(f64::MIN_POSITIVE);
                let chord = linalg::norm(&core::array::from_fn(|j| a[j] - u[j]));
                2.0 * (chord / span).min(1.0).asin().to_degrees()
            }
        };
        self.earlier
            .iter()
            .enumerate()
            .map(|(k, a)| (k, angle(a)))
            .min_by(|a, b| a.1.total_cmp(&b.1))
    }

    fn span(&self) -> f64 {
        let mut best = 0.0f64;
        for a in &self.earlier {
            for b in &self.earlier {
                best = best.max(linalg::norm(&core::array::from_fn(|j| a[j] - b[j])));
            }
        }
        best
    }

    /// Feeds one window; returns an event when the unit has settled.
    pub fn push(&mut self, mean_u: [f64; 3], mean_rate_rad_s: [f64; 3]) -> Option<PositionEvent> {
        let b = self.bias_rad_s.unwrap_or([0.0; 3]);
        let rel: [f64; 3] = core::array::from_fn(|j| mean_rate_rad_s[j] - b[j]);
        if linalg::norm(&rel) > MOVED_RATE_RAD_S {
            self.moved = true;
            self.warned_same = None;
        }
        self.recent.push_back((mean_u, mean_rate_rad_s));
        if self.recent.len() > self.hold {
            self.recent.pop_front();
        }
        if self.recent.len() < self.hold || !self.moved {
            return None;
        }
        let (mu, su) = self.mean_std(|w| w.0);
        let (mw, sw) = self.mean_std(|w| w.1);
        // A steady turn about the vertical keeps every window alike: only the rate's mean tells it.
        let turning = match self.bias_rad_s {
            Some(b) => linalg::norm(&core::array::from_fn(|j| mw[j] - b[j])) > STILL_RATE_RAD_S,
            None => linalg::norm(&mw) > GYRO_OFFSET_MAX_RAD_S,
        };
        if su > STILL_ACC_STD_REL * linalg::norm(&mu) || sw > STILL_GYRO_STD_RAD_S || turning {
            return None;
        }
        match self.nearest(&mu) {
            Some((index, angle_deg)) if angle_deg < self.same_position_deg => {
                if self.warned_same == Some(index) {
                    return None;
                }
                self.warned_same = Some(index);
                Some(PositionEvent::SameAs { index, angle_deg })
            }
            _ => Some(PositionEvent::NewPosition { mean_u: mu }),
        }
    }

    /// Body directions (x up, x down, …) with no position within 50° yet, once the positions give
    /// gravity's direction (at once for a zero-centred output, after six for one with an offset).
    pub(crate) fn missing_faces(&self) -> Vec<&str> {
        self.coverage.missing_faces()
    }

    /// What to tell the operator after a position: how many remain, which directions are missing.
    pub(crate) fn guidance(&self, planned: usize) -> String {
        let k = self.positions();
        let missing = self.missing_faces();
        let faces = if missing.is_empty() {
            String::new()
        } else {
            format!("; not yet near: {}", missing.join(", "))
        };
        if k >= planned {
            format!("{k} positions recorded: enough{faces}")
        } else if k >= MIN_POSITIONS {
            format!(
                "{k} positions recorded: enough for a calibration, {} more planned for a better one{faces}",
                planned - k
            )
        } else {
            format!(
                "{k} positions recorded, {} more needed (at least {MIN_POSITIONS}){faces}",
                MIN_POSITIONS - k
            )
        }
    }
}

/// Tells the operator to turn the unit to a new position, then reads windows until the watcher
/// reports a new still position (repeating the request when it is an earlier one).
pub(crate) fn wait_for_new_position<T: Transport>(
    client: &mut DeviceClient<T>,
    op: &mut dyn Operator,
    watcher: &mut PositionWatcher,
    window: u32,
    window_rate_hz: f64,
    label: &str,
) -> Result<[f64; 3], LinkError> {
    let next = watcher.coverage.next_step();
    if let Some(live) = client.view() {
        live.hand_step(label, watcher.coverage(), next.clone());
    }
    let towards = next.map_or(String::new(), |(t, words)| {
        format!("; best next: {} — {words}", t.label)
    });
    op.turn_unit(&format!(
        "[{label}] turn the unit to a new position (at least 10° from the earlier ones) and hold it \
         still{towards}"
    ));
    watcher.start();
    client.start_stream(StreamKind::RawWindows, window)?;
    let max_windows = (MAX_WAIT_S * window_rate_hz) as u64;
    for _ in 0..max_windows {
        let w = client.next_raw_window()?;
        match watcher.push(w.mean_raw.map(f64::from), w.mean_rate_rad_s.map(f64::from)) {
            Some(PositionEvent::NewPosition { mean_u }) => {
                client.stop_stream()?;
                op.say(&format!("[{label}] still at a new position: recording"));
                return Ok(mean_u);
            }
            Some(PositionEvent::SameAs { index, angle_deg }) => op.turn_unit(&format!(
                "[{label}] this is position {} again ({angle_deg:.0}° away): turn to a different one",
                index + 1
            )),
            None => {}
        }
    }
    client.stop_stream()?;
    Err(LinkError::Unexpected {
        waiting_for: "the unit held still at a new position",
        got: format!("no new still position in {MAX_WAIT_S} s"),
    })
}

/// Whether a plan is run hand-held on a device without a table: every static segment's attitude is
/// free and nothing spins.
pub fn is_hand_held(plan: &Plan) -> bool {
    plan.segments.iter().all(|s| s.is_static() && s.is_free())
}

/// Verification without a reference attitude: at three new still positions the compensated specific
/// force must have gravity's magnitude (the direction is what a hand cannot give).
pub(crate) fn verify_magnitude<T: Transport>(
    client: &mut DeviceClient<T>,
    op: &mut dyn Operator,
    plan: &Plan,
    window: u32,
    window_rate_hz: f64,
    opts: &ProcedureOptions,
    sample_rate_hz: f64,
) -> Result<Vec<VerificationPoint>, LinkError> {
    let g = plan.gravity_m_s2;
    let mut watcher = PositionWatcher::new(plan.output_unit, window_rate_hz, 10.0);
    let mut points = Vec::new();
    for k in 1..=3 {
        let label = format!("hand-held check {k}");
        let raw = wait_for_new_position(client, op, &mut watcher, window, window_rate_hz, &label)?;
        watcher.accept(raw, [0.0; 3]);
        let cw = ((sample_rate_hz / 10.0).round() as u32).max(1);
        client.start_stream(StreamKind::CompensatedWindows, cw)?;
        let n = (opts.verify_seconds * sample_rate_hz / f64::from(cw))
            .round()
            .max(1.0) as u64;
        let (mut sum, mut count, mut uncalibrated) = ([0.0f64; 3], 0.0f64, false);
        for _ in 0..n {
            let w = client.next_compensated_window()?;
            uncalibrated |= w.flags.has(SampleFlags::UNCALIBRATED);
            let c = f64::from(w.count);
            for j in 0..3 {
                sum[j] += f64::from(w.mean_m_s2[j]) * c;
            }
            count += c;
        }
        client.stop_stream()?;
        let measured_g: [f64; 3] = core::array::from_fn(|j| sum[j] / count.max(1.0) / g);
        let up = linalg::unit(&measured_g);
        let error_mg = (linalg::norm(&measured_g) - 1.0).abs() * 1e3;
        points.push(VerificationPoint {
            label: format!("{label} (|f| = 1 g)"),
            up_b: up,
            rate_deg_s: 0.0,
            measured_g,
            expected_g: up,
            error_mg,
            temp_c: None,
            pass: !uncalibrated && error_mg <= opts.verify_tolerance_mg,
        });
    }
    Ok(points)
}

#[cfg(test)]
mod tests {
    use super::*;
    use estimator::sim::handheld::{logger_unit, simulate_hand, HandSpec};

    /// Windows of 4 samples (50 Hz) of a simulated hand session.
    fn windows(spec: &HandSpec) -> Vec<([f64; 3], [f64; 3], f64)> {
        let sim = simulate_hand(&logger_unit(OutputUnit::MetresPerSecondSquared), spec);
        sim.rows
            .chunks(4)
            .map(|c| {
                let n = c.len() as f64;
                let u = core::array::from_fn(|j| c.iter().map(|r| r.1[j]).sum::<f64>() / n);
                let w = core::array::from_fn(|j| c.iter().map(|r| r.2[j]).sum::<f64>() / n);
                (u, w, c[0].0)
            })
            .collect()
    }

    #[test]
    fn waits_for_each_new_position_refuses_a_repeat_and_says_when_enough() {
        let mut spec = HandSpec::standard(41);
        // Positions 1–12 of the hand plan, then position 3 again, then 13.
        let mut ups = spec.ups[..12].to_vec();
        ups.push(spec.ups[2]);
        ups.push(spec.ups[12]);
        spec.ups = ups;
        let sim = simulate_hand(&logger_unit(OutputUnit::MetresPerSecondSquared), &spec);
        let mut w = PositionWatcher::new(OutputUnit::MetresPerSecondSquared, 50.0, 10.0);
        w.start();
        let mut accepted_at = Vec::new();
        let mut repeats = Vec::new();
        for (u, rate, t) in windows(&spec) {
            match w.push(u, rate) {
                Some(PositionEvent::NewPosition { mean_u }) => {
                    accepted_at.push(t);
                    w.accept(mean_u, rate);
                    w.start();
                }
                Some(PositionEvent::SameAs { index, .. }) => repeats.push((t, index)),
                None => {}
            }
        }
        // One acceptance inside each hold except the repeated one, which is reported as position 3.
        assert_eq!(accepted_at.len(), 13, "{accepted_at:?}");
        let hold_of = |t: f64| sim.holds.iter().position(|h| t >= h.0 && t <= h.1 + 0.05);
        let holds: Vec<Option<usize>> = accepted_at.iter().map(|&t| hold_of(t)).collect();
        let expect: Vec<Option<usize>> = (0..14).filter(|&k| k != 12).map(Some).collect();
        assert_eq!(holds, expect);
        assert_eq!(repeats.len(), 1, "{repeats:?}");
        assert_eq!(repeats[0].1, 2);
        assert_eq!(hold_of(repeats[0].0), Some(12));
        let g = w.guidance(24);
        assert!(
            g.starts_with("13 positions recorded: enough for a calibration, 11 more"),
            "{g}"
        );
    }

    /// Turning steadily about the vertical leaves the accelerometers' output and the rate unchanged
    /// window to window, but the unit is not still: no position is taken while it turns, whatever
    /// the rate (here 2 °/s after a first position; before any, when the gyro's offset is not known
    /// yet, 45 °/s), and one is taken once it stops.
    #[test]
    fn a_steady_turn_about_the_vertical_is_not_still() {
        let g = [0.0, 0.0, 9.8];
        let bias = [0.002, -0.001, 0.003];
        let turning = |deg_s: f64| {
            let r = deg_s.to_radians();
            [bias[0], bias[1], bias[2] + r]
        };
        // Before the first position the gyro's bias is not known yet.
        let mut w = PositionWatcher::new(OutputUnit::MetresPerSecondSquared, 50.0, 10.0);
        w.start();
        for k in 0..200 {
            assert_eq!(w.push(g, turning(45.0)), None, "window {k} at 45 °/s");
        }
        let taken = (0..100).find_map(|_| w.push(g, bias));
        assert!(matches!(taken, Some(PositionEvent::NewPosition { .. })));
        w.accept(g, bias);
        // Then a turn to a new attitude, and a steady turn about its vertical.
        w.start();
        let h = [9.8, 0.0, 0.0];
        assert_eq!(w.push(h, [0.5, 0.0, 0.0]), None);
        for k in 0..200 {
            assert_eq!(w.push(h, turning(2.0)), None, "window {k} at 2 °/s");
        }
        let taken = (0..100).find_map(|_| w.push(h, bias));
        assert!(matches!(taken, Some(PositionEvent::NewPosition { .. })));
    }

    #[test]
    fn guidance_counts_down_to_the_minimum() {
        let mut w = PositionWatcher::new(OutputUnit::StandardGravity, 50.0, 10.0);
        w.accept([0.0, 0.0, 1.0], [0.0; 3]);
        w.accept([1.0, 0.0, 0.0], [0.0; 3]);
        let g = w.guidance(24);
        assert!(g.contains("2 positions recorded, 7 more needed"), "{g}");
        assert!(g.contains("x down, y up, y down, z down"), "{g}");
    }
}
