//! The parameter blob written to the device's flash.
//!
//! Layout (all little-endian):
//!
//! ```text
//! offset 0   4 bytes  magic "ACAL"
//! offset 4   u16      format version (BLOB_FORMAT_VERSION)
//! offset 6   u16      payload length n
//! offset 8   n bytes  postcard payload
//! offset 8+n u32      CRC-32/ISO-HDLC of bytes 0..8+n
//! ```
//!
//! Payload versions:
//!
//! - **1**: unit id, the paper-form parameters (f64), lever arms, reference point, gravity, creation
//!   time. Still read: as a perfect gyro without a temperature model.
//! - **2** (written now): version 1's fields followed by two optional sections, each a postcard
//!   `Option` (one byte 0 when absent): the gyro correction (`G` row-major, bias in rad/s;
//!   docs/model.md §8) and the temperature model (reference, valid range, polynomial coefficients;
//!   docs/model.md §9).
//!
//! Decoding checks every layer (length, magic, version, CRC, postcard, then the physics: finite values,
//! scale factors away from zero, `K·A` and `G` invertible with sane condition numbers, plausible
//! gravity, lever arms, gyro bias and temperature model, and every value within the range of the
//! device's `f32` arithmetic) and returns a typed [`BlobError`] for each failure. It never panics on
//! any byte string (property-tested). [`decode_for_unit`] also refuses a blob made for another unit.

use crate::compensator::{Compensator, CompensatorError, LeverMode};
use crate::params::{
    Calibration, LeverArms, OutputUnit, ParamsError, ReferencePoint, StaticParams,
};
use crate::sensor_models::{GyroCorrection, TemperatureModel};
use crate::units::UnitId;
use postcard::experimental::max_size::MaxSize;
use serde::{Deserialize, Serialize};

/// First four bytes of every blob.
pub const BLOB_MAGIC: [u8; 4] = *b"ACAL";
/// Format version written. Bump when the payload changes; [`decode`] reads every version listed in
/// the module documentation and refuses any other.
pub const BLOB_FORMAT_VERSION: u16 = 2;
/// The first format version (no gyro, no temperature section), still read.
pub(crate) const BLOB_FORMAT_VERSION_V1: u16 = 1;
const HEADER_LEN: usize = 8;
const CRC_LEN: usize = 4;
/// Largest encoded blob, from the payload type's postcard bound.
pub const BLOB_MAX_LEN: usize = HEADER_LEN + PayloadV2::POSTCARD_MAX_SIZE + CRC_LEN;
/// Largest accepted |r_i| component, metres: no accelerometer unit is a metre across.
pub(crate) const MAX_LEVER_ARM_M: f64 = 1.0;

/// CRC-32/ISO-HDLC (zlib's and Ethernet's: reflected polynomial 0xEDB88320, initial value and final
/// XOR all ones), bit by bit: the blob's checksum, and the firmware store's. A table-driven form
/// needs a 1 KiB table, which the device's image cannot spare for a checksum of a few hundred
/// bytes computed at boot and on a calibration write.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Crc32(u32);

impl Default for Crc32 {
    fn default() -> Self {
        Self::new()
    }
}

impl Crc32 {
    /// Nothing checksummed yet.
    pub const fn new() -> Self {
        Crc32(!0)
    }

    /// Adds `bytes`.
    pub fn update(&mut self, bytes: &[u8]) {
        let mut c = self.0;
        for &b in bytes {
            c ^= u32::from(b);
            for _ in 0..8 {
                c = (c >> 1) ^ (0xEDB8_8320 & (c & 1).wrapping_neg());
            }
        }
        self.0 = c;
    }

    /// The CRC of the bytes added.
    pub const fn finish(self) -> u32 {
        !self.0
    }

    /// The CRC of `bytes`.
    pub fn checksum(bytes: &[u8]) -> u32 {
        let mut c = Self::new();
        c.update(bytes);
        c.finish()
    }
}

/// A calibration bound to one unit, as stored on the device.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct ParameterBlob {
    /// The unit this calibration was made for.
    pub unit_id: UnitId,
    /// The calibration.
    pub calibration: Calibration,
    /// When it was made, seconds since the Unix epoch (0 if unknown).
    pub created_unix_s: u64,
}

