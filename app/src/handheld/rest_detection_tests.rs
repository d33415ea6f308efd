//! Rest detection ([`recording::session::rest`]) on simulated logs whose truth is known: short rests in
//! long vibrating flights, hand-held rests beside table rests, continuous hand motion with no rest,
//! and a rad/s gyro held in a hand.

use super::segmentation_tests::recording;
use estimator::sim::handheld::{logger_unit, simulate_hand, HandSpec};
use recording::session::import::Recording;
use recording::session::segment::{find_intervals, SegmentError, SegmentOptions, StillThreshold};
use shared::rng::Rng;
use shared::OutputUnit;
use std::f64::consts::PI;

const RATE_HZ: f64 = 200.0;

/// Sinusoids per axis: (amplitude, angular frequency, phase).
type Tones = Vec<[(f64, f64, f64); 3]>;

fn tones(rng: &mut Rng, count: usize, amp: (f64, f64), hz: (f64, f64)) -> Tones {
    (0..count)
        .map(|_| {
            core::array::from_fn(|_| {
                (
                    rng.range(amp.0, amp.1),
                    2.0 * PI * rng.range(hz.0, hz.1),
                    2.0 * PI * rng.uniform(),
                )
            })
        })
        .collect()
}

fn play(t: &Tones, s: f64) -> [f64; 3] {
    core::array::from_fn(|j| t.iter().map(|p| p[j].0 * (p[j].1 * s + p[j].2).sin()).sum())
}

/// A multirotor's log in g and rad/s: `dur_s` of flight (the frame vibrating at 25–95 Hz by
/// 0.05–0.2 g and 2–8 °/s per tone, the attitude swinging ±10° at 0.05–0.2 Hz), except during
/// `rests` (start, length, s), where the vehicle stands level with its motors off: the sensors' own
/// noise (2 mg, 0.1 °/s per sample) and the gyro's bias only.
fn flight(seed: u64, dur_s: f64, rests: &[(f64, f64)]) -> Recording {
    let mut rng = Rng::new(seed, 70);
    let vib_a = tones(&mut rng, 3, (0.05, 0.2), (25.0, 95.0));
    let vib_w = tones(&mut rng, 3, (2.0, 8.0), (25.0, 95.0));
    let swing = tones(&mut rng, 2, (3.0, 5.0), (0.05, 0.2));
    let bias = [0.5f64, -0.3, 0.2].map(f64::to_radians);
    let mut rec = Recording {
        acc_unit: Some(OutputUnit::StandardGravity),
        rate_hz: RATE_HZ,
        ..Recording::default()
    };
    let n = (dur_s * RATE_HZ) as usize;
    for k in 0..n {
        let t = k as f64 / RATE_HZ;
        let at_rest = rests.iter().any(|&(a, l)| t >= a && t < a + l);
        let (roll, pitch) = if at_rest {
            (0.0, 0.0)
        } else {
            let s = play(&swing, t);
            (s[0].to_radians(), s[1].to_radians())
        };
        let g_b = [
            -pitch.sin(),
            roll.sin() * pitch.cos(),
            roll.cos() * pitch.cos(),
        ];
        let (va, vw) = if at_rest {
            ([0.0; 3], [0.0; 3])
        } else {
            (play(&vib_a, t), play(&vib_w, t).map(f64::to_radians))
        };
        rec.t_s.push(t);
        rec.acc.push(core::array::from_fn(|j| {
            g_b[j] + va[j] + 2e-3 * rng.normal()
        }));
        rec.gyro_rad_s.push(core::array::from_fn(|j| {
            bias[j] + vw[j] + 0.1f64.to_radians() * rng.normal()
        }));
    }
    rec
}

/// Every still found lies inside one of `rests` and covers most of it, and each rest has one.
fn assert_rests_found(rec: &Recording, rests: &[(f64, f64)], what: &str) {
    let seg =
        find_intervals(rec, &SegmentOptions::default()).unwrap_or_else(|e| panic!("{what}: {e}"));
    assert_eq!(seg.stills.len(), rests.len(), "{what}: {:?}", seg.stills);
    for (s, &(a, l)) in seg.stills.iter().zip(rests) {
        let (t0, t1) = (s.start_s, s.start_s + s.duration_s);
        assert!(
            t0 >= a && t1 <= a + l,
            "{what}: {t0}..{t1} not inside {a}..{}",
            a + l
        );
        // The window's half and the trim come off each end: 0.35 s.
        assert!(
            s.duration_s > l - 0.8,
            "{what}: {t0}..{t1} of {a}..{}",
            a + l
        );
        assert!(s.direction[2] > 0.9999, "{what}: {:?}", s.direction);
    }
}

