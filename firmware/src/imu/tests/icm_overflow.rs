//! Overflow: in stop-on-full mode the model drops the packets that do not fit; the driver flags the
//! first sample after them — exactly there, with the count from the time stamps — and no other,
//! and the pipeline counts them as lost, keeping its sample index as the time base.

use super::*;
use crate::imu::icm42688::FifoFormat;
use crate::imu::{ImuFlags, PipelineFeed};
use crate::pipeline::{Pipeline, PipelineCommand};
use shared::wire::{DeviceToHost, SampleFlags, StreamKind, StreamRequest};

fn overflow_case(format: FifoFormat, capacity: u32) {
    let cfg = Config {
        fifo: format,
        watermark_packets: 16,
        ..Config::DEFAULT
    };
    let mut imu = started(cfg);
    run_samples(&mut imu, capacity + 22);
    assert_eq!(
        imu.device_mut().dropped.as_slice(),
        (capacity..capacity + 22).collect::<Vec<_>>().as_slice(),
        "the model dropped the samples after the FIFO filled"
    );
    let mut got = drain_all(&mut imu);
    assert_eq!(got.len() as u32, capacity);
    run_samples(&mut imu, 5);
    got.extend(drain_all(&mut imu));
    let flagged: Vec<usize> = (0..got.len())
        .filter(|&k| got[k].flags.has(ImuFlags::DATA_LOST))
        .collect();
    assert_eq!(
        flagged,
        vec![capacity as usize],
        "exactly the sample after the gap"
    );
    assert_eq!(got[capacity as usize].lost_before, 22);
    // That sample is the generator's sample number capacity + 22.
    let (lsb, max) = match format {
        FifoFormat::Packet3 => (2048.0, 32767),
        FifoFormat::Packet4HighRes => (8192.0, 131_071),
    };
    let t = truths(capacity as usize + 23)[capacity as usize + 22];
    let want = code(t.accel_g[2] * lsb, max) as f32;
    assert_eq!(got[capacity as usize].accel_out[2], want);
}

#[test]
fn overflow_flagged_exactly_where_packets_were_dropped_packet3() {
    overflow_case(FifoFormat::Packet3, 2048 / 16);
}

#[test]
fn overflow_flagged_exactly_where_packets_were_dropped_packet4() {
    overflow_case(FifoFormat::Packet4HighRes, 2048 / 20);
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
