//! `host bringup`'s checks that need the board in a pose or in motion: "flat, top up" and "nose
//! up" (the axes' signs and order: a wrong IMU rotation in the board's description passes a check
//! of |g| alone), the noise at rest against the datasheet's density and across the axes, and
//! repeated samples while the board is waved (ArduPilot's way of showing that a part holds its
//! output, as the ICM-42688-P's adaptive full-scale switch does when left on).
//!
//! Who moves the board is an [`Operator`]: a person at a terminal, or the simulated device's
//! virtual table ([`TableOperator`]).

use super::bringup::{names, Check};
use super::client::{DeviceClient, LinkError, Transport};
use shared::wire::{Health, RawWindow, StreamKind, VirtualTable};
use std::time::{Duration, Instant};

/// A pose or motion the checks ask for.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Pose {
    /// At rest, the board's nose (its +x, the arrow) pointing straight up.
    NoseUp,
    /// Waved by hand: turning about all axes, a few hundred degrees per second.
    Waved,
}

impl Pose {
    /// What a person is asked to do.
    pub fn instruction(self) -> &'static str {
        match self {
            Pose::NoseUp => {
                "hold the board still with its nose (the arrow, +x) pointing straight up"
            }
            Pose::Waved => {
                "wave the board about all its axes (a few turns per second) until told to stop"
            }
        }
    }
}

/// Whoever puts the board in a pose.
pub trait Operator<T: Transport> {
    /// Brings the board into `pose` and returns once it is there; `Ok(false)` when nobody can.
    fn pose(&mut self, pose: Pose, client: &mut DeviceClient<T>) -> Result<bool, LinkError>;
    /// The board may go back to rest (after a wave).
    fn rest(&mut self, _client: &mut DeviceClient<T>) -> Result<(), LinkError> {
        Ok(())
    }
}

/// Nobody: the pose checks are skipped.
pub(crate) struct NoOperator;

impl<T: Transport> Operator<T> for NoOperator {
    fn pose(&mut self, _: Pose, _: &mut DeviceClient<T>) -> Result<bool, LinkError> {
        Ok(false)
    }
}

/// The simulated or QEMU device's virtual table (`SetVirtualTable`): nose up is the table with
/// the body's +x vertical; a wave is the table turning at 6 rad/s about a tilted axis.
pub struct TableOperator;

impl<T: Transport> Operator<T> for TableOperator {
    fn pose(&mut self, pose: Pose, client: &mut DeviceClient<T>) -> Result<bool, LinkError> {
        let table = match pose {
            Pose::NoseUp => VirtualTable {
                up_b: [1.0, 0.0, 0.0],
                rate_rad_s: 0.0,
                accel_rad_s2: 0.0,
            },
            Pose::Waved => VirtualTable {
                up_b: [0.3, -0.4, 0.866],
                rate_rad_s: 6.0,
                accel_rad_s2: 0.0,
            },
        };
        client.set_table(table)?;
        Ok(true)
    }

    fn rest(&mut self, client: &mut DeviceClient<T>) -> Result<(), LinkError> {
        client.set_table(VirtualTable {
            up_b: [0.0, 0.0, 1.0],
            rate_rad_s: 0.0,
            accel_rad_s2: 0.0,
        })
    }
}

/// Largest off-axis component of gravity in a pose, g: ≈ 11.5° of tilt, or a bias far beyond an
/// uncalibrated part's tens of mg.
pub(crate) const POSE_OFF_AXIS_G: f64 = 0.2;
/// An axis noisier than this many times the quietest one is a noisy axis.
pub(crate) const NOISE_AXIS_RATIO: f64 = 3.0;
/// The measured noise may exceed the datasheet's density over the whole Nyquist band by this
/// factor (the parts' own filters keep it below that band's).
pub(crate) const NOISE_DATASHEET_FACTOR: f64 = 2.0;
/// Repeated gyro samples allowed while waved (a sample's three rates equal to the previous
/// one's; with noise and motion a real repeat is practically impossible).
pub(crate) const REPEATS_ALLOWED_FRACTION: f64 = 0.005;

const AXES: [&str; 3] = ["x", "y", "z"];

/// Gravity in g along the board's axes at rest, from `mean` in counts at `lsb_per_g`.
pub(crate) fn in_g(mean: [f64; 3], lsb_per_g: f64) -> [f64; 3] {
    mean.map(|v| v / lsb_per_g)
}

/// "Flat, top up" (`axis` 2, sign +) or "nose up" (`axis` 0): gravity along that axis alone.
pub(crate) fn pose_check(name: &'static str, g: Option<[f64; 3]>, axis: usize) -> Check {
    let Some(g) = g else {
        return Check::skipped(
            name,
            "no scale to read gravity in g: an uncalibrated analog unit (calibrate first)",
        );
    };
    let detail = format!(
        "gravity along x {:+.3} g, y {:+.3} g, z {:+.3} g (expected {} +1 g, the others within ±{POSE_OFF_AXIS_G} g)",
        g[0], g[1], g[2], AXES[axis]
    );
    let ok = g[axis] > 1.0 - POSE_OFF_AXIS_G
        && (0..3).all(|i| i == axis || g[i].abs() < POSE_OFF_AXIS_G);
    let (big, _) = g
        .iter()
        .enumerate()
        .map(|(i, v)| (i, v.abs()))
        .fold((axis, 0.0), |b, (i, v)| if v > b.1 { (i, v) } else { b });
    let cause = if big == axis && g[axis] < 0.0 {
        format!(
            "gravity reads on −{0}: the {0} axis is reversed — the IMU rotation in the board's \
             description is off by 180° (or the board was not in the pose)",
            AXES[axis]
        )
    } else if big != axis && g[big].abs() > 1.0 - POSE_OFF_AXIS_G {
        format!(
            "gravity reads on {}{} instead of +{}: the axes are swapped — the IMU rotation in the \
             board's description is off by 90° (or the board was not in the pose)",
            if g[big] < 0.0 { "−" } else { "+" },
            AXES[big],
            AXES[axis]
        )
    } else {
        "gravity is split between axes: the board was tilted or moving; repeat with it still"
            .to_string()
    };
    Check::new(name, ok, detail, cause)
}

