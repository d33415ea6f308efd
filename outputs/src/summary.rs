//! The machine-readable result of one calibration: every parameter of the calibration file with its
//! 1σ (the accelerometer's paper form, then the gyro's `G` and `b`, then the temperature model's
//! coefficients), the fit's χ², and pass/fail against production limits. `host calibrate --json`
//! prints it; `host batch` writes one per unit into its lot summary; `host compare` compares the
//! same gyro and temperature values ([`section_values`]).

use estimator::calibration_files::calibration_unit_file;
use estimator::estimate::gyro::UNDETERMINED_SIGMA;
use estimator::estimate::{paper_values, CalibrationOutcome, PAPER_LEN};
use estimator::unit_file::UnitFile;
use recording::limits;
use serde::{Deserialize, Serialize};
use shared::params::{axis_name, ParamsError};
use shared::sensor_models::MAX_TEMPERATURE_DEGREE;
use shared::Calibration;

/// ASCII keys of the paper-form values (same order as `estimate::paper_labels`), for CSV columns and
/// JSON keys: `bias_x`, `scale_x`, `theta_xy`, `r1x`, …
pub fn parameter_keys() -> Vec<String> {
    let mut v = Vec::with_capacity(PAPER_LEN);
    for i in 0..3 {
        v.push(format!("bias_{}", axis_name(i)));
    }
    for i in 0..3 {
        v.push(format!("scale_{}", axis_name(i)));
    }
    for i in 0..3 {
        for j in 0..3 {
            v.push(format!("theta_{}{}", axis_name(i), axis_name(j)));
        }
    }
    for i in 0..3 {
        for j in 0..3 {
            v.push(format!("r{}{}", i + 1, axis_name(j)));
        }
    }
    v
}

/// ASCII keys of the gyro's values: `gyro_g_xx` … `gyro_g_zz` (`G`, rows gyro axes, columns body
/// axes), then `gyro_bias_x` … (`b`, rad/s).
pub(crate) fn gyro_keys() -> Vec<String> {
    let mut v = Vec::with_capacity(12);
    for i in 0..3 {
        for j in 0..3 {
            v.push(format!("gyro_g_{}{}", axis_name(i), axis_name(j)));
        }
    }
    for i in 0..3 {
        v.push(format!("gyro_bias_{}", axis_name(i)));
    }
    v
}

