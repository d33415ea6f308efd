//! The operator's live page (`host calibrate --port … --view`): what the procedure is doing, where
//! the unit points, what is covered, what to do next and, at the end, the result. The procedure
//! feeds a [`Live`] (its windows through the client's tap, its steps through [`Live`]'s methods);
//! [`server`] serves its snapshot as JSON beside one HTML page built into the binary, read-only.
//!
//! `guide` holds what the page and the terminal prompts both say: gravity's direction, the
//! targets still missing and the turn that reaches the best of them.

pub(crate) mod guide;
pub mod server;

use crate::handheld::{STILL_ACC_STD_REL, STILL_GYRO_STD_RAD_S, STILL_HOLD_S};
use guide::{table_sigma, turn_words, Coverage, Target};
use recording::session::{Plan, SegmentPlan, SegmentStats};
use serde::Serialize;
use serde_json::Value;
use shared::linalg;
use shared::wire::{Identity, RawWindow};
use std::collections::VecDeque;
use std::sync::{Arc, Mutex, MutexGuard};

/// A watched session: the state and the server that shows it.
pub struct Viewed {
    /// The state the procedure feeds.
    pub live: Live,
    server: server::ViewServer,
}

impl Viewed {
    /// Serves a new state on a free port of 127.0.0.1, says where on stderr and opens it in the
    /// user's browser where one is set up (`$BROWSER`, or `xdg-open` with a display).
    pub fn start() -> Result<Viewed, server::ViewError> {
        let live = Live::new();
        let server = server::ViewServer::start(live.clone())?;
        let url = server.url();
        let opened = server::open_in_browser(&url);
        eprintln!(
            "live page: {url}{}",
            if opened {
                " (opened in the browser)"
            } else {
                ""
            }
        );
        Ok(Viewed { live, server })
    }

    /// The page's address.
    pub fn url(&self) -> String {
        self.server.url()
    }

    /// Keeps the page up after the session, with its result, until Enter (or the end of standard
    /// input: nothing waits when no one can answer).
    pub fn linger(&self) {
        use std::io::{BufRead, IsTerminal};
        if std::io::stdin().is_terminal() {
            eprintln!(
                "the result stays on {} — press Enter to stop serving it",
                self.url()
            );
        }
        let mut line = String::new();
        let _ = std::io::stdin().lock().read_line(&mut line);
    }
}

/// The live state, shared between the procedure and the page's server.
#[derive(Clone, Default)]
pub struct Live(Arc<Mutex<State>>);

/// The device as the page names it.
#[derive(Clone, Debug, Serialize)]
struct DeviceInfo {
    board: String,
    unit_id: String,
    output_unit: String,
    sample_rate_hz: u32,
}

/// The latest window, in the device's units and, once the rough scale is known, in g.
#[derive(Clone, Debug, Default, Serialize)]
struct LiveReading {
    output: [f64; 3],
    force_g: Option<[f64; 3]>,
    force_norm_g: Option<f64>,
    rate_deg_s: [f64; 3],
    up_b: Option<[f64; 3]>,
    /// Where `up_b` comes from: "gravity" (the rough scale) or "table" (the plan's mount).
    up_from: Option<&'static str>,
    temp_c: Option<f64>,
    t_s: f64,
}

/// How still the unit is over the last hold, against the thresholds the recording uses.
#[derive(Clone, Debug, Default, Serialize)]
struct Stillness {
    acc_std_rel: f64,
    acc_limit_rel: f64,
    rate_std_deg_s: f64,
    rate_limit_deg_s: f64,
    /// The larger of the two ratios to their limits: below 1 is still.
    ratio: f64,
    still: bool,
    hold_s: f64,
}

/// A recorded position or segment.
#[derive(Clone, Debug, Serialize)]
struct Recorded {
    name: String,
    up_b: Option<[f64; 3]>,
    rate_deg_s: f64,
}

