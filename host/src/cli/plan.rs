//! `host plan --check`: a plan's segments and the predicted 1σ of every parameter (Cramér–Rao bound),
//! before any data.

use super::output::Output;
use super::{load_unit, CliError};
use crate::estimate::{predict, PredictSettings, Prediction};
use crate::session::builtin::load_plan;
use crate::session::Package;
use crate::session::Plan;
use crate::summary::{parameter_keys, parameter_unit};
use crate::unit_file::{UnitFile, UnitFileError};

/// The MEMS IMU a single-package plan is predicted for when no unit is given.
const SINGLE_PACKAGE_UNIT_TOML: &str = include_str!("../../units/single-package.toml");
use clap::Args;
use serde_json::json;
use std::path::PathBuf;

/// `host plan`.
#[derive(Debug, Args)]
pub struct PlanArgs {
    /// Plan file (or built-in plan name) to check.
    #[arg(long, value_name = "FILE|NAME")]
    pub check: String,
    /// Accelerometer white noise per sample, 1σ, mg.
    #[arg(long, value_name = "MG", default_value_t = 1.0, value_parser = crate::limits::real(crate::limits::MIN_LIMIT, crate::limits::MAX_SIM_NOISE))]
    pub noise_mg: f64,
    /// Gyro white noise per sample, 1σ, °/s.
    #[arg(long, value_name = "DEG_S", default_value_t = 0.05, value_parser = crate::limits::real(crate::limits::MIN_LIMIT, crate::limits::MAX_SIM_NOISE))]
    pub gyro_noise_deg_s: f64,
    /// Unit file giving the scale factors and lever arms to predict for (default: the paper's unit,
    /// or for a plan with package = "single" `host/units/single-package.toml`, a MEMS IMU).
    #[arg(long, value_name = "FILE")]
    pub unit: Option<PathBuf>,
    /// Predict with the accelerometers' bias a random walk of this strength, mg/√s (the Allan K
    /// of `host noise`, in mg; docs/model.md §11): the segments' order in the plan then matters.
    #[arg(long, value_name = "MG_SQRT_S", value_parser = crate::limits::real(0.0, crate::limits::MAX_BIAS_WALK_MG_SQRT_S))]
    pub bias_walk: Option<f64>,
    /// Print the prediction as one JSON document on stdout (the table goes to stderr).
    #[arg(long)]
    pub json: bool,
}

