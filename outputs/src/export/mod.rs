//! Our calibration in the formats other tools read (`host export --format F`), and the conversions
//! between our model and each tool's convention.
//!
//! Formats: [`ExportFormat`], one module each: [`kalibr`] (YAML), [`c`] (the C package, with the
//! portable blob decoder and the device's per-sample correction in `c/`, and Fusion's header),
//! [`json`], [`params`] (PX4 and ArduPilot), [`toml_forms`] (the conversions below as TOML). Each
//! writer states the conventions it assumes in the file it writes, marks what the target cannot hold,
//! and refuses (unless told) what the calibration did not determine or the target's documented range
//! excludes (never a silent zero or a NaN). The driver scale of the formats that read m/s² follows one
//! rule ([`ExportInput::driver_scale`]). `consumer_tests` reads each file the way its consumer does
//! and checks the consumer's own correction, written from its source, against `host apply`; the C
//! outputs are compiled and run against the Rust device code.
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
#[cfg(test)]
mod consumer_tests;
pub mod json;
pub mod kalibr;
pub mod params;
pub mod toml_forms;

use estimator::unit_file::UnitFile;
use recording::spelling::{Spelling, UserOption};
use serde::{Deserialize, Serialize};
use shared::linalg::{self, RowMajor3};
use shared::params::ParamsError;
use shared::{Calibration, OutputUnit};

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
    /// Kalibr's IMU YAML (imu.yaml): topic, rate, noise densities and random walks (needs --noise).
    Kalibr,
    /// Our accelerometer and gyro intrinsics in the form of Kalibr's scale-misalignment-size-effect
    /// results, for comparison with a Kalibr run.
    KalibrIntrinsics,
    /// A C header with x-io Fusion `FusionMatrix`/`FusionVector` initialisers for `FusionModelInertial`.
    FusionC,
    /// A C package (--out DIR): acal_calibration.h (the calibration as a struct initialiser, the
    /// device's precomputed constants, the blob as bytes), the blob decoder acal_blob.{h,c}, and the
    /// device's whole per-sample correction acal_device.{h,c}, and example.c (the blob decoded, one
    /// sample corrected, printed).
    C,
    /// acal_calibration.h alone, one file (for a firmware that has the package's acal_blob and
    /// acal_device already: a new unit's calibration is this one file).
    CHeader,
    /// Everything in the calibration file plus derived forms and fit statistics, as JSON.
    Json,
    /// A PX4 parameter file (QGroundControl format): CAL_ACC0_ID, CAL_ACC0_{X,Y,Z}{OFF,SCALE} and,
    /// with --gyro-device-id, CAL_GYRO0_ID and CAL_GYRO0_{X,Y,Z}OFF.
    Px4,
    /// An ArduPilot parameter file: INS_ACCOFFS_{X,Y,Z}, INS_ACCSCAL_{X,Y,Z}, INS_GYROFFS_{X,Y,Z}.
    Ardupilot,
    /// The paper's K_A, ∇_b and lever arms, as TOML.
    Plain,
    /// Fusion's misalignment, sensitivity and offset, as TOML.
    Fusion,
    /// The plain, Fusion and general Kalibr-style forms together, as TOML.
    All,
}

