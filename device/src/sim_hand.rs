//! The simulated hand of `--port sim-hand`: the simulated device without a table, turned by a hand
//! whenever the procedure asks the operator to turn it. The hand-held procedure (`handheld`) then runs
//! end to end without a board, on the firmware's own logic, as it runs with a board held in the hand
//! (an F405 flight controller on its USB cable, say).
//!
//! Asked to turn, the hand spins the unit about the vertical for `TURN_S` at `TURN_RATE_DEG_S`
//! (the motion the procedure waits for before it takes a new position), then tilts it at the same
//! rate along the great circle to its next attitude, and lets go: the unit is still there, as on a
//! desk (no tremor). Every turn is a real rotation that the gyro sees whole, so the session's
//! recording holds the turns the hand-held gyro fit needs (docs/model.md §8). Its attitudes are
//! the built-in `hand` plan's well-spread ups, each `AIM_ERROR_DEG` off where the plan aims, in a
//! direction that changes from position to position, as a person's aim would be. Like a person who
//! loses count, every `REPEAT_EVERY`th turn brings the unit back to where it just was, which the
//! procedure must refuse and ask again.

use super::operator::{AutomaticOperator, Operator};
use super::procedure::ProcedureError;
use recording::session::builtin::builtin_plan;
use shared::linalg;
use shared::wire::VirtualTable;
use std::sync::atomic::{AtomicU32, Ordering};
use std::sync::Arc;

/// How long one turn lasts, s.
pub(crate) const TURN_S: f64 = 1.0;
/// How fast the hand turns the unit, °/s (the procedure takes 10 °/s as moved).
pub(crate) const TURN_RATE_DEG_S: f64 = 90.0;
/// How far each attitude is off the plan's aim, degrees.
pub(crate) const AIM_ERROR_DEG: f64 = 3.0;
/// Every this many turns, the hand sets the unit down where it was before the turn.
pub(crate) const REPEAT_EVERY: u32 = 7;

/// A tilt along a great circle: from `from` about `axis` (unit, body axes) at `rate` rad/s.
#[derive(Clone, Copy, Debug, PartialEq)]
struct Tilt {
    from: [f64; 3],
    to: [f32; 3],
    axis: [f64; 3],
    rate: f64,
    /// Samples done, and in all.
    done: u32,
    samples: u32,
}

impl Tilt {
    /// "Up" after `k` samples: `from` turned by −rate·t about `axis` (`du/dt = u × ω` with
    /// `ω = −rate·axis`), and the body rate.
    fn at(&self, k: u32, fs: f64) -> HandMove {
        let th = -self.rate * f64::from(k) / fs;
        let (a, u) = (self.axis, self.from);
        let (sn, c) = (th.sin(), th.cos());
        let axu = linalg::cross(&a, &u);
        let adu = linalg::dot(&a, &u);
        let up: [f64; 3] =
            core::array::from_fn(|j| u[j] * c + axu[j] * sn + a[j] * adu * (1.0 - c));
        HandMove::Tilt(
            still(up.map(|x| x as f32)),
            a.map(|x| (-self.rate * x) as f32),
        )
    }
}

/// What the hand does to the unit before a sample.
#[derive(Clone, Copy, Debug, PartialEq)]
pub(crate) enum HandMove {
    /// Sets the table: a spin about the vertical, or the unit set down still.
    Table(VirtualTable),
    /// Turning: "up" where this table setting puts it, the body turning at this rate, rad/s
    /// (`VirtualSensor::set_tilt`); one per sample of the tilt.
    Tilt(VirtualTable, [f32; 3]),
}

/// The operator's side of the hand: each call asks it for one more turn.
#[derive(Clone, Debug, Default)]
pub struct HandCue(Arc<AtomicU32>);

impl HandCue {
    /// Asks the hand to turn the unit to its next attitude.
    pub fn turn(&self) {
        self.0.fetch_add(1, Ordering::Relaxed);
    }

    fn requested(&self) -> u32 {
        self.0.load(Ordering::Relaxed)
    }
}

/// The device's side of the hand: sets the sensor's attitude and rate sample by sample.
pub(crate) struct SimHand {
    cue: HandCue,
    served: u32,
    ups: Vec<[f32; 3]>,
    next: usize,
    turns: u32,
    turn_samples: u32,
    sample_rate_hz: u32,
    turning_left: u32,
    /// A tilt under way.
    tilting: Option<Tilt>,
}

impl SimHand {
    /// A hand for a device sampling at `sample_rate_hz`, with the cue that drives it.
    pub(crate) fn new(sample_rate_hz: u32) -> (SimHand, HandCue) {
        let cue = HandCue::default();
        let plan_ups: Vec<[f64; 3]> = builtin_plan("hand")
            .and_then(Result::ok)
            .map(|p| p.segments.iter().map(|s| s.up_b).collect())
            .unwrap_or_default();
        let ups = plan_ups
            .iter()
            .enumerate()
            .map(|(k, up)| off_aim(up, k))
            .collect();
        let hand = SimHand {
            cue: cue.clone(),
            served: 0,
            ups,
            next: 0,
            turns: 0,
            turn_samples: (TURN_S * f64::from(sample_rate_hz)).round().max(1.0) as u32,
            sample_rate_hz: sample_rate_hz.max(1),
            turning_left: 0,
            tilting: None,
        };
        (hand, cue)
    }

