//! `plan.toml`: what a calibration session does, segment by segment (format in `docs/recording-format.md`).

use serde::{Deserialize, Serialize};
use shared::OutputUnit;
use std::collections::HashSet;
use std::path::Path;

/// The recording format's version: `format_version` in `plan.toml`, which says what the plan may
/// contain and which header `samples.csv` has (docs/recording-format.md). Every reader, writer and
/// message takes its number from here, so that they cannot disagree about which version holds what.
#[derive(Clone, Copy, Debug, PartialEq, Eq, PartialOrd, Ord, Hash)]
pub enum RecordingVersion {
    /// Version 1: every mount on the fixture, taken as exact; eight columns.
    V1 = 1,
    /// Version 2: version 1 plus the fixture's attitude accuracy (`attitude_sigma_deg`), free
    /// attitudes and the table's rate accuracy (`table_rate_sigma_ppm`); eight columns.
    V2Attitudes = 2,
    /// Version 3: version 2 plus the unit's temperature: chamber set-points on segments and a ninth
    /// column, `temp_c` (docs/model.md §9).
    V3Temperature = 3,
}

impl RecordingVersion {
    /// The oldest version this build reads.
    pub(crate) const OLDEST: RecordingVersion = RecordingVersion::V1;
    /// The newest version this build reads and writes.
    pub(crate) const NEWEST: RecordingVersion = RecordingVersion::V3Temperature;
    /// The version a plan without `format_version` has: version 2 reads every version 1 plan
    /// unchanged, and a plan that wants temperature has to say so.
    pub const DEFAULT: RecordingVersion = RecordingVersion::V2Attitudes;

    /// The version numbered `n`, if this build knows it.
    pub const fn from_number(n: u32) -> Option<RecordingVersion> {
        match n {
            1 => Some(RecordingVersion::V1),
            2 => Some(RecordingVersion::V2Attitudes),
            3 => Some(RecordingVersion::V3Temperature),
            _ => None,
        }
    }

    /// Its number, as `format_version` writes it.
    pub const fn number(self) -> u32 {
        self as u32
    }

    /// True when `samples.csv` ends with the unit's temperature, `temp_c`.
    pub const fn has_temperature(self) -> bool {
        self.number() >= RecordingVersion::V3Temperature.number()
    }

    /// True when the plan may give attitude priors, free attitudes and the table's rate accuracy.
    pub const fn has_attitudes(self) -> bool {
        self.number() >= RecordingVersion::V2Attitudes.number()
    }

    /// The columns of `samples.csv`, in order.
    pub const fn columns(self) -> &'static [&'static str] {
        if self.has_temperature() {
            &super::COLUMNS_TEMPERATURE
        } else {
            &super::COLUMNS
        }
    }

    /// The exact first line of `samples.csv`.
    pub const fn samples_header(self) -> &'static str {
        if self.has_temperature() {
            super::SAMPLES_HEADER_TEMPERATURE
        } else {
            super::SAMPLES_HEADER
        }
    }
}

/// The number only, as in `format_version = 3`, so messages can quote it as the plan spells it.
impl std::fmt::Display for RecordingVersion {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        write!(f, "{}", self.number())
    }
}

/// [`RecordingVersion::DEFAULT`]'s number, for plans built in code.
pub const PLAN_FORMAT_VERSION: u32 = RecordingVersion::DEFAULT.number();
/// [`RecordingVersion::V3Temperature`]'s number, for plans built in code that record `temp_c`.
pub const PLAN_FORMAT_VERSION_TEMPERATURE: u32 = RecordingVersion::V3Temperature.number();

/// 1σ of each mount's tilt (per axis perpendicular to the nominal up) when the plan says nothing,
/// degrees. A machined fixture on a levelled rate table is good to a few arc-minutes at best once the
/// unit's own seating on the fixture is counted; 0.05° (3 arc-minutes) is the order of a good
/// commercial fixture and its seating repeatability. Taking it as exact instead costs ~1 mg at this
/// level (docs/model.md §7), while a prior that is somewhat too wide costs almost nothing.
pub(crate) const DEFAULT_ATTITUDE_SIGMA_DEG: f64 = 0.05;

/// 1σ of a rate table's relative rate error when the plan says nothing, ppm: 0.001 %, a good
/// precision rate table's rate accuracy averaged over whole turns (such tables quote 1–10 ppm; a
/// plain turntable without an encoder-locked servo is worse, and its plan should say so). The gyro's
/// scale factors cannot be better than this.
pub(crate) const DEFAULT_TABLE_RATE_SIGMA_PPM: f64 = 10.0;

