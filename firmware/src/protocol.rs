//! The host link: frame reception, the request handler and the non-blocking link service.
//!
//! Frames are the shared wire types (`shared::wire`), postcard + COBS, zero-terminated. The receiver
//! ([`FrameReceiver`]) ignores empty frames, answers a frame longer than `HOST_FRAME_MAX` with one
//! `FrameTooLong` (after discarding up to the next zero) and a frame that does not decode with
//! `MalformedFrame`. Every decoded request gets exactly one answer ([`Controller::handle`]).
//!
//! The [`LinkService`] runs in the main loop: it reads a bounded number of bytes per call, answers
//! requests, and moves answers (first) and queued stream frames to the link only as fast as the link
//! accepts them. Nothing here waits for the link, and sampling never waits for any of it.

use heapless::Deque;
use shared::blob::{decode_for_unit, BlobError, BLOB_MAX_LEN};
use shared::compensator::{Compensator, LeverMode};
use shared::units::UnitId;
use shared::wire::{
    decode_frame, encode_frame, Ack, BlobChunk, Board, CalibrationState, DeviceError, DeviceToHost,
    HostToDevice, Identity, VirtualTable, BLOB_CHUNK_LEN, DEVICE_FRAME_MAX, HOST_FRAME_MAX,
    PROTOCOL_VERSION,
};
use shared::{Calibration, OutputUnit};

use crate::pipeline::{Pipeline, PipelineCommand, MAX_WINDOW_SAMPLES};
use crate::storage::CalStore;

mod store_job;
use crate::virtual_sensor::VirtualSensor;
use crate::{ByteLink, FIRMWARE_VERSION};
pub use store_job::{StoreJob, StoreMailbox};

/// What the request handler needs to know about the board.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct DeviceInfo {
    /// The unit's identifier (blobs for other units are refused).
    pub unit_id: UnitId,
    /// Which board.
    pub board: Board,
    /// Sampling rate, Hz.
    pub sample_rate_hz: u32,
    /// The board has a virtual table (`SetVirtualTable` is accepted).
    pub virtual_table: bool,
    /// What its raw outputs are measured in.
    pub output_unit: OutputUnit,
}

/// Something only the board can do.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum BoardEvent {
    /// Set the virtual table (already checked and normalised).
    SetTable(VirtualTable),
    /// Set the virtual unit's die temperature, °C (already checked).
    SetTemperature(f32),
    /// Restart the device after the pending answers are sent.
    Reset,
}

/// Result of one request.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Outcome {
    /// The answer to send; `None` while a calibration write waits for its store
    /// ([`Controller::take_store_job`]): the answer comes with [`Controller::finish_store`].
    pub reply: Option<DeviceToHost>,
    /// A change for the sampling pipeline.
    pub pipeline: Option<PipelineCommand>,
    /// A board action.
    pub board: Option<BoardEvent>,
}

impl Outcome {
    fn reply(reply: DeviceToHost) -> Self {
        Outcome {
            reply: Some(reply),
            pipeline: None,
            board: None,
        }
    }
    fn error(e: DeviceError) -> Self {
        Self::reply(DeviceToHost::Error(e))
    }
    fn ack(a: Ack) -> Self {
        Self::reply(DeviceToHost::Ack(a))
    }
}

/// A validated calibration whose store is under way ([`StoreJob`]).
struct Pending {
    calibration: Calibration,
    created_unix_s: u64,
}

/// The request handler: identity, calibration state and storage, lever mode, chunk assembly.
pub struct Controller<S> {
    info: DeviceInfo,
    /// `None` while a [`StoreJob`] holds it.
    store: Option<S>,
    /// A store handed out (or ready to be): its answer is owed.
    pending: Option<Pending>,
    /// The job ready to be taken by the board.
    job: Option<StoreJob<S>>,
    state: CalibrationState,
    calibration: Option<Calibration>,
    lever_mode: LeverMode,
    stored: [u8; BLOB_MAX_LEN],
    stored_len: usize,
    assembly: [u8; BLOB_MAX_LEN],
    assembly_len: usize,
    assembly_total: usize,
    /// What `Health` answers.
    #[cfg(feature = "health")]
    health: crate::health::HealthState,
}

impl<S: CalStore> Controller<S> {
    /// The health report's state (`crate::health`).
    #[cfg(feature = "health")]
    pub(crate) fn health_mut(&mut self) -> &mut crate::health::HealthState {
        &mut self.health
    }

