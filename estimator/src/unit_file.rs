//! The unit file: a unit's parameters in the paper's layout, as TOML. The same schema serves the
//! simulator's truth (`../shared/reference/paper-unit.toml` is the default) and the calibrator's result
//! (`calibration.toml`, which adds 1σ uncertainties), so `host simulate --unit calibration.toml`
//! round-trips.
//!
//! ```toml
//! g_m_s2 = 9.80665
//! unit_id = "000102030405060708090a0b"   # optional, 24 hex digits
//! output_unit = "V"                        # optional, "V" (default) or "LSB"
//! [static]
//! zero_bias_v = [..]            # or zero_bias_lsb for LSB units
//! scale_v_per_g = [..]          # or scale_lsb_per_g
//! installation_angles_deg = [[..], [..], [..]]
//! [dynamic]
//! lever_arms_m = [[..], [..], [..]]
//! package = "single"           # optional: one package, the three rows equal (docs/model.md §4.7)
//! reference = "table-axis"      # or "centroid", or "body-point" with reference_offset_m = [..]
//! [uncertainty]                 # optional, 1σ, same units as the values
//! zero_bias_1sigma = [..]
//! scale_per_g_1sigma = [..]
//! installation_angles_deg_1sigma = [[..], ..]
//! lever_arms_m_1sigma = [[..], ..]
//! lever_arms_observable = [[true, ..], ..]
//! [gyro]                        # optional: w = matrix · ω_body + bias (absent: a perfect gyro)
//! bias_rad_s = [..]
//! matrix = [[..], [..], [..]]
//! bias_rad_s_1sigma = [..]      # optional, an estimate's 1σ
//! matrix_1sigma = [[..], ..]    # optional; entries above 1e-3: not determined by the plan
//! [temperature]                 # optional: docs/model.md §9
//! reference_c = 25.0
//! valid_range_c = [-20.0, 60.0]
//! zero_bias_out_per_c = [[c1, c2, c3], ..]   # per axis, output unit per °C, °C², °C³
//! scale_rel_per_c = [[c1, c2, c3], ..]       # per axis, relative scale per °C, °C², °C³
//! # an estimate adds zero_bias_degree, scale_degree and the 1σ of every coefficient
//! ```
//! Other top-level tables (`[procedure]`, `[expected]`, a simulator's `[noise]`) are kept in `other`.

use crate::estimate::Uncertainty;
use recording::session::Package;
use serde::{Deserialize, Serialize};
use shared::linalg::RowMajor3;
use shared::sensor_models::TemperatureModel;
use shared::{Calibration, LeverArms, OutputUnit, ReferencePoint, StaticParams, UnitId};
use std::path::{Path, PathBuf};

/// The paper's unit (Tables 1 and 3), built in.
pub const PAPER_UNIT_TOML: &str = include_str!("../../reference/paper-unit.toml");

/// Top-level tables a unit file may have besides the ones it interprets: kept as they are in
/// [`UnitFile::other`] (the paper's `[procedure]` and `[expected]`, the simulator's `[noise]` and
/// `[simulation]` in `truth.toml`).
pub(crate) const KNOWN_EXTRA_TABLES: &[&str] =
    &["procedure", "expected", "noise", "simulation", "thermal"];

/// Line and column (1-based) where top-level `key` is written: a `[key]` header or a `key =` line.
fn key_position(text: &str, key: &str) -> (usize, usize) {
    for (n, line) in text.lines().enumerate() {
        let t = line.trim_start();
        let col = line.len() - t.len() + 1;
        let bare = t.trim_start_matches('[').trim_start();
        let rest = bare.strip_prefix(key).or_else(|| {
            bare.strip_prefix('"')
                .and_then(|b| b.strip_prefix(key))
                .and_then(|b| b.strip_prefix('"'))
        });
        if let Some(rest) = rest {
            let rest = rest.trim_start();
            if rest.starts_with(['=', ']', '.']) {
                return (n + 1, col);
            }
        }
    }
    (1, 1)
}

