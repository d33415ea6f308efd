//! Host↔device messages and their framing.
//!
//! Every frame is one postcard-serialised message, COBS-encoded and terminated by a zero byte
//! ([`encode_frame`]); a receiver collects bytes with postcard's [`CobsAccumulator`] (re-exported), which
//! resynchronises on the next zero after garbage. Message enums are named by direction
//! ([`HostToDevice`], [`DeviceToHost`]); all payloads are fixed-size, so the largest frame of each
//! direction is a constant computed from the types ([`HOST_FRAME_MAX`], [`DEVICE_FRAME_MAX`]).
//!
//! Vectors are plain `[f32; 3]` in body axes (or sensor axes for raw outputs), with the unit in the field
//! name; matrices never travel (the calibration goes as a [`crate::blob`] in [`BlobChunk`]s).
//!
//! A UART cannot carry every sample at 10 kHz, so the device accumulates windows of a length the host
//! chooses ([`StreamRequest::window_samples`]) and sends count, mean and variance; single decimated
//! samples are available too.

use crate::blob::BlobError;
use crate::compensator::LeverMode;
use crate::units::UnitId;
use postcard::experimental::max_size::MaxSize;
use serde::{de::DeserializeOwned, Deserialize, Serialize};

pub use postcard::accumulator::{CobsAccumulator, FeedResult};

/// Version of this protocol; a host refuses a device that speaks another (the [`Identity`] that
/// carries it keeps its layout across versions, so the refusal is always readable).
///
/// - 1: the first protocol.
/// - 2: windows carry the mean temperature (`mean_temp_c`); [`SampleFlags::TEMPERATURE`];
///   [`HostToDevice::SetVirtualTemperature`]; blob errors for the gyro, temperature and `f32` range.
/// - 3: [`Identity::output_unit`] (a board's raw outputs may be volts or counts), appended: a host
///   reads the version of an older device before the identity's new field.
/// - 4: [`HostToDevice::Health`] → [`DeviceToHost::Health`] (the part, its WHO_AM_I and start,
///   its nominal sensitivity, the error counters), both appended; everything of version 3 is
///   unchanged, so a host speaks to a version 3 device without the health report.
#[cfg(feature = "health")]
pub const PROTOCOL_VERSION: u16 = 4;
/// Version of this protocol: 3 without the `health` feature (the QEMU image).
#[cfg(not(feature = "health"))]
pub const PROTOCOL_VERSION: u16 = 3;
/// The oldest device version a host speaks to (it asks [`HostToDevice::Health`] only from 4 on).
pub const MIN_PROTOCOL_VERSION: u16 = 3;

#[cfg(feature = "health")]
mod health;
#[cfg(feature = "health")]
pub use health::{ErrorCounters, Health, ImuInit, ImuPart, ImuStatus};
/// Bytes of blob per [`BlobChunk`] (serde's array limit is 32).
pub const BLOB_CHUNK_LEN: usize = 32;

/// Bytes COBS needs for a message of at most `n` bytes, including the terminating zero.
pub const fn cobs_frame_len(n: usize) -> usize {
    n + n / 254 + 2
}
/// Largest frame the host sends.
pub const HOST_FRAME_MAX: usize = cobs_frame_len(HostToDevice::POSTCARD_MAX_SIZE);
/// Largest frame the device sends.
pub const DEVICE_FRAME_MAX: usize = cobs_frame_len(DeviceToHost::POSTCARD_MAX_SIZE);
// Small enough to size UART buffers with: checked at compile time.
const _: () = assert!(DEVICE_FRAME_MAX < 128 && HOST_FRAME_MAX < 128);

/// One piece of a parameter blob, for writing or reading it over a small-frame link.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize, MaxSize)]
pub struct BlobChunk {
    /// Byte offset of `data[0]` in the blob.
    pub offset: u16,
    /// Length of the whole blob.
    pub total_len: u16,
    /// Valid bytes in `data` (≤ [`BLOB_CHUNK_LEN`]).
    pub len: u8,
    /// Bytes `offset .. offset + len` of the blob; the rest is zero.
    #[serde(with = "chunk_bytes")]
    pub data: [u8; BLOB_CHUNK_LEN],
}

/// A chunk's bytes as serde's own `[u8; 32]` puts them (a tuple of 32 `u8`: postcard's 32 plain
/// bytes), by a loop: serde's array impls unroll one element call per byte with its error path,
/// 0.9 KiB to decode a chunk in the QEMU image. Same format (tested: `chunk_bytes_are_serdes`).
mod chunk_bytes {
    use super::BLOB_CHUNK_LEN;
    use serde::de::{Error, SeqAccess, Visitor};
    use serde::ser::SerializeTuple;
    use serde::{Deserializer, Serializer};

