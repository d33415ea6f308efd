//! Each format read the way its consumer reads it, its correction computed by an independent
//! implementation of the consumer's own formula (written here from the consumer's source, cited at
//! each), against `host apply`'s path ([`crate::apply::Applier`], the device's `f32` compensator) on
//! the same raw rows. The difference is what the format cannot hold; each test states its bound and
//! prints the largest difference (`cargo test -p host --lib consumer_tests -- --nocapture`), the
//! figures of the table in `docs/tools.md`.

use super::*;
use crate::apply::Applier;
use shared::forward::{BodyMotion, ForwardModel};
use shared::{BodyAngularAccel, BodyRate, BodySpecificForce, GyroCorrection, LeverMode};
use std::collections::HashMap;

/// A hand-held calibration's unit: output in m/s² (a logger's), the paper's ~1° installation angles
/// and lever arms, a typical MEMS gyro.
pub(super) fn handheld_unit() -> Calibration {
    let mut cal = shared::params::PAPER_UNIT;
    cal.statics.output_unit = OutputUnit::MetresPerSecondSquared;
    cal.statics.scale_out_per_g = [9.83, 9.85, 9.84];
    cal.statics.zero_bias_out = [0.05, -0.03, 0.08];
    cal.gyro = Some(firmware::paper_unit::typical_gyro());
    cal
}

/// One raw row: outputs, the gyro's reading (rad/s), and the true body rate.
#[derive(Clone, Copy, Debug)]
pub(super) struct RawRow {
    pub u: [f64; 3],
    pub w_rad_s: [f64; 3],
    pub omega_rad_s: [f64; 3],
}

fn gyro_reading(g: &GyroCorrection, omega: &[f64; 3]) -> [f64; 3] {
    std::array::from_fn(|i| linalg::dot(&g.matrix[i], omega) + g.bias_rad_s[i])
}

/// Segments of raw rows of `cal`'s unit: still attitudes, then constant-rate spins (ω̇ = 0, the
/// device's ω̇ estimate is then exactly 0 too) about several axes up to 200 °/s.
pub(super) fn segments(cal: &Calibration) -> Vec<Vec<RawRow>> {
    let model = ForwardModel::new(cal).unwrap();
    let gyro = cal.gyro.unwrap_or(GyroCorrection::PERFECT);
    let g = cal.gravity_m_s2;
    let ups = [
        [1.0, 0.0, 0.0],
        [0.0, -1.0, 0.0],
        [0.0, 0.0, 1.0],
        [0.6, 0.0, -0.8],
        [0.48, 0.6, 0.64],
    ];
    let spins = [
        [0.0, 0.0, 200.0],
        [0.0, -150.0, 0.0],
        [100.0, 0.0, 0.0],
        [80.0, 80.0, -80.0],
    ];
    let mut out = Vec::new();
    for (k, up) in ups.iter().enumerate() {
        for spin in std::iter::once(&[0.0; 3]).chain(spins.iter().skip(k % 2)) {
            let omega = spin.map(f64::to_radians);
            let motion = BodyMotion {
                f_o: BodySpecificForce {
                    m_s2: up.map(|v| v * g),
                },
                omega: BodyRate { rad_s: omega },
                omega_dot: BodyAngularAccel::default(),
            };
            let row = RawRow {
                u: model.outputs(&motion).raw,
                w_rad_s: gyro_reading(&gyro, &omega),
                omega_rad_s: omega,
            };
            out.push(vec![row; 5]);
        }
    }
    out
}

/// `host apply`'s result for each row: specific force (m/s²) and corrected rate (rad/s), `f32`.
pub(super) fn reference(cal: &Calibration, segs: &[Vec<RawRow>]) -> Vec<Vec<([f32; 3], [f32; 3])>> {
    let device = shared::Compensator::new(cal, LeverMode::RateAndAcceleration).unwrap();
    segs.iter()
        .map(|seg| {
            // A segment change restarts the ω̇ estimate, as host apply does.
            let mut a = Applier::new(cal, LeverMode::RateAndAcceleration, 1000.0).unwrap();
            seg.iter()
                .map(|r| {
                    let u = r.u.map(|v| v as f32);
                    let w = r.w_rad_s.map(|v| v as f32);
                    (a.sample(&u, &w).unwrap(), device.correct_rate(&w).rad_s)
                })
                .collect()
        })
        .collect()
}

