//! `host bringup`: the first checks of a board fresh from its first flash, each with a verdict and,
//! when it fails, the likely cause — before anyone spends an hour calibrating a board whose IMU
//! samples at the wrong rate or has a dead axis.
//!
//! From one identity and a few seconds of raw windows of the board at rest: the identity; that
//! samples flow at all (the F405 starts sampling only after the ICM-42688-P answered WHO_AM_I
//! 0x47 at boot; the protocol has no WHO_AM_I request, so samples are the evidence); the sample
//! rate measured on the host's clock against the one the identity states; samples lost (FIFO
//! overflow), rejected (saturated, invalid) and frames dropped; the temperature; every axis alive
//! (its variance not exactly zero); the gravity vector's length at rest (in m/s² when a calibration
//! is applied, in counts at the F405's ±4 g, not checked for an uncalibrated analog unit); the
//! gyro's rate at rest.

use super::bringup_motion::{self as motion, NoOperator, Operator, Pose};
use super::client::{DeviceClient, LinkError, Transport};
use shared::wire::{
    CalibrationState, Health, Identity, RawWindow, SampleFlags, StreamKind, MIN_PROTOCOL_VERSION,
    PROTOCOL_VERSION,
};
use shared::OutputUnit;
use std::time::{Duration, Instant};

/// How far the measured sample rate may be from the stated one: a crystal is within 0.01 %, the
/// ICM-42688-P's own clock within ±1 % (DS-000347, ODR accuracy); what is left is the host's
/// timing of frames over a few seconds.
pub(crate) const RATE_TOLERANCE: f64 = 0.03;
/// Standard gravity, m/s².
const G: f64 = 9.80665;
/// Gravity's length at rest may differ from 1 g by this fraction (an uncalibrated part's scale
/// and bias: the ICM-42688-P's ±0.5 % sensitivity and ±20 mg offset, DS-000347 Table 2).
pub(crate) const GRAVITY_TOLERANCE: f64 = 0.05;
/// Counts per g of a version 3 device in counts (the F405's ICM-42688-P at ±4 g: 8192, DS-000347
/// Table 2); a version 4 device states its own in its health report.
pub(crate) const F405_LSB_PER_G: f64 = 8192.0;
/// The gyro's rate at rest may be this large, rad/s (3 °/s; the ICM-42688-P's zero-rate offset is
/// ±0.5 °/s, DS-000347 Table 1, so more means the board moved or the part is off).
pub(crate) const REST_RATE_LIMIT_RAD_S: f64 = 3.0 * std::f64::consts::PI / 180.0;
/// A die temperature outside this range, °C, is not a board on a bench.
pub(crate) const TEMPERATURE_RANGE_C: (f32, f32) = (-40.0, 85.0);

/// A check's outcome.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Verdict {
    /// Within its limits.
    Pass,
    /// Outside them; see the cause.
    Fail,
    /// Not measurable on this device (said why in the detail).
    Skipped,
}

/// One check.
#[derive(Clone, Debug, PartialEq)]
pub struct Check {
    /// What was checked.
    pub name: &'static str,
    /// Its outcome.
    pub verdict: Verdict,
    /// Measured against expected.
    pub detail: String,
    /// The likely cause of a failure.
    pub cause: Option<String>,
}

impl Check {
    pub(crate) fn new(
        name: &'static str,
        ok: bool,
        detail: String,
        cause: impl Into<String>,
    ) -> Check {
        Check {
            name,
            verdict: if ok { Verdict::Pass } else { Verdict::Fail },
            detail,
            cause: (!ok).then(|| cause.into()),
        }
    }

    pub(crate) fn skipped(name: &'static str, detail: impl Into<String>) -> Check {
        Check {
            name,
            verdict: Verdict::Skipped,
            detail: detail.into(),
            cause: None,
        }
    }
}

/// Every check, in order.
#[derive(Clone, Debug)]
pub struct Bringup {
    /// The device's identity.
    pub identity: Identity,
    /// The checks.
    pub checks: Vec<Check>,
}

impl Bringup {
    /// No check failed.
    pub fn passed(&self) -> bool {
        self.checks.iter().all(|c| c.verdict != Verdict::Fail)
    }