/// The temperature model's polynomials, in key order: (key stem, unit per °C^k of the output unit
/// `out`).
fn temperature_polynomials(out: &str) -> [(&'static str, String); 3] {
    [
        ("temp_bias", format!("{out}/degC")),
        ("temp_scale", "1/degC".into()),
        ("temp_gyro_bias", "rad/s/degC".into()),
    ]
}

/// ASCII keys of the temperature model's coefficients: `temp_bias_x_c1` (the zero bias's `ΔT¹`
/// coefficient of axis x), … `temp_scale_*`, `temp_gyro_bias_*`, `c1` to `c3` per axis.
pub(crate) fn temperature_keys() -> Vec<String> {
    let mut v = Vec::new();
    for (stem, _) in temperature_polynomials("") {
        for i in 0..3 {
            for k in 1..=MAX_TEMPERATURE_DEGREE {
                v.push(format!("{stem}_{}_c{k}", axis_name(i)));
            }
        }
    }
    v
}

/// Every key a summary can have, in order: [`parameter_keys`], `gyro_keys`, `temperature_keys`
/// (the lot summary's columns).
pub fn all_parameter_keys() -> Vec<String> {
    let mut v = parameter_keys();
    v.extend(gyro_keys());
    v.extend(temperature_keys());
    v
}

/// A gyro entry with this 1σ is not determined by the plan (above [`UNDETERMINED_SIGMA`], or NaN).
pub(crate) fn gyro_entry_undetermined(sigma: f64) -> bool {
    sigma.is_nan() || sigma > UNDETERMINED_SIGMA
}

/// One value of a calibration file's `[gyro]` or `[temperature]` section.
#[derive(Clone, Debug, PartialEq)]
pub struct SectionValue {
    /// Its key (`gyro_keys`, `temperature_keys`).
    pub name: String,
    /// Its unit as stored in the file.
    pub unit: String,
    /// The value.
    pub value: f64,
    /// Its 1σ, when the file has one and the value is part of the model (a temperature coefficient
    /// above the degree the data chose is 0 by that choice and has none).
    pub sigma: Option<f64>,
    /// A gyro entry the plan did not determine (1σ above [`UNDETERMINED_SIGMA`]).
    pub undetermined: bool,
}

/// The values of `file`'s `[gyro]` and `[temperature]` sections, each with its 1σ, in key order; an
/// absent section gives none.
pub fn section_values(file: &UnitFile) -> Vec<SectionValue> {
    let mut v = Vec::new();
    let keys = gyro_keys();
    if let Some(g) = &file.gyro {
        for i in 0..3 {
            for j in 0..3 {
                let sigma = g.matrix_1sigma.map(|s| s[i][j]);
                v.push(SectionValue {
                    name: keys[3 * i + j].clone(),
                    unit: "1".into(),
                    value: g.matrix[i][j],
                    sigma,
                    undetermined: sigma.is_some_and(gyro_entry_undetermined),
                });
            }
        }
        for i in 0..3 {
            v.push(SectionValue {
                name: keys[9 + i].clone(),
                unit: "rad/s".into(),
                value: g.bias_rad_s[i],
                sigma: g.bias_rad_s_1sigma.map(|s| s[i]),
                undetermined: false,
            });
        }
    }
    let Some(t) = &file.temperature else {
        return v;
    };
    let out = file
        .output_unit
        .unwrap_or(shared::OutputUnit::Volts)
        .symbol();
    let polys = [
        (
            Some(t.zero_bias_out_per_c),
            t.zero_bias_out_per_c_1sigma,
            t.zero_bias_degree,
        ),
        (
            Some(t.scale_rel_per_c),
            t.scale_rel_per_c_1sigma,
            t.scale_degree,
        ),
        (
            t.gyro_bias_rad_s_per_c,
            t.gyro_bias_rad_s_per_c_1sigma,
            t.gyro_bias_degree,
        ),
    ];
    for ((stem, unit), (coef, sigma, degree)) in temperature_polynomials(out).into_iter().zip(polys)
    {
        let Some(coef) = coef else { continue };
        for i in 0..3 {
            for k in 1..=MAX_TEMPERATURE_DEGREE {
                // In the model: up to the chosen degree; without one, any coefficient with a 1σ.
                let in_model = degree.is_none_or(|d| k <= d[i]);
                let s = sigma.map(|s| s[i][k - 1]).filter(|s| {
                    in_model && (degree.is_some() || *s > 0.0 || coef[i][k - 1] != 0.0)
                });
                v.push(SectionValue {
                    name: format!("{stem}_{}_c{k}", axis_name(i)),
                    unit: if k == 1 {
                        unit.clone()
                    } else {
                        format!("{unit}^{k}")
                    },
                    value: coef[i][k - 1],
                    sigma: s,
                    undetermined: false,
                });
            }
        }
    }
    v
}

/// The temperature model's setting in a summary (its coefficients are parameters).
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct TemperatureRange {
    /// `T_ref`, °C: the static values hold there.
    pub reference_c: f64,
    /// The temperatures the calibration covers, °C.
    pub valid_range_c: [f64; 2],
    /// The degree of each zero-bias polynomial the data chose (an estimate's).
    pub zero_bias_degree: Option<[usize; 3]>,
    /// The degree of each scale polynomial.
    pub scale_degree: Option<[usize; 3]>,
    /// The degree of each gyro bias polynomial.
    pub gyro_bias_degree: Option<[usize; 3]>,
}

/// Units of the paper-form values, in order.
pub fn parameter_unit(index: usize, output_unit: &str) -> String {
    match index {
        0..=2 => output_unit.to_string(),
        3..=5 => format!("{output_unit}/g"),
        6..=14 => "deg".into(),
        _ => "m".into(),
    }
}

/// One parameter.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct Parameter {
    /// ASCII key ([`parameter_keys`]).
    pub name: String,
    /// Unit.
    pub unit: String,
    /// Value.
    pub value: f64,
    /// 1σ after χ² scaling; `None` when the plan did not determine the value (named in
    /// [`CalibrationSummary::undetermined`]) or a temperature coefficient is above its chosen degree.
    pub sigma: Option<f64>,
}

/// χ²/dof above which a calibration fails without `--max-chi2-per-dof`: residuals ten times the
/// segments' own noise are a model that does not describe the data (docs/model.md §4.4), whatever
/// the scaled 1σ say. Clean simulated sessions give about 1.
pub const DEFAULT_MAX_CHI2_PER_DOF: f64 = 100.0;

