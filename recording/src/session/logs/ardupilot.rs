//! ArduPilot's own correction of its IMU samples, undone sample by sample, so that a calibration
//! sees the sensor's output and not what is left after the vehicle's calibration.
//!
//! Every ArduPilot driver passes each sample through `_rotate_and_correct_accel` before it is
//! published, filtered and logged as `IMU` (and `ACC`) (`ArduPilot/ardupilot`
//! `libraries/AP_InertialSensor/AP_InertialSensor_Backend.cpp`): after the driver's own sensor
//! rotation, `a ← a − [p(T − 35) − p(T_cal − 35)]` (the temperature calibration, `INS_TCALn_*`,
//! `AP_InertialSensor_tempcal.cpp` `correct_sensor`, only with `INS_TCALn_ENABLE = 1`, `T` and
//! `T_cal = INS_ACCn_CALTEMP` clipped to `INS_TCALn_TMIN..TMAX`, coefficients stored ×10⁶), then
//! `a ← (a − INS_ACCOFFS) ∘ INS_ACCSCAL`, then the board rotation `AHRS_ORIENTATION`;
//! `_rotate_and_correct_gyro` likewise `ω ← R·(ω − [p_g(T − 35) − p_g(T_cal − 35)] − INS_GYROFFS)`.
//! Firmware before the sensor-frame calibration (`INS_CALSENSFRAME = 0`, a parameter since
//! retired: `AP_InertialSensor.cpp` keeps its index reserved) rotated first and corrected after, in
//! an order that changed between its versions: such a log is refused, not guessed at.
//! All of it is affine in the sample, so it commutes with the logged low-pass filter and is undone
//! exactly (to the `float` rounding of the vehicle): `a = Rᵀ·l ∘ (1/INS_ACCSCAL) + INS_ACCOFFS +
//! p(T − 35) − p(T_cal − 35)`. The result is the frame `INS_ACC*` are written in, which is what
//! `export --format ardupilot` writes for.

use super::vehicle::{ardupilot_name, VehicleParams, ARDUPILOT_SLOTS};
use crate::session::import::Recording;
use crate::session::note::Note;

/// ArduPilot's thermal reference, °C (`TEMP_REFERENCE`).
const TCAL_REFERENCE_C: f64 = 35.0;
/// ArduPilot stores thermal coefficients ×10⁶ (`polynomial_eval`'s `INV_SCALE_FACTOR`).
const TCAL_SCALE: f64 = 1e-6;
/// `AHRS_ORIENTATION`'s custom rotation (`ROTATION_CUSTOM_OLD`, `AHRS_CUSTOM_ROLL/PIT/YAW`).
const ROTATION_CUSTOM: u32 = 100;

/// Why the vehicle's correction of a log's IMU cannot be undone; each says what to do.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum UndoError {
    /// No `PARM` message at all.
    #[error(
        "the log holds no parameters (PARM messages), and ArduPilot corrects its IMU samples with \
         its own calibration (INS_ACCOFFS, INS_ACCSCAL, AHRS_ORIENTATION) before logging them: \
         without them a calibration would be the leftover of the vehicle's. Use the log as the \
         vehicle wrote it (ArduPilot writes every parameter at the start of each log), not a copy \
         cut or converted without its PARM messages"
    )]
    NoParameters,
    /// A parameter the correction used is not in the log.
    #[error(
        "the log has no {name}, which ArduPilot applied to IMU instance {instance} before logging \
         it: the correction cannot be undone. Use the whole log (its PARM messages are at the \
         start), or one from firmware that logs {name}"
    )]
    Missing {
        /// The parameter.
        name: String,
        /// The IMU instance.
        instance: u8,
    },
    /// A parameter the correction used changed during the log.
    #[error(
        "{name} changed during the log (from {first} to {later}): the samples before and after \
         were corrected differently. Record the calibration session with the parameters left \
         alone, or cut the log at the change"
    )]
    Changed {
        /// The parameter.
        name: String,
        /// Its first value.
        first: f64,
        /// Its later value.
        later: f64,
    },
    /// A scale of zero (no calibration in that slot).
    #[error(
        "{name} = {value}: ArduPilot multiplied IMU instance {instance} by it, which cannot be \
         undone (a slot with no calibration is 0); the log's samples of that IMU hold nothing of \
         the sensor's output"
    )]
    ZeroScale {
        /// The parameter.
        name: String,
        /// Its value.
        value: f64,
        /// The IMU instance.
        instance: u8,
    },
    /// A board rotation this reader does not know.
    #[error(
        "AHRS_ORIENTATION = {0}: a board rotation this reader does not know (0..40 and 100, \
         custom, are read); log the IMU with AHRS_ORIENTATION = 0 for the calibration session"
    )]
    UnknownRotation(f64),
    /// A calibration of the body-frame era.
    #[error(
        "INS_CALSENSFRAME = 0: the log's firmware corrected its IMU samples with a calibration made \
         in the board's frame, in an order that changed between its versions, so they cannot be \
         undone with certainty; record the session with current firmware"
    )]
    BodyFrameCalibration,
    /// ArduPilot keeps calibrations for three IMUs here.
    #[error(
        "IMU instance {0}: the calibrations read are INS_ACC*, INS_ACC2*, INS_ACC3* (instances \
         0..2)"
    )]
    NoSlot(u8),
    /// The temperature calibration is on but the samples have no temperature.
    #[error(
        "INS_TCAL{n}_ENABLE = 1: ArduPilot corrected IMU instance {instance} for its temperature, \
         and the samples read carry none (ACC/GYR messages): log IMU (LOG_BITMASK's IMU bit), whose \
         T the correction needs"
    )]
    NoTemperature {
        /// The TCAL block, 1-based.
        n: u8,
        /// The IMU instance.
        instance: u8,
    },
}

