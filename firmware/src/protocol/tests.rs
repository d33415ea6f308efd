//! End-to-end tests of the device logic on the PC: bytes in, bytes out, with the virtual sensor, the
//! pipeline, the link service and the A/B store on a RAM flash — the QEMU board minus its registers.

use super::*;
use crate::paper_unit::{self, QEMU_UNIT_ID};
use crate::storage::{AbStore, RamNorFlash, StoreError};
use proptest::prelude::*;
use shared::blob::{ParameterBlob, BLOB_MAX_LEN};
use shared::wire::{
    blob_chunks, CompensatedWindow, SampleFlags, StreamKind, StreamRequest, HOST_FRAME_MAX,
};
use shared::OutputUnit;
use std::collections::VecDeque;
use std::vec::Vec;

const ERASE: usize = 1024;
type Store = AbStore<RamNorFlash<'static, ERASE>>;

/// A link with a receive queue and a transmit byte budget per poll (`None`: unlimited).
struct TestLink {
    rx: VecDeque<u8>,
    tx: Vec<u8>,
    budget: Option<usize>,
}

impl ByteLink for TestLink {
    fn try_read(&mut self) -> Option<u8> {
        self.rx.pop_front()
    }
    fn try_write(&mut self, b: u8) -> bool {
        match &mut self.budget {
            Some(0) => false,
            Some(n) => {
                *n -= 1;
                self.tx.push(b);
                true
            }
            None => {
                self.tx.push(b);
                true
            }
        }
    }
}

const INFO: DeviceInfo = DeviceInfo {
    unit_id: QEMU_UNIT_ID,
    board: Board::QemuMps2An386,
    sample_rate_hz: 1000,
    virtual_table: true,
    output_unit: OutputUnit::Volts,
};

struct Sim {
    service: LinkService<Store>,
    pipeline: Pipeline<16>,
    sensor: VirtualSensor,
    link: TestLink,
    resets: u32,
}

fn fresh_store() -> Store {
    let mem: &'static mut [u8] = Vec::leak(std::vec![0u8; 2 * ERASE]);
    AbStore::new(RamNorFlash::new(mem), 0, ERASE as u32).unwrap()
}

impl Sim {
    fn boot(store: Store) -> Sim {
        let controller = Controller::boot(INFO, store, LeverMode::RateAndAcceleration);
        let mut pipeline = Pipeline::new(INFO.sample_rate_hz);
        pipeline.apply(PipelineCommand::Compensator(controller.compensator()));
        Sim {
            service: LinkService::new(controller),
            pipeline,
            sensor: VirtualSensor::new(&paper_unit::calibration(), 1000, true).unwrap(),
            link: TestLink {
                rx: VecDeque::new(),
                tx: Vec::new(),
                budget: None,
            },
            resets: 0,
        }
    }

    fn new() -> Sim {
        Sim::boot(fresh_store())
    }

    fn send(&mut self, m: &HostToDevice) {
        let mut buf = [0u8; HOST_FRAME_MAX];
        let f = encode_frame(m, &mut buf).unwrap();
        self.link.rx.extend(f.iter().copied());
    }

    /// Runs `samples` samples, polling the link after each; handles board events like a board.
    fn run(&mut self, samples: u32) {
        for _ in 0..samples.max(1) {
            if samples > 0 {
                self.sensor.step(&mut self.pipeline);
            }
            if let Some(b) = self.link.budget.as_mut() {
                *b = 12;
            }
            // The board's lowest priority (idle loop): a calibration write's store.
            self.service.run_store_here(&mut self.pipeline);
            match self.service.poll(&mut self.link, &mut self.pipeline) {
                Some(BoardEvent::SetTable(t)) => self.sensor.set_table(&t).unwrap(),
                Some(BoardEvent::SetTemperature(t)) => self.sensor.set_temperature(t),
                Some(BoardEvent::Reset) => {
                    self.service.flush(&mut self.link, 1000);
                    self.reboot();
                }
                None => {}
            }
        }
        // Drain the receive side (and a store's answer) without sampling.
        while !self.link.rx.is_empty() || self.service.controller.store_pending() {
            self.run(0);
        }
    }

