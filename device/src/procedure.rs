//! `host calibrate --port`: the whole loop against a device.
//!
//! Identify → for each plan segment, tell the operator what to do (or drive the virtual table of a
//! simulated or emulated device) → record raw windows with a live check that the data match the plan →
//! save the recording as it goes (the documented session format, readable by `host calibrate --input`) →
//! estimate → write `calibration.toml`/`.bin` → write the blob to the device → reset it → read it back →
//! verify the compensated output on held-out positions (`super::verify`) → one pass/fail line.
//!
//! A device streams window statistics, not every sample (a UART cannot carry 10 kHz of samples), so the
//! recording holds one row per window: the window's mean outputs and rates, with `sample_rate_hz` set to
//! the window rate. The estimator's weights stay right: the spread of the window means is the sample
//! noise divided by the window length, and there are that many times fewer rows.

use super::live_check::{instruction, table_for};
pub(crate) use super::live_check::{live_check, remount_check};
use super::operator::Operator;
use crate::{hand_session, handheld, window_log, DeviceClient, LinkError, Transport};
use app::{CalibrateError, CalibrateOptions, Calibrated};
use estimator::calibration_files::{self, OutputError, WrittenCalibration};
use recording::session::{self, Plan, RecordingError, SegmentPlan, SessionWriter};
use recording::spelling::Spelling;
use shared::chain::Chain;
use shared::wire::{Board, CalibrationState, Identity, StreamKind, VirtualTable};
use std::path::{Path, PathBuf};

/// Settings of the procedure.
#[derive(Clone, Debug)]
pub struct ProcedureOptions {
    /// The plan to run (durations default to 60 s per segment).
    pub plan: Plan,
    /// Where the recording and the result go (`OUT/recording/`, `OUT/calibration.toml`, `.bin`).
    pub out_dir: PathBuf,
    /// Samples per streamed window; default: a 50th of the sampling rate (20 windows per second).
    pub window_samples: Option<u32>,
    /// Time discarded after each set-up (table settling, ω̇ filter), s.
    pub settle_s: f64,
    /// The estimator's settings and the limits the result is checked against.
    pub calibrate: CalibrateOptions,
    /// Largest compensated error accepted at a verification position, mg.
    pub verify_tolerance_mg: f64,
    /// Seconds of data per verification position.
    pub verify_seconds: f64,
    /// A second temperature to verify at (at rest), °C: the virtual chamber is set to it, or the
    /// operator brings a real board there and its reading is checked.
    pub verify_temp_c: Option<f64>,
    /// Replace an existing recording and calibration in `out_dir`.
    pub force: bool,
    /// No progress bars.
    pub quiet: bool,
}

impl ProcedureOptions {
    /// Largest compensated error accepted at a verification position unless told otherwise, mg.
    pub const DEFAULT_VERIFY_TOLERANCE_MG: f64 = 1.0;

    /// Defaults for `plan` into `out_dir`, the messages spelled as the caller spells its options.
    pub fn new(plan: Plan, out_dir: PathBuf, spelling: Spelling) -> Self {
        ProcedureOptions {
            plan,
            out_dir,
            window_samples: None,
            settle_s: 0.5,
            calibrate: CalibrateOptions::new(spelling),
            verify_tolerance_mg: Self::DEFAULT_VERIFY_TOLERANCE_MG,
            verify_seconds: 2.0,
            verify_temp_c: None,
            force: false,
            quiet: false,
        }
    }
}

pub use super::verify::VerificationPoint;

/// Everything the procedure produced.
#[derive(Debug)]
pub struct ProcedureOutcome {
    /// Who the device said it was.
    pub identity: Identity,
    /// The saved recording.
    pub recording_dir: PathBuf,
    /// The calibration, estimated from the saved recording as `host calibrate --input` would; its
    /// document names the files written (the verification is the caller's to add).
    pub calibrated: Calibrated,
    /// The estimate's result tables ([`outputs::report::render_session`]), for the caller to print
    /// with its other results.
    pub report: String,
    /// The files written.
    pub written: WrittenCalibration,
    /// The device's state after the reset.
    pub state_after_reset: CalibrationState,
    /// Verification positions.
    pub verification: Vec<VerificationPoint>,
    /// Live-check warnings.
    pub warnings: Vec<String>,
    /// Output frames the device dropped (link too slow for the window length).
    pub dropped_frames: u32,
    /// All checks passed.
    pub passed: bool,
}

