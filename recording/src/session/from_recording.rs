//! A session (plan + samples) from one continuous recording cut by [`super::segment`]: every still
//! interval becomes a static segment whose attitude is free, or the nearest body axis with a prior
//! when it is within `AXIS_SNAP_DEG` of one (a unit set down on its faces, docs/model.md §7); in a
//! six-face session ([`plan_for_faces`]) every still interval is its nearest face with a prior.

use super::import::Recording;
use super::segment::{angle_deg, Interval, Segmentation};
use super::{
    Plan, RecordingError, RecordingVersion, SegmentAccumulator, SegmentPlan, SegmentStats,
    SessionWriter,
};
use crate::session::plan::Attitude;
use std::path::Path;

/// A still position this close to a body axis is taken as set down on that face, degrees.
pub(crate) const AXIS_SNAP_DEG: f64 = 2.0;
/// Prior 1σ of such a face position about each axis, degrees: a cube's face on a bench that is level
/// to a fraction of a degree, with the direction measured before calibration (scale and axis errors
/// of about 1 % and 0.5° move it by as much).
pub(crate) const FACE_PRIOR_DEG: f64 = 1.0;

/// The nearest body axis (±x, ±y, ±z) if within `deg`.
fn nearest_axis(d: &[f64; 3], deg: f64) -> Option<[f64; 3]> {
    (0..3)
        .flat_map(|j| {
            [1.0, -1.0].map(|s| {
                let mut a = [0.0; 3];
                a[j] = s;
                a
            })
        })
        .find(|a| angle_deg(d, a) < deg)
}

/// Default prior 1σ of a six-face session's faces, degrees (`--face-sigma-deg`): a cube set down by
/// hand on a bench that is level to a fraction of a degree; docs/model.md §7.1.
pub const SIX_FACE_PRIOR_DEG: f64 = 2.0;

/// Still interval `k`'s segment: its nearest axis within `snap_deg` with a prior of `prior_deg`, else
/// free.
fn segment_for(k: usize, iv: &Interval, snap_deg: f64, prior_deg: f64) -> SegmentPlan {
    let name = format!("still {:02}", k + 1);
    let axis = nearest_axis(&iv.direction, snap_deg);
    SegmentPlan {
        up_b: axis.unwrap_or(iv.direction.map(|c| (c * 1e6).round() / 1e6)),
        attitude: if axis.is_some() {
            Attitude::Face
        } else {
            Attitude::Free
        },
        attitude_sigma_deg: axis.map(|_| prior_deg),
        duration_s: Some((iv.duration_s * 1e3).round() / 1e3),
        mount: Some(name.clone()),
        name,
        ..SegmentPlan::default()
    }
}

/// The plan of the session: one static segment per still interval, format 2, or format 3 when the
/// recording has the unit's temperature (its `temp_c` column, docs/recording-format.md).
pub fn plan_for(rec: &Recording, seg: &Segmentation) -> Plan {
    plan_with(rec, seg, AXIS_SNAP_DEG, FACE_PRIOR_DEG)
}

/// The plan of a six-face session (`super::segment::PositionSet::SixFaces`): every still interval is
/// its face, `faces` (`super::coverage::six_face_labels`), with the prior `face_sigma_deg`, which
/// fixes the body frame and lets the nine intrinsic parameters follow (docs/model.md §7.1).
pub fn plan_for_faces(
    rec: &Recording,
    seg: &Segmentation,
    faces: &[[f64; 3]],
    face_sigma_deg: f64,
) -> Plan {
    let mut plan = plan_with(rec, seg, AXIS_SNAP_DEG, face_sigma_deg);
    for (sp, face) in plan.segments.iter_mut().zip(faces) {
        sp.up_b = *face;
        sp.attitude = Attitude::Face;
        sp.attitude_sigma_deg = Some(face_sigma_deg);
    }
    plan
}

fn plan_with(rec: &Recording, seg: &Segmentation, snap_deg: f64, prior_deg: f64) -> Plan {
    Plan {
        format_version: if rec.temp_c.is_some() {
            RecordingVersion::V3Temperature.number()
        } else {
            RecordingVersion::V2Attitudes.number()
        },
        output_unit: rec.acc_unit.unwrap_or(shared::OutputUnit::Lsb),
        sample_rate_hz: (rec.rate_hz * 1e6).round() / 1e6,
        gravity_m_s2: shared::STANDARD_GRAVITY_M_S2,
        unit_id: None,
        package: Default::default(),
        attitude_sigma_deg: None,
        table_rate_sigma_ppm: None,
        acc_offset: (rec.acc_offset != [0.0; 3]).then_some(rec.acc_offset),
        segments: seg
            .stills
            .iter()
            .enumerate()
            .map(|(k, iv)| segment_for(k, iv, snap_deg, prior_deg))
            .collect(),
    }
}

