//! Kalibr's IMU YAML (`imu.yaml` of `kalibr_calibrate_imu_camera --imu`), with our accelerometer
//! intrinsics in Kalibr's own scale-misalignment-size-effect parameterisation.
//!
//! Kalibr reads `rostopic`, `update_rate` and the four noise figures as its input (continuous-time
//! densities: `accelerometer_noise_density` m/s²/√Hz, `accelerometer_random_walk` m/s³/√Hz,
//! `gyroscope_noise_density` rad/s/√Hz, `gyroscope_random_walk` rad/s²/√Hz — the Allan deviation's
//! white-noise line at τ = 1 s and random-walk line at τ = 3 s, from `host noise`). The intrinsics are
//! written the way Kalibr writes its own results (`model`, `T_i_b`, `accelerometers: {M, rx_i, ry_i,
//! rz_i}`), so they can be compared with a Kalibr run or used as its initial values.
//!
//! Conventions assumed (stated in the file too):
//! - the IMU message carries `a_m = c·U` (m/s²), `U` the raw outputs and `c` the driver's scale
//!   ([`super::ExportInput::driver_scale`]);
//! - Kalibr's accelerometer model is `a_m = M·C_i_b·(f_b + lever terms) + b` with `M` lower-triangular.
//!   Ours is `U = (K·A/g)·f + u0` (`docs/model.md` §2), so `M·C_i_b = c·K·A/g`: an RQ factorisation
//!   (`M` lower-triangular with a positive diagonal, `C_i_b` a rotation) and `b = c·u0`;
//! - Kalibr's body frame is our body frame with its origin at our reference point; Kalibr's IMU frame
//!   is rotated by `C_i_b` and, as Kalibr fixes `rx_i = 0`, placed at the x accelerometer's sensing
//!   point: `r_b_i = r_x`, `ry_i = C_i_b·(r_y − r_x)`, `rz_i = C_i_b·(r_z − r_x)`;
//! - Kalibr applies `M` to the axis-selected lever terms, where ours applies each sensing axis to its own
//!   point: the two agree exactly at rest and to second order (misalignment × lever term, ~10 µg at
//!   200 °/s with mrad misalignments and cm lever arms) in rotation.

use super::{ExportError, ExportInput};
use serde::{Deserialize, Serialize};
use shared::linalg::{self, RowMajor3};
use std::fmt::Write as _;

/// The noise figures Kalibr needs; `None` where the noise analysis did not determine one.
#[derive(Clone, Debug, Default, PartialEq, Serialize, Deserialize)]
pub struct KalibrNoise {
    /// Sample rate, Hz.
    pub update_rate_hz: Option<f64>,
    /// Accelerometer white noise density, m/s²/√Hz (worst axis).
    pub accelerometer_noise_density: Option<f64>,
    /// Accelerometer bias random walk, m/s³/√Hz (worst axis).
    pub accelerometer_random_walk: Option<f64>,
    /// Gyro white noise density, rad/s/√Hz (worst axis).
    pub gyroscope_noise_density: Option<f64>,
    /// Gyro bias random walk, rad/s²/√Hz (worst axis).
    pub gyroscope_random_walk: Option<f64>,
}

/// Our intrinsics in Kalibr's parameterisation.
#[derive(Clone, Debug, PartialEq)]
pub struct KalibrIntrinsics {
    /// Lower-triangular `M` (dimensionless: m/s² measured per m/s² true).
    pub m: RowMajor3,
    /// `C_i_b`, body → IMU frame rotation.
    pub c_i_b: RowMajor3,
    /// IMU frame origin in the body frame, m (= the x sensing point).
    pub r_b_i_m: [f64; 3],
    /// Sensing points in the IMU frame relative to its origin, m.
    pub r_i_m: RowMajor3,
    /// Accelerometer bias as the driver reports it, m/s².
    pub bias_m_s2: [f64; 3],
}