/// Why a blob was refused. Fieldless, so it also travels on the wire.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize, MaxSize)]
pub enum BlobError {
    /// Fewer bytes than a header and a CRC.
    TooShort,
    /// The first four bytes are not "ACAL": not a calibration blob (erased flash reads 0xFF…).
    BadMagic,
    /// A format version this build does not read.
    UnsupportedVersion,
    /// The payload length in the header disagrees with the byte count.
    LengthMismatch,
    /// The CRC does not match: the blob is corrupt.
    CrcMismatch,
    /// The payload does not decode.
    Malformed,
    /// A value is NaN or infinite.
    NonFinite,
    /// A scale factor is zero or negative, or a sensing direction is zero.
    DegenerateAxis,
    /// `K·A` is singular or badly conditioned.
    IllConditioned,
    /// Local gravity is implausible.
    BadGravity,
    /// A lever arm component exceeds `MAX_LEVER_ARM_M`.
    LeverArmOutOfRange,
    /// The blob was made for another unit.
    ForeignUnit,
    /// The output buffer is smaller than the blob.
    BufferTooSmall,
    /// The gyro correction is implausible (scale, condition, bias or non-finite values).
    BadGyro,
    /// The temperature model is implausible (range, scale over the range, non-finite values).
    BadTemperatureModel,
    /// A value is beyond the range the device computes with: its `f32` arithmetic (e.g. a bias
    /// of 1e300), or an installation angle beyond ±`crate::trig::MAX_ANGLE_DEG`.
    OutOfDeviceRange,
}

impl core::fmt::Display for BlobError {
    fn fmt(&self, f: &mut core::fmt::Formatter<'_>) -> core::fmt::Result {
        let s = match self {
            BlobError::TooShort => "too short to be a calibration blob",
            BlobError::BadMagic => "not a calibration blob (bad magic)",
            BlobError::UnsupportedVersion => "calibration blob of an unsupported format version",
            BlobError::LengthMismatch => "calibration blob length does not match its header",
            BlobError::CrcMismatch => "calibration blob is corrupt (CRC mismatch)",
            BlobError::Malformed => "calibration blob payload does not decode",
            BlobError::NonFinite => "calibration contains NaN or infinite values",
            BlobError::DegenerateAxis => {
                "calibration has a zero or negative scale factor (positive by convention: a \
                 reversed axis is an installation angle near 180°) or a zero sensing direction"
            }
            BlobError::IllConditioned => "calibration's K·A matrix is singular or ill-conditioned",
            BlobError::BadGravity => "calibration's local gravity is implausible",
            BlobError::LeverArmOutOfRange => "calibration's lever arms exceed 1 m",
            BlobError::ForeignUnit => "calibration was made for another unit",
            BlobError::BufferTooSmall => "buffer too small for the calibration blob",
            BlobError::BadGyro => "calibration's gyro correction is implausible",
            BlobError::BadTemperatureModel => "calibration's temperature model is implausible",
            BlobError::OutOfDeviceRange => {
                "calibration holds a value beyond the device's range (f32, installation angles)"
            }
        };
        f.write_str(s)
    }
}

/// Lets a host error name this one as its `source()`.
impl core::error::Error for BlobError {}

impl From<CompensatorError> for BlobError {
    fn from(e: CompensatorError) -> Self {
        match e {
            CompensatorError::Params(ParamsError::NonFinite) => BlobError::NonFinite,
            CompensatorError::Params(ParamsError::DegenerateAxis { .. }) => {
                BlobError::DegenerateAxis
            }
            CompensatorError::Params(ParamsError::AngleOutOfRange { .. }) => {
                BlobError::OutOfDeviceRange
            }
            CompensatorError::IllConditioned { .. } => BlobError::IllConditioned,
            CompensatorError::Gravity => BlobError::BadGravity,
            CompensatorError::Gyro(_) => BlobError::BadGyro,
            CompensatorError::Temperature(_) => BlobError::BadTemperatureModel,
            CompensatorError::OutOfDeviceRange => BlobError::OutOfDeviceRange,
        }
    }
}