/// Why the procedure stopped. `Link`, `Estimate` and `HandSession` lead with their reason and say
/// after it where the data are kept: they show the reason (and its causes) and do not return it.
#[derive(Debug, thiserror::Error)]
pub enum ProcedureError {
    /// The link failed; what was recorded so far is saved at `recording` (if anything was).
    #[error(fmt = link_message)]
    Link {
        /// The link error.
        cause: LinkError,
        /// The saved recording and its row count.
        recording: Option<(PathBuf, u64)>,
    },
    /// The recording could not be written or read back.
    #[error(transparent)]
    Recording(#[from] RecordingError),
    /// No calibration could be estimated from the recording.
    #[error("{}\n(the recording is saved in {})", Chain(.cause), .recording.display())]
    Estimate {
        /// Why.
        cause: CalibrateError,
        /// The saved recording.
        recording: PathBuf,
    },
    /// The result could not be written.
    #[error(transparent)]
    Output(OutputError),
    /// The device did not apply the calibration after the reset.
    #[error(
        "after the reset the device reports its calibration as {0:?}, not the one written: \
         the write did not take; retry, and check the device's storage"
    )]
    NotApplied(CalibrationState),
    /// The calibration read back differs from the one written.
    #[error(
        "the calibration read back from the device differs from the one written: retry the write"
    )]
    ReadBackMismatch,
    /// The operator stopped.
    #[error("stopped by the operator ({0})")]
    Aborted(String),
    /// The terminal failed.
    #[error("terminal error")]
    Terminal(#[source] std::io::Error),
    /// A hand-held session's window log could not be opened.
    #[error(transparent)]
    WindowLog(window_log::WindowLogError),
    /// A hand-held session's window log could not be kept or gave no session.
    #[error(
        "{}\n(every window of the session is in {}: `{}` tells more)",
        Chain(.cause.as_ref()), .stream.display(), .command
    )]
    HandSession {
        /// Why.
        cause: Box<crate::hand_session::HandSessionError>,
        /// The window log.
        stream: PathBuf,
        /// The `host segment` command that reads it as the procedure did.
        command: String,
    },
}

/// [`ProcedureError::Link`]'s message: the link's, and where the recording so far is kept.
fn link_message(
    cause: &LinkError,
    recording: &Option<(PathBuf, u64)>,
    f: &mut std::fmt::Formatter<'_>,
) -> std::fmt::Result {
    match recording {
        Some((dir, rows)) => write!(
            f,
            "{}\nthe recording so far ({rows} windows) is saved in {}: the segments completed \
             can be estimated with `host calibrate --input {}`",
            Chain(cause),
            dir.display(),
            dir.display()
        ),
        None => write!(f, "{}", Chain(cause)),
    }
}

/// What the operator is told of the device before the procedure starts.
fn identity_line(identity: &Identity) -> String {
    format!(
        "device: {:?}, firmware {}.{}.{}, unit {}, {} Hz, calibration {:?}",
        identity.board,
        identity.firmware_version[0],
        identity.firmware_version[1],
        identity.firmware_version[2],
        identity.unit_id,
        identity.sample_rate_hz,
        identity.calibration
    )
}

/// The device can set its own table.
pub fn has_virtual_table(identity: &Identity) -> bool {
    matches!(identity.board, Board::Simulated | Board::QemuMps2An386)
}