/// How a segment's attitude is known.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "lowercase")]
pub enum Attitude {
    /// On the fixture: `up_b` is the nominal up, with the mount's `attitude_sigma_deg` prior.
    #[default]
    Fixture,
    /// Unknown (e.g. held by hand): `up_b`, when given, is only a rough guess; the direction is
    /// estimated from the data with no prior.
    Free,
    /// Set down on a face of the unit's housing (or held on it by hand), as `host segment` finds
    /// it: `up_b` is that face's normal, a body axis, with the segment's prior. The faces, not a
    /// fixture, then fix the body frame (docs/model.md §7.1).
    Face,
}

fn is_fixture(a: &Attitude) -> bool {
    *a == Attitude::Fixture
}

fn is_zero3(v: &[f64; 3]) -> bool {
    *v == [0.0; 3]
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
    pub output_unit: OutputUnit,
    /// Sample rate of `samples.csv`, Hz.
    pub sample_rate_hz: f64,
    /// Local gravity, m/s².
    #[serde(default = "default_gravity")]
    pub gravity_m_s2: f64,
    /// Identifier of the unit recorded (24 hex digits; written by the live procedure from the device's
    /// identity). The calibration blob is bound to it.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub unit_id: Option<String>,
    /// 1σ of each mount's tilt away from its nominal up, per axis, degrees (format 2). Absent:
    /// `DEFAULT_ATTITUDE_SIGMA_DEG`; 0: the fixture is taken as exact.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub attitude_sigma_deg: Option<f64>,
    /// 1σ of the rate table's relative rate error, ppm (format 2): the gyro's scale factors cannot
    /// be better. Absent: `DEFAULT_TABLE_RATE_SIGMA_PPM`.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub table_rate_sigma_ppm: Option<f64>,
    /// Whether the three accelerometers share one package (`"single"`: a MEMS IMU, one lever arm for
    /// the three, docs/model.md §4.7) or sit apart (`"separate"`, the default).
    #[serde(default, skip_serializing_if = "Package::is_separate")]
    pub package: Package,
    /// Outputs in counts read from a logger's file with its counts of zero force (`--acc-offset`,
    /// an unsigned output's mid-scale), per axis: `samples.csv` holds the logger's own counts (the
    /// offset added back), so a calibration made from it has biases in those counts, the offset
    /// in them, and records it for `apply`. Absent: none was subtracted.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub acc_offset: Option<[f64; 3]>,
    /// The segments, in the order they are run.
    #[serde(rename = "segment")]
    pub segments: Vec<SegmentPlan>,
}

/// Where a unit's three accelerometers are (docs/model.md §4.7).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "lowercase")]
pub enum Package {
    /// Three separate sensors, each with its own lever arm (the paper's unit).
    #[default]
    Separate,
    /// One package (a MEMS IMU): its sensing points are within a millimetre, one lever arm `r`.
    Single,
}

impl Package {
    /// Whether it is [`Package::Separate`] (the default, left out when written).
    pub fn is_separate(&self) -> bool {
        *self == Package::Separate
    }
}

/// One segment: a fixed mount ("up" direction) at rest, at a constant table rate, or ramping.
#[derive(Clone, Debug, Default, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct SegmentPlan {
    /// Unique name; `samples.csv` rows refer to it.
    pub name: String,
    /// Direction of "up" (the +1 g specific force at rest) in body axes; unit vector. May be left out
    /// (all zero) only for a free attitude.
    #[serde(default, skip_serializing_if = "is_zero3")]
    pub up_b: [f64; 3],
    /// Whether `up_b` is a fixture's nominal or unknown (format 2).
    #[serde(default, skip_serializing_if = "is_fixture")]
    pub attitude: Attitude,
    /// This segment's mount tilt 1σ, degrees, over the plan's (format 2; all segments of a mount
    /// must agree).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub attitude_sigma_deg: Option<f64>,
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
    /// (`docs/model.md` §4.5). Absent: unknown (the estimator treats it per `mount`).
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

    /// The attitude is unknown (estimated with no prior).
    pub fn is_free(&self) -> bool {
        self.attitude == Attitude::Free
    }

    /// `up_b` was given (always for a fixture segment).
    pub fn has_up(&self) -> bool {
        !is_zero3(&self.up_b)
    }

    /// The mount this segment belongs to: its `mount`, else its own name for a free attitude (each
    /// hand-held position is its own mount), else named after `up_b`.
    pub fn mount_name(&self) -> String {
        if self.mount.is_none() && self.is_free() {
            return format!("free '{}'", self.name);
        }
        self.mount.clone().unwrap_or_else(|| {
            format!(
                "up({:+.4},{:+.4},{:+.4})",
                self.up_b[0], self.up_b[1], self.up_b[2]
            )
        })
    }
}

