//! The device's health report (protocol version 4): what its inertial part is and how its start
//! went, the part's nominal sensitivity (so a host checks gravity in the device's own counts), and
//! the error counters since boot — what a board without a debug probe can tell about itself.
//!
//! Asked with [`super::HostToDevice::Health`], answered [`super::DeviceToHost::Health`]. Both were
//! appended to their enums, so a version 3 device answers the request `Error(MalformedFrame)` and
//! keeps running, and a version 3 host never sends it.

use postcard::experimental::max_size::MaxSize;
use serde::{Deserialize, Serialize};

/// The inertial part behind the samples.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize, MaxSize)]
pub enum ImuPart {
    /// An analog accelerometer triad on an ADC (no identity register).
    Analog,
    /// A simulated or virtual unit (the host's in-process device, QEMU's virtual sensor).
    Virtual,
    /// TDK InvenSense ICM-42688-P (WHO_AM_I 0x47).
    Icm42688P,
    /// ST LSM6DSO (WHO_AM_I 0x6C).
    Lsm6dso,
    /// Bosch BMI270 (CHIP_ID 0x24).
    Bmi270,
}

impl ImuPart {
    /// The identity register's value the part answers with (`None` for a part without one).
    pub const fn expected_id(self) -> Option<u8> {
        match self {
            ImuPart::Analog | ImuPart::Virtual => None,
            ImuPart::Icm42688P => Some(0x47),
            ImuPart::Lsm6dso => Some(0x6C),
            ImuPart::Bmi270 => Some(0x24),
        }
    }

    /// The accelerometer's noise density from the part's datasheet, µg/√Hz (`None` when not a
    /// datasheet part): ICM-42688-P 70 (DS-000347, accelerometer specifications), LSM6DSO 70
    /// (DS12140, high-performance mode), BMI270 160 (BST-BMI270-DS000, accelerometer output noise).
    pub const fn accel_noise_ug_per_sqrt_hz(self) -> Option<f32> {
        match self {
            ImuPart::Analog | ImuPart::Virtual => None,
            ImuPart::Icm42688P | ImuPart::Lsm6dso => Some(70.0),
            ImuPart::Bmi270 => Some(160.0),
        }
    }
}

/// How the part's start went.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize, MaxSize)]
pub enum ImuInit {
    /// Identified and configured; sampling.
    Ok,
    /// The identity register read another value (in [`ImuStatus::who_am_i`]).
    WrongDevice,
    /// The bus failed.
    BusError,
    /// The part's own start failed (BMI270: INTERNAL_STATUS not "init OK" after its configuration
    /// upload).
    ConfigRejected,
    /// The part answered but a configured register did not read back.
    RegisterMismatch,
    /// Nothing to start (analog or virtual unit).
    NotApplicable,
}

/// The part and its start.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize, MaxSize)]
pub struct ImuStatus {
    /// Which part the firmware drives.
    pub part: ImuPart,
    /// The identity register's last value read (0 when none).
    pub who_am_i: u8,
    /// The start's result.
    pub init: ImuInit,
}

/// Error counters since boot; each saturates at `u32::MAX`.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Serialize, Deserialize, MaxSize)]
pub struct ErrorCounters {
    /// FIFO reads out of step, flushed and resynchronised.
    pub fifo_resyncs: u32,
    /// Burst chains restarted after a stall (an interrupt or a DMA completion lost).
    pub stalls: u32,
    /// Re-initialisations after the periodic register check found a register changed.
    pub reinits: u32,
    /// Frames from the host that did not decode (a CRC or COBS error on the link).
    pub crc_errors: u32,
    /// Samples lost (FIFO overflow, flush, a stall), as counted by the part's time stamps.
    pub lost_samples: u32,
    /// Boots after an independent-watchdog reset.
    pub watchdog_resets: u32,
}

/// Answer to [`super::HostToDevice::Health`].
#[derive(Clone, Copy, Debug, PartialEq, Eq, Deserialize, MaxSize)]
pub struct Health {
    /// The part and its start.
    pub imu: ImuStatus,
    /// The accelerometer's nominal sensitivity at its configured range, counts per g, when the
    /// raw outputs are counts (0 otherwise: volts have no nominal scale).
    pub accel_lsb_per_g: u32,
    /// The error counters.
    pub counters: ErrorCounters,
}

/// The derived form's bytes (postcard: the fields in order — a struct's as its fields, an enum's
/// variant index and a `u32` as varints, a `u8` as itself), encoded by one loop into a buffer and
/// handed to the serializer as plain bytes, as `BlobChunk`'s data go: serde's derive inlines the
/// varint encoder once per field into the device's frame encoder (0.5 KiB of the QEMU image).
/// Checked against the derived deserializer (`wire::tests::health_bytes_are_the_derived_form`).
impl Serialize for Health {
    fn serialize<S: serde::Serializer>(&self, s: S) -> Result<S::Ok, S::Error> {
        use serde::ser::SerializeTuple;
        let c = &self.counters;
        let words = [
            self.imu.part as u32,
            self.imu.init as u32,
            self.accel_lsb_per_g,
            c.fifo_resyncs,
            c.stalls,
            c.reinits,
            c.crc_errors,
            c.lost_samples,
            c.watchdog_resets,
        ];
        // At most 5 bytes per varint, and WHO_AM_I.
        let mut buf = [0u8; 9 * 5 + 1];
        let mut n = 0;
        for (i, &w) in words.iter().enumerate() {
            let mut v = w;
            while v >= 0x80 {
                buf[n] = v as u8 | 0x80;
                v >>= 7;
                n += 1;
            }
            buf[n] = v as u8;
            n += 1;
            if i == 0 {
                buf[n] = self.imu.who_am_i;
                n += 1;
            }
        }
        let mut t = s.serialize_tuple(n)?;
        for b in &buf[..n] {
            t.serialize_element(b)?;
        }
        t.end()
    }
}
