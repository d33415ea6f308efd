//! A driver's samples through [`PipelineFeed`] into the pipeline: the tests that need both sides,
//! kept on the pipeline's (the drivers under `imu` know nothing of the pipeline). Moved unchanged
//! from `imu::tests::alignment` and `imu::tests::icm_overflow`.

use super::{Pipeline, PipelineCommand, PipelineFeed};
use crate::imu::alignment::SPEEDYBEE_F405_V4;
use crate::imu::icm42688::Config;
use crate::imu::tests::{code, drain_all, run_samples, started, truths};
use crate::imu::{ImuFlags, ImuSample};
use shared::wire::{DeviceToHost, SampleFlags, StreamKind, StreamRequest};

/// Through the feed and the pipeline as `burst_done` does it: a window's means are in the board's
/// axes; a NaN (invalid) sample stays left out; the values are exact (a signed permutation).
#[test]
fn windows_are_in_the_board_frame() {
    let sample = |accel_out, gyro_rad_s| ImuSample {
        accel_out,
        gyro_rad_s,
        temp_c: 25.0,
        timestamp: 0,
        lost_before: 0,
        flags: ImuFlags::default(),
    };
    let mut samples = [sample([100.0, 200.0, 4096.0], [0.25, -0.5, 0.125]); 8];
    samples[3] = ImuSample {
        flags: ImuFlags(ImuFlags::INVALID),
        ..sample([f32::NAN; 3], [f32::NAN; 3])
    };
    SPEEDYBEE_F405_V4.apply(&mut samples);
    let mut p = Pipeline::<4>::new(8000);
    p.apply(PipelineCommand::Stream(StreamRequest {
        kind: StreamKind::RawWindows,
        window_samples: 8,
    }));
    PipelineFeed::new(8000).push_all(&samples, &mut p);
    match p.pop_output() {
        Some(DeviceToHost::RawWindow(w)) => {
            assert_eq!(w.count, 7);
            assert_eq!(w.mean_raw, [200.0, -100.0, 4096.0]);
            assert_eq!(w.mean_rate_rad_s, [-0.5, -0.25, 0.125]);
        }
        other => panic!("{other:?}"),
    }
}

#[test]
fn the_pipeline_counts_the_lost_samples() {
    let cfg = Config {
        watermark_packets: 16,
        ..Config::DEFAULT
    };
    let mut imu = started(cfg);
    let mut p = Pipeline::<8>::new(1000);
    p.apply(PipelineCommand::Stream(StreamRequest {
        kind: StreamKind::RawWindows,
        window_samples: 200,
    }));
    run_samples(&mut imu, 150); // 128 kept, 22 dropped
    let mut feed = PipelineFeed::new(1000);
    for s in drain_all(&mut imu) {
        feed.push(&s, &mut p);
    }
    run_samples(&mut imu, 60);
    for s in drain_all(&mut imu) {
        feed.push(&s, &mut p);
    }
    // 128 + 22 lost + 60 = 210 samples of time: one 200-sample window closed.
    assert_eq!(p.samples(), 210);
    let Some(DeviceToHost::RawWindow(w)) = p.pop_output() else {
        panic!("a window");
    };
    assert!(w.flags.has(SampleFlags::SAMPLES_LOST));
    // Rejected: the invalid first sample, the 22 lost and the saturated ones in the window
    // (samples 1..128 and 150..200).
    let t = truths(200);
    let saturated = (1..128)
        .chain(150..200)
        .filter(|&k| {
            t[k].accel_g
                .iter()
                .any(|g| code(g * 2048.0, 32767).abs() == 32767)
                || t[k]
                    .gyro_dps
                    .iter()
                    .any(|d| code(d * 16.4, 32767).abs() == 32767)
        })
        .count() as u32;
    assert_eq!(w.rejected, 1 + 22 + saturated);
    assert_eq!(w.count + w.rejected, 200);
}