    pub fn serialize<S: Serializer>(data: &[u8; BLOB_CHUNK_LEN], s: S) -> Result<S::Ok, S::Error> {
        let mut t = s.serialize_tuple(BLOB_CHUNK_LEN)?;
        for b in data {
            t.serialize_element(b)?;
        }
        t.end()
    }

    struct Bytes;

    impl<'de> Visitor<'de> for Bytes {
        type Value = [u8; BLOB_CHUNK_LEN];

        fn expecting(&self, f: &mut core::fmt::Formatter) -> core::fmt::Result {
            f.write_str("a blob chunk's bytes")
        }

        fn visit_seq<A: SeqAccess<'de>>(self, mut seq: A) -> Result<Self::Value, A::Error> {
            let mut data = [0u8; BLOB_CHUNK_LEN];
            for (i, b) in data.iter_mut().enumerate() {
                *b = seq
                    .next_element()?
                    .ok_or_else(|| A::Error::invalid_length(i, &self))?;
            }
            Ok(data)
        }
    }

    pub fn deserialize<'de, D: Deserializer<'de>>(d: D) -> Result<[u8; BLOB_CHUNK_LEN], D::Error> {
        d.deserialize_tuple(BLOB_CHUNK_LEN, Bytes)
    }
}

/// What the device should stream.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize, MaxSize)]
pub enum StreamKind {
    /// [`RawWindow`]s: statistics of the uncompensated outputs and the gyro (for calibration).
    RawWindows,
    /// [`CompensatedWindow`]s: statistics of the compensated specific force (for verification).
    CompensatedWindows,
    /// One [`RawSample`] every `window_samples` samples.
    RawDecimated,
    /// One [`CompensatedSample`] every `window_samples` samples.
    CompensatedDecimated,
}

/// Start a stream.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize, MaxSize)]
pub struct StreamRequest {
    /// What to send.
    pub kind: StreamKind,
    /// Samples per window (or decimation factor), ≥ 1.
    pub window_samples: u32,
}

/// The state of the virtual rate table of a simulated or emulated device.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize, MaxSize)]
pub struct VirtualTable {
    /// "Up" in body axes (unit vector).
    pub up_b: [f32; 3],
    /// Table rate about the vertical, rad/s.
    pub rate_rad_s: f32,
    /// Table angular acceleration about the vertical, rad/s² (the rate ramps from `rate_rad_s`).
    pub accel_rad_s2: f32,
}

/// Messages from the host to the device.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize, MaxSize)]
pub enum HostToDevice {
    /// Ask for an [`Identity`].
    Identify,
    /// Start (or change) the stream.
    Stream(StreamRequest),
    /// Stop streaming.
    StopStream,
    /// One chunk of a new calibration blob; the device validates and stores the blob when the last
    /// chunk arrives (answering [`Ack::CalibrationStored`] or an error).
    WriteCalibration(BlobChunk),
    /// Ask for the chunk of the stored blob at this offset.
    ReadCalibration {
        /// Byte offset.
        offset: u16,
    },
    /// Choose which lever-arm terms the device applies.
    SetLeverMode(LeverMode),
    /// Set the virtual table (simulated and QEMU devices only).
    SetVirtualTable(VirtualTable),
    /// Restart the device (it reloads the calibration from storage).
    Reset,
    /// Heat or cool the virtual unit to this die temperature, °C (simulated and QEMU devices only);
    /// its temperature sensor follows with the board's thermal lag.
    SetVirtualTemperature {
        /// Die temperature, °C.
        temp_c: f32,
    },
    /// Ask for the [`Health`] report (version 4).
    #[cfg(feature = "health")]
    Health,
}

/// Which board the device is.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize, MaxSize)]
pub enum Board {
    /// The host's in-process simulated device.
    Simulated,
    /// The firmware on QEMU's mps2-an386 with its virtual sensor.
    QemuMps2An386,
    /// The firmware on an STM32F4 board with real sensors.
    Stm32f4,
    /// The host's in-process simulated device without a table, turned by a simulated hand.
    SimulatedHand,
}

/// What the device holds as its calibration.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize, MaxSize)]
pub enum CalibrationState {
    /// A valid calibration for this unit is applied.
    Valid {
        /// Its creation time, seconds since the Unix epoch.
        created_unix_s: u64,
    },
    /// No calibration stored: outputs are uncalibrated.
    Missing,
    /// A stored calibration was refused at boot for this reason: outputs are uncalibrated.
    Rejected(BlobError),
}