/// The still interval after each whole table turn (`after_still` of each, 0-based: the turn is
/// between still `k` and `k + 1`) is the same mount as the one before: the unit was turned flat and
/// set back against its stop, so both see the same up and share one attitude unknown (docs/model.md
/// §7.2); only segments with a known up and a prior (not free) are joined.
pub fn join_table_turn_mounts(plan: &mut Plan, after_still: impl Iterator<Item = usize>) {
    for k in after_still {
        let Some([before, after]) = plan.segments.get_mut(k..k + 2) else {
            continue;
        };
        if !before.is_free() && !after.is_free() && before.up_b == after.up_b {
            after.mount.clone_from(&before.mount);
        }
    }
}

/// Normal gravity at geodetic latitude `lat_deg` and height `height_m` above the ellipsoid, m/s²:
/// Somigliana's closed formula on the WGS 84 ellipsoid and its second-order height correction
/// (NIMA TR8350.2, *Department of Defense World Geodetic System 1984*, 3rd ed., eqs. 4-1 and 4-3).
/// Within about 0.1 mg of a site's real gravity away from mountains and large anomalies; a logger's
/// m/s² output is scaled by it (`gravity_m_s2` of the plan).
pub fn normal_gravity_m_s2(lat_deg: f64, height_m: f64) -> f64 {
    // WGS 84: equatorial normal gravity, Somigliana's constant, first eccentricity squared.
    const GAMMA_E: f64 = 9.780_325_335_9;
    const K: f64 = 0.001_931_852_652_41;
    const E2: f64 = 0.006_694_379_990_13;
    // Height correction: 2/a (1 + f + m − 2 f sin²φ) and 3/a², from a, f and m of WGS 84.
    const A_M: f64 = 6_378_137.0;
    const F: f64 = 1.0 / 298.257_223_563;
    const M: f64 = 0.003_449_786_506_84;
    let s2 = lat_deg.to_radians().sin().powi(2);
    let gamma = GAMMA_E * (1.0 + K * s2) / (1.0 - E2 * s2).sqrt();
    let h = height_m;
    gamma * (1.0 - 2.0 / A_M * (1.0 + F + M - 2.0 * F * s2) * h + 3.0 / (A_M * A_M) * h * h)
}

/// The per-segment statistics, as reading the written session would give them.
pub fn stats_for(rec: &Recording, seg: &Segmentation, plan: &Plan) -> Vec<SegmentStats> {
    seg.stills
        .iter()
        .zip(&plan.segments)
        .filter_map(|(iv, sp)| {
            let mut acc = SegmentAccumulator::new(sp.name.clone());
            for i in iv.start..iv.end {
                let (t_s, u, w_rad_s) = (rec.t_s[i], &rec.acc[i], &rec.gyro_rad_s[i]);
                match (&rec.temp_c, plan.has_temperature()) {
                    (Some(temp), true) => acc.push_with_temperature(t_s, u, w_rad_s, temp[i]),
                    _ => acc.push(t_s, u, w_rad_s),
                }
            }
            acc.finish()
        })
        .collect()
}