/// The version 1 payload; plain arrays only (row-major), no nalgebra types.
#[derive(Serialize, Deserialize, MaxSize)]
struct Payload {
    unit_id: UnitId,
    output_unit: OutputUnit,
    zero_bias_out: [f64; 3],
    scale_out_per_g: [f64; 3],
    installation_angles_deg: [[f64; 3]; 3],
    lever_arms_m: [[f64; 3]; 3],
    reference: ReferencePoint,
    gravity_m_s2: f64,
    created_unix_s: u64,
}

/// The version 2 payload: version 1's fields (postcard writes a nested struct's fields in place), then
/// the optional sections.
#[derive(Serialize, Deserialize, MaxSize)]
struct PayloadV2 {
    v1: Payload,
    gyro: Option<GyroCorrection>,
    temperature: Option<TemperatureModel>,
}

impl ParameterBlob {
    /// Checks the physics: everything the compensator needs, plus plausible lever arms.
    pub fn validate(&self) -> Result<(), BlobError> {
        let cal = &self.calibration;
        if let ReferencePoint::BodyPoint { offset_m } = cal.reference {
            if !offset_m.iter().all(|v| v.is_finite()) {
                return Err(BlobError::NonFinite);
            }
        }
        Compensator::new(cal, LeverMode::RateAndAcceleration)?;
        if cal
            .lever_arms
            .r_m
            .iter()
            .flatten()
            .any(|v| v.abs() > MAX_LEVER_ARM_M)
        {
            return Err(BlobError::LeverArmOutOfRange);
        }
        if cal.statics.scale_out_per_g.iter().any(|k| *k <= 0.0) {
            return Err(BlobError::DegenerateAxis);
        }
        Ok(())
    }

    /// Encodes into `out`, returning the number of bytes written. Refuses an invalid calibration.
    pub fn encode(&self, out: &mut [u8]) -> Result<usize, BlobError> {
        self.validate()?;
        if out.len() < HEADER_LEN + CRC_LEN {
            return Err(BlobError::BufferTooSmall);
        }
        let cal = &self.calibration;
        let v1 = Payload {
            unit_id: self.unit_id,
            output_unit: cal.statics.output_unit,
            zero_bias_out: cal.statics.zero_bias_out,
            scale_out_per_g: cal.statics.scale_out_per_g,
            installation_angles_deg: cal.statics.installation_angles_deg,
            lever_arms_m: cal.lever_arms.r_m,
            reference: cal.reference,
            gravity_m_s2: cal.gravity_m_s2,
            created_unix_s: self.created_unix_s,
        };
        let payload = PayloadV2 {
            v1,
            gyro: cal.gyro,
            temperature: cal.temperature,
        };
        let body_end = out.len() - CRC_LEN;
        let n = postcard::to_slice(&payload, &mut out[HEADER_LEN..body_end])
            .map_err(|_| BlobError::BufferTooSmall)?
            .len();
        out[0..4].copy_from_slice(&BLOB_MAGIC);
        out[4..6].copy_from_slice(&BLOB_FORMAT_VERSION.to_le_bytes());
        out[6..8].copy_from_slice(&(n as u16).to_le_bytes());
        let crc = Crc32::checksum(&out[..HEADER_LEN + n]);
        out[HEADER_LEN + n..HEADER_LEN + n + CRC_LEN].copy_from_slice(&crc.to_le_bytes());
        Ok(HEADER_LEN + n + CRC_LEN)
    }

    /// Encodes into a fixed-size array (length in the second value).
    pub fn to_bytes(&self) -> Result<([u8; BLOB_MAX_LEN], usize), BlobError> {
        let mut buf = [0u8; BLOB_MAX_LEN];
        let n = self.encode(&mut buf)?;
        Ok((buf, n))
    }
}