/// Answer to [`HostToDevice::Identify`].
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize, MaxSize)]
pub struct Identity {
    /// [`PROTOCOL_VERSION`] of the device.
    pub protocol_version: u16,
    /// Firmware version (major, minor, patch).
    pub firmware_version: [u8; 3],
    /// The unit's identifier.
    pub unit_id: UnitId,
    /// Which board.
    pub board: Board,
    /// Calibration status.
    pub calibration: CalibrationState,
    /// Lever-arm mode in force.
    pub lever_mode: LeverMode,
    /// Sampling rate of the accelerometers and gyro, Hz.
    pub sample_rate_hz: u32,
    /// What the raw outputs are measured in (the unit of `RawWindow::mean_raw` and of the
    /// calibration the device takes): volts for an ADC board, counts for a digital IMU.
    pub output_unit: crate::params::OutputUnit,
}

/// Per-frame status bits.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Serialize, Deserialize, MaxSize)]
pub struct SampleFlags(pub u8);

impl SampleFlags {
    /// No valid calibration: compensated values are raw outputs passed through the identity.
    pub const UNCALIBRATED: u8 = 1;
    /// At least one sample in the frame was saturated (at the ADC's or gyro's range limit).
    pub const SATURATED: u8 = 2;
    /// At least one sample was NaN/infinite and was left out of the statistics.
    pub const NON_FINITE: u8 = 4;
    /// Output frames were dropped since the previous frame (the link was too slow).
    pub const FRAMES_DROPPED: u8 = 8;
    /// Compensated frames only: the calibration's temperature model was not applied at the unit's
    /// actual temperature in this frame — outside the calibrated range (the nearest end was used),
    /// or no valid temperature reading yet (the reference values were used).
    pub const TEMPERATURE: u8 = 16;
    /// Samples were lost in this frame's span (a digital IMU's FIFO overflowed or was flushed):
    /// they count in `rejected`, and the sample indices still advance over them.
    pub const SAMPLES_LOST: u8 = 32;

    /// True when `bit` is set.
    pub fn has(self, bit: u8) -> bool {
        self.0 & bit != 0
    }
}

/// Statistics of a window of raw samples.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize, MaxSize)]
pub struct RawWindow {
    /// Index of the window's first sample since boot.
    pub first_sample: u64,
    /// Samples in the statistics (saturated and non-finite ones are left out).
    pub count: u32,
    /// Mean of the accelerometer outputs, sensor axes, output unit.
    pub mean_raw: [f32; 3],
    /// Variance of the outputs, output unit².
    pub var_raw: [f32; 3],
    /// Mean gyro rate, body axes, rad/s.
    pub mean_rate_rad_s: [f32; 3],
    /// Variance of the gyro rate, (rad/s)².
    pub var_rate_rad2_s2: [f32; 3],
    /// Mean of the unit's temperature readings during the window, °C (the latest reading when none
    /// fell in the window; NaN when the board has no temperature sensor).
    pub mean_temp_c: f32,
    /// Samples left out because saturated or non-finite.
    pub rejected: u32,
    /// Output frames dropped since boot.
    pub dropped_frames: u32,
    /// Status bits.
    pub flags: SampleFlags,
}

/// Statistics of a window of compensated samples.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize, MaxSize)]
pub struct CompensatedWindow {
    /// Index of the window's first sample since boot.
    pub first_sample: u64,
    /// Samples in the statistics.
    pub count: u32,
    /// Mean specific force at the reference point, body axes, m/s².
    pub mean_m_s2: [f32; 3],
    /// Its variance, (m/s²)².
    pub var_m2_s4: [f32; 3],
    /// Mean gyro rate, body axes, rad/s (corrected with the calibration's gyro model).
    pub mean_rate_rad_s: [f32; 3],
    /// Mean temperature, °C, as in [`RawWindow::mean_temp_c`].
    pub mean_temp_c: f32,
    /// Samples left out because saturated or non-finite.
    pub rejected: u32,
    /// Output frames dropped since boot.
    pub dropped_frames: u32,
    /// Status bits.
    pub flags: SampleFlags,
}

/// One raw sample.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize, MaxSize)]
pub struct RawSample {
    /// Sample index since boot.
    pub index: u64,
    /// Accelerometer outputs, sensor axes, output unit.
    pub raw: [f32; 3],
    /// Gyro rate, body axes, rad/s.
    pub rate_rad_s: [f32; 3],
    /// Status bits.
    pub flags: SampleFlags,
}

