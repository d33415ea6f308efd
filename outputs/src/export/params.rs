//! PX4 and ArduPilot accelerometer and gyro parameters.
//!
//! Both autopilots correct each axis alone, in the sensor frame, before their board rotation. PX4
//! (`PX4/PX4-Autopilot` `src/lib/sensor_calibration/Accelerometer.hpp`, `Correct()`):
//! `a = R·((a_m − CAL_ACC0_xOFF) ∘ CAL_ACC0_xSCALE)`, and `Gyroscope.hpp`: `ω = R·(w_m − CAL_GYRO0_xOFF)`
//! (PX4 holds no gyro scale). ArduPilot (`ArduPilot/ardupilot`
//! `libraries/AP_InertialSensor/AP_InertialSensor_Backend.cpp`, `_rotate_and_correct_accel` and
//! `_rotate_and_correct_gyro`): `a = R·((a_m − INS_ACCOFFS) ∘ INS_ACCSCAL)`, `ω = R·(w_m − INS_GYROFFS)`.
//! `a_m` is the driver's reading in m/s² (here `a_m = c·U`, `c` the driver's scale,
//! [`super::ExportInput::driver_scale`]), `w_m` the gyro's in rad/s.
//! Our inverse model is `f = g·(K·A)⁻¹·(U − u0)` (`docs/model.md` §3), so the closest per-axis form
//! keeps the diagonal of `g·(K·A)⁻¹`: `offset_i = c·u0_i`, `scale_i = g·[(K·A)⁻¹]_ii / c`; the gyro's
//! `ω = G⁻¹(w − b)` (§8) keeps `offset = b`, exact at rest.
//!
//! What neither can hold, and each file says so with the size of what is dropped: the
//! cross-axis terms of `(K·A)⁻¹` (misalignment; bounded here by the largest row sum of the dropped
//! terms at 1 g), the gyro's scale and misalignment `G⁻¹ − I` (bounded at 100 °/s), the per-axis
//! sensing points and the lever-arm compensation. The file also states the driver scale it assumes.
//!
//! A temperature model (`docs/model.md` §9) goes into the autopilots' thermal offsets ([`thermal`]):
//! PX4's `TC_A0_*`/`TC_G0_*` (`src/modules/temperature_compensation/TemperatureCompensation.cpp`,
//! `calc_thermal_offsets_3D`: `x0 + x1·dT + x2·dT² + x3·dT³`, `dT` from `TC_*_TREF` with the temperature
//! clipped to `TMIN..TMAX`, subtracted before `CAL_*_xOFF`) and ArduPilot's `INS_TCAL1_*`
//! (`AP_InertialSensor_tempcal.cpp`, `correct_sensor`: `p(T − 35) − p(T_cal − 35)` with `p` a cubic
//! without constant whose coefficients are stored ×10⁶, `T` and `T_cal = INS_ACC1_CALTEMP` clipped to
//! `TMIN..TMAX`, subtracted before the offsets). Both hold our zero-bias and gyro-bias polynomials
//! exactly (ArduPilot's re-centred on 35 °C); neither holds the scale factors' temperature dependence,
//! whose size over the valid range each file states.
//!
//! ArduPilot's documented ranges (the `@Range` metadata of `AP_InertialSensor.cpp` and
//! `AP_InertialSensor_tempcal.cpp`: `INS_ACCSCAL_*` 0.8..1.2, `INS_ACCOFFS_*` −3.5..3.5 m/s²,
//! `INS_TCAL1_TMIN`/`TMAX` −70..80 °C) are checked: a value outside is refused unless
//! `--allow-out-of-range`, which writes it with a `# WARNING:` line. PX4's parameter metadata
//! documents no range for `CAL_ACC0_*`/`CAL_GYRO0_*`, so nothing is checked there beyond `f32`.

use super::{as_f32, Autopilot, ExportError, ExportInput};
use recording::spelling::{Spelling, UserOption};
use shared::linalg::{self, RowMajor3};
use std::fmt::Write as _;

/// Per-axis offsets (m/s²) and scales for an autopilot, and what the per-axis form drops.
#[derive(Clone, Debug, PartialEq)]
pub struct PerAxis {
    /// The driver's scale assumed, m/s² per output unit.
    pub driver_scale: f64,
    /// Offsets, m/s², in the driver's reading.
    pub offset_m_s2: [f64; 3],
    /// Scales (dimensionless).
    pub scale: [f64; 3],
    /// Largest error of the dropped cross-axis terms at 1 g on any axis, g.
    pub dropped_cross_axis_g: f64,
    /// The gyro's offsets `b`, rad/s, when the calibration has a gyro correction.
    pub gyro_offset_rad_s: Option<[f64; 3]>,
    /// Largest error of the dropped `G⁻¹ − I` at 100 °/s on any axis, °/s.
    pub dropped_gyro_deg_s_at_100: f64,
}

