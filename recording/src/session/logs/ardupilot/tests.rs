use super::*;

/// ArduPilot's `_rotate_and_correct_accel` and `_rotate_and_correct_gyro` as the source writes
/// them (`AP_InertialSensor_Backend.cpp`, current master), in `f32` like the vehicle: temperature
/// term, offsets, scales, then the board rotation.
fn ardupilot_forward(
    p: &VehicleParams,
    n: u8,
    rot: Rotate,
    acc: [f64; 3],
    gyro: [f64; 3],
    temp_c: f64,
) -> ([f64; 3], [f64; 3]) {
    let g = |name: String| p.get(&name).unwrap() as f32;
    let axes = ["X", "Y", "Z"];
    let sfx = if n == 0 {
        String::new()
    } else {
        (n + 1).to_string()
    };
    let tcal = |sensor: &str, caltemp: &str, v: &mut [f32; 3]| {
        let k = n + 1;
        if p.get(&format!("INS_TCAL{k}_ENABLE")) != Some(1.0) {
            return;
        }
        let (lo, hi) = (
            g(format!("INS_TCAL{k}_TMIN")),
            g(format!("INS_TCAL{k}_TMAX")),
        );
        let t = (temp_c as f32).clamp(lo, hi);
        let tc = g(format!("INS_{caltemp}{k}_CALTEMP")).clamp(lo, hi);
        for (i, axis) in axes.iter().enumerate() {
            let c = |o: u8| g(format!("INS_TCAL{k}_{sensor}{o}_{axis}"));
            let eval = |d: f32| (c(1) + (c(2) + c(3) * d) * d) * d * 1.0e-6;
            v[i] -= eval(t - 35.0);
            v[i] += eval(tc - 35.0);
        }
    };
    let mut a = acc.map(|x| x as f32);
    tcal("ACC", "ACC", &mut a);
    for (i, axis) in axes.iter().enumerate() {
        a[i] -= g(format!("INS_ACC{sfx}OFFS_{axis}"));
        a[i] *= g(format!("INS_ACC{sfx}SCAL_{axis}"));
    }
    let mut w = gyro.map(|x| x as f32);
    tcal("GYR", "GYR", &mut w);
    for (i, axis) in axes.iter().enumerate() {
        w[i] -= g(format!("INS_GYR{sfx}OFFS_{axis}"));
    }
    (rot(a).map(f64::from), rot(w).map(f64::from))
}

/// A board rotation as `Vector3::rotate` applies it.
type Rotate = fn([f32; 3]) -> [f32; 3];

/// `Vector3::rotate(ROTATION_ROLL_180)` and `ROTATION_YAW_90` as `AP_Math/vector3.cpp` writes them.
fn roll_180(v: [f32; 3]) -> [f32; 3] {
    [v[0], -v[1], -v[2]]
}
fn yaw_90(v: [f32; 3]) -> [f32; 3] {
    [-v[1], v[0], v[2]]
}

fn params(instance: u8, orientation: f64, tcal: bool) -> VehicleParams {
    params_with(instance, orientation, tcal, &[])
}

/// [`params`], with `first` logged before the others (a later value of the same name is then a
/// change, never the value read).
fn params_with(instance: u8, orientation: f64, tcal: bool, first: &[(&str, f64)]) -> VehicleParams {
    let mut p = VehicleParams::default();
    for (name, v) in first {
        p.record(name, *v);
    }
    let mut p = Params(p, first);
    let sfx = if instance == 0 {
        String::new()
    } else {
        (instance + 1).to_string()
    };
    for (i, axis) in ["X", "Y", "Z"].iter().enumerate() {
        p.put(&format!("INS_ACC{sfx}OFFS_{axis}"), [0.94, -0.31, 0.52][i]);
        p.put(
            &format!("INS_ACC{sfx}SCAL_{axis}"),
            [1.036, 0.981, 1.012][i],
        );
        p.put(
            &format!("INS_GYR{sfx}OFFS_{axis}"),
            [0.02, -0.011, 0.005][i],
        );
    }
    p.put("AHRS_ORIENTATION", orientation);
    let k = instance + 1;
    if tcal {
        p.put(&format!("INS_TCAL{k}_ENABLE"), 1.0);
        p.put(&format!("INS_TCAL{k}_TMIN"), 10.0);
        p.put(&format!("INS_TCAL{k}_TMAX"), 60.0);
        p.put(&format!("INS_ACC{k}_CALTEMP"), 41.0);
        p.put(&format!("INS_GYR{k}_CALTEMP"), 39.0);
        for o in 1..=3 {
            for (i, axis) in ["X", "Y", "Z"].iter().enumerate() {
                let c = [3000.0, -120.0, 2.5][o - 1] * [1.0, -0.7, 0.4][i];
                p.put(&format!("INS_TCAL{k}_ACC{o}_{axis}"), c);
                p.put(&format!("INS_TCAL{k}_GYR{o}_{axis}"), c * 0.01);
            }
        }
    }
    p.0
}