/// A unit file.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct UnitFile {
    /// Local gravity, m/s².
    pub g_m_s2: f64,
    /// Unit identifier, 24 hex digits.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub unit_id: Option<String>,
    /// Output unit (default V).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub output_unit: Option<OutputUnit>,
    /// The body frame the calibration's angles, lever arms and gyro matrix are in (an estimate's;
    /// absent in a file written by hand or before the frame was recorded).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub frame: Option<FrameSection>,
    /// Table 1.
    #[serde(rename = "static")]
    pub statics: StaticSection,
    /// Table 3.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub dynamic: Option<DynamicSection>,
    /// 1σ uncertainties of an estimate.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub uncertainty: Option<Uncertainty>,
    /// The gyro model (absent: a perfect gyro).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub gyro: Option<GyroSection>,
    /// How the biases and scale factors move with temperature.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub temperature: Option<TemperatureSection>,
    /// Any other tables, kept as they are.
    #[serde(flatten)]
    pub other: toml::Table,
}

/// `[static]`.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct StaticSection {
    /// Zero-bias outputs, V.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub zero_bias_v: Option<[f64; 3]>,
    /// Zero-bias outputs, LSB.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub zero_bias_lsb: Option<[f64; 3]>,
    /// Scale factors, V/g.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub scale_v_per_g: Option<[f64; 3]>,
    /// Scale factors, LSB/g.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub scale_lsb_per_g: Option<[f64; 3]>,
    /// Zero-bias outputs, m/s² (a logger's unit kept as recorded).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub zero_bias_m_s2: Option<[f64; 3]>,
    /// Scale factors, (m/s²)/g.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub scale_m_s2_per_g: Option<[f64; 3]>,
    /// Zero-bias outputs, g (a logger's unit kept as recorded).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub zero_bias_g: Option<[f64; 3]>,
    /// Scale factors, g/g.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub scale_g_per_g: Option<[f64; 3]>,
    /// θ_ij, degrees.
    pub installation_angles_deg: RowMajor3,
    /// The counts of zero force subtracted from a raw log when it was read (`--acc-offset`), per
    /// axis: `zero_bias_lsb` is of the logger's own counts and holds them, so `apply` on a raw log
    /// applies the calibration to those counts (and refuses another offset). Absent: none was
    /// subtracted, or a file written before the offset was recorded.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub raw_offset_lsb: Option<[f64; 3]>,
}

/// `[frame]`: what the body axes are (docs/model.md §7): a fixture's, the housing's faces', or the
/// accelerometer triad's own when no attitude was known.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct FrameSection {
    /// Which frame.
    pub kind: FrameKind,
    /// The axes in words, for a reader of the file.
    pub axes: String,
}

/// Which body frame a calibration is in.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "lowercase")]
pub enum FrameKind {
    /// A fixture's: the plan's nominal ups.
    Fixture,
    /// The housing's: the faces the unit was set down on.
    Faces,
    /// The accelerometer triad's own (no attitude known).
    Accelerometer,
}

impl FrameKind {
    /// What the body axes are, in words, as `[frame]`'s `axes` says them (no figure of a session).
    pub fn axes(self) -> &'static str {
        match self {
            FrameKind::Fixture => {
                "the fixture's axes: the plan's nominal ups, the mounts' tilts averaging to zero \
                 within their attitude prior"
            }
            FrameKind::Faces => {
                "the housing's axes: each body axis along the normal of a face the unit was set \
                 down on, the faces' placement errors averaging to zero within their prior"
            }
            FrameKind::Accelerometer => {
                "the accelerometer triad's own: x along accelerometer x's sensing axis, y in the \
                 plane of the x and y sensing axes, z completing a right-handed frame"
            }
        }
    }
}

impl FrameSection {
    /// The section of a fit's body frame.
    pub fn of(frame: &crate::estimate::BodyFrame) -> FrameSection {
        let kind = frame.kind();
        FrameSection {
            kind,
            axes: kind.axes().into(),
        }
    }
}