/// The largest differences from host apply: specific force at rest and in rotation (µg), rate (°/s).
#[derive(Clone, Copy, Debug, Default)]
struct Worst {
    rest_ug: f64,
    spin_ug: f64,
    deg_s: f64,
}

/// Runs `correct(u, w) -> (f m/s², ω rad/s)` over every row and returns the largest differences from
/// host apply, asserting `bound(row) -> (g, °/s)` row by row.
fn compare(
    cal: &Calibration,
    correct: impl Fn(&RawRow) -> ([f64; 3], Option<[f64; 3]>),
    bound: impl Fn(&RawRow) -> (f64, f64),
) -> Worst {
    let segs = segments(cal);
    let want = reference(cal, &segs);
    let g = cal.gravity_m_s2;
    let mut worst = Worst::default();
    for (seg, want) in segs.iter().zip(&want) {
        for (r, (f_ref, rate_ref)) in seg.iter().zip(want) {
            let (f, rate) = correct(r);
            let (bound_g, bound_deg_s) = bound(r);
            let d_g = (0..3)
                .map(|j| (f[j] - f64::from(f_ref[j])).abs() / g)
                .fold(0.0, f64::max);
            assert!(d_g <= bound_g, "{d_g} g > {bound_g} g at {r:?}");
            let at_rest = r.omega_rad_s == [0.0; 3];
            let ug = if at_rest {
                &mut worst.rest_ug
            } else {
                &mut worst.spin_ug
            };
            *ug = ug.max(d_g * 1e6);
            if let Some(rate) = rate {
                let d = (0..3)
                    .map(|j| (rate[j] - f64::from(rate_ref[j])).abs().to_degrees())
                    .fold(0.0, f64::max);
                assert!(d <= bound_deg_s, "{d} deg/s > {bound_deg_s} at {r:?}");
                worst.deg_s = worst.deg_s.max(d);
            }
        }
    }
    worst
}

fn report(format: &str, w: &Worst) {
    eprintln!(
        "{format}: largest difference from host apply {:.1} µg at rest, {:.1} µg in rotation, {:.5} °/s",
        w.rest_ug, w.spin_ug, w.deg_s
    );
}

/// The largest lever-arm term of a row, g: what the per-axis forms drop besides misalignment.
fn lever_g(cal: &Calibration, r: &RawRow) -> f64 {
    let w2: f64 = r.omega_rad_s.iter().map(|v| v * v).sum();
    let r_max = cal
        .lever_arms
        .r_m
        .iter()
        .map(linalg::norm)
        .fold(0.0, f64::max);
    w2 * r_max / cal.gravity_m_s2
}

/// QGroundControl's loader (`mavlink/qgroundcontrol` `src/FactSystem/ParameterManager.cc`,
/// `readParametersFromStream`): `#` lines skipped, the others split on tabs into exactly five fields
/// `sysid compid name value type`; a sysid other than the vehicle's refuses the file.
fn qgc_load(text: &str, vehicle_sysid: u8) -> HashMap<String, f64> {
    let mut v = HashMap::new();
    for line in text.lines().filter(|l| !l.starts_with('#')) {
        let f: Vec<&str> = line.split('\t').collect();
        assert_eq!(f.len(), 5, "{line}");
        assert_eq!(f[0].parse::<u8>().unwrap(), vehicle_sysid, "{line}");
        let value = match f[4] {
            // MAV_PARAM_TYPE_REAL32: PX4 stores a float.
            "9" => f64::from(f[3].parse::<f32>().unwrap()),
            // MAV_PARAM_TYPE_INT32.
            "6" => f64::from(f[3].parse::<i32>().unwrap()),
            t => panic!("type {t} in {line}"),
        };
        v.insert(f[2].to_string(), value);
    }
    v
}