/// Production limits; each `None` is not checked, but χ²/dof always is
/// (`DEFAULT_MAX_CHI2_PER_DOF`).
#[derive(Clone, Copy, Debug, Default, PartialEq, Serialize, Deserialize, clap::Args)]
pub struct Limits {
    /// Fail when χ²/dof exceeds this (a misfit: table errors, a moved unit, a bad sensor); default 100.
    /// A temperature model's own fit is held to the same limit (docs/model.md §9).
    #[arg(long, value_name = "X")]
    pub max_chi2_per_dof: Option<f64>,
    /// Fail when any zero bias B = u0/k (paper eq. 1) exceeds this, mg. Meaningful for outputs that
    /// read 0 at 0 g (digital); a mid-rail analog output's u0/k is its offset, not a bias.
    #[arg(long, value_name = "MG")]
    pub max_bias_mg: Option<f64>,
    /// Fail when any sensing axis is further than this from its body axis, degrees.
    #[arg(long, value_name = "DEG")]
    pub max_misalignment_deg: Option<f64>,
    /// Fail when any bias 1σ exceeds this, mg (the session did not determine the unit well enough).
    #[arg(long, value_name = "MG")]
    pub max_bias_sigma_mg: Option<f64>,
}

/// One limit's verdict.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct Check {
    /// Which limit.
    pub name: String,
    /// The value checked.
    pub value: f64,
    /// The limit.
    pub limit: f64,
    /// `value ≤ limit`.
    pub passed: bool,
}

/// The result of one calibration.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct CalibrationSummary {
    /// Unit id (24 hex digits), if the recording had one.
    pub unit_id: Option<String>,
    /// The parameters: the accelerometer's in paper form ([`parameter_keys`]), then the gyro's
    /// (`gyro_keys`) and the temperature model's (`temperature_keys`) when the calibration has them.
    pub parameters: Vec<Parameter>,
    /// The parameters the session did not determine (their `sigma` is null): lever-arm components,
    /// gyro entries.
    #[serde(default)]
    pub undetermined: Vec<String>,
    /// The temperature model's reference and range, when the calibration has one.
    #[serde(default)]
    pub temperature: Option<TemperatureRange>,
    /// The calibration file itself, every table as `calibration.toml` holds it (the values above are
    /// taken from it; an undetermined 1σ, ∞ in the file, is `null` in JSON).
    #[serde(default)]
    pub calibration: Option<UnitFile>,
    /// Σ whitened residual².
    pub chi2: f64,
    /// Degrees of freedom.
    pub dof: i64,
    /// χ²/dof.
    pub chi2_per_dof: f64,
    /// The temperature fit's own χ² when the calibration has a temperature model
    /// (docs/model.md §9); its worst axis's χ²/dof is checked against the same limit as
    /// `chi2_per_dof` (`thermal_chi2_per_dof`). Absent without a temperature model.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub thermal_fit: Option<ThermalFitSummary>,
    /// The limits checked.
    pub checks: Vec<Check>,
    /// All checks passed.
    pub passed: bool,
    /// The estimator's warnings.
    pub warnings: Vec<String>,
    /// For a single-package unit (one lever arm for the three accelerometers, whose `r1*`, `r2*`,
    /// `r3*` above are that one point): why its in-package size effect is not given
    /// (docs/model.md §4.7). Absent otherwise.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub in_package_size_effect: Option<String>,
    /// The accelerometers' bias random walk the fit assumed and each segment's fitted bias over
    /// the session (docs/model.md §11). Absent with a constant bias.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub bias_walk: Option<BiasWalkSummary>,
    /// The gyro's bias random walk the gyro model's mean rates were weighted with, °/s/√s
    /// (docs/model.md §11.6). Absent with a constant gyro bias or without a gyro model.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub gyro_bias_walk_deg_s_sqrt_s: Option<f64>,
    /// The gyro's bias random walk estimated from the session, with its 1σ, and whether the fit
    /// used it (docs/model.md §11.6). Absent when not estimated.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub gyro_walk: Option<GyroWalkSummary>,
}

/// The gyro's bias random walk estimated from the session (docs/model.md §11.6).
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct GyroWalkSummary {
    /// The estimate, °/s/√s.
    pub deg_s_sqrt_s: f64,
    /// Its 1σ, °/s/√s.
    pub sigma_deg_s_sqrt_s: f64,
    /// The likelihood interval, °/s/√s.
    pub interval_deg_s_sqrt_s: [f64; 2],
    /// How far the session rules out a constant gyro bias, σ.
    pub significance: f64,
    /// Whether the fit weighted the gyro's means with it (determined by the session).
    pub used: bool,
    /// Each axis's strength, estimated where the one strength is used (docs/model.md §11.6).
    /// Absent where it is not.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub axes: Option<GyroWalkAxesSummary>,
}