/// `[dynamic]`.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct DynamicSection {
    /// Row i = r_i, body axes, m.
    pub lever_arms_m: RowMajor3,
    /// `"single"`: the three accelerometers share one package, so the three rows are one point
    /// (the package's lever arm) and the in-package size effect was not measured (docs/model.md
    /// §4.7). Absent: `"separate"`.
    #[serde(default, skip_serializing_if = "Package::is_separate")]
    pub package: Package,
    /// "table-axis" (default), "centroid" or "body-point".
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub reference: Option<String>,
    /// With reference = "body-point": the point, body axes, m.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub reference_offset_m: Option<[f64; 3]>,
}

/// `[gyro]`: the gyro reads `w = matrix · ω_body + bias` (docs/model.md §8).
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct GyroSection {
    /// Bias, gyro axes, rad/s.
    pub bias_rad_s: [f64; 3],
    /// Scale and misalignment (rows: gyro axes, columns: body axes).
    pub matrix: RowMajor3,
    /// 1σ of `bias_rad_s` (an estimate's).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub bias_rad_s_1sigma: Option<[f64; 3]>,
    /// 1σ of `matrix` (an estimate's; entries above 1e-3 are not determined by the plan).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub matrix_1sigma: Option<RowMajor3>,
}

/// `[temperature]`: the temperature model (docs/model.md §9) and, for an estimate, how it was chosen.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct TemperatureSection {
    /// `T_ref`, °C: the static values hold there.
    pub reference_c: f64,
    /// The temperatures the calibration covers, °C.
    pub valid_range_c: [f64; 2],
    /// Zero-bias change per axis, output unit per °C, °C², °C³.
    pub zero_bias_out_per_c: [[f64; 3]; 3],
    /// Relative scale change per axis, per °C, °C², °C³.
    pub scale_rel_per_c: [[f64; 3]; 3],
    /// Gyro bias change per axis, rad/s per °C, °C², °C³.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub gyro_bias_rad_s_per_c: Option<[[f64; 3]; 3]>,
    /// The degree of each zero-bias polynomial the data chose (an estimate's).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub zero_bias_degree: Option<[usize; 3]>,
    /// The degree of each scale polynomial the data chose.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub scale_degree: Option<[usize; 3]>,
    /// 1σ of `zero_bias_out_per_c` (0 for a coefficient the chosen degree leaves out).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub zero_bias_out_per_c_1sigma: Option<[[f64; 3]; 3]>,
    /// 1σ of `scale_rel_per_c`.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub scale_rel_per_c_1sigma: Option<[[f64; 3]; 3]>,
    /// The degree of each gyro bias polynomial the data chose (0: no dependence shown).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub gyro_bias_degree: Option<[usize; 3]>,
    /// 1σ of `gyro_bias_rad_s_per_c`.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub gyro_bias_rad_s_per_c_1sigma: Option<[[f64; 3]; 3]>,
}

impl TemperatureSection {
    /// The model alone.
    pub fn model(&self) -> TemperatureModel {
        TemperatureModel {
            reference_c: self.reference_c,
            valid_range_c: self.valid_range_c,
            zero_bias_out_per_c: self.zero_bias_out_per_c,
            scale_rel_per_c: self.scale_rel_per_c,
            gyro_bias_rad_s_per_c: self.gyro_bias_rad_s_per_c,
        }
    }

    /// The section of a model, without an estimate's extras.
    pub fn from_model(m: &TemperatureModel) -> TemperatureSection {
        TemperatureSection {
            reference_c: m.reference_c,
            valid_range_c: m.valid_range_c,
            zero_bias_out_per_c: m.zero_bias_out_per_c,
            scale_rel_per_c: m.scale_rel_per_c,
            gyro_bias_rad_s_per_c: m.gyro_bias_rad_s_per_c,
            zero_bias_degree: None,
            scale_degree: None,
            zero_bias_out_per_c_1sigma: None,
            scale_rel_per_c_1sigma: None,
            gyro_bias_degree: None,
            gyro_bias_rad_s_per_c_1sigma: None,
        }
    }
}

