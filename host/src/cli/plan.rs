//! `host plan --check`: a plan's segments and the predicted 1σ of every parameter (Cramér–Rao bound),
//! before any data.

use super::output::Output;
use super::{load_unit, CliError};
use estimator::estimate::{predict, PredictSettings, Prediction};
use estimator::unit_file::{UnitFile, UnitFileError};
use outputs::summary::{parameter_keys, parameter_unit};
use recording::session::builtin::load_plan;
use recording::session::Package;
use recording::session::Plan;

/// The MEMS IMU a single-package plan is predicted for when no unit is given.
const SINGLE_PACKAGE_UNIT_TOML: &str = include_str!("../../units/single-package.toml");
use clap::Args;
use serde_json::json;
use std::path::PathBuf;

/// `host plan`.
#[derive(Debug, Args)]
pub(crate) struct PlanArgs {
    /// Plan file (or built-in plan name) to check.
    #[arg(long, value_name = "FILE|NAME")]
    pub check: String,
    /// Accelerometer white noise per sample, 1σ, mg.
    #[arg(long, value_name = "MG", default_value_t = 1.0, value_parser = recording::limits::real(recording::limits::MIN_LIMIT, crate::limits::MAX_SIM_NOISE))]
    pub noise_mg: f64,
    /// Gyro white noise per sample, 1σ, °/s.
    #[arg(long, value_name = "DEG_S", default_value_t = 0.05, value_parser = recording::limits::real(recording::limits::MIN_LIMIT, crate::limits::MAX_SIM_NOISE))]
    pub gyro_noise_deg_s: f64,
    /// Unit file giving the scale factors and lever arms to predict for (default: the paper's unit,
    /// or for a plan with package = "single" `host/units/single-package.toml`, a MEMS IMU).
    #[arg(long, value_name = "FILE")]
    pub unit: Option<PathBuf>,
    /// Predict with the accelerometers' bias a random walk of this strength, mg/√s (the Allan K
    /// of `host noise`, in mg; docs/model.md §11): the segments' order in the plan then matters.
    /// Without it, the walk the unit's class is expected to have (see --gyro-bias-walk); 0 for a
    /// constant bias.
    #[arg(long, value_name = "MG_SQRT_S", value_parser = recording::limits::real(0.0, crate::limits::MAX_BIAS_WALK_MG_SQRT_S))]
    pub bias_walk: Option<f64>,
    /// Predict with the gyro's bias a random walk of this strength, °/s/√s (docs/model.md §11.6);
    /// 0 for a constant gyro bias. Without it (and without --bias-walk) the walks the unit's
    /// class is expected to have: the unit file's `[noise]` figures where it has them, else for a
    /// digital MEMS unit (an LSB plan, or a single package) 0.002 mg/√s and 0.0005 °/s/√s,
    /// ordinary figures for a consumer part, and none for an analog unit.
    #[arg(long, value_name = "DEG_S_SQRT_S", value_parser = recording::limits::real(0.0, crate::limits::MAX_GYRO_BIAS_WALK_DEG_S_SQRT_S))]
    pub gyro_bias_walk: Option<f64>,
    /// Print the prediction as one JSON document on stdout (the table goes to stderr).
    #[arg(long)]
    pub json: bool,
}

/// `host plan --check`: the plan's segments and the predicted 1σ of every parameter.
pub(crate) fn run(a: &PlanArgs, quiet: bool) -> Result<Prediction, CliError> {
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
    let walks = expected_walks(a, &plan, &unit)?;
    let k = truth.statics.scale_out_per_g;
    let settings = PredictSettings {
        noise_out_per_sample_1sigma: k.map(|k| a.noise_mg * 1e-3 * k.abs()),
        gyro_noise_rad_s: a.gyro_noise_deg_s.to_radians(),
        options: estimator::estimate::EstimateOptions {
            bias_walk: if walks.accel_mg_sqrt_s > 0.0 {
                estimator::estimate::BiasWalk::Given(walks.accel_mg_sqrt_s)
            } else {
                estimator::estimate::BiasWalk::Off
            },
            gyro_bias_walk_deg_s_sqrt_s: walks.gyro_deg_s_sqrt_s,
            ..estimator::estimate::EstimateOptions::new(crate::cli::spelling::FLAGS)
        },
        ..PredictSettings::white(0.0, crate::cli::spelling::FLAGS)
    };
    let stats = estimator::sim::synth::prediction_stats(&plan, &truth, &settings)
        .map_err(estimator::estimate::EstimateError::from)?;
    let prediction = predict(&plan, &truth, &stats, &settings)?;
    out.line("")?;
    let walk = walks.describe();
    out.line(format_args!(
        "noise: {} mg per sample on each accelerometer, {} °/s on the gyro{walk}",
        a.noise_mg, a.gyro_noise_deg_s
    ))?;
    out.human(outputs::report::render_prediction(&prediction))?;
    let advice = if walks.accel_mg_sqrt_s > 0.0 {
        app::segment_order::order_advice(&plan, &truth, &settings)?
    } else {
        Vec::new()
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
        "bias_walk_mg_sqrt_s": walks.accel_mg_sqrt_s,
        "gyro_bias_walk_deg_s_sqrt_s": walks.gyro_deg_s_sqrt_s,
        "walks_from": walks.from,
        "parameters": parameters,
        "lever_arms_observable": prediction.lever_arms_observable,
        "lever_arms_fixed": prediction.lever_arms_fixed,
        "warnings": estimator::estimate::note::Note::texts(&prediction.warnings),
        "single_package": prediction.single_package,
        "in_package_size_effect": prediction
            .single_package
            .then_some(estimator::estimate::IN_PACKAGE_NOT_OBSERVABLE),
    });
    if !advice.is_empty() {
        doc["order_advice"] = json!(advice);
    }
    out.document(&doc)?;
    Ok(prediction)
}