/// The gyro's bias random walk per axis (x, y, z), estimated from the session (docs/model.md
/// §11.6).
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct GyroWalkAxesSummary {
    /// The estimates, °/s/√s.
    pub deg_s_sqrt_s: [f64; 3],
    /// Their 1σ, °/s/√s.
    pub sigma_deg_s_sqrt_s: [f64; 3],
    /// Their likelihood intervals, °/s/√s.
    pub interval_deg_s_sqrt_s: [[f64; 2]; 3],
    /// The strengths each axis's means were weighted with when used, °/s/√s.
    pub fit_deg_s_sqrt_s: [f64; 3],
    /// How far the session rules out a constant bias on each axis, σ.
    pub significance: [f64; 3],
    /// 2 Δlog L of the per-axis strengths over the one strength.
    pub likelihood_ratio: f64,
    /// Whether the fit weighted the gyro's means with them (in place of the one strength).
    pub used: bool,
}

/// The temperature fit's χ² per accelerometer axis, over every sample of the segments that
/// determine the model (docs/model.md §9). A segment enters the main fit only by its mean, so a
/// misfit within a ramp shows here and not in the main χ²/dof.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct ThermalFitSummary {
    /// Σ whitened residual² per axis.
    pub chi2: [f64; 3],
    /// Degrees of freedom per axis.
    pub dof: [usize; 3],
    /// χ²/dof per axis.
    pub chi2_per_dof: [f64; 3],
    /// The largest of them: the figure checked as `thermal_chi2_per_dof`.
    pub worst_chi2_per_dof: f64,
}

impl ThermalFitSummary {
    /// The temperature fit's figures, when the outcome has one.
    pub(crate) fn of(outcome: &CalibrationOutcome) -> Option<ThermalFitSummary> {
        let fit = outcome.thermal.as_ref()?;
        Some(ThermalFitSummary {
            chi2: fit.chi2.map(|(c, _)| c),
            dof: fit.chi2.map(|(_, d)| d),
            chi2_per_dof: fit.reduced_chi2(),
            worst_chi2_per_dof: fit.worst_reduced_chi2(),
        })
    }
}

/// The bias random walk of a fit (docs/model.md §11.3, §11.4).
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct BiasWalkSummary {
    /// Where its strength came from: `given`, `unit` (the unit's noise figures) or `estimated`.
    pub source: String,
    /// The strength, mg/√s (from the unit: the strongest axis's).
    pub mg_sqrt_s: f64,
    /// Each axis's strength, mg/√s.
    pub axes_mg_sqrt_s: [f64; 3],
    /// Estimated: its 1σ, mg/√s.
    pub sigma_mg_sqrt_s: Option<f64>,
    /// Estimated: the likelihood interval, mg/√s.
    pub interval_mg_sqrt_s: Option<[f64; 2]>,
    /// The strength the segments were weighted with, mg/√s.
    pub fit_mg_sqrt_s: f64,
    /// Estimated: how far the session rules out no walk, σ.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub significance: Option<f64>,
    /// Whether the fit weighted the segments with it (an estimate only where the session
    /// determines it; otherwise the bias is fitted as constant).
    #[serde(default = "used_by_default")]
    pub used: bool,
    /// Each segment's fitted wander of the bias from the session's start, in time order.
    pub track: Vec<BiasTrackPoint>,
}

/// One segment's fitted bias wander (docs/model.md §11.4).
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct BiasTrackPoint {
    /// The segment.
    pub segment: String,
    /// The middle of its span, s from the session's first sample.
    pub t_mid_s: f64,
    /// The wander per axis, mg.
    pub bias_mg: [f64; 3],
    /// Its 1σ per axis, mg.
    pub sigma_mg: [f64; 3],
}

/// A summary written before estimates could go unused: its walk was used.
fn used_by_default() -> bool {
    true
}

