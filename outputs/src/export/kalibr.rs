//! Kalibr's IMU configuration (`imu.yaml` of `kalibr_calibrate_imu_camera --imu`), and our intrinsics
//! in the form of Kalibr's own calibrated-IMU output, as a separate document for comparison.
//!
//! What Kalibr reads from `imu.yaml` (`ethz-asl/kalibr`
//! `aslam_offline_calibration/kalibr/python/kalibr_common/ConfigReader.py`, `ImuParameters`): `rostopic`,
//! `update_rate` and the four noise figures, each checked to be positive — continuous-time densities
//! `accelerometer_noise_density` m/s²/√Hz, `accelerometer_random_walk` m/s³/√Hz,
//! `gyroscope_noise_density` rad/s/√Hz, `gyroscope_random_walk` rad/s²/√Hz (the Allan deviation's
//! white-noise line at τ = 1 s and random-walk line at τ = 3 s, from `host noise`). Nothing else: the
//! intrinsics model is chosen on Kalibr's command line (`--imu-models`) and estimated from identity
//! (`kalibr/python/kalibr_imu_camera_calibration/IccSensors.py`, `addDesignVariables`), so `imu.yaml`
//! holds no `model` or `M`, and there is never a NaN or placeholder: without every noise figure the
//! export is refused.
//!
//! `kalibr-intrinsics` writes what a `--imu-models scale-misalignment-size-effect` run writes in its
//! results (`IccSensors.py`, `ScaledMisalignedImu.ImuParameters.setIntrisicsMatrices` and
//! `ScaledMisalignedSizeEffectImu`): `model`, `T_i_b`, `accelerometers: {M, rx_i, ry_i, rz_i}`,
//! `gyroscopes: {M, C_gyro_i}`, for comparison with such a run. Conventions (stated in the file too):
//! - the IMU message carries `a_m = c·U` (m/s²), `U` the raw outputs and `c` the driver's scale
//!   ([`super::ExportInput::driver_scale`]), and the gyro `w` in rad/s;
//! - Kalibr's accelerometer model is `a_m = M·C_i_b·(f_b + lever terms) + b` with `M` lower-triangular.
//!   Ours is `U = (K·A/g)·f + u0` (`docs/model.md` §2), so `M·C_i_b = c·K·A/g`: an RQ factorisation
//!   (`M` lower-triangular with a positive diagonal, `C_i_b` a rotation) and `b = c·u0`;
//! - Kalibr's gyro model is `w = M_g·C_gyro_i·C_i_b·ω_b + A·(…) + b_g`; ours `w = G·ω + b` (§8), so
//!   `M_g·C_gyro_i = G·C_i_bᵀ` (RQ again); we have no g-sensitivity, so `A` is not written;
//! - Kalibr's body frame is our body frame with its origin at our reference point; Kalibr's IMU frame
//!   is rotated by `C_i_b` and, as Kalibr fixes `rx_i = 0`, placed at the x accelerometer's sensing
//!   point: `r_b_i = r_x`, `ry_i = C_i_b·(r_y − r_x)`, `rz_i = C_i_b·(r_z − r_x)`;
//! - Kalibr applies `M` to the axis-selected lever terms, where ours applies each sensing axis to its own
//!   point: the two agree exactly at rest and to second order (misalignment × lever term, ~10 µg at
//!   200 °/s with mrad misalignments and cm lever arms) in rotation.
//! - the biases are not part of Kalibr's results (it estimates bias splines); ours are written under
//!   `host_export_biases` for reference.

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
pub(crate) struct KalibrIntrinsics {
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
    /// The gyro's `(M_g, C_gyro_i, b_g)` when the calibration has a gyro correction.
    pub gyro: Option<(RowMajor3, RowMajor3, [f64; 3])>,
}