// shape: reads better whole because it is the procedure's outline, one call per step in the order
// the operator sees them (identify, record, estimate, write, store, verify); what is left is the glue.
/// Runs the whole procedure.
pub fn run<T: Transport>(
    client: &mut DeviceClient<T>,
    opts: &ProcedureOptions,
    op: &mut dyn Operator,
) -> Result<ProcedureOutcome, ProcedureError> {
    let link = |source| ProcedureError::Link {
        cause: source,
        recording: None,
    };
    // Nothing is recorded over, and no run is wasted on a refusal at its end.
    calibration_files::refuse_overwrite(&opts.out_dir, opts.force)
        .map_err(ProcedureError::Output)?;
    let identity = client.identify().map_err(link)?;
    op.say(&identity_line(&identity));
    let fs = f64::from(identity.sample_rate_hz.max(1));
    let window = opts
        .window_samples
        .unwrap_or((identity.sample_rate_hz / 50).max(1));
    let window_rate = fs / f64::from(window);
    let drive = has_virtual_table(&identity);

    let plan = device_plan(&opts.plan, &identity, window_rate, drive, op);
    let hand = !drive && handheld::is_hand_held(&plan);
    if let Some(live) = client.view() {
        live.identity(&identity);
        live.plan(
            &plan,
            hand,
            window_rate,
            recording::session::segment::SAME_POSITION_DEG,
        );
    }
    let recording_dir = opts.out_dir.join("recording");
    if hand {
        log_every_window(client, opts, fs, window)?;
    }
    let Recorded { warnings, dropped } = record_plan(
        client,
        op,
        &plan,
        drive,
        (window, window_rate),
        opts,
        &recording_dir,
    )?;

    let phase = |client: &DeviceClient<T>, p: &str| {
        if let Some(live) = client.view() {
            live.phase(p);
        }
    };
    phase(client, "estimating");
    let session_dir = match client.finish_window_log() {
        Some(log) => segment_window_log(log, &plan, op, opts)?,
        None => recording_dir,
    };
    // Estimate from the saved recording: the one calibrate use case, as `host calibrate` on a
    // recording.
    let (session, mut calibrated) = app::calibrate_session_dir(
        &session_dir,
        &opts.calibrate,
        &session::ReadOptions { quiet: opts.quiet },
    )
    .map_err(|source| ProcedureError::Estimate {
        cause: source,
        recording: session_dir.clone(),
    })?;
    // The result table is the caller's to print (on stdout, with the other results).
    let report =
        outputs::report::render_session(&calibrated.outcome, &session.plan, &session.stats);

    let created = calibration_files::now_unix_s();
    let written = app::write_result(&opts.out_dir, &mut calibrated, created, opts.force)
        .map_err(ProcedureError::Output)?;

    phase(client, "storing");
    let after = store_on_device(client, op, &written, created)?;
    phase(client, "verifying");

    let verification = if hand {
        handheld::verify_magnitude(client, op, &plan, window, window_rate, opts, fs)
    } else {
        let frame = calibrated.outcome.static_split.frame;
        super::verify::verify(client, op, &plan, drive, frame, opts, fs)
    }
    .map_err(link)?;
    let passed = verification.iter().all(|v| v.pass);
    Ok(ProcedureOutcome {
        report,
        identity,
        recording_dir: session_dir,
        calibrated,
        written,
        state_after_reset: after.calibration,
        verification,
        warnings,
        dropped_frames: dropped,
        passed,
    })
}

/// A hand-held session logs every window, turns included: the gyro is fitted from the hand's
/// turns.
fn log_every_window<T: Transport>(
    client: &mut DeviceClient<T>,
    opts: &ProcedureOptions,
    fs: f64,
    window: u32,
) -> Result<(), ProcedureError> {
    let log = hand_session::open_log(&opts.out_dir, fs, window, opts.force)
        .map_err(ProcedureError::WindowLog)?;
    client.log_windows(log);
    Ok(())
}

/// The end of a hand-held session: its window log closed and segmented as `host segment` would
/// (the command said), into the session directory that is calibrated.
fn segment_window_log(
    log: Result<(PathBuf, u64), window_log::WindowLogError>,
    plan: &Plan,
    op: &mut dyn Operator,
    opts: &ProcedureOptions,
) -> Result<PathBuf, ProcedureError> {
    let stream = opts.out_dir.join(window_log::STREAM_FILE);
    let (stream, rows) = log.map_err(|e| hand_error(e.into(), &stream, plan, opts))?;
    let segmented = opts.out_dir.join(hand_session::SEGMENTED_DIR);
    op.say(&format!(
        "{} windows in {}: segmented as `{}` does, turns and all",
        rows,
        stream.display(),
        hand_session::segment_command(&stream, plan, &segmented)
    ));
    hand_session::segment_log(
        &stream,
        plan,
        &opts.out_dir,
        opts.force,
        opts.calibrate.estimate.spelling,
    )
    .map_err(|e| hand_error(e, &stream, plan, opts))
}