/// The correction one IMU went through.
#[derive(Clone, Debug, PartialEq)]
struct Correction {
    /// Board rotation, body ← sensor (row-major).
    rotation: [[f64; 3]; 3],
    acc_offset: [f64; 3],
    acc_inv_scale: [f64; 3],
    gyro_offset: [f64; 3],
    tcal: Option<Tcal>,
}

/// `INS_TCALn_*` when enabled.
#[derive(Clone, Debug, PartialEq)]
struct Tcal {
    range_c: [f64; 2],
    /// Per axis, coefficients of x, x², x³ (already ×10⁻⁶).
    acc: [[f64; 3]; 3],
    gyro: [[f64; 3]; 3],
    acc_cal_c: f64,
    gyro_cal_c: f64,
}

impl Tcal {
    /// `p(T − 35) − p(T_cal − 35)` per axis with both temperatures clipped, for `coeff`.
    fn term(&self, coeff: &[[f64; 3]; 3], cal_c: f64, t_c: f64) -> [f64; 3] {
        let clip = |t: f64| t.clamp(self.range_c[0], self.range_c[1]) - TCAL_REFERENCE_C;
        let (x, xc) = (clip(t_c), clip(cal_c));
        let p = |k: &[f64; 3], x: f64| (k[0] + (k[1] + k[2] * x) * x) * x;
        std::array::from_fn(|i| p(&coeff[i], x) - p(&coeff[i], xc))
    }
}

/// Reads the correction of IMU `instance` from `p`.
fn correction(p: &VehicleParams, instance: u8) -> Result<Correction, UndoError> {
    if p.is_empty() {
        return Err(UndoError::NoParameters);
    }
    if instance >= ARDUPILOT_SLOTS {
        return Err(UndoError::NoSlot(instance));
    }
    let get = |name: String| -> Result<f64, UndoError> {
        let first = p.get(&name).ok_or_else(|| UndoError::Missing {
            name: name.clone(),
            instance,
        })?;
        match p.changed(&name) {
            Some(later) => Err(UndoError::Changed { name, first, later }),
            None => Ok(first),
        }
    };
    let xyz = |stem: &str, rest: &str| -> Result<[f64; 3], UndoError> {
        let n = |axis| ardupilot_name(stem, instance, &format!("{rest}{axis}"));
        Ok([get(n("X"))?, get(n("Y"))?, get(n("Z"))?])
    };
    let acc_offset = xyz("INS_ACC", "OFFS_")?;
    let scale = xyz("INS_ACC", "SCAL_")?;
    let mut acc_inv_scale = [0.0; 3];
    for (i, (s, axis)) in scale.iter().zip(["X", "Y", "Z"]).enumerate() {
        if *s == 0.0 || !s.is_finite() {
            return Err(UndoError::ZeroScale {
                name: ardupilot_name("INS_ACC", instance, &format!("SCAL_{axis}")),
                value: *s,
                instance,
            });
        }
        acc_inv_scale[i] = 1.0 / s;
    }
    let gyro_offset = xyz("INS_GYR", "OFFS_")?;
    let orientation = get("AHRS_ORIENTATION".into())?;
    let rotation = if orientation == f64::from(ROTATION_CUSTOM) {
        let deg = |n: &str| get(n.into());
        from_euler_deg(
            deg("AHRS_CUSTOM_ROLL")?,
            deg("AHRS_CUSTOM_PIT")?,
            deg("AHRS_CUSTOM_YAW")?,
        )
    } else {
        board_rotation(orientation).ok_or(UndoError::UnknownRotation(orientation))?
    };
    if p.get("INS_CALSENSFRAME") == Some(0.0) {
        return Err(UndoError::BodyFrameCalibration);
    }
    let tcal = tcal(p, instance, &get)?;
    Ok(Correction {
        rotation,
        acc_offset,
        acc_inv_scale,
        gyro_offset,
        tcal,
    })
}