/// Why a calibration cannot be exported.
#[derive(Debug, thiserror::Error)]
pub enum ExportError {
    /// The parameters do not convert (degenerate axis, singular matrix…).
    #[error("cannot export the calibration")]
    Params(#[from] ParamsError),
    /// The compensator refuses the parameters.
    #[error("cannot export the calibration")]
    Compensator(#[source] shared::compensator::CompensatorError),
    /// The blob cannot be encoded.
    #[error("cannot export the calibration's blob")]
    Blob(#[source] shared::blob::BlobError),
    /// The calibration file's unit id is not one.
    #[error("cannot export the calibration's blob")]
    UnitId(#[source] estimator::unit_file::UnitFileInvalid),
    /// The calibration file has no unit id, which the blob needs.
    #[error(
        "cannot export the calibration's blob: the calibration file has no unit_id, and a blob is \
         bound to one unit; calibrate with the unit's id (or add unit_id = \"…24 hex digits…\")"
    )]
    NoUnitId,
    /// A file of the export could not be written (or exists, without `--force`).
    #[error(transparent)]
    Written(#[from] recording::output_file::OutputFileError),
    /// Writing TOML failed.
    #[error("cannot export the calibration")]
    Toml(#[source] toml::ser::Error),
    /// Writing JSON failed.
    #[error("cannot export the calibration")]
    Json(#[source] serde_json::Error),
    /// A scale factor is negative or zero: the convention (and every target's model) has positive
    /// ones.
    #[error("cannot export the calibration")]
    NegativeScale(#[from] crate::calibration_guard::ScaleError),
    /// The target reads m/s² from its driver, and the output unit does not say how to get there.
    #[error(
        "{format} reads the accelerometer in m/s² from its driver, and this calibration's output unit is {unit}: \
         give {}, the m/s² per {unit} the driver applies to the raw reading \
         (only the driver's configuration knows it; outputs in m/s² or g need none)",
        .spelling.given(UserOption::DriverScale, "M_S2_PER_UNIT")
    )]
    DriverScaleRequired {
        /// The format.
        format: &'static str,
        /// The output unit's symbol.
        unit: &'static str,
        /// The caller's names of the options.
        spelling: Spelling,
    },
    /// The driver scale given is not a positive finite number.
    #[error(
        "{} must be a positive, finite number of m/s² per output unit",
        .1.given(UserOption::DriverScale, .0)
    )]
    DriverScale(f64, Spelling),
    /// A value of the export does not fit the target's number type (e.g. an absurd driver scale).
    #[error(
        "cannot export {name} = {value:e}: beyond the target's single-precision range; \
         check {} (m/s² per output unit, e.g. 1 for a driver already in m/s²)",
        .spelling.name(UserOption::DriverScale)
    )]
    NotRepresentable {
        /// The parameter.
        name: String,
        /// Its value.
        value: f64,
        /// The caller's names of the options.
        spelling: Spelling,
    },
    /// A value lies outside the range the target documents for it.
    #[error(
        "{name} = {value} is outside {target}'s documented range {lo}..{hi}{hint}; \
         the target would reject or misuse it ({} writes it anyway, with a warning)",
        .spelling.switch(UserOption::AllowOutOfRange)
    )]
    OutOfRange {
        /// The parameter.
        name: String,
        /// Its value.
        value: f64,
        /// The target.
        target: &'static str,
        /// The documented lower end.
        lo: f64,
        /// The documented upper end.
        hi: f64,
        /// What probably caused it.
        hint: String,
        /// The caller's names of the options.
        spelling: Spelling,
    },
    /// Values the calibration did not determine would be written as numbers.
    #[error(
        "{format} would hold values the calibration did not determine ({names}); calibrate with a plan \
         that determines them, or give {} to write them marked UNDETERMINED",
        .spelling.switch(UserOption::AllowUndetermined)
    )]
    Undetermined {
        /// The format.
        format: &'static str,
        /// The entries.
        names: String,
        /// The caller's names of the options.
        spelling: Spelling,
    },
    /// Kalibr's form needs `c·K·A/g` (or `G·C_i_bᵀ`) as lower-triangular × rotation, which does not exist.
    #[error(
        "cannot write Kalibr's M*C_i_b: {0} is singular or left-handed (Kalibr's form needs a \
         right-handed, invertible triad)"
    )]
    NoKalibrFactorisation(&'static str),
    /// `K·A` has no inverse: the sensing directions are linearly dependent.
    #[error(
        "cannot export the calibration: its sensing directions are linearly dependent (K·A is \
         singular), so no correction exists; check the installation angles"
    )]
    Singular,
    /// Kalibr's `imu.yaml` without a noise analysis.
    #[error(
        "Kalibr needs the IMU's noise densities and random walks, which only a noise analysis gives: \
         run `host noise --input SESSION --out DIR` on a recording with a long still segment and give \
         {}",
        .0.given(UserOption::Noise, "DIR/noise.json")
    )]
    NoNoise(Spelling),
    /// A noise figure Kalibr needs that the noise analysis did not determine. The causes that fit:
    /// too short a recording always; for the accelerometer's figures also an output in volts or
    /// counts that `host noise` had no calibration to convert (`noise.json` comes from
    /// `host noise`, for Python callers too).
    #[error(
        "the noise analysis did not determine Kalibr's {name} (Kalibr refuses a missing or \
         non-positive value): its still recording is too short to show that term (noise.json's \
         `fits` say how long it would need to be){}",
        if name.starts_with("accelerometer") {
            ", or its accelerometer was not in m/s² or g and `host noise` had no --calibration \
             to convert it"
        } else {
            ""
        }
    )]
    NoiseFigure {
        /// Kalibr's key.
        name: &'static str,
    },
    /// An autopilot applies its calibration parameters only to the sensor whose id they carry.
    #[error(
        "{}: give {}, the vehicle's {id_parameter} as its parameter list shows it",
        .autopilot.why_the_id(),
        .spelling.given(UserOption::DeviceId, "ID")
    )]
    DeviceIdRequired {
        /// The target.
        autopilot: Autopilot,
        /// The target's parameter that holds the accelerometer's id.
        id_parameter: &'static str,
        /// The caller's names of the options.
        spelling: Spelling,
    },
    /// A slot beyond the autopilot's.
    #[error(
        "slot {slot}: {} keeps {} calibration slots (0..{})",
        .autopilot.name(),
        .autopilot.slots(),
        .autopilot.slots() - 1
    )]
    NoSuchSlot {
        /// The target.
        autopilot: Autopilot,
        /// The slot asked for.
        slot: u8,
    },
    /// A device id the target's parameter protocol cannot carry exactly.
    #[error(
        "{}: ArduPilot sends {name} as a float, exact only below 16777216 (2^24); check the \
         id against the vehicle's {name} in its parameter list",
        .spelling.given(*.option, .id)
    )]
    IdNotExact {
        /// The parameter.
        name: &'static str,
        /// The option that gave it.
        option: UserOption,
        /// The caller's names of the options.
        spelling: Spelling,
        /// The id given.
        id: u32,
    },
}

