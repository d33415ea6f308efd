//! Our calibration in the conventions other tools use, so a result can be taken elsewhere and checked.
//!
//! Each form comes with its own `compensate`, written in that tool's convention; a test checks that every
//! form turns the same samples into the same specific force as `shared::Compensator`.
//!
//! - [`PlainMatrices`]: the paper's eq. 6 / 16 matrices, `f_b[g] = K_A·U − ∇_b − f_L^b`.
//! - [`FusionStyle`]: x-io Fusion's `FusionModelInertial`:
//!   `f[g] = misalignment · ((U − offset) ∘ sensitivity)`, with `misalignment = A⁻¹`,
//!   `sensitivity = 1/k` (g per output unit) and `offset = u0`. Fusion has no lever-arm terms.
//! - [`KalibrStyle`]: Kalibr's "scale-misalignment-size-effect" accelerometer model in its general
//!   form: the measurement of axis `i` is `row_i(M)·f(r_i) + b_i` with `M = K·A/g` (output unit per m/s²),
//!   `b = u0`, and the sensing point of axis x, y, z at `rx`, `ry`, `rz` (m, relative to the reference
//!   point). Kalibr itself writes `M` in a lower-triangular parameterisation tied to its IMU frame; ours is
//!   the same map expressed in the body frame.

use serde::{Deserialize, Serialize};
use shared::linalg::{self, RowMajor3};
use shared::params::ParamsError;
use shared::Calibration;

/// The plain `K_A`, `∇_b` of the paper, plus the lever arms.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct PlainMatrices {
    /// `K_A = (K A)⁻¹`, g per output unit, row-major.
    pub k_a_g_per_out: RowMajor3,
    /// `∇_b = K_A u0`, g.
    pub nabla_b_g: [f64; 3],
    /// Row i = `r_i`, m.
    pub lever_arms_m: RowMajor3,
    /// g used for the lever terms, m/s².
    pub gravity_m_s2: f64,
}

/// x-io Fusion's inertial calibration triple.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct FusionStyle {
    /// `A⁻¹`, row-major (Fusion's `FusionMatrix` is row-major too).
    pub misalignment: RowMajor3,
    /// `1/k_i`, g per output unit.
    pub sensitivity: [f64; 3],
    /// `u0`, output unit.
    pub offset: [f64; 3],
}

/// Kalibr-style scale-misalignment-size-effect parameters.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct KalibrStyle {
    /// `M = K·A/g`, output unit per m/s², row-major.
    pub m: RowMajor3,
    /// `u0`, output unit.
    pub bias: [f64; 3],
    /// Sensing point of the x accelerometer, m.
    pub rx: [f64; 3],
    /// Sensing point of the y accelerometer, m.
    pub ry: [f64; 3],
    /// Sensing point of the z accelerometer, m.
    pub rz: [f64; 3],
}

/// All three forms.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct Conversions {
    /// The paper's matrices.
    pub plain: PlainMatrices,
    /// Fusion's triple.
    pub fusion: FusionStyle,
    /// Kalibr's model.
    pub kalibr: KalibrStyle,
}

/// Converts a calibration to every form.
pub fn convert(cal: &Calibration) -> Result<Conversions, ParamsError> {
    let (fitted, _) = cal.statics.to_fitted()?;
    let (k, a) = fitted.decompose()?;
    let bad = ParamsError::DegenerateAxis { axis: 0 };
    let k_a = linalg::inverse(&fitted.m_out_per_g).ok_or(bad)?;
    let a_inv = linalg::inverse(&a).ok_or(bad)?;
    let g = cal.gravity_m_s2;
    let r = cal.lever_arms.r_m;
    Ok(Conversions {
        plain: PlainMatrices {
            k_a_g_per_out: k_a,
            nabla_b_g: linalg::mat_vec(&k_a, &fitted.zero_bias_out),
            lever_arms_m: r,
            gravity_m_s2: g,
        },
        fusion: FusionStyle {
            misalignment: a_inv,
            sensitivity: k.map(|ki| 1.0 / ki),
            offset: fitted.zero_bias_out,
        },
        kalibr: KalibrStyle {
            m: fitted.m_out_per_g.map(|row| row.map(|v| v / g)),
            bias: fitted.zero_bias_out,
            rx: r[0],
            ry: r[1],
            rz: r[2],
        },
    })
}