/// Parameters recorded except those already given first.
struct Params<'a>(VehicleParams, &'a [(&'a str, f64)]);

impl Params<'_> {
    fn put(&mut self, name: &str, v: f64) {
        if !self.1.iter().any(|(n, _)| *n == name) {
            self.0.record(name, v);
        }
    }
}

fn raw_recording(n: usize) -> Recording {
    let mut rec = Recording::default();
    for k in 0..n {
        let s = k as f64 * 0.37;
        rec.t_s.push(k as f64 * 0.01);
        rec.acc.push([
            9.0 * s.sin(),
            9.0 * s.cos() * 0.6,
            4.0 - 3.0 * (1.3 * s).cos(),
        ]);
        rec.gyro_rad_s.push([0.3 * s.cos(), -0.2, 0.1 * s.sin()]);
    }
    rec.temp_c = Some((0..n).map(|k| 5.0 + 0.6 * k as f64).collect());
    rec
}

/// The sensor's output, corrected as ArduPilot corrects it (offsets, scales, board rotation and
/// the temperature terms, with temperatures below, inside and above TMIN..TMAX), is read back to
/// within the vehicle's `float` rounding, on each of the three instances' parameter names.
#[test]
fn ardupilots_correction_is_undone_sample_by_sample() {
    let rots: [(f64, Rotate); 2] = [(8.0, roll_180), (2.0, yaw_90)];
    for instance in 0..3u8 {
        for (orientation, rot) in rots {
            for tcal in [false, true] {
                let p = params(instance, orientation, tcal);
                let raw = raw_recording(100);
                let mut logged = raw.clone();
                for k in 0..raw.len() {
                    let temp = raw.temp_c.as_ref().unwrap()[k];
                    let (a, w) =
                        ardupilot_forward(&p, instance, rot, raw.acc[k], raw.gyro_rad_s[k], temp);
                    logged.acc[k] = a;
                    logged.gyro_rad_s[k] = w;
                }
                let note = undo(&mut logged, &p, instance).unwrap().unwrap();
                assert!(note.to_string().contains("undone"), "{note}");
                for k in 0..raw.len() {
                    for i in 0..3 {
                        let (da, dw) = (
                            logged.acc[k][i] - raw.acc[k][i],
                            logged.gyro_rad_s[k][i] - raw.gyro_rad_s[k][i],
                        );
                        assert!(
                            da.abs() < 5e-6 && dw.abs() < 1e-6,
                            "instance {instance} orientation {orientation} tcal {tcal} \
                             sample {k} axis {i}: {da} {dw}"
                        );
                    }
                }
            }
        }
    }
}

/// The rotation table against ArduPilot's own explicit formulas (`AP_Math/vector3.cpp`,
/// `Vector3::rotate`): a rotation the log names is applied as the vehicle applied it.
#[test]
fn board_rotations_match_ardupilots_vector_rotate() {
    let v = [1.0, 2.0, 3.0];
    let r = |n: f64| {
        let m = board_rotation(n).unwrap();
        std::array::from_fn::<f64, 3, _>(|i| (0..3).map(|j| m[i][j] * v[j]).sum())
    };
    let close = |a: [f64; 3], b: [f64; 3]| a.iter().zip(&b).all(|(x, y)| (x - y).abs() < 1e-4);
    assert!(close(r(8.0), [1.0, -2.0, -3.0]));
    assert!(close(r(2.0), [-2.0, 1.0, 3.0]));
    // ROTATION_PITCH_180: x = -x, z = -z.
    assert!(close(r(12.0), [-1.0, 2.0, -3.0]));
    // ROTATION_ROLL_90: tmp = z; z = y; y = -tmp.
    assert!(close(r(16.0), [1.0, -3.0, 2.0]));
    // ROTATION_ROLL_90_PITCH_68_YAW_293: the explicit matrix of vector3.cpp.
    let want = [
        0.143_038_97 * 1.0 + 0.368_776_49 * 2.0 - 0.918_446_38 * 3.0,
        -0.332_132_78 * 1.0 - 0.856_289_42 * 2.0 - 0.395_545_5 * 3.0,
        -0.932_323_8 * 1.0 + 0.361_624_57 * 2.0,
    ];
    assert!(close(r(38.0), want), "{:?} {want:?}", r(38.0));
    assert!(board_rotation(41.0).is_none() && board_rotation(2.5).is_none());
}

/// What cannot be undone is refused with what to do: no parameters, one missing, one changed in
/// the log, a zero scale (an empty slot), the temperature calibration without temperatures.
#[test]
fn what_cannot_be_undone_is_refused() {
    let mut rec = raw_recording(10);
    let e = undo(&mut rec, &VehicleParams::default(), 0).unwrap_err();
    assert_eq!(e, UndoError::NoParameters);
    assert!(e.to_string().contains("PARM"), "{e}");
    let e = undo(&mut rec, &params(0, 0.0, false), 1).unwrap_err();
    assert!(
        matches!(&e, UndoError::Missing { name, .. } if name == "INS_ACC2OFFS_X"),
        "{e}"
    );
    let mut p = params(0, 0.0, false);
    p.record("INS_ACCSCAL_Y", 1.2);
    let e = undo(&mut rec, &p, 0).unwrap_err();
    assert!(matches!(&e, UndoError::Changed { name, .. } if name == "INS_ACCSCAL_Y"));
    let p = params_with(2, 0.0, false, &[("INS_ACC3SCAL_Z", 0.0)]);
    let e = undo(&mut rec, &p, 2).unwrap_err();
    assert!(matches!(e, UndoError::ZeroScale { .. }), "{e}");
    let mut rec = raw_recording(10);
    rec.temp_c = None;
    let e = undo(&mut rec, &params(0, 0.0, true), 0).unwrap_err();
    assert!(matches!(e, UndoError::NoTemperature { .. }), "{e}");
    let e = undo(&mut rec, &params(0, 41.0, false), 0).unwrap_err();
    assert!(matches!(e, UndoError::UnknownRotation(_)), "{e}");
    let e = undo(
        &mut rec,
        &params_with(0, 0.0, false, &[("INS_CALSENSFRAME", 0.0)]),
        0,
    );
    assert_eq!(e.unwrap_err(), UndoError::BodyFrameCalibration);
}