/// [`ProcedureError::HandSession`] for the window log at `stream`.
fn hand_error(
    source: hand_session::HandSessionError,
    stream: &Path,
    plan: &Plan,
    opts: &ProcedureOptions,
) -> ProcedureError {
    let segmented = opts.out_dir.join(hand_session::SEGMENTED_DIR);
    ProcedureError::HandSession {
        cause: Box::new(source),
        stream: stream.to_path_buf(),
        command: hand_session::segment_command(stream, plan, &segmented),
    }
}

/// The plan as this device records it: in the device's output unit (its raw outputs are what is
/// recorded and calibrated, so a plan written for another board, as the built-in plans in volts
/// are for counts, is corrected and the operator told), at its window rate, bound to its unit, and
/// with an exact fixture on a virtual table (docs/model.md §7) unless the plan says otherwise.
fn device_plan(
    plan: &Plan,
    identity: &Identity,
    window_rate: f64,
    drive: bool,
    op: &mut dyn Operator,
) -> Plan {
    let mut plan = plan.clone();
    if plan.output_unit != identity.output_unit {
        op.say(&format!(
            "the device's outputs are in {}: the plan's {} is replaced",
            identity.output_unit.symbol(),
            plan.output_unit.symbol()
        ));
        plan.output_unit = identity.output_unit;
    }
    plan.sample_rate_hz = window_rate;
    plan.unit_id = Some(identity.unit_id.to_string());
    if drive && plan.attitude_sigma_deg.is_none() {
        plan.attitude_sigma_deg = Some(0.0);
        plan.format_version = plan.format_version.max(2);
    }
    plan
}

/// What recording the plan leaves besides the files: the live checks' warnings and the most frames
/// the device dropped.
struct Recorded {
    warnings: Vec<String>,
    dropped: u32,
}

/// Records every segment of `plan` into `recording_dir` (synced at each segment end), with the live
/// check of each; stops, with the recording so far on disk, at a link error or when the operator
/// does not keep a segment that failed its check.
fn record_plan<T: Transport>(
    client: &mut DeviceClient<T>,
    op: &mut dyn Operator,
    plan: &Plan,
    drive: bool,
    (window, window_rate): (u32, f64),
    opts: &ProcedureOptions,
    recording_dir: &Path,
) -> Result<Recorded, ProcedureError> {
    let mut writer = SessionWriter::create(recording_dir, plan, opts.force)?;
    let mut warnings = Vec::new();
    let mut dropped = 0u32;

    let hand = !drive && handheld::is_hand_held(plan);
    let planned_free = plan.segments.iter().filter(|s| s.is_free()).count();
    let mut watcher = watcher_for(plan, window_rate);
    let mut static_done: Vec<(SegmentPlan, session::SegmentStats)> = Vec::new();
    for (index, seg) in plan.segments.iter().enumerate() {
        let saved = |w: &SessionWriter| Some((w.dir().to_path_buf(), w.rows()));
        if let (false, Some(live)) = (hand && seg.is_free(), client.view()) {
            live.table_step(index, seg);
        }
        if hand && seg.is_free() {
            handheld::wait_for_new_position(
                client,
                op,
                &mut watcher,
                window,
                window_rate,
                &seg.name,
            )
            .map_err(|source| ProcedureError::Link {
                cause: source,
                recording: saved(&writer),
            })?;
        }
        let result = record_segment(
            client,
            op,
            seg,
            drive,
            window,
            window_rate,
            opts,
            &mut writer,
        );
        match result {
            Ok((stats, rejected, drops)) => {
                dropped = dropped.max(drops);
                let mut problems = live_check(seg, &stats, rejected);
                if hand && seg.is_free() {
                    take_position(client.view(), &mut watcher, &stats);
                    op.say(&watcher.guidance(planned_free));
                } else {
                    if let Some(live) = client.view() {
                        live.table_recorded(index, seg, &stats);
                    }
                    if seg.is_static() {
                        problems.extend(remount_check(seg, &stats, &static_done));
                        static_done.push((seg.clone(), stats.clone()));
                    }
                }
                if !problems.is_empty() && !op.keep_despite(&seg.name, &problems)? {
                    writer.end_segment()?;
                    return Err(ProcedureError::Aborted(format!(
                        "segment '{}' failed its live check; the recording so far is in {}",
                        seg.name,
                        recording_dir.display()
                    )));
                }
                warnings.extend(
                    problems
                        .into_iter()
                        .map(|p| format!("segment '{}': {p}", seg.name)),
                );
            }
            Err(source) => {
                // Whatever was recorded reaches the disk before the error is reported.
                writer.end_segment()?;
                return Err(ProcedureError::Link {
                    cause: source,
                    recording: saved(&writer),
                });
            }
        }
        writer.end_segment()?;
        client.flush_window_log();
    }
    writer.finish()?;
    if dropped > 0 {
        warnings.push(format!(
            "the device dropped {dropped} output frames: the link is too slow for {window}-sample windows; \
             use a longer --window"
        ));
    }
    Ok(Recorded { warnings, dropped })
}