    /// A system reset: RAM state lost, the store (flash) kept; link bytes already sent are kept.
    fn reboot(&mut self) {
        let store = core::mem::replace(
            &mut self.service,
            LinkService::new(Controller::boot(INFO, fresh_store(), LeverMode::Off)),
        )
        .controller
        .into_store()
        .expect("no store job out at a reset");
        let link = core::mem::replace(
            &mut self.link,
            TestLink {
                rx: VecDeque::new(),
                tx: Vec::new(),
                budget: None,
            },
        );
        let resets = self.resets + 1;
        *self = Sim::boot(store);
        self.link = link;
        self.resets = resets;
    }

    fn request(&mut self, m: &HostToDevice) -> Vec<DeviceToHost> {
        self.send(m);
        self.run(0);
        self.take()
    }

    fn take(&mut self) -> Vec<DeviceToHost> {
        let bytes = core::mem::take(&mut self.link.tx);
        let mut out = Vec::new();
        for frame in bytes.split(|b| *b == 0).filter(|f| !f.is_empty()) {
            let mut f = frame.to_vec();
            out.push(decode_frame::<DeviceToHost>(&mut f).expect("device frames decode"));
        }
        out
    }

    fn identity(&mut self) -> Identity {
        match self.request(&HostToDevice::Identify).as_slice() {
            [DeviceToHost::Identity(i)] => *i,
            other => panic!("{other:?}"),
        }
    }

    fn write_blob(&mut self, blob: &[u8]) -> Vec<DeviceToHost> {
        let mut replies = Vec::new();
        for c in blob_chunks(blob) {
            replies.extend(self.request(&HostToDevice::WriteCalibration(c)));
        }
        replies
    }
}

fn blob_for(unit: UnitId, created: u64) -> Vec<u8> {
    let (buf, n) = ParameterBlob {
        unit_id: unit,
        calibration: paper_unit::calibration(),
        created_unix_s: created,
    }
    .to_bytes()
    .unwrap();
    buf[..n].to_vec()
}

fn last(replies: &[DeviceToHost]) -> DeviceToHost {
    *replies.last().expect("a reply")
}

#[test]
fn identify_reports_the_unit_and_a_missing_calibration() {
    let mut sim = Sim::new();
    let id = sim.identity();
    assert_eq!(id.unit_id, QEMU_UNIT_ID);
    assert_eq!(id.protocol_version, PROTOCOL_VERSION);
    assert_eq!(id.board, Board::QemuMps2An386);
    assert_eq!(id.calibration, CalibrationState::Missing);
    assert_eq!(id.sample_rate_hz, 1000);
}

fn compensated_window(sim: &mut Sim, n: u32) -> CompensatedWindow {
    sim.request(&HostToDevice::Stream(StreamRequest {
        kind: StreamKind::CompensatedWindows,
        window_samples: n,
    }));
    sim.run(n);
    let frames = sim.take();
    sim.request(&HostToDevice::StopStream);
    match frames.as_slice() {
        [DeviceToHost::CompensatedWindow(w)] => *w,
        other => panic!("{other:?}"),
    }
}