/// RQ factorisation of `n = L·R`: `L` lower-triangular with a positive diagonal, `R` a rotation.
/// `None` when `n` is singular or left-handed (then no rotation exists).
pub(crate) fn rq(n: &RowMajor3) -> Option<(RowMajor3, RowMajor3)> {
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
pub(crate) fn intrinsics(input: &ExportInput<'_>) -> Result<KalibrIntrinsics, ExportError> {
    let (fitted, _) = input.cal.statics.to_fitted()?;
    let c = input.driver_scale("Kalibr")?;
    let g = input.cal.gravity_m_s2;
    let n = fitted.m_out_per_g.map(|row| row.map(|v| v * c / g));
    if let Some(v) = n
        .iter()
        .flatten()
        .find(|v| !(v.is_finite() && v.abs() < 1e150))
    {
        return Err(ExportError::NotRepresentable {
            name: "Kalibr's c*K*A/g".into(),
            value: *v,
            spelling: input.options.spelling,
        });
    }
    let (m, c_i_b) = rq(&n).ok_or(ExportError::NoKalibrFactorisation("c*K*A/g"))?;
    let gyro = match &input.cal.gyro {
        Some(gy) => {
            let c_b_i = linalg::from_na(&linalg::to_na(&c_i_b).transpose());
            let n_g = linalg::from_na(&(linalg::to_na(&gy.matrix) * linalg::to_na(&c_b_i)));
            let (m_g, c_gyro_i) =
                rq(&n_g).ok_or(ExportError::NoKalibrFactorisation("G*C_i_b^T"))?;
            Some((m_g, c_gyro_i, gy.bias_rad_s))
        }
        None => None,
    };
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
        gyro,
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

/// The noise figures, all of them, or why not.
fn noise_figures(
    input: &ExportInput<'_>,
) -> Result<[(&'static str, f64, &'static str); 5], ExportError> {
    let n = input
        .noise
        .ok_or(ExportError::NoNoise(input.options.spelling))?;
    let fields = [
        ("update_rate", n.update_rate_hz, "Hz"),
        (
            "accelerometer_noise_density",
            n.accelerometer_noise_density,
            "m/s^2/sqrt(Hz)",
        ),
        (
            "accelerometer_random_walk",
            n.accelerometer_random_walk,
            "m/s^3/sqrt(Hz)",
        ),
        (
            "gyroscope_noise_density",
            n.gyroscope_noise_density,
            "rad/s/sqrt(Hz)",
        ),
        (
            "gyroscope_random_walk",
            n.gyroscope_random_walk,
            "rad/s^2/sqrt(Hz)",
        ),
    ];
    let mut out = [("", 0.0, ""); 5];
    for (k, (name, v, unit)) in fields.into_iter().enumerate() {
        match v {
            Some(v) if v.is_finite() && v > 0.0 => out[k] = (name, v, unit),
            _ => return Err(ExportError::NoiseFigure { name }),
        }
    }
    Ok(out)
}

/// The `imu.yaml` text: only what Kalibr reads.
pub fn render(input: &ExportInput<'_>) -> Result<String, ExportError> {
    let fields = noise_figures(input)?;
    let mut s = String::new();
    let w = &mut s;
    // Writing to a String cannot fail.
    let _ = writeln!(
        w,
        "# Kalibr IMU configuration (host export --format kalibr). Kalibr reads exactly these keys\n\
         # (kalibr_common/ConfigReader.py, ImuParameters). Its intrinsics model comes from --imu-models\n\
         # and is estimated from identity; ours, in the form of Kalibr's results, is the separate\n\
         # document of host export --format kalibr-intrinsics, for comparison."
    );
    let _ = writeln!(w, "rostopic: {}", input.rostopic);
    for (name, v, unit) in fields {
        let _ = writeln!(w, "{name}: {}  # {unit}", num(v));
    }
    Ok(s)
}

/// Our intrinsics as Kalibr's calibrated-IMU results hold them (`scale-misalignment-size-effect`).
pub(crate) fn render_intrinsics(input: &ExportInput<'_>) -> Result<String, ExportError> {
    let k = intrinsics(input)?;
    let mut s = String::new();
    let w = &mut s;
    let _ = writeln!(
        w,
        "# Our calibration in the form of Kalibr's results for --imu-models scale-misalignment-size-effect\n\
         # (host export --format kalibr-intrinsics; compare with a Kalibr run's results, Kalibr does not\n\
         # read this). Assumes the IMU topic carries a_m = c*U m/s^2 with c = {} m/s^2 per output unit\n\
         # and the gyro in rad/s. Kalibr's model a_m = M*C_i_b*f_b + b (M lower-triangular) with\n\
         # M*C_i_b = c*K*A/g (RQ); gyro w = M*C_gyro_i*C_i_b*omega + b with M*C_gyro_i = G*C_i_b^T;\n\
         # body origin = the calibration's reference point, IMU origin = the x sensing point (rx_i = 0).",
        num(input.driver_scale("Kalibr")?)
    );
    w.push_str(&super::temperature_not_held(&input.cal, "Kalibr"));
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
    match &k.gyro {
        Some((m_g, c_gyro_i, _)) => {
            // Entries of G the calibration did not determine are never written as plain numbers.
            let undetermined = super::c::undetermined_gyro_inverse(input);
            if undetermined.iter().flatten().any(|u| *u) {
                if !input.options.allow_undetermined {
                    return Err(ExportError::Undetermined {
                        format: "kalibr-intrinsics",
                        names: "the gyroscope's M and C_gyro_i (from an undetermined G)".into(),
                        spelling: input.options.spelling,
                    });
                }
                let _ = writeln!(
                    w,
                    "# UNDETERMINED: the gyroscope's M and C_gyro_i come from a G with undetermined \
                     entries (--allow-undetermined)"
                );
            }
            let _ = writeln!(
                w,
                "gyroscopes:  # no A (g-sensitivity): our gyro model has none"
            );
            let _ = writeln!(w, "  M:");
            for r in m_g {
                let _ = writeln!(w, "    - {}", row(r));
            }
            let _ = writeln!(w, "  C_gyro_i:");
            for r in c_gyro_i {
                let _ = writeln!(w, "    - {}", row(r));
            }
        }
        None => {
            let _ = writeln!(
                w,
                "# gyroscopes: UNDETERMINED (the calibration has no gyro correction)"
            );
        }
    }
    let _ = writeln!(
        w,
        "host_export_biases:  # not in Kalibr's results (it estimates bias splines); for reference"
    );
    let _ = writeln!(
        w,
        "  accelerometer: {}  # m/s^2, as the driver reports it",
        row(&k.bias_m_s2)
    );
    if let Some((_, _, b)) = &k.gyro {
        let _ = writeln!(w, "  gyroscope: {}  # rad/s", row(b));
    }
    Ok(s)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn intrinsics_refuse_or_mark_a_gyro_with_undetermined_entries() {
        let mut cal = UnitFile::paper_unit().to_calibration().unwrap();
        cal.gyro = Some(firmware::paper_unit::typical_gyro());
        let mut unit = UnitFile::from_calibration(&cal, None, None);
        unit.gyro.as_mut().unwrap().matrix_1sigma = Some([[1e-5; 3]; 3]);
        let mut input = ExportInput::for_tests(&unit, cal);
        input.driver_scale_m_s2_per_out = Some(24.8);
        assert!(!render_intrinsics(&input)
            .unwrap()
            .contains("UNDETERMINED: the gyroscope"));
        let mut sigma = [[1e-5; 3]; 3];
        for row in &mut sigma {
            row[2] = 0.05;
        }
        unit.gyro.as_mut().unwrap().matrix_1sigma = Some(sigma);
        let mut input = ExportInput::for_tests(&unit, cal);
        input.driver_scale_m_s2_per_out = Some(24.8);
        let e = render_intrinsics(&input).unwrap_err().to_string();
        assert!(e.contains("<AllowUndetermined>"), "{e}");
        input.options.allow_undetermined = true;
        assert!(render_intrinsics(&input)
            .unwrap()
            .contains("UNDETERMINED: the gyroscope"));
    }
    use crate::export::consumer_tests::handheld_unit;
    use estimator::unit_file::UnitFile;

    /// What Kalibr's ConfigReader.py reads: these keys, each positive (`checkUpdateRate`,
    /// `checkAccelerometerStatistics`, `checkGyroStatistics`).
    #[derive(Deserialize)]
    #[serde(deny_unknown_fields)]
    struct ImuYaml {
        rostopic: String,
        update_rate: f64,
        accelerometer_noise_density: f64,
        accelerometer_random_walk: f64,
        gyroscope_noise_density: f64,
        gyroscope_random_walk: f64,
    }

    fn full_noise() -> KalibrNoise {
        KalibrNoise {
            update_rate_hz: Some(1000.0),
            accelerometer_noise_density: Some(3.1e-4),
            accelerometer_random_walk: Some(4.0e-5),
            gyroscope_noise_density: Some(2.5e-5),
            gyroscope_random_walk: Some(1.0e-6),
        }
    }

    #[test]
    fn imu_yaml_holds_exactly_what_kalibr_reads_and_every_value_is_positive() {
        let cal = handheld_unit();
        let unit = UnitFile::from_calibration(&cal, None, None);
        let noise = full_noise();
        let input = ExportInput {
            noise: Some(&noise),
            ..ExportInput::for_tests(&unit, cal)
        };
        let text = render(&input).unwrap();
        let p: ImuYaml = serde_yaml::from_str(&text).unwrap();
        assert_eq!(p.rostopic, "/imu0");
        assert_eq!(p.update_rate, 1000.0);
        assert_eq!(p.accelerometer_noise_density, 3.1e-4);
        assert_eq!(p.accelerometer_random_walk, 4.0e-5);
        assert_eq!(p.gyroscope_noise_density, 2.5e-5);
        assert_eq!(p.gyroscope_random_walk, 1.0e-6);
        assert!(
            !text.to_lowercase().contains("nan") && !text.contains("initial"),
            "{text}"
        );
    }

    #[test]
    fn kalibr_without_every_noise_figure_is_refused_with_how_to_get_it() {
        let cal = handheld_unit();
        let unit = UnitFile::from_calibration(&cal, None, None);
        let e = render(&ExportInput::for_tests(&unit, cal)).unwrap_err();
        assert!(
            e.to_string().contains("host noise") && e.to_string().contains("<Noise>"),
            "{e}"
        );
        let noise = KalibrNoise {
            accelerometer_random_walk: None,
            ..full_noise()
        };
        let input = ExportInput {
            noise: Some(&noise),
            ..ExportInput::for_tests(&unit, cal)
        };
        let e = render(&input).unwrap_err().to_string();
        assert!(e.contains("accelerometer_random_walk"), "{e}");
        assert!(
            e.contains("too short") && e.contains("--calibration"),
            "{e}"
        );
        // A gyro figure has one cause: the calibration converts only the accelerometer.
        let noise = KalibrNoise {
            gyroscope_random_walk: None,
            ..full_noise()
        };
        let input = ExportInput {
            noise: Some(&noise),
            ..ExportInput::for_tests(&unit, cal)
        };
        let e = render(&input).unwrap_err().to_string();
        assert!(
            e.contains("gyroscope_random_walk") && e.contains("too short"),
            "{e}"
        );
        assert!(!e.contains("--calibration"), "{e}");
    }

    #[test]
    fn intrinsics_factor_into_kalibrs_triangular_and_rotation_form() {
        let cal = handheld_unit();
        let unit = UnitFile::from_calibration(&cal, None, None);
        let k = intrinsics(&ExportInput::for_tests(&unit, cal)).unwrap();
        let (m_g, c_gyro_i, _) = k.gyro.unwrap();
        for m in [k.m, m_g] {
            assert!(m[0][1] == 0.0 && m[0][2] == 0.0 && m[1][2] == 0.0, "{m:?}");
            assert!((0..3).all(|i| m[i][i] > 0.0));
        }
        for r in [k.c_i_b, c_gyro_i] {
            let rtr = linalg::to_na(&r).transpose() * linalg::to_na(&r);
            assert!((rtr - nalgebra::Matrix3::identity()).norm() < 1e-12);
        }
        // M_g·C_gyro_i·C_i_b = G.
        let g = linalg::to_na(&m_g) * linalg::to_na(&c_gyro_i) * linalg::to_na(&k.c_i_b);
        assert!((g - linalg::to_na(&cal.gyro.unwrap().matrix)).norm() < 1e-12);
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
