//! The host side of the protocol (`shared::wire`): request/response over any byte [`Transport`],
//! resynchronising on garbage, with a deadline on every wait so that a device that stops answering
//! becomes a [`LinkError::Timeout`] naming what was awaited — never a hang.

use shared::wire::{
    self, Ack, CobsAccumulator, DeviceError, DeviceToHost, FeedResult, HostToDevice, Identity,
    RawWindow, StreamKind, StreamRequest, VirtualTable, DEVICE_FRAME_MAX, HOST_FRAME_MAX,
    MIN_PROTOCOL_VERSION, PROTOCOL_VERSION,
};
use shared::LeverMode;
use std::collections::VecDeque;
use std::time::{Duration, Instant};

/// A byte link to a device: a serial port, a pty to QEMU, or the in-process simulated device.
pub trait Transport {
    /// Sends all of `bytes`.
    fn send(&mut self, bytes: &[u8]) -> Result<(), LinkError>;
    /// Reads what is available into `buf`, waiting at most `timeout`; `Ok(0)` when nothing came.
    fn receive(&mut self, buf: &mut [u8], timeout: Duration) -> Result<usize, LinkError>;
}

/// What went wrong on the link.
#[derive(Debug, thiserror::Error)]
pub enum LinkError {
    /// The port could not be opened or failed.
    #[error("{0}")]
    Io(String, #[source] std::io::Error),
    /// Nothing valid arrived in time.
    #[error(
        "the device stopped answering: waited {:.1} s for {waiting_for} and got nothing (check the cable, the port \
         name and that the firmware is running; power-cycle the board and retry)",
        .after.as_secs_f64()
    )]
    Timeout {
        /// What we were waiting for.
        waiting_for: &'static str,
        /// How long we waited.
        after: Duration,
    },
    /// The device answered with a typed error.
    #[error("the device refused")]
    Device(#[source] shared::wire::DeviceError),
    /// The device answered something that does not fit the request.
    #[error("protocol error: expected {waiting_for}, the device sent {got}")]
    Unexpected {
        /// What we were waiting for.
        waiting_for: &'static str,
        /// What came.
        got: String,
    },
    /// The device speaks another protocol version.
    #[error(
        "the device speaks protocol version {device}, this host speaks {PROTOCOL_VERSION}: \
         flash the matching firmware"
    )]
    ProtocolVersion {
        /// The device's version.
        device: u16,
    },
    /// A calibration read back from the device is incomplete or inconsistent.
    #[error("calibration read back from the device is bad: {0}")]
    BadReadBack(String),
}

/// A connected device.
pub struct DeviceClient<T: Transport> {
    transport: T,
    accumulator: Box<CobsAccumulator<{ 2 * DEVICE_FRAME_MAX }>>,
    /// Bytes received but not yet fed to the accumulator.
    unread: Vec<u8>,
    inbox: VecDeque<DeviceToHost>,
    timeout: Duration,
    /// Frames that did not decode (garbage on the line), since connecting.
    pub garbage_frames: u64,
    /// The version of an identity that did not decode: a device of another protocol version.
    foreign_version: Option<u16>,
    /// Who else sees each raw window (the live page).
    tap: Option<crate::view::Live>,
    /// Where every raw window is logged as well (a live hand-held session's `stream.csv`).
    window_log: Option<crate::window_log::WindowLog>,
}

impl<T: Transport> DeviceClient<T> {
    /// Wraps a transport; `timeout` bounds every wait for an answer.
    pub fn new(transport: T, timeout: Duration) -> Self {
        DeviceClient {
            transport,
            accumulator: Box::new(CobsAccumulator::new()),
            unread: Vec::new(),
            inbox: VecDeque::new(),
            timeout,
            garbage_frames: 0,
            foreign_version: None,
            tap: None,
            window_log: None,
        }
    }

    /// The transport (e.g. to inject faults in tests).
    pub fn transport_mut(&mut self) -> &mut T {
        &mut self.transport
    }