/// The watcher of a hand-held plan's positions, with the plan's aims as its targets.
fn watcher_for(plan: &Plan, window_rate: f64) -> handheld::PositionWatcher {
    let mut watcher = handheld::PositionWatcher::new(
        plan.output_unit,
        window_rate,
        recording::session::segment::SAME_POSITION_DEG,
    );
    watcher.set_aims(&plan.segments.iter().map(|s| s.up_b).collect::<Vec<_>>());
    watcher
}

/// A hand-held position just recorded: the watcher takes it with its mean's 1σ (which weighs it in
/// the predicted 1σ), and the live page shows the coverage it gives.
fn take_position(
    live: Option<&crate::view::Live>,
    watcher: &mut handheld::PositionWatcher,
    stats: &session::SegmentStats,
) {
    let n = stats.count.max(1) as f64;
    let sigma = core::array::from_fn(|j| (stats.cov_u[j][j] / n).sqrt());
    watcher.accept_with_spread(stats.mean_u, stats.mean_w_rad_s, sigma);
    if let Some(live) = live {
        live.hand_recorded(watcher.coverage());
    }
}

/// Writes the blob, resets the device and checks that it applied it and reads it back unchanged.
fn store_on_device<T: Transport>(
    client: &mut DeviceClient<T>,
    op: &mut dyn Operator,
    written: &WrittenCalibration,
    created: u64,
) -> Result<Identity, ProcedureError> {
    let link = |source| ProcedureError::Link {
        cause: source,
        recording: None,
    };
    client.write_calibration(&written.blob).map_err(link)?;
    op.say("calibration written to the device; resetting it");
    let after = client.reset().map_err(link)?;
    if after.calibration
        != (CalibrationState::Valid {
            created_unix_s: created,
        })
    {
        return Err(ProcedureError::NotApplied(after.calibration));
    }
    let back = client.read_calibration().map_err(link)?;
    if back != written.blob {
        return Err(ProcedureError::ReadBackMismatch);
    }
    op.say("read back: identical");
    Ok(after)
}