/// `INS_TCAL{instance+1}_*` when `INS_TCALn_ENABLE = 1` (absent: firmware without it).
fn tcal(
    p: &VehicleParams,
    instance: u8,
    get: &dyn Fn(String) -> Result<f64, UndoError>,
) -> Result<Option<Tcal>, UndoError> {
    let n = instance + 1;
    let enable = format!("INS_TCAL{n}_ENABLE");
    if p.get(&enable).is_none() || get(enable)? != 1.0 {
        return Ok(None);
    }
    let poly = |sensor: &str| -> Result<[[f64; 3]; 3], UndoError> {
        let mut c = [[0.0; 3]; 3];
        for (k, order) in (1..=3).enumerate() {
            for (axis, row) in ["X", "Y", "Z"].iter().zip(c.iter_mut()) {
                row[k] = get(format!("INS_TCAL{n}_{sensor}{order}_{axis}"))? * TCAL_SCALE;
            }
        }
        Ok(c)
    };
    Ok(Some(Tcal {
        range_c: [
            get(format!("INS_TCAL{n}_TMIN"))?,
            get(format!("INS_TCAL{n}_TMAX"))?,
        ],
        acc: poly("ACC")?,
        gyro: poly("GYR")?,
        acc_cal_c: get(format!("INS_ACC{n}_CALTEMP"))?,
        gyro_cal_c: get(format!("INS_GYR{n}_CALTEMP"))?,
    }))
}

/// ArduPilot's `Matrix3::from_euler(roll, pitch, yaw)`: `Rz(yaw)·Ry(pitch)·Rx(roll)`.
fn from_euler_deg(roll: f64, pitch: f64, yaw: f64) -> [[f64; 3]; 3] {
    let (sr, cr) = roll.to_radians().sin_cos();
    let (sp, cp) = pitch.to_radians().sin_cos();
    let (sy, cy) = yaw.to_radians().sin_cos();
    [
        [cp * cy, sr * sp * cy - cr * sy, cr * sp * cy + sr * sy],
        [cp * sy, sr * sp * sy + cr * cy, cr * sp * sy - sr * cy],
        [-sp, sr * cp, cr * cp],
    ]
}

/// `AHRS_ORIENTATION` 0..40 as ArduPilot's `Vector3::rotate` turns a vector: each is
/// `from_euler(roll, pitch, yaw)` of the angles in its name (`AP_Math/tests/test_rotations.cpp`,
/// `test_euler`; 38 is roll 90, pitch 68.8, yaw 293.3 there).
fn board_rotation(value: f64) -> Option<[[f64; 3]; 3]> {
    const EULER: [(f64, f64, f64); 41] = [
        (0.0, 0.0, 0.0),
        (0.0, 0.0, 45.0),
        (0.0, 0.0, 90.0),
        (0.0, 0.0, 135.0),
        (0.0, 0.0, 180.0),
        (0.0, 0.0, 225.0),
        (0.0, 0.0, 270.0),
        (0.0, 0.0, 315.0),
        (180.0, 0.0, 0.0),
        (180.0, 0.0, 45.0),
        (180.0, 0.0, 90.0),
        (180.0, 0.0, 135.0),
        (0.0, 180.0, 0.0),
        (180.0, 0.0, 225.0),
        (180.0, 0.0, 270.0),
        (180.0, 0.0, 315.0),
        (90.0, 0.0, 0.0),
        (90.0, 0.0, 45.0),
        (90.0, 0.0, 90.0),
        (90.0, 0.0, 135.0),
        (270.0, 0.0, 0.0),
        (270.0, 0.0, 45.0),
        (270.0, 0.0, 90.0),
        (270.0, 0.0, 135.0),
        (0.0, 90.0, 0.0),
        (0.0, 270.0, 0.0),
        (0.0, 180.0, 90.0),
        (0.0, 180.0, 270.0),
        (90.0, 90.0, 0.0),
        (180.0, 90.0, 0.0),
        (270.0, 90.0, 0.0),
        (90.0, 180.0, 0.0),
        (270.0, 180.0, 0.0),
        (90.0, 270.0, 0.0),
        (180.0, 270.0, 0.0),
        (270.0, 270.0, 0.0),
        (90.0, 180.0, 90.0),
        (90.0, 0.0, 270.0),
        (90.0, 68.8, 293.3),
        (0.0, 315.0, 0.0),
        (90.0, 315.0, 0.0),
    ];
    if value.fract() != 0.0 || !(0.0..41.0).contains(&value) {
        return None;
    }
    let (r, p, y) = EULER[value as usize];
    Some(from_euler_deg(r, p, y))
}