    /// Loads and validates the stored calibration. An invalid, corrupt or foreign blob (or a storage
    /// error) leaves the device uncalibrated with the reason in [`Self::calibration_state`].
    #[inline(never)]
    pub fn boot(info: DeviceInfo, mut store: S, lever_mode: LeverMode) -> Self {
        let mut stored = [0u8; BLOB_MAX_LEN];
        let (stored_len, state, calibration) = match store.load(&mut stored) {
            Ok(Some(n)) => match decode_for_unit(&stored[..n], info.unit_id) {
                Ok(blob) => (
                    n,
                    CalibrationState::Valid {
                        created_unix_s: blob.created_unix_s,
                    },
                    Some(blob.calibration),
                ),
                Err(e) => {
                    warn_rejected(e);
                    (n, CalibrationState::Rejected(e), None)
                }
            },
            Ok(None) => {
                #[cfg(target_os = "none")]
                defmt::warn!("no calibration stored: running uncalibrated");
                (0, CalibrationState::Missing, None)
            }
            Err(_) => {
                #[cfg(target_os = "none")]
                defmt::warn!("calibration storage unreadable: running uncalibrated");
                (0, CalibrationState::Missing, None)
            }
        };
        Controller {
            info,
            store: Some(store),
            pending: None,
            job: None,
            state,
            calibration,
            lever_mode,
            stored,
            stored_len,
            assembly: [0; BLOB_MAX_LEN],
            assembly_len: 0,
            assembly_total: 0,
            #[cfg(feature = "health")]
            health: crate::health::HealthState::new(),
        }
    }

    /// The compensator for the current calibration and lever mode (`None`: uncalibrated).
    pub fn compensator(&self) -> Option<Compensator> {
        self.calibration
            .as_ref()
            .and_then(|c| Compensator::new(c, self.lever_mode).ok())
    }

    /// What the device holds as its calibration.
    pub fn calibration_state(&self) -> CalibrationState {
        self.state
    }

    /// The lever-arm mode in force.
    pub fn lever_mode(&self) -> LeverMode {
        self.lever_mode
    }

    /// The store (for tests and boards that inspect it); `None` while a store job holds it.
    pub fn store_mut(&mut self) -> Option<&mut S> {
        self.store.as_mut()
    }

    /// Gives the store back (to boot again from it); `None` while a store job holds it (the link
    /// reads no request, so no reset either, until the job is back).
    pub fn into_store(self) -> Option<S> {
        self.store
    }

    /// A calibration write waits for its store: its answer is owed.
    pub fn store_pending(&self) -> bool {
        self.pending.is_some()
    }

    /// The store job of a validated calibration write, for the board's lowest priority
    /// ([`StoreJob::run`]), then [`Self::finish_store`].
    pub fn take_store_job(&mut self) -> Option<StoreJob<S>> {
        self.job.take()
    }

    /// Takes a job back after [`StoreJob::run`]: the store returns, and on success the calibration
    /// is applied. Returns the write's answer (`None` for a job this controller did not hand out).
    #[inline(never)]
    pub fn finish_store(&mut self, job: StoreJob<S>) -> Option<Outcome> {
        let pending = self.pending.take()?;
        let StoreJob {
            store,
            blob,
            len,
            result,
        } = job;
        self.store = Some(store);
        if result != Some(Ok(())) {
            #[cfg(target_os = "none")]
            defmt::warn!("storing the calibration failed; the previous one stays in force");
            return Some(Outcome::error(DeviceError::StorageFailed));
        }
        self.stored[..len].copy_from_slice(&blob[..len]);
        self.stored_len = len;
        let compensator = Compensator::new(&pending.calibration, self.lever_mode).ok();
        self.calibration = Some(pending.calibration);
        self.state = CalibrationState::Valid {
            created_unix_s: pending.created_unix_s,
        };
        Some(Outcome {
            pipeline: Some(PipelineCommand::Compensator(compensator)),
            ..Outcome::ack(Ack::CalibrationStored)
        })
    }

