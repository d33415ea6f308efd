//! Verification after a calibration is stored: the device's compensated output at positions the
//! plan did not record (held-out attitudes and spins on a virtual table; the plan's own positions,
//! set up by the operator, on a real one) against the specific force they should give
//! (`docs/model.md` §4.5).

use super::live_check::{instruction, table_for};
use super::operator::Operator;
use super::procedure::ProcedureOptions;
use crate::{DeviceClient, LinkError, Transport};
use estimator::estimate::attitude::best_rotation;
use estimator::estimate::{BodyFrame, ReferenceChoice};
use nalgebra::{Matrix3, Vector3};
use recording::session::{Plan, SegmentPlan};
use shared::wire::{SampleFlags, StreamKind};

/// One verification position.
#[derive(Clone, Debug, PartialEq)]
pub struct VerificationPoint {
    /// What it is.
    pub label: String,
    /// Up, body axes.
    pub up_b: [f64; 3],
    /// Table rate, °/s.
    pub rate_deg_s: f64,
    /// Mean compensated specific force, g.
    pub measured_g: [f64; 3],
    /// What it should be, g.
    pub expected_g: [f64; 3],
    /// Largest axis error, mg.
    pub error_mg: f64,
    /// The device's mean temperature reading over the position, °C (`None`: it reports none).
    pub temp_c: Option<f64>,
    /// Within the tolerance.
    pub pass: bool,
}

/// Verification positions: held-out attitudes and a fast spin on a virtual table; on a real table the
/// plan's first static positions and its fastest constant-rate segment, set up by the operator. A plan
/// without rotations calibrates no lever arm, so its verification does not spin.
fn verification_positions(plan: &Plan, drive: bool) -> Vec<(String, [f64; 3], f64)> {
    if drive {
        let spins = plan.segments.iter().any(|s| !s.is_static());
        let n = |v: [f64; 3]| {
            let k = shared::linalg::norm(&v);
            v.map(|x| x / k)
        };
        return vec![
            ("held-out (1,1,1) at rest".into(), n([1.0, 1.0, 1.0]), 0.0),
            (
                "held-out (-1,0.5,-0.3) at rest".into(),
                n([-1.0, 0.5, -0.3]),
                0.0,
            ),
            (
                "held-out (0.2,-0.9,0.4) at rest".into(),
                n([0.2, -0.9, 0.4]),
                0.0,
            ),
            ("x up at 200 °/s".into(), [1.0, 0.0, 0.0], 200.0),
            (
                "(1,-1,1) up at -150 °/s".into(),
                n([1.0, -1.0, 1.0]),
                -150.0,
            ),
        ]
        .into_iter()
        .filter(|(_, _, rate)| spins || *rate == 0.0)
        .collect();
    }
    let mut v: Vec<_> = plan
        .segments
        .iter()
        .filter(|s| s.is_static())
        .take(3)
        .map(|s| (format!("{} at rest", s.name), s.up_b, 0.0))
        .collect();
    if let Some(s) = plan
        .segments
        .iter()
        .filter(|s| !s.is_static() && s.rate_end_deg_s.is_none())
        .max_by(|a, b| a.rate_deg_s.abs().total_cmp(&b.rate_deg_s.abs()))
    {
        v.push((format!("{} spinning", s.name), s.up_b, s.rate_deg_s));
    }
    v
}

/// Largest difference between the temperature asked for a second verification and the one the
/// device reports, °C: a board not yet there is not verified "at" that temperature.
pub(crate) const VERIFY_TEMP_TOLERANCE_C: f64 = 2.0;