/// Why a plan is unusable.
#[derive(Debug, thiserror::Error)]
pub enum PlanError {
    /// The file could not be read.
    #[error("cannot read plan {}", .0.display())]
    Io(std::path::PathBuf, #[source] std::io::Error),
    /// The TOML does not parse or has wrong fields (the message names line and column). The cause
    /// is kept as a value (not its text) and said in the message, so it is not also a `source`.
    #[error("plan {} is not valid: {}", .0.display(), .1)]
    Syntax(std::path::PathBuf, Box<toml::de::Error>),
    /// An array in the plan longer than the field that reads it, which serde would cut short.
    #[error("plan {} is not valid: {}", .0.display(), .1)]
    Surplus(std::path::PathBuf, super::toml_check::SurplusValues),
    /// A number out of its range (the rate); said in the message, so not also a `source`.
    #[error("plan is not usable: {0}")]
    Range(crate::limits::RangeError),
    /// A format version this build does not read.
    #[error(
        "plan format_version {} is not supported (this build reads {} to {}); upgrade \
         the tool or rewrite the plan",
        .0,
        RecordingVersion::OLDEST,
        RecordingVersion::NEWEST
    )]
    Version(u32),
    /// Semantic problem, naming the segment.
    #[error("plan is not usable: {0}")]
    Invalid(String),
}

impl Plan {
    /// Reads and validates a plan file.
    pub fn load(path: &Path) -> Result<Plan, PlanError> {
        let text = crate::limits::read_text_bounded(path)
            .map_err(|e| PlanError::Io(path.to_path_buf(), e))?;
        Plan::parse(&text).map_err(|e| match e {
            PlanError::Syntax(_, m) => PlanError::Syntax(path.to_path_buf(), m),
            PlanError::Surplus(_, m) => PlanError::Surplus(path.to_path_buf(), m),
            other => other,
        })
    }

    /// Parses and validates plan text.
    pub fn parse(text: &str) -> Result<Plan, PlanError> {
        let plan: Plan =
            toml::from_str(text).map_err(|e| PlanError::Syntax("<text>".into(), Box::new(e)))?;
        if let Some(e) = super::toml_check::surplus_values(text, &plan) {
            return Err(PlanError::Surplus("<text>".into(), e));
        }
        plan.validate()?;
        Ok(plan)
    }

    /// Semantic checks: version, positive rate, unique names, unit `up_b`, finite numbers.
    pub fn validate(&self) -> Result<(), PlanError> {
        let version = self.version()?;
        self.validate_attitudes(version)?;
        crate::limits::positive_at_most(
            "sample_rate_hz",
            self.sample_rate_hz,
            crate::limits::MAX_SAMPLE_RATE_HZ,
        )
        .map_err(PlanError::Range)?;
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
            if !s.has_up() && !s.is_free() {
                return Err(PlanError::Invalid(format!(
                    "segment '{}' has no up_b: give it, or set attitude = \"free\" to estimate it",
                    s.name
                )));
            }
            if s.has_up() && (!n.is_finite() || (n - 1.0).abs() > 1e-3) {
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
            self.validate_sizes(s)?;
            self.validate_temperatures(s)?;
        }
        self.validate_mounts()
    }

    /// Rates, durations and table centres within what a rate table and the tools can carry: a typo
    /// like `rate_deg_s = 1e9` or `duration_s = 1e12` is named here, not met later as a "singular" fit
    /// or a recording that grows without bound.
    fn validate_sizes(&self, s: &SegmentPlan) -> Result<(), PlanError> {
        use crate::limits::{MAX_RATE_DEG_S, MAX_SEGMENT_DURATION_S, MAX_SEGMENT_ROWS};
        let invalid = |m: String| PlanError::Invalid(format!("segment '{}': {m}", s.name));
        for (field, r) in [
            ("rate_deg_s", Some(s.rate_deg_s)),
            ("rate_end_deg_s", s.rate_end_deg_s),
        ] {
            if let Some(r) = r.filter(|r| r.abs() > MAX_RATE_DEG_S) {
                return Err(invalid(format!(
                    "{field} = {r} is beyond any rate table (at most ±{MAX_RATE_DEG_S} °/s)"
                )));
            }
        }
        if let Some(d) = s.duration_s {
            if d > MAX_SEGMENT_DURATION_S || d * self.sample_rate_hz > MAX_SEGMENT_ROWS {
                return Err(invalid(format!(
                    "duration_s = {d} at {} Hz is too long (at most {MAX_SEGMENT_DURATION_S} s and                      {MAX_SEGMENT_ROWS:e} rows per segment)",
                    self.sample_rate_hz
                )));
            }
        }
        if let Some(c) = s.table_centre_m {
            if c.iter().any(|v| !v.is_finite() || v.abs() > 10.0) {
                return Err(invalid(format!(
                    "table_centre_m = {c:?} must be three finite distances within ±10 m"
                )));
            }
        }
        Ok(())
    }