/// ArduPilot's loader (`ArduPilot/ardupilot` `libraries/AP_Param/AP_Param.cpp`, `parse_param_line`):
/// `#` lines skipped, name and value split on `", =\t"`, the value read as a float.
fn ardupilot_load(text: &str) -> HashMap<String, f64> {
    text.lines()
        .filter(|l| !l.starts_with('#') && !l.trim().is_empty())
        .map(|l| {
            let mut t = l.split(|c| ", =\t".contains(c)).filter(|s| !s.is_empty());
            let name = t.next().unwrap();
            assert!(name.len() <= 16, "AP_MAX_NAME_SIZE: {name}");
            let value: f32 = t.next().unwrap().parse().unwrap();
            (name.to_string(), f64::from(value))
        })
        .collect()
}

/// PX4's and ArduPilot's per-axis correction in `f32` (PX4 `Accelerometer.hpp`/`Gyroscope.hpp`
/// `Correct()`, ArduPilot `AP_InertialSensor_Backend.cpp` `_rotate_and_correct_*`, rotation none):
/// `a = (a_m − off) ∘ scale`, `ω = w_m − gyro_off`, with `a_m = c·U` from the driver.
fn per_axis_correct(
    v: &HashMap<String, f64>,
    names: &[String; 9],
    c: f64,
    r: &RawRow,
) -> ([f64; 3], Option<[f64; 3]>) {
    let get = |n: &str| v[n] as f32;
    let f = std::array::from_fn(|i| {
        let a_m = (c * r.u[i]) as f32;
        f64::from((a_m - get(&names[i])) * get(&names[3 + i]))
    });
    let rate = v
        .contains_key(&names[6])
        .then(|| std::array::from_fn(|i| f64::from(r.w_rad_s[i] as f32 - get(&names[6 + i]))));
    (f, rate)
}

fn names(pattern: [&str; 3]) -> [String; 9] {
    std::array::from_fn(|k| pattern[k / 3].replace('#', ["X", "Y", "Z"][k % 3]))
}

#[test]
fn px4_file_as_qgroundcontrol_loads_it_corrects_like_host_apply_within_what_it_holds() {
    let cal = handheld_unit();
    let unit = UnitFile::from_calibration(&cal, None, None);
    let mut input = ExportInput::for_tests(&unit, cal);
    input.options.device_id = Some(2_490_378);
    input.options.gyro_device_id = Some(2_359_306);
    input.options.sysid = 7;
    let text = params::render_px4(&input).unwrap();
    assert!(
        text.contains("reboot") && !text.contains("next boot"),
        "{text}"
    );
    let v = qgc_load(&text, 7);
    assert_eq!(v["CAL_ACC0_ID"], 2_490_378.0);
    assert_eq!(v["CAL_GYRO0_ID"], 2_359_306.0);
    let p = params::per_axis(&input, "PX4").unwrap();
    // A calibration in m/s²: the driver's reading is the output itself.
    assert_eq!(p.driver_scale, 1.0);
    let n = names(["CAL_ACC0_#OFF", "CAL_ACC0_#SCALE", "CAL_GYRO0_#OFF"]);
    let w = compare(
        &cal,
        |r| per_axis_correct(&v, &n, 1.0, r),
        |r| {
            let w_deg_s = linalg::norm(&r.omega_rad_s).to_degrees() * 1.01;
            (
                p.dropped_cross_axis_g * 1.05 + 2.0 * lever_g(&cal, r) + 2e-5,
                p.dropped_gyro_deg_s_at_100 * w_deg_s / 100.0 + 1e-4,
            )
        },
    );
    report("px4", &w);
    // Not vacuous: the paper's ~1° misalignments cost tens of mg, the gyro's 0.5 % a degree per second.
    assert!(
        w.rest_ug > 0.3e6 * p.dropped_cross_axis_g && w.rest_ug > 5e3,
        "{w:?}"
    );
    assert!(w.deg_s > 0.5, "{w:?}");
}

