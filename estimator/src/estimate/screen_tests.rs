//! Screening that speaks: every segment left out carries the figure that failed and its limit, and
//! a refusal for too few positions counts them and names every segment left out. The planted
//! disturbances (a gyro rate, a noise factor) are the independent truth the figures must show.

use super::*;
use crate::sim::testkit::{self, clean_session};
use recording::session::plan::Attitude;
use recording::session::{Plan, SegmentStats};
use shared::OutputUnit;

/// The paper's plan plus six oblique static attitudes, so that the fit survives bad statics.
fn plan_with_obliques() -> Plan {
    let mut plan = testkit::paper_plan(OutputUnit::Volts);
    let s3 = 1.0 / 3f64.sqrt();
    for (k, up) in [
        [s3, s3, s3],
        [-s3, s3, s3],
        [s3, -s3, s3],
        [s3, s3, -s3],
        [-s3, -s3, s3],
        [-s3, s3, -s3],
    ]
    .into_iter()
    .enumerate()
    {
        let mut seg = plan.segments[0].clone();
        seg.name = format!("oblique {k}");
        seg.up_b = up;
        plan.segments.push(seg);
    }
    plan
}

#[test]
fn screen_gives_each_moved_segment_its_figure_and_limit() {
    let plan = plan_with_obliques();
    let (_, clean) = clean_session(&plan, 2);
    let mut stats = clean.clone();
    // Planted: a 2 °/s turn on y+, and accelerometer x five times noisier on y−.
    stats[2].mean_w_rad_s = [0.0, 0.0, 2f64.to_radians()];
    stats[3].cov_u[0][0] *= 25.0;
    let options = EstimateOptions::default();
    let out = calibrate_session_stats(&plan, &stats, &options).unwrap();
    let find = |name: &str| out.excluded.iter().find(|e| e.name == name).unwrap();

    let turned = find(&plan.segments[2].name);
    let fig = turned
        .reason
        .figure()
        .expect("a moved segment has a figure");
    assert_eq!(fig.unit, "°/s");
    assert!((fig.value - 2.0).abs() < 0.01, "{fig:?}");
    assert!((fig.limit - options.motion_rate_threshold_rad_s.to_degrees()).abs() < 1e-12);
    assert!(fig.at_most && fig.value > fig.limit);
    let line = turned.to_string();
    assert!(
        line.contains("2.000 °/s") && line.contains("limit 0.500 °/s"),
        "{line}"
    );

    let shaken = find(&plan.segments[3].name);
    let fig = shaken
        .reason
        .figure()
        .expect("a noisy segment has a figure");
    assert_eq!(fig.unit, "×");
    // The others' noise is the simulator's 1 mg: the ratio is the planted 5× within the
    // estimate's scatter (a 1000 Hz segment's standard deviation is good to a few %).
    assert!((fig.value - 5.0).abs() < 0.5, "{fig:?}");
    assert_eq!(fig.limit, options.motion_noise_ratio);
    let line = shaken.to_string();
    assert!(
        line.contains("accelerometer x") && line.contains("> limit 2.000×"),
        "{line}"
    );
}

/// Every static position of `plan` held by hand: the attitudes free, as a hand-held session's.
fn free_statics(plan: &Plan) -> Plan {
    let mut p = plan.clone();
    p.segments.retain(|s| s.is_static());
    for s in &mut p.segments {
        s.attitude = Attitude::Free;
    }
    p
}

#[test]
fn screen_refusal_counts_positions_left_and_names_every_segment_left_out() {
    // The six faces, the six edge diagonals and the four corners: sixteen positions.
    let plan = free_statics(&testkit::many_mounts_plan());
    let positions = plan.segments.len();
    assert_eq!(positions, 16);
    let (_, clean) = clean_session(&plan, 5);
    // All sixteen positions: the free-attitude fit calibrates.
    let options = EstimateOptions::default();
    calibrate_session_stats(&plan, &clean, &options).unwrap();
    // Eight of them turned (planted rates ±3..10 °/s of alternating sign, beyond a hand's 2 °/s
    // drift, the other eight still, so the static median stays at the truth's zero): eight
    // positions are left, nine are needed.
    let mut stats = clean;
    let moved: Vec<String> = (0..8).map(|k| stats[2 * k].name.clone()).collect();
    for k in 0..8 {
        let sign = if k % 2 == 0 { 1.0 } else { -1.0 };
        stats[2 * k].mean_w_rad_s = [0.0, sign * (k as f64 + 3.0).to_radians(), 0.0];
    }
    let e = calibrate_session_stats(&plan, &stats, &options).unwrap_err();
    match &e {
        EstimateError::TooFewPositions {
            left,
            needed,
            planned,
            dropped,
        } => {
            assert_eq!((*left, *needed, *planned), (8, 9, positions));
            assert_eq!(dropped.len(), moved.len(), "{dropped:?}");
        }
        other => panic!("{other}"),
    }
    let text = e.to_string();
    assert!(
        text.contains("8 static position(s) left of the 16 planned") && text.contains("needs 9"),
        "{text}"
    );
    assert!(!text.contains("were excluded"), "{text}");
    for (k, name) in moved.iter().enumerate() {
        let planted = format!("{:.3} °/s > limit 2.000 °/s", k as f64 + 3.0);
        assert!(
            text.lines()
                .any(|l| l.contains(&format!("'{name}'")) && l.contains(&planted)),
            "'{name}' with {planted} in:\n{text}"
        );
    }
}