/// Why a unit file is unusable.
#[derive(Debug, thiserror::Error)]
pub enum UnitFileError {
    /// Not readable.
    #[error("cannot read unit file {}", .0.display())]
    Io(PathBuf, #[source] std::io::Error),
    /// Not valid TOML or wrong fields (the message names line and column).
    #[error("unit file {} is not valid: {}", .0.display(), .1)]
    Syntax(PathBuf, UnitFileSyntax),
    /// Semantically wrong (names the field and the fix).
    #[error("unit file {}", .0.display())]
    Invalid(PathBuf, #[source] UnitFileInvalid),
}

/// Why unit-file text is not a unit file: the TOML's own error (it names line and column), an array
/// longer than its field, or a key no unit file has.
#[derive(Debug, thiserror::Error)]
pub enum UnitFileSyntax {
    /// Not TOML, or a field of the wrong type.
    #[error("{0}")]
    Toml(toml::de::Error),
    /// An array longer than its field.
    #[error("{0}")]
    Surplus(recording::session::toml_check::SurplusValues),
    /// A key or table that no unit file has.
    #[error(
        "line {line}, column {column}: unknown key or table '{key}'; a unit file has g_m_s2, \
         unit_id, output_unit, [static], [dynamic], [uncertainty], [gyro], [temperature] and the \
         tables {}",
        KNOWN_EXTRA_TABLES.iter().map(|t| format!("[{t}]")).collect::<Vec<_>>().join(", ")
    )]
    UnknownKey {
        /// The key.
        key: String,
        /// Its line, from 1.
        line: usize,
        /// Its column, from 1.
        column: usize,
    },
}

/// Why a unit file's values are not a calibration; each names the field and the fix.
#[derive(Debug, thiserror::Error)]
pub enum UnitFileInvalid {
    /// `[static]` has keys of another unit too.
    #[error("[static] mixes units: with output_unit = \"{unit}\" use {bias} and {scale}")]
    MixedUnits {
        /// The output unit's symbol.
        unit: &'static str,
        /// Its zero-bias key.
        bias: &'static str,
        /// Its scale key.
        scale: &'static str,
    },
    /// A `[static]` key of the output unit is missing.
    #[error("[static] needs {0}")]
    Missing(&'static str),
    /// A single package with three different lever arms.
    #[error(
        "[dynamic] package = \"single\" needs the three rows of lever_arms_m equal (one package, \
         one lever arm): write the package's position three times, or remove package = \"single\""
    )]
    SinglePackageArms,
    /// A reference point that is none of the three, or an offset without `body-point`.
    #[error(
        "[dynamic] reference = {reference:?} with reference_offset_m = {offset_m:?}: use \
         \"table-axis\", \"centroid\", or \"body-point\" together with reference_offset_m"
    )]
    Reference {
        /// The reference given.
        reference: Option<String>,
        /// The offset given, m.
        offset_m: Option<[f64; 3]>,
    },
    /// A unit id that is not 24 hexadecimal digits.
    #[error("unit_id '{0}' must be 24 hexadecimal digits")]
    UnitId(String),
    /// The values do not make a compensator (a singular matrix, a non-finite value).
    #[error(transparent)]
    Compensator(#[from] shared::compensator::CompensatorError),
}

impl UnitFile {
    /// The built-in paper unit.
    pub fn paper_unit() -> UnitFile {
        toml::from_str(PAPER_UNIT_TOML).expect("the built-in unit file parses")
    }

    /// Reads a unit file.
    pub fn load(path: &Path) -> Result<UnitFile, UnitFileError> {
        let text = recording::limits::read_text_bounded(path)
            .map_err(|e| UnitFileError::Io(path.to_path_buf(), e))?;
        let file =
            UnitFile::parse(&text).map_err(|e| UnitFileError::Syntax(path.to_path_buf(), e))?;
        file.to_calibration()
            .map_err(|m| UnitFileError::Invalid(path.to_path_buf(), m))?;
        Ok(file)
    }

    /// Parses unit-file text strictly: an unknown key or table (a typo such as `[dynamc]`, which would
    /// otherwise silently mean zero lever arms) is an error naming its line and column.
    pub fn parse(text: &str) -> Result<UnitFile, UnitFileSyntax> {
        let file: UnitFile = toml::from_str(text).map_err(UnitFileSyntax::Toml)?;
        if let Some(e) = recording::session::toml_check::surplus_values(text, &file) {
            return Err(UnitFileSyntax::Surplus(e));
        }
        if let Some(key) = file
            .other
            .keys()
            .find(|k| !KNOWN_EXTRA_TABLES.contains(&k.as_str()))
        {
            let (line, column) = key_position(text, key);
            return Err(UnitFileSyntax::UnknownKey {
                key: key.clone(),
                line,
                column,
            });
        }
        Ok(file)
    }