#[test]
fn write_read_back_compensate_and_survive_reset() {
    let mut sim = Sim::new();
    let table = VirtualTable {
        up_b: [1.0, 0.0, 0.0],
        rate_rad_s: 200f32.to_radians(),
        accel_rad_s2: 0.0,
    };
    assert_eq!(
        sim.request(&HostToDevice::SetVirtualTable(table)),
        [DeviceToHost::Ack(Ack::TableSet)]
    );
    // Uncalibrated: identity pass-through and the flag.
    let w = compensated_window(&mut sim, 100);
    assert!(w.flags.has(SampleFlags::UNCALIBRATED));

    let blob = blob_for(QEMU_UNIT_ID, 1_800_000_000);
    let replies = sim.write_blob(&blob);
    let n_chunks = blob.len().div_ceil(BLOB_CHUNK_LEN);
    assert_eq!(replies.len(), n_chunks);
    assert!(matches!(
        replies[0],
        DeviceToHost::Ack(Ack::ChunkReceived { received: 32 })
    ));
    assert_eq!(last(&replies), DeviceToHost::Ack(Ack::CalibrationStored));
    assert_eq!(
        sim.identity().calibration,
        CalibrationState::Valid {
            created_unix_s: 1_800_000_000
        }
    );

    // Calibrated, full lever compensation: back to (g, 0, 0) within the noise.
    let w = compensated_window(&mut sim, 500);
    assert_eq!(w.flags, SampleFlags(0));
    assert_eq!(w.count, 500);
    let g = 9.80665f32;
    assert!((w.mean_m_s2[0] - g).abs() < 2e-3, "{w:?}");
    assert!(
        w.mean_m_s2[1].abs() < 2e-3 && w.mean_m_s2[2].abs() < 2e-3,
        "{w:?}"
    );
    // Static only: the paper's ~11 mg centripetal error on y is back.
    sim.request(&HostToDevice::SetLeverMode(LeverMode::Off));
    let w = compensated_window(&mut sim, 500);
    assert!(
        (w.mean_m_s2[1].abs() / g * 1e3 - 11.19).abs() < 0.3,
        "{w:?}"
    );

    // Read back chunk by chunk.
    let mut back = Vec::new();
    while back.len() < blob.len() {
        match sim
            .request(&HostToDevice::ReadCalibration {
                offset: back.len() as u16,
            })
            .as_slice()
        {
            [DeviceToHost::CalibrationChunk(c)] => {
                assert_eq!(usize::from(c.total_len), blob.len());
                back.extend_from_slice(&c.data[..usize::from(c.len)]);
            }
            other => panic!("{other:?}"),
        }
    }
    assert_eq!(back, blob);
    assert_eq!(
        sim.request(&HostToDevice::ReadCalibration { offset: 9999 }),
        [DeviceToHost::Error(DeviceError::UnexpectedChunk)]
    );

    // Reset: answered, then the device boots again with the stored calibration.
    assert_eq!(
        sim.request(&HostToDevice::Reset),
        [DeviceToHost::Ack(Ack::Resetting)]
    );
    assert_eq!(sim.resets, 1);
    let id = sim.identity();
    assert_eq!(
        id.calibration,
        CalibrationState::Valid {
            created_unix_s: 1_800_000_000
        }
    );
    assert_eq!(id.lever_mode, LeverMode::RateAndAcceleration);
}

#[test]
fn foreign_corrupt_and_out_of_order_blobs_are_refused() {
    let mut sim = Sim::new();
    let good = blob_for(QEMU_UNIT_ID, 7);
    sim.write_blob(&good);
    let foreign = blob_for(UnitId(*b"SOMEONE-ELSE"), 8);
    assert_eq!(
        last(&sim.write_blob(&foreign)),
        DeviceToHost::Error(DeviceError::BlobRejected(BlobError::ForeignUnit))
    );
    let mut corrupt = blob_for(QEMU_UNIT_ID, 9);
    corrupt[40] ^= 0x10;
    assert_eq!(
        last(&sim.write_blob(&corrupt)),
        DeviceToHost::Error(DeviceError::BlobRejected(BlobError::CrcMismatch))
    );
    // The previous calibration stays in force.
    assert_eq!(
        sim.identity().calibration,
        CalibrationState::Valid { created_unix_s: 7 }
    );
    // Out of order: second chunk first.
    let chunks: Vec<_> = blob_chunks(&good).collect();
    assert_eq!(
        sim.request(&HostToDevice::WriteCalibration(chunks[1])),
        [DeviceToHost::Error(DeviceError::UnexpectedChunk)]
    );
    // A repeated chunk in the middle.
    sim.request(&HostToDevice::WriteCalibration(chunks[0]));
    assert_eq!(
        sim.request(&HostToDevice::WriteCalibration(
            chunks[0].clone_with_offset(0)
        )),
        [DeviceToHost::Ack(Ack::ChunkReceived { received: 32 })]
    );
    sim.request(&HostToDevice::WriteCalibration(chunks[1]));
    assert_eq!(
        sim.request(&HostToDevice::WriteCalibration(chunks[1])),
        [DeviceToHost::Error(DeviceError::UnexpectedChunk)]
    );
    // Oversized total.
    let mut big = chunks[0];
    big.total_len = (BLOB_MAX_LEN + 1) as u16;
    assert_eq!(
        sim.request(&HostToDevice::WriteCalibration(big)),
        [DeviceToHost::Error(DeviceError::BlobRejected(
            BlobError::BufferTooSmall
        ))]
    );
}

trait CloneWithOffset {
    fn clone_with_offset(&self, offset: u16) -> Self;
}
impl CloneWithOffset for BlobChunk {
    fn clone_with_offset(&self, offset: u16) -> Self {
        BlobChunk { offset, ..*self }
    }
}

