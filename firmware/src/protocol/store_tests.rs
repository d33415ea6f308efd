//! The calibration store leaves the link's path: the link service (what the F405's USB interrupt
//! runs) never erases or programs flash; the board's lowest priority does, through [`StoreJob`].

use super::*;
use crate::paper_unit::{self, QEMU_UNIT_ID};
use crate::storage::{AbStore, RamNorFlash};
use embedded_storage::nor_flash::{ErrorType, NorFlash, ReadNorFlash};
use shared::blob::ParameterBlob;
use shared::wire::{blob_chunks, HOST_FRAME_MAX};
use shared::OutputUnit;
use std::cell::Cell;
use std::collections::VecDeque;
use std::rc::Rc;
use std::vec::Vec;

const ERASE: usize = 1024;

/// A RAM flash that counts its erase and program operations where the test can see them.
struct CountingFlash {
    inner: RamNorFlash<'static, ERASE>,
    ops: Rc<Cell<u32>>,
}

impl ErrorType for CountingFlash {
    type Error = <RamNorFlash<'static, ERASE> as ErrorType>::Error;
}

impl ReadNorFlash for CountingFlash {
    const READ_SIZE: usize = 1;
    fn read(&mut self, offset: u32, bytes: &mut [u8]) -> Result<(), Self::Error> {
        self.inner.read(offset, bytes)
    }
    fn capacity(&self) -> usize {
        self.inner.capacity()
    }
}

impl NorFlash for CountingFlash {
    const WRITE_SIZE: usize = 4;
    const ERASE_SIZE: usize = ERASE;
    fn erase(&mut self, from: u32, to: u32) -> Result<(), Self::Error> {
        self.ops.set(self.ops.get() + 1);
        self.inner.erase(from, to)
    }
    fn write(&mut self, offset: u32, bytes: &[u8]) -> Result<(), Self::Error> {
        self.ops.set(self.ops.get() + 1);
        self.inner.write(offset, bytes)
    }
}

#[derive(Default)]
struct Link {
    rx: VecDeque<u8>,
    tx: Vec<u8>,
}

impl ByteLink for Link {
    fn try_read(&mut self) -> Option<u8> {
        self.rx.pop_front()
    }
    fn try_write(&mut self, b: u8) -> bool {
        self.tx.push(b);
        true
    }
}

impl Link {
    fn send(&mut self, m: &HostToDevice) {
        let mut buf = [0u8; HOST_FRAME_MAX];
        self.rx
            .extend(encode_frame(m, &mut buf).unwrap().iter().copied());
    }
    fn take(&mut self) -> Vec<DeviceToHost> {
        let bytes = core::mem::take(&mut self.tx);
        bytes
            .split(|b| *b == 0)
            .filter(|f| !f.is_empty())
            .map(|f| decode_frame::<DeviceToHost>(&mut f.to_vec()).unwrap())
            .collect()
    }
}

const INFO: DeviceInfo = DeviceInfo {
    unit_id: QEMU_UNIT_ID,
    board: Board::QemuMps2An386,
    sample_rate_hz: 1000,
    virtual_table: true,
    output_unit: OutputUnit::Volts,
};

fn service() -> (LinkService<AbStore<CountingFlash>>, Rc<Cell<u32>>) {
    let ops = Rc::new(Cell::new(0));
    let mem: &'static mut [u8] = Vec::leak(std::vec![0u8; 2 * ERASE]);
    let flash = CountingFlash {
        inner: RamNorFlash::new(mem),
        ops: ops.clone(),
    };
    let store = AbStore::new(flash, 0, ERASE as u32).unwrap();
    let controller = Controller::boot(INFO, store, LeverMode::RateAndAcceleration);
    (LinkService::new(controller), ops)
}

fn blob() -> Vec<u8> {
    let (buf, n) = ParameterBlob {
        unit_id: QEMU_UNIT_ID,
        calibration: paper_unit::calibration(),
        created_unix_s: 7,
    }
    .to_bytes()
    .unwrap();
    buf[..n].to_vec()
}

/// A whole calibration write and a request after it, through the link service alone — the USB
/// interrupt's work on the F405 — erases and programs nothing and answers neither; the job, run
/// as the idle loop runs it and handed back, stores, applies and answers, then the request after
/// it is answered. Fails if the handler stores the blob itself.
#[test]
fn the_link_path_never_erases_or_programs_flash() {
    let (mut service, ops) = service();
    let mut pipeline = Pipeline::<4>::new(1000);
    let mut link = Link::default();
    let chunks: Vec<_> = blob_chunks(&blob()).collect();
    for c in &chunks {
        link.send(&HostToDevice::WriteCalibration(*c));
    }
    link.send(&HostToDevice::Identify);
    for _ in 0..50 {
        service.poll(&mut link, &mut pipeline);
    }
    assert_eq!(ops.get(), 0, "the link path erased or programmed flash");
    let replies = link.take();
    assert_eq!(replies.len(), chunks.len() - 1, "{replies:?}");
    assert!(replies
        .iter()
        .all(|r| matches!(r, DeviceToHost::Ack(Ack::ChunkReceived { .. }))));
    assert!(!pipeline.is_calibrated());

    // The idle loop's half, through the board's mailbox.
    let mut mailbox = StoreMailbox::new();
    mailbox.post(service.take_store_job().expect("a store job"));
    assert!(mailbox.take_done().is_none());
    let mut job = mailbox.take_to_run().expect("a job to run");
    job.run();
    assert!(ops.get() > 0, "the job stored nothing");
    mailbox.post(job);
    assert!(mailbox.take_to_run().is_none());
    let job = mailbox.take_done().expect("the job back");
    let before = ops.get();
    service.finish_store(job, &mut pipeline);
    for _ in 0..5 {
        service.poll(&mut link, &mut pipeline);
    }
    assert_eq!(ops.get(), before);
    let replies = link.take();
    assert_eq!(replies[0], DeviceToHost::Ack(Ack::CalibrationStored));
    assert!(
        matches!(replies[1], DeviceToHost::Identity(i)
            if i.calibration == CalibrationState::Valid { created_unix_s: 7 }),
        "{replies:?}"
    );
    assert!(pipeline.is_calibrated());
    assert!(service.take_store_job().is_none());
}

/// A job handed back unrun answers `StorageFailed` and changes nothing; the store comes back, so the
/// next write works.
#[test]
fn a_job_handed_back_unrun_fails_cleanly() {
    let (mut service, _) = service();
    let mut pipeline = Pipeline::<4>::new(1000);
    let mut link = Link::default();
    for c in blob_chunks(&blob()) {
        link.send(&HostToDevice::WriteCalibration(c));
    }
    for _ in 0..50 {
        service.poll(&mut link, &mut pipeline);
    }
    let job = service.take_store_job().unwrap();
    service.finish_store(job, &mut pipeline);
    service.poll(&mut link, &mut pipeline);
    assert_eq!(
        link.take().last(),
        Some(&DeviceToHost::Error(DeviceError::StorageFailed))
    );
    assert!(!pipeline.is_calibrated());
    for c in blob_chunks(&blob()) {
        link.send(&HostToDevice::WriteCalibration(c));
    }
    for _ in 0..50 {
        service.poll(&mut link, &mut pipeline);
        service.run_store_here(&mut pipeline);
    }
    assert_eq!(
        link.take().last(),
        Some(&DeviceToHost::Ack(Ack::CalibrationStored))
    );
}