/// Decodes and validates a blob of exactly `bytes.len()` bytes, for any unit.
pub fn decode(bytes: &[u8]) -> Result<ParameterBlob, BlobError> {
    if bytes.len() < HEADER_LEN + CRC_LEN {
        return Err(BlobError::TooShort);
    }
    if bytes[0..4] != BLOB_MAGIC {
        return Err(BlobError::BadMagic);
    }
    let version = u16::from_le_bytes([bytes[4], bytes[5]]);
    if version != BLOB_FORMAT_VERSION && version != BLOB_FORMAT_VERSION_V1 {
        return Err(BlobError::UnsupportedVersion);
    }
    let n = usize::from(u16::from_le_bytes([bytes[6], bytes[7]]));
    if bytes.len() != HEADER_LEN + n + CRC_LEN {
        return Err(BlobError::LengthMismatch);
    }
    let (body, crc_bytes) = bytes.split_at(HEADER_LEN + n);
    let stored = u32::from_le_bytes([crc_bytes[0], crc_bytes[1], crc_bytes[2], crc_bytes[3]]);
    if Crc32::checksum(body) != stored {
        return Err(BlobError::CrcMismatch);
    }
    let payload = &body[HEADER_LEN..];
    let (p, rest) = if version == BLOB_FORMAT_VERSION_V1 {
        let (v1, rest): (Payload, _) =
            postcard::take_from_bytes(payload).map_err(|_| BlobError::Malformed)?;
        let v2 = PayloadV2 {
            v1,
            gyro: None,
            temperature: None,
        };
        (v2, rest)
    } else {
        postcard::take_from_bytes::<PayloadV2>(payload).map_err(|_| BlobError::Malformed)?
    };
    if !rest.is_empty() {
        return Err(BlobError::Malformed);
    }
    let PayloadV2 {
        v1: p,
        gyro,
        temperature,
    } = p;
    let blob = ParameterBlob {
        unit_id: p.unit_id,
        calibration: Calibration {
            statics: StaticParams {
                output_unit: p.output_unit,
                zero_bias_out: p.zero_bias_out,
                scale_out_per_g: p.scale_out_per_g,
                installation_angles_deg: p.installation_angles_deg,
            },
            lever_arms: LeverArms {
                r_m: p.lever_arms_m,
            },
            reference: p.reference,
            gravity_m_s2: p.gravity_m_s2,
            gyro,
            temperature,
        },
        created_unix_s: p.created_unix_s,
    };
    blob.validate()?;
    Ok(blob)
}

/// Decodes, validates, and checks that the blob was made for `unit`.
pub fn decode_for_unit(bytes: &[u8], unit: UnitId) -> Result<ParameterBlob, BlobError> {
    let blob = decode(bytes)?;
    if blob.unit_id != unit {
        return Err(BlobError::ForeignUnit);
    }
    Ok(blob)
}

#[cfg(test)]
pub(crate) mod tests {
    use super::*;
    use crate::params::tests::paper_unit;
    use proptest::prelude::*;

    const UNIT: UnitId = UnitId([1, 2, 3, 4, 5, 6, 7, 8, 9, 10, 11, 12]);

    fn paper_blob() -> ParameterBlob {
        ParameterBlob {
            unit_id: UNIT,
            calibration: paper_unit(),
            created_unix_s: 1_790_000_000,
        }
    }

    #[test]
    fn round_trip_is_exact() {
        let (buf, n) = paper_blob().to_bytes().unwrap();
        assert!(n <= BLOB_MAX_LEN);
        assert_eq!(&buf[0..4], b"ACAL");
        assert_eq!(decode_for_unit(&buf[..n], UNIT).unwrap(), paper_blob());
    }

    #[test]
    fn each_layer_has_its_error() {
        let (buf, n) = paper_blob().to_bytes().unwrap();
        let good = &buf[..n];
        assert_eq!(decode(&good[..5]), Err(BlobError::TooShort));
        assert_eq!(decode(&[0xFF; 64]), Err(BlobError::BadMagic));
        let mut v = good.to_vec();
        v[4] = 3;
        assert_eq!(decode(&v), Err(BlobError::UnsupportedVersion));
        v[4] = 0;
        assert_eq!(decode(&v), Err(BlobError::UnsupportedVersion));
        assert_eq!(decode(&good[..n - 1]), Err(BlobError::LengthMismatch));
        let mut v = good.to_vec();
        v[20] ^= 0x40;
        assert_eq!(decode(&v), Err(BlobError::CrcMismatch));
        assert_eq!(
            decode_for_unit(good, UnitId([9; 12])),
            Err(BlobError::ForeignUnit)
        );
    }