    /// Answers one request.
    #[inline(never)]
    pub fn handle(&mut self, msg: HostToDevice) -> Outcome {
        match msg {
            HostToDevice::Identify => Outcome::reply(DeviceToHost::Identity(Identity {
                protocol_version: PROTOCOL_VERSION,
                firmware_version: FIRMWARE_VERSION,
                unit_id: self.info.unit_id,
                board: self.info.board,
                calibration: self.state,
                lever_mode: self.lever_mode,
                sample_rate_hz: self.info.sample_rate_hz,
                output_unit: self.info.output_unit,
            })),
            HostToDevice::Stream(req) => {
                if req.window_samples == 0 || req.window_samples > MAX_WINDOW_SAMPLES {
                    return Outcome::error(DeviceError::BadWindow);
                }
                Outcome {
                    pipeline: Some(PipelineCommand::Stream(req)),
                    ..Outcome::ack(Ack::StreamStarted)
                }
            }
            #[cfg(feature = "health")]
            HostToDevice::Health => Outcome::reply(DeviceToHost::Health(self.health.report())),
            HostToDevice::StopStream => Outcome {
                pipeline: Some(PipelineCommand::StopStream),
                ..Outcome::ack(Ack::StreamStopped)
            },
            HostToDevice::WriteCalibration(chunk) => self.write_chunk(&chunk),
            HostToDevice::ReadCalibration { offset } => {
                let off = usize::from(offset);
                if self.stored_len == 0 {
                    return Outcome::error(DeviceError::NoCalibration);
                }
                if off >= self.stored_len {
                    return Outcome::error(DeviceError::UnexpectedChunk);
                }
                let len = (self.stored_len - off).min(BLOB_CHUNK_LEN);
                let mut data = [0u8; BLOB_CHUNK_LEN];
                data[..len].copy_from_slice(&self.stored[off..off + len]);
                Outcome::reply(DeviceToHost::CalibrationChunk(BlobChunk {
                    offset,
                    total_len: self.stored_len as u16,
                    len: len as u8,
                    data,
                }))
            }
            HostToDevice::SetLeverMode(mode) => {
                self.lever_mode = mode;
                let pipeline = self
                    .calibration
                    .is_some()
                    .then(|| PipelineCommand::Compensator(self.compensator()));
                Outcome {
                    pipeline,
                    ..Outcome::ack(Ack::LeverModeSet)
                }
            }
            HostToDevice::SetVirtualTable(t) => {
                if !self.info.virtual_table {
                    return Outcome::error(DeviceError::Unsupported);
                }
                match VirtualSensor::check_table(&t) {
                    Ok(t) => Outcome {
                        board: Some(BoardEvent::SetTable(t)),
                        ..Outcome::ack(Ack::TableSet)
                    },
                    Err(_) => Outcome::error(DeviceError::Unsupported),
                }
            }
            HostToDevice::SetVirtualTemperature { temp_c } => {
                if !self.info.virtual_table {
                    return Outcome::error(DeviceError::Unsupported);
                }
                match VirtualSensor::check_temperature(temp_c) {
                    Ok(t) => Outcome {
                        board: Some(BoardEvent::SetTemperature(t)),
                        ..Outcome::ack(Ack::TemperatureSet)
                    },
                    Err(_) => Outcome::error(DeviceError::Unsupported),
                }
            }
            HostToDevice::Reset => Outcome {
                board: Some(BoardEvent::Reset),
                ..Outcome::ack(Ack::Resetting)
            },
        }
    }

    #[inline(never)]
    fn write_chunk(&mut self, c: &BlobChunk) -> Outcome {
        let (off, len, total) = (
            usize::from(c.offset),
            usize::from(c.len),
            usize::from(c.total_len),
        );
        if off == 0 {
            // A chunk at offset 0 always starts a new write.
            self.assembly_len = 0;
            self.assembly_total = total;
        }
        if total > BLOB_MAX_LEN {
            self.assembly_total = 0;
            return Outcome::error(DeviceError::BlobRejected(BlobError::BufferTooSmall));
        }
        let consistent = total > 0
            && len > 0
            && len <= BLOB_CHUNK_LEN
            && total == self.assembly_total
            && off == self.assembly_len
            && off + len <= total;
        if !consistent {
            self.assembly_len = 0;
            self.assembly_total = 0;
            return Outcome::error(DeviceError::UnexpectedChunk);
        }
        self.assembly[off..off + len].copy_from_slice(&c.data[..len]);
        self.assembly_len += len;
        if self.assembly_len < total {
            return Outcome::ack(Ack::ChunkReceived {
                received: self.assembly_len as u16,
            });
        }
        self.assembly_len = 0;
        self.assembly_total = 0;
        let blob = match decode_for_unit(&self.assembly[..total], self.info.unit_id) {
            Ok(b) => b,
            Err(e) => {
                warn_rejected(e);
                return Outcome::error(DeviceError::BlobRejected(e));
            }
        };
        if let Err(e) = Compensator::new(&blob.calibration, self.lever_mode) {
            return Outcome::error(DeviceError::BlobRejected(e.into()));
        }
        // The store is slow (a sector erase): it leaves this handler, which may run in the link's
        // interrupt, as a job for the board's lowest priority; the answer waits for it.
        let Some(store) = self.store.take() else {
            return Outcome::error(DeviceError::StorageFailed);
        };
        let mut job = StoreJob {
            store,
            blob: [0xFF; BLOB_MAX_LEN],
            len: total,
            result: None,
        };
        job.blob[..total].copy_from_slice(&self.assembly[..total]);
        self.job = Some(job);
        self.pending = Some(Pending {
            calibration: blob.calibration,
            created_unix_s: blob.created_unix_s,
        });
        Outcome {
            reply: None,
            pipeline: None,
            board: None,
        }
    }
}