/// What the operator is asked to do now.
#[derive(Clone, Debug, Serialize)]
struct Step {
    label: String,
    target: Option<Target>,
    words: String,
    rate_deg_s: f64,
}

#[derive(Clone, Debug, Default, Serialize)]
struct Progress {
    positions_done: usize,
    positions_needed: usize,
    positions_planned: usize,
    turns_done: usize,
    turns_planned: usize,
    segments_done: usize,
    segments_planned: usize,
    sigma_bias_mg: Option<f64>,
    sigma_scale_ppm: Option<f64>,
    sigma_model: &'static str,
}

#[derive(Default)]
struct State {
    seq: u64,
    phase: String,
    device: Option<DeviceInfo>,
    hand_held: bool,
    plan: Option<Plan>,
    coverage: Coverage,
    table_ups: Vec<[f64; 3]>,
    recorded: Vec<Recorded>,
    step: Option<Step>,
    /// The update at which `step` was set.
    step_seq: u64,
    reading: LiveReading,
    recent: VecDeque<([f64; 3], [f64; 3])>,
    hold: usize,
    stillness: Stillness,
    progress: Progress,
    messages: VecDeque<String>,
    result: Option<Value>,
    next: Vec<String>,
    windows: u64,
    first_sample: Option<u64>,
    sample_rate_hz: f64,
}

/// Messages kept for the page.
const MESSAGES: usize = 8;

impl Live {
    /// An empty state (phase "connecting").
    pub fn new() -> Live {
        let live = Live::default();
        live.edit(|s| s.phase = "connecting".into());
        live
    }