    /// Before a sample: what the hand does to the unit now, if it changes anything.
    pub(crate) fn step(&mut self, current: &VirtualTable) -> Option<HandMove> {
        let fs = f64::from(self.sample_rate_hz);
        if let Some(tilt) = self.tilting.as_mut() {
            tilt.done += 1;
            if tilt.done < tilt.samples {
                return Some(tilt.at(tilt.done, fs));
            }
            let to = tilt.to;
            self.tilting = None;
            return Some(HandMove::Table(still(to)));
        }
        if self.turning_left > 0 {
            self.turning_left -= 1;
            if self.turning_left > 0 {
                return None;
            }
            return Some(self.tilt_to_next(current.up_b));
        }
        if self.cue.requested() == self.served {
            return None;
        }
        self.served = self.served.wrapping_add(1);
        self.turning_left = self.turn_samples;
        Some(HandMove::Table(VirtualTable {
            up_b: current.up_b,
            rate_rad_s: TURN_RATE_DEG_S.to_radians() as f32,
            accel_rad_s2: 0.0,
        }))
    }

    /// The end of a spin: the tilt along the great circle from `from` to the next attitude, at
    /// [`TURN_RATE_DEG_S`] rounded to whole samples (or the unit set down, when the next attitude
    /// is this one).
    fn tilt_to_next(&mut self, from: [f32; 3]) -> HandMove {
        self.turns += 1;
        if !(self.turns % REPEAT_EVERY == 0 && self.next > 0) {
            self.next += 1;
        }
        let n = self.ups.len().max(1);
        let to = self
            .ups
            .get((self.next.max(1) - 1) % n)
            .copied()
            .unwrap_or(from);
        let (u0, u1) = (from.map(f64::from), to.map(f64::from));
        let angle = linalg::dot(&u0, &u1).clamp(-1.0, 1.0).acos();
        let fs = f64::from(self.sample_rate_hz);
        let samples = (angle / TURN_RATE_DEG_S.to_radians() * fs).round();
        if samples < 1.0 {
            return HandMove::Table(still(to));
        }
        // `du/dt = u × ω` carries u0 to u1 about a = u0 × u1 when ω = −(angle/T)·a.
        let axis = match linalg::unit(&linalg::cross(&u0, &u1)) {
            a if a.iter().all(|x| x.is_finite()) && linalg::norm(&a) > 0.5 => a,
            _ => perpendicular(&u0),
        };
        let tilt = Tilt {
            from: u0,
            to,
            axis,
            rate: angle / (samples / fs),
            done: 0,
            samples: samples as u32,
        };
        self.tilting = Some(tilt);
        tilt.at(0, fs)
    }
}

/// The unit at rest with `up_b` up.
fn still(up_b: [f32; 3]) -> VirtualTable {
    VirtualTable {
        up_b,
        rate_rad_s: 0.0,
        accel_rad_s2: 0.0,
    }
}

/// A unit vector perpendicular to `up`.
fn perpendicular(up: &[f64; 3]) -> [f64; 3] {
    let helper = if up[0].abs() < 0.9 {
        [1.0, 0.0, 0.0]
    } else {
        [0.0, 1.0, 0.0]
    };
    linalg::unit(&linalg::cross(up, &helper))
}

/// `up` turned by [`AIM_ERROR_DEG`] towards a direction perpendicular to it that rotates with `k`.
fn off_aim(up: &[f64; 3], k: usize) -> [f32; 3] {
    // Any vector not along `up`, crossed with it, gives a perpendicular; rotate it about `up` by k
    // times the golden angle so that successive errors point different ways.
    let e1 = perpendicular(up);
    let e2 = linalg::cross(up, &e1);
    let phi = k as f64 * 2.399_963_229_728_653;
    let t = AIM_ERROR_DEG.to_radians();
    core::array::from_fn(|j| {
        let side = phi.cos() * e1[j] + phi.sin() * e2[j];
        (t.cos() * up[j] + t.sin() * side) as f32
    })
}

/// The operator who holds the simulated unit: progress printed as [`AutomaticOperator`] prints it,
/// each request to turn passed on to the hand.
pub struct HandOperator {
    /// Prints and keeps the warnings.
    pub inner: AutomaticOperator,
    /// The hand's cue.
    pub cue: HandCue,
}

impl Operator for HandOperator {
    fn say(&mut self, text: &str) {
        self.inner.say(text);
    }

    fn wait_ready(&mut self, instruction: &str) -> Result<(), ProcedureError> {
        self.inner.wait_ready(instruction)
    }

    fn turn_unit(&mut self, instruction: &str) {
        self.inner.say(instruction);
        self.cue.turn();
    }

