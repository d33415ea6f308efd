//! The vehicle's own parameters as its log carries them (ArduPilot's `PARM` messages, PX4's ULog
//! parameter messages) and the device ids of PX4's sensor topics: what a log's IMU stream already
//! went through (`super::ardupilot`), and which calibration slot a sensor holds.
//!
//! The slots follow the autopilots' own lookup. PX4 (`PX4/PX4-Autopilot`
//! `src/lib/sensor_calibration/Utilities.cpp`): `FindCurrentCalibrationIndex` takes the first of
//! the four `CAL_ACCn_ID` equal to the sensor's device id; without one, `FindAvailableCalibrationIndex`
//! takes the preferred index (the sensor's instance) when its `CAL_ACCn_ID` is 0, else the first
//! slot whose id is 0. ArduPilot (`libraries/AP_InertialSensor/AP_InertialSensor.cpp`,
//! `register_accel`) keeps one slot per accelerometer instance: `INS_ACC_ID`, `INS_ACC2_ID`,
//! `INS_ACC3_ID` hold the ids of instances 0, 1 and 2.

use super::keep::{Keep, PassReport};
use super::{dataflash, ulog, LogError, LogFormat};
use std::collections::BTreeMap;
use std::io::{BufRead, BufReader};
use std::path::Path;
use std::sync::{Arc, Mutex};

/// Most parameters kept: ArduPilot and PX4 have about 1500; a log claiming more is damaged.
const MAX_PARAMS: usize = 16_384;

/// PX4's calibration slots per sensor kind (`Utilities.cpp`, `MAX_SENSOR_COUNT`).
pub const PX4_SLOTS: u8 = 4;
/// ArduPilot's calibration slots (`INS_ACC_ID`, `INS_ACC2_ID`, `INS_ACC3_ID`).
pub const ARDUPILOT_SLOTS: u8 = 3;

/// The two sensors a slot is for.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum SensorKind {
    /// The accelerometer.
    Accel,
    /// The gyro.
    Gyro,
}

/// A log's parameters, as first logged, and what changed later.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct VehicleParams {
    values: BTreeMap<String, f64>,
    changed: BTreeMap<String, f64>,
    /// PX4: `sensor_accel.device_id` per instance (`multi_id`).
    pub accel_ids: BTreeMap<u8, u32>,
    /// PX4: `sensor_gyro.device_id` per instance.
    pub gyro_ids: BTreeMap<u8, u32>,
    /// Parameters left out beyond `MAX_PARAMS`.
    pub left_out: usize,
}

/// A sensor's device id and the calibration slot it takes.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct SensorSlot {
    /// The device id.
    pub device_id: u32,
    /// The slot (PX4's `n` of `CAL_ACCn_*`; ArduPilot's instance: INS_ACC*, INS_ACC2*, INS_ACC3*).
    pub slot: u8,
}

/// Why a log gives no id or slot for a sensor; each says what to give instead.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum SlotError {
    /// PX4: the log has no device id for the sensor's instance.
    #[error(
        "the log has no {topic} message of instance {instance} (its device_id): give the id \
         with --device-id (`listener {topic}` on the console shows it)"
    )]
    NoDeviceId {
        /// `sensor_accel` or `sensor_gyro`.
        topic: &'static str,
        /// The instance.
        instance: u8,
    },
    /// The id parameter is absent or 0.
    #[error(
        "the log's parameters have no {name} (or it is 0: no sensor there): give the id with \
         --device-id and the slot with --slot"
    )]
    NoId {
        /// The parameter.
        name: String,
    },
    /// PX4: every slot holds another sensor's id.
    #[error(
        "device id {device_id} is in none of {prefix}0_ID..{prefix}3_ID and none is free ({ids}): \
         give the slot to replace with --slot"
    )]
    NoFreeSlot {
        /// The sensor's id.
        device_id: u32,
        /// `CAL_ACC` or `CAL_GYRO`.
        prefix: &'static str,
        /// The slots' ids.
        ids: String,
    },
    /// An instance beyond the autopilot's slots.
    #[error("instance {instance}: ArduPilot keeps calibrations for instances 0..2 only")]
    NoSuchSlot {
        /// The instance.
        instance: u8,
    },
}

impl VehicleParams {
    /// The value first logged for `name`.
    pub fn get(&self, name: &str) -> Option<f64> {
        self.values.get(name).copied()
    }

    /// Whether the log holds no parameter at all.
    pub fn is_empty(&self) -> bool {
        self.values.is_empty()
    }

