//! The autopilot round trip: from the log a vehicle wrote to the parameters it loads, for the right
//! sensors. The log's own parameters give each IMU's device id and the calibration slot that id
//! holds (`recording::session::logs::vehicle`, after PX4's `FindCurrentCalibrationIndex` and
//! ArduPilot's `register_accel`); [`calibrate_each_imu`] calibrates every IMU of a vehicle from
//! one log, each through the one segment and calibrate path (`handheld`, `calibrate`).

use crate::calibrate::{calibrate_recording, CalibrateOptions, Recording};
use crate::handheld::gyro::HandGyroFileError;
use crate::handheld::{segment_recording, InMemoryError, SegmentChoices};
use estimator::calibration_files::calibration_unit_file;
use estimator::estimate::EstimateError;
use estimator::unit_file::UnitFile;
use recording::session::logs::vehicle::{
    read_vehicle_params, SensorKind, SensorSlot, SlotError, VehicleParams,
};
use recording::session::logs::{read_log_keeping, LogError, LogFormat, LogSource};
use recording::session::note::Note;
use std::path::{Path, PathBuf};

/// Why a log gives no ids, slots or calibrations; each says what to do.
#[derive(Debug, thiserror::Error)]
pub enum AutopilotError {
    /// The log cannot be read.
    #[error(transparent)]
    Log(#[from] LogError),
    /// Not a vehicle's log (text, MCAP): no parameters.
    #[error(
        "{0} is not a PX4 ULog or an ArduPilot DataFlash log: it carries no vehicle parameters; \
         give --device-id (and --slot) instead of --log"
    )]
    NotAVehicleLog(PathBuf),
    /// The log's parameters give no id or slot.
    #[error("{path}, IMU instance {instance}")]
    Slot {
        /// The log.
        path: PathBuf,
        /// The IMU instance.
        instance: u8,
        /// Why.
        source: SlotError,
    },
    /// The log names no IMU.
    #[error(
        "{0}: the log's parameters name no IMU (PX4: no sensor_accel message; ArduPilot: no \
         INS_ACC_ID set): choose one with --instance N"
    )]
    NoImu(PathBuf),
    /// One IMU's recording gives no session.
    #[error("IMU instance {instance}")]
    Segment {
        /// The IMU instance.
        instance: u8,
        /// Why.
        source: InMemoryError,
    },
    /// One IMU's hand-turn gyro does not read back.
    #[error("IMU instance {instance}")]
    HandGyro {
        /// The IMU instance.
        instance: u8,
        /// Why.
        source: HandGyroFileError,
    },
    /// One IMU's estimate failed.
    #[error("IMU instance {instance}")]
    Estimate {
        /// The IMU instance.
        instance: u8,
        /// Why.
        source: EstimateError,
    },
}

/// A vehicle's log as the export reads it: its format and parameters.
#[derive(Clone, Debug)]
pub struct VehicleLog {
    /// The log.
    pub path: PathBuf,
    /// PX4 ULog or ArduPilot DataFlash.
    pub format: LogFormat,
    /// Its parameters and device ids.
    pub params: VehicleParams,
}

/// One IMU's ids and slots as its vehicle's log gives them.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct ImuIds {
    /// The IMU instance (ULog's `multi_id`, DataFlash's `I`).
    pub instance: u8,
    /// The accelerometer's device id and slot.
    pub accel: SensorSlot,
    /// The gyro's, where the log has them.
    pub gyro: Option<SensorSlot>,
}

impl VehicleLog {
    /// Reads the parameters of the vehicle's log at `path`.
    pub fn read(path: &Path) -> Result<VehicleLog, AutopilotError> {
        let (format, params) = read_vehicle_params(path)?
            .ok_or_else(|| AutopilotError::NotAVehicleLog(path.to_path_buf()))?;
        Ok(VehicleLog {
            path: path.to_path_buf(),
            format,
            params,
        })
    }

    /// The IMU instances the vehicle has, refused when none.
    pub fn instances(&self) -> Result<Vec<u8>, AutopilotError> {
        let found = self.params.instances(self.format);
        if found.is_empty() {
            return Err(AutopilotError::NoImu(self.path.clone()));
        }
        Ok(found)
    }

    /// The ids and slots of IMU `instance`.
    pub fn ids(&self, instance: u8) -> Result<ImuIds, AutopilotError> {
        let slot = |kind| match self.format {
            LogFormat::Ulog => self.params.px4_slot(kind, instance),
            _ => self.params.ardupilot_slot(kind, instance),
        };
        let accel = slot(SensorKind::Accel).map_err(|source| AutopilotError::Slot {
            path: self.path.clone(),
            instance,
            source,
        })?;
        Ok(ImuIds {
            instance,
            accel,
            gyro: slot(SensorKind::Gyro).ok(),
        })
    }
}

/// One IMU's calibration from its vehicle's log.
#[derive(Debug)]
pub struct ImuCalibration {
    /// Its ids and slots.
    pub ids: ImuIds,
    /// The calibration file it would be written as.
    pub unit: UnitFile,
    /// What the reader, the segmentation and the checks said.
    pub warnings: Vec<String>,
}

/// Calibrates each IMU of `log` in `instances` from the hand-held session the log holds: each read
/// (its vehicle's own correction undone where the log's stream carries one), segmented and
/// calibrated as `host segment` then `host calibrate` do.
pub fn calibrate_each_imu(
    log: &VehicleLog,
    instances: &[u8],
    choices: &SegmentChoices,
    options: &CalibrateOptions,
    max_samples: usize,
) -> Result<Vec<ImuCalibration>, AutopilotError> {
    let mut out = Vec::new();
    for &instance in instances {
        let ids = log.ids(instance)?;
        let source = LogSource {
            text: None,
            instance: Some(instance),
            topic: None,
            spelling: choices.segment.spelling,
            rate_hz: None,
        };
        let read = read_log_keeping(&log.path, &source, max_samples)?;
        let session = segment_recording(read.recording, choices)
            .map_err(|source| AutopilotError::Segment { instance, source })?;
        let hand_gyro = session
            .gyro_estimate()
            .map_err(|source| AutopilotError::HandGyro { instance, source })?;
        let mut warnings = Note::texts(&read.warnings);
        warnings.extend(session.warnings.iter().cloned());
        let stats = session.stats();
        let calibrated = calibrate_recording(
            Recording {
                plan: &session.plan,
                stats: &stats,
                hand_gyro: hand_gyro.as_ref(),
                reader_warnings: &warnings,
            },
            options,
        )
        .map_err(|source| AutopilotError::Estimate { instance, source })?;
        let unit = calibration_unit_file(&calibrated.outcome, calibrated.unit_id);
        out.push(ImuCalibration {
            ids,
            unit,
            warnings,
        });
    }
    Ok(out)
}