/// An autopilot whose parameters carry the device id they were calibrated for.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Autopilot {
    /// PX4: `CAL_ACC0_*` apply to the accelerometer whose device id is `CAL_ACC0_ID`.
    Px4,
    /// ArduPilot: `AP_InertialSensor::register_accel` counts `INS_ACC*` as a calibration only for
    /// the accelerometer whose id is `INS_ACC_ID`.
    ArduPilot,
}

impl Autopilot {
    /// The autopilot's name.
    pub fn name(self) -> &'static str {
        match self {
            Autopilot::Px4 => "PX4",
            Autopilot::ArduPilot => "ArduPilot",
        }
    }

    /// Its calibration slots per sensor (`recording::session::logs::vehicle`).
    pub fn slots(self) -> u8 {
        use recording::session::logs::vehicle::{ARDUPILOT_SLOTS, PX4_SLOTS};
        match self {
            Autopilot::Px4 => PX4_SLOTS,
            Autopilot::ArduPilot => ARDUPILOT_SLOTS,
        }
    }

    fn why_the_id(self) -> &'static str {
        match self {
            Autopilot::Px4 => {
                "PX4 applies CAL_ACC0_* only to the accelerometer whose device id is CAL_ACC0_ID \
                 (`listener sensor_accel` shows it as device_id on the vehicle)"
            }
            Autopilot::ArduPilot => {
                "ArduPilot counts INS_ACCOFFS_*/INS_ACCSCAL_* as a calibration only for the \
                 accelerometer whose id is INS_ACC_ID (pre-arm: \"3D Accel calibration needed\" \
                 otherwise; ArduPilot sets it at start-up to the accelerometer it detects)"
            }
        }
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
    /// accelerometer reading is `U × this`); `None`: from the output unit ([`ExportInput::driver_scale`]).
    pub driver_scale_m_s2_per_out: Option<f64>,
    /// The choices only the user can make (ids, what to allow).
    pub options: ExportOptions,
}