/// ArduPilot's accelerometer pre-arm check for the first accelerometer, from its sources
/// (`ArduPilot/ardupilot` `libraries/AP_InertialSensor/AP_InertialSensor.cpp`):
/// `register_accel` marks the accelerometer detected with id `detected` as id-ok only when a saved
/// `INS_ACC_ID` equals it (`_accel_id(i).load()` and the comparison), and `accel_calibrated_ok_all`
/// then needs id-ok, offsets not all exactly zero and scales not all exactly zero; a failure is
/// `AP_Arming::ins_checks`' "3D Accel calibration needed". `saved` are the parameters loaded.
fn ardupilot_accel_calibrated_ok(saved: &HashMap<String, f64>, detected: u32) -> bool {
    let id_ok = saved
        .get("INS_ACC_ID")
        .is_some_and(|id| *id as f32 as i64 == i64::from(detected));
    let vector =
        |p: &str| ["X", "Y", "Z"].map(|a| saved.get(&format!("{p}{a}")).copied().unwrap_or(0.0));
    let is_zero = |v: [f64; 3]| v.iter().all(|x| *x == 0.0);
    id_ok && !is_zero(vector("INS_ACCOFFS_")) && !is_zero(vector("INS_ACCSCAL_"))
}

/// The ArduPilot file passes ArduPilot's own accelerometer pre-arm check when the id it was made
/// for is the one the vehicle detects, and fails it for another accelerometer; without the id the
/// export is refused (the file without INS_ACC_ID failed the check on every vehicle).
#[test]
fn ardupilot_file_passes_the_accelerometer_pre_arm_check_of_its_accelerometer() {
    let cal = handheld_unit();
    let unit = UnitFile::from_calibration(&cal, None, None);
    let mut input = ExportInput::for_tests(&unit, cal);
    let e = params::render_ardupilot(&input).unwrap_err();
    assert!(
        e.to_string().contains("<DeviceId>") && e.to_string().contains("INS_ACC_ID"),
        "{e}"
    );
    // An ICM-42688-P on SPI bus 1 as ArduPilot numbers it (bus type, bus, address, device type).
    input.options.device_id = Some(3_932_170);
    let text = params::render_ardupilot(&input).unwrap();
    let v = ardupilot_load(&text);
    assert!(ardupilot_accel_calibrated_ok(&v, 3_932_170), "{text}");
    assert!(!ardupilot_accel_calibrated_ok(&v, 3_932_171));
    // The file as it was written before (every line but INS_ACC_ID): refused by the check.
    let mut without = v.clone();
    without.remove("INS_ACC_ID");
    assert!(!ardupilot_accel_calibrated_ok(&without, 3_932_170));
    assert!(
        text.contains("reboot") && text.contains("3D Accel"),
        "{text}"
    );
    // The gyro's offsets need its id, and the file says they are replaced at boot unless
    // INS_GYR_CAL = 0.
    assert!(text.contains("Gyro offsets NOT WRITTEN") && !v.contains_key("INS_GYROFFS_X"));
    input.options.gyro_device_id = Some(3_932_426);
    let text = params::render_ardupilot(&input).unwrap();
    let v = ardupilot_load(&text);
    assert_eq!(v["INS_GYR_ID"], 3_932_426.0);
    assert!(text.contains("INS_GYR_CAL = 0"), "{text}");
    // An id the float parameter protocol would round is refused.
    input.options.device_id = Some(1 << 24);
    let e = params::render_ardupilot(&input).unwrap_err();
    assert!(
        matches!(e, crate::export::ExportError::IdNotExact { .. }),
        "{e}"
    );
}

#[test]
fn ardupilot_file_as_ap_param_loads_it_corrects_like_host_apply_within_what_it_holds() {
    let cal = handheld_unit();
    let unit = UnitFile::from_calibration(&cal, None, None);
    let mut input = ExportInput::for_tests(&unit, cal);
    input.options.device_id = Some(3_932_170);
    input.options.gyro_device_id = Some(3_932_426);
    let text = params::render_ardupilot(&input).unwrap();
    assert!(!text.contains("WARNING"), "{text}");
    let v = ardupilot_load(&text);
    // The two ids, the accelerometer's 6 values and the gyro's 3 offsets.
    assert_eq!(v.len(), 11);
    let p = params::per_axis(&input, "ArduPilot").unwrap();
    let n = names(["INS_ACCOFFS_#", "INS_ACCSCAL_#", "INS_GYROFFS_#"]);
    let w = compare(
        &cal,
        |r| per_axis_correct(&v, &n, 1.0, r),
        |r| {
            let w_deg_s = linalg::norm(&r.omega_rad_s).to_degrees() * 1.01;
            (
                p.dropped_cross_axis_g * 1.05 + 2.0 * lever_g(&cal, r) + 2e-5,
                p.dropped_gyro_deg_s_at_100 * w_deg_s / 100.0 + 1e-4,
            )
        },
    );
    report("ardupilot", &w);
    assert!(
        w.rest_ug > 0.3e6 * p.dropped_cross_axis_g && w.rest_ug > 5e3,
        "{w:?}"
    );
    assert!(w.deg_s > 0.5, "{w:?}");
}

