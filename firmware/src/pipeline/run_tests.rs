//! Runs against the per-sample path: for any mix of clean and flagged samples, any stream, lever
//! mode, calibration and temperature period, and any split into transfers, `PipelineFeed::push_all`
//! (runs through `Pipeline::on_run`) gives the frames, sample count and temperature state that
//! `PipelineFeed::push` gives sample by sample.

use proptest::prelude::*;
use shared::compensator::{Compensator, LeverMode};
use shared::wire::{StreamKind, StreamRequest};

use super::PipelineFeed;
use super::{Pipeline, PipelineCommand};
use crate::imu::{ImuFlags, ImuSample};
use crate::paper_unit;

/// One generated sample: values, temperature, and what is odd about it (0: clean).
fn sample(k: usize, odd: u8, lost: u16, temp_c: f32) -> ImuSample {
    let t = k as f32 * 0.01;
    let mut s = ImuSample {
        accel_out: [
            2.5 + 0.1 * t.sin(),
            2.4 - 0.05 * t,
            2.6 + 0.02 * (3.0 * t).cos(),
        ],
        gyro_rad_s: [0.5 * t.cos(), -0.3 + 0.01 * t, 2.0 * (0.7 * t).sin()],
        temp_c,
        timestamp: k as u16,
        lost_before: 0,
        flags: ImuFlags(0),
    };
    match odd {
        1 => s.flags.0 |= ImuFlags::SATURATED,
        2 => {
            s.flags.0 |= ImuFlags::INVALID;
            s.gyro_rad_s = [f32::NAN; 3];
        }
        3 => {
            s.flags.0 |= ImuFlags::DATA_LOST;
            s.lost_before = lost;
        }
        _ => {}
    }
    s
}

fn pipeline(stream: u8, window: u32, comp: u8, thermal: bool, rate_hz: u32) -> Pipeline<8> {
    let mut p = Pipeline::<8>::new(rate_hz);
    let mut cal = shared::Calibration {
        gyro: Some(paper_unit::typical_gyro()),
        ..paper_unit::calibration()
    };
    if thermal {
        cal.temperature = Some(paper_unit::typical_thermal_model());
    }
    let mode = [
        LeverMode::Off,
        LeverMode::RateOnly,
        LeverMode::RateAndAcceleration,
    ];
    let c = mode
        .get(usize::from(comp))
        .map(|&m| Compensator::new(&cal, m).unwrap());
    p.apply(PipelineCommand::Compensator(c));
    let kinds = [
        StreamKind::RawWindows,
        StreamKind::CompensatedWindows,
        StreamKind::RawDecimated,
        StreamKind::CompensatedDecimated,
    ];
    if let Some(&kind) = kinds.get(usize::from(stream)) {
        p.apply(PipelineCommand::Stream(StreamRequest {
            kind,
            window_samples: window,
        }));
    }
    p
}

fn drain(p: &mut Pipeline<8>, out: &mut Vec<String>) {
    // Debug text: every f32 printed so that it reads back to the same bits (NaN as NaN).
    while let Some(f) = p.pop_output() {
        out.push(format!("{f:?}"));
    }
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(400))]
    #[test]
    fn runs_give_what_samples_one_by_one_give(
        odd in prop::collection::vec((0u8..12, 0u16..4), 1..400),
        temps in prop::collection::vec(prop_oneof![20 => 15.0f32..45.0, 1 => Just(f32::NAN)], 1..400),
        splits in prop::collection::vec(1usize..24, 1..60),
        stream in 0u8..5,
        window in 1u32..60,
        comp in 0u8..4,
        thermal in any::<bool>(),
        rate_hz in prop_oneof![Just(100u32), Just(160), Just(1000)],
    ) {
        let samples: Vec<ImuSample> = odd
            .iter()
            .enumerate()
            .map(|(k, &(o, lost))| sample(k, o, lost, temps[k % temps.len()]))
            .collect();
        let (mut one, mut runs) = (
            pipeline(stream, window, comp, thermal, rate_hz),
            pipeline(stream, window, comp, thermal, rate_hz),
        );
        let (mut feed_one, mut feed_runs) = (PipelineFeed::new(rate_hz), PipelineFeed::new(rate_hz));
        let (mut frames_one, mut frames_runs) = (Vec::new(), Vec::new());
        let mut rest = &samples[..];
        for &k in splits.iter().cycle() {
            if rest.is_empty() {
                break;
            }
            let (batch, tail) = rest.split_at(k.min(rest.len()));
            for s in batch {
                feed_one.push(s, &mut one);
            }
            feed_runs.push_all(batch, &mut runs);
            drain(&mut one, &mut frames_one);
            drain(&mut runs, &mut frames_runs);
            prop_assert_eq!(one.samples(), runs.samples());
            prop_assert_eq!(
                format!("{:?}", one.compensator().map(|c| c.temperature_state())),
                format!("{:?}", runs.compensator().map(|c| c.temperature_state()))
            );
            rest = tail;
        }
        prop_assert_eq!(frames_one, frames_runs);
    }
}

/// The runs are taken: a clean transfer goes through `on_run` in one piece (its count is the
/// transfer's), and a flagged sample stops a run.
#[test]
fn a_clean_transfer_is_one_run_and_a_flag_stops_it() {
    let mut p = pipeline(1, 1000, 2, true, 1000);
    let clean: Vec<ImuSample> = (0..16).map(|k| sample(k, 0, 0, 25.0)).collect();
    assert_eq!(p.on_run(&clean, |_| {}), 16);
    let mut flagged = clean.clone();
    flagged[5] = sample(5, 1, 0, 25.0);
    assert_eq!(p.on_run(&flagged, |_| {}), 5);
    let mut p = pipeline(2, 10, 2, true, 1000); // decimated: per sample
    assert_eq!(p.on_run(&clean, |_| {}), 0);
}