#[test]
fn screen_refusal_on_a_fixture_names_the_segments_left_out() {
    // The paper's plan: six faces. Both z faces turned (planted 2 and 3 °/s): the four left lie in
    // the xy plane.
    let plan = testkit::paper_plan(OutputUnit::Volts);
    let (_, mut stats) = clean_session(&plan, 7);
    let z: Vec<usize> = (0..stats.len())
        .filter(|&k| plan.segments[k].is_static() && plan.segments[k].up_b[2] != 0.0)
        .collect();
    assert_eq!(z.len(), 2);
    for (n, &k) in z.iter().enumerate() {
        stats[k].mean_w_rad_s = [(2.0 + n as f64).to_radians(), 0.0, 0.0];
    }
    let e = calibrate_session_stats(&plan, &stats, &EstimateOptions::default()).unwrap_err();
    assert!(
        matches!(e, EstimateError::TooFewAttitudes { attitudes: 4, ref dropped, .. } if dropped.len() == 2),
        "{e:?}"
    );
    let text = e.to_string();
    assert!(
        text.contains("the 4 usable static attitude(s)") && text.contains("at least four"),
        "{text}"
    );
    for (n, &k) in z.iter().enumerate() {
        let planted = format!("{:.3} °/s > limit 0.500 °/s", 2.0 + n as f64);
        let name = format!("'{}'", plan.segments[k].name);
        assert!(
            text.lines()
                .any(|l| l.contains(&name) && l.contains(&planted)),
            "{name} with {planted} in:\n{text}"
        );
    }
}

/// `st`'s gyro noise: `deg_s` per axis, white.
fn gyro_noise(st: &mut SegmentStats, deg_s: f64) {
    let v = deg_s.to_radians().powi(2);
    st.cov_w = [[v, 0.0, 0.0], [0.0, v, 0.0], [0.0, 0.0, v]];
}

/// A session with ten rests on a table and six held by hand: the hand's tremor triples the
/// gyro's noise at its positions (as a real MPU-6050 session shows: about 1 °/s against a table's
/// 0.3 °/s) without moving their mean specific force. Those positions are kept; held on a fixture,
/// the same noise is a sign of motion and the segment is left out.
#[test]
fn a_hand_held_position_is_not_moving_for_its_tremor() {
    let plan = free_statics(&testkit::many_mounts_plan());
    let (_, mut stats) = clean_session(&plan, 7);
    for (k, st) in stats.iter_mut().enumerate() {
        gyro_noise(st, if k < 10 { 0.3 } else { 1.0 });
    }
    let options = EstimateOptions::default();
    let out = calibrate_session_stats(&plan, &stats, &options).unwrap();
    assert!(out.excluded.is_empty(), "{:?}", out.excluded);
    // The same noise at a position on a rate table's fixture (a session with spins): left out as
    // moved (the criterion is alive).
    let fixture = testkit::many_mounts_plan();
    let (_, mut stats) = clean_session(&fixture, 7);
    let mut first = true;
    for (k, st) in stats.iter_mut().enumerate() {
        if fixture.segments[k].is_static() {
            gyro_noise(st, if first { 1.0 } else { 0.3 });
            first = false;
        }
    }
    let out = calibrate_session_stats(&fixture, &stats, &options).unwrap();
    let left_out = out.excluded.iter().find(|e| e.name == stats[0].name);
    assert!(
        left_out.is_some_and(|e| e.to_string().contains("gyro x noise")),
        "{:?}",
        out.excluded
    );
}