/// What a YAML parser sees of the intrinsics document (Kalibr's keys, `IccSensors.py`).
#[derive(serde::Deserialize)]
struct KalibrResults {
    model: String,
    #[serde(rename = "T_i_b")]
    t_i_b: Vec<Vec<f64>>,
    accelerometers: KalibrAccel,
    gyroscopes: KalibrGyro,
    host_export_biases: KalibrBiases,
}
#[derive(serde::Deserialize)]
struct KalibrAccel {
    #[serde(rename = "M")]
    m: Vec<Vec<f64>>,
    rx_i: Vec<f64>,
    ry_i: Vec<f64>,
    rz_i: Vec<f64>,
}
#[derive(serde::Deserialize)]
struct KalibrGyro {
    #[serde(rename = "M")]
    m: Vec<Vec<f64>>,
    #[serde(rename = "C_gyro_i")]
    c_gyro_i: Vec<Vec<f64>>,
}
#[derive(serde::Deserialize)]
struct KalibrBiases {
    accelerometer: Vec<f64>,
    gyroscope: Vec<f64>,
}

fn m3(v: &[Vec<f64>]) -> nalgebra::Matrix3<f64> {
    nalgebra::Matrix3::from_fn(|i, j| v[i][j])
}

fn v3(v: &[f64]) -> nalgebra::Vector3<f64> {
    nalgebra::Vector3::new(v[0], v[1], v[2])
}

#[test]
fn kalibr_intrinsics_inverted_as_kalibr_models_them_correct_like_host_apply() {
    let cal = handheld_unit();
    let unit = UnitFile::from_calibration(&cal, None, None);
    let input = ExportInput::for_tests(&unit, cal);
    let text = kalibr::render_intrinsics(&input).unwrap();
    let k: KalibrResults = serde_yaml::from_str(&text).unwrap();
    assert_eq!(k.model, "scale-misalignment-size-effect");
    let t = nalgebra::Matrix4::from_fn(|i, j| k.t_i_b[i][j]);
    let c_i_b: nalgebra::Matrix3<f64> = t.fixed_view::<3, 3>(0, 0).into();
    let r_b_i = -(c_i_b.transpose() * t.fixed_view::<3, 1>(0, 3));
    let (m_a, b_a) = (
        m3(&k.accelerometers.m),
        v3(&k.host_export_biases.accelerometer),
    );
    let rs = [
        &k.accelerometers.rx_i,
        &k.accelerometers.ry_i,
        &k.accelerometers.rz_i,
    ]
    .map(|r| r_b_i + c_i_b.transpose() * v3(r));
    let c_gyro_b = m3(&k.gyroscopes.c_gyro_i) * c_i_b;
    let m_g = m3(&k.gyroscopes.m);
    let b_g = v3(&k.host_export_biases.gyroscope);
    // Kalibr's models (`kalibr/python/kalibr_imu_camera_calibration/IccSensors.py`,
    // ScaledMisalignedSizeEffectImu.addAccelerometerErrorTerms and ScaledMisalignedImu.
    // addGyroscopeErrorTerms, no g-sensitivity): a_m = M (C_i_b f + Σ_k I_k C_i_b (ω̇×r_k + ω×(ω×r_k)))
    // + b and w = M_g C_gyro_b ω + b_g, inverted for f and ω.
    let correct = |r: &RawRow| {
        let w = v3(&r.w_rad_s);
        let omega = (m_g * c_gyro_b).try_inverse().unwrap() * (w - b_g);
        let a_m = v3(&r.u); // the driver's scale is 1 for a calibration in m/s²
        let mut inner = m_a.try_inverse().unwrap() * (a_m - b_a);
        for (axis, rk) in rs.iter().enumerate() {
            let lever = c_i_b * omega.cross(&omega.cross(rk));
            inner[axis] -= lever[axis];
        }
        let f = c_i_b.transpose() * inner;
        ([f[0], f[1], f[2]], Some([omega[0], omega[1], omega[2]]))
    };
    // Kalibr applies M to the axis-selected lever terms, we apply each axis's sensing direction to its
    // own point: second order (misalignment × lever term); the rest is f32 rounding of host apply.
    let w = compare(&cal, correct, |r| (0.05 * lever_g(&cal, r) + 2e-6, 2e-4));
    report("kalibr-intrinsics", &w);
}