/// The per-axis form of `input` for `format` (which names the target in errors).
pub(crate) fn per_axis(
    input: &ExportInput<'_>,
    format: &'static str,
) -> Result<PerAxis, ExportError> {
    let (fitted, _) = input.cal.statics.to_fitted()?;
    let inv = linalg::inverse(&fitted.m_out_per_g).ok_or(ExportError::Singular)?;
    let c = input.driver_scale(format)?;
    let g = input.cal.gravity_m_s2;
    // (K·A)⁻¹ = D + E with D its diagonal; dropping E leaves E·(U − u0) = E·D⁻¹·f/g per axis.
    let dropped = (0..3)
        .map(|i| {
            (0..3)
                .filter(|&j| j != i)
                .map(|j| (inv[i][j] / inv[j][j]).abs())
                .sum::<f64>()
        })
        .fold(0.0, f64::max);
    let gyro_inv = match &input.cal.gyro {
        Some(gy) => Some(gy.checked_inverse().map_err(|e| {
            ExportError::Compensator(shared::compensator::CompensatorError::Gyro(e))
        })?),
        None => None,
    };
    let dropped_gyro = gyro_inv.map_or(0.0, |gi: RowMajor3| {
        (0..3)
            .map(|i| {
                (0..3)
                    .map(|j| (gi[i][j] - f64::from(u8::from(i == j))).abs())
                    .sum::<f64>()
            })
            .fold(0.0, f64::max)
            * 100.0
    });
    Ok(PerAxis {
        driver_scale: c,
        offset_m_s2: fitted.zero_bias_out.map(|v| v * c),
        scale: std::array::from_fn(|i| g * inv[i][i] / c),
        dropped_cross_axis_g: dropped,
        gyro_offset_rad_s: input.cal.gyro.map(|gy| gy.bias_rad_s),
        dropped_gyro_deg_s_at_100: dropped_gyro,
    })
}

fn caveats(w: &mut String, input: &ExportInput<'_>, p: &PerAxis, tool: &str) {
    let unit = input.cal.statics.output_unit.symbol();
    let gyro = p.gyro_offset_rad_s.is_some();
    let _ = writeln!(
        w,
        "# Accelerometer{} calibration for {tool} (host export). Assumes the driver reports\n\
         # a_m = c*U m/s^2 with c = {:?} m/s^2 per {unit} (the calibration's output unit){}, and sensor\n\
         # axes = our body axes (board rotation: none).\n\
         # NOT HELD by these parameters (apply them elsewhere, or accept the error):\n\
         # - accelerometer cross-axis (misalignment) terms: up to {:.3} mg at 1 g on the worst axis;",
        if gyro { " and gyro" } else { "" },
        p.driver_scale,
        if gyro { ", the gyro w in rad/s" } else { "" },
        p.dropped_cross_axis_g * 1e3,
    );
    if gyro {
        let _ = writeln!(
            w,
            "# - the gyro's scale and misalignment (G^-1 - I): up to {:.4} deg/s at 100 deg/s;",
            p.dropped_gyro_deg_s_at_100
        );
    }
    let _ = writeln!(
        w,
        "# - the per-axis sensing points and the lever-arm (size-effect) compensation."
    );
    if !gyro {
        let _ = writeln!(
            w,
            "# Gyro offsets: UNDETERMINED (the calibration has no gyro correction); none written."
        );
    }
}

/// Values as the autopilots store them (IEEE single precision), shortest form.
fn f32_text(name: &str, v: f64, spelling: Spelling) -> Result<String, ExportError> {
    Ok(format!("{}", as_f32(name, v, spelling)?))
}

/// The values of a parameter file, in order: `(name, value, is_integer)`.
type Values = Vec<(String, f64, bool)>;

fn accel_values(p: &PerAxis, off: &str, scl: &str) -> Values {
    let mut v = Values::new();
    for (i, axis) in ["X", "Y", "Z"].iter().enumerate() {
        v.push((off.replace('#', axis), p.offset_m_s2[i], false));
    }
    for (i, axis) in ["X", "Y", "Z"].iter().enumerate() {
        v.push((scl.replace('#', axis), p.scale[i], false));
    }
    v
}

/// A QGroundControl parameter file for PX4. QGroundControl's loader (`mavlink/qgroundcontrol`
/// `src/FactSystem/ParameterManager.cc`, `readParametersFromStream`) skips `#` lines, splits the others
/// on tabs into exactly five fields `sysid compid name value type`, refuses a file whose sysid is not
/// the vehicle's, and converts the value by its MAVLink type (9 = REAL32, 6 = INT32).
pub(crate) fn render_px4(input: &ExportInput<'_>) -> Result<String, ExportError> {
    let (comments, values) = px4_slot(input)?;
    let o = input.options;
    let mut s = comments;
    px4_after_loading(&mut s, &values);
    px4_table(&mut s, o, values)?;
    Ok(s)
}