impl PlainMatrices {
    /// Paper eq. 16: `f_b = K_A U − ∇_b − f_L^b`, with `f_L^b = A⁻¹ d` computed as `K_A (K d)`, in m/s².
    pub fn compensate(&self, u: [f64; 3], omega: [f64; 3], omega_dot: [f64; 3]) -> [f64; 3] {
        let w = linalg::lever_matrix(&omega, &omega_dot);
        let ka_u = linalg::mat_vec(&self.k_a_g_per_out, &u);
        // K d in output units needs K·A rows: K A = K_A⁻¹.
        let m = linalg::inverse(&self.k_a_g_per_out).unwrap_or([[0.0; 3]; 3]);
        let kd: [f64; 3] = std::array::from_fn(|i| {
            linalg::dot(&m[i], &linalg::mat_vec(&w, &self.lever_arms_m[i])) / self.gravity_m_s2
        });
        let f_l = linalg::mat_vec(&self.k_a_g_per_out, &kd);
        std::array::from_fn(|j| (ka_u[j] - self.nabla_b_g[j] - f_l[j]) * self.gravity_m_s2)
    }
}

impl FusionStyle {
    /// `FusionModelInertial`, in g; static only.
    pub fn compensate_static_g(&self, u: [f64; 3]) -> [f64; 3] {
        let scaled: [f64; 3] =
            std::array::from_fn(|i| (u[i] - self.offset[i]) * self.sensitivity[i]);
        linalg::mat_vec(&self.misalignment, &scaled)
    }
}

impl KalibrStyle {
    /// Solves `u_i = row_i(M)·(f + W r_i) + b_i` for `f` (m/s²).
    pub fn compensate(&self, u: [f64; 3], omega: [f64; 3], omega_dot: [f64; 3]) -> [f64; 3] {
        let w = linalg::lever_matrix(&omega, &omega_dot);
        let r = [self.rx, self.ry, self.rz];
        let rhs: [f64; 3] = std::array::from_fn(|i| {
            u[i] - self.bias[i] - linalg::dot(&self.m[i], &linalg::mat_vec(&w, &r[i]))
        });
        let inv = linalg::inverse(&self.m).unwrap_or([[0.0; 3]; 3]);
        linalg::mat_vec(&inv, &rhs)
    }
}

/// The conventions [`export`] writes.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum ExportFormat {
    /// The paper's `K_A`, `∇_b` and the lever arms ([`crate::export::PlainMatrices`]).
    Plain,
    /// x-io Fusion's misalignment, sensitivity, offset ([`crate::export::FusionStyle`]).
    Fusion,
    /// Kalibr-style `M`, bias, `rx/ry/rz` ([`crate::export::KalibrStyle`]).
    Kalibr,
    /// All three, as the tables `[plain]`, `[fusion]`, `[kalibr]`.
    All,
}

impl std::str::FromStr for ExportFormat {
    type Err = String;
    fn from_str(s: &str) -> Result<Self, String> {
        match s {
            "plain" => Ok(ExportFormat::Plain),
            "fusion" => Ok(ExportFormat::Fusion),
            "kalibr" => Ok(ExportFormat::Kalibr),
            "all" => Ok(ExportFormat::All),
            _ => Err(format!(
                "unknown export format '{s}': use plain, fusion, kalibr or all"
            )),
        }
    }
}

const HEADER_PLAIN: &str = "\
# Plain matrices (paper eq. 16): f_b[g] = K_A·U − ∇_b − f_L^b, with f_L^b = K_A·(K d),
# (K d)_i = row_i(K_A⁻¹)·(W r_i)/g and W = [ω̇×] + [ω×]². K_A in g per output unit, row-major;
# ∇_b in g; lever_arms_m row i = r_i (m, body axes, from the reference point).
";
const HEADER_FUSION: &str = "\
# x-io Fusion FusionModelInertial: f[g] = misalignment·((U − offset) ∘ sensitivity).
# misalignment = A⁻¹ (row-major), sensitivity = 1/k_i (g per output unit), offset = u0. No lever arms:
# static compensation only.
";
const HEADER_KALIBR: &str = "\
# Kalibr-style scale-misalignment-size-effect model, general form, in the body frame:
# u_i = row_i(m)·(f + W r_i) + bias_i, m = K·A/g (output unit per m/s², row-major), bias = u0,
# rx, ry, rz = sensing points of the x, y, z accelerometers (m). Solve for f (m/s²).
";