/// The hand-held unit with a temperature model of a MEMS part's size, in m/s².
fn heated_unit() -> Calibration {
    let mut cal = handheld_unit();
    let mut t = firmware::paper_unit::typical_thermal_model();
    // The paper's 0.4 V/g model scaled to m/s² (9.8 m/s² per g).
    t.zero_bias_out_per_c = t.zero_bias_out_per_c.map(|r| r.map(|v| v * 24.5));
    cal.temperature = Some(t);
    cal
}

/// PX4's thermal offsets (`TemperatureCompensation.cpp`, `calc_thermal_offsets_3D`, f32) and
/// ArduPilot's (`AP_InertialSensor_tempcal.cpp`, `correct_sensor`), applied before the per-axis
/// correction as each does; against host apply at temperatures across and beyond the valid range.
/// The difference from host apply changes with temperature only by the scale factors' drift, which
/// neither holds (its size is what the file states).
#[test]
fn thermal_offsets_of_px4_and_ardupilot_follow_host_apply_over_temperature() {
    // Without a scale drift the thermal offsets are all the model has: held to f32 rounding.
    let mut offsets_only = heated_unit();
    if let Some(t) = offsets_only.temperature.as_mut() {
        t.scale_rel_per_c = [[0.0; 3]; 3];
    }
    for cal in [offsets_only, heated_unit()] {
        thermal_check(cal);
    }
}

fn clip(x: f32, lo: f32, hi: f32) -> f32 {
    x.max(lo).min(hi)
}

/// PX4's thermal offset (`calc_thermal_offsets_3D`): `x0 + x1 dT + x2 dT² + x3 dT³`, `dT` from
/// `TREF`, the temperature clipped to `TMIN..TMAX`, in `f32`.
fn px4_offsets(px4: &HashMap<String, f64>, prefix: &str, temp: f32) -> [f32; 3] {
    let g = |n: &str| px4[&format!("{prefix}_{n}")] as f32;
    let dt = clip(temp, g("TMIN"), g("TMAX")) - g("TREF");
    let (dt2, dt3) = (dt * dt, dt * dt * dt);
    std::array::from_fn(|i| {
        g(&format!("X0_{i}"))
            + g(&format!("X1_{i}")) * dt
            + g(&format!("X2_{i}")) * dt2
            + g(&format!("X3_{i}")) * dt3
    })
}

/// ArduPilot's thermal correction (`TCal::correct_sensor`): `p(T − 35) − p(T_cal − 35)`,
/// `p(x) = (c1 + (c2 + c3 x) x) x · 1e-6`, both temperatures clipped to `TMIN..TMAX`, in `f32`.
fn ap_offsets(ap: &HashMap<String, f64>, name: &str, caltemp: &str, temp: f32) -> [f32; 3] {
    let (lo, hi) = (ap["INS_TCAL1_TMIN"] as f32, ap["INS_TCAL1_TMAX"] as f32);
    let c = |k: usize, a: &str| ap[&format!("INS_TCAL1_{name}{k}_{a}")] as f32;
    let p = |x: f32, a: &str| (c(1, a) + (c(2, a) + c(3, a) * x) * x) * x * 1e-6;
    let tc = clip(ap[caltemp] as f32, lo, hi);
    let temp = clip(temp, lo, hi);
    std::array::from_fn(|i| {
        let a = ["X", "Y", "Z"][i];
        p(temp - 35.0, a) - p(tc - 35.0, a)
    })
}