/// The noise at rest, per accelerometer axis: against the others, and against the part's
/// datasheet density over the Nyquist band when the part and its scale are known.
pub(crate) fn noise_check(
    windows: &[(Instant, RawWindow)],
    health: Option<&Health>,
    sample_rate_hz: u32,
    unit: &str,
) -> Check {
    let n = windows.len() as f64;
    let sigma: [f64; 3] = core::array::from_fn(|i| {
        (windows
            .iter()
            .map(|(_, w)| f64::from(w.var_raw[i]))
            .sum::<f64>()
            / n)
            .sqrt()
    });
    // A stuck axis (σ exactly 0) is the axes check's; the others are compared among themselves.
    let quietest = sigma
        .iter()
        .cloned()
        .filter(|&s| s > 0.0)
        .fold(f64::INFINITY, f64::min);
    let noisy: Vec<usize> = (0..3)
        .filter(|&i| quietest.is_finite() && sigma[i] > NOISE_AXIS_RATIO * quietest)
        .collect();
    let datasheet = health.and_then(|h| {
        let density = h.imu.part.accel_noise_ug_per_sqrt_hz()?;
        (h.accel_lsb_per_g > 0).then(|| {
            let bound_g = NOISE_DATASHEET_FACTOR
                * f64::from(density)
                * 1e-6
                * (f64::from(sample_rate_hz) / 2.0).sqrt();
            (bound_g * f64::from(h.accel_lsb_per_g), density)
        })
    });
    let over: Vec<usize> = match datasheet {
        Some((bound, _)) => (0..3).filter(|&i| sigma[i] > bound).collect(),
        None => Vec::new(),
    };
    let mut detail = format!(
        "σ at rest: x {:.4}, y {:.4}, z {:.4} {unit}",
        sigma[0], sigma[1], sigma[2]
    );
    match datasheet {
        Some((bound, density)) => detail.push_str(&format!(
            "; datasheet {density} µg/√Hz over {} Hz: at most {bound:.4} {unit}",
            sample_rate_hz / 2
        )),
        None => {
            detail.push_str("; no datasheet density for this part: axes compared with each other")
        }
    }
    let worst: Vec<usize> = if noisy.is_empty() {
        over.clone()
    } else {
        noisy.clone()
    };
    let names: Vec<String> = worst
        .iter()
        .map(|&i| format!("accelerometer {}", AXES[i]))
        .collect();
    let cause = format!(
        "{} noisier than {}: a loose or vibrating mount, a damaged sensing element, or \
         interference on the part's supply",
        names.join(", "),
        if noisy.is_empty() {
            "the datasheet allows".to_string()
        } else {
            format!("{NOISE_AXIS_RATIO}× the quietest axis")
        }
    );
    Check::new(
        names::NOISE,
        noisy.is_empty() && over.is_empty(),
        detail,
        cause,
    )
}

/// Every sample for `measure` while the board is waved: consecutive samples (by index) whose
/// three gyro rates are all equal to the previous sample's are repeats.
pub(crate) fn repeats_check<T: Transport>(
    client: &mut DeviceClient<T>,
    measure: Duration,
) -> Result<Check, LinkError> {
    client.start_stream(StreamKind::RawDecimated, 1)?;
    let start = Instant::now();
    let (mut pairs, mut repeats, mut moving) = (0u64, 0u64, 0u64);
    let mut prev: Option<(u64, [f32; 3])> = None;
    let mut result = Ok(());
    while start.elapsed() < measure {
        match client.next_raw_sample() {
            Ok(s) => {
                let speed = s.rate_rad_s.iter().map(|w| w * w).sum::<f32>();
                moving += u64::from(speed > 1.0);
                if let Some((i, w)) = prev {
                    if s.index == i + 1 {
                        pairs += 1;
                        repeats += u64::from(w == s.rate_rad_s);
                    }
                }
                prev = Some((s.index, s.rate_rad_s));
            }
            Err(e) => {
                result = Err(e);
                break;
            }
        }
    }
    client.stop_stream()?;
    result?;
    let fraction = repeats as f64 / (pairs.max(1)) as f64;
    let detail = format!(
        "{repeats} repeated gyro samples in {pairs} consecutive pairs ({:.2} %; limit {:.1} %), \
         {moving} samples above 1 rad/s",
        100.0 * fraction,
        100.0 * REPEATS_ALLOWED_FRACTION
    );
    if moving * 2 < pairs {
        return Ok(Check::new(
            names::REPEATS,
            false,
            detail,
            "the board was not waved (less than half the samples turning faster than 1 rad/s): \
             repeat, waving it harder",
        ));
    }
    Ok(Check::new(
        names::REPEATS,
        fraction <= REPEATS_ALLOWED_FRACTION,
        detail,
        "the part holds its output while turning: on the ICM-42688-P the adaptive full-scale \
         switch (AFSR) is still on — flash a current build; otherwise samples are read faster \
         than the part produces them",
    ))
}