fn warn_rejected(e: BlobError) {
    #[cfg(target_os = "none")]
    defmt::warn!(
        "calibration blob refused (BlobError #{=u8}): running uncalibrated",
        e as u8
    );
    let _ = e;
}

/// What a completed frame was.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Received {
    /// A request.
    Message(HostToDevice),
    /// A frame that could not be used, with the error to answer.
    Error(DeviceError),
}

/// Collects COBS frames byte by byte.
pub struct FrameReceiver {
    buf: [u8; HOST_FRAME_MAX],
    len: usize,
    overflow: bool,
}

impl Default for FrameReceiver {
    fn default() -> Self {
        Self::new()
    }
}

impl FrameReceiver {
    /// Empty.
    pub const fn new() -> Self {
        FrameReceiver {
            buf: [0; HOST_FRAME_MAX],
            len: 0,
            overflow: false,
        }
    }

    /// Feeds one byte; a zero completes a frame.
    pub fn push(&mut self, byte: u8) -> Option<Received> {
        if byte != 0 {
            if self.len < self.buf.len() {
                self.buf[self.len] = byte;
                self.len += 1;
            } else {
                self.overflow = true;
            }
            return None;
        }
        let (len, overflow) = (self.len, self.overflow);
        self.len = 0;
        self.overflow = false;
        if overflow {
            return Some(Received::Error(DeviceError::FrameTooLong));
        }
        if len == 0 {
            return None; // empty frame: line idle / resynchronisation
        }
        Some(match decode_frame::<HostToDevice>(&mut self.buf[..len]) {
            Ok(m) => Received::Message(m),
            Err(_) => Received::Error(DeviceError::MalformedFrame),
        })
    }
}

/// Encodes one frame at a time and hands its bytes to the link as it accepts them.
pub struct Transmitter {
    buf: [u8; DEVICE_FRAME_MAX],
    len: usize,
    pos: usize,
}

impl Default for Transmitter {
    fn default() -> Self {
        Self::new()
    }
}

impl Transmitter {
    /// Idle.
    pub const fn new() -> Self {
        Transmitter {
            buf: [0; DEVICE_FRAME_MAX],
            len: 0,
            pos: 0,
        }
    }

    /// Nothing left to send.
    pub fn is_idle(&self) -> bool {
        self.pos >= self.len
    }

    /// Encodes `msg` (the previous frame must be finished).
    #[inline(never)]
    pub fn load(&mut self, msg: &DeviceToHost) {
        self.pos = 0;
        self.len = encode_frame(msg, &mut self.buf).map_or(0, |f| f.len());
    }

    /// Sends as many bytes as the link takes; true when the frame is finished.
    pub fn pump<L: ByteLink>(&mut self, link: &mut L) -> bool {
        while self.pos < self.len {
            if !link.try_write(self.buf[self.pos]) {
                return false;
            }
            self.pos += 1;
        }
        true
    }
}

/// The main loop's access to the sampling pipeline (which a board may keep behind a critical section).
pub trait PipelineAccess {
    /// Applies a command.
    fn apply(&mut self, cmd: PipelineCommand);
    /// Takes the next queued output frame.
    fn pop_output(&mut self) -> Option<DeviceToHost>;
}

impl<const Q: usize> PipelineAccess for Pipeline<Q> {
    fn apply(&mut self, cmd: PipelineCommand) {
        Pipeline::apply(self, cmd)
    }
    fn pop_output(&mut self) -> Option<DeviceToHost> {
        Pipeline::pop_output(self)
    }
}