/// What an export needs from the user beyond the calibration.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct ExportOptions {
    /// Write values outside the target's documented range (with a warning) instead of refusing.
    pub allow_out_of_range: bool,
    /// Write entries the calibration did not determine (marked) instead of refusing.
    pub allow_undetermined: bool,
    /// The autopilot's device id of the accelerometer (PX4's `CAL_ACC0_ID`, ArduPilot's
    /// `INS_ACC_ID`).
    pub device_id: Option<u32>,
    /// The autopilot's device id of the gyro (`CAL_GYRO0_ID`, `INS_GYR_ID`); without it no gyro
    /// offsets are written.
    pub gyro_device_id: Option<u32>,
    /// The accelerometer's calibration slot (PX4's `n` of `CAL_ACCn_*`, ArduPilot's instance of
    /// `INS_ACC*`/`INS_ACC2*`/`INS_ACC3*`); `None`: the first.
    pub slot: Option<u8>,
    /// The gyro's slot; `None`: the accelerometer's.
    pub gyro_slot: Option<u8>,
    /// MAVLink system id of the vehicle, the first column of QGroundControl's parameter file.
    pub sysid: u8,
    /// MAVLink component id of the autopilot, the second column.
    pub compid: u8,
    /// How the caller names these options in messages.
    pub spelling: Spelling,
}

impl ExportOptions {
    /// Nothing allowed, no ids, vehicle and component 1, the messages spelled as the caller spells
    /// its options.
    pub fn new(spelling: Spelling) -> ExportOptions {
        ExportOptions {
            allow_out_of_range: false,
            allow_undetermined: false,
            device_id: None,
            gyro_device_id: None,
            slot: None,
            gyro_slot: None,
            sysid: 1,
            compid: 1,
            spelling,
        }
    }
}

/// The tests' options: [`ExportOptions::new`] with the neutral test spelling.
#[cfg(test)]
impl Default for ExportOptions {
    fn default() -> Self {
        ExportOptions::new(Spelling::default())
    }
}

#[cfg(test)]
impl<'a> ExportInput<'a> {
    /// The tests' input: this unit and calibration, no noise figures, the default driver scale.
    pub(crate) fn for_tests(unit: &'a UnitFile, cal: Calibration) -> ExportInput<'a> {
        ExportInput {
            unit,
            cal,
            noise: None,
            rostopic: "/imu0",
            driver_scale_m_s2_per_out: None,
            options: ExportOptions::default(),
        }
    }
}

/// Standard gravity, m/s²: the value of the unit "g" a driver converts with.
pub(crate) const STANDARD_GRAVITY_M_S2: f64 = 9.80665;

impl ExportInput<'_> {
    /// The driver's scale `c` (m/s² per output unit) for a target that reads `c·U` in m/s², the same
    /// rule in every format: as given; else 1 for an output already in m/s², standard gravity for one
    /// in g; for volts and LSB only the driver knows it, so it must be given.
    pub fn driver_scale(&self, format: &'static str) -> Result<f64, ExportError> {
        if let Some(c) = self.driver_scale_m_s2_per_out {
            return if c.is_finite() && c > 0.0 {
                Ok(c)
            } else {
                Err(ExportError::DriverScale(c, self.options.spelling))
            };
        }
        match self.cal.statics.output_unit {
            OutputUnit::MetresPerSecondSquared => Ok(1.0),
            OutputUnit::StandardGravity => Ok(STANDARD_GRAVITY_M_S2),
            unit @ (OutputUnit::Volts | OutputUnit::Lsb) => Err(ExportError::DriverScaleRequired {
                format,
                unit: unit.symbol(),
                spelling: self.options.spelling,
            }),
        }
    }
}