    #[test]
    fn invalid_physics_is_refused_on_both_sides() {
        let mut b = paper_blob();
        b.calibration.statics.installation_angles_deg[2] =
            b.calibration.statics.installation_angles_deg[0];
        assert_eq!(
            b.encode(&mut [0; BLOB_MAX_LEN]),
            Err(BlobError::IllConditioned)
        );
        let mut b = paper_blob();
        b.calibration.lever_arms.r_m[0][0] = 2.0;
        assert_eq!(
            b.encode(&mut [0; BLOB_MAX_LEN]),
            Err(BlobError::LeverArmOutOfRange)
        );
        let mut b = paper_blob();
        b.calibration.statics.zero_bias_out[1] = f64::NAN;
        assert_eq!(b.encode(&mut [0; BLOB_MAX_LEN]), Err(BlobError::NonFinite));

        // A blob whose CRC is right but whose physics is wrong (written by a buggy or foreign tool)
        // is still refused on decode.
        let mut p = payload_of(&paper_blob());
        p.v1.scale_out_per_g[0] = 0.0;
        assert_eq!(decode(&resigned(&p)), Err(BlobError::DegenerateAxis));
    }

    mod v1 {
        include!("blob_v1_vectors.rs");
    }

    /// A gyro with 0.5 % scale errors, 0.5° misalignment and 0.5 °/s biases, and a temperature model.
    pub(crate) fn gyro_and_temperature() -> (GyroCorrection, TemperatureModel) {
        let m = 0.5f64.to_radians();
        let gyro = GyroCorrection {
            matrix: [[1.005, m, -m], [-m, 0.995, m], [m, -m, 1.004]],
            bias_rad_s: [
                0.5f64.to_radians(),
                -0.5f64.to_radians(),
                0.3f64.to_radians(),
            ],
        };
        let temperature = TemperatureModel {
            reference_c: 25.0,
            valid_range_c: [-20.0, 60.0],
            zero_bias_out_per_c: [
                [1.2e-4, 2e-7, 0.0],
                [-0.9e-4, 0.0, 0.0],
                [1e-4, -1e-7, 1e-9],
            ],
            scale_rel_per_c: [[150e-6, 0.0, 0.0], [-120e-6, 1e-7, 0.0], [100e-6, 0.0, 0.0]],
            gyro_bias_rad_s_per_c: Some([[1e-4, 0.0, 0.0], [0.0, -2e-4, 0.0], [5e-5, 1e-6, 0.0]]),
        };
        (gyro, temperature)
    }

    /// The bitwise CRC against the `crc` crate's table-driven CRC-32/ISO-HDLC: its check value,
    /// and random bytes split at random points (the incremental form).
    #[test]
    fn crc32_is_crc_32_iso_hdlc() {
        let table = crc::Crc::<u32>::new(&crc::CRC_32_ISO_HDLC);
        assert_eq!(Crc32::checksum(b"123456789"), 0xCBF4_3926);
        assert_eq!(Crc32::checksum(&[]), table.checksum(&[]));
        let mut state = 0x9E37_79B9u32;
        let mut bytes = [0u8; 700];
        for round in 0..200 {
            for b in bytes.iter_mut() {
                state ^= state << 13;
                state ^= state >> 17;
                state ^= state << 5;
                *b = state as u8;
            }
            let len = round * 3 + 1;
            let split = (state as usize) % len;
            let mut c = Crc32::new();
            c.update(&bytes[..split]);
            c.update(&bytes[split..len]);
            assert_eq!(c.finish(), table.checksum(&bytes[..len]), "{len} {split}");
        }
    }

