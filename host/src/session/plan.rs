//! `plan.toml`: what a calibration session does, segment by segment (format in `docs/recording-format.md`).

use serde::{Deserialize, Serialize};
use shared::OutputUnit;
use std::collections::HashSet;
use std::path::Path;

/// Plan format version 1: `samples.csv` without temperature (the default when absent).
pub const PLAN_FORMAT_VERSION: u32 = 1;
/// Plan format version 2: `samples.csv` ends with the unit's temperature, `temp_c`.
pub const PLAN_FORMAT_VERSION_TEMPERATURE: u32 = 2;

/// Output unit as spelled in files: "V" or "LSB".
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize)]
pub enum OutputUnitName {
    /// Volts.
    V,
    /// ADC counts.
    #[serde(rename = "LSB")]
    Lsb,
}

impl From<OutputUnitName> for OutputUnit {
    fn from(u: OutputUnitName) -> Self {
        match u {
            OutputUnitName::V => OutputUnit::Volts,
            OutputUnitName::Lsb => OutputUnit::Lsb,
        }
    }
}

impl From<OutputUnit> for OutputUnitName {
    fn from(u: OutputUnit) -> Self {
        match u {
            OutputUnit::Volts => OutputUnitName::V,
            OutputUnit::Lsb => OutputUnitName::Lsb,
        }
    }
}

fn default_version() -> u32 {
    PLAN_FORMAT_VERSION
}
fn default_gravity() -> f64 {
    shared::STANDARD_GRAVITY_M_S2
}

/// A calibration plan.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Plan {
    /// Format version of this file.
    #[serde(default = "default_version")]
    pub format_version: u32,
    /// Unit of the accelerometer outputs in `samples.csv`.
    pub output_unit: OutputUnitName,
    /// Sample rate of `samples.csv`, Hz.
    pub sample_rate_hz: f64,
    /// Local gravity, m/s².
    #[serde(default = "default_gravity")]
    pub gravity_m_s2: f64,
    /// Identifier of the unit recorded (24 hex digits; written by the live procedure from the device's
    /// identity). The calibration blob is bound to it.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub unit_id: Option<String>,
    /// The segments, in the order they are run.
    #[serde(rename = "segment")]
    pub segments: Vec<SegmentPlan>,
}

/// One segment: a fixed mount ("up" direction) at rest, at a constant table rate, or ramping.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct SegmentPlan {
    /// Unique name; `samples.csv` rows refer to it.
    pub name: String,
    /// Direction of "up" (the +1 g specific force at rest) in body axes; unit vector.
    pub up_b: [f64; 3],
    /// Table rate about the vertical at the segment's start, °/s, signed; 0 for static.
    #[serde(default)]
    pub rate_deg_s: f64,
    /// Table rate at the segment's end for a spin-up/spin-down (linear ramp), °/s. Absent: constant.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub rate_end_deg_s: Option<f64>,
    /// Planned duration, s (used by `simulate` and by the live procedure).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub duration_s: Option<f64>,
    /// Position of the table's spin-axis point relative to the body origin, body axes, m
    /// (`docs/model.md` §5). Absent: unknown (the estimator treats it per `mount`).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub table_centre_m: Option<[f64; 3]>,
    /// Name of the physical mount; segments with the same mount share one table centre.
    /// Absent: the segment's own `up_b` names its mount.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub mount: Option<String>,
    /// Thermal chamber set-point at the segment's start, °C (a soak step; docs/model.md §9). Absent:
    /// no chamber. The estimator uses the recorded `temp_c`, never this.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub temp_c: Option<f64>,
    /// Set-point at the segment's end for a slow ramp, °C. Absent: constant.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub temp_end_c: Option<f64>,
}

impl SegmentPlan {
    /// At rest for the whole segment.
    pub fn is_static(&self) -> bool {
        self.rate_deg_s == 0.0 && self.rate_end_deg_s.is_none_or(|r| r == 0.0)
    }

    /// The mount this segment belongs to.
    pub fn mount_name(&self) -> String {
        self.mount.clone().unwrap_or_else(|| {
            format!(
                "up({:+.4},{:+.4},{:+.4})",
                self.up_b[0], self.up_b[1], self.up_b[2]
            )
        })
    }
}