/// One compensated sample.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize, MaxSize)]
pub struct CompensatedSample {
    /// Sample index since boot.
    pub index: u64,
    /// Specific force at the reference point, body axes, m/s².
    pub specific_force_m_s2: [f32; 3],
    /// Gyro rate, body axes, rad/s (corrected with the calibration's gyro model).
    pub rate_rad_s: [f32; 3],
    /// Status bits.
    pub flags: SampleFlags,
}

/// Positive answers.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize, MaxSize)]
pub enum Ack {
    /// The stream started.
    StreamStarted,
    /// The stream stopped.
    StreamStopped,
    /// A calibration chunk was buffered; send the next one.
    ChunkReceived {
        /// Bytes of the blob received so far.
        received: u16,
    },
    /// The whole blob was validated and stored; it is applied from now on.
    CalibrationStored,
    /// The lever-arm mode was changed.
    LeverModeSet,
    /// The virtual table was set.
    TableSet,
    /// The device is about to restart.
    Resetting,
    /// The virtual unit's temperature was set.
    TemperatureSet,
}

/// Typed errors the device answers with. It keeps running after every one of them.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize, MaxSize)]
pub enum DeviceError {
    /// The frame did not decode (bad COBS, unknown message, wrong length).
    MalformedFrame,
    /// A frame longer than [`HOST_FRAME_MAX`] was discarded.
    FrameTooLong,
    /// A calibration chunk out of order or with an inconsistent length; the write restarts at offset 0.
    UnexpectedChunk,
    /// The assembled blob was refused; the previous calibration stays in force.
    BlobRejected(BlobError),
    /// Storage failed to write; the previous calibration stays in force.
    StorageFailed,
    /// No calibration is stored (answer to a read).
    NoCalibration,
    /// This board does not support the request (e.g. a virtual table on a real board).
    Unsupported,
    /// A window length of zero or beyond the device's limit.
    BadWindow,
}

/// Messages from the device to the host.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize, MaxSize)]
pub enum DeviceToHost {
    /// Answer to `Identify`.
    Identity(Identity),
    /// Streamed raw statistics.
    RawWindow(RawWindow),
    /// Streamed compensated statistics.
    CompensatedWindow(CompensatedWindow),
    /// Streamed raw sample.
    RawSample(RawSample),
    /// Streamed compensated sample.
    CompensatedSample(CompensatedSample),
    /// A chunk of the stored calibration blob.
    CalibrationChunk(BlobChunk),
    /// A positive answer.
    Ack(Ack),
    /// A typed error.
    Error(DeviceError),
    /// Answer to `Health` (version 4).
    #[cfg(feature = "health")]
    Health(Health),
}

impl core::fmt::Display for DeviceError {
    fn fmt(&self, f: &mut core::fmt::Formatter<'_>) -> core::fmt::Result {
        match self {
            DeviceError::MalformedFrame => f.write_str("device could not decode a frame"),
            DeviceError::FrameTooLong => f.write_str("device discarded an over-long frame"),
            DeviceError::UnexpectedChunk => f.write_str("calibration chunk out of order"),
            DeviceError::BlobRejected(e) => write!(f, "device refused the calibration: {e}"),
            DeviceError::StorageFailed => f.write_str("device failed to store the calibration"),
            DeviceError::NoCalibration => f.write_str("device holds no calibration"),
            DeviceError::Unsupported => f.write_str("request not supported by this board"),
            DeviceError::BadWindow => f.write_str("window length out of range"),
        }
    }
}

/// Lets a host error name this one as its `source()`.
impl core::error::Error for DeviceError {}

/// Why a frame could not be encoded or decoded.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum WireError {
    /// The buffer is smaller than the frame.
    BufferTooSmall,
    /// The bytes are not a valid frame of the expected message type.
    Malformed,
}

impl core::fmt::Display for WireError {
    fn fmt(&self, f: &mut core::fmt::Formatter<'_>) -> core::fmt::Result {
        match self {
            WireError::BufferTooSmall => f.write_str("frame buffer too small"),
            WireError::Malformed => f.write_str("malformed frame"),
        }
    }
}

/// Lets a host error name this one as its `source()`.
impl core::error::Error for WireError {}

/// Longest postcard encoding of a protocol message, either way, bytes.
const RAW_MAX: usize = if HostToDevice::POSTCARD_MAX_SIZE > DeviceToHost::POSTCARD_MAX_SIZE {
    HostToDevice::POSTCARD_MAX_SIZE
} else {
    DeviceToHost::POSTCARD_MAX_SIZE
};