/// Verifies the stored calibration at the verification positions. A calibration whose body frame is
/// a convention (`frame`: no attitude known, docs/model.md §7) is compared after the best common
/// rotation of the positions at rest: its frame is not the table's, and what it fixes (magnitudes
/// and the angles between positions) is what is judged.
pub(crate) fn verify<T: Transport>(
    client: &mut DeviceClient<T>,
    op: &mut dyn Operator,
    plan: &Plan,
    drive: bool,
    frame: BodyFrame,
    opts: &ProcedureOptions,
    sample_rate_hz: f64,
) -> Result<Vec<VerificationPoint>, LinkError> {
    // The expected specific force at the reference point O is g·up − W c, with c the reference point
    // relative to the table axis (`docs/model.md` §4.5); spinning checks need c, known for these references.
    let c = match opts.calibrate.estimate.reference {
        ReferenceChoice::TableAxis => Some([0.0; 3]),
        ReferenceChoice::BodyPoint(p) => Some(p),
        ReferenceChoice::Centroid => None,
    };
    if plan.segments.iter().all(|s| s.is_static()) {
        op.say(
            "verification at rest only: the plan has no rotations, so it calibrated no lever arm",
        );
    }
    let mut measured = Vec::new();
    let positions = verification_positions(plan, drive);
    for (label, up, rate) in &positions {
        let Some(c) = (if *rate == 0.0 { Some([0.0; 3]) } else { c }) else {
            op.say(&format!(
                "verify {label}: skipped (the centroid reference has no fixed table-axis offset)"
            ));
            continue;
        };
        let p = Position {
            label: label.clone(),
            up: *up,
            rate_deg_s: *rate,
            centre_m: c,
        };
        measured.push(verify_position(
            client,
            op,
            plan,
            drive,
            opts,
            sample_rate_hz,
            &p,
        )?);
    }
    let at_reference = measured.len();
    if let Some(t) = opts.verify_temp_c {
        // A second temperature: the temperature model (or its absence) is what is judged, at rest.
        if drive {
            op.say(&format!(
                "verification at {t:.1} °C: the virtual chamber is set to it"
            ));
            client.set_temperature(t as f32)?;
        } else {
            op.wait_ready(&format!(
                "verification at {t:.1} °C: bring the board to {t:.1} °C (a hot plate or a chamber) \
                 and hold it there until its temperature is steady"
            ))
            .map_err(|e| LinkError::Unexpected {
                waiting_for: "the operator",
                got: shared::chain::Chain(&e).to_string(),
            })?;
        }
        for (label, up, _) in positions.iter().filter(|p| p.2 == 0.0) {
            let p = Position {
                label: format!("{label}, {t:.0} °C"),
                up: *up,
                rate_deg_s: 0.0,
                centre_m: [0.0; 3],
            };
            let mut m = verify_position(client, op, plan, drive, opts, sample_rate_hz, &p)?;
            let reached = m
                .temp_c
                .is_some_and(|r| (r - t).abs() <= VERIFY_TEMP_TOLERANCE_C);
            if !reached {
                op.say(&format!(
                    "verify {}: the device reads {}, not within {VERIFY_TEMP_TOLERANCE_C} °C of \
                     {t:.1} °C: not verified at that temperature",
                    m.label,
                    m.temp_c
                        .map_or("no temperature".to_string(), |r| format!("{r:.1} °C"))
                ));
                m.temperature_missed = true;
            }
            measured.push(m);
        }
    }
    let rotation = frame_rotation(op, frame, &measured[..at_reference]);
    Ok(measured
        .into_iter()
        .map(|m| m.judge(rotation.as_ref(), opts.verify_tolerance_mg))
        .collect())
}

/// The rotation the expected forces are turned by before they are judged: none in the fixture's
/// frame; in a conventional frame, the best common rotation of the positions at rest (`reference`:
/// those at the reference temperature), which the operator is told.
fn frame_rotation(
    op: &mut dyn Operator,
    frame: BodyFrame,
    reference: &[Measured],
) -> Option<Matrix3<f64>> {
    match frame {
        BodyFrame::Fixture { .. } | BodyFrame::Faces { .. } => None,
        BodyFrame::Convention => {
            op.say(
                "the calibration's body frame is a convention (no attitude was known), not the \
                 table's: each position is compared after the best common rotation of those at \
                 rest, so their magnitudes and the angles between them are verified",
            );
            let rest: Vec<&Measured> = reference.iter().filter(|m| m.rate_deg_s == 0.0).collect();
            let expected: Vec<[f64; 3]> = rest.iter().map(|m| m.expected_g).collect();
            let got: Vec<[f64; 3]> = rest.iter().map(|m| m.measured_g).collect();
            best_rotation(&expected, &got)
        }
    }
}

/// One position's measurement, before it is judged.
struct Measured {
    label: String,
    up_b: [f64; 3],
    rate_deg_s: f64,
    measured_g: [f64; 3],
    expected_g: [f64; 3],
    temp_c: Option<f64>,
    uncalibrated: bool,
    temperature_missed: bool,
}

impl Measured {
    /// The point's error against its expected specific force (turned by `rotation` when the
    /// calibration's frame is a convention) and its verdict.
    fn judge(self, rotation: Option<&Matrix3<f64>>, tolerance_mg: f64) -> VerificationPoint {
        let expected_g = rotation.map_or(self.expected_g, |r| {
            let v = r * Vector3::from(self.expected_g);
            [v[0], v[1], v[2]]
        });
        let error_mg = (0..3)
            .map(|j| (self.measured_g[j] - expected_g[j]).abs() * 1e3)
            .fold(0.0, f64::max);
        VerificationPoint {
            label: match rotation {
                Some(_) => format!("{} (frame-free)", self.label),
                None => self.label,
            },
            up_b: self.up_b,
            rate_deg_s: self.rate_deg_s,
            measured_g: self.measured_g,
            expected_g,
            error_mg,
            temp_c: self.temp_c,
            pass: !self.uncalibrated && !self.temperature_missed && error_mg <= tolerance_mg,
        }
    }
}

/// One verification position: where the unit is, how it turns, and the reference point's offset
/// from the table axis.
struct Position {
    label: String,
    up: [f64; 3],
    rate_deg_s: f64,
    centre_m: [f64; 3],
}