    /// Shows every raw window on the live page as well.
    pub fn set_view(&mut self, live: crate::view::Live) {
        self.tap = Some(live);
    }

    /// Logs every raw window from now on.
    pub(crate) fn log_windows(&mut self, log: crate::window_log::WindowLog) {
        self.window_log = Some(log);
    }

    /// Flushes the window log, if one is open.
    pub(crate) fn flush_window_log(&mut self) {
        if let Some(log) = self.window_log.as_mut() {
            log.flush();
        }
    }

    /// Closes the window log: where it is and its rows (`None` when none was open).
    pub(crate) fn finish_window_log(
        &mut self,
    ) -> Option<Result<(std::path::PathBuf, u64), crate::window_log::WindowLogError>> {
        self.window_log
            .take()
            .map(crate::window_log::WindowLog::finish)
    }

    /// The live page this client feeds, if any.
    pub fn view(&self) -> Option<&crate::view::Live> {
        self.tap.as_ref()
    }

    /// Changes the answer timeout.
    pub fn set_timeout(&mut self, timeout: Duration) {
        self.timeout = timeout;
    }

    /// Sends one message.
    pub fn send(&mut self, msg: &HostToDevice) -> Result<(), LinkError> {
        let mut buf = [0u8; HOST_FRAME_MAX];
        let frame = wire::encode_frame(msg, &mut buf).map_err(|_| LinkError::Unexpected {
            waiting_for: "an encodable message",
            got: format!("{msg:?}"),
        })?;
        self.transport.send(frame)
    }

    /// The next message from the device, waiting until `deadline`.
    pub(crate) fn next_message(
        &mut self,
        waiting_for: &'static str,
        wait: Duration,
    ) -> Result<DeviceToHost, LinkError> {
        let start = Instant::now();
        loop {
            if let Some(m) = self.inbox.pop_front() {
                return Ok(m);
            }
            self.drain_unread();
            if let Some(m) = self.inbox.pop_front() {
                return Ok(m);
            }
            let elapsed = start.elapsed();
            if elapsed >= wait {
                return Err(LinkError::Timeout {
                    waiting_for,
                    after: wait,
                });
            }
            let mut buf = [0u8; 4096];
            let n = self
                .transport
                .receive(&mut buf, (wait - elapsed).min(Duration::from_millis(200)))?;
            self.unread.extend_from_slice(&buf[..n]);
        }
    }

    fn drain_unread(&mut self) {
        let bytes = std::mem::take(&mut self.unread);
        let mut window: &[u8] = &bytes;
        while !window.is_empty() {
            window = match self.accumulator.feed::<DeviceToHost>(window) {
                FeedResult::Consumed => break,
                FeedResult::OverFull(rest) => {
                    self.garbage_frames += 1;
                    rest
                }
                FeedResult::DeserError(rest) => {
                    self.garbage_frames += 1;
                    // The frame just fed: an identity of another protocol version still names it.
                    let mut frame = window[..window.len() - rest.len()].to_vec();
                    if let Some(v) = wire::identity_version_of(&mut frame) {
                        self.foreign_version = Some(v);
                    }
                    rest
                }
                FeedResult::Success { data, remaining } => {
                    self.inbox.push_back(data);
                    remaining
                }
            };
        }
    }

