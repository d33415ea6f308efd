//! Overflow: in stop-on-full mode the model drops the packets that do not fit; the driver flags the
//! first sample after them — exactly there, with the count from the time stamps — and no other
//! (the pipeline's count of them is tested on the pipeline side, in its `feed_tests`).

use super::*;
use crate::imu::icm42688::FifoFormat;
use crate::imu::ImuFlags;

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