/// Sets up one position (the virtual table, or the operator), streams the compensated output for
/// `opts.verify_seconds` after the settling time, and compares its mean with the expected specific
/// force.
fn verify_position<T: Transport>(
    client: &mut DeviceClient<T>,
    op: &mut dyn Operator,
    plan: &Plan,
    drive: bool,
    opts: &ProcedureOptions,
    sample_rate_hz: f64,
    p: &Position,
) -> Result<Measured, LinkError> {
    let g = plan.gravity_m_s2;
    let (up, rate) = (p.up, p.rate_deg_s);
    let seg = SegmentPlan {
        name: p.label.clone(),
        up_b: up,
        rate_deg_s: rate,
        rate_end_deg_s: None,
        duration_s: Some(opts.verify_seconds),
        table_centre_m: None,
        mount: None,
        ..SegmentPlan::default()
    };
    if drive {
        client.set_table(table_for(&seg))?;
    } else {
        op.wait_ready(&format!("verification: {}", instruction(&seg)))
            .map_err(|e| LinkError::Unexpected {
                waiting_for: "the operator",
                got: shared::chain::Chain(&e).to_string(),
            })?;
    }
    let window = ((sample_rate_hz / 10.0).round() as u32).max(1);
    client.start_stream(StreamKind::CompensatedWindows, window)?;
    let per_s = sample_rate_hz / f64::from(window);
    for _ in 0..(opts.settle_s * per_s).round() as u64 {
        client.next_compensated_window()?;
    }
    let n = (opts.verify_seconds * per_s).round().max(1.0) as u64;
    let (mut sum, mut count, mut uncalibrated) = ([0.0f64; 3], 0.0f64, false);
    let (mut temp_sum, mut temp_count) = (0.0f64, 0.0f64);
    for _ in 0..n {
        let w = client.next_compensated_window()?;
        uncalibrated |= w.flags.has(SampleFlags::UNCALIBRATED);
        let k = f64::from(w.count);
        for j in 0..3 {
            sum[j] += f64::from(w.mean_m_s2[j]) * k;
        }
        count += k;
        if w.mean_temp_c.is_finite() {
            temp_sum += f64::from(w.mean_temp_c) * k;
            temp_count += k;
        }
    }
    client.stop_stream()?;
    let omega = up.map(|u| u * rate.to_radians());
    let wc = shared::linalg::mat_vec(
        &shared::linalg::lever_matrix(&omega, &[0.0; 3]),
        &p.centre_m,
    );
    let expected_g: [f64; 3] = std::array::from_fn(|j| (g * up[j] - wc[j]) / g);
    let measured_g: [f64; 3] = std::array::from_fn(|j| sum[j] / count.max(1.0) / g);
    Ok(Measured {
        label: p.label.clone(),
        up_b: up,
        rate_deg_s: rate,
        measured_g,
        expected_g,
        temp_c: (temp_count > 0.0).then(|| temp_sum / temp_count),
        uncalibrated,
        temperature_missed: false,
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    fn at_rest(label: &str, expected_g: [f64; 3], measured_g: [f64; 3]) -> Measured {
        Measured {
            label: label.into(),
            up_b: expected_g,
            rate_deg_s: 0.0,
            measured_g,
            expected_g,
            temp_c: None,
            uncalibrated: false,
            temperature_missed: false,
        }
    }

    /// Turned by any rotation the positions pass after the best common rotation; a magnitude
    /// 5 mg off, or an angle between two positions 0.5° off, fails in any frame.
    #[test]
    fn a_conventional_frame_is_judged_by_what_it_fixes() {
        let k = 1.0 / 3f64.sqrt();
        let ups = [[k, k, k], [0.0, 1.0, 0.0], [0.6, 0.0, -0.8]];
        // A 20° rotation about (1, 2, 2)/3, the frame the calibration happened to choose.
        let r = nalgebra::Rotation3::from_axis_angle(
            &nalgebra::Unit::new_normalize(Vector3::new(1.0, 2.0, 2.0)),
            20f64.to_radians(),
        );
        let turn = |v: [f64; 3]| {
            let x = r * Vector3::from(v);
            [x[0], x[1], x[2]]
        };
        let judge = |measured: [[f64; 3]; 3]| {
            let m: Vec<Measured> = (0..3).map(|i| at_rest("p", ups[i], measured[i])).collect();
            let e: Vec<[f64; 3]> = m.iter().map(|m| m.expected_g).collect();
            let g: Vec<[f64; 3]> = m.iter().map(|m| m.measured_g).collect();
            let rot = best_rotation(&e, &g);
            m.into_iter()
                .map(|m| m.judge(rot.as_ref(), 1.0))
                .collect::<Vec<_>>()
        };
        let turned = ups.map(turn);
        assert!(judge(turned).iter().all(|p| p.pass && p.error_mg < 1e-9));
        // Without the rotation the same right calibration fails: the frames differ.
        let plain = at_rest("p", ups[0], turned[0]).judge(None, 1.0);
        assert!(!plain.pass, "{plain:?}");
        let mut long = turned;
        long[1] = long[1].map(|x| x * 1.005);
        assert!(judge(long).iter().any(|p| !p.pass));
        let mut bent = turned;
        let tilt = nalgebra::Rotation3::from_axis_angle(&Vector3::x_axis(), 0.5f64.to_radians());
        let b = tilt * Vector3::from(bent[2]);
        bent[2] = [b[0], b[1], b[2]];
        assert!(judge(bent).iter().any(|p| !p.pass));
    }
}