impl GyroWalkSummary {
    /// The gyro walk estimated for `outcome`, when it was.
    pub(crate) fn of(outcome: &CalibrationOutcome) -> Option<GyroWalkSummary> {
        let g = outcome.gyro_walk.as_ref()?;
        Some(GyroWalkSummary {
            deg_s_sqrt_s: g.deg_s_sqrt_s,
            sigma_deg_s_sqrt_s: g.sigma_deg_s_sqrt_s,
            interval_deg_s_sqrt_s: g.interval_deg_s_sqrt_s,
            significance: g.significance,
            used: g.used,
            axes: g.axes.map(|a| GyroWalkAxesSummary {
                deg_s_sqrt_s: a.deg_s_sqrt_s,
                sigma_deg_s_sqrt_s: a.sigma_deg_s_sqrt_s,
                interval_deg_s_sqrt_s: a.interval_deg_s_sqrt_s,
                fit_deg_s_sqrt_s: a.fit_deg_s_sqrt_s,
                significance: a.significance,
                likelihood_ratio: a.likelihood_ratio,
                used: a.used,
            }),
        })
    }
}

impl BiasWalkSummary {
    /// The walk of `outcome`, when its fit assumed one.
    pub(crate) fn of(outcome: &CalibrationOutcome) -> Option<BiasWalkSummary> {
        let w = outcome.bias_walk.as_ref()?;
        Some(BiasWalkSummary {
            source: w.origin.word().into(),
            mg_sqrt_s: w.mg_sqrt_s,
            axes_mg_sqrt_s: w.axes_mg_sqrt_s,
            sigma_mg_sqrt_s: w.sigma_mg_sqrt_s,
            interval_mg_sqrt_s: w.interval_mg_sqrt_s,
            fit_mg_sqrt_s: w.fit_mg_sqrt_s,
            significance: w.significance,
            used: w.used,
            track: outcome
                .bias_track
                .iter()
                .map(|p| BiasTrackPoint {
                    segment: p.name.clone(),
                    t_mid_s: p.t_mid_s,
                    bias_mg: p.bias_mg,
                    sigma_mg: p.sigma_mg,
                })
                .collect(),
        })
    }
}

/// The paper-form parameters ([`parameter_keys`]) with their units, `values` and, from the
/// diagonal of `covariance` (empty: none), their 1σ.
fn paper_parameters(
    cal: &Calibration,
    values: &[f64; PAPER_LEN],
    covariance: &[Vec<f64>],
) -> Vec<Parameter> {
    let unit = cal.statics.output_unit.symbol();
    parameter_keys()
        .into_iter()
        .enumerate()
        .map(|(i, name)| {
            let var = covariance.get(i).and_then(|r| r.get(i)).copied();
            Parameter {
                name,
                unit: parameter_unit(i, unit),
                value: values[i],
                sigma: var.filter(|v| v.is_finite() && *v >= 0.0).map(f64::sqrt),
            }
        })
        .collect()
}

/// Every parameter of a calibration file, named and ordered as [`CalibrationSummary::parameters`]:
/// the paper-form values (their 1σ need the fit's covariance, which a file does not hold: `None`),
/// then its `[gyro]` and `[temperature]` sections with the file's 1σ.
pub fn file_parameters(file: &UnitFile, cal: &Calibration) -> Result<Vec<Parameter>, ParamsError> {
    let mut v = paper_parameters(cal, &paper_values(cal)?, &[]);
    v.extend(
        section_values(file)
            .into_iter()
            .map(SectionValue::into_parameter),
    );
    Ok(v)
}

impl SectionValue {
    /// As a [`Parameter`]: an undetermined entry has no 1σ.
    fn into_parameter(self) -> Parameter {
        Parameter {
            sigma: self.sigma.filter(|_| !self.undetermined),
            name: self.name,
            unit: self.unit,
            value: self.value,
        }
    }
}