    /// Sends `msg` and waits for the first answer that `pick` accepts, skipping stream frames.
    /// A device error is returned as [`LinkError::Device`].
    fn request<R>(
        &mut self,
        msg: &HostToDevice,
        waiting_for: &'static str,
        mut pick: impl FnMut(&DeviceToHost) -> Option<R>,
    ) -> Result<R, LinkError> {
        self.send(msg)?;
        let deadline = Instant::now() + self.timeout;
        loop {
            let left = deadline.saturating_duration_since(Instant::now());
            let m = self.next_message(waiting_for, left)?;
            if let Some(r) = pick(&m) {
                return Ok(r);
            }
            match m {
                // The answer to a garbled frame (line noise, or a request of ours that was corrupted):
                // not the answer to this request. Keep waiting; the deadline bounds it.
                DeviceToHost::Error(DeviceError::MalformedFrame | DeviceError::FrameTooLong) => {
                    self.garbage_frames += 1;
                    continue;
                }
                DeviceToHost::Error(e) => return Err(LinkError::Device(e)),
                // Stream frames, and answers to earlier requests that nobody waited for (a write
                // abandoned half-way, say): stale, not this request's answer.
                DeviceToHost::RawWindow(_)
                | DeviceToHost::CompensatedWindow(_)
                | DeviceToHost::RawSample(_)
                | DeviceToHost::CompensatedSample(_)
                | DeviceToHost::Ack(_)
                | DeviceToHost::Identity(_)
                | DeviceToHost::CalibrationChunk(_)
                | DeviceToHost::Health(_) => continue,
            }
        }
    }

    /// Asks who the device is; checks the protocol version. Retries a few times, because a device
    /// that just booted (or a QEMU pty that was just opened) may miss the first frame.
    pub fn identify(&mut self) -> Result<Identity, LinkError> {
        let mut last = None;
        self.foreign_version = None;
        for _ in 0..3 {
            let answer = self.request(&HostToDevice::Identify, "an identity", |m| match m {
                DeviceToHost::Identity(id) => Some(*id),
                _ => None,
            });
            // An identity that did not decode, of another version: that version is the answer.
            if let (Err(_), Some(device)) = (&answer, self.foreign_version) {
                return Err(LinkError::ProtocolVersion { device });
            }
            match answer {
                Ok(id)
                    if !(MIN_PROTOCOL_VERSION..=PROTOCOL_VERSION)
                        .contains(&id.protocol_version) =>
                {
                    return Err(LinkError::ProtocolVersion {
                        device: id.protocol_version,
                    })
                }
                Ok(id) => return Ok(id),
                Err(e @ LinkError::Timeout { .. }) => last = Some(e),
                Err(LinkError::Unexpected { .. }) => continue,
                Err(e) => return Err(e),
            }
        }
        Err(last.unwrap_or(LinkError::Timeout {
            waiting_for: "an identity",
            after: self.timeout,
        }))
    }

    fn expect_ack(
        &mut self,
        msg: &HostToDevice,
        waiting_for: &'static str,
        want: Ack,
    ) -> Result<(), LinkError> {
        self.request(msg, waiting_for, |m| match m {
            DeviceToHost::Ack(a) if *a == want => Some(()),
            _ => None,
        })
    }

    /// The device's health report: its part, WHO_AM_I and start, its nominal sensitivity and its
    /// error counters (protocol version 4; ask only a device whose identity says 4 or later).
    pub fn health(&mut self) -> Result<wire::Health, LinkError> {
        self.request(&HostToDevice::Health, "a health report", |m| match m {
            DeviceToHost::Health(h) => Some(*h),
            _ => None,
        })
    }

    /// Starts a stream of `kind` with `window_samples` per window.
    pub fn start_stream(&mut self, kind: StreamKind, window_samples: u32) -> Result<(), LinkError> {
        self.expect_ack(
            &HostToDevice::Stream(StreamRequest {
                kind,
                window_samples,
            }),
            "a stream acknowledgement",
            Ack::StreamStarted,
        )
    }

    /// Stops streaming and discards what was queued.
    pub fn stop_stream(&mut self) -> Result<(), LinkError> {
        self.expect_ack(
            &HostToDevice::StopStream,
            "a stop acknowledgement",
            Ack::StreamStopped,
        )?;
        self.inbox.clear();
        Ok(())
    }