#[test]
fn boot_with_a_foreign_or_invalid_stored_blob_runs_uncalibrated_with_the_flag() {
    for (bytes, why) in [
        (
            blob_for(UnitId(*b"SOMEONE-ELSE"), 1),
            BlobError::ForeignUnit,
        ),
        (std::vec![0x55u8; 100], BlobError::BadMagic),
    ] {
        // Put it in flash behind the protocol's back (as an old firmware or another tool might have).
        let mut store = fresh_store();
        store.store(&bytes).unwrap();
        let mut sim = Sim::boot(store);
        assert_eq!(sim.identity().calibration, CalibrationState::Rejected(why));
        sim.request(&HostToDevice::Stream(StreamRequest {
            kind: StreamKind::RawWindows,
            window_samples: 10,
        }));
        sim.run(30);
        let frames = sim.take();
        assert_eq!(frames.len(), 3);
        for f in frames {
            let DeviceToHost::RawWindow(w) = f else {
                panic!("{f:?}")
            };
            assert!(w.flags.has(SampleFlags::UNCALIBRATED));
        }
        // The rejected bytes can still be read for diagnosis.
        assert!(matches!(
            sim.request(&HostToDevice::ReadCalibration { offset: 0 })
                .as_slice(),
            [DeviceToHost::CalibrationChunk(_)]
        ));
    }
    // Nothing stored at all.
    let mut sim = Sim::new();
    assert_eq!(
        sim.request(&HostToDevice::ReadCalibration { offset: 0 }),
        [DeviceToHost::Error(DeviceError::NoCalibration)]
    );
}

struct FailingStore;
impl CalStore for FailingStore {
    fn load(&mut self, _: &mut [u8; BLOB_MAX_LEN]) -> Result<Option<usize>, StoreError> {
        Err(StoreError::Flash)
    }
    fn store(&mut self, _: &[u8]) -> Result<(), StoreError> {
        Err(StoreError::Flash)
    }
}

#[test]
fn storage_failure_is_reported_and_nothing_changes() {
    let mut c = Controller::boot(INFO, FailingStore, LeverMode::RateOnly);
    assert_eq!(c.calibration_state(), CalibrationState::Missing);
    let blob = blob_for(QEMU_UNIT_ID, 3);
    let mut last = None;
    for chunk in blob_chunks(&blob) {
        last = Some(c.handle(HostToDevice::WriteCalibration(chunk)));
    }
    // The handler only parks the write: no answer until its store job has run.
    assert_eq!(last.unwrap().reply, None);
    let mut job = c.take_store_job().unwrap();
    job.run();
    let o = c.finish_store(job).unwrap();
    assert_eq!(
        o.reply,
        Some(DeviceToHost::Error(DeviceError::StorageFailed))
    );
    assert_eq!(o.pipeline, None);
    assert_eq!(c.calibration_state(), CalibrationState::Missing);
    assert!(c.compensator().is_none());
}

/// A version 1 blob of the paper unit for the QEMU unit: a version 2 blob without sections is the
/// version 1 payload followed by two `None` bytes, so drop them and re-sign it under version 1.
fn version_1_blob() -> Vec<u8> {
    let v2 = blob_for(QEMU_UNIT_ID, 77);
    let n = v2.len() - 4 - 8 - 2;
    assert_eq!(&v2[8 + n..8 + n + 2], &[0, 0]);
    let mut v1 = v2[..8 + n].to_vec();
    v1[4..6].copy_from_slice(&1u16.to_le_bytes());
    v1[6..8].copy_from_slice(&(n as u16).to_le_bytes());
    let crc = crc::Crc::<u32>::new(&crc::CRC_32_ISO_HDLC).checksum(&v1);
    v1.extend_from_slice(&crc.to_le_bytes());
    v1
}

#[test]
fn a_version_1_blob_flashes_and_works_as_a_perfect_gyro() {
    let mut sim = Sim::new();
    assert_eq!(
        last(&sim.write_blob(&version_1_blob())),
        DeviceToHost::Ack(Ack::CalibrationStored)
    );
    assert_eq!(
        sim.identity().calibration,
        CalibrationState::Valid { created_unix_s: 77 }
    );
    sim.request(&HostToDevice::SetVirtualTable(VirtualTable {
        up_b: [1.0, 0.0, 0.0],
        rate_rad_s: 200f32.to_radians(),
        accel_rad_s2: 0.0,
    }));
    let w = compensated_window(&mut sim, 2000);
    // The perfect virtual gyro and a perfect-gyro calibration: back to (g, 0, 0) within noise.
    assert!((w.mean_m_s2[0] - 9.80665).abs() < 5e-4, "{w:?}");
    assert!(
        w.mean_m_s2[1].abs() < 5e-4 && w.mean_m_s2[2].abs() < 5e-4,
        "{w:?}"
    );
    assert!(
        (w.mean_rate_rad_s[0] - 200f32.to_radians()).abs() < 1e-3,
        "{w:?}"
    );
}