/// The unit's raw row at rest with `up` at `temp` (the model clamped to its range, as the device
/// is), from our forward model: outputs and the gyro's reading of a small rate.
fn heated_row(cal: &Calibration, up: [f64; 3], temp: f64) -> RawRow {
    let t = cal.temperature.unwrap();
    let dt = temp.clamp(t.valid_range_c[0], t.valid_range_c[1]) - t.reference_c;
    let poly = |k: &[f64; 3]| dt * (k[0] + dt * (k[1] + dt * k[2]));
    let mut heated = *cal;
    for i in 0..3 {
        heated.statics.zero_bias_out[i] += poly(&t.zero_bias_out_per_c[i]);
    }
    let mut fm = ForwardModel::new(&heated).unwrap();
    for i in 0..3 {
        let s = 1.0 + poly(&t.scale_rel_per_c[i]);
        fm.m_out_per_g[i] = fm.m_out_per_g[i].map(|v| v * s);
    }
    let omega = [0.3, -0.2, 0.1];
    let u = fm
        .outputs(&BodyMotion {
            f_o: BodySpecificForce {
                m_s2: up.map(|v| v * cal.gravity_m_s2),
            },
            omega: BodyRate::default(),
            omega_dot: BodyAngularAccel::default(),
        })
        .raw;
    let w_cold = gyro_reading(&cal.gyro.unwrap(), &omega);
    RawRow {
        u,
        w_rad_s: std::array::from_fn(|j| w_cold[j] + poly(&t.gyro_bias_polynomials()[j])),
        omega_rad_s: [0.0; 3],
    }
}

/// host apply's specific force (one row at `temp`: the first row refreshes at once) and the device's
/// corrected rate at `temp`.
fn apply_at(cal: &Calibration, r: &RawRow, temp: f64) -> ([f64; 3], [f64; 3]) {
    let mut a = Applier::new(cal, LeverMode::RateAndAcceleration, 1000.0).unwrap();
    let row = recording::session::reader::Row {
        segment: "t",
        segment_index: 0,
        t_s: 0.0,
        u: r.u,
        w_rad_s: [0.0; 3],
        temp_c: Some(temp),
    };
    let f = a.row(&row).unwrap().map(f64::from);
    let mut dev = shared::Compensator::new(cal, LeverMode::RateAndAcceleration).unwrap();
    dev.refresh(temp as f32);
    let rate = dev.correct_rate(&r.w_rad_s.map(|v| v as f32)).rad_s;
    (f, rate.map(f64::from))
}

