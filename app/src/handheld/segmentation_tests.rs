//! Segmentation ([`recording::session::segment`]) on simulated hand-held recordings: the simulator
//! lives above the recording layer, so these tests live here.

use estimator::sim::handheld::{logger_unit, simulate_hand, HandSpec};
use recording::session::coverage::coverage;
use recording::session::import::Recording;
use recording::session::segment::{angle_deg, find_intervals, PositionSet, SegmentOptions};
use shared::linalg;

/// The simulated session as the importer would deliver it.
pub(crate) fn recording(spec: &HandSpec, unit: shared::OutputUnit) -> Recording {
    let s = simulate_hand(&logger_unit(unit), spec);
    Recording {
        t_s: s.rows.iter().map(|r| r.0).collect(),
        acc: s.rows.iter().map(|r| r.1).collect(),
        gyro_rad_s: s.rows.iter().map(|r| r.2).collect(),
        acc_unit: Some(unit),
        rate_hz: spec.rate_hz,
        ..Recording::default()
    }
}

#[test]
fn finds_every_hand_position_and_no_false_one() {
    for seed in [1, 2, 3] {
        let spec = HandSpec::standard(seed);
        let sim = simulate_hand(
            &logger_unit(shared::OutputUnit::MetresPerSecondSquared),
            &spec,
        );
        let rec = recording(&spec, shared::OutputUnit::MetresPerSecondSquared);
        let seg = find_intervals(&rec, &SegmentOptions::default()).unwrap();
        assert_eq!(seg.stills.len(), sim.holds.len(), "seed {seed}");
        assert!(seg.spins.is_empty());
        for (s, (t0, t1, up)) in seg.stills.iter().zip(&sim.holds) {
            let (a, b) = (s.start_s, s.start_s + s.duration_s);
            assert!(
                a >= *t0 && b <= *t1,
                "seed {seed}: {a}..{b} not inside {t0}..{t1}"
            );
            assert!(
                s.duration_s > 0.6 * (t1 - t0),
                "seed {seed}: {a}..{b} of {t0}..{t1}"
            );
            assert!(angle_deg(&s.direction, up) < 3.0);
        }
        let cov = coverage(&seg.stills, 10.0);
        assert_eq!(cov.distinct, 24);
        assert!(cov.missing_faces.is_empty());
        assert_eq!(cov.check(24, 10.0).unwrap(), PositionSet::Spread);
    }
}

#[test]
fn a_steady_spin_is_listed_as_a_spin_not_as_a_still_position() {
    let mut rng = shared::rng::Rng::new(5, 0);
    let mut rec = Recording {
        acc_unit: Some(shared::OutputUnit::StandardGravity),
        rate_hz: 200.0,
        ..Recording::default()
    };
    // 4 s still z up, 4 s spinning at 90 °/s about the vertical (z), 4 s still x up.
    let parts = [
        ([0.0, 0.0, 1.0], 0.0),
        ([0.0, 0.0, 1.0], 90.0),
        ([1.0, 0.0, 0.0], 0.0),
    ];
    for (k, (up, rate)) in parts.iter().enumerate() {
        for i in 0..800 {
            rec.t_s.push((k * 800 + i) as f64 / 200.0);
            rec.acc
                .push(core::array::from_fn(|j| up[j] + 1e-3 * rng.normal()));
            let w: [f64; 3] = core::array::from_fn(|j| {
                (if j == 2 { *rate } else { 0.0 } + 0.05 * rng.normal()).to_radians()
            });
            rec.gyro_rad_s.push(w);
        }
    }
    let seg = find_intervals(&rec, &SegmentOptions::default()).unwrap();
    assert_eq!(seg.stills.len(), 2);
    assert_eq!(seg.spins.len(), 1);
    let spin = &seg.spins[0];
    assert!((linalg::norm(&spin.mean_gyro_rad_s).to_degrees() - 90.0).abs() < 0.1);
    assert!(spin.start_s > 4.0 && spin.start_s + spin.duration_s < 8.0);
    assert!(angle_deg(&seg.stills[1].direction, &[1.0, 0.0, 0.0]) < 0.5);
}

#[test]
fn no_still_interval_spans_a_time_gap() {
    let mut rng = shared::rng::Rng::new(9, 0);
    let mut rec = Recording {
        acc_unit: Some(shared::OutputUnit::StandardGravity),
        rate_hz: 100.0,
        ..Recording::default()
    };
    // 10 s still, z up, with 2 s of time stamps missing after 5 s.
    for i in 0..1000 {
        rec.t_s
            .push(i as f64 / 100.0 + if i >= 500 { 2.0 } else { 0.0 });
        rec.acc.push(core::array::from_fn(|j| {
            f64::from(u8::from(j == 2)) + 1e-3 * rng.normal()
        }));
        rec.gyro_rad_s.push(core::array::from_fn(|_| {
            0.01f64.to_radians() * rng.normal()
        }));
    }
    let seg = find_intervals(&rec, &SegmentOptions::default()).unwrap();
    assert_eq!(seg.stills.len(), 2, "{:?}", seg.stills);
    assert!(seg.stills[0].end <= 500 && seg.stills[1].start >= 500);
}