    /// The unit id, if the file has a valid one.
    pub fn unit_id(&self) -> Result<Option<UnitId>, UnitFileInvalid> {
        match &self.unit_id {
            None => Ok(None),
            Some(s) => UnitId::parse_hex(s)
                .map(Some)
                .ok_or_else(|| UnitFileInvalid::UnitId(s.clone())),
        }
    }

    /// The calibration this file describes.
    pub fn to_calibration(&self) -> Result<Calibration, UnitFileInvalid> {
        let unit = self.output_unit.unwrap_or(OutputUnit::Volts);
        let s = &self.statics;
        let [v, lsb, m_s2, g] = s.by_unit();
        let (_, bias, scale, b_name, k_name) = match unit {
            OutputUnit::Volts => v,
            OutputUnit::Lsb => lsb,
            OutputUnit::MetresPerSecondSquared => m_s2,
            OutputUnit::StandardGravity => g,
        };
        let wrong_unit = s
            .by_unit()
            .iter()
            .any(|(u, b, k, ..)| *u != unit && (b.is_some() || k.is_some()));
        if wrong_unit {
            return Err(UnitFileInvalid::MixedUnits {
                unit: unit.symbol(),
                bias: b_name,
                scale: k_name,
            });
        }
        let bias = bias.ok_or(UnitFileInvalid::Missing(b_name))?;
        let scale = scale.ok_or(UnitFileInvalid::Missing(k_name))?;
        let statics = StaticParams {
            output_unit: unit,
            zero_bias_out: bias,
            scale_out_per_g: scale,
            installation_angles_deg: s.installation_angles_deg,
        };
        let (lever_arms, reference) = match &self.dynamic {
            None => (LeverArms::default(), ReferencePoint::TableAxis),
            Some(d) => {
                let r = &d.lever_arms_m;
                if d.package == Package::Single && (r[1] != r[0] || r[2] != r[0]) {
                    return Err(UnitFileInvalid::SinglePackageArms);
                }
                let reference = match (d.reference.as_deref(), d.reference_offset_m) {
                    (None | Some("table-axis"), None) => ReferencePoint::TableAxis,
                    (Some("centroid"), None) => ReferencePoint::Centroid,
                    (Some("body-point"), Some(offset_m)) => ReferencePoint::BodyPoint { offset_m },
                    (r, o) => {
                        return Err(UnitFileInvalid::Reference {
                            reference: r.map(str::to_string),
                            offset_m: o,
                        })
                    }
                };
                (
                    LeverArms {
                        r_m: d.lever_arms_m,
                    },
                    reference,
                )
            }
        };
        let cal = Calibration {
            statics,
            lever_arms,
            reference,
            gravity_m_s2: self.g_m_s2,
            gyro: self.gyro.as_ref().map(|g| shared::GyroCorrection {
                matrix: g.matrix,
                bias_rad_s: g.bias_rad_s,
            }),
            temperature: self.temperature.as_ref().map(TemperatureSection::model),
        };
        self.unit_id()?;
        shared::Compensator::new(&cal, shared::LeverMode::RateAndAcceleration)?;
        Ok(cal)
    }