/// RQ factorisation of `n = L·R`: `L` lower-triangular with a positive diagonal, `R` a rotation.
/// `None` when `n` is singular or left-handed (then no rotation exists).
pub fn rq(n: &RowMajor3) -> Option<(RowMajor3, RowMajor3)> {
    // nᵀ = Q·U (QR), so n = Uᵀ·Qᵀ; signs moved so that U's diagonal is positive.
    let qr = linalg::to_na(n).transpose().qr();
    let (mut q, mut u) = (qr.q(), qr.r());
    for i in 0..3 {
        if u[(i, i)] < 0.0 {
            q.column_mut(i).neg_mut();
            u.row_mut(i).neg_mut();
        }
        if u[(i, i)] == 0.0 || !u[(i, i)].is_finite() {
            return None;
        }
    }
    let r = q.transpose();
    if r.determinant() <= 0.0 {
        return None;
    }
    Some((linalg::from_na(&u.transpose()), linalg::from_na(&r)))
}

/// The intrinsics of `input` in Kalibr's parameterisation.
pub fn intrinsics(input: &ExportInput<'_>) -> Result<KalibrIntrinsics, ExportError> {
    let (fitted, _) = input.cal.statics.to_fitted()?;
    let c = input.driver_scale();
    let g = input.cal.gravity_m_s2;
    let n = fitted.m_out_per_g.map(|row| row.map(|v| v * c / g));
    let (m, c_i_b) = rq(&n).ok_or(ExportError::Params(
        shared::params::ParamsError::DegenerateAxis { axis: 0 },
    ))?;
    let r = input.cal.lever_arms.r_m;
    let rel = |k: usize| -> [f64; 3] {
        linalg::mat_vec(&c_i_b, &std::array::from_fn(|j| r[k][j] - r[0][j]))
    };
    Ok(KalibrIntrinsics {
        m,
        c_i_b,
        r_b_i_m: r[0],
        r_i_m: [[0.0; 3], rel(1), rel(2)],
        bias_m_s2: fitted.zero_bias_out.map(|v| v * c),
    })
}

fn num(v: f64) -> String {
    if v.is_finite() {
        format!("{v:?}")
    } else {
        ".nan".into()
    }
}

fn row(v: &[f64]) -> String {
    let items: Vec<String> = v.iter().map(|x| num(*x)).collect();
    format!("[{}]", items.join(", "))
}