impl CalibrationSummary {
    /// The summary of `outcome`, checked against `limits`.
    pub fn new(outcome: &CalibrationOutcome, unit_id: Option<String>, limits: &Limits) -> Self {
        let cal = &outcome.calibration;
        let values = paper_values(cal).unwrap_or([f64::NAN; PAPER_LEN]);
        let mut parameters = paper_parameters(cal, &values, &outcome.covariance);
        let mut undetermined: Vec<String> = parameters
            .iter()
            .filter(|p| p.sigma.is_none())
            .map(|p| p.name.clone())
            .collect();
        // The gyro and temperature values exactly as calibration.toml holds them.
        let id = unit_id.as_deref().and_then(shared::UnitId::parse_hex);
        let file = calibration_unit_file(outcome, id);
        let sections = section_values(&file);
        undetermined.extend(
            sections
                .iter()
                .filter(|s| s.undetermined)
                .map(|s| s.name.clone()),
        );
        parameters.extend(sections.into_iter().map(SectionValue::into_parameter));
        let temperature = file.temperature.as_ref().map(|t| TemperatureRange {
            reference_c: t.reference_c,
            valid_range_c: t.valid_range_c,
            zero_bias_degree: t.zero_bias_degree,
            scale_degree: t.scale_degree,
            gyro_bias_degree: t.gyro_bias_degree,
        });
        let k = cal.statics.scale_out_per_g;
        let bias_mg = |i: usize| (values[i] / k[i]).abs() * 1e3;
        let mut checks = Vec::new();
        let mut check = |name: &str, value: f64, limit: Option<f64>| {
            if let Some(limit) = limit {
                checks.push(Check {
                    name: name.into(),
                    value,
                    limit,
                    // NaN fails.
                    passed: value <= limit,
                });
            }
        };
        let max_chi2 = limits.max_chi2_per_dof.unwrap_or(DEFAULT_MAX_CHI2_PER_DOF);
        check("chi2_per_dof", outcome.fit.reduced_chi2, Some(max_chi2));
        // The temperature fit's misfit under the same limit: a misfit within a segment never
        // reaches the main fit, which sees each segment's mean (docs/model.md §9).
        let thermal_fit = ThermalFitSummary::of(outcome);
        if let Some(t) = &thermal_fit {
            check("thermal_chi2_per_dof", t.worst_chi2_per_dof, Some(max_chi2));
        }
        let worst_bias = (0..3).map(bias_mg).fold(0.0, f64::max);
        check("bias_mg", worst_bias, limits.max_bias_mg);
        let worst_angle = (0..3).map(|i| values[6 + 4 * i].abs()).fold(0.0, f64::max);
        check("misalignment_deg", worst_angle, limits.max_misalignment_deg);
        let worst_sigma = (0..3)
            .map(|i| {
                parameters[i]
                    .sigma
                    .map_or(f64::INFINITY, |s| s / k[i].abs() * 1e3)
            })
            .fold(0.0, f64::max);
        check("bias_sigma_mg", worst_sigma, limits.max_bias_sigma_mg);
        let passed = checks.iter().all(|c| c.passed);
        CalibrationSummary {
            unit_id,
            parameters,
            undetermined,
            temperature,
            calibration: Some(file),
            chi2: outcome.fit.chi2,
            dof: outcome.fit.dof,
            chi2_per_dof: outcome.fit.reduced_chi2,
            thermal_fit,
            checks,
            passed,
            warnings: estimator::estimate::note::Note::texts(&outcome.warnings),
            in_package_size_effect: outcome
                .single_package
                .then(|| estimator::estimate::IN_PACKAGE_NOT_OBSERVABLE.to_string()),
            bias_walk: BiasWalkSummary::of(outcome),
            gyro_bias_walk_deg_s_sqrt_s: outcome.gyro_bias_walk_deg_s_sqrt_s,
            gyro_walk: GyroWalkSummary::of(outcome),
        }
    }

    /// The failed checks as one line, e.g. "chi2_per_dof 3.1 > 2".
    pub fn failures(&self) -> String {
        let f: Vec<String> = self
            .checks
            .iter()
            .filter(|c| !c.passed)
            .map(|c| format!("{} {:.4} > {}", c.name, c.value, c.limit))
            .collect();
        f.join(", ")
    }
}

/// Gives the pass/fail limit options (declared in [`Limits`]) their ranges:
/// `--max-misalignment-deg` in `[MIN_LIMIT, 90]`, `--max-chi2-per-dof`, `--max-bias-mg` and
/// `--max-bias-sigma-mg` in `[MIN_LIMIT, MAX_LIMIT]`. A command that flattens the limits applies it to its
/// arguments with `#[command(mut_args(summary::pass_fail_limits))]`; other arguments pass unchanged.
pub fn pass_fail_limits(arg: clap::Arg) -> clap::Arg {
    match arg.get_id().as_str() {
        "max_misalignment_deg" => arg.value_parser(limits::real(limits::MIN_LIMIT, 90.0)),
        "max_chi2_per_dof" | "max_bias_mg" | "max_bias_sigma_mg" => {
            arg.value_parser(limits::real(limits::MIN_LIMIT, limits::MAX_LIMIT))
        }
        _ => arg,
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn keys_match_the_estimators_labels_one_to_one() {
        let keys = parameter_keys();
        let labels = estimator::estimate::paper_labels();
        assert_eq!(keys.len(), labels.len());
        assert_eq!((keys[0].as_str(), labels[0].as_str()), ("bias_x", "bias x"));
        assert_eq!(keys[7], "theta_xy");
        assert_eq!(labels[7], "θxy");
        assert_eq!(keys[23], "r3z");
    }
}