/// A digital MEMS unit's accelerometer bias walk when nothing says otherwise, mg/√s: an ordinary
/// figure for a consumer part (docs/model.md §11).
const MEMS_ACCEL_WALK_MG_SQRT_S: f64 = 0.002;
/// And its gyro's, °/s/√s (docs/model.md §11.6).
const MEMS_GYRO_WALK_DEG_S_SQRT_S: f64 = 0.0005;

/// The walks the prediction assumes and where they came from.
struct Walks {
    accel_mg_sqrt_s: f64,
    gyro_deg_s_sqrt_s: f64,
    /// `given`, `unit` (its file's `[noise]`), `mems` (the class's ordinary figures) or `none`.
    from: &'static str,
}

impl Walks {
    /// The clause of the noise line that states them.
    fn describe(&self) -> String {
        let why = match self.from {
            "given" => "given",
            "unit" => "the unit file's [noise]",
            "mems" => "expected of a digital MEMS unit; --bias-walk 0 --gyro-bias-walk 0 for none",
            _ => return String::new(),
        };
        format!(
            "; bias random walks {} mg/√s and {} °/s/√s ({why}; docs/model.md §11)",
            self.accel_mg_sqrt_s, self.gyro_deg_s_sqrt_s
        )
    }
}

/// The walks to predict with: those given, else the unit file's `[noise]` figures, else those of
/// the unit's class (a digital MEMS unit: an LSB plan or a single package; an analog unit: none).
fn expected_walks(a: &PlanArgs, plan: &Plan, unit: &UnitFile) -> Result<Walks, CliError> {
    if a.bias_walk.is_some() || a.gyro_bias_walk.is_some() {
        return Ok(Walks {
            accel_mg_sqrt_s: a.bias_walk.unwrap_or(0.0),
            gyro_deg_s_sqrt_s: a.gyro_bias_walk.unwrap_or(0.0),
            from: "given",
        });
    }
    let noise = estimator::sim::NoiseModel::from_unit_file(unit)?;
    if let Some(n) = noise.filter(|n| n.accel_bias_walk_mg_sqrt_s > 0.0) {
        return Ok(Walks {
            accel_mg_sqrt_s: n.accel_bias_walk_mg_sqrt_s,
            gyro_deg_s_sqrt_s: n.gyro_bias_walk_one(),
            from: "unit",
        });
    }
    let mems = plan.output_unit == shared::OutputUnit::Lsb || plan.package == Package::Single;
    Ok(if mems {
        // A plan without spins estimates no gyro model for a gyro walk to weigh.
        let spins = plan.segments.iter().any(|s| !s.is_static());
        Walks {
            accel_mg_sqrt_s: MEMS_ACCEL_WALK_MG_SQRT_S,
            gyro_deg_s_sqrt_s: if spins {
                MEMS_GYRO_WALK_DEG_S_SQRT_S
            } else {
                0.0
            },
            from: "mems",
        }
    } else {
        Walks {
            accel_mg_sqrt_s: 0.0,
            gyro_deg_s_sqrt_s: 0.0,
            from: "none",
        }
    })
}

/// The segment-order advice under the walk (docs/model.md §11.2), one paragraph each; nothing when
/// no order helps.
fn print_advice(advice: &[app::segment_order::OrderAdvice], out: &Output) -> Result<(), CliError> {
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