    /// How many parameters the log holds.
    pub fn len(&self) -> usize {
        self.values.len()
    }

    /// A later value of `name` different from the first, if the log has one.
    pub fn changed(&self, name: &str) -> Option<f64> {
        self.changed.get(name).copied()
    }

    /// Records a parameter message: the first value is kept, a later different one noted.
    pub(crate) fn record(&mut self, name: &str, value: f64) {
        match self.values.get(name) {
            Some(&first) => {
                let same = first == value || (first.is_nan() && value.is_nan());
                if !same && !self.changed.contains_key(name) {
                    self.changed.insert(name.to_string(), value);
                }
            }
            None if self.values.len() >= MAX_PARAMS => self.left_out += 1,
            None => {
                self.values.insert(name.to_string(), value);
            }
        }
    }

    /// An id parameter's value as the unsigned device id it stores (PX4 keeps ids in an `int32`,
    /// ArduPilot's travel as `float`), `None` when absent or 0.
    fn id(&self, name: &str) -> Option<u32> {
        let v = self.get(name)?;
        let id = (v as i64) as i32 as u32;
        (v.is_finite() && id != 0).then_some(id)
    }

    /// PX4: the device id of `kind`'s sensor of `instance` (its topic's `device_id`) and its slot.
    pub fn px4_slot(&self, kind: SensorKind, instance: u8) -> Result<SensorSlot, SlotError> {
        let (ids, topic) = match kind {
            SensorKind::Accel => (&self.accel_ids, "sensor_accel"),
            SensorKind::Gyro => (&self.gyro_ids, "sensor_gyro"),
        };
        let device_id = *ids
            .get(&instance)
            .ok_or(SlotError::NoDeviceId { topic, instance })?;
        let slot = self.px4_slot_of(kind, device_id, instance)?;
        Ok(SensorSlot { device_id, slot })
    }

    /// PX4's slot for `device_id` (`FindAvailableCalibrationIndex` with `preferred` the instance).
    pub fn px4_slot_of(
        &self,
        kind: SensorKind,
        device_id: u32,
        preferred: u8,
    ) -> Result<u8, SlotError> {
        let prefix = match kind {
            SensorKind::Accel => "CAL_ACC",
            SensorKind::Gyro => "CAL_GYRO",
        };
        let ids: Vec<Option<u32>> = (0..PX4_SLOTS)
            .map(|n| self.id(&format!("{prefix}{n}_ID")))
            .collect();
        if let Some(n) = ids.iter().position(|&id| id == Some(device_id)) {
            return Ok(n as u8);
        }
        if ids.get(usize::from(preferred)) == Some(&None) {
            return Ok(preferred);
        }
        match ids.iter().position(Option::is_none) {
            Some(n) => Ok(n as u8),
            None => Err(SlotError::NoFreeSlot {
                device_id,
                prefix,
                ids: ids
                    .iter()
                    .map(|id| id.unwrap_or(0).to_string())
                    .collect::<Vec<_>>()
                    .join(", "),
            }),
        }
    }

    /// ArduPilot: the id of `kind`'s sensor of `instance` (`INS_ACC_ID`, `INS_ACC2_ID`, …) and its
    /// slot, the instance itself.
    pub fn ardupilot_slot(&self, kind: SensorKind, instance: u8) -> Result<SensorSlot, SlotError> {
        if instance >= ARDUPILOT_SLOTS {
            return Err(SlotError::NoSuchSlot { instance });
        }
        let name = ardupilot_id_name(kind, instance);
        let device_id = self.id(&name).ok_or(SlotError::NoId { name })?;
        Ok(SensorSlot {
            device_id,
            slot: instance,
        })
    }
}

/// The parameters (and PX4's sensor device ids) of the vehicle's log at `path`, read in a pass that
/// keeps no samples; `None` for a format that carries none (text, MCAP).
pub fn read_vehicle_params(path: &Path) -> Result<Option<(LogFormat, VehicleParams)>, LogError> {
    let io = |source| LogError::Io {
        path: path.to_path_buf(),
        source,
    };
    let file = std::fs::File::open(path).map_err(io)?;
    let mut r = BufReader::with_capacity(1 << 20, file);
    let format = LogFormat::detect(r.fill_buf().map_err(io)?);
    let params = match format {
        LogFormat::Ulog => ulog::read_params(r).map_err(|source| LogError::Ulog {
            path: path.to_path_buf(),
            source,
        })?,
        LogFormat::DataFlash => {
            let survey = Keep::Survey(Arc::new(Mutex::new(PassReport::default())));
            let read = dataflash::read_with_params(r, 0, &survey, None);
            read.map_err(|source| LogError::DataFlash {
                path: path.to_path_buf(),
                source,
            })?
            .2
        }
        LogFormat::Text | LogFormat::Mcap => return Ok(None),
    };
    Ok(Some((format, params)))
}