fn thermal_check(cal: Calibration) {
    let t = cal.temperature.unwrap();
    let unit = UnitFile::from_calibration(&cal, None, None);
    let mut input = ExportInput::for_tests(&unit, cal);
    input.options.device_id = Some(11);
    input.options.gyro_device_id = Some(12);
    let px4_text = params::render_px4(&input).unwrap();
    // PX4 starts its temperature compensation only at boot: the file says to reboot.
    assert!(px4_text.contains("apply from the next boot"), "{px4_text}");
    let px4 = qgc_load(&px4_text, 1);
    let ap = ardupilot_load(&params::render_ardupilot(&input).unwrap());
    let p = params::per_axis(&input, "PX4").unwrap();
    let th = params::thermal(&input, &p).unwrap();
    assert_eq!(px4["TC_A_ENABLE"], 1.0);
    assert_eq!(px4["TC_A0_ID"], 11.0);
    assert_eq!(ap["INS_TCAL1_ENABLE"], 1.0);
    let g = cal.gravity_m_s2;
    let names_px4 = names(["CAL_ACC0_#OFF", "CAL_ACC0_#SCALE", "CAL_GYRO0_#OFF"]);
    let names_ap = names(["INS_ACCOFFS_#", "INS_ACCSCAL_#", "INS_GYROFFS_#"]);
    let mut worst = [0.0f64; 4];
    // The largest difference itself at the reference and at two other temperatures, per format and
    // quantity (µg-able g, °/s), for the table in docs/tools.md.
    let shown = [t.reference_c, -20.0, 60.0];
    let mut at = [[0.0f64; 3]; 4];
    for up in [[1.0, 0.0, 0.0], [0.0, 0.0, -1.0], [0.6, 0.48, 0.64]] {
        let mut at_ref: Option<[[f64; 3]; 4]> = None;
        for temp in [25.0f64, -30.0, -20.0, 0.0, 40.0, 60.0, 75.0] {
            let raw = heated_row(&cal, up, temp);
            let (u, w) = (raw.u, raw.w_rad_s);
            let (f_ref, rate_ref) = apply_at(&cal, &raw, temp);
            let mut diffs = [[0.0; 3]; 4];
            for (k, (v, n, acc_off, gyr_off)) in [
                (
                    &px4,
                    &names_px4,
                    px4_offsets(&px4, "TC_A0", temp as f32),
                    px4_offsets(&px4, "TC_G0", temp as f32),
                ),
                (
                    &ap,
                    &names_ap,
                    ap_offsets(&ap, "ACC", "INS_ACC1_CALTEMP", temp as f32),
                    ap_offsets(&ap, "GYR", "INS_GYR1_CALTEMP", temp as f32),
                ),
            ]
            .into_iter()
            .enumerate()
            {
                // The thermal offset comes off the driver's reading before the per-axis correction.
                let cooled = RawRow {
                    u: std::array::from_fn(|i| u[i] - f64::from(acc_off[i])),
                    w_rad_s: std::array::from_fn(|i| w[i] - f64::from(gyr_off[i])),
                    ..raw
                };
                let (f, rate) = per_axis_correct(v, n, 1.0, &cooled);
                let rate = rate.unwrap();
                diffs[2 * k] = std::array::from_fn(|j| (f[j] - f_ref[j]) / g);
                diffs[2 * k + 1] = std::array::from_fn(|j| (rate[j] - rate_ref[j]).to_degrees());
            }
            if let Some(c) = shown.iter().position(|s| *s == temp) {
                for k in 0..4 {
                    let m = diffs[k].iter().map(|v| v.abs()).fold(0.0, f64::max);
                    at[k][c] = at[k][c].max(m);
                }
            }
            let base = *at_ref.get_or_insert(diffs);
            for (k, (d, b)) in diffs.iter().zip(&base).enumerate() {
                let change = (0..3).map(|j| (d[j] - b[j]).abs()).fold(0.0, f64::max);
                let bound = if k % 2 == 0 {
                    th.dropped_scale_g * 1.1 + 3e-6
                } else {
                    2e-4
                };
                assert!(change <= bound, "{k} at {temp} °C: {change} > {bound}");
                worst[k] = worst[k].max(change);
            }
        }
    }
    eprintln!(
        "thermal: change with temperature of the difference from host apply: px4 {:.1} µg, {:.5} °/s; \
         ardupilot {:.1} µg, {:.5} °/s (scale drift not held: {:.1} µg)",
        worst[0] * 1e6,
        worst[1],
        worst[2] * 1e6,
        worst[3],
        th.dropped_scale_g * 1e6
    );
    for (k, name) in ["px4", "ardupilot"].iter().enumerate() {
        eprintln!(
            "thermal: {name} difference from host apply at {:.0} / {:.0} / {:.0} °C: {:.0} / {:.0} / \
             {:.0} µg, {:.3} / {:.3} / {:.3} °/s",
            shown[0],
            shown[1],
            shown[2],
            at[2 * k][0] * 1e6,
            at[2 * k][1] * 1e6,
            at[2 * k][2] * 1e6,
            at[2 * k + 1][0],
            at[2 * k + 1][1],
            at[2 * k + 1][2]
        );
    }
    // Not vacuous: the zero-bias drift over the range is tens of mg, the gyro's 0.4 °/s.
    let drift_g = (0..3)
        .map(|i| {
            let k = th.accel_m_s2[i];
            let x = t.valid_range_c[0] - t.reference_c;
            (x * (k[0] + x * (k[1] + x * k[2]))).abs() / g
        })
        .fold(0.0, f64::max);
    assert!(
        drift_g > 5.0 * (worst[0].max(worst[2]) - th.dropped_scale_g).max(0.0) && drift_g > 0.01,
        "{drift_g}"
    );
}