    /// A unit file for a calibration (the inverse of [`UnitFile::to_calibration`]).
    pub fn from_calibration(
        cal: &Calibration,
        unit_id: Option<UnitId>,
        uncertainty: Option<Uncertainty>,
    ) -> UnitFile {
        let unit = cal.statics.output_unit;
        let is = |u: OutputUnit| unit == u;
        let (v, lsb) = (is(OutputUnit::Volts), is(OutputUnit::Lsb));
        let (ms2, g) = (
            is(OutputUnit::MetresPerSecondSquared),
            is(OutputUnit::StandardGravity),
        );
        let s = &cal.statics;
        let (reference, reference_offset_m) = match cal.reference {
            ReferencePoint::TableAxis => ("table-axis", None),
            ReferencePoint::Centroid => ("centroid", None),
            ReferencePoint::BodyPoint { offset_m } => ("body-point", Some(offset_m)),
        };
        UnitFile {
            g_m_s2: cal.gravity_m_s2,
            unit_id: unit_id.map(|u| u.to_string()),
            output_unit: Some(unit),
            frame: None,
            statics: StaticSection {
                zero_bias_v: v.then_some(s.zero_bias_out),
                zero_bias_lsb: lsb.then_some(s.zero_bias_out),
                scale_v_per_g: v.then_some(s.scale_out_per_g),
                scale_lsb_per_g: lsb.then_some(s.scale_out_per_g),
                zero_bias_m_s2: ms2.then_some(s.zero_bias_out),
                scale_m_s2_per_g: ms2.then_some(s.scale_out_per_g),
                zero_bias_g: g.then_some(s.zero_bias_out),
                scale_g_per_g: g.then_some(s.scale_out_per_g),
                installation_angles_deg: s.installation_angles_deg,
                raw_offset_lsb: None,
            },
            dynamic: Some(DynamicSection {
                lever_arms_m: cal.lever_arms.r_m,
                package: Package::Separate,
                reference: Some(reference.into()),
                reference_offset_m,
            }),
            uncertainty,
            gyro: cal.gyro.map(|g| GyroSection {
                bias_rad_s: g.bias_rad_s,
                matrix: g.matrix,
                bias_rad_s_1sigma: None,
                matrix_1sigma: None,
            }),
            temperature: cal.temperature.as_ref().map(TemperatureSection::from_model),
            other: toml::Table::new(),
        }
    }

    /// Where the unit's accelerometers are: one package or separate (docs/model.md §4.7).
    pub fn package(&self) -> Package {
        self.dynamic
            .as_ref()
            .map_or(Package::Separate, |d| d.package)
    }

    /// TOML text.
    pub fn to_toml(&self) -> String {
        let text = toml::to_string(self).expect("a unit file always serialises");
        matrices_as_rows(&text)
    }
}

/// `key = [[a, b, c], [d, e, f]]` (how the serialiser writes a matrix on one line) written one row
/// per line, as a reader writes a matrix; every other line as it is. The TOML value is the same.
fn matrices_as_rows(text: &str) -> String {
    let mut out = String::with_capacity(text.len() + 64);
    for line in text.lines() {
        let rows = line
            .split_once(" = [[")
            .and_then(|(key, rest)| Some((key, rest.strip_suffix("]]")?)));
        match rows {
            Some((key, inner)) => {
                out.push_str(key);
                out.push_str(" = [\n");
                for row in inner.split("], [") {
                    out.push_str("    [");
                    out.push_str(row);
                    out.push_str("],\n");
                }
                out.push_str("]\n");
            }
            None => {
                out.push_str(line);
                out.push('\n');
            }
        }
    }
    out
}

/// One unit's pair of `[static]` keys: (unit, zero bias, scale, their key names).
type UnitKeys = (
    OutputUnit,
    Option<[f64; 3]>,
    Option<[f64; 3]>,
    &'static str,
    &'static str,
);