/// `host plan --check`: the plan's segments and the predicted 1σ of every parameter.
pub fn run(a: &PlanArgs, quiet: bool) -> Result<Prediction, CliError> {
    let out = Output {
        json: a.json,
        quiet,
    };
    let plan = load_plan(&a.check)?;
    let unit = match (&a.unit, plan.package) {
        (None, Package::Single) => UnitFile::parse(SINGLE_PACKAGE_UNIT_TOML).map_err(|m| {
            CliError::Unit(UnitFileError::Syntax("<single-package unit>".into(), m))
        })?,
        _ => load_unit(a.unit.as_deref())?,
    };
    let truth = unit.to_calibration().map_err(|m| {
        CliError::Unit(UnitFileError::Invalid(
            a.unit.clone().unwrap_or_else(|| match plan.package {
                Package::Single => "<single-package unit>".into(),
                Package::Separate => "<paper unit>".into(),
            }),
            m,
        ))
    })?;
    if !(a.noise_mg.is_finite() && a.noise_mg > 0.0) {
        return Err(CliError::Usage(format!(
            "--noise-mg {} must be a positive number",
            a.noise_mg
        )));
    }
    print_plan(&plan, &out)?;
    let k = truth.statics.scale_out_per_g;
    let settings = PredictSettings {
        noise_out_per_sample_1sigma: k.map(|k| a.noise_mg * 1e-3 * k.abs()),
        gyro_noise_rad_s: a.gyro_noise_deg_s.to_radians(),
        options: crate::estimate::EstimateOptions {
            bias_walk: match a.bias_walk {
                Some(k) if k > 0.0 => crate::estimate::BiasWalk::Given(k),
                _ => crate::estimate::BiasWalk::Off,
            },
            ..crate::estimate::EstimateOptions::default()
        },
        ..PredictSettings::white(0.0)
    };
    let stats = crate::sim::synth::prediction_stats(&plan, &truth, &settings)
        .map_err(crate::estimate::EstimateError::from)?;
    let prediction = predict(&plan, &truth, &stats, &settings)?;
    out.line("")?;
    let walk = a.bias_walk.filter(|k| *k > 0.0).map_or(String::new(), |k| {
        format!("; a bias random walk of {k} mg/√s (docs/model.md §11)")
    });
    out.line(format_args!(
        "noise: {} mg per sample on each accelerometer, {} °/s on the gyro{walk}",
        a.noise_mg, a.gyro_noise_deg_s
    ))?;
    out.human(crate::report::render_prediction(&prediction))?;
    let advice = match a.bias_walk {
        Some(k) if k > 0.0 => crate::app::segment_order::order_advice(&plan, &truth, &settings)?,
        _ => Vec::new(),
    };
    print_advice(&advice, &out)?;
    let unit = prediction.output_unit.symbol();
    let parameters: Vec<_> = parameter_keys()
        .into_iter()
        .enumerate()
        .map(|(i, name)| {
            let s = prediction.sigma[i];
            json!({
                "name": name,
                "unit": parameter_unit(i, unit),
                "value": prediction.values[i],
                "predicted_sigma": s.is_finite().then_some(s),
            })
        })
        .collect();
    let mut doc = json!({
        "plan": a.check,
        "segments": plan.segments.len(),
        "sample_rate_hz": plan.sample_rate_hz,
        "noise_mg": a.noise_mg,
        "gyro_noise_deg_s": a.gyro_noise_deg_s,
        "parameters": parameters,
        "lever_arms_observable": prediction.lever_arms_observable,
        "lever_arms_fixed": prediction.lever_arms_fixed,
        "warnings": prediction.warnings,
        "single_package": prediction.single_package,
        "in_package_size_effect": prediction
            .single_package
            .then_some(crate::estimate::IN_PACKAGE_NOT_OBSERVABLE),
    });
    if !advice.is_empty() {
        doc["order_advice"] = json!(advice);
    }
    out.document(&doc)?;
    Ok(prediction)
}

/// The segment-order advice under the walk (docs/model.md §11.2), one paragraph each; nothing when
/// no order helps.
fn print_advice(
    advice: &[crate::app::segment_order::OrderAdvice],
    out: &Output,
) -> Result<(), CliError> {
    for v in advice {
        let (b, f) = (&v.before, &v.after);
        let pct = |x: f64, y: f64| 100.0 * (y / x - 1.0);
        let cost = if v.added_s > 0.0 {
            format!(" ({} s more)", v.added_s)
        } else {
            String::new()
        };
        out.line(format_args!(
            "order under the walk: {}{cost}: worst bias 1σ {:.4} → {:.4} mg ({:+.0} %), worst \
             scale 1σ {:.1} → {:.1} ppm ({:+.0} %)",
            v.change,
            b.worst_bias_sigma_mg,
            f.worst_bias_sigma_mg,
            pct(b.worst_bias_sigma_mg, f.worst_bias_sigma_mg),
            b.worst_scale_sigma_ppm,
            f.worst_scale_sigma_ppm,
            pct(b.worst_scale_sigma_ppm, f.worst_scale_sigma_ppm),
        ))?;
        out.line(format_args!("  order: {}", v.order.join(", ")))?;
    }
    Ok(())
}

fn print_plan(plan: &Plan, out: &Output) -> Result<(), CliError> {
    out.line(format_args!(
        "{} segments at {} Hz, output unit {}, g = {} m/s²",
        plan.segments.len(),
        plan.sample_rate_hz,
        plan.output_unit.symbol(),
        plan.gravity_m_s2
    ))?;
    for s in &plan.segments {
        let rate = match s.rate_end_deg_s {
            Some(r1) if r1 != s.rate_deg_s => format!("{} → {} °/s", s.rate_deg_s, r1),
            _ if s.is_static() => "static".to_string(),
            _ => format!("{} °/s", s.rate_deg_s),
        };
        out.line(format_args!(
            "  {:<14} up_b = [{:+.4}, {:+.4}, {:+.4}]  {:<16} {}",
            s.name,
            s.up_b[0],
            s.up_b[1],
            s.up_b[2],
            rate,
            s.duration_s
                .map_or("(no duration)".into(), |d| format!("{d} s"))
        ))?;
    }
    Ok(())
}