    /// Re-signs `p` in place of the payload of a valid version 2 blob (a buggy or foreign writer).
    fn resigned(p: &PayloadV2) -> std::vec::Vec<u8> {
        let mut buf = [0u8; BLOB_MAX_LEN];
        let n = postcard::to_slice(p, &mut buf[HEADER_LEN..]).unwrap().len();
        buf[0..4].copy_from_slice(&BLOB_MAGIC);
        buf[4..6].copy_from_slice(&BLOB_FORMAT_VERSION.to_le_bytes());
        buf[6..8].copy_from_slice(&(n as u16).to_le_bytes());
        let crc = Crc32::checksum(&buf[..HEADER_LEN + n]);
        buf[HEADER_LEN + n..HEADER_LEN + n + 4].copy_from_slice(&crc.to_le_bytes());
        buf[..HEADER_LEN + n + CRC_LEN].to_vec()
    }

    fn payload_of(b: &ParameterBlob) -> PayloadV2 {
        let (buf, n) = b.to_bytes().unwrap();
        postcard::from_bytes(&buf[HEADER_LEN..n - CRC_LEN]).unwrap()
    }

    #[test]
    fn version_1_blobs_still_decode_as_a_perfect_gyro_without_temperature_model() {
        assert_eq!(u16::from_le_bytes([v1::V1_PAPER[4], v1::V1_PAPER[5]]), 1);
        let b = decode_for_unit(v1::V1_PAPER, UnitId(*b"V1-BLOB-UNIT")).unwrap();
        assert_eq!(b.calibration, crate::params::PAPER_UNIT);
        assert_eq!(b.calibration.gyro, None);
        assert_eq!(b.calibration.temperature, None);
        assert_eq!(b.created_unix_s, 1_790_000_000);
        let b2 = decode(v1::V1_LSB_BODY_POINT).unwrap();
        assert_eq!(b2.calibration.statics.output_unit, OutputUnit::Lsb);
        assert_eq!(
            b2.calibration.reference,
            ReferencePoint::BodyPoint {
                offset_m: [0.01, -0.02, 0.003]
            }
        );
        // Applied as a perfect gyro: the rate passes through bit for bit; nothing to refresh.
        let mut c = Compensator::new(&b.calibration, LeverMode::RateAndAcceleration).unwrap();
        let w = [0.3f32, -1.7, 2.5e-3];
        assert_eq!(c.correct_rate(&w).rad_s, w);
        assert_eq!(
            c.refresh(80.0),
            crate::compensator::TemperatureState::NotModelled
        );
        // Re-encoding writes version 2 and the content survives.
        let (buf, n) = b.to_bytes().unwrap();
        assert_eq!(u16::from_le_bytes([buf[4], buf[5]]), BLOB_FORMAT_VERSION);
        assert_eq!(
            n,
            v1::V1_PAPER.len() + 2,
            "two absent sections cost one byte each"
        );
        assert_eq!(decode(&buf[..n]).unwrap(), b);
        // A version 1 header on a version 2 payload (or the reverse) is refused, never misread.
        let mut v = v1::V1_PAPER.to_vec();
        v[4] = 2;
        assert_eq!(decode(&v), Err(BlobError::CrcMismatch));
    }

    #[test]
    fn gyro_and_temperature_sections_round_trip() {
        let (gyro, temperature) = gyro_and_temperature();
        let mut b = paper_blob();
        b.calibration.gyro = Some(gyro);
        b.calibration.temperature = Some(temperature);
        let (buf, n) = b.to_bytes().unwrap();
        assert!(n <= BLOB_MAX_LEN);
        assert_eq!(decode_for_unit(&buf[..n], UNIT).unwrap(), b);
        // Only the gyro, only the temperature model.
        for (g, t) in [(Some(gyro), None), (None, Some(temperature))] {
            b.calibration.gyro = g;
            b.calibration.temperature = t;
            let (buf, n) = b.to_bytes().unwrap();
            assert_eq!(decode(&buf[..n]).unwrap(), b);
        }
    }