impl StaticSection {
    /// The bias and scale keys of every output unit.
    fn by_unit(&self) -> [UnitKeys; 4] {
        [
            (
                OutputUnit::Volts,
                self.zero_bias_v,
                self.scale_v_per_g,
                "zero_bias_v",
                "scale_v_per_g",
            ),
            (
                OutputUnit::Lsb,
                self.zero_bias_lsb,
                self.scale_lsb_per_g,
                "zero_bias_lsb",
                "scale_lsb_per_g",
            ),
            (
                OutputUnit::MetresPerSecondSquared,
                self.zero_bias_m_s2,
                self.scale_m_s2_per_g,
                "zero_bias_m_s2",
                "scale_m_s2_per_g",
            ),
            (
                OutputUnit::StandardGravity,
                self.zero_bias_g,
                self.scale_g_per_g,
                "zero_bias_g",
                "scale_g_per_g",
            ),
        ]
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn an_array_longer_than_its_field_is_refused_not_cut() {
        UnitFile::parse(PAPER_UNIT_TOML).unwrap();
        let text = PAPER_UNIT_TOML.replace(
            "zero_bias_v = [2.405098, 2.380978, 2.435503]",
            "zero_bias_v = [2.405098, 2.380978, 2.435503, 9.0]",
        );
        let e = UnitFile::parse(&text).unwrap_err().to_string();
        assert!(
            e.contains("'static.zero_bias_v' has 4 values, 3 expected"),
            "{e}"
        );
        let gyro = "\n[gyro]\nbias_rad_s = [0, 0, 0]\nmatrix = [[1, 0, 0, 0], [0, 1, 0, 0], [0, 0, 1, 0]]\n";
        let e = UnitFile::parse(&format!("{PAPER_UNIT_TOML}{gyro}"))
            .unwrap_err()
            .to_string();
        assert!(
            e.contains("'gyro.matrix[0]' has 4 values, 3 expected"),
            "{e}"
        );
        let plan = "output_unit = \"V\"\nsample_rate_hz = 100\n[[segment]]\nname = \"x+\"\n\
                    up_b = [1, 0, 0, 7]\n";
        let e = recording::session::Plan::parse(plan)
            .unwrap_err()
            .to_string();
        assert!(
            e.contains("'segment[0].up_b' has 4 values, 3 expected"),
            "{e}"
        );
        recording::session::Plan::parse(&plan.replace(", 7]", "]")).unwrap();
    }

    #[test]
    fn paper_unit_reads_with_table_values() {
        let f = UnitFile::paper_unit();
        let cal = f.to_calibration().unwrap();
        assert_eq!(cal.statics.zero_bias_out, [2.405098, 2.380978, 2.435503]);
        assert_eq!(cal.lever_arms.r_m[1], [-0.00256, -0.00893, -0.00026]);
        assert!(f.other.contains_key("expected"));
        // The file form and the built-in constant are one unit.
        assert_eq!(cal, shared::params::PAPER_UNIT);
    }

    #[test]
    fn round_trips_through_toml_with_lsb_and_uncertainty() {
        let mut cal = shared::params::PAPER_UNIT;
        cal.statics.output_unit = shared::OutputUnit::Lsb;
        cal.statics.scale_out_per_g = [4096.0, 4100.0, 4090.0];
        cal.statics.zero_bias_out = [12.0, -40.0, 3.5];
        cal.reference = ReferencePoint::BodyPoint {
            offset_m: [0.001, 0.0, -0.002],
        };
        let unc = Uncertainty {
            zero_bias_1sigma: [0.1; 3],
            scale_per_g_1sigma: [0.2; 3],
            installation_angles_deg_1sigma: [[1e-3; 3]; 3],
            lever_arms_m_1sigma: [[1e-5; 3]; 3],
            lever_arms_observable: [[true, false, true]; 3],
        };
        let id = UnitId([7; 12]);
        let text = UnitFile::from_calibration(&cal, Some(id), Some(unc.clone())).to_toml();
        assert!(
            text.contains("scale_lsb_per_g") && !text.contains("scale_v_per_g"),
            "{text}"
        );
        let back: UnitFile = toml::from_str(&text).unwrap();
        assert_eq!(back.to_calibration().unwrap(), cal);
        assert_eq!(back.unit_id().unwrap(), Some(id));
        assert_eq!(back.uncertainty, Some(unc));
        // A matrix is written as a reader writes one: a row per line; a vector on one line.
        let angles = cal.statics.installation_angles_deg;
        let rows: String = angles
            .iter()
            .map(|r| format!("    [{:?}, {:?}, {:?}],\n", r[0], r[1], r[2]))
            .collect();
        assert!(
            text.contains(&format!("installation_angles_deg = [\n{rows}]\n")),
            "{text}"
        );
        assert!(
            text.contains("zero_bias_lsb = [12.0, -40.0, 3.5]\n"),
            "{text}"
        );
    }

    #[test]
    fn bad_files_get_messages_naming_the_field() {
        let dir = tempfile::tempdir().unwrap();
        let p = dir.path().join("u.toml");
        std::fs::write(
            &p,
            PAPER_UNIT_TOML.replace("scale_v_per_g", "scale_lsb_per_g"),
        )
        .unwrap();
        let e = shared::chain::Chain(&UnitFile::load(&p).unwrap_err()).to_string();
        assert!(
            e.contains("mixes units") || e.contains("needs scale_v_per_g"),
            "{e}"
        );
        std::fs::write(&p, "g_m_s2 = 9.8\n[static]\nzero_bias_v = [1, 2]\n").unwrap();
        let e = shared::chain::Chain(&UnitFile::load(&p).unwrap_err()).to_string();
        assert!(e.contains("line"), "{e}");
        let e = UnitFile::load(&dir.path().join("missing.toml"))
            .unwrap_err()
            .to_string();
        assert!(e.contains("cannot read"), "{e}");
    }

    /// `package = "single"` needs one point in the three rows, and a calibration file written for
    /// a single-package fit reads back as one.
    #[test]
    fn a_single_package_unit_has_one_lever_arm() {
        let text = include_str!("../../host/units/single-package.toml");
        let unit = UnitFile::parse(text).unwrap();
        assert_eq!(unit.package(), Package::Single);
        let cal = unit.to_calibration().unwrap();
        assert_eq!(cal.lever_arms.r_m, [[0.012, -0.007, 0.025]; 3]);
        let apart = text.replacen("[0.012, -0.007, 0.025],", "[0.0125, -0.007, 0.025],", 1);
        let e = UnitFile::parse(&apart)
            .unwrap()
            .to_calibration()
            .unwrap_err();
        assert!(
            e.to_string()
                .contains("package = \"single\" needs the three rows"),
            "{e}"
        );
        let mut back = UnitFile::from_calibration(&cal, None, None);
        assert_eq!(back.package(), Package::Separate);
        back.dynamic.as_mut().unwrap().package = Package::Single;
        let again = UnitFile::parse(&back.to_toml()).unwrap();
        assert_eq!(again.package(), Package::Single);
        assert_eq!(again.to_calibration().unwrap(), cal);
    }

    /// Each way a unit file's values fail is its own variant, and says what it said when it was a
    /// message (the texts written out here by hand).
    #[test]
    fn an_invalid_unit_file_says_which_field_and_the_fix() {
        let paper = UnitFile::paper_unit;
        let mut u = paper();
        u.statics.scale_v_per_g = None;
        let e = u.to_calibration().unwrap_err();
        assert!(
            matches!(e, UnitFileInvalid::Missing("scale_v_per_g")),
            "{e:?}"
        );
        assert_eq!(e.to_string(), "[static] needs scale_v_per_g");
        let mut u = paper();
        u.statics.zero_bias_lsb = Some([0.0; 3]);
        assert_eq!(
            u.to_calibration().unwrap_err().to_string(),
            "[static] mixes units: with output_unit = \"V\" use zero_bias_v and scale_v_per_g"
        );
        let mut u = paper();
        u.output_unit = Some(OutputUnit::Lsb);
        assert_eq!(
            u.to_calibration().unwrap_err().to_string(),
            "[static] mixes units: with output_unit = \"LSB\" use zero_bias_lsb and scale_lsb_per_g"
        );
        let mut u = paper();
        u.unit_id = Some("12".into());
        assert_eq!(
            u.to_calibration().unwrap_err().to_string(),
            "unit_id '12' must be 24 hexadecimal digits"
        );
        let mut u = paper();
        if let Some(d) = u.dynamic.as_mut() {
            d.reference = Some("centroid".into());
            d.reference_offset_m = Some([0.0, 0.0, 0.1]);
        }
        assert_eq!(
            u.to_calibration().unwrap_err().to_string(),
            "[dynamic] reference = Some(\"centroid\") with reference_offset_m = Some([0.0, 0.0, \
             0.1]): use \"table-axis\", \"centroid\", or \"body-point\" together with \
             reference_offset_m"
        );
        let mut u = paper();
        u.statics.scale_v_per_g = Some([0.0; 3]);
        let e = u.to_calibration().unwrap_err();
        assert!(matches!(e, UnitFileInvalid::Compensator(_)), "{e:?}");
    }
}
