//! The machine-readable result of one calibration: every paper-form parameter with its 1σ, the fit's
//! χ², and pass/fail against production limits. `host calibrate --json` prints it; `host batch`
//! writes one per unit into its lot summary.

use crate::estimate::{paper_values, CalibrationOutcome, PAPER_LEN};
use serde::{Deserialize, Serialize};
use shared::params::axis_name;

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
    /// 1σ after χ² scaling; `None` when the plan did not determine the value.
    pub sigma: Option<f64>,
}

/// Production limits; each `None` is not checked.
#[derive(Clone, Copy, Debug, Default, PartialEq, Serialize, Deserialize, clap::Args)]
pub struct Limits {
    /// Fail when χ²/dof exceeds this (a misfit: table errors, a moved unit, a bad sensor).
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
    /// The parameters in paper form.
    pub parameters: Vec<Parameter>,
    /// Σ whitened residual².
    pub chi2: f64,
    /// Degrees of freedom.
    pub dof: i64,
    /// χ²/dof.
    pub chi2_per_dof: f64,
    /// The limits checked.
    pub checks: Vec<Check>,
    /// All checks passed.
    pub passed: bool,
    /// The estimator's warnings.
    pub warnings: Vec<String>,
}

impl CalibrationSummary {
    /// The summary of `outcome`, checked against `limits`.
    pub fn new(outcome: &CalibrationOutcome, unit_id: Option<String>, limits: &Limits) -> Self {
        let cal = &outcome.calibration;
        let values = paper_values(cal).unwrap_or([f64::NAN; PAPER_LEN]);
        let unit = cal.statics.output_unit.symbol();
        let parameters = parameter_keys()
            .into_iter()
            .enumerate()
            .map(|(i, name)| {
                let var = outcome.covariance.get(i).and_then(|r| r.get(i)).copied();
                Parameter {
                    name,
                    unit: parameter_unit(i, unit),
                    value: values[i],
                    sigma: var.filter(|v| v.is_finite() && *v >= 0.0).map(f64::sqrt),
                }
            })
            .collect::<Vec<_>>();
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
        check(
            "chi2_per_dof",
            outcome.fit.reduced_chi2,
            limits.max_chi2_per_dof,
        );
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
            chi2: outcome.fit.chi2,
            dof: outcome.fit.dof,
            chi2_per_dof: outcome.fit.reduced_chi2,
            checks,
            passed,
            warnings: outcome.warnings.clone(),
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

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn keys_match_the_estimators_labels_one_to_one() {
        let keys = parameter_keys();
        let labels = crate::estimate::paper_labels();
        assert_eq!(keys.len(), labels.len());
        assert_eq!((keys[0].as_str(), labels[0].as_str()), ("bias_x", "bias x"));
        assert_eq!(keys[7], "theta_xy");
        assert_eq!(labels[7], "θxy");
        assert_eq!(keys[23], "r3z");
    }
}