/// Several IMUs' calibrations in one QGroundControl file, each in its own slot (`inputs` hold each
/// one's ids and slot): the slots must differ.
pub fn render_px4_slots(inputs: &[ExportInput<'_>]) -> Result<String, ExportError> {
    let mut s = String::new();
    let mut values = Values::new();
    for input in inputs {
        let (comments, v) = px4_slot(input)?;
        s.push_str(&comments);
        values.extend(v);
    }
    px4_after_loading(&mut s, &values);
    match inputs.first() {
        Some(i) => px4_table(&mut s, i.options, values)?,
        // No calibration: the table's header alone, for the default vehicle id.
        None => px4_header(&mut s, 1),
    }
    Ok(s)
}

/// PX4's per-slot names (`Utilities.cpp` builds them as `CAL_%s%u_ID`; four slots).
const PX4_ACC_ID: [&str; 4] = ["CAL_ACC0_ID", "CAL_ACC1_ID", "CAL_ACC2_ID", "CAL_ACC3_ID"];

/// One calibration's comments and values in its slot (`ExportOptions::slot`, default 0).
fn px4_slot(input: &ExportInput<'_>) -> Result<(String, Values), ExportError> {
    let p = per_axis(input, "PX4")?;
    let o = input.options;
    let n = o.slot.unwrap_or(0);
    let id_name = PX4_ACC_ID
        .get(usize::from(n))
        .copied()
        .ok_or(ExportError::NoSuchSlot {
            autopilot: Autopilot::Px4,
            slot: n,
        })?;
    let device_id = o.device_id.ok_or(ExportError::DeviceIdRequired {
        autopilot: Autopilot::Px4,
        id_parameter: id_name,
        spelling: o.spelling,
    })?;
    let mut s = String::new();
    caveats(&mut s, input, &p, "PX4");
    let _ = writeln!(
        s,
        "# Slot {n}: CAL_ACC{n}_* for the accelerometer with device id {device_id} (PX4 applies a slot to\n\
         # the sensor whose id it holds: FindCurrentCalibrationIndex, src/lib/sensor_calibration/Utilities.cpp)."
    );
    let mut values: Values = vec![(id_name.into(), f64::from(device_id as i32), true)];
    values.extend(accel_values(
        &p,
        &format!("CAL_ACC{n}_#OFF"),
        &format!("CAL_ACC{n}_#SCALE"),
    ));
    let gn = o.gyro_slot.unwrap_or(n);
    match (p.gyro_offset_rad_s, o.gyro_device_id) {
        (Some(b), Some(id)) => {
            values.push((format!("CAL_GYRO{gn}_ID"), f64::from(id as i32), true));
            for (i, axis) in ["X", "Y", "Z"].iter().enumerate() {
                values.push((format!("CAL_GYRO{gn}_{axis}OFF"), b[i], false));
            }
            let _ = writeln!(
                s,
                "# CAL_GYRO{gn}_*OFF: with IMU_GYRO_CAL_EN = 1 (PX4's default) the gyro_calibration module\n\
                 # (started by ROMFS/px4fmu_common/init.d/rcS; src/modules/gyro_calibration) measures the\n\
                 # gyro offsets again whenever the vehicle rests disarmed and saves them over these."
            );
        }
        (Some(_), None) => {
            let _ = writeln!(
                s,
                "# Gyro offsets NOT WRITTEN: PX4 applies CAL_GYRO{gn}_* only to the gyro whose device id is\n\
                 # CAL_GYRO{gn}_ID; give {} to write them.",
                o.spelling.given(UserOption::GyroDeviceId, "ID")
            );
        }
        (None, _) => {}
    }
    values.extend(px4_thermal(input, &p, device_id, &mut s)?);
    Ok((s, values))
}

/// How to load a PX4 file of `values` safely and check it took, from the sources each step follows.
fn px4_after_loading(s: &mut String, values: &Values) {
    let _ = writeln!(
        s,
        "# Load: QGroundControl, Vehicle Setup > Parameters > Tools > Load from file (ParameterManager.cc,\n\
         # readParametersFromStream: sets each line's parameter, leaves the others alone); or on the\n\
         # console (nsh, MAVLink shell) `param set NAME VALUE` for each line below, then `param save`.\n\
         # NEVER `param load` this file: PX4's param_load (src/lib/parameters/parameters.cpp) first\n\
         # resets EVERY parameter to its default, then reads a binary (BSON) file, which this is not;\n\
         # the import fails after the reset, and `param save` would store the reset vehicle.\n\
         # Then reboot. Check: `listener sensor_accel` shows each device_id the slots name, and\n\
         # QGroundControl's pre-flight checks no longer ask for an accelerometer calibration."
    );
    if values.iter().any(|(name, _, _)| name.starts_with("TC_")) {
        let _ = writeln!(
            s,
            "# CAL_* take effect at once, but PX4 starts its temperature compensation at boot only\n\
             # when TC_A_ENABLE or TC_G_ENABLE is set: the TC_* values apply from the next boot."
        );
    }
}

/// QGroundControl's table of `values`.
fn px4_table(s: &mut String, o: super::ExportOptions, values: Values) -> Result<(), ExportError> {
    px4_header(s, o.sysid);
    for (name, v, int) in values {
        let (text, ty) = if int {
            (format!("{}", v as i64), 6)
        } else {
            (f32_text(&name, v, o.spelling)?, 9)
        };
        let _ = writeln!(s, "{}\t{}\t{name}\t{text}\t{ty}", o.sysid, o.compid);
    }
    Ok(())
}

/// The header of QGroundControl's parameter table for vehicle `sysid`.
fn px4_header(s: &mut String, sysid: u8) {
    let _ = writeln!(
        s,
        "#\n# Onboard parameters for Vehicle {sysid}\n#\n# Vehicle-Id\tComponent-Id\tName\tValue\tType"
    );
}

/// What a temperature model becomes in the autopilots' thermal offsets, in the driver's units.
#[derive(Clone, Debug, PartialEq)]
pub struct Thermal {
    /// Reference temperature of our model, °C.
    pub reference_c: f64,
    /// Valid range, °C.
    pub range_c: [f64; 2],
    /// Accelerometer offset polynomials (row = axis: coefficients of dT, dT², dT³), m/s² per °C^k.
    pub accel_m_s2: [[f64; 3]; 3],
    /// Gyro offset polynomials, rad/s per °C^k (`None`: the model has no gyro-bias drift).
    pub gyro_rad_s: Option<[[f64; 3]; 3]>,
    /// Largest effect of the scale factors' temperature dependence over the range at 1 g, g.
    pub dropped_scale_g: f64,
}

/// The per-axis thermal offsets of `input`'s temperature model: the driver's reading drifts by
/// `c·P_i(dT)` (zero biases, docs/model.md §9) and the gyro's by `B_j(dT)`.
pub fn thermal(input: &ExportInput<'_>, p: &PerAxis) -> Option<Thermal> {
    let t = input.cal.temperature.as_ref()?;
    let c = p.driver_scale;
    let poly = |k: &[f64; 3], x: f64| x * (k[0] + x * (k[1] + x * k[2]));
    let dropped = t
        .check_points()
        .map(|temp| {
            (0..3)
                .map(|i| poly(&t.scale_rel_per_c[i], temp - t.reference_c).abs())
                .fold(0.0, f64::max)
        })
        .fold(0.0, f64::max);
    Some(Thermal {
        reference_c: t.reference_c,
        range_c: t.valid_range_c,
        accel_m_s2: t.zero_bias_out_per_c.map(|r| r.map(|v| v * c)),
        gyro_rad_s: t.gyro_bias_rad_s_per_c,
        dropped_scale_g: dropped,
    })
}

fn thermal_caveat(w: &mut String, th: &Thermal) {
    let _ = writeln!(
        w,
        "# Temperature model (reference {} degC, valid {}..{} degC): zero-bias and gyro-bias drift held\n\
         # exactly; NOT HELD: the scale factors' drift, up to {:.3} mg at 1 g over the valid range.",
        th.reference_c,
        th.range_c[0],
        th.range_c[1],
        th.dropped_scale_g * 1e3
    );
}

/// PX4's `TC_A0_*` (and with the gyro's id and a gyro-bias drift, `TC_G0_*`): `x0 = 0` (the offset
/// at the reference is `CAL_*_xOFF`), `x1..x3` our polynomial in the driver's units.
fn px4_thermal(
    input: &ExportInput<'_>,
    p: &PerAxis,
    device_id: u32,
    w: &mut String,
) -> Result<Values, ExportError> {
    let Some(th) = thermal(input, p) else {
        return Ok(Values::new());
    };
    thermal_caveat(w, &th);
    let mut v = Values::new();
    let mut block = |prefix: &str, enable: &str, id: u32, poly: &[[f64; 3]; 3]| {
        v.push((enable.to_string(), 1.0, true));
        v.push((format!("{prefix}_ID"), f64::from(id as i32), true));
        v.push((format!("{prefix}_TREF"), th.reference_c, false));
        v.push((format!("{prefix}_TMIN"), th.range_c[0], false));
        v.push((format!("{prefix}_TMAX"), th.range_c[1], false));
        for k in 0..4 {
            for (axis, row) in poly.iter().enumerate() {
                let value = if k == 0 { 0.0 } else { row[k - 1] };
                v.push((format!("{prefix}_X{k}_{axis}"), value, false));
            }
        }
    };
    let o = input.options;
    let (n, gn) = (o.slot.unwrap_or(0), o.gyro_slot.or(o.slot).unwrap_or(0));
    block(
        &format!("TC_A{n}"),
        "TC_A_ENABLE",
        device_id,
        &th.accel_m_s2,
    );
    match (th.gyro_rad_s, o.gyro_device_id) {
        (Some(g), Some(id)) => block(&format!("TC_G{gn}"), "TC_G_ENABLE", id, &g),
        (Some(_), None) => {
            let _ = writeln!(
                w,
                "# TC_G{gn}_* NOT WRITTEN: PX4 applies them only to the gyro whose id is TC_G{gn}_ID; give {}.",
                input.options.spelling.given(UserOption::GyroDeviceId, "ID")
            );
        }
        (None, _) => {}
    }
    Ok(v)
}

/// ArduPilot's fixed reference of its thermal polynomials, °C (`TEMP_REFERENCE`).
const ARDUPILOT_TCAL_REFERENCE_C: f64 = 35.0;
/// ArduPilot stores the thermal coefficients multiplied by this (`SCALE_FACTOR`).
const ARDUPILOT_TCAL_SCALE: f64 = 1e6;

/// Our cubic `P(y)` (no constant, `y = T − T_ref`) as ArduPilot's `p(x)` about 35 °C, `x = T − 35`:
/// `p(x) = P(x + d) − P(d)` with `d = 35 − T_ref`, so that `p(T − 35) − p(T_ref − 35) = P(T − T_ref)`.
fn recentred(k: &[f64; 3], reference_c: f64) -> [f64; 3] {
    let d = ARDUPILOT_TCAL_REFERENCE_C - reference_c;
    [
        k[0] + 2.0 * k[1] * d + 3.0 * k[2] * d * d,
        k[1] + 3.0 * k[2] * d,
        k[2],
    ]
}

/// ArduPilot's `INS_TCAL1_*` and the calibration temperatures `INS_ACC1_CALTEMP`, `INS_GYR1_CALTEMP`
/// (our reference: the offsets and scales hold there).
fn ardupilot_thermal(input: &ExportInput<'_>, p: &PerAxis, w: &mut String) -> Values {
    let Some(th) = thermal(input, p) else {
        return Values::new();
    };
    thermal_caveat(w, &th);
    let k = input.options.slot.unwrap_or(0) + 1;
    let mut v: Values = vec![
        (format!("INS_TCAL{k}_ENABLE"), 1.0, true),
        (format!("INS_TCAL{k}_TMIN"), th.range_c[0], false),
        (format!("INS_TCAL{k}_TMAX"), th.range_c[1], false),
        (format!("INS_ACC{k}_CALTEMP"), th.reference_c, false),
    ];
    let mut polys = vec![("ACC", th.accel_m_s2)];
    match th.gyro_rad_s {
        Some(g) => {
            v.push((format!("INS_GYR{k}_CALTEMP"), th.reference_c, false));
            polys.push(("GYR", g));
        }
        None => {
            let _ = writeln!(
                w,
                "# INS_TCAL1_GYR*: UNDETERMINED (the model has no gyro-bias drift); not written."
            );
        }
    }
    let tk = k;
    for (name, poly) in &polys {
        let q: Vec<[f64; 3]> = poly.iter().map(|k| recentred(k, th.reference_c)).collect();
        for k in 0..3 {
            for (axis, row) in ["X", "Y", "Z"].iter().zip(&q) {
                v.push((
                    format!("INS_TCAL{tk}_{name}{}_{axis}", k + 1),
                    row[k] * ARDUPILOT_TCAL_SCALE,
                    false,
                ));
            }
        }
    }
    v
}

/// ArduPilot's documented range of a parameter (its `@Range` metadata in
/// `libraries/AP_InertialSensor/AP_InertialSensor.cpp`), if any.
fn ardupilot_range(name: &str) -> Option<(f64, f64)> {
    let acc = name.starts_with("INS_ACC");
    if acc && name.contains("SCAL_") {
        Some((0.8, 1.2))
    } else if acc && name.contains("OFFS_") {
        Some((-3.5, 3.5))
    } else if name.starts_with("INS_TCAL") && (name.ends_with("_TMIN") || name.ends_with("_TMAX")) {
        Some((-70.0, 80.0))
    } else {
        None
    }
}

/// Largest device id ArduPilot's parameter protocol carries exactly: its values travel as `float`
/// (MAVLink's `PARAM_SET`), exact for whole numbers up to 2²⁴.
const ARDUPILOT_EXACT_ID_LIMIT: u32 = 1 << 24;

/// A device id as an ArduPilot `INS_*_ID` value, refused where the parameter protocol would round it.
fn ardupilot_id(
    name: &'static str,
    option: UserOption,
    spelling: Spelling,
    id: u32,
) -> Result<(String, f64, bool), ExportError> {
    if id >= ARDUPILOT_EXACT_ID_LIMIT {
        return Err(ExportError::IdNotExact {
            name,
            option,
            spelling,
            id,
        });
    }
    Ok((name.into(), f64::from(id), true))
}

/// What a user must do after loading the ArduPilot file, what persists, and how to check it took.
fn ardupilot_after_loading(w: &mut String, gyro_written: bool) {
    let _ = writeln!(
        w,
        "# Load: Mission Planner, Config > Full Parameter List > Load from file, then Write Params; or\n\
         # MAVProxy `param load FILE` (mavproxy_param.py: sets each parameter the file names, the others\n\
         # untouched). Then reboot. At start-up ArduPilot compares each INS_ACC*_ID with the\n\
         # accelerometer it detects in that slot (AP_InertialSensor::register_accel) and counts the\n\
         # offsets and scales below as a calibration only when they match. Check: no pre-arm message\n\
         # \"3D Accel calibration needed\" (accel_calibrated_ok_all wants every accelerometer\n\
         # calibrated), and the INS_ACC*_ID the parameter list shows after the reboot equal these."
    );
    if gyro_written {
        let _ = writeln!(
            w,
            "# INS_GYR*OFFS_* persist only with INS_GYR_CAL = 0 (never): with its default 1 (start-up)\n\
             # ArduPilot measures the gyro offsets again at every boot, the vehicle still, and replaces\n\
             # these. Keep 1 unless the vehicle cannot be still at boot."
        );
    }
}

/// An ArduPilot parameter file (`NAME,VALUE`, as Mission Planner saves and loads).
///
/// `INS_ACC_ID` (and `INS_GYR_ID` with the gyro's offsets) are the device ids the calibration is for:
/// `AP_InertialSensor::register_accel` (`ArduPilot/ardupilot`
/// `libraries/AP_InertialSensor/AP_InertialSensor.cpp`) marks an accelerometer whose saved
/// `INS_ACC_ID` is absent or differs from the detected one as not calibrated, and
/// `accel_calibrated_ok_all` then fails the pre-arm check; so the id is required, as PX4's is.
pub(crate) fn render_ardupilot(input: &ExportInput<'_>) -> Result<String, ExportError> {
    render_ardupilot_slots(std::slice::from_ref(input))
}

/// ArduPilot's per-slot id names (`AP_InertialSensor.cpp`: `INS_ACC_ID`, `INS_ACC2_ID`, `INS_ACC3_ID`).
const ARDUPILOT_ACC_ID: [&str; 3] = ["INS_ACC_ID", "INS_ACC2_ID", "INS_ACC3_ID"];
const ARDUPILOT_GYR_ID: [&str; 3] = ["INS_GYR_ID", "INS_GYR2_ID", "INS_GYR3_ID"];

/// Several IMUs' calibrations in one ArduPilot file, each in its slot (`ExportOptions::slot`).
pub fn render_ardupilot_slots(inputs: &[ExportInput<'_>]) -> Result<String, ExportError> {
    let (mut s, mut lines, mut gyro_written) = (String::new(), String::new(), false);
    for input in inputs {
        let (comments, slot_lines, gyro) = ardupilot_slot(input)?;
        s.push_str(&comments);
        lines.push_str(&slot_lines);
        gyro_written |= gyro;
    }
    ardupilot_after_loading(&mut s, gyro_written);
    s.push_str(&lines);
    Ok(s)
}

/// One calibration's comments and `NAME,VALUE` lines in its slot, and whether gyro offsets are
/// among them.
fn ardupilot_slot(input: &ExportInput<'_>) -> Result<(String, String, bool), ExportError> {
    let p = per_axis(input, "ArduPilot")?;
    let o = input.options;
    let n = o.slot.unwrap_or(0);
    let no_slot = |slot| ExportError::NoSuchSlot {
        autopilot: Autopilot::ArduPilot,
        slot,
    };
    let id_name = *ARDUPILOT_ACC_ID.get(usize::from(n)).ok_or(no_slot(n))?;
    let gn = o.gyro_slot.unwrap_or(n);
    let gyr_id_name = *ARDUPILOT_GYR_ID.get(usize::from(gn)).ok_or(no_slot(gn))?;
    let device_id = o.device_id.ok_or(ExportError::DeviceIdRequired {
        autopilot: Autopilot::ArduPilot,
        id_parameter: id_name,
        spelling: o.spelling,
    })?;
    let unit = input.cal.statics.output_unit.symbol();
    let mut s = String::new();
    caveats(&mut s, input, &p, "ArduPilot");
    let _ = writeln!(
        s,
        "# Slot {n} (IMU instance {n}): {id_name} = {device_id} and its offsets and scales."
    );
    let mut values = vec![ardupilot_id(
        id_name,
        UserOption::DeviceId,
        o.spelling,
        device_id,
    )?];
    let sfx = |k: u8| {
        if k == 0 {
            String::new()
        } else {
            (k + 1).to_string()
        }
    };
    values.extend(accel_values(
        &p,
        &format!("INS_ACC{}OFFS_#", sfx(n)),
        &format!("INS_ACC{}SCAL_#", sfx(n)),
    ));
    let gyro_written = match (p.gyro_offset_rad_s, o.gyro_device_id) {
        (Some(b), Some(id)) => {
            values.push(ardupilot_id(
                gyr_id_name,
                UserOption::GyroDeviceId,
                o.spelling,
                id,
            )?);
            for (i, axis) in ["X", "Y", "Z"].iter().enumerate() {
                values.push((format!("INS_GYR{}OFFS_{axis}", sfx(gn)), b[i], false));
            }
            true
        }
        (Some(_), None) => {
            let _ = writeln!(
                s,
                "# Gyro offsets NOT WRITTEN: ArduPilot keeps INS_GYR{}OFFS_* for the gyro whose id is\n\
                 # {gyr_id_name}; give {} to write them.",
                sfx(gn),
                o.spelling.given(UserOption::GyroDeviceId, "ID")
            );
            false
        }
        (None, _) => false,
    };
    values.extend(ardupilot_thermal(input, &p, &mut s));
    let mut lines = String::new();
    for (name, v, int) in &values {
        if *int {
            let _ = writeln!(lines, "{name},{}", *v as i64);
            continue;
        }
        let text = f32_text(name, *v, input.options.spelling)?;
        if let Some((lo, hi)) = ardupilot_range(name) {
            if !(lo..=hi).contains(v) {
                check_range(input, &p, unit, name, *v, (lo, hi), &mut s)?;
            }
        }
        let _ = writeln!(lines, "{name},{text}");
    }
    Ok((s, lines, gyro_written))
}

/// A value outside ArduPilot's documented range: refused, or, allowed ([`UserOption::AllowOutOfRange`]), written
/// with a `# WARNING:` line.
fn check_range(
    input: &ExportInput<'_>,
    p: &PerAxis,
    unit: &str,
    name: &str,
    v: f64,
    (lo, hi): (f64, f64),
    s: &mut String,
) -> Result<(), ExportError> {
    let hint = if name.contains("OFFS_") {
        format!(
            " m/s² (the driver's reading at zero specific force, c*u0 with c = {} m/s² per {unit}: \
             the driver must remove the output's offset, or the scale c is wrong)",
            p.driver_scale
        )
    } else {
        format!(
            " (g*[(K*A)^-1]_ii / c with c = {} m/s² per {unit}: is {} the driver's true scale?)",
            p.driver_scale,
            input.options.spelling.name(UserOption::DriverScale)
        )
    };
    let e = ExportError::OutOfRange {
        name: name.to_string(),
        value: v,
        target: "ArduPilot",
        lo,
        hi,
        hint,
        spelling: input.options.spelling,
    };
    if !input.options.allow_out_of_range {
        return Err(e);
    }
    let _ = writeln!(
        s,
        "# WARNING: {name} = {v} is outside ArduPilot's documented range {lo}..{hi}; written \
         because of {}",
        input.options.spelling.switch(UserOption::AllowOutOfRange)
    );
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::export::consumer_tests::handheld_unit;
    use crate::export::{render, ExportFormat, STANDARD_GRAVITY_M_S2};
    use estimator::unit_file::UnitFile;
    use shared::OutputUnit;

    /// The driver scale comes from the output unit, the same in every format: 1 for m/s², standard
    /// gravity for g, refused without <DriverScale> for V and LSB (only the driver knows it).
    #[test]
    fn driver_scale_follows_the_output_unit_in_every_format() {
        let cal = handheld_unit();
        let unit = UnitFile::from_calibration(&cal, None, None);
        let mut input = ExportInput::for_tests(&unit, cal);
        input.options.device_id = Some(1);
        for format in ["PX4", "ArduPilot", "Kalibr"] {
            assert_eq!(input.driver_scale(format).unwrap(), 1.0);
        }
        // CAL_ACC0_XSCALE = g·[(K·A)⁻¹]_xx: about g/k_x, not (g/k_x)·(mean k/g), 0.34 % more here.
        let p = per_axis(&input, "PX4").unwrap();
        let g = cal.gravity_m_s2;
        assert!((p.scale[0] - g / 9.83).abs() < 5e-4, "{}", p.scale[0]);
        let text = render(&input, ExportFormat::Px4).unwrap();
        assert!(text.contains("c = 1.0 m/s^2 per m/s2"), "{text}");
        let mut in_g = cal;
        in_g.statics.output_unit = OutputUnit::StandardGravity;
        in_g.statics.scale_out_per_g = [1.001, 0.998, 1.0];
        let input_g = ExportInput::for_tests(&unit, in_g);
        assert_eq!(input_g.driver_scale("PX4").unwrap(), STANDARD_GRAVITY_M_S2);
        for (out_unit, symbol) in [(OutputUnit::Volts, "V"), (OutputUnit::Lsb, "LSB")] {
            let mut raw = shared::params::PAPER_UNIT;
            raw.statics.output_unit = out_unit;
            let input = ExportInput {
                options: input.options,
                ..ExportInput::for_tests(&unit, raw)
            };
            for format in [
                ExportFormat::Px4,
                ExportFormat::Ardupilot,
                ExportFormat::KalibrIntrinsics,
            ] {
                let e = render(&input, format).unwrap_err();
                assert!(matches!(e, ExportError::DriverScaleRequired { .. }), "{e}");
                let m = e.to_string();
                assert!(m.contains("<DriverScale>") && m.contains(symbol), "{m}");
            }
        }
    }

    /// ArduPilot's documented ranges: a V unit's offset (c·u0 ≈ 59 m/s² at c = g/k) and an absurd
    /// scale are refused, or written with a warning when allowed.
    #[test]
    fn ardupilot_refuses_values_outside_its_documented_ranges() {
        let unit = UnitFile::paper_unit();
        let cal = unit.to_calibration().unwrap();
        let mut input = ExportInput::for_tests(&unit, cal);
        input.options.device_id = Some(1);
        input.driver_scale_m_s2_per_out = Some(cal.gravity_m_s2 / 0.4);
        let e = render_ardupilot(&input).unwrap_err();
        assert!(
            matches!(e, ExportError::OutOfRange { ref name, .. } if name == "INS_ACCOFFS_X"),
            "{e}"
        );
        assert!(e.to_string().contains("-3.5..3.5"), "{e}");
        input.driver_scale_m_s2_per_out = Some(1e-3);
        let e = render_ardupilot(&input).unwrap_err();
        assert!(
            matches!(e, ExportError::OutOfRange { ref name, .. } if name == "INS_ACCSCAL_X"),
            "{e}"
        );
        assert!(e.to_string().contains("0.8..1.2"), "{e}");
        input.options.allow_out_of_range = true;
        let text = render_ardupilot(&input).unwrap();
        let warnings = text
            .lines()
            .filter(|l| l.starts_with("# WARNING: INS_ACCSCAL_"))
            .count();
        assert_eq!(warnings, 3, "{text}");
    }

    /// Called from Python, every refusal an export makes names Python's keywords, never a flag,
    /// outside a quoted `host` command (the command line's own words are checked above).
    #[test]
    fn refusals_name_the_callers_keywords() {
        let unit = UnitFile::paper_unit();
        let cal = unit.to_calibration().unwrap();
        let mut input = ExportInput::for_tests(&unit, cal);
        input.options.spelling = recording::testkit::KEYWORD_SPELLING;
        input.driver_scale_m_s2_per_out = Some(cal.gravity_m_s2 / 0.4);
        let mut seen = vec![(
            render(
                &ExportInput {
                    driver_scale_m_s2_per_out: None,
                    ..input
                },
                ExportFormat::Px4,
            )
            .unwrap_err(),
            "<DriverScale>=M_S2_PER_UNIT",
        )];
        for format in [ExportFormat::Px4, ExportFormat::Ardupilot] {
            seen.push((render(&input, format).unwrap_err(), "<DeviceId>=ID"));
        }
        seen.push((
            render(&input, ExportFormat::Kalibr).unwrap_err(),
            "<Noise>=\"DIR/noise.json\"",
        ));
        input.options.device_id = Some(1);
        seen.push((
            render(&input, ExportFormat::Ardupilot).unwrap_err(),
            "<AllowOutOfRange>=True",
        ));
        input.driver_scale_m_s2_per_out = Some(1e300);
        seen.push((
            render(&input, ExportFormat::Px4).unwrap_err(),
            "<DriverScale>",
        ));
        for (e, keyword) in seen {
            let m = e.to_string();
            assert!(m.contains(keyword), "{keyword}: {m}");
            // A `host …` command line (the noise analysis is one) keeps its flags.
            let outside_commands: String = m.split('`').step_by(2).collect();
            assert!(!outside_commands.contains(" --"), "a flag in: {m}");
        }
    }

    /// Each bad scale gets its own message, in every format: never "zero scale factor".
    #[test]
    fn bad_scales_are_named_for_what_they_are() {
        let cal = handheld_unit();
        let unit = UnitFile::from_calibration(&cal, None, None);
        let mut input = ExportInput::for_tests(&unit, cal);
        input.options.device_id = Some(1);
        input.driver_scale_m_s2_per_out = Some(1e300);
        for format in [
            ExportFormat::Px4,
            ExportFormat::Ardupilot,
            ExportFormat::KalibrIntrinsics,
        ] {
            let e = render(&input, format).unwrap_err();
            assert!(
                matches!(e, ExportError::NotRepresentable { .. }),
                "{format:?}: {e}"
            );
            assert!(!e.to_string().contains("zero scale"), "{e}");
        }
        for bad in [-1.0, 0.0, f64::NAN, f64::INFINITY] {
            input.driver_scale_m_s2_per_out = Some(bad);
            let e = render(&input, ExportFormat::Px4).unwrap_err();
            assert!(matches!(e, ExportError::DriverScale(..)), "{e}");
            assert!(e.to_string().contains("positive, finite"), "{e}");
        }
        let mut negative = shared::params::PAPER_UNIT;
        negative.statics.scale_out_per_g[1] = -0.398;
        let mut unit = UnitFile::from_calibration(&negative, None, None);
        unit.unit_id = Some("a1b2c3d4e5f60718293a4b5c".into());
        let mut input = ExportInput::for_tests(&unit, negative);
        input.driver_scale_m_s2_per_out = Some(24.5);
        input.options.device_id = Some(1);
        for format in [
            ExportFormat::CHeader,
            ExportFormat::FusionC,
            ExportFormat::Json,
            ExportFormat::Px4,
            ExportFormat::Plain,
        ] {
            let e = render(&input, format).unwrap_err();
            assert!(
                matches!(
                    e,
                    ExportError::NegativeScale(crate::calibration_guard::ScaleError {
                        axis: "y",
                        ..
                    })
                ),
                "{format:?}: {e}"
            );
            assert!(
                shared::chain::Chain(&e)
                    .to_string()
                    .contains("negative scale factor (-0.398 V per g)"),
                "{e}"
            );
        }
    }

    /// PX4 needs the accelerometer's device id (refused without it) and writes QGroundControl's
    /// five columns with the vehicle's ids; gyro offsets need the gyro's id.
    #[test]
    fn px4_file_carries_the_device_ids_and_the_vehicles_ids() {
        let cal = handheld_unit();
        let unit = UnitFile::from_calibration(&cal, None, None);
        let mut input = ExportInput::for_tests(&unit, cal);
        let e = render_px4(&input).unwrap_err();
        assert!(e.to_string().contains("<DeviceId>"), "{e}");
        input.options.device_id = Some(3_000_000_000);
        input.options.sysid = 42;
        input.options.compid = 1;
        let text = render_px4(&input).unwrap();
        assert!(
            text.contains("42\t1\tCAL_ACC0_ID\t-1294967296\t6"),
            "{text}"
        );
        assert!(!text.contains("\tCAL_GYRO0"), "{text}");
        assert!(text.contains("<GyroDeviceId>"), "{text}");
        input.options.gyro_device_id = Some(2_359_306);
        let text = render_px4(&input).unwrap();
        assert!(text.contains("42\t1\tCAL_GYRO0_ID\t2359306\t6"), "{text}");
        let b = cal.gyro.unwrap().bias_rad_s[0] as f32;
        assert!(
            text.contains(&format!("42\t1\tCAL_GYRO0_XOFF\t{b}\t9")),
            "{text}"
        );
    }
}