/// Serialises `msg` (a protocol message, at most `RAW_MAX` bytes of postcard) as one COBS frame
/// ending in a zero byte; returns the used part of `buf`.
///
/// In two passes, postcard into a scratch buffer and then one COBS pass (`cobs_encode`), rather
/// than postcard's `to_slice_cobs`, whose COBS flavour was inlined at every byte each message
/// field pushes: 3.5 KiB of the QEMU image's frame encoder. The frame is the same, byte for byte
/// (tested against `to_slice_cobs`).
pub fn encode_frame<'a, T: Serialize>(
    msg: &T,
    buf: &'a mut [u8],
) -> Result<&'a mut [u8], WireError> {
    let mut raw = [0u8; RAW_MAX];
    let n = postcard::to_slice(msg, &mut raw)
        .map_err(|_| WireError::BufferTooSmall)?
        .len();
    let len = cobs_encode(&raw[..n], buf).ok_or(WireError::BufferTooSmall)?;
    *buf.get_mut(len).ok_or(WireError::BufferTooSmall)? = 0;
    Ok(&mut buf[..=len])
}

/// Consistent overhead byte stuffing (Cheshire and Baker, 1999) of `src` into `dst`, without the
/// terminating zero: each block is a code byte (1 + the non-zero bytes that follow, 0xFF for a
/// full block of 254 with no zero implied) and its bytes. Returns the length, `None` when `dst`
/// is too short. Out of line: one copy for every message.
#[inline(never)]
fn cobs_encode(src: &[u8], dst: &mut [u8]) -> Option<usize> {
    let (mut code_at, mut out, mut code) = (0usize, 1usize, 1u8);
    for &b in src {
        if b != 0 {
            *dst.get_mut(out)? = b;
            out += 1;
            code += 1;
        }
        if b == 0 || code == 0xFF {
            *dst.get_mut(code_at)? = code;
            code_at = out;
            out += 1;
            code = 1;
        }
    }
    *dst.get_mut(code_at)? = code;
    Some(out)
}

/// Decodes one COBS frame (with or without its terminating zero), in place.
pub fn decode_frame<T: DeserializeOwned>(frame: &mut [u8]) -> Result<T, WireError> {
    postcard::from_bytes_cobs(frame).map_err(|_| WireError::Malformed)
}

/// The protocol version of a `DeviceToHost::Identity` frame that does not decode as this version's
/// (a device of another protocol version, whose identity's later fields differ): every version's
/// identity starts with the variant's index and the version, so the host can still name the version
/// it refuses. `None` for any other frame.
pub fn identity_version_of(frame: &mut [u8]) -> Option<u16> {
    let (variant, version): (u32, u16) = decode_frame(frame).ok()?;
    (variant == IDENTITY_VARIANT).then_some(version)
}

/// Index of `DeviceToHost::Identity` among `DeviceToHost`'s variants (postcard's encoding of it).
const IDENTITY_VARIANT: u32 = 0;

/// Splits a blob into the chunks of a write.
pub fn blob_chunks(blob: &[u8]) -> impl Iterator<Item = BlobChunk> + '_ {
    let total_len = blob.len() as u16;
    blob.chunks(BLOB_CHUNK_LEN)
        .enumerate()
        .map(move |(i, part)| {
            let mut data = [0u8; BLOB_CHUNK_LEN];
            data[..part.len()].copy_from_slice(part);
            BlobChunk {
                offset: (i * BLOB_CHUNK_LEN) as u16,
                total_len,
                len: part.len() as u8,
                data,
            }
        })
}

#[cfg(test)]
mod tests {
    use super::*;
    use proptest::prelude::*;

    /// An identity of version 2 (no output unit) and one of this version: the version is read from
    /// either; a window frame is not an identity.
    #[test]
    fn the_version_of_another_versions_identity_is_readable() {
        let mut buf = [0u8; DEVICE_FRAME_MAX];
        let v2 = (
            IDENTITY_VARIANT,
            2u16,
            [0u8, 1, 0],
            UnitId(*b"OLD-DEVICE-1"),
            Board::Stm32f4,
            CalibrationState::Missing,
            LeverMode::Off,
            1000u32,
        );
        let frame = encode_frame(&v2, &mut buf).unwrap();
        assert!(decode_frame::<DeviceToHost>(&mut frame.to_vec()).is_err());
        assert_eq!(identity_version_of(frame), Some(2));
        let now = DeviceToHost::Identity(Identity {
            protocol_version: PROTOCOL_VERSION,
            firmware_version: [0, 1, 0],
            unit_id: UnitId(*b"NEW-DEVICE-1"),
            board: Board::Stm32f4,
            calibration: CalibrationState::Missing,
            lever_mode: LeverMode::Off,
            sample_rate_hz: 8000,
            output_unit: crate::OutputUnit::Lsb,
        });
        let frame = encode_frame(&now, &mut buf).unwrap();
        assert_eq!(identity_version_of(frame), Some(PROTOCOL_VERSION));
        let ack = DeviceToHost::Ack(Ack::StreamStopped);
        let frame = encode_frame(&ack, &mut buf).unwrap();
        assert_eq!(identity_version_of(frame), None);
    }