    /// One mount is one physical fixing: all its segments share one `up_b` and one table centre.
    fn validate_mounts(&self) -> Result<(), PlanError> {
        let mut seen: std::collections::HashMap<String, &SegmentPlan> = Default::default();
        for s in &self.segments {
            let mount = s.mount_name();
            let Some(first) = seen.get(&mount) else {
                seen.insert(mount, s);
                continue;
            };
            let diff = (0..3)
                .map(|j| (first.up_b[j] - s.up_b[j]).abs())
                .fold(0.0, f64::max);
            if diff > 1e-4 {
                return Err(PlanError::Invalid(format!(
                    "mount '{mount}' is used by segment '{}' with up_b {:?} and by segment '{}' with                      up_b {:?}: one mount has one up_b; give the segments different mount names",
                    first.name, first.up_b, s.name, s.up_b
                )));
            }
            if let (Some(a), Some(b)) = (first.table_centre_m, s.table_centre_m) {
                if a != b {
                    return Err(PlanError::Invalid(format!(
                        "mount '{mount}': segment '{}' has table_centre_m {a:?} but segment '{}' has                          {b:?}; one mount has one table centre",
                        first.name, s.name
                    )));
                }
            }
        }
        Ok(())
    }

    /// The table's relative rate 1σ, ppm (the default when absent).
    pub fn table_rate_sigma_ppm(&self) -> f64 {
        self.table_rate_sigma_ppm
            .unwrap_or(DEFAULT_TABLE_RATE_SIGMA_PPM)
    }

    /// The plan-level mount tilt 1σ, degrees (the default when absent).
    pub(crate) fn attitude_sigma_deg(&self) -> f64 {
        self.attitude_sigma_deg
            .unwrap_or(DEFAULT_ATTITUDE_SIGMA_DEG)
    }

    /// The tilt 1σ of the mount `seg` belongs to, degrees; `None` for a free attitude.
    pub fn mount_sigma_deg(&self, seg: &SegmentPlan) -> Option<f64> {
        if seg.is_free() {
            return None;
        }
        Some(seg.attitude_sigma_deg.unwrap_or(self.attitude_sigma_deg()))
    }