/// Answers waiting to be sent (requests are not read while it is full: back-pressure, not loss).
const REPLY_QUEUE: usize = 4;
/// Bytes read per [`LinkService::poll`] call, so that transmission keeps up.
const RX_BURST: usize = 64;

/// Receives requests and transmits answers and stream frames, never waiting for the link.
pub struct LinkService<S> {
    /// The request handler.
    pub controller: Controller<S>,
    rx: FrameReceiver,
    tx: Transmitter,
    replies: Deque<DeviceToHost, REPLY_QUEUE>,
}

impl<S: CalStore> LinkService<S> {
    /// Around a booted controller.
    pub fn new(controller: Controller<S>) -> Self {
        LinkService {
            controller,
            rx: FrameReceiver::new(),
            tx: Transmitter::new(),
            replies: Deque::new(),
        }
    }

    /// One round: read and answer requests, then send what the link accepts. Returns a board action
    /// (its answer is already queued; for [`BoardEvent::Reset`] call [`Self::flush`] first).
    pub fn poll<L: ByteLink, P: PipelineAccess>(
        &mut self,
        link: &mut L,
        pipeline: &mut P,
    ) -> Option<BoardEvent> {
        let mut event = None;
        for _ in 0..RX_BURST {
            // While a calibration write waits for its store, its answer is owed: no request is
            // read until it is sent (back-pressure, as for a full reply queue).
            if self.replies.is_full() || event.is_some() || self.controller.store_pending() {
                break;
            }
            let Some(byte) = link.try_read() else {
                break;
            };
            let reply = match self.rx.push(byte) {
                None => continue,
                Some(Received::Error(e)) => {
                    #[cfg(feature = "health")]
                    self.controller.count_frame_error();
                    DeviceToHost::Error(e)
                }
                Some(Received::Message(m)) => {
                    let o = self.controller.handle(m);
                    if let Some(c) = o.pipeline {
                        pipeline.apply(c);
                    }
                    event = o.board;
                    match o.reply {
                        Some(r) => r,
                        None => continue, // owed: sent by `finish_store`
                    }
                }
            };
            // Cannot fail: checked `is_full` above and one reply per frame.
            let _ = self.replies.push_back(reply);
        }
        self.transmit(link, pipeline);
        event
    }

    /// The store job of a calibration write that [`Self::poll`] validated, for the board's lowest
    /// priority: run it there ([`StoreJob::run`]) and hand it back with [`Self::finish_store`].
    pub fn take_store_job(&mut self) -> Option<StoreJob<S>> {
        self.controller.take_store_job()
    }

    /// Takes a store job back: applies the calibration when it was stored and queues the write's
    /// answer (sent by the next [`Self::poll`]).
    pub fn finish_store<P: PipelineAccess>(&mut self, job: StoreJob<S>, pipeline: &mut P) {
        if let Some(o) = self.controller.finish_store(job) {
            if let Some(c) = o.pipeline {
                pipeline.apply(c);
            }
            if let Some(r) = o.reply {
                // Room is left: the write's request was read only with a free slot, and nothing
                // was read after it.
                let _ = self.replies.push_back(r);
            }
        }
    }

    /// For a board whose link service already runs at its lowest priority (the QEMU board's main
    /// loop, the simulated device): runs a waiting store job here and now.
    pub fn run_store_here<P: PipelineAccess>(&mut self, pipeline: &mut P) {
        if let Some(mut job) = self.take_store_job() {
            job.run();
            self.finish_store(job, pipeline);
        }
    }

    fn transmit<L: ByteLink, P: PipelineAccess>(&mut self, link: &mut L, pipeline: &mut P) {
        loop {
            if self.tx.is_idle() {
                match self.replies.pop_front().or_else(|| pipeline.pop_output()) {
                    Some(m) => self.tx.load(&m),
                    None => return,
                }
            }
            if !self.tx.pump(link) {
                return;
            }
        }
    }

    /// Sends the pending answers (not stream frames), giving up after `max_spins` refused bytes.
    pub fn flush<L: ByteLink>(&mut self, link: &mut L, max_spins: u32) {
        let mut spins = 0;
        loop {
            if self.tx.is_idle() {
                match self.replies.pop_front() {
                    Some(m) => self.tx.load(&m),
                    None => return,
                }
            }
            if !self.tx.pump(link) {
                spins += 1;
                if spins > max_spins {
                    return;
                }
            }
        }
    }
}

#[cfg(test)]
mod store_tests;
#[cfg(test)]
mod tests;