    #[cfg(feature = "health")]
    /// The hand-encoded `Health` decodes with the derived deserializer to itself, for every part
    /// and start, small and largest counters; and the message frame round-trips.
    #[test]
    fn health_bytes_are_the_derived_form() {
        let parts = [
            ImuPart::Analog,
            ImuPart::Virtual,
            ImuPart::Icm42688P,
            ImuPart::Lsm6dso,
            ImuPart::Bmi270,
        ];
        let inits = [
            ImuInit::Ok,
            ImuInit::WrongDevice,
            ImuInit::BusError,
            ImuInit::ConfigRejected,
            ImuInit::RegisterMismatch,
            ImuInit::NotApplicable,
        ];
        let values = [
            0u32,
            1,
            127,
            128,
            16_383,
            16_384,
            8192,
            u32::MAX - 1,
            u32::MAX,
        ];
        let mut k = 0usize;
        for part in parts {
            for init in inits {
                for (j, &v) in values.iter().enumerate() {
                    k += 1;
                    let w = |o: usize| values[(j + o) % values.len()];
                    let h = Health {
                        imu: ImuStatus {
                            part,
                            who_am_i: (k * 37) as u8,
                            init,
                        },
                        accel_lsb_per_g: v,
                        counters: ErrorCounters {
                            fifo_resyncs: w(1),
                            stalls: w(2),
                            reinits: w(3),
                            crc_errors: w(4),
                            lost_samples: w(5),
                            watchdog_resets: w(6),
                        },
                    };
                    let mut buf = [0u8; 64];
                    let bytes = postcard::to_slice(&h, &mut buf).unwrap();
                    assert!(bytes.len() <= Health::POSTCARD_MAX_SIZE);
                    let back: Health = postcard::from_bytes(bytes).unwrap();
                    assert_eq!(back, h);
                    let mut frame = [0u8; DEVICE_FRAME_MAX];
                    let f = encode_frame(&DeviceToHost::Health(h), &mut frame).unwrap();
                    let m: DeviceToHost = decode_frame(&mut f.to_vec()).unwrap();
                    assert_eq!(m, DeviceToHost::Health(h));
                }
            }
        }
    }

    fn sample_messages() -> std::vec::Vec<HostToDevice> {
        std::vec![
            HostToDevice::Identify,
            HostToDevice::Stream(StreamRequest {
                kind: StreamKind::RawWindows,
                window_samples: u32::MAX
            }),
            HostToDevice::WriteCalibration(BlobChunk {
                offset: u16::MAX,
                total_len: u16::MAX,
                len: 32,
                data: [0xFF; 32]
            }),
            HostToDevice::SetVirtualTable(VirtualTable {
                up_b: [f32::MAX; 3],
                rate_rad_s: -1.0,
                accel_rad_s2: f32::NAN
            }),
            HostToDevice::Reset,
        ]
    }

    #[test]
    fn frames_round_trip_and_fit_the_computed_bound() {
        let mut buf = [0u8; HOST_FRAME_MAX];
        for m in sample_messages() {
            let frame = encode_frame(&m, &mut buf).unwrap();
            assert!(frame.len() <= HOST_FRAME_MAX);
            assert_eq!(*frame.last().unwrap(), 0);
            let back: HostToDevice = decode_frame(frame).unwrap();
            // NaN != NaN: compare the re-encoding instead.
            assert_eq!(std::format!("{back:?}"), std::format!("{m:?}"));
        }
        let worst = DeviceToHost::RawWindow(RawWindow {
            first_sample: u64::MAX,
            count: u32::MAX,
            mean_raw: [1.0; 3],
            var_raw: [1.0; 3],
            mean_rate_rad_s: [1.0; 3],
            var_rate_rad2_s2: [1.0; 3],
            mean_temp_c: 1.0,
            rejected: u32::MAX,
            dropped_frames: u32::MAX,
            flags: SampleFlags(0xFF),
        });
        let mut dbuf = [0u8; DEVICE_FRAME_MAX];
        let n = encode_frame(&worst, &mut dbuf).unwrap().len();
        assert!(n <= DEVICE_FRAME_MAX, "{n} > {DEVICE_FRAME_MAX}");
    }

    fn plain<T: Serialize>(m: &T) -> std::vec::Vec<u8> {
        let mut buf = [0u8; 256];
        postcard::to_slice(m, &mut buf).unwrap().to_vec()
    }