/// `Rᵀ·v`.
fn rotate_back(r: &[[f64; 3]; 3], v: [f64; 3]) -> [f64; 3] {
    std::array::from_fn(|j| r[0][j] * v[0] + r[1][j] * v[1] + r[2][j] * v[2])
}

/// Undoes ArduPilot's correction of IMU `instance` in `rec` (the `IMU`/`ACC`/`GYR` samples as
/// logged) with the log's parameters `p`; what was undone, for the user (`None`: the vehicle's
/// correction was the identity).
pub(crate) fn undo(
    rec: &mut Recording,
    p: &VehicleParams,
    instance: u8,
) -> Result<Option<Note>, UndoError> {
    let c = correction(p, instance)?;
    if c.is_identity() {
        return Ok(None);
    }
    if c.tcal.is_some() && rec.temp_c.is_none() && !rec.is_empty() {
        return Err(UndoError::NoTemperature {
            n: instance + 1,
            instance,
        });
    }
    let temps = rec.temp_c.as_deref().unwrap_or_default();
    let mut last_temp = temps.iter().copied().find(|t| t.is_finite());
    let mut no_temp = 0usize;
    for (k, (a, w)) in rec.acc.iter_mut().zip(&mut rec.gyro_rad_s).enumerate() {
        let (mut acc, mut gyro) = (rotate_back(&c.rotation, *a), rotate_back(&c.rotation, *w));
        acc = std::array::from_fn(|i| acc[i] * c.acc_inv_scale[i] + c.acc_offset[i]);
        gyro = std::array::from_fn(|i| gyro[i] + c.gyro_offset[i]);
        if let Some(t) = &c.tcal {
            let temp = match temps.get(k).copied().filter(|t| t.is_finite()) {
                Some(t) => {
                    last_temp = Some(t);
                    t
                }
                None => {
                    no_temp += 1;
                    last_temp.unwrap_or(TCAL_REFERENCE_C)
                }
            };
            let (da, dw) = (
                t.term(&t.acc, t.acc_cal_c, temp),
                t.term(&t.gyro, t.gyro_cal_c, temp),
            );
            acc = std::array::from_fn(|i| acc[i] + da[i]);
            gyro = std::array::from_fn(|i| gyro[i] + dw[i]);
        }
        *a = acc;
        *w = gyro;
    }
    Ok(Some(Note::ArduPilotUndone {
        instance,
        offs: ardupilot_name("INS_ACC", instance, "OFFS"),
        scal: ardupilot_name("INS_ACC", instance, "SCAL"),
        acc_offset: c.acc_offset,
        acc_scale: c.acc_inv_scale.map(|s| 1.0 / s),
        orientation: p.get("AHRS_ORIENTATION").unwrap_or(0.0),
        tcal: c.tcal.is_some(),
        no_temp,
    }))
}

impl Correction {
    /// Offsets and gyro offsets 0, scales 1, no rotation, no temperature terms.
    fn is_identity(&self) -> bool {
        self.tcal.is_none()
            && self.acc_offset == [0.0; 3]
            && self.gyro_offset == [0.0; 3]
            && self.acc_inv_scale == [1.0; 3]
            && self.rotation == from_euler_deg(0.0, 0.0, 0.0)
    }
}

#[cfg(test)]
mod tests;