#[test]
fn heating_the_virtual_unit_shows_in_the_window_temperature() {
    let mut sim = Sim::new();
    assert_eq!(
        sim.request(&HostToDevice::SetVirtualTemperature { temp_c: 41.5 }),
        [DeviceToHost::Ack(Ack::TemperatureSet)]
    );
    assert_eq!(
        sim.request(&HostToDevice::Stream(StreamRequest {
            kind: StreamKind::RawWindows,
            window_samples: 500,
        })),
        [DeviceToHost::Ack(Ack::StreamStarted)]
    );
    sim.run(500);
    let windows: Vec<_> = sim
        .take()
        .into_iter()
        .filter_map(|m| match m {
            DeviceToHost::RawWindow(w) => Some(w),
            _ => None,
        })
        .collect();
    assert_eq!(windows.len(), 1);
    assert_eq!(windows[0].mean_temp_c, 41.5);
}

#[test]
fn bad_requests_get_typed_errors() {
    let mut sim = Sim::new();
    assert_eq!(
        sim.request(&HostToDevice::Stream(StreamRequest {
            kind: StreamKind::RawWindows,
            window_samples: 0
        })),
        [DeviceToHost::Error(DeviceError::BadWindow)]
    );
    assert_eq!(
        sim.request(&HostToDevice::SetVirtualTable(VirtualTable {
            up_b: [f32::NAN, 0.0, 1.0],
            rate_rad_s: 0.0,
            accel_rad_s2: 0.0
        })),
        [DeviceToHost::Error(DeviceError::Unsupported)]
    );
    let mut real = Controller::boot(
        DeviceInfo {
            virtual_table: false,
            output_unit: OutputUnit::Lsb,
            board: Board::Stm32f4,
            ..INFO
        },
        fresh_store(),
        LeverMode::RateOnly,
    );
    let o = real.handle(HostToDevice::SetVirtualTable(VirtualTable {
        up_b: [0.0, 0.0, 1.0],
        rate_rad_s: 0.0,
        accel_rad_s2: 0.0,
    }));
    assert_eq!(o.reply, Some(DeviceToHost::Error(DeviceError::Unsupported)));
    let o = real.handle(HostToDevice::SetVirtualTemperature { temp_c: 30.0 });
    assert_eq!(o.reply, Some(DeviceToHost::Error(DeviceError::Unsupported)));
    for temp_c in [f32::NAN, 1e9] {
        assert_eq!(
            sim.request(&HostToDevice::SetVirtualTemperature { temp_c }),
            [DeviceToHost::Error(DeviceError::Unsupported)]
        );
    }
    // Garbage, an over-long frame, and empty frames.
    sim.link.rx.extend([0x42, 0x42, 0x42, 0x00, 0x00, 0x00]);
    sim.link
        .rx
        .extend(std::iter::repeat_n(0x07, 3 * HOST_FRAME_MAX));
    sim.link.rx.push_back(0);
    sim.run(0);
    assert_eq!(
        sim.take(),
        [
            DeviceToHost::Error(DeviceError::MalformedFrame),
            DeviceToHost::Error(DeviceError::FrameTooLong)
        ]
    );
    assert_eq!(sim.identity().unit_id, QEMU_UNIT_ID);
}

#[test]
fn a_slow_link_drops_frames_not_samples_and_reports_it() {
    let mut sim = Sim::new();
    sim.request(&HostToDevice::Stream(StreamRequest {
        kind: StreamKind::RawWindows,
        window_samples: 1,
    }));
    // ~12 bytes per sample period against ~70-byte frames per sample.
    sim.link.budget = Some(12);
    sim.run(2000);
    sim.link.budget = None;
    sim.send(&HostToDevice::StopStream);
    sim.run(0);
    let frames: Vec<_> = sim
        .take()
        .into_iter()
        .filter_map(|f| match f {
            DeviceToHost::RawWindow(w) => Some(w),
            _ => None,
        })
        .collect();
    assert!(
        frames.len() > 100 && frames.len() < 1000,
        "{}",
        frames.len()
    );
    let last = frames.last().unwrap();
    // Every window was either delivered or counted as dropped (the count in the last delivered frame
    // cannot include drops after it).
    assert_eq!(sim.pipeline.dropped_frames() as usize + frames.len(), 2000);
    assert!(last.dropped_frames <= sim.pipeline.dropped_frames());
    assert_eq!(sim.pipeline.samples(), 2000);
    assert!(frames
        .iter()
        .any(|w| w.flags.has(SampleFlags::FRAMES_DROPPED)));
    // Window indices account for every sample: gaps equal the drops in between.
    for pair in frames.windows(2) {
        let gap = pair[1].first_sample - pair[0].first_sample - 1;
        assert_eq!(
            gap,
            u64::from(pair[1].dropped_frames - pair[0].dropped_frames)
        );
        assert_eq!(
            pair[1].flags.has(SampleFlags::FRAMES_DROPPED),
            gap > 0,
            "{pair:?}"
        );
    }
}