    /// COBS by its definition (no run reaches 254 bytes here): each zero, and the start, becomes the
    /// distance to the next zero; a terminating zero ends the frame.
    fn cobs(data: &[u8]) -> std::vec::Vec<u8> {
        let mut out = std::vec::Vec::new();
        for run in data.split(|b| *b == 0) {
            assert!(run.len() < 254);
            out.push(run.len() as u8 + 1);
            out.extend_from_slice(run);
        }
        out.push(0);
        out
    }

    /// Version 2 frames byte for byte, written out by hand from postcard's format (variant index as a
    /// varint, integers as varints, f32 little-endian, fields in order), then COBS.
    #[test]
    fn version_2_window_and_temperature_frames_match_hand_encoded_vectors() {
        let w = DeviceToHost::RawWindow(RawWindow {
            first_sample: 300,
            count: 2,
            mean_raw: [1.0, 2.0, -1.0],
            var_raw: [0.5; 3],
            mean_rate_rad_s: [0.25, 0.0, 4.0],
            var_rate_rad2_s2: [1.0; 3],
            mean_temp_c: 25.5,
            rejected: 1,
            dropped_frames: 0,
            flags: SampleFlags(SampleFlags::TEMPERATURE),
        });
        let f = |v: f32| v.to_le_bytes();
        let mut payload = std::vec![0x01, 0xAC, 0x02, 0x02]; // RawWindow, 300, 2
        for v in [1.0, 2.0, -1.0, 0.5, 0.5, 0.5, 0.25, 0.0, 4.0, 1.0, 1.0, 1.0] {
            payload.extend_from_slice(&f(v));
        }
        assert_eq!(f(25.5), [0x00, 0x00, 0xCC, 0x41]);
        payload.extend_from_slice(&[0x00, 0x00, 0xCC, 0x41, 0x01, 0x00, 0x10]);
        assert_eq!(plain(&w), payload);
        let mut buf = [0u8; DEVICE_FRAME_MAX];
        let frame = encode_frame(&w, &mut buf).unwrap().to_vec();
        assert_eq!(frame, cobs(&payload));
        assert!(frame.len() <= DEVICE_FRAME_MAX);
        let mut back = frame.clone();
        assert_eq!(decode_frame::<DeviceToHost>(&mut back).unwrap(), w);

        // SetVirtualTemperature is HostToDevice variant 8: tag, then the f32.
        let m = HostToDevice::SetVirtualTemperature { temp_c: -20.0 };
        assert_eq!(plain(&m), [0x08, 0x00, 0x00, 0xA0, 0xC1]);
        // COBS of 08 00 00 A0 C1: each zero becomes the distance to the next one.
        let mut buf = [0u8; HOST_FRAME_MAX];
        assert_eq!(
            encode_frame(&m, &mut buf).unwrap(),
            [0x02, 0x08, 0x01, 0x03, 0xA0, 0xC1, 0x00]
        );
        assert_eq!(plain(&DeviceToHost::Ack(Ack::TemperatureSet)), [0x06, 0x07]);
    }

    #[test]
    fn accumulator_resynchronises_after_garbage() {
        let mut acc = CobsAccumulator::<{ HOST_FRAME_MAX }>::new();
        let mut buf = [0u8; HOST_FRAME_MAX];
        let frame = encode_frame(&HostToDevice::Identify, &mut buf)
            .unwrap()
            .to_vec();
        let mut stream = std::vec![0x55, 0x13, 0x00]; // garbage, then a terminator
        stream.extend_from_slice(&frame);
        let mut got = std::vec::Vec::new();
        let mut window: &[u8] = &stream;
        while !window.is_empty() {
            window = match acc.feed::<HostToDevice>(window) {
                FeedResult::Consumed => break,
                FeedResult::OverFull(rest) | FeedResult::DeserError(rest) => rest,
                FeedResult::Success { data, remaining } => {
                    got.push(data);
                    remaining
                }
            };
        }
        assert_eq!(got, std::vec![HostToDevice::Identify]);
    }

    #[test]
    fn blob_chunks_cover_the_blob() {
        let blob: std::vec::Vec<u8> = (0..100u8).collect();
        let chunks: std::vec::Vec<_> = blob_chunks(&blob).collect();
        assert_eq!(chunks.len(), 4);
        let mut again = std::vec::Vec::new();
        for c in &chunks {
            assert_eq!(usize::from(c.offset), again.len());
            again.extend_from_slice(&c.data[..usize::from(c.len)]);
        }
        assert_eq!(again, blob);
    }