/// Why a calibration cannot be exported.
#[derive(Debug)]
pub struct ExportError(pub String);

impl std::fmt::Display for ExportError {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        write!(f, "cannot export the calibration: {}", self.0)
    }
}

impl std::error::Error for ExportError {}

/// `host export`: the calibration in another tool's convention, as TOML (with a comment header that
/// states the convention).
pub fn export(calibration: &Calibration, format: ExportFormat) -> Result<String, ExportError> {
    let c: Conversions = convert(calibration).map_err(|e| ExportError(e.to_string()))?;
    let ser = |r: Result<String, toml::ser::Error>| r.map_err(|e| ExportError(e.to_string()));
    Ok(match format {
        ExportFormat::Plain => format!("{HEADER_PLAIN}{}", ser(toml::to_string(&c.plain))?),
        ExportFormat::Fusion => format!("{HEADER_FUSION}{}", ser(toml::to_string(&c.fusion))?),
        ExportFormat::Kalibr => format!("{HEADER_KALIBR}{}", ser(toml::to_string(&c.kalibr))?),
        ExportFormat::All => format!(
            "{HEADER_PLAIN}{HEADER_FUSION}{HEADER_KALIBR}{}",
            ser(toml::to_string(&c))?
        ),
    })
}

/// [`export`] of a calibration file's values, with the lever-arm components its plan did not
/// determine (`lever_arms_observable = false` in `[uncertainty]`) written as `nan` and listed in a
/// comment: a consumer must not take an undetermined component (often exactly 0) for a measurement.
pub fn export_marked(
    calibration: &Calibration,
    format: ExportFormat,
    observable: Option<&[[bool; 3]; 3]>,
) -> Result<String, ExportError> {
    let mut cal = *calibration;
    let mut names = Vec::new();
    if let Some(obs) = observable {
        for i in 0..3 {
            for j in 0..3 {
                if !obs[i][j] {
                    cal.lever_arms.r_m[i][j] = f64::NAN;
                    names.push(format!("r{}{}", i + 1, shared::params::axis_name(j)));
                }
            }
        }
    }
    let text = export(&cal, format)?;
    if names.is_empty() {
        return Ok(text);
    }
    Ok(format!(
        "# NOT DETERMINED by the calibration's plan, written as nan (not a measurement): {}\n{text}",
        names.join(", ")
    ))
}

#[cfg(test)]
mod tests {
    use super::*;
    use shared::forward::{BodyMotion, ForwardModel};
    use shared::{
        BodyAngularAccel, BodyRate, BodySpecificForce, Compensator, LeverMode, SensorOutputs,
    };

    #[test]
    fn every_form_compensates_like_the_device() {
        let cal = shared::params::PAPER_UNIT;
        let conv = convert(&cal).unwrap();
        let model = ForwardModel::new(&cal).unwrap();
        let full = Compensator::new(&cal, LeverMode::RateAndAcceleration).unwrap();
        let g = cal.gravity_m_s2;
        let mut worst = [0.0f64; 3];
        for k in 0..200 {
            let x = k as f64;
            let motion = BodyMotion {
                f_o: BodySpecificForce {
                    m_s2: [9.0 * (0.1 * x).sin(), 7.0 * (0.2 * x).cos(), 5.0 - 0.05 * x],
                },
                omega: BodyRate {
                    rad_s: [3.0 * (0.3 * x).sin(), -2.0, 0.01 * x],
                },
                omega_dot: BodyAngularAccel {
                    rad_s2: [10.0, -5.0 * (0.7 * x).cos(), 0.0],
                },
            };
            let u = model.outputs(&motion).raw;
            let (w, wd) = (motion.omega.rad_s, motion.omega_dot.rad_s2);
            let device = full
                .compensate(
                    &SensorOutputs {
                        raw: u.map(|v| v as f32),
                    },
                    &BodyRate {
                        rad_s: w.map(|v| v as f32),
                    },
                    &BodyAngularAccel {
                        rad_s2: wd.map(|v| v as f32),
                    },
                )
                .to_f64()
                .m_s2;
            let plain = conv.plain.compensate(u, w, wd);
            let kalibr = conv.kalibr.compensate(u, w, wd);
            // Static-only forms against a static motion's outputs.
            let still = BodyMotion {
                omega: BodyRate::default(),
                omega_dot: BodyAngularAccel::default(),
                ..motion
            };
            let u_still = model.outputs(&still).raw;
            let fusion = conv.fusion.compensate_static_g(u_still).map(|v| v * g);
            for j in 0..3 {
                // The f64 forms agree with the truth to rounding; the device's f32 path to its stated 2e-4.
                assert!((plain[j] - motion.f_o.m_s2[j]).abs() < 1e-9);
                assert!((kalibr[j] - motion.f_o.m_s2[j]).abs() < 1e-9);
                assert!((fusion[j] - motion.f_o.m_s2[j]).abs() < 1e-9);
                worst[j] = worst[j].max((device[j] - plain[j]).abs());
            }
        }
        assert!(worst.iter().all(|w| *w < 2e-4), "{worst:?}");
    }