/// Writes `dir/plan.toml` and `dir/samples.csv` (refuses an existing session unless `overwrite`), the
/// accelerometer with the recording's offset added back: the calibration applies to the logger's own
/// outputs, its biases in the logger's counts.
pub fn write_session(
    dir: &Path,
    rec: &Recording,
    seg: &Segmentation,
    plan: &Plan,
    overwrite: bool,
) -> Result<u64, RecordingError> {
    let mut w = SessionWriter::create(dir, plan, overwrite)?;
    for (iv, sp) in seg.stills.iter().zip(&plan.segments) {
        for i in iv.start..iv.end {
            let (t_s, w_rad_s) = (rec.t_s[i], &rec.gyro_rad_s[i]);
            let u: [f64; 3] = core::array::from_fn(|j| rec.acc[i][j] + rec.acc_offset[j]);
            match (&rec.temp_c, w.has_temperature()) {
                (Some(temp), true) => {
                    w.write_row_with_temperature(&sp.name, t_s, &u, w_rad_s, temp[i])?
                }
                _ => w.write_row(&sp.name, t_s, &u, w_rad_s)?,
            }
        }
        w.end_segment()?;
    }
    w.finish()
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::session::segment::IntervalKind;

    fn interval(direction: [f64; 3]) -> Interval {
        Interval {
            kind: IntervalKind::Still,
            start: 0,
            end: 10,
            start_s: 0.0,
            duration_s: 4.0,
            mean_acc: direction,
            std_acc: [1e-3; 3],
            mean_gyro_rad_s: [0.0; 3],
            std_gyro_rad_s: [1e-3; 3],
            direction,
        }
    }

    #[test]
    fn normal_gravity_matches_the_wgs84_tables() {
        // TR8350.2's table 3.4: normal gravity at the equator and at the poles (the pole's is not an
        // input of the formula: it checks the constants), and the usual free-air gradient.
        assert!((normal_gravity_m_s2(0.0, 0.0) - 9.780_325_335_9).abs() < 1e-9);
        assert!((normal_gravity_m_s2(-90.0, 0.0) - 9.832_184_937_8).abs() < 1e-9);
        assert!((normal_gravity_m_s2(90.0, 0.0) - 9.832_184_937_8).abs() < 1e-9);
        let gradient = normal_gravity_m_s2(45.0, 1000.0) - normal_gravity_m_s2(45.0, 0.0);
        assert!((gradient + 3.086e-3).abs() < 2e-6, "{gradient}");
    }

    #[test]
    fn a_position_near_a_face_gets_the_axis_with_a_prior_others_are_free() {
        let tilt = |deg: f64| {
            let r = deg.to_radians();
            [r.sin(), -r.cos(), 0.0]
        };
        let near = segment_for(0, &interval(tilt(1.0)), AXIS_SNAP_DEG, FACE_PRIOR_DEG);
        assert_eq!(near.up_b, [0.0, -1.0, 0.0]);
        assert!(!near.is_free());
        assert_eq!(near.attitude_sigma_deg, Some(FACE_PRIOR_DEG));
        assert_eq!(near.mount.as_deref(), Some("still 01"));
        let far = segment_for(1, &interval(tilt(5.0)), AXIS_SNAP_DEG, FACE_PRIOR_DEG);
        assert!(far.is_free());
        assert!((far.up_b[0] - 5f64.to_radians().sin()).abs() < 1e-6);
        assert_eq!(far.attitude_sigma_deg, None);
    }

    #[test]
    fn a_recording_with_temperature_writes_format_3_with_its_temp_c_column() {
        let n = 10;
        let mut rec = Recording {
            t_s: (0..n).map(|i| i as f64 * 0.01).collect(),
            acc: vec![[0.0, 0.0, 9.81]; n],
            gyro_rad_s: vec![[0.0; 3]; n],
            acc_unit: Some(shared::OutputUnit::MetresPerSecondSquared),
            rate_hz: 100.0,
            temp_c: Some((0..n).map(|i| 20.0 + i as f64).collect()),
            ..Recording::default()
        };
        let seg = Segmentation {
            stills: vec![interval([0.0, 0.0, 1.0])],
            spins: Vec::new(),
            short_dropped: 0,
            acc_threshold: 0.01,
            gyro_threshold_rad_s: 0.01,
            gravity_out: 9.81,
        };
        let dir = tempfile::tempdir().unwrap();
        let plan = plan_for(&rec, &seg);
        assert!(plan.has_temperature());
        write_session(dir.path(), &rec, &seg, &plan, false).unwrap();
        let text = std::fs::read_to_string(dir.path().join(crate::session::SAMPLES_FILE)).unwrap();
        let mut lines = text.lines();
        assert_eq!(
            lines.next(),
            Some(crate::session::SAMPLES_HEADER_TEMPERATURE)
        );
        let row = lines.nth(3).unwrap();
        let temp: f64 = row.rsplit(',').next().unwrap().parse().unwrap();
        assert_eq!(temp, 23.0, "{row}");
        let stats = stats_for(&rec, &seg, &plan);
        assert_eq!(stats[0].count, 10);
        // Without temperature: format 2, eight columns.
        rec.temp_c = None;
        assert!(!plan_for(&rec, &seg).has_temperature());
    }
}