    #[test]
    fn values_beyond_the_devices_f32_range_are_refused() {
        // The hostile tester's blob: CRC-valid, a zero bias of 1e300 (f64-finite, f32-infinite).
        let mut p = payload_of(&paper_blob());
        p.v1.zero_bias_out[1] = 1e300;
        assert_eq!(decode(&resigned(&p)), Err(BlobError::OutOfDeviceRange));
        // Scale factors so large that the lever-arm terms k·r/g overflow the device's range, while
        // K·A stays invertible: refused on both sides.
        let mut b = paper_blob();
        b.calibration.statics.scale_out_per_g = [1e24; 3];
        b.calibration.statics.zero_bias_out = [0.0; 3];
        assert_eq!(
            b.encode(&mut [0; BLOB_MAX_LEN]),
            Err(BlobError::OutOfDeviceRange)
        );
        // Scale factors so large that g·K_A would underflow f32's normal range (an axis would vanish).
        let mut b = paper_blob();
        b.calibration.statics.scale_out_per_g = [1e35; 3];
        b.calibration.statics.zero_bias_out = [0.0; 3];
        b.calibration.lever_arms = LeverArms::default();
        assert_eq!(
            b.encode(&mut [0; BLOB_MAX_LEN]),
            Err(BlobError::OutOfDeviceRange)
        );
        // A temperature polynomial whose f32 coefficients overflow.
        let (_, mut t) = gyro_and_temperature();
        t.zero_bias_out_per_c[0][2] = 1e39;
        let mut p = payload_of(&paper_blob());
        p.temperature = Some(t);
        assert_eq!(decode(&resigned(&p)), Err(BlobError::OutOfDeviceRange));
    }

    #[test]
    fn implausible_gyro_and_temperature_sections_are_refused() {
        let (gyro, temperature) = gyro_and_temperature();
        let mut p = payload_of(&paper_blob());
        let mut g = gyro;
        g.matrix[2] = g.matrix[0];
        p.gyro = Some(g);
        assert_eq!(decode(&resigned(&p)), Err(BlobError::BadGyro));
        let mut g = gyro;
        g.bias_rad_s[0] = f64::NAN;
        p.gyro = Some(g);
        assert_eq!(decode(&resigned(&p)), Err(BlobError::BadGyro));
        p.gyro = Some(gyro);
        let mut t = temperature;
        t.valid_range_c = [30.0, 20.0];
        p.temperature = Some(t);
        assert_eq!(decode(&resigned(&p)), Err(BlobError::BadTemperatureModel));
        // A gyro bias drift that exceeds the bias limit at the range's end.
        let mut t = temperature;
        t.gyro_bias_rad_s_per_c = Some([[0.05, 0.0, 0.0]; 3]);
        p.temperature = Some(t);
        assert_eq!(decode(&resigned(&p)), Err(BlobError::BadGyro));
    }

    proptest! {
        #![proptest_config(ProptestConfig { cases: 5000, ..ProptestConfig::default() })]

        /// Any byte string decodes to a typed result, never a panic.
        #[test]
        fn random_bytes_never_panic(bytes in prop::collection::vec(any::<u8>(), 0..400)) {
            let _ = decode(&bytes);
        }

        /// Random bytes behind a valid header (so decoding reaches the CRC and postcard layers).
        #[test]
        fn random_payloads_never_panic(bytes in prop::collection::vec(any::<u8>(), 0..700), v1 in any::<bool>()) {
            let mut v = std::vec::Vec::from(*b"ACAL");
            let version = if v1 { BLOB_FORMAT_VERSION_V1 } else { BLOB_FORMAT_VERSION };
            v.extend_from_slice(&version.to_le_bytes());
            v.extend_from_slice(&(bytes.len().saturating_sub(4) as u16).to_le_bytes());
            v.extend_from_slice(&bytes);
            let _ = decode(&v);
        }

        /// Every truncation and every single-byte corruption of a valid blob is refused.
        #[test]
        fn truncated_or_flipped_blobs_are_refused(cut in 0usize..700, at in 0usize..700, bit in 0u8..8) {
            let (gyro, temperature) = gyro_and_temperature();
            let mut b = paper_blob();
            b.calibration.gyro = Some(gyro);
            b.calibration.temperature = Some(temperature);
            let (buf, n) = b.to_bytes().unwrap();
            let cut = cut % n;
            prop_assert!(decode(&buf[..cut]).is_err());
            let mut v = buf[..n].to_vec();
            v[at % n] ^= 1 << bit;
            prop_assert!(decode(&v).is_err());
        }
    }
}