/// Sets up and records one segment; returns its statistics, rejected samples and dropped frames.
#[allow(clippy::too_many_arguments)]
fn record_segment<T: Transport>(
    client: &mut DeviceClient<T>,
    op: &mut dyn Operator,
    seg: &SegmentPlan,
    drive: bool,
    window: u32,
    window_rate: f64,
    opts: &ProcedureOptions,
    writer: &mut SessionWriter,
) -> Result<(session::SegmentStats, u64, u32), LinkError> {
    let ramp = seg.rate_end_deg_s.is_some_and(|r1| r1 != seg.rate_deg_s);
    if drive {
        op.say(&format!("{} (virtual table driven)", instruction(seg)));
        let table = table_for(seg);
        if let Some(t) = chamber_temperature_c(seg, 0.0) {
            client.set_temperature(t)?;
        }
        if ramp {
            // Settle at the ramp's start rate, then start the ramp with the recording: settling after
            // the ramp had begun would record a later, faster part than the plan's.
            client.set_table(VirtualTable {
                accel_rad_s2: 0.0,
                ..table
            })?;
            settle_windows(client, window, (opts.settle_s * window_rate).round() as u64)?;
        }
        client.set_table(table)?;
    } else if seg.is_free() && seg.is_static() {
        // Hand-held: the unit was already found still at a new position.
    } else {
        op.wait_ready(&instruction(seg))
            .map_err(|e| LinkError::Unexpected {
                waiting_for: "the operator",
                got: Chain(&e).to_string(),
            })?;
    }
    let duration = seg.duration_s.unwrap_or(60.0);
    let n_windows = (duration * window_rate).round().max(1.0) as u64;
    let settle = if ramp && drive {
        0
    } else {
        (opts.settle_s * window_rate).round() as u64
    };
    client.start_stream(StreamKind::RawWindows, window)?;
    for _ in 0..settle {
        client.next_raw_window()?;
    }
    let bar = recording::ui::progress_bar(n_windows, "recording", opts.quiet);
    bar.set_message(seg.name.clone());
    let mut acc = session::SegmentAccumulator::new(seg.name.clone());
    let mut rejected = 0u64;
    let mut dropped = 0u32;
    let fs = window_rate * f64::from(window);
    let chamber_ramp = drive && seg.temp_end_c.is_some();
    for k in 0..n_windows {
        if chamber_ramp {
            if let Some(t) = chamber_temperature_c(seg, (k as f64 + 0.5) / n_windows as f64) {
                client.send_temperature(t)?;
            }
        }
        let w = client.next_raw_window()?;
        let t = (w.first_sample as f64 + f64::from(w.count) / 2.0) / fs;
        let u = w.mean_raw.map(f64::from);
        let rate = w.mean_rate_rad_s.map(f64::from);
        rejected += u64::from(w.rejected);
        dropped = dropped.max(w.dropped_frames);
        if w.count > 0 {
            // A recording with temperature (format version 3) takes the window's mean reading; a
            // device without a sensor sends NaN, which the reader leaves out and reports.
            let temp_c = f64::from(w.mean_temp_c);
            let written = if writer.has_temperature() {
                acc.push_with_temperature(t, &u, &rate, temp_c);
                writer.write_row_with_temperature(&seg.name, t, &u, &rate, temp_c)
            } else {
                acc.push(t, &u, &rate);
                writer.write_row(&seg.name, t, &u, &rate)
            };
            written.map_err(|e| LinkError::Unexpected {
                waiting_for: "a writable recording",
                got: Chain(&e).to_string(),
            })?;
        }
        bar.inc(1);
    }
    bar.finish_and_clear();
    client.stop_stream()?;
    let stats = acc.finish().ok_or(LinkError::Unexpected {
        waiting_for: "usable windows",
        got: "only empty windows".into(),
    })?;
    Ok((stats, rejected, dropped))
}

/// The chamber temperature a segment asks for at `fraction` (0..1) of its recording, °C: its `temp_c`,
/// or along the ramp to `temp_end_c`. A virtual device's die follows it (the host drives it as it
/// drives the table); the recording keeps what the unit's sensor reads.
fn chamber_temperature_c(seg: &SegmentPlan, fraction: f64) -> Option<f32> {
    let t0 = seg.temp_c?;
    let t1 = seg.temp_end_c.unwrap_or(t0);
    Some((t0 + (t1 - t0) * fraction) as f32)
}

/// Streams and discards `n` windows (the table settling at a new set-up).
fn settle_windows<T: Transport>(
    client: &mut DeviceClient<T>,
    window: u32,
    n: u64,
) -> Result<(), LinkError> {
    client.start_stream(StreamKind::RawWindows, window)?;
    for _ in 0..n {
        client.next_raw_window()?;
    }
    client.stop_stream()
}

/// The plan a device gets by default: the oblique plan when its table is virtual (it observes all nine
/// lever-arm components), the hand plan for the simulated hand (it has no table), the paper's plan
/// otherwise (no fixture beyond the paper's is needed).
pub fn default_plan(identity: &Identity) -> Result<Plan, session::PlanError> {
    session::builtin::load_plan(if has_virtual_table(identity) {
        "oblique"
    } else if identity.board == Board::SimulatedHand {
        "hand"
    } else {
        "paper"
    })
}