    proptest! {
        /// The two-pass encoder gives postcard's own COBS frame, byte for byte, for any bytes
        /// (runs of zeros, runs of 254 and more non-zero bytes, the buffer's exact size).
        #[test]
        fn encode_frame_is_postcards_cobs(
            runs in prop::collection::vec((0usize..3, 0usize..600, any::<u8>()), 0..4),
            spare in 0usize..3,
        ) {
            // Runs of zeros and of non-zero bytes, some longer than a block's 254.
            let mut bytes = std::vec::Vec::new();
            for (zeros, len, seed) in runs {
                bytes.extend(core::iter::repeat_n(0u8, zeros));
                bytes.extend((0..len).map(|i| (i as u8).wrapping_add(seed).max(1)));
            }
            let mut want = std::vec![0u8; 2 * bytes.len() + 8];
            let want = postcard::to_slice_cobs(&Bytes(&bytes), &mut want).unwrap().to_vec();
            // The COBS pass alone over any length, and the whole encoder over a message's.
            let mut got = std::vec![0u8; want.len() + spare];
            let n = cobs_encode(&bytes, &mut got).unwrap();
            prop_assert_eq!(&got[..n], &want[..want.len() - 1]);
            prop_assert!(cobs_encode(&bytes, &mut got[..want.len() - 2]).is_none());
            if bytes.len() <= RAW_MAX {
                prop_assert_eq!(encode_frame(&Bytes(&bytes), &mut got).unwrap(), &want[..]);
                prop_assert!(encode_frame(&Bytes(&bytes), &mut got[..want.len() - 1]).is_err());
            }
        }
    }

    /// A chunk as `chunk_bytes` puts it and as serde's derive for `[u8; 32]` puts it: the same
    /// bytes, and each decodes the other's (and a short one is refused by both).
    #[test]
    fn chunk_bytes_are_serdes() {
        #[derive(Serialize, serde::Deserialize, Debug, PartialEq)]
        struct Plain {
            offset: u16,
            total_len: u16,
            len: u8,
            data: [u8; BLOB_CHUNK_LEN],
        }
        let data: [u8; BLOB_CHUNK_LEN] = core::array::from_fn(|i| (i * 37 % 256) as u8);
        let chunk = BlobChunk {
            offset: 300,
            total_len: 570,
            len: 32,
            data,
        };
        let plain = Plain {
            offset: 300,
            total_len: 570,
            len: 32,
            data,
        };
        let (mut a, mut b) = ([0u8; 64], [0u8; 64]);
        let a = postcard::to_slice(&chunk, &mut a).unwrap();
        let b = postcard::to_slice(&plain, &mut b).unwrap();
        assert_eq!(a, b);
        assert_eq!(postcard::from_bytes::<BlobChunk>(b).unwrap(), chunk);
        assert_eq!(postcard::from_bytes::<Plain>(a).unwrap(), plain);
        assert!(postcard::from_bytes::<BlobChunk>(&a[..a.len() - 1]).is_err());
    }

    /// Serialises as its bytes, one after another (a tuple).
    struct Bytes<'a>(&'a [u8]);
    impl Serialize for Bytes<'_> {
        fn serialize<S: serde::Serializer>(&self, s: S) -> Result<S::Ok, S::Error> {
            use serde::ser::SerializeTuple;
            let mut t = s.serialize_tuple(self.0.len())?;
            for b in self.0 {
                t.serialize_element(b)?;
            }
            t.end()
        }
    }

    proptest! {
        #![proptest_config(ProptestConfig { cases: 5000, ..ProptestConfig::default() })]
        /// Random and truncated frames decode to a typed error or a message, never a panic.
        #[test]
        fn random_frames_never_panic(mut bytes in prop::collection::vec(any::<u8>(), 0..200)) {
            let mut copy = bytes.clone();
            let _ = decode_frame::<HostToDevice>(&mut bytes);
            let _ = decode_frame::<DeviceToHost>(&mut copy);
        }

        #[test]
        fn truncated_frames_never_decode_to_garbage_silently(cut in 0usize..40) {
            let mut buf = [0u8; HOST_FRAME_MAX];
            let m = HostToDevice::Stream(StreamRequest { kind: StreamKind::CompensatedWindows, window_samples: 1000 });
            let frame = encode_frame(&m, &mut buf).unwrap();
            let n = frame.len();
            let cut = cut % (n - 1);
            let mut part = frame[..cut].to_vec();
            // A cut frame must either fail or (never) equal the original.
            if let Ok(back) = decode_frame::<HostToDevice>(&mut part) {
                prop_assert_ne!(back, m);
            }
        }
    }
}