    /// The next raw window of a running stream.
    pub fn next_raw_window(&mut self) -> Result<RawWindow, LinkError> {
        loop {
            match self.next_message("a raw window", self.timeout)? {
                DeviceToHost::RawWindow(w) => {
                    if let Some(live) = &self.tap {
                        live.window(&w);
                    }
                    if let Some(log) = self.window_log.as_mut() {
                        log.push(&w);
                    }
                    return Ok(w);
                }
                DeviceToHost::Error(e) => return Err(LinkError::Device(e)),
                _ => continue,
            }
        }
    }

    /// The next raw sample of a running `RawDecimated` stream.
    pub fn next_raw_sample(&mut self) -> Result<wire::RawSample, LinkError> {
        loop {
            match self.next_message("a raw sample", self.timeout)? {
                DeviceToHost::RawSample(s) => return Ok(s),
                DeviceToHost::Error(e) => return Err(LinkError::Device(e)),
                _ => continue,
            }
        }
    }

    /// The next compensated window of a running stream.
    pub fn next_compensated_window(&mut self) -> Result<wire::CompensatedWindow, LinkError> {
        loop {
            match self.next_message("a compensated window", self.timeout)? {
                DeviceToHost::CompensatedWindow(w) => return Ok(w),
                DeviceToHost::Error(e) => return Err(LinkError::Device(e)),
                _ => continue,
            }
        }
    }

    /// Sets the virtual table (simulated and QEMU devices).
    pub fn set_table(&mut self, table: VirtualTable) -> Result<(), LinkError> {
        self.expect_ack(
            &HostToDevice::SetVirtualTable(table),
            "a table acknowledgement",
            Ack::TableSet,
        )
    }

    /// Sets the virtual unit's die temperature, °C (simulated and QEMU devices): the chamber of a
    /// plan's soak segment.
    pub(crate) fn set_temperature(&mut self, temp_c: f32) -> Result<(), LinkError> {
        self.expect_ack(
            &HostToDevice::SetVirtualTemperature { temp_c },
            "a temperature acknowledgement",
            Ack::TemperatureSet,
        )
    }

    /// The same while a stream runs (a chamber ramp), without waiting: the acknowledgement arrives
    /// among the stream's windows, which [`Self::next_raw_window`] skips.
    pub(crate) fn send_temperature(&mut self, temp_c: f32) -> Result<(), LinkError> {
        self.send(&HostToDevice::SetVirtualTemperature { temp_c })
    }

    /// Chooses which lever-arm terms the device applies.
    pub fn set_lever_mode(&mut self, mode: LeverMode) -> Result<(), LinkError> {
        self.expect_ack(
            &HostToDevice::SetLeverMode(mode),
            "a lever-mode acknowledgement",
            Ack::LeverModeSet,
        )
    }

    /// Writes a calibration blob chunk by chunk; the device validates and stores it at the end.
    pub fn write_calibration(&mut self, blob: &[u8]) -> Result<(), LinkError> {
        let chunks: Vec<_> = wire::blob_chunks(blob).collect();
        let last = chunks.len().saturating_sub(1);
        for (i, chunk) in chunks.into_iter().enumerate() {
            let want_end = usize::from(chunk.offset) + usize::from(chunk.len);
            self.request(
                &HostToDevice::WriteCalibration(chunk),
                "a calibration-write answer",
                |m| match m {
                    DeviceToHost::Ack(Ack::CalibrationStored) if i == last => Some(()),
                    DeviceToHost::Ack(Ack::ChunkReceived { received })
                        if i != last && usize::from(*received) == want_end =>
                    {
                        Some(())
                    }
                    _ => None,
                },
            )?;
        }
        Ok(())
    }

