//! Errors: an SPI failure reaches the caller as `Error::Spi` (start and drain); a FIFO read out of
//! step is reported as `FifoCorrupt` with the header it found, the FIFO is flushed, and the next
//! sample is flagged as following lost data. The async driver gives the same samples.

use super::*;
use crate::imu::icm42688::{regs, Error, Icm42688Async};
use crate::imu::sim::BusFault;
use crate::imu::{ImuFlags, ImuSourceAsync};
use embedded_hal::spi::{Operation, SpiDevice};

#[test]
fn spi_errors_propagate() {
    let mut m = Icm42688Model::new(TestGen::default());
    m.fail_spi = true;
    assert_eq!(
        Icm42688::new(m, Config::DEFAULT).err(),
        Some(Error::Spi(BusFault))
    );
    let mut imu = started(Config::DEFAULT);
    run_samples(&mut imu, 3);
    imu.device_mut().fail_spi = true;
    let mut buf = [ImuSample::default(); 4];
    assert_eq!(imu.drain(&mut buf), Err(Error::Spi(BusFault)));
    assert_eq!(imu.self_test().err(), Some(Error::Spi(BusFault)));
}

#[test]
fn fifo_out_of_step_is_flushed_and_flagged() {
    let mut imu = started(Config::DEFAULT);
    run_samples(&mut imu, 5);
    assert_eq!(drain_all(&mut imu).len(), 5);
    run_samples(&mut imu, 5);
    // Something else popped 3 bytes: the next "header" is accelerometer data.
    let mut junk = [0u8; 3];
    imu.device_mut()
        .transaction(&mut [
            Operation::Write(&[regs::FIFO_DATA as u8 | regs::READ]),
            Operation::Read(&mut junk),
        ])
        .unwrap();
    let mut buf = [ImuSample::default(); 8];
    match imu.drain(&mut buf) {
        Err(Error::FifoCorrupt { header }) => assert_ne!(header & 0xFC, regs::HEADER_PACKET3),
        other => panic!("{other:?}"),
    }
    assert_eq!(imu.device_mut().fifo_len(), 0, "flushed");
    run_samples(&mut imu, 2);
    let got = drain_all(&mut imu);
    assert_eq!(got.len(), 2);
    assert!(got[0].flags.has(ImuFlags::DATA_LOST));
    assert!(!got[1].flags.has(ImuFlags::DATA_LOST));
}

fn block_on<F: core::future::Future>(f: F) -> F::Output {
    let mut f = core::pin::pin!(f);
    let mut cx = core::task::Context::from_waker(core::task::Waker::noop());
    loop {
        if let core::task::Poll::Ready(v) = f.as_mut().poll(&mut cx) {
            return v;
        }
    }
}

#[test]
fn async_driver_gives_the_same_samples() {
    let cfg = Config {
        watermark_packets: 20,
        ..Config::DEFAULT
    };
    let mut a = block_on(Icm42688Async::new(
        Icm42688Model::new(TestGen::default()),
        cfg,
    ))
    .unwrap();
    let mut b = started(cfg);
    for _ in 0..20 {
        let m = a.device_mut();
        m.advance_ns(m.until_next_sample_ns());
    }
    run_samples(&mut b, 20);
    let mut sa = [ImuSample::default(); 16];
    let da = block_on(a.drain(&mut sa)).unwrap();
    let mut sb = [ImuSample::default(); 16];
    let db = b.drain(&mut sb).unwrap();
    assert_eq!(da, db);
    assert_eq!(format!("{sa:?}"), format!("{sb:?}"));
    a.device_mut().generator().still = true;
    let r = block_on(a.self_test()).unwrap();
    assert!(r.passed(), "{r:?}");
    a.device_mut().who_am_i = 0x12;
    assert_eq!(block_on(a.who_am_i()).unwrap(), 0x12);
}