    #[test]
    fn plain_matrices_are_the_reference_k_a() {
        let cal = shared::params::PAPER_UNIT;
        let c = convert(&cal).unwrap();
        // paper-unit.toml [expected]: K_A[0][0] = 2.53161061 g/V, ∇_b = (6.13688643, …) g.
        assert!((c.plain.k_a_g_per_out[0][0] - 2.53161061).abs() < 1e-7);
        assert!((c.plain.nabla_b_g[0] - 6.13688643).abs() < 1e-7);
    }

    /// Each exported form, read back from its TOML, compensates like the device's compensator.
    #[test]
    fn every_exported_form_reads_back_and_compensates_the_same() {
        let cal = shared::params::PAPER_UNIT;
        let plain: PlainMatrices =
            toml::from_str(&export(&cal, ExportFormat::Plain).unwrap()).unwrap();
        let fusion: FusionStyle =
            toml::from_str(&export(&cal, ExportFormat::Fusion).unwrap()).unwrap();
        let kalibr: KalibrStyle =
            toml::from_str(&export(&cal, ExportFormat::Kalibr).unwrap()).unwrap();
        let all: Conversions = toml::from_str(&export(&cal, ExportFormat::All).unwrap()).unwrap();
        assert_eq!(all, convert(&cal).unwrap());
        assert_eq!(
            (&plain, &fusion, &kalibr),
            (&all.plain, &all.fusion, &all.kalibr)
        );
        let model = ForwardModel::new(&cal).unwrap();
        let g = cal.gravity_m_s2;
        for k in 0..50 {
            let x = k as f64;
            let f = [9.0 * (0.3 * x).sin(), -4.0 + 0.1 * x, 9.8 * (0.2 * x).cos()];
            let motion = BodyMotion {
                f_o: BodySpecificForce { m_s2: f },
                omega: BodyRate {
                    rad_s: [3.0 * (0.5 * x).cos(), 1.0, -0.02 * x],
                },
                omega_dot: BodyAngularAccel {
                    rad_s2: [0.0, 4.0 * (0.1 * x).sin(), 2.0],
                },
            };
            let u = model.outputs(&motion).raw;
            let (w, wd) = (motion.omega.rad_s, motion.omega_dot.rad_s2);
            let p = plain.compensate(u, w, wd);
            let kk = kalibr.compensate(u, w, wd);
            let still = BodyMotion {
                omega: BodyRate::default(),
                omega_dot: BodyAngularAccel::default(),
                ..motion
            };
            let fu = fusion
                .compensate_static_g(model.outputs(&still).raw)
                .map(|v| v * g);
            for j in 0..3 {
                assert!(
                    (p[j] - f[j]).abs() < 1e-9,
                    "plain {j}: {} vs {}",
                    p[j],
                    f[j]
                );
                assert!((kk[j] - f[j]).abs() < 1e-9, "kalibr {j}");
                assert!((fu[j] - f[j]).abs() < 1e-9, "fusion {j}");
            }
        }
    }

    #[test]
    fn export_format_names() {
        assert_eq!("kalibr".parse::<ExportFormat>(), Ok(ExportFormat::Kalibr));
        assert!("yaml"
            .parse::<ExportFormat>()
            .unwrap_err()
            .contains("plain"));
    }
}