    /// Format 2 keys need format 2; σ finite ≥ 0; a mount's segments agree on attitude and σ.
    fn validate_attitudes(&self, version: RecordingVersion) -> Result<(), PlanError> {
        if let Some(v) = self.table_rate_sigma_ppm {
            if !(v.is_finite() && v > 0.0 && v <= 1e5) {
                return Err(PlanError::Invalid(format!(
                    "table_rate_sigma_ppm = {v} must be a positive number of ppm (100 = 0.01 %)"
                )));
            }
        }
        let uses_v2 = self.attitude_sigma_deg.is_some()
            || self.table_rate_sigma_ppm.is_some()
            || self.segments.iter().any(|s| {
                s.attitude != Attitude::Fixture || s.attitude_sigma_deg.is_some() || !s.has_up()
            });
        if uses_v2 && !version.has_attitudes() {
            return Err(PlanError::Invalid(format!(
                "attitude, attitude_sigma_deg, table_rate_sigma_ppm and a missing up_b need \
                 format_version = {}",
                RecordingVersion::V2Attitudes
            )));
        }
        let sigmas = self.attitude_sigma_deg.iter().chain(
            self.segments
                .iter()
                .filter_map(|s| s.attitude_sigma_deg.as_ref()),
        );
        for v in sigmas {
            if !(v.is_finite() && (0.0..=10.0).contains(v)) {
                return Err(PlanError::Invalid(format!(
                    "attitude_sigma_deg = {v} must be between 0 and 10 degrees (use attitude = \"free\" \
                     for an unknown attitude)"
                )));
            }
        }
        let mut by_mount: std::collections::HashMap<String, (&SegmentPlan, Option<f64>)> =
            Default::default();
        for s in &self.segments {
            let key = s.mount_name();
            let sigma = self.mount_sigma_deg(s);
            if let Some((first, first_sigma)) = by_mount.get(&key) {
                if first.is_free() != s.is_free() || *first_sigma != sigma {
                    return Err(PlanError::Invalid(format!(
                        "segments '{}' and '{}' share mount '{key}' but not its attitude / \
                         attitude_sigma_deg: give them the same, or different mounts",
                        first.name, s.name
                    )));
                }
            } else {
                by_mount.insert(key, (s, sigma));
            }
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
                 set format_version = {} (samples.csv with temp_c)",
                s.name,
                RecordingVersion::V3Temperature
            )));
        }
        Ok(())
    }

    /// The plan's recording version, or why this build cannot read it.
    pub fn version(&self) -> Result<RecordingVersion, PlanError> {
        RecordingVersion::from_number(self.format_version)
            .ok_or(PlanError::Version(self.format_version))
    }

    /// True when `samples.csv` carries the unit's temperature (format version 3 and later; false for
    /// a version this build does not read, which [`Plan::validate`] refuses).
    pub fn has_temperature(&self) -> bool {
        self.version().is_ok_and(RecordingVersion::has_temperature)
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
    fn format_2_attitudes_and_format_1_still_read() {
        // A format 1 plan reads as before, with the default fixture accuracy.
        let p = Plan::parse(&format!("format_version = 1\n{GOOD}")).unwrap();
        assert_eq!(p.attitude_sigma_deg(), DEFAULT_ATTITUDE_SIGMA_DEG);
        assert_eq!(p.mount_sigma_deg(&p.segments[0]), Some(0.05));
        // Format 2: a plan-level σ, a per-segment σ and a free segment without up_b.
        let v2 = format!(
            "format_version = 2\nattitude_sigma_deg = 0.1\n{GOOD}\
             [[segment]]\nname = \"hand\"\nattitude = \"free\"\nduration_s = 5\n\
             [[segment]]\nname = \"z+\"\nup_b = [0, 0, 1]\nattitude_sigma_deg = 0\n"
        );
        let p = Plan::parse(&v2).unwrap();
        assert_eq!(p.mount_sigma_deg(&p.segments[0]), Some(0.1));
        assert!(p.segments[2].is_free() && !p.segments[2].has_up());
        assert_eq!(p.mount_sigma_deg(&p.segments[2]), None);
        assert_eq!(p.mount_sigma_deg(&p.segments[3]), Some(0.0));
        assert_eq!(Plan::parse(&p.to_toml()).unwrap(), p);
        // The new keys in a format 1 plan, a missing up_b on a fixture segment, a mount whose
        // segments disagree: each named.
        let e = Plan::parse(&v2.replace("format_version = 2", "format_version = 1")).unwrap_err();
        assert!(e.to_string().contains("format_version = 2"), "{e}");
        let e = Plan::parse(&v2.replace("attitude = \"free\"\n", "")).unwrap_err();
        assert!(e.to_string().contains("'hand' has no up_b"), "{e}");
        let e = Plan::parse(&v2.replace(
            "name = \"x+ 100\"\n",
            "name = \"x+ 100\"\nattitude_sigma_deg = 0.3\n",
        ))
        .unwrap_err();
        assert!(e.to_string().contains("share mount"), "{e}");
    }

    #[test]
    fn chamber_temperatures_need_format_version_3() {
        let with_temp = GOOD.replace("duration_s = 60", "duration_s = 60\ntemp_c = -20");
        let e = Plan::parse(&with_temp).unwrap_err();
        assert!(e.to_string().contains("format_version = 3"), "{e}");
        let p = Plan::parse(&format!("format_version = 3\n{with_temp}")).unwrap();
        assert!(p.has_temperature());
        assert_eq!(p.segments[0].temp_c, Some(-20.0));
        assert_eq!(p.version().unwrap().columns().last(), Some(&"temp_c"));
        assert_eq!(Plan::parse(&p.to_toml()).unwrap(), p);
        let hot = with_temp.replace("temp_c = -20", "temp_c = 500");
        let e = Plan::parse(&format!("format_version = 3\n{hot}")).unwrap_err();
        assert!(e.to_string().contains("500"), "{e}");
        let ramp = with_temp.replace("temp_c = -20", "temp_end_c = 20");
        let e = Plan::parse(&format!("format_version = 3\n{ramp}")).unwrap_err();
        assert!(e.to_string().contains("needs temp_c"), "{e}");
    }
}