    fn lock(&self) -> MutexGuard<'_, State> {
        // A panic while holding the lock leaves a state that is still whole enough to show.
        self.0.lock().unwrap_or_else(|e| e.into_inner())
    }

    fn edit(&self, f: impl FnOnce(&mut State)) {
        let mut s = self.lock();
        f(&mut s);
        s.seq += 1;
    }

    /// The device.
    pub fn identity(&self, id: &Identity) {
        self.edit(|s| {
            s.device = Some(DeviceInfo {
                board: format!("{:?}", id.board),
                unit_id: id.unit_id.to_string(),
                output_unit: id.output_unit.symbol().to_string(),
                sample_rate_hz: id.sample_rate_hz,
            });
            s.coverage.zero_centred = id.output_unit != shared::OutputUnit::Volts;
            s.sample_rate_hz = f64::from(id.sample_rate_hz.max(1));
        });
    }

    /// The plan as recorded, hand-held or on a table, at `window_rate` windows per second.
    pub fn plan(&self, plan: &Plan, hand_held: bool, window_rate: f64, same_position_deg: f64) {
        self.edit(|s| {
            s.hand_held = hand_held;
            s.hold = ((STILL_HOLD_S * window_rate).round() as usize).max(3);
            let zero_centred = s.coverage.zero_centred;
            let aims: Vec<[f64; 3]> = if hand_held {
                plan.segments.iter().map(|g| g.up_b).collect()
            } else {
                Vec::new()
            };
            s.coverage = Coverage::new(zero_centred, same_position_deg, &aims);
            if !hand_held {
                s.coverage.targets = plan
                    .segments
                    .iter()
                    .map(|g| Target {
                        label: g.name.clone(),
                        up_b: linalg::unit(&g.up_b),
                        done: false,
                    })
                    .collect();
            }
            let free = plan.segments.iter().filter(|g| g.is_free()).count();
            s.progress = Progress {
                positions_needed: if hand_held {
                    recording::session::segment::MIN_POSITIONS
                } else {
                    plan.segments.iter().filter(|g| g.is_static()).count()
                },
                positions_planned: if hand_held {
                    free
                } else {
                    plan.segments.iter().filter(|g| g.is_static()).count()
                },
                turns_planned: if hand_held {
                    free.saturating_sub(1)
                } else {
                    plan.segments.iter().filter(|g| !g.is_static()).count()
                },
                segments_planned: plan.segments.len(),
                sigma_model: if hand_held {
                    "magnitude of gravity, free attitudes (docs/model.md §7)"
                } else {
                    "known mounts, linear per axis (docs/model.md §2)"
                },
                ..Progress::default()
            };
            s.plan = Some(plan.clone());
            s.phase = "recording".into();
        });
    }

    /// A line the operator is told (the terminal's words).
    pub fn say(&self, text: &str) {
        self.edit(|s| {
            s.messages.push_back(text.to_string());
            while s.messages.len() > MESSAGES {
                s.messages.pop_front();
            }
        });
    }

    /// The procedure's phase ("recording", "estimating", "storing", "verifying", "done").
    pub fn phase(&self, phase: &str) {
        self.edit(|s| s.phase = phase.into());
    }

    /// A table segment is being set up and recorded.
    pub fn table_step(&self, index: usize, seg: &SegmentPlan) {
        self.edit(|s| {
            let now = s.reading.up_b;
            let target = s.coverage.targets.get(index).cloned();
            s.step_seq = s.seq + 1;
            s.step = Some(Step {
                label: seg.name.clone(),
                words: format!(
                    "{}{}",
                    turn_words(now.as_ref(), &seg.up_b),
                    if seg.rate_deg_s != 0.0 {
                        format!(", table at {:+.0} °/s", seg.rate_deg_s)
                    } else {
                        ", table at rest".into()
                    }
                ),
                target,
                rate_deg_s: seg.rate_deg_s,
            });
        });
    }

    /// The hand-held procedure waits for a new position: the coverage so far (the watcher's, whose
    /// words the terminal prints too), the best open target and the turn that reaches it. While
    /// verifying, the recording's coverage stays on the page.
    pub fn hand_step(&self, label: &str, coverage: &Coverage, next: Option<(Target, String)>) {
        self.edit(|s| {
            let verifying = s.phase == "verifying";
            if !verifying {
                s.set_hand_coverage(coverage);
            }
            let (target, words) = match next {
                // A check needs only a new position: the recording's targets stay as they were.
                _ if verifying => (
                    None,
                    "turn to a position not recorded before and hold it still: |f| must be 1 g"
                        .into(),
                ),
                Some((t, w)) => (Some(t), w),
                None => (
                    None,
                    "every target is covered: turn to any new position".into(),
                ),
            };
            s.step_seq = s.seq + 1;
            s.step = Some(Step {
                label: label.into(),
                target,
                words,
                rate_deg_s: 0.0,
            });
        });
    }

    /// A hand-held position was recorded: the watcher's coverage with it.
    pub fn hand_recorded(&self, coverage: &Coverage) {
        self.edit(|s| {
            s.set_hand_coverage(coverage);
            s.progress.segments_done += 1;
            // The best next target changes with each position: never show the one just reached.
            let (target, words) = match coverage.next_step() {
                Some((t, w)) => (Some(t), w),
                None => (
                    None,
                    "every target is covered: turn to any new position".into(),
                ),
            };
            s.step_seq = s.seq + 1;
            s.step = Some(Step {
                label: format!("after position {}", coverage.outputs.len()),
                target,
                words,
                rate_deg_s: 0.0,
            });
        });
    }

    /// A table segment was recorded (its statistics in the device's units).
    pub fn table_recorded(&self, index: usize, seg: &SegmentPlan, stats: &SegmentStats) {
        self.edit(|s| {
            if let Some(t) = s.coverage.targets.get_mut(index) {
                t.done = true;
            }
            s.recorded.push(Recorded {
                name: seg.name.clone(),
                up_b: Some(linalg::unit(&seg.up_b)),
                rate_deg_s: seg.rate_deg_s,
            });
            s.progress.segments_done += 1;
            if !seg.is_static() {
                s.progress.turns_done += 1;
                return;
            }
            s.progress.positions_done += 1;
            let n = stats.count.max(1) as f64;
            s.coverage.outputs.push(stats.mean_u);
            s.coverage
                .sigma_out
                .push(core::array::from_fn(|j| (stats.cov_u[j][j] / n).sqrt()));
            s.table_ups.push(linalg::unit(&seg.up_b));
            // The 1σ in g needs the scale: half each axis's spread over the mounts so far.
            if let Some(g) = rough_span(&s.coverage.outputs) {
                let pts: Vec<([f64; 3], f64)> = s
                    .table_ups
                    .iter()
                    .zip(&s.coverage.sigma_out)
                    .map(|(d, so)| (*d, (0..3).map(|j| so[j] / g[j]).fold(0.0, f64::max)))
                    .collect();
                let sigma = table_sigma(&pts);
                s.progress.sigma_bias_mg = sigma.map(|v| v.0);
                s.progress.sigma_scale_ppm = sigma.map(|v| v.1);
            }
        });
    }

    /// The result: the command's own JSON document, and the next commands to run.
    pub fn finish<D: Serialize>(&self, document: &D, next: Vec<String>) {
        let doc = serde_json::to_value(document).unwrap_or(Value::Null);
        self.edit(|s| {
            s.result = Some(doc);
            s.next = next;
            s.step = None;
            s.step_seq = s.seq + 1;
            s.phase = "done".into();
        });
    }

    /// The session stopped without a result.
    pub fn failed(&self, why: &str) {
        self.edit(|s| {
            s.phase = "failed".into();
            s.step = None;
            s.step_seq = s.seq + 1;
            s.messages.push_back(why.to_string());
        });
    }

    /// A raw window from the device: the live reading and the stillness over the last hold.
    pub fn window(&self, w: &RawWindow) {
        self.edit(|s| s.window(w));
    }

    /// The number of the latest update.
    pub fn seq(&self) -> u64 {
        self.lock().seq
    }

    /// The state as the page reads it.
    pub fn snapshot(&self) -> Value {
        let s = self.lock();
        serde_json::json!({
            "seq": s.seq,
            "phase": s.phase,
            "device": s.device,
            "mode": if s.hand_held { "hand-held" } else { "table" },
            "live": s.reading,
            "stillness": s.stillness,
            "recorded": s.recorded,
            "targets": s.coverage.targets,
            "step": s.step,
            "step_seq": s.step_seq,
            "progress": s.progress,
            "messages": s.messages,
            "result": s.result,
            "next": s.next,
            "windows": s.windows,
        })
    }
}