fn arb_message() -> impl Strategy<Value = HostToDevice> {
    prop_oneof![
        Just(HostToDevice::Identify),
        Just(HostToDevice::StopStream),
        Just(HostToDevice::Reset),
        (0u32..5000).prop_map(|n| HostToDevice::Stream(StreamRequest {
            kind: StreamKind::RawDecimated,
            window_samples: n
        })),
        (any::<u16>(), any::<u16>(), any::<u8>(), any::<[u8; 32]>()).prop_map(
            |(offset, total_len, len, data)| HostToDevice::WriteCalibration(BlobChunk {
                offset,
                total_len,
                len,
                data
            })
        ),
        any::<u16>().prop_map(|offset| HostToDevice::ReadCalibration { offset }),
        (any::<[f32; 3]>(), any::<f32>(), any::<f32>()).prop_map(|(up_b, r, a)| {
            HostToDevice::SetVirtualTable(VirtualTable {
                up_b,
                rate_rad_s: r,
                accel_rad_s2: a,
            })
        }),
        any::<f32>().prop_map(|temp_c| HostToDevice::SetVirtualTemperature { temp_c }),
    ]
}

proptest! {
    #![proptest_config(ProptestConfig { cases: 300, ..ProptestConfig::default() })]

    /// Random bytes: never a panic, every device frame decodes, and the device still answers.
    #[test]
    fn random_bytes_never_break_the_device(bytes in prop::collection::vec(any::<u8>(), 0..600)) {
        let mut sim = Sim::new();
        sim.request(&HostToDevice::Stream(StreamRequest { kind: StreamKind::RawWindows, window_samples: 5 }));
        sim.link.rx.extend(bytes.iter().copied());
        sim.run(50);
        sim.take();
        sim.link.rx.push_back(0); // terminate whatever partial frame is left
        sim.run(0);
        sim.take();
        prop_assert_eq!(sim.identity().unit_id, QEMU_UNIT_ID);
    }

    /// Every non-empty frame, valid, truncated or corrupted, gets exactly one answer.
    #[test]
    fn one_answer_per_frame(
        msgs in prop::collection::vec((arb_message(), 0usize..100, any::<u8>(), 0usize..100), 1..12)
    ) {
        let mut sim = Sim::new();
        let mut frames = 0;
        for (m, cut, flip, at) in msgs {
            let mut buf = [0u8; HOST_FRAME_MAX];
            let f = encode_frame(&m, &mut buf).unwrap();
            let mut body = f[..f.len() - 1].to_vec();
            // Truncate and/or corrupt some of them (never creating a zero inside a frame).
            if cut < body.len() && cut % 3 == 0 { body.truncate(cut.max(1)); }
            if flip != 0 && at < body.len() { body[at] ^= flip; if body[at] == 0 { body[at] = 1; } }
            sim.link.rx.extend(body.iter().copied());
            sim.link.rx.push_back(0);
            frames += 1;
            let before = sim.resets;
            sim.run(3);
            let replies = sim.take();
            // Stream frames are not answers (a corrupted byte may turn a raw stream into another kind).
            let stream_frame = |r: &&DeviceToHost| matches!(
                r,
                DeviceToHost::RawSample(_)
                    | DeviceToHost::CompensatedSample(_)
                    | DeviceToHost::RawWindow(_)
                    | DeviceToHost::CompensatedWindow(_)
            );
            prop_assert_eq!(replies.iter().filter(|r| !stream_frame(r)).count(), 1, "{:?} -> {:?}", m, replies);
            let _ = before;
        }
        prop_assert!(frames > 0);
        prop_assert_eq!(sim.identity().unit_id, QEMU_UNIT_ID);
    }
}