/// Why a plan is unusable.
#[derive(Debug)]
pub enum PlanError {
    /// The file could not be read.
    Io(std::path::PathBuf, std::io::Error),
    /// The TOML does not parse or has wrong fields (the message names line and column).
    Syntax(std::path::PathBuf, String),
    /// A format version this build does not read.
    Version(u32),
    /// Semantic problem, naming the segment.
    Invalid(String),
}

impl std::fmt::Display for PlanError {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match self {
            PlanError::Io(p, e) => write!(f, "cannot read plan {}: {e}", p.display()),
            PlanError::Syntax(p, e) => write!(f, "plan {} is not valid: {e}", p.display()),
            PlanError::Version(v) => write!(
                f,
                "plan format_version {v} is not supported (this build reads {PLAN_FORMAT_VERSION} and \
                 {PLAN_FORMAT_VERSION_TEMPERATURE}); upgrade the tool or rewrite the plan"
            ),
            PlanError::Invalid(m) => write!(f, "plan is not usable: {m}"),
        }
    }
}

impl std::error::Error for PlanError {}

impl Plan {
    /// Reads and validates a plan file.
    pub fn load(path: &Path) -> Result<Plan, PlanError> {
        let text =
            std::fs::read_to_string(path).map_err(|e| PlanError::Io(path.to_path_buf(), e))?;
        Plan::parse(&text).map_err(|e| match e {
            PlanError::Syntax(_, m) => PlanError::Syntax(path.to_path_buf(), m),
            other => other,
        })
    }

    /// Parses and validates plan text.
    pub fn parse(text: &str) -> Result<Plan, PlanError> {
        let plan: Plan =
            toml::from_str(text).map_err(|e| PlanError::Syntax("<text>".into(), e.to_string()))?;
        plan.validate()?;
        Ok(plan)
    }

    /// Semantic checks: version, positive rate, unique names, unit `up_b`, finite numbers.
    pub fn validate(&self) -> Result<(), PlanError> {
        if ![PLAN_FORMAT_VERSION, PLAN_FORMAT_VERSION_TEMPERATURE].contains(&self.format_version) {
            return Err(PlanError::Version(self.format_version));
        }
        if !(self.sample_rate_hz.is_finite() && self.sample_rate_hz > 0.0) {
            return Err(PlanError::Invalid(
                "sample_rate_hz must be a positive number".into(),
            ));
        }
        if !(9.7..=9.9).contains(&self.gravity_m_s2) {
            return Err(PlanError::Invalid(format!(
                "gravity_m_s2 = {} is not a local gravity (9.7..9.9 m/s²)",
                self.gravity_m_s2
            )));
        }
        if let Some(id) = &self.unit_id {
            if shared::UnitId::parse_hex(id).is_none() {
                return Err(PlanError::Invalid(format!(
                    "unit_id '{id}' must be 24 hexadecimal digits"
                )));
            }
        }
        if self.segments.is_empty() {
            return Err(PlanError::Invalid("the plan has no [[segment]]".into()));
        }
        let mut names = HashSet::new();
        for s in &self.segments {
            if !names.insert(s.name.as_str()) {
                return Err(PlanError::Invalid(format!(
                    "segment name '{}' is used twice",
                    s.name
                )));
            }
            if s.name.is_empty() || s.name.contains([',', '"', '\n']) {
                return Err(PlanError::Invalid(format!(
                    "segment name '{}' must be non-empty and free of commas and quotes",
                    s.name
                )));
            }
            let n = shared::linalg::norm(&s.up_b);
            if !n.is_finite() || (n - 1.0).abs() > 1e-3 {
                return Err(PlanError::Invalid(format!(
                    "segment '{}': up_b {:?} is not a unit vector (norm {n:.4})",
                    s.name, s.up_b
                )));
            }
            let numbers = [
                s.rate_deg_s,
                s.rate_end_deg_s.unwrap_or(0.0),
                s.duration_s.unwrap_or(1.0),
            ];
            if numbers.iter().any(|v| !v.is_finite()) || s.duration_s.is_some_and(|d| d <= 0.0) {
                return Err(PlanError::Invalid(format!(
                    "segment '{}': rates must be finite and duration_s positive",
                    s.name
                )));
            }
            self.validate_temperatures(s)?;
        }
        Ok(())
    }