/// The YAML text.
pub fn render(input: &ExportInput<'_>) -> Result<String, ExportError> {
    let k = intrinsics(input)?;
    let noise = input.noise.cloned().unwrap_or_default();
    let mut s = String::new();
    let w = &mut s;
    // Writing to a String cannot fail.
    let _ = writeln!(
        w,
        "# Kalibr IMU configuration (host export --format kalibr)."
    );
    let _ = writeln!(
        w,
        "# Assumes the IMU topic carries a_m = c*U m/s^2 with c = {} m/s^2 per output unit;",
        num(input.driver_scale())
    );
    let _ = writeln!(
        w,
        "# Kalibr's model a_m = M*C_i_b*f_b + b (M lower-triangular) with M*C_i_b = c*K*A/g (RQ),\n\
         # body origin = the calibration's reference point, IMU origin = the x sensing point (rx_i = 0).\n\
         # A value .nan is UNDETERMINED: Kalibr will refuse it; give --noise NOISE.json from host noise."
    );
    w.push_str(&super::temperature_not_held(&input.cal, "Kalibr"));
    let _ = writeln!(w, "rostopic: {}", input.rostopic);
    let fields = [
        ("update_rate", noise.update_rate_hz, "Hz"),
        (
            "accelerometer_noise_density",
            noise.accelerometer_noise_density,
            "m/s^2/sqrt(Hz)",
        ),
        (
            "accelerometer_random_walk",
            noise.accelerometer_random_walk,
            "m/s^3/sqrt(Hz)",
        ),
        (
            "gyroscope_noise_density",
            noise.gyroscope_noise_density,
            "rad/s/sqrt(Hz)",
        ),
        (
            "gyroscope_random_walk",
            noise.gyroscope_random_walk,
            "rad/s^2/sqrt(Hz)",
        ),
    ];
    for (name, v, unit) in fields {
        match v {
            Some(v) if v.is_finite() => {
                let _ = writeln!(w, "{name}: {}  # {unit}", num(v));
            }
            _ => {
                let _ = writeln!(
                    w,
                    "{name}: .nan  # {unit}; UNDETERMINED (no noise analysis given, or its still segment was too short to show this term)"
                );
            }
        }
    }
    let _ = writeln!(w, "model: scale-misalignment-size-effect");
    let t = linalg::mat_vec(&k.c_i_b, &k.r_b_i_m).map(|v| -v);
    let _ = writeln!(w, "T_i_b:");
    for i in 0..3 {
        let _ = writeln!(
            w,
            "  - {}",
            row(&[k.c_i_b[i][0], k.c_i_b[i][1], k.c_i_b[i][2], t[i]])
        );
    }
    let _ = writeln!(w, "  - [0.0, 0.0, 0.0, 1.0]");
    let _ = writeln!(w, "accelerometers:");
    let _ = writeln!(w, "  M:");
    for r in &k.m {
        let _ = writeln!(w, "    - {}", row(r));
    }
    let _ = writeln!(
        w,
        "  bias: {}  # m/s^2, as the driver reports it",
        row(&k.bias_m_s2)
    );
    for (name, r) in ["rx_i", "ry_i", "rz_i"].iter().zip(&k.r_i_m) {
        let _ = writeln!(w, "  {name}: {}  # m", row(r));
    }
    if let Some(u) = &input.unit.uncertainty {
        let unobserved: Vec<String> = (0..3)
            .flat_map(|i| (0..3).map(move |j| (i, j)))
            .filter(|&(i, j)| !u.lever_arms_observable[i][j])
            .map(|(i, j)| format!("r{}{}", i + 1, ["x", "y", "z"][j]))
            .collect();
        if !unobserved.is_empty() {
            let _ = writeln!(
                w,
                "# UNDETERMINED lever-arm components (the plan did not observe them): {}",
                unobserved.join(", ")
            );
        }
    }
    Ok(s)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::unit_file::UnitFile;
    use shared::forward::{BodyMotion, ForwardModel};
    use shared::{BodyAngularAccel, BodyRate, BodySpecificForce};

    /// What a YAML parser sees (Kalibr's keys; `.nan` is YAML's NaN).
    #[derive(Deserialize)]
    struct Parsed {
        rostopic: String,
        update_rate: f64,
        accelerometer_noise_density: f64,
        accelerometer_random_walk: f64,
        gyroscope_noise_density: f64,
        gyroscope_random_walk: f64,
        model: String,
        #[serde(rename = "T_i_b")]
        t_i_b: Vec<Vec<f64>>,
        accelerometers: Accel,
    }
    #[derive(Deserialize)]
    struct Accel {
        #[serde(rename = "M")]
        m: Vec<Vec<f64>>,
        bias: Vec<f64>,
        rx_i: Vec<f64>,
        ry_i: Vec<f64>,
        rz_i: Vec<f64>,
    }

    #[test]
    fn yaml_parses_back_and_its_model_reproduces_the_outputs() {
        let unit = UnitFile::paper_unit();
        let cal = unit.to_calibration().unwrap();
        let noise = KalibrNoise {
            update_rate_hz: Some(1000.0),
            accelerometer_noise_density: Some(3.1e-4),
            accelerometer_random_walk: None,
            gyroscope_noise_density: Some(2.5e-5),
            gyroscope_random_walk: Some(1.0e-6),
        };
        let input = ExportInput {
            noise: Some(&noise),
            ..ExportInput::for_tests(&unit, cal)
        };
        let text = render(&input).unwrap();
        let p: Parsed = serde_yaml::from_str(&text).unwrap();
        assert_eq!(p.rostopic, "/imu0");
        assert_eq!(p.model, "scale-misalignment-size-effect");
        assert_eq!(p.update_rate, 1000.0);
        assert_eq!(p.accelerometer_noise_density, 3.1e-4);
        assert!(
            p.accelerometer_random_walk.is_nan(),
            "undetermined must be marked"
        );
        assert!(text.contains("accelerometer_random_walk: .nan  # m/s^3/sqrt(Hz); UNDETERMINED"));
        assert_eq!(p.gyroscope_noise_density, 2.5e-5);
        assert_eq!(p.gyroscope_random_walk, 1.0e-6);
        // M lower-triangular with a positive diagonal, C_i_b a rotation.
        let m: RowMajor3 =
            std::array::from_fn(|i| std::array::from_fn(|j| p.accelerometers.m[i][j]));
        let c: RowMajor3 = std::array::from_fn(|i| std::array::from_fn(|j| p.t_i_b[i][j]));
        assert!(m[0][1] == 0.0 && m[0][2] == 0.0 && m[1][2] == 0.0);
        assert!((0..3).all(|i| m[i][i] > 0.0));
        let ctc = linalg::to_na(&c).transpose() * linalg::to_na(&c);
        assert!((ctc - nalgebra::Matrix3::identity()).norm() < 1e-12);
        // Kalibr's model, read from the file, gives the raw outputs of our forward model (at rest:
        // the lever terms are where the two models differ, see the module documentation).
        let model = ForwardModel::new(&cal).unwrap();
        let cs = input.driver_scale();
        let t = [p.t_i_b[0][3], p.t_i_b[1][3], p.t_i_b[2][3]];
        let r_b_i =
            linalg::mat_vec(&linalg::from_na(&linalg::to_na(&c).transpose()), &t).map(|v| -v);
        for k in 0..3 {
            assert!((r_b_i[k] - cal.lever_arms.r_m[0][k]).abs() < 1e-12);
        }
        assert_eq!(p.accelerometers.rx_i, vec![0.0; 3]);
        let ry_b = linalg::mat_vec(
            &linalg::from_na(&linalg::to_na(&c).transpose()),
            &[
                p.accelerometers.ry_i[0],
                p.accelerometers.ry_i[1],
                p.accelerometers.ry_i[2],
            ],
        );
        for k in 0..3 {
            assert!((ry_b[k] + r_b_i[k] - cal.lever_arms.r_m[1][k]).abs() < 1e-12);
        }
        assert_eq!(p.accelerometers.rz_i.len(), 3);
        for x in 0..20 {
            let x = f64::from(x);
            let f = [9.0 * (0.3 * x).sin(), -4.0 + 0.4 * x, 9.8 * (0.2 * x).cos()];
            let u = model
                .outputs(&BodyMotion {
                    f_o: BodySpecificForce { m_s2: f },
                    omega: BodyRate::default(),
                    omega_dot: BodyAngularAccel::default(),
                })
                .raw;
            let a_m = linalg::mat_vec(&m, &linalg::mat_vec(&c, &f));
            for i in 0..3 {
                let want = cs * u[i];
                let got = a_m[i] + p.accelerometers.bias[i];
                assert!(
                    (got - want).abs() < 1e-9 * want.abs().max(1.0),
                    "{i}: {got} vs {want}"
                );
            }
        }
    }

    #[test]
    fn rq_refuses_a_left_handed_triad() {
        let n = [[1.0, 0.0, 0.0], [0.0, 1.0, 0.0], [0.0, 0.0, -1.0]];
        assert!(rq(&n).is_none());
        let (l, r) = rq(&[[2.0, 0.1, 0.0], [0.0, 1.0, 0.2], [0.1, 0.0, 3.0]]).unwrap();
        let back = linalg::to_na(&l) * linalg::to_na(&r);
        assert!(
            (back - linalg::to_na(&[[2.0, 0.1, 0.0], [0.0, 1.0, 0.2], [0.1, 0.0, 3.0]])).norm()
                < 1e-12
        );
    }
}
