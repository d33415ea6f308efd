//! Watermark: INT1 rises when the FIFO holds the watermark's number of packets, not before; reading
//! INT_STATUS (each drain does) releases it; with FIFO_WM_GT_TH it rises again at the next sample
//! while the FIFO is still above the watermark.

use super::*;

#[test]
fn int1_at_the_watermark() {
    let cfg = Config {
        watermark_packets: 10,
        ..Config::DEFAULT
    };
    let mut imu = started(cfg);
    for k in 1..10 {
        run_samples(&mut imu, 1);
        assert!(!imu.device_mut().int1(), "INT1 low with {k} packets");
    }
    run_samples(&mut imu, 1);
    assert!(imu.device_mut().int1(), "INT1 high with 10 packets");
    // A partial drain leaves 6 packets: INT1 released by the status read, and stays low below
    // the watermark.
    let mut four = [ImuSample::default(); 4];
    let d = imu.drain(&mut four).unwrap();
    assert_eq!((d.samples, d.more), (4, true));
    assert!(!imu.device_mut().int1());
    run_samples(&mut imu, 3);
    assert!(!imu.device_mut().int1(), "9 packets");
    run_samples(&mut imu, 1);
    assert!(imu.device_mut().int1(), "10 packets again");
    let mut buf = [ImuSample::default(); 16];
    assert_eq!(imu.drain(&mut buf).unwrap().samples, 10);
    // Still at the watermark after the next sample? Only 1 packet: no.
    run_samples(&mut imu, 1);
    assert!(!imu.device_mut().int1());
}