    /// Chamber set-points are plausible and recorded: a plan that sets them must record `temp_c`.
    fn validate_temperatures(&self, s: &SegmentPlan) -> Result<(), PlanError> {
        let (lo, hi) = shared::sensor_models::TEMPERATURE_LIMITS_C;
        for t in [s.temp_c, s.temp_end_c].into_iter().flatten() {
            if !(lo..=hi).contains(&t) {
                return Err(PlanError::Invalid(format!(
                    "segment '{}': temperature {t} °C is outside {lo}..{hi} °C",
                    s.name
                )));
            }
        }
        if s.temp_end_c.is_some() && s.temp_c.is_none() {
            return Err(PlanError::Invalid(format!(
                "segment '{}': temp_end_c needs temp_c (the ramp's start)",
                s.name
            )));
        }
        if s.temp_c.is_some() && !self.has_temperature() {
            return Err(PlanError::Invalid(format!(
                "segment '{}' sets a chamber temperature but the recording would not hold it: \
                 set format_version = {PLAN_FORMAT_VERSION_TEMPERATURE} (samples.csv with temp_c)",
                s.name
            )));
        }
        Ok(())
    }

    /// True when `samples.csv` carries the unit's temperature (format version 2).
    pub fn has_temperature(&self) -> bool {
        self.format_version == PLAN_FORMAT_VERSION_TEMPERATURE
    }

    /// The columns of this plan's `samples.csv`.
    pub fn columns(&self) -> &'static [&'static str] {
        if self.has_temperature() {
            &super::COLUMNS_TEMPERATURE
        } else {
            &super::COLUMNS
        }
    }

    /// The segment called `name`.
    pub fn segment(&self, name: &str) -> Option<&SegmentPlan> {
        self.segments.iter().find(|s| s.name == name)
    }

    /// Serialises to TOML.
    pub fn to_toml(&self) -> String {
        toml::to_string_pretty(self).expect("a plan always serialises")
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    const GOOD: &str = r#"
output_unit = "V"
sample_rate_hz = 1000
[[segment]]
name = "x+"
up_b = [1, 0, 0]
duration_s = 60
[[segment]]
name = "x+ 100"
up_b = [1, 0, 0]
rate_deg_s = 100
"#;

    #[test]
    fn parses_and_round_trips() {
        let p = Plan::parse(GOOD).unwrap();
        assert_eq!(p.segments.len(), 2);
        assert!(p.segments[0].is_static() && !p.segments[1].is_static());
        assert_eq!(p.gravity_m_s2, shared::STANDARD_GRAVITY_M_S2);
        assert_eq!(Plan::parse(&p.to_toml()).unwrap(), p);
    }

    #[test]
    fn errors_name_the_problem() {
        let e = Plan::parse(&GOOD.replace("[1, 0, 0]\nduration_s", "[1, 1, 0]\nduration_s"))
            .unwrap_err();
        assert!(
            e.to_string().contains("'x+'") && e.to_string().contains("unit vector"),
            "{e}"
        );
        let e = Plan::parse(&GOOD.replace("x+ 100", "x+")).unwrap_err();
        assert!(e.to_string().contains("used twice"), "{e}");
        let e = Plan::parse(&GOOD.replace("sample_rate_hz", "sample_rat_hz")).unwrap_err();
        assert!(e.to_string().contains("line"), "{e}");
        let e = Plan::parse(&format!("format_version = 9\n{GOOD}")).unwrap_err();
        assert!(matches!(e, PlanError::Version(9)));
    }

    #[test]
    fn chamber_temperatures_need_format_version_2() {
        let with_temp = GOOD.replace("duration_s = 60", "duration_s = 60\ntemp_c = -20");
        let e = Plan::parse(&with_temp).unwrap_err();
        assert!(e.to_string().contains("format_version = 2"), "{e}");
        let p = Plan::parse(&format!("format_version = 2\n{with_temp}")).unwrap();
        assert!(p.has_temperature());
        assert_eq!(p.segments[0].temp_c, Some(-20.0));
        assert_eq!(p.columns().last(), Some(&"temp_c"));
        assert_eq!(Plan::parse(&p.to_toml()).unwrap(), p);
        let hot = with_temp.replace("temp_c = -20", "temp_c = 500");
        let e = Plan::parse(&format!("format_version = 2\n{hot}")).unwrap_err();
        assert!(e.to_string().contains("500"), "{e}");
        let ramp = with_temp.replace("temp_c = -20", "temp_end_c = 20");
        let e = Plan::parse(&format!("format_version = 2\n{ramp}")).unwrap_err();
        assert!(e.to_string().contains("needs temp_c"), "{e}");
    }
}