#[test]
fn a_two_second_rest_anywhere_in_a_ten_minute_vibrating_flight_is_found_every_time() {
    for seed in 0..8 {
        let mut rng = Rng::new(seed, 71);
        let start = rng.range(5.0, 590.0);
        let rests = [(start, 2.0)];
        assert_rests_found(
            &flight(seed, 600.0, &rests),
            &rests,
            &format!("seed {seed}"),
        );
    }
}

#[test]
fn short_rests_at_the_ends_of_a_flight_log_are_found() {
    for seed in 0..4 {
        // A 150 s log whose first 3 s are at rest, and 2 s rests at both ends of 73 s.
        let first = [(0.0, 3.0)];
        assert_rests_found(&flight(seed, 150.0, &first), &first, "3 s of 150 s");
        let both = [(0.0, 2.0), (71.0, 2.0)];
        assert_rests_found(
            &flight(seed, 73.0, &both),
            &both,
            "2 s at both ends of 73 s",
        );
    }
}

#[test]
fn a_flight_with_no_rest_has_no_still_interval_and_the_message_says_what_was_measured() {
    // As `segment` asks, which has the fixed limits' option.
    let offered = SegmentOptions {
        offer_still_threshold: true,
        ..SegmentOptions::default()
    };
    let e = find_intervals(&flight(3, 120.0, &[]), &offered).unwrap_err();
    let text = e.to_string();
    assert!(matches!(e, SegmentError::NoStill { .. }), "{text}");
    assert!(
        text.contains("<StillThreshold> MG,DEG_S") && text.contains(" mg") && !text.contains("NaN"),
        "{text}"
    );
    // As `apply` and `noise` ask, which have no such option: not named.
    let e = find_intervals(&flight(3, 120.0, &[]), &SegmentOptions::default()).unwrap_err();
    assert!(!e.to_string().contains("<StillThreshold>"), "{e}");
}

/// A session of `hand` positions held in a hand (tremor `tremor_deg_s` per axis), then the other
/// positions set down on a table, one recording; the true holds in order.
fn hand_then_table(seed: u64, tremor_deg_s: f64) -> (Recording, Vec<(f64, f64)>) {
    let base = HandSpec::standard(seed);
    let (hand_ups, table_ups) = base.ups.split_at(12);
    let hand = HandSpec {
        ups: hand_ups.to_vec(),
        tremor_deg_s,
        tremor_g: 2e-3,
        ..base.clone()
    };
    let table = HandSpec {
        ups: table_ups.to_vec(),
        hold_tremor: false,
        seed: seed + 1000,
        ..base
    };
    let unit = logger_unit(OutputUnit::MetresPerSecondSquared);
    let (a, b) = (simulate_hand(&unit, &hand), simulate_hand(&unit, &table));
    let shift = a.rows.last().map_or(0.0, |r| r.0) + 1.0 / RATE_HZ;
    let mut rec = recording(&hand, OutputUnit::MetresPerSecondSquared);
    for r in &b.rows {
        rec.t_s.push(r.0 + shift);
        rec.acc.push(r.1);
        rec.gyro_rad_s.push(r.2);
    }
    let holds = a
        .holds
        .iter()
        .map(|h| (h.0, h.1))
        .chain(b.holds.iter().map(|h| (h.0 + shift, h.1 + shift)))
        .collect();
    (rec, holds)
}

#[test]
fn hand_held_rests_beside_table_rests_are_all_found_over_many_seeds() {
    for seed in 0..10 {
        // A person's tremor of 0.5–2 °/s (rms over the axes) at the hand-held rests.
        let tremor = [0.3, 0.6, 1.1][seed as usize % 3];
        let (rec, holds) = hand_then_table(seed, tremor);
        let seg = find_intervals(&rec, &SegmentOptions::default())
            .unwrap_or_else(|e| panic!("seed {seed}: {e}"));
        assert_eq!(seg.stills.len(), holds.len(), "seed {seed}");
        for (s, (t0, t1)) in seg.stills.iter().zip(&holds) {
            let (a, b) = (s.start_s, s.start_s + s.duration_s);
            assert!(
                a >= *t0 && b <= *t1,
                "seed {seed}: {a}..{b} not inside {t0}..{t1}"
            );
            assert!(
                s.duration_s > 0.6 * (t1 - t0),
                "seed {seed}: {a}..{b} of {t0}..{t1}"
            );
        }
    }
}

