//! The operator's instruction for a segment, the table setting that performs it, and the live checks
//! that a recorded segment matches its plan (the live procedure's `crate::procedure`).

use recording::session::{self, SegmentPlan};
use shared::wire::VirtualTable;

pub(crate) fn describe_up(up: &[f64; 3]) -> String {
    let names = ["x", "y", "z"];
    for (i, n) in names.iter().enumerate() {
        if (up[i].abs() - 1.0).abs() < 1e-9 {
            return format!("{}-axis {}", n, if up[i] > 0.0 { "up" } else { "down" });
        }
    }
    format!(
        "tilted, up = ({:+.3}, {:+.3}, {:+.3}) in body axes",
        up[0], up[1], up[2]
    )
}

pub(crate) fn instruction(seg: &SegmentPlan) -> String {
    let mount = describe_up(&seg.up_b);
    let motion = match (seg.rate_deg_s, seg.rate_end_deg_s) {
        (0.0, None) => format!("[{}] mount the unit {mount}, table at rest", seg.name),
        (r, None) => format!("[{}] mount the unit {mount}, set the table to {r:+.0} °/s about the vertical", seg.name),
        (r0, Some(r1)) => format!(
            "[{}] mount the unit {mount}, ramp the table from {r0:+.0} to {r1:+.0} °/s about the vertical",
            seg.name
        ),
    };
    match (seg.temp_c, seg.temp_end_c) {
        (None, _) => motion,
        (Some(t), None) => {
            format!(
                "{motion}; chamber at {t:+.1} °C, soaked until the unit's temperature is steady"
            )
        }
        (Some(t0), Some(t1)) => {
            format!("{motion}; ramp the chamber from {t0:+.1} to {t1:+.1} °C during the segment")
        }
    }
}

pub(crate) fn table_for(seg: &SegmentPlan) -> VirtualTable {
    let duration = seg.duration_s.unwrap_or(60.0);
    let accel = seg
        .rate_end_deg_s
        .map_or(0.0, |r1| (r1 - seg.rate_deg_s) / duration);
    VirtualTable {
        up_b: seg.up_b.map(|v| v as f32),
        rate_rad_s: seg.rate_deg_s.to_radians() as f32,
        accel_rad_s2: accel.to_radians() as f32,
    }
}

/// The live check of one recorded segment against its plan (`docs/model.md` §5: ω = rate·up).
pub(crate) fn live_check(
    seg: &SegmentPlan,
    stats: &session::SegmentStats,
    rejected_samples: u64,
) -> Vec<String> {
    let mut problems = Vec::new();
    let w = stats.mean_w_rad_s;
    let along = shared::linalg::dot(&w, &seg.up_b);
    let across: [f64; 3] = std::array::from_fn(|j| w[j] - along * seg.up_b[j]);
    let across_deg_s = shared::linalg::norm(&across).to_degrees();
    let planned = 0.5 * (seg.rate_deg_s + seg.rate_end_deg_s.unwrap_or(seg.rate_deg_s));
    let along_deg_s = along.to_degrees();
    if seg.is_static() {
        let spread = stats
            .std_w()
            .iter()
            .fold(0.0f64, |a, b| a.max(*b))
            .to_degrees();
        if shared::linalg::norm(&w).to_degrees() > 1.0 || spread > 1.0 {
            problems.push(format!(
                "the unit should be at rest but the gyro reads {:.2} °/s (spread {spread:.2} °/s): wait for the \
                 table to stop and do not touch the unit",
                shared::linalg::norm(&w).to_degrees()
            ));
        }
    } else {
        let tol = (0.05 * planned.abs()).max(2.0);
        if (along_deg_s - planned).abs() > tol {
            if (along_deg_s + planned).abs() <= tol {
                problems.push(format!(
                    "the unit turns at {along_deg_s:+.1} °/s about the plan's up direction, the plan says \
                     {planned:+.1} °/s: it is mounted upside down, or the table turns the other way"
                ));
            } else {
                problems.push(format!(
                    "the rate about the plan's up direction is {along_deg_s:+.1} °/s, the plan says {planned:+.1} °/s: \
                     set the table rate"
                ));
            }
        }
        if across_deg_s > (0.09 * planned.abs()).max(2.0) {
            problems.push(format!(
                "the rotation axis is {across_deg_s:.1} °/s off the plan's up direction ({}): check the mount",
                describe_up(&seg.up_b)
            ));
        }
    }
    if rejected_samples > 0 {
        problems.push(format!(
            "{rejected_samples} samples were saturated or invalid and left out: check the range and the wiring"
        ));
    }
    problems
}

/// "Right side up" for a static segment, without a calibration: if its mean outputs equal those of an
/// earlier static segment whose planned attitude differs by more than 10°, the unit was not re-mounted
/// (a 10° change moves some output by about 0.17 g, thousands of noise σ of a segment mean).
pub(crate) fn remount_check(
    seg: &SegmentPlan,
    stats: &session::SegmentStats,
    earlier: &[(SegmentPlan, session::SegmentStats)],
) -> Option<String> {
    let cos_10_deg = 10f64.to_radians().cos();
    earlier.iter().find_map(|(other, o)| {
        let different = shared::linalg::dot(&seg.up_b, &other.up_b) < cos_10_deg;
        // Outputs within 20 standard errors of each other on every axis: the same attitude.
        let same = (0..3).all(|i| {
            let se = (stats.cov_u[i][i] / stats.count as f64 + o.cov_u[i][i] / o.count as f64).sqrt();
            (stats.mean_u[i] - o.mean_u[i]).abs() <= 20.0 * se.max(1e-12)
        });
        (different && same).then(|| {
            format!(
                "the outputs are those of segment '{}' ({}), not of {}: the unit was not re-mounted",
                other.name,
                describe_up(&other.up_b),
                describe_up(&seg.up_b)
            )
        })
    })
}