/// `OUT` for a run: the given directory, or a new one per run in the current directory,
/// `calibration-<unit id>-<UTC time>` (a suffix `-2`, `-3`, … if that exists), so that a second run
/// never records over the first.
pub fn default_out_dir(out: Option<&Path>, identity: &Identity) -> PathBuf {
    if let Some(dir) = out {
        return dir.to_path_buf();
    }
    let base = format!(
        "calibration-{}-{}",
        identity.unit_id,
        calibration_files::utc_stamp(calibration_files::now_unix_s())
    );
    std::iter::once(PathBuf::from(&base))
        .chain((2..).map(|n| PathBuf::from(format!("{base}-{n}"))))
        .find(|dir| !dir.exists())
        .unwrap_or_default()
}

#[cfg(test)]
mod tests {
    use super::*;
    use recording::session::SegmentAccumulator;

    fn seg(up: [f64; 3], rate: f64) -> SegmentPlan {
        SegmentPlan {
            name: "s".into(),
            up_b: up,
            rate_deg_s: rate,
            rate_end_deg_s: None,
            duration_s: Some(1.0),
            table_centre_m: None,
            mount: None,
            ..SegmentPlan::default()
        }
    }

    /// Statistics of 200 windows with outputs `u` (± a small alternating noise) and gyro rate `w`.
    fn stats(u: [f64; 3], w_deg_s: [f64; 3]) -> session::SegmentStats {
        let mut acc = SegmentAccumulator::new("s");
        for k in 0..200 {
            let n = if k % 2 == 0 { 1e-5 } else { -1e-5 };
            acc.push(
                k as f64 * 0.02,
                &u.map(|v| v + n),
                &w_deg_s.map(f64::to_radians),
            );
        }
        acc.finish().unwrap()
    }

    #[test]
    fn matching_segments_pass() {
        assert!(live_check(
            &seg([1.0, 0.0, 0.0], 0.0),
            &stats([2.8, 2.4, 2.4], [0.0; 3]),
            0
        )
        .is_empty());
        let spin = stats([2.8, 2.4, 2.4], [200.0, 0.0, 0.0]);
        assert!(live_check(&seg([1.0, 0.0, 0.0], 200.0), &spin, 0).is_empty());
    }

    #[test]
    fn motion_wrong_rate_upside_down_and_wrong_axis_are_named() {
        let moving = live_check(
            &seg([1.0, 0.0, 0.0], 0.0),
            &stats([2.8, 2.4, 2.4], [0.0, 3.0, 0.0]),
            0,
        );
        assert!(moving[0].contains("should be at rest"), "{moving:?}");
        let slow = live_check(
            &seg([1.0, 0.0, 0.0], 200.0),
            &stats([2.8; 3], [150.0, 0.0, 0.0]),
            0,
        );
        assert!(slow[0].contains("the plan says +200.0"), "{slow:?}");
        let flipped = live_check(
            &seg([1.0, 0.0, 0.0], 200.0),
            &stats([2.8; 3], [-200.0, 0.0, 0.0]),
            0,
        );
        assert!(flipped[0].contains("upside down"), "{flipped:?}");
        let tilted = live_check(
            &seg([0.0, 0.0, 1.0], 100.0),
            &stats([2.8; 3], [0.0, 100.0, 0.0]),
            0,
        );
        assert!(
            tilted.iter().any(|p| p.contains("rotation axis")),
            "{tilted:?}"
        );
        let saturated = live_check(&seg([1.0, 0.0, 0.0], 0.0), &stats([2.8; 3], [0.0; 3]), 12);
        assert!(
            saturated[0].contains("12 samples were saturated"),
            "{saturated:?}"
        );
    }

    #[test]
    fn a_unit_left_in_the_previous_mount_is_caught() {
        let x_up = (
            seg([1.0, 0.0, 0.0], 0.0),
            stats([2.80, 2.39, 2.43], [0.0; 3]),
        );
        let y_up = seg([0.0, 1.0, 0.0], 0.0);
        let same = stats([2.80, 2.39, 2.43], [0.0; 3]);
        let p = remount_check(&y_up, &same, std::slice::from_ref(&x_up)).unwrap();
        assert!(
            p.contains("not re-mounted") && p.contains("x-axis up"),
            "{p}"
        );
        let moved = stats([2.41, 2.78, 2.43], [0.0; 3]);
        assert!(remount_check(&y_up, &moved, &[x_up]).is_none());
    }
}