    /// The check named `name`.
    pub fn check(&self, name: &str) -> Option<&Check> {
        self.checks.iter().find(|c| c.name == name)
    }
}

/// The report as `host bringup` prints it: one line per check (`PASS`, `FAIL` or `SKIP`, its
/// name, what was measured against what), a failure's likely cause under it.
impl std::fmt::Display for Bringup {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        for c in &self.checks {
            let verdict = match c.verdict {
                Verdict::Pass => "PASS",
                Verdict::Fail => "FAIL",
                Verdict::Skipped => "SKIP",
            };
            writeln!(f, "{verdict}  {:<28} {}", c.name, c.detail)?;
            if let Some(cause) = &c.cause {
                writeln!(f, "      likely cause: {cause}")?;
            }
        }
        Ok(())
    }
}

/// Why the bring-up could not run.
#[derive(Debug, thiserror::Error)]
pub enum BringupError {
    /// The device did not identify itself (or the link failed).
    #[error("bring-up: the device did not identify itself")]
    Identify(#[source] LinkError),
    /// Starting or stopping the stream failed.
    #[error("bring-up: the device refused the stream")]
    Stream(#[source] LinkError),
}

/// The check names, as printed and as the tests look them up.
pub mod names {
    /// The identity.
    pub const IDENTITY: &str = "identity";
    /// Samples arrive (the IMU answered WHO_AM_I at boot).
    pub const SAMPLES: &str = "samples (WHO_AM_I at boot)";
    /// Measured against stated sample rate.
    pub const RATE: &str = "sample rate";
    /// Samples lost, rejected; frames dropped.
    pub const LOST: &str = "lost and invalid samples";
    /// The temperature.
    pub const TEMPERATURE: &str = "temperature";
    /// No axis stuck.
    pub const AXES: &str = "axes alive";
    /// Gravity's length at rest.
    pub const GRAVITY: &str = "gravity at rest";
    /// The gyro at rest.
    pub const GYRO_REST: &str = "gyro at rest";
    /// The part, its WHO_AM_I and its start (the device's health report).
    pub const PART: &str = "part and WHO_AM_I";
    /// The device's error counters.
    pub const COUNTERS: &str = "device error counters";
    /// Gravity along +z alone, the board flat and top up.
    pub const FLAT: &str = "flat, top up";
    /// Gravity along +x alone, the board nose up.
    pub const NOSE_UP: &str = "nose up";
    /// Noise at rest against the datasheet and across the axes.
    pub const NOISE: &str = "noise at rest";
    /// No repeated samples while waved.
    pub const REPEATS: &str = "repeated samples while waved";
}

/// Why a pose check was skipped without an operator.
const NO_OPERATOR: &str =
    "nobody to move the board (run at a terminal, or on the simulated device)";

/// Runs the checks on a device at rest, measuring for `measure` of the host's time; the checks
/// that need the board moved are skipped.
pub fn bringup<T: Transport>(
    client: &mut DeviceClient<T>,
    measure: Duration,
) -> Result<Bringup, BringupError> {
    bringup_with(client, measure, &mut NoOperator)
}

/// Runs the checks, the board at rest, flat and top up; then `operator` turns it nose up and
/// waves it.
pub fn bringup_with<T: Transport, O: Operator<T>>(
    client: &mut DeviceClient<T>,
    measure: Duration,
    operator: &mut O,
) -> Result<Bringup, BringupError> {
    let identity = client.identify().map_err(BringupError::Identify)?;
    let mut checks = vec![identity_check(&identity)];
    let health = if identity.protocol_version >= 4 {
        Some(client.health().map_err(BringupError::Identify)?)
    } else {
        None
    };
    checks.push(crate::bringup_health::part_check(health.as_ref()));
    let window = (identity.sample_rate_hz / 10).max(1);
    client
        .start_stream(StreamKind::RawWindows, window)
        .map_err(BringupError::Stream)?;
    let windows = collect(client, measure);
    client.stop_stream().map_err(BringupError::Stream)?;
    let windows = match windows {
        Ok(w) if w.len() >= 2 => w,
        other => {
            let why = match other {
                Err(e) => shared::chain::Chain(&e).to_string(),
                Ok(w) => format!("{} window(s) in {:.1} s", w.len(), measure.as_secs_f64()),
            };
            checks.push(Check::new(
                names::SAMPLES,
                false,
                why,
                "no samples: the IMU did not answer WHO_AM_I at boot (on the F405 the LED blinks \
                 at 4 Hz), or sampling is not running; check the board and power-cycle it",
            ));
            return Ok(Bringup { identity, checks });
        }
    };
    checks.push(Check::new(
        names::SAMPLES,
        true,
        format!("{} windows of {window} samples", windows.len()),
        "",
    ));
    checks.push(rate_check(&identity, &windows, window));
    checks.push(lost_check(&windows));
    checks.push(temperature_check(&windows));
    checks.push(axes_check(&windows));
    let lsb = lsb_per_g(health.as_ref());
    let rest_g = measure_g(client, &identity, lsb, Some(&windows))?;
    checks.push(gravity_check(&identity, rest_g, lsb));
    checks.push(motion::pose_check(names::FLAT, rest_g, 2));
    let unit = match identity.output_unit {
        OutputUnit::Lsb => "counts".to_string(),
        OutputUnit::Volts => "V".to_string(),
        other => format!("{other:?}"),
    };
    checks.push(motion::noise_check(
        &windows,
        health.as_ref(),
        identity.sample_rate_hz,
        &unit,
    ));
    checks.push(gyro_rest_check(&windows));
    let stream = BringupError::Stream;
    if operator.pose(Pose::NoseUp, client).map_err(stream)? {
        let g = measure_g(client, &identity, lsb, None)?;
        checks.push(motion::pose_check(names::NOSE_UP, g, 0));
    } else {
        checks.push(Check::skipped(names::NOSE_UP, NO_OPERATOR));
    }
    if operator.pose(Pose::Waved, client).map_err(stream)? {
        checks.push(motion::repeats_check(client, measure).map_err(stream)?);
        operator.rest(client).map_err(stream)?;
    } else {
        checks.push(Check::skipped(names::REPEATS, NO_OPERATOR));
    }
    if identity.protocol_version >= 4 {
        let after = client.health().map_err(BringupError::Identify)?;
        checks.push(crate::bringup_health::counters_check(
            health.as_ref(),
            &after,
        ));
    }
    Ok(Bringup { identity, checks })
}

/// Raw windows with their arrival times, for `measure` after the first.
fn collect<T: Transport>(
    client: &mut DeviceClient<T>,
    measure: Duration,
) -> Result<Vec<(Instant, RawWindow)>, LinkError> {
    let first = client.next_raw_window()?;
    let start = Instant::now();
    let mut windows = vec![(start, first)];
    while start.elapsed() < measure {
        let w = client.next_raw_window()?;
        windows.push((Instant::now(), w));
    }
    Ok(windows)
}

fn identity_check(id: &Identity) -> Check {
    let [a, b, c] = id.firmware_version;
    let detail = format!(
        "{:?} board, firmware {a}.{b}.{c}, protocol {}, unit {}, {} Hz stated, outputs in {:?}, calibration {:?}",
        id.board, id.protocol_version, id.unit_id, id.sample_rate_hz, id.output_unit, id.calibration
    );
    let ok = (MIN_PROTOCOL_VERSION..=PROTOCOL_VERSION).contains(&id.protocol_version)
        && id.sample_rate_hz > 0;
    Check::new(
        names::IDENTITY,
        ok,
        detail,
        "the firmware does not state a sample rate; flash a current build",
    )
}

/// Samples counted by the windows' indices between the first window's arrival and the last's,
/// over the host's time between them.
fn rate_check(id: &Identity, windows: &[(Instant, RawWindow)], window: u32) -> Check {
    let (t0, w0) = &windows[0];
    let (t1, w1) = &windows[windows.len() - 1];
    let samples =
        (w1.first_sample + u64::from(window)).saturating_sub(w0.first_sample + u64::from(window));
    let elapsed = t1.duration_since(*t0).as_secs_f64().max(1e-9);
    let measured = samples as f64 / elapsed;
    let stated = f64::from(id.sample_rate_hz);
    let off = measured / stated - 1.0;
    Check::new(
        names::RATE,
        off.abs() <= RATE_TOLERANCE,
        format!(
            "{measured:.1} Hz measured over {elapsed:.2} s, {stated:.0} Hz stated ({:+.1} %; limit ±{:.0} %)",
            100.0 * off,
            100.0 * RATE_TOLERANCE
        ),
        "the part samples at another rate than the firmware states: the IMU's output data rate \
         setting, or the board's crystal (HSE) is not the one the clock tree assumes",
    )
}

fn lost_check(windows: &[(Instant, RawWindow)]) -> Check {
    let (mut lost, mut saturated, mut non_finite, mut rejected, mut total) = (0, 0, 0, 0u64, 0u64);
    for (_, w) in windows {
        lost += usize::from(w.flags.has(SampleFlags::SAMPLES_LOST));
        saturated += usize::from(w.flags.has(SampleFlags::SATURATED));
        non_finite += usize::from(w.flags.has(SampleFlags::NON_FINITE));
        rejected += u64::from(w.rejected);
        total += u64::from(w.count) + u64::from(w.rejected);
    }
    let dropped = windows[windows.len() - 1].1.dropped_frames - windows[0].1.dropped_frames;
    let detail = format!(
        "{rejected} of {total} samples rejected; windows flagged: {lost} samples lost, {saturated} saturated, {non_finite} invalid; {dropped} frames dropped"
    );
    let cause = if lost > 0 {
        "the IMU's FIFO overflowed or was flushed: something held sampling up (a flash erase, a \
         stalled burst chain) — see the device's log"
    } else if saturated > 0 {
        "an axis at its full-scale code: the board moved during the check, or the range is too small"
    } else if non_finite > 0 {
        "invalid samples: the IMU marked data invalid (a sensor restarting) or the link corrupts values"
    } else {
        "frames dropped: the link is slower than the windows (a busy USB hub, a slow UART)"
    };
    Check::new(names::LOST, rejected == 0 && dropped == 0, detail, cause)
}

fn temperature_check(windows: &[(Instant, RawWindow)]) -> Check {
    let t = windows[windows.len() - 1].1.mean_temp_c;
    let (lo, hi) = TEMPERATURE_RANGE_C;
    Check::new(
        names::TEMPERATURE,
        t.is_finite() && (lo..=hi).contains(&t),
        format!("{t:.2} °C (expected {lo:.0} to {hi:.0} °C)"),
        "no temperature reading, or one no bench sees: the temperature register is not read or \
         not scaled (ICM-42688-P: 132.48 LSB/°C around 25 °C)",
    )
}

/// An axis whose variance is exactly zero in every window never changed: real sensors are never
/// that quiet.
fn axes_check(windows: &[(Instant, RawWindow)]) -> Check {
    let axis = ["x", "y", "z"];
    let mut stuck = Vec::new();
    for i in 0..3 {
        if windows.iter().all(|(_, w)| w.var_raw[i] == 0.0) {
            stuck.push(format!("accelerometer {}", axis[i]));
        }
        if windows.iter().all(|(_, w)| w.var_rate_rad2_s2[i] == 0.0) {
            stuck.push(format!("gyro {}", axis[i]));
        }
    }
    let detail = if stuck.is_empty() {
        "every accelerometer and gyro axis shows noise".to_string()
    } else {
        format!("stuck (variance exactly 0): {}", stuck.join(", "))
    };
    Check::new(
        names::AXES,
        stuck.is_empty(),
        detail,
        "a stuck axis: its output never changes — a dead sensing element, a data bit stuck, or the \
         driver reading a register that does not update",
    )
}

fn mean3(windows: &[(Instant, RawWindow)], f: impl Fn(&RawWindow) -> [f32; 3]) -> [f64; 3] {
    let n = windows.len() as f64;
    let mut m = [0.0; 3];
    for (_, w) in windows {
        for (mi, v) in m.iter_mut().zip(f(w)) {
            *mi += f64::from(v) / n;
        }
    }
    m
}

fn norm(v: [f64; 3]) -> f64 {
    (v[0] * v[0] + v[1] * v[1] + v[2] * v[2]).sqrt()
}

/// Counts per g: the health report's (0 when it states none), or a version 3 device's F405 ±4 g.
fn lsb_per_g(health: Option<&Health>) -> f64 {
    match health {
        Some(h) => f64::from(h.accel_lsb_per_g),
        None => F405_LSB_PER_G,
    }
}

/// Gravity along the board's axes, g: from a compensated window of one second when a calibration
/// is applied; else from the raw means in counts (`windows`, or half a second measured now) at
/// the device's counts per g; `None` for an uncalibrated analog unit.
fn measure_g<T: Transport>(
    client: &mut DeviceClient<T>,
    id: &Identity,
    lsb_per_g: f64,
    windows: Option<&[(Instant, RawWindow)]>,
) -> Result<Option<[f64; 3]>, BringupError> {
    if matches!(id.calibration, CalibrationState::Valid { .. }) {
        let window = id.sample_rate_hz.max(1);
        client
            .start_stream(StreamKind::CompensatedWindows, window)
            .map_err(BringupError::Stream)?;
        let w = client.next_compensated_window();
        client.stop_stream().map_err(BringupError::Stream)?;
        let w = w.map_err(BringupError::Stream)?;
        return Ok(Some(w.mean_m_s2.map(|v| f64::from(v) / G)));
    }
    if id.output_unit != OutputUnit::Lsb || lsb_per_g <= 0.0 {
        return Ok(None);
    }
    let mean = match windows {
        Some(w) => mean3(w, |w| w.mean_raw),
        None => {
            client
                .start_stream(StreamKind::RawWindows, (id.sample_rate_hz / 10).max(1))
                .map_err(BringupError::Stream)?;
            let w = collect(client, Duration::from_millis(500));
            client.stop_stream().map_err(BringupError::Stream)?;
            mean3(&w.map_err(BringupError::Stream)?, |w| w.mean_raw)
        }
    };
    Ok(Some(crate::bringup_motion::in_g(mean, lsb_per_g)))
}

/// Gravity's length at rest, in g (see [`measure_g`]).
fn gravity_check(id: &Identity, g: Option<[f64; 3]>, lsb_per_g: f64) -> Check {
    let Some(g) = g else {
        let why = if id.output_unit == OutputUnit::Lsb {
            "outputs in counts but the device states no counts per g (calibrate first)"
        } else {
            "uncalibrated analog unit: no scale to compare the outputs with (calibrate first)"
        };
        return Check::skipped(names::GRAVITY, why);
    };
    let calibrated = matches!(id.calibration, CalibrationState::Valid { .. });
    let length = norm(g);
    let off = length - 1.0;
    let source = if calibrated {
        "compensated".to_string()
    } else {
        format!("counts at {lsb_per_g:.0} per g")
    };
    Check::new(
        names::GRAVITY,
        off.abs() <= GRAVITY_TOLERANCE,
        format!(
            "|a| = {length:.4} g ({source}), expected 1 g ({:+.1} %; limit ±{:.0} %)",
            100.0 * off,
            100.0 * GRAVITY_TOLERANCE
        ),
        format!(
            "gravity's length is off: the board moved, the accelerometer's range is not the one \
             the device states ({lsb_per_g:.0} counts per g), or a calibration for another unit \
             is applied"
        ),
    )
}

fn gyro_rest_check(windows: &[(Instant, RawWindow)]) -> Check {
    let rate = norm(mean3(windows, |w| w.mean_rate_rad_s));
    Check::new(
        names::GYRO_REST,
        rate <= REST_RATE_LIMIT_RAD_S,
        format!(
            "{:.3} °/s at rest (limit {:.1} °/s)",
            rate.to_degrees(),
            REST_RATE_LIMIT_RAD_S.to_degrees()
        ),
        "the gyro reads a rate at rest: the board moved during the check, or the gyro's \
         zero-rate offset is far beyond the part's (ICM-42688-P: ±0.5 °/s)",
    )
}