    fn keep_despite(&mut self, segment: &str, problems: &[String]) -> Result<bool, ProcedureError> {
        self.inner.keep_despite(segment, problems)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn table(up_b: [f32; 3]) -> VirtualTable {
        VirtualTable {
            up_b,
            rate_rad_s: 0.0,
            accel_rad_s2: 0.0,
        }
    }

    #[test]
    fn the_hand_turns_only_when_asked_then_sets_the_unit_down_still() {
        let (mut hand, cue) = SimHand::new(100);
        let start = table([0.0, 0.0, 1.0]);
        assert_eq!(hand.step(&start), None, "not asked: the unit stays");
        cue.turn();
        let Some(HandMove::Table(spin)) = hand.step(&start) else {
            panic!("asked: it turns")
        };
        assert_eq!(spin.up_b, start.up_b);
        assert!((f64::from(spin.rate_rad_s).to_degrees() - TURN_RATE_DEG_S).abs() < 1e-3);
        // The spin lasts TURN_S (100 samples at 100 Hz), then the tilt to the first attitude.
        for _ in 0..99 {
            assert_eq!(hand.step(&spin), None);
        }
        let Some(HandMove::Tilt(from, omega)) = hand.step(&spin) else {
            panic!("a tilt after the spin")
        };
        assert_eq!(
            from,
            table(start.up_b),
            "the tilt starts still, where the spin left it"
        );
        let mut samples = 1;
        let down = loop {
            match hand.step(&from) {
                Some(HandMove::Tilt(_, w)) => {
                    assert_eq!(w, omega, "one rate through the tilt");
                    samples += 1;
                }
                Some(HandMove::Table(t)) => break t,
                None => panic!("a tilt moves the unit at every sample"),
            }
        };
        assert_eq!(down.rate_rad_s, 0.0);
        assert_eq!(down.up_b, hand.ups[0]);
        // The tilt's rate over its samples carries "up" from the start to the attitude set down
        // (du/dt = u × ω: up turned by −|ω|·t about ω).
        let w = omega.map(f64::from);
        let t = f64::from(samples) / 100.0;
        let rate = linalg::norm(&w);
        assert!((rate.to_degrees() - TURN_RATE_DEG_S).abs() < 2.0, "{rate}");
        let k = linalg::unit(&w);
        let u0 = start.up_b.map(f64::from);
        let (sn, c) = ((-rate * t).sin(), (-rate * t).cos());
        let kxu = linalg::cross(&k, &u0);
        let kdu = linalg::dot(&k, &u0);
        let u: [f64; 3] =
            core::array::from_fn(|j| u0[j] * c + kxu[j] * sn + k[j] * kdu * (1.0 - c));
        let u1 = down.up_b.map(f64::from);
        let miss = linalg::norm(&[u[0] - u1[0], u[1] - u1[1], u[2] - u1[2]]);
        // Within the single precision of the wire's rates and attitudes (10⁻⁵ rad is 2″).
        assert!(miss < 1e-5, "{u:?} vs {u1:?}");
        assert_eq!(hand.step(&down), None, "one turn per request");
    }

    /// The attitudes set down after each of `n` turns.
    fn set_down(hand: &mut SimHand, cue: &HandCue, n: u32) -> Vec<[f32; 3]> {
        let mut t = table([0.0, 0.0, 1.0]);
        let mut downs = Vec::new();
        for _ in 0..n {
            cue.turn();
            // A spin is 10 samples at 10 Hz, a tilt at most 20; give it a few more.
            for _ in 0..40 {
                match hand.step(&t) {
                    Some(HandMove::Table(next)) => {
                        t = next;
                        if t.rate_rad_s == 0.0 {
                            downs.push(t.up_b);
                            break;
                        }
                    }
                    Some(HandMove::Tilt(from, _)) => t = from,
                    None => {}
                }
            }
        }
        downs
    }

    #[test]
    fn every_seventh_turn_comes_back_to_the_position_before_it() {
        let (mut hand, cue) = SimHand::new(10);
        let downs = set_down(&mut hand, &cue, 15);
        assert_eq!(downs.len(), 15);
        for (k, d) in downs.iter().enumerate() {
            let turn = k as u32 + 1;
            if turn % REPEAT_EVERY == 0 {
                assert_eq!(*d, downs[k - 1], "turn {turn} repeats");
            } else {
                assert!(downs[..k].iter().all(|e| e != d), "turn {turn} is new");
            }
        }
        assert_eq!(downs[0], hand.ups[0]);
        assert_eq!(downs[14], hand.ups[12], "two repeats: two positions behind");
    }

    #[test]
    fn each_attitude_is_the_aim_error_off_the_plans_and_they_differ() {
        let plan = builtin_plan("hand").unwrap().unwrap();
        let (hand, _) = SimHand::new(100);
        assert_eq!(hand.ups.len(), plan.segments.len());
        for (seg, got) in plan.segments.iter().zip(&hand.ups) {
            let g = got.map(f64::from);
            let cos = shared::linalg::dot(&seg.up_b, &g) / shared::linalg::norm(&g);
            let off_deg = cos.clamp(-1.0, 1.0).acos().to_degrees();
            assert!((off_deg - AIM_ERROR_DEG).abs() < 1e-3, "{off_deg}°");
            assert!((shared::linalg::norm(&g) - 1.0).abs() < 1e-6);
        }
    }
}
