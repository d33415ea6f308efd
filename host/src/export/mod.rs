//! Our calibration in the formats other tools read (`host export --format F`), and the conversions
//! between our model and each tool's convention.
//!
//! Formats: [`ExportFormat`], one module each: [`kalibr`] (YAML), [`c`] (C headers, with the portable
//! C blob decoder in `c/`), [`json`], [`params`] (PX4 and ArduPilot), [`toml_forms`] (the conversions
//! below as TOML). Each writer states the conventions it assumes in the file it writes, and
//! marks what the target cannot hold or what the calibration did not determine (never a silent zero).
//! Each is checked by its own consumer in the tests: gcc for the C outputs (run against the Rust
//! compensator), a YAML parser for Kalibr's file, a JSON parser for the JSON document.
//!
//! The conversions (each with its own `compensate`, written in that tool's convention; a test checks
//! that every form turns the same samples into the same specific force as `shared::Compensator`):
//!
//! - [`PlainMatrices`]: the paper's eq. 6 / 16 matrices, `f_b[g] = K_A·U − ∇_b − f_L^b`.
//! - [`FusionStyle`]: x-io Fusion's `FusionModelInertial`:
//!   `f[g] = misalignment · ((U − offset) ∘ sensitivity)`, with `misalignment = A⁻¹`,
//!   `sensitivity = 1/k` (g per output unit) and `offset = u0`. Fusion has no lever-arm terms.
//! - [`KalibrStyle`]: Kalibr's "scale-misalignment-size-effect" accelerometer model in its general
//!   form: the measurement of axis `i` is `row_i(M)·f(r_i) + b_i` with `M = K·A/g` (output unit per m/s²),
//!   `b = u0`, and the sensing point of axis x, y, z at `rx`, `ry`, `rz` (m, relative to the reference
//!   point). Kalibr itself writes `M` lower-triangular after a rotation into its IMU frame
//!   ([`kalibr`] does that factorisation).

pub mod c;
pub mod json;
pub mod kalibr;
pub mod params;
pub mod toml_forms;

use crate::unit_file::UnitFile;
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

/// The formats `host export` writes.
#[derive(Clone, Copy, Debug, PartialEq, Eq, clap::ValueEnum)]
pub enum ExportFormat {
    /// Kalibr's IMU YAML (imu.yaml): topic, rate, noise densities and random walks, plus the
    /// accelerometer intrinsics in Kalibr's scale-misalignment-size-effect parameterisation.
    Kalibr,
    /// A C header with x-io Fusion `FusionMatrix`/`FusionVector` initialisers for `FusionModelInertial`.
    FusionC,
    /// A C header: the calibration as a plain struct initialiser, the device's precomputed
    /// compensator constants, and the blob as a byte array (decode it with export/c/acal_blob.c).
    CHeader,
    /// Everything in the calibration file plus derived forms and fit statistics, as JSON.
    Json,
    /// A PX4 parameter file (QGroundControl format): CAL_ACC0_{X,Y,Z}{OFF,SCALE}.
    Px4,
    /// An ArduPilot parameter file: INS_ACCOFFS_{X,Y,Z}, INS_ACCSCAL_{X,Y,Z}.
    Ardupilot,
    /// The paper's K_A, ∇_b and lever arms, as TOML.
    Plain,
    /// Fusion's misalignment, sensitivity and offset, as TOML.
    Fusion,
    /// The plain, Fusion and general Kalibr-style forms together, as TOML.
    All,
}

/// Why a calibration cannot be exported.
#[derive(Debug)]
pub enum ExportError {
    /// The parameters do not convert (degenerate axis, singular matrix…).
    Params(ParamsError),
    /// The compensator refuses the parameters.
    Compensator(shared::compensator::CompensatorError),
    /// The blob cannot be encoded.
    Blob(shared::blob::BlobError),
    /// The calibration file has no valid unit id, which the blob needs.
    UnitId(String),
    /// Serialising failed.
    Serialise(String),
}