impl VehicleParams {
    /// The IMU instances the log's vehicle has: PX4's `sensor_accel` instances, ArduPilot's slots
    /// whose `INS_ACC*_ID` is set.
    pub fn instances(&self, format: LogFormat) -> Vec<u8> {
        match format {
            LogFormat::Ulog => self.accel_ids.keys().copied().collect(),
            _ => (0..ARDUPILOT_SLOTS)
                .filter(|&i| self.id(&ardupilot_id_name(SensorKind::Accel, i)).is_some())
                .collect(),
        }
    }
}

/// ArduPilot's per-instance parameter name: `INS_ACC` + (``, `2`, `3`) + `rest`.
pub(crate) fn ardupilot_name(stem: &str, instance: u8, rest: &str) -> String {
    match instance {
        0 => format!("{stem}{rest}"),
        n => format!("{stem}{}{rest}", n + 1),
    }
}

/// `INS_ACC_ID`, `INS_ACC2_ID`, `INS_GYR3_ID`, ….
pub(crate) fn ardupilot_id_name(kind: SensorKind, instance: u8) -> String {
    let stem = match kind {
        SensorKind::Accel => "INS_ACC",
        SensorKind::Gyro => "INS_GYR",
    };
    ardupilot_name(stem, instance, "_ID")
}

#[cfg(test)]
mod tests {
    use super::*;

    fn px4(ids: &[(u8, f64)], accel: &[(u8, u32)]) -> VehicleParams {
        let mut p = VehicleParams::default();
        for &(n, id) in ids {
            p.record(&format!("CAL_ACC{n}_ID"), id);
        }
        p.accel_ids = accel.iter().copied().collect();
        p
    }

    /// PX4's lookup: the slot holding the id, else the instance's own slot when free, else the
    /// first free one; an id stored as a negative int32 is the same unsigned id.
    #[test]
    fn px4_slots_follow_find_current_then_available_calibration_index() {
        let p = px4(&[(0, 1_310_988.0), (1, 1_311_004.0)], &[(0, 1_311_004)]);
        assert_eq!(p.px4_slot(SensorKind::Accel, 0).unwrap().slot, 1);
        let p = px4(&[(0, 1_310_988.0)], &[(1, 99)]);
        assert_eq!(p.px4_slot(SensorKind::Accel, 1).unwrap().slot, 1);
        let p = px4(&[(0, 5.0), (1, 6.0)], &[(1, 99)]);
        assert_eq!(p.px4_slot(SensorKind::Accel, 1).unwrap().slot, 2);
        let p = px4(&[(0, 5.0), (1, 6.0), (2, 7.0), (3, 8.0)], &[(0, 99)]);
        let e = p.px4_slot(SensorKind::Accel, 0).unwrap_err();
        assert!(e.to_string().contains("--slot"), "{e}");
        let p = px4(&[(2, -1_294_967_296.0)], &[(0, 3_000_000_000)]);
        assert_eq!(p.px4_slot(SensorKind::Accel, 0).unwrap().slot, 2);
        let e = px4(&[], &[]).px4_slot(SensorKind::Accel, 0).unwrap_err();
        assert!(e.to_string().contains("--device-id"), "{e}");
    }

    #[test]
    fn ardupilot_slots_are_the_instances_and_a_later_value_is_a_change() {
        let mut p = VehicleParams::default();
        p.record("INS_ACC2_ID", 1_442_826.0);
        p.record("INS_ACC2_ID", 1_442_826.0);
        assert_eq!(p.changed("INS_ACC2_ID"), None);
        let s = p.ardupilot_slot(SensorKind::Accel, 1).unwrap();
        assert_eq!((s.device_id, s.slot), (1_442_826, 1));
        assert!(p.ardupilot_slot(SensorKind::Accel, 0).is_err());
        p.record("INS_ACC2_ID", 7.0);
        assert_eq!(p.changed("INS_ACC2_ID"), Some(7.0));
        assert_eq!(ardupilot_name("INS_ACC", 2, "OFFS_X"), "INS_ACC3OFFS_X");
    }
}