/// Half the spread of each axis's output over the positions, output per g: the scale once two
/// opposite mounts of each axis are in.
fn rough_span(outputs: &[[f64; 3]]) -> Option<[f64; 3]> {
    let g: [f64; 3] = core::array::from_fn(|j| {
        let (lo, hi) = outputs
            .iter()
            .fold((f64::INFINITY, f64::NEG_INFINITY), |(l, h), u| {
                (l.min(u[j]), h.max(u[j]))
            });
        (hi - lo) / 2.0
    });
    g.iter().all(|v| *v > 0.0).then_some(g)
}

impl State {
    fn set_hand_coverage(&mut self, coverage: &Coverage) {
        self.coverage = coverage.clone();
        let ups = self.coverage.ups();
        self.recorded = (0..self.coverage.outputs.len())
            .map(|k| Recorded {
                name: format!("position {}", k + 1),
                up_b: ups.as_ref().map(|u| u[k]),
                rate_deg_s: 0.0,
            })
            .collect();
        self.progress.positions_done = self.coverage.outputs.len();
        self.progress.turns_done = self.progress.positions_done.saturating_sub(1);
        let sigma = self.coverage.sigma();
        self.progress.sigma_bias_mg = sigma.map(|v| v.0);
        self.progress.sigma_scale_ppm = sigma.map(|v| v.1);
    }