impl std::fmt::Display for ExportError {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match self {
            ExportError::Params(e) => write!(f, "cannot export the calibration: {e}"),
            ExportError::Compensator(e) => write!(f, "cannot export the calibration: {e}"),
            ExportError::Blob(e) => write!(f, "cannot export the calibration's blob: {e}"),
            ExportError::UnitId(m) => write!(f, "cannot export the calibration's blob: {m}"),
            ExportError::Serialise(m) => write!(f, "cannot export the calibration: {m}"),
        }
    }
}

impl std::error::Error for ExportError {}

impl From<ParamsError> for ExportError {
    fn from(e: ParamsError) -> Self {
        ExportError::Params(e)
    }
}

/// What an export is made from.
#[derive(Clone, Debug)]
pub struct ExportInput<'a> {
    /// The calibration file as read (uncertainty, unit id and observability included).
    pub unit: &'a UnitFile,
    /// Its calibration.
    pub cal: Calibration,
    /// Noise figures from `host noise`, if any (Kalibr needs them).
    pub noise: Option<&'a kalibr::KalibrNoise>,
    /// Kalibr's `rostopic`.
    pub rostopic: &'a str,
    /// m/s² per output unit of the driver the PX4/ArduPilot/Kalibr user runs (their raw
    /// accelerometer reading is `U × this`); `None`: `g / mean(k_i)`, a nominal scale.
    pub driver_scale_m_s2_per_out: Option<f64>,
}

#[cfg(test)]
impl<'a> ExportInput<'a> {
    /// The tests' input: this unit and calibration, no noise figures, the nominal driver scale.
    pub(crate) fn for_tests(unit: &'a UnitFile, cal: Calibration) -> ExportInput<'a> {
        ExportInput {
            unit,
            cal,
            noise: None,
            rostopic: "/imu0",
            driver_scale_m_s2_per_out: None,
        }
    }
}

impl ExportInput<'_> {
    /// The driver's scale: as given, or `g / mean(k_i)`.
    pub fn driver_scale(&self) -> f64 {
        self.driver_scale_m_s2_per_out.unwrap_or_else(|| {
            let k = self.cal.statics.scale_out_per_g;
            self.cal.gravity_m_s2 * 3.0 / (k[0] + k[1] + k[2])
        })
    }
}

/// A `#` comment for the formats that cannot hold a temperature model (Kalibr, the TOML forms): their
/// values are the calibration's at its reference temperature (docs/model.md §9).
pub(crate) fn temperature_not_held(cal: &Calibration, format: &str) -> String {
    match &cal.temperature {
        Some(t) => format!(
            "# NOT HELD by {format}: the temperature model ([temperature] in the calibration file); these \
             values hold at {} °C (valid {}..{} °C); use host apply or the c-header export for the model.\n",
            t.reference_c, t.valid_range_c[0], t.valid_range_c[1]
        ),
        None => String::new(),
    }
}

/// Writes `input` in `format`.
pub fn render(input: &ExportInput<'_>, format: ExportFormat) -> Result<String, ExportError> {
    match format {
        ExportFormat::Kalibr => kalibr::render(input),
        ExportFormat::FusionC => c::render_fusion(input),
        ExportFormat::CHeader => c::render_header(input),
        ExportFormat::Json => json::render(input),
        ExportFormat::Px4 => params::render_px4(input),
        ExportFormat::Ardupilot => params::render_ardupilot(input),
        ExportFormat::Plain | ExportFormat::Fusion | ExportFormat::All => {
            let observable = input.unit.uncertainty.as_ref();
            toml_forms::render_marked(
                &input.cal,
                format,
                observable.map(|u| &u.lever_arms_observable),
            )
        }
    }
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

#[cfg(test)]
mod tests {
    /// A format that cannot hold the temperature model says so instead of dropping it silently.
    #[test]
    fn formats_without_a_temperature_model_say_so() {
        let mut cal = shared::params::PAPER_UNIT;
        let plain = toml_forms::render_marked(&cal, ExportFormat::Plain, None).unwrap();
        assert!(!plain.contains("NOT HELD"), "{plain}");
        cal.temperature = Some(firmware::paper_unit::typical_thermal_model());
        let plain = toml_forms::render_marked(&cal, ExportFormat::Plain, None).unwrap();
        assert!(
            plain.starts_with("# NOT HELD by these forms: the temperature model")
                && plain.contains("hold at 25 °C"),
            "{plain}"
        );
    }

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
}