    /// Reads the stored calibration blob.
    pub fn read_calibration(&mut self) -> Result<Vec<u8>, LinkError> {
        let mut blob = Vec::new();
        loop {
            let offset = blob.len() as u16;
            let chunk = self.request(
                &HostToDevice::ReadCalibration { offset },
                "a calibration chunk",
                |m| match m {
                    DeviceToHost::CalibrationChunk(c) => Some(*c),
                    _ => None,
                },
            )?;
            if chunk.offset != offset || usize::from(chunk.len) > wire::BLOB_CHUNK_LEN {
                return Err(LinkError::BadReadBack(format!(
                    "asked for offset {offset}, got offset {} length {}",
                    chunk.offset, chunk.len
                )));
            }
            blob.extend_from_slice(&chunk.data[..usize::from(chunk.len)]);
            if blob.len() >= usize::from(chunk.total_len) || chunk.len == 0 {
                blob.truncate(usize::from(chunk.total_len));
                return Ok(blob);
            }
        }
    }

    /// Restarts the device and waits until it identifies again.
    pub fn reset(&mut self) -> Result<Identity, LinkError> {
        self.expect_ack(
            &HostToDevice::Reset,
            "a reset acknowledgement",
            Ack::Resetting,
        )?;
        self.inbox.clear();
        self.unread.clear();
        *self.accumulator = CobsAccumulator::new();
        self.identify()
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A device that answers every request with `reply`.
    struct Replies {
        reply: Vec<u8>,
        pending: Vec<u8>,
    }

    impl Transport for Replies {
        fn send(&mut self, _: &[u8]) -> Result<(), LinkError> {
            self.pending.extend_from_slice(&self.reply);
            Ok(())
        }
        fn receive(&mut self, buf: &mut [u8], _: Duration) -> Result<usize, LinkError> {
            let n = buf.len().min(self.pending.len());
            buf[..n].copy_from_slice(&self.pending[..n]);
            self.pending.drain(..n);
            Ok(n)
        }
    }

    fn client_answering<M: serde::Serialize>(reply: &M) -> DeviceClient<Replies> {
        let mut buf = [0u8; DEVICE_FRAME_MAX];
        let frame = wire::encode_frame(reply, &mut buf).unwrap().to_vec();
        let t = Replies {
            reply: frame,
            pending: Vec::new(),
        };
        DeviceClient::new(t, Duration::from_millis(50))
    }

    /// The simulated device's identity (the firmware's own answer), as of protocol `version`.
    fn identity(version: u16) -> Identity {
        let truth = estimator::unit_file::UnitFile::paper_unit()
            .to_calibration()
            .unwrap();
        let device = super::super::sim::SimDevice::new(truth).unwrap();
        let id = DeviceClient::new(device, Duration::from_millis(50))
            .identify()
            .unwrap();
        Identity {
            protocol_version: version,
            ..id
        }
    }

    #[test]
    fn a_device_of_another_version_is_refused_by_its_version() {
        // Same layout, another version.
        let mut c = client_answering(&DeviceToHost::Identity(identity(PROTOCOL_VERSION + 1)));
        let e = c.identify().unwrap_err();
        assert!(
            matches!(e, LinkError::ProtocolVersion { device } if device == PROTOCOL_VERSION + 1),
            "{e}"
        );
        // Version 2's identity had no output unit: it does not decode, and its version is named.
        let id = identity(2);
        let v2 = (
            0u32, // the Identity variant
            id.protocol_version,
            id.firmware_version,
            id.unit_id,
            id.board,
            id.calibration,
            id.lever_mode,
            id.sample_rate_hz,
        );
        let mut c = client_answering(&v2);
        let e = c.identify().unwrap_err();
        assert!(matches!(e, LinkError::ProtocolVersion { device: 2 }), "{e}");
        assert!(e.to_string().contains("protocol version 2"), "{e}");
        // This version's identity is taken.
        let mut c = client_answering(&DeviceToHost::Identity(identity(PROTOCOL_VERSION)));
        assert_eq!(c.identify().unwrap(), identity(PROTOCOL_VERSION));
        // Version 3 (no health report, otherwise the same messages) is taken too.
        assert_eq!(MIN_PROTOCOL_VERSION, 3);
        let mut c = client_answering(&DeviceToHost::Identity(identity(3)));
        assert_eq!(c.identify().unwrap(), identity(3));
    }
}