    fn window(&mut self, w: &RawWindow) {
        self.windows += 1;
        let u = w.mean_raw.map(f64::from);
        let rate = w.mean_rate_rad_s.map(f64::from);
        self.recent.push_back((u, rate));
        while self.recent.len() > self.hold.max(3) {
            self.recent.pop_front();
        }
        let rough = if self.hand_held {
            self.coverage.rough()
        } else {
            guide::rough_scale(self.coverage.zero_centred, &self.coverage.outputs)
        };
        let force = rough.map(|r| r.force_g(&u));
        let (up, from) = match (&force, &self.step) {
            (Some(f), _) => (Some(linalg::unit(f)), Some("gravity")),
            (None, Some(step)) if !self.hand_held => {
                (step.target.as_ref().map(|t| t.up_b), Some("table"))
            }
            _ => (None, None),
        };
        let temp = f64::from(w.mean_temp_c);
        self.reading = LiveReading {
            output: u,
            force_g: force,
            force_norm_g: force.map(|f| linalg::norm(&f)),
            rate_deg_s: rate.map(f64::to_degrees),
            up_b: up,
            up_from: from,
            temp_c: temp.is_finite().then_some(temp),
            t_s: {
                let first = *self.first_sample.get_or_insert(w.first_sample);
                w.first_sample.saturating_sub(first) as f64 / self.sample_rate_hz.max(1.0)
            },
        };
        self.stillness = stillness(&self.recent, self.hold);
    }
}

/// A window's mean output and mean rate.
type Window = ([f64; 3], [f64; 3]);

/// The spread of the window means over the last hold, against the hand-held procedure's limits
/// (`handheld::PositionWatcher` takes a position below both).
fn stillness(recent: &VecDeque<([f64; 3], [f64; 3])>, hold: usize) -> Stillness {
    let n = recent.len().max(1) as f64;
    let spread = |f: &dyn Fn(&Window) -> [f64; 3]| {
        let m: [f64; 3] = core::array::from_fn(|j| recent.iter().map(|w| f(w)[j]).sum::<f64>() / n);
        let var = recent
            .iter()
            .map(|w| (0..3).map(|j| (f(w)[j] - m[j]).powi(2)).sum::<f64>())
            .sum::<f64>()
            / n;
        (m, var.sqrt())
    };
    let (mu, su) = spread(&|w| w.0);
    let (_, sw) = spread(&|w| w.1);
    let acc_rel = su / linalg::norm(&mu).max(f64::MIN_POSITIVE);
    let ratio = (acc_rel / STILL_ACC_STD_REL).max(sw / STILL_GYRO_STD_RAD_S);
    Stillness {
        acc_std_rel: acc_rel,
        acc_limit_rel: STILL_ACC_STD_REL,
        rate_std_deg_s: sw.to_degrees(),
        rate_limit_deg_s: STILL_GYRO_STD_RAD_S.to_degrees(),
        ratio,
        still: recent.len() >= hold && ratio < 1.0,
        hold_s: STILL_HOLD_S,
    }
}

/// An operator whose every line also goes to the live page.
pub struct ViewOperator<'a> {
    /// Who really turns the unit (a person, the automatic table, the simulated hand).
    pub inner: &'a mut dyn crate::operator::Operator,
    /// The page.
    pub live: Live,
}

impl crate::operator::Operator for ViewOperator<'_> {
    fn say(&mut self, text: &str) {
        self.live.say(text);
        self.inner.say(text);
    }

    fn wait_ready(&mut self, instruction: &str) -> Result<(), crate::procedure::ProcedureError> {
        self.live.say(instruction);
        self.inner.wait_ready(instruction)
    }

    fn turn_unit(&mut self, instruction: &str) {
        self.live.say(instruction);
        self.inner.turn_unit(instruction);
    }

    fn keep_despite(
        &mut self,
        segment: &str,
        problems: &[String],
    ) -> Result<bool, crate::procedure::ProcedureError> {
        for p in problems {
            self.live.say(&format!("segment '{segment}': {p}"));
        }
        self.inner.keep_despite(segment, problems)
    }
}