/// Refuses what no format can express faithfully: a negative scale factor
/// ([`crate::calibration_guard`]).
pub(crate) fn check_exportable(cal: &Calibration) -> Result<(), ExportError> {
    Ok(crate::calibration_guard::check_scales(cal)?)
}

/// `value` as the target's `f32`, refused when it does not fit.
pub(crate) fn as_f32(name: &str, value: f64, spelling: Spelling) -> Result<f32, ExportError> {
    let v = value as f32;
    if v.is_finite() {
        Ok(v)
    } else {
        Err(ExportError::NotRepresentable {
            name: name.to_string(),
            value,
            spelling,
        })
    }
}

/// A `#` comment for the formats that cannot hold a temperature model (Kalibr, the TOML forms): their
/// values are the calibration's at its reference temperature (docs/model.md §9).
pub(crate) fn temperature_not_held(cal: &Calibration, format: &str) -> String {
    match &cal.temperature {
        Some(t) => format!(
            "# NOT HELD by {format}: the temperature model ([temperature] in the calibration file); these \
             values hold at {} °C (valid {}..{} °C); use host apply or the c export for the model.\n",
            t.reference_c, t.valid_range_c[0], t.valid_range_c[1]
        ),
        None => String::new(),
    }
}

/// Writes `input` in `format`.
pub fn render(input: &ExportInput<'_>, format: ExportFormat) -> Result<String, ExportError> {
    check_exportable(&input.cal)?;
    let text = render_format(input, format)?;
    // A single-package unit's rows are one point: say so where the format has comments, so that no
    // export reads as a measured per-axis size effect (docs/model.md §4.7; the JSON form carries
    // the calibration file's `package = "single"`).
    let comment = match format {
        ExportFormat::Json => None,
        ExportFormat::FusionC | ExportFormat::C | ExportFormat::CHeader => Some("//"),
        _ => Some("#"),
    };
    Ok(match (input.unit.package(), comment) {
        (recording::session::Package::Single, Some(c)) => format!(
            "{c} single package: the three accelerometers' lever arms are one point, the package's r; \
             their in-package differences r_i - r were not observable and are written as 0\n{text}"
        ),
        _ => text,
    })
}

/// [`render`] before the single-package note.
fn render_format(input: &ExportInput<'_>, format: ExportFormat) -> Result<String, ExportError> {
    match format {
        ExportFormat::Kalibr => kalibr::render(input),
        ExportFormat::KalibrIntrinsics => kalibr::render_intrinsics(input),
        ExportFormat::FusionC => c::render_fusion(input),
        ExportFormat::C | ExportFormat::CHeader => c::render_header(input),
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
    #[cfg(test)]
    pub(crate) fn compensate(&self, u: [f64; 3], omega: [f64; 3], omega_dot: [f64; 3]) -> [f64; 3] {
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
    #[cfg(test)]
    pub(crate) fn compensate_static_g(&self, u: [f64; 3]) -> [f64; 3] {
        let scaled: [f64; 3] =
            std::array::from_fn(|i| (u[i] - self.offset[i]) * self.sensitivity[i]);
        linalg::mat_vec(&self.misalignment, &scaled)
    }
}

impl KalibrStyle {
    /// Solves `u_i = row_i(M)·(f + W r_i) + b_i` for `f` (m/s²).
    #[cfg(test)]
    pub(crate) fn compensate(&self, u: [f64; 3], omega: [f64; 3], omega_dot: [f64; 3]) -> [f64; 3] {
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