#[test]
fn continuous_hand_motion_has_no_false_rest() {
    for seed in 0..10 {
        let spec = HandSpec {
            hold_s: (0.0, 0.0),
            // Slow turns too: 1–3 s and 3–6 s between positions.
            turn_s: if seed % 2 == 0 {
                (1.0, 3.0)
            } else {
                (3.0, 6.0)
            },
            tremor_deg_s: 1.0,
            tremor_g: 2e-3,
            ..HandSpec::standard(seed)
        };
        let rec = recording(&spec, OutputUnit::MetresPerSecondSquared);
        match find_intervals(&rec, &SegmentOptions::default()) {
            Err(SegmentError::NoStill { .. }) => {}
            Ok(seg) => panic!("seed {seed}: false rests {:?}", seg.stills),
            Err(e) => panic!("seed {seed}: {e}"),
        }
    }
}

#[test]
fn a_rad_s_gyro_held_in_a_hand_is_not_told_to_change_its_unit() {
    // Hand-held rests only, the gyro moving 0.5–0.9 °/s per axis with the hand's tremor, logged
    // in rad/s as it should be: the rests are found ...
    for (seed, tremor) in [(1, 0.5), (2, 0.7), (3, 0.9)] {
        let spec = HandSpec {
            tremor_deg_s: tremor,
            tremor_g: 2e-3,
            ..HandSpec::standard(seed)
        };
        let rec = recording(&spec, OutputUnit::MetresPerSecondSquared);
        let seg = find_intervals(&rec, &SegmentOptions::default())
            .unwrap_or_else(|e| panic!("seed {seed}: {e}"));
        assert_eq!(seg.stills.len(), spec.ups.len(), "seed {seed}");
        // ... and where they are too short to keep, the refusal never suggests a gyro in °/s.
        let short = HandSpec {
            hold_s: (0.7, 0.9),
            ..spec
        };
        let offered = SegmentOptions {
            offer_still_threshold: true,
            ..SegmentOptions::default()
        };
        let e = find_intervals(
            &recording(&short, OutputUnit::MetresPerSecondSquared),
            &offered,
        )
        .unwrap_err()
        .to_string();
        assert!(
            !e.contains("gyro-unit") && !e.contains("<GyroUnit>") && !e.contains("NaN"),
            "seed {seed}: {e}"
        );
        assert!(e.contains("<StillThreshold>"), "{e}");
    }
}

#[test]
fn fixed_limits_are_honoured_where_the_floor_would_refuse() {
    // Held in a shaking hand (4 °/s per axis of tremor): beyond a hand-held rest's signature.
    let spec = HandSpec {
        tremor_deg_s: 4.0,
        ..HandSpec::standard(4)
    };
    let rec = recording(&spec, OutputUnit::MetresPerSecondSquared);
    let fixed = SegmentOptions {
        still_threshold: Some(StillThreshold {
            acc_mg: 15.0,
            gyro_deg_s: 12.0,
        }),
        ..SegmentOptions::default()
    };
    let seg = find_intervals(&rec, &fixed).unwrap();
    let sim = simulate_hand(&logger_unit(OutputUnit::MetresPerSecondSquared), &spec);
    assert_eq!(
        seg.stills.len(),
        spec.ups.len(),
        "{:?}\n{:?}",
        seg.stills
            .iter()
            .map(|s| (s.start_s, s.duration_s))
            .collect::<Vec<_>>(),
        sim.holds.iter().map(|h| (h.0, h.1)).collect::<Vec<_>>()
    );
    // A limit tighter than the tremor finds nothing and says which limits it used.
    let tight = SegmentOptions {
        still_threshold: Some(StillThreshold {
            acc_mg: 15.0,
            gyro_deg_s: 1.0,
        }),
        ..SegmentOptions::default()
    };
    let e = find_intervals(&rec, &tight).unwrap_err().to_string();
    assert!(e.contains("within 15.00 mg and 1.000 °/s"), "{e}");
}

#[test]
fn a_recording_shorter_than_a_window_is_refused_without_made_up_figures() {
    let rec = Recording {
        t_s: vec![0.0, 0.01],
        acc: vec![[0.0, 0.0, 1.0]; 2],
        gyro_rad_s: vec![[0.0; 3]; 2],
        rate_hz: 100.0,
        ..Recording::default()
    };
    let e = find_intervals(&rec, &SegmentOptions::default())
        .unwrap_err()
        .to_string();
    assert!(e.contains("2 sample(s)") && !e.contains("NaN"), "{e}");
}
