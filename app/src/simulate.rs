//! `simulate`: a virtual unit on a virtual rate table, written as a session directory
//! (`plan.toml`, `samples.csv`, `truth.toml`). The command line's flags and Python's keyword
//! arguments both become a [`Simulation`].

use estimator::sim::{simulate_to_dir_with_progress, NoiseModel, SimulateError, SimulationSummary};
use estimator::unit_file::{UnitFile, UnitFileError};
use recording::session::builtin::{load_plan, paper_plan};
use recording::session::{Plan, PlanError};
use std::path::PathBuf;

/// A simulated session to write.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct Simulation {
    /// The session directory to write.
    pub out: PathBuf,
    /// The unit file of the simulated unit (default: the paper's unit).
    pub unit: Option<PathBuf>,
    /// A plan file or a built-in plan's name (default: the paper's plan).
    pub plan: Option<String>,
    /// Seed of the noise.
    pub seed: u64,
    /// Replace an existing session.
    pub force: bool,
    /// The noise, over the defaults and the unit file's `[noise]`.
    pub noise: NoiseChoices,
}

/// The noise asked for: each given value replaces the unit file's (or the default's).
#[derive(Clone, Debug, Default, PartialEq)]
pub struct NoiseChoices {
    /// Start from no noise at all.
    pub no_noise: bool,
    /// Accelerometer white noise per sample, 1σ, mg.
    pub noise_mg: Option<f64>,
    /// ADC quantisation step in the output unit.
    pub lsb: Option<f64>,
    /// Accelerometer bias random walk, mg/√s.
    pub drift_mg_sqrt_s: Option<f64>,
    /// Random tilt of each table mount, 1σ per axis, degrees.
    pub tilt_deg: Option<f64>,
    /// Table rate scale error, fraction.
    pub rate_scale: Option<f64>,
    /// Table rate offset, °/s.
    pub rate_offset_deg_s: Option<f64>,
    /// Gyro white noise per sample, 1σ, °/s.
    pub gyro_noise_deg_s: Option<f64>,
    /// Gyro bias, body axes, °/s.
    pub gyro_bias_deg_s: Option<[f64; 3]>,
    /// Gyro scale errors, ppm.
    pub gyro_scale_ppm: Option<[f64; 3]>,
    /// Every off-diagonal entry of the gyro matrix, degrees.
    pub gyro_misalignment_deg: Option<f64>,
    /// Accelerometer flicker bias noise as its bias instability, mg.
    pub flicker_mg: Option<f64>,
    /// Gyro bias random walk, °/s/√s.
    pub gyro_drift_deg_s_sqrt_s: Option<f64>,
    /// Gyro flicker bias noise as its bias instability, °/s.
    pub gyro_flicker_deg_s: Option<f64>,
}

/// Why a simulation was not written; each keeps its cause.
#[derive(Debug, thiserror::Error)]
pub enum SimulationError {
    /// The unit file.
    #[error(transparent)]
    Unit(#[from] UnitFileError),
    /// The plan.
    #[error(transparent)]
    Plan(#[from] PlanError),
    /// The simulator (its noise model or the session it writes).
    #[error(transparent)]
    Simulate(#[from] SimulateError),
}

/// What was written.
#[derive(Debug)]
pub struct Simulated {
    /// Rows and notes.
    pub summary: SimulationSummary,
    /// The plan simulated.
    pub plan: Plan,
    /// The noise simulated.
    pub noise: NoiseModel,
}

impl NoiseChoices {
    /// The noise model: the defaults, then the unit file's `[noise]`, then these choices.
    pub fn model(&self, unit: &UnitFile) -> Result<NoiseModel, SimulateError> {
        let mut n = if self.no_noise {
            NoiseModel::none()
        } else {
            NoiseModel::from_unit_file(unit)?.unwrap_or_default()
        };
        let set = |dst: &mut f64, v: Option<f64>| {
            if let Some(v) = v {
                *dst = v;
            }
        };
        set(&mut n.accel_white_mg, self.noise_mg);
        set(&mut n.accel_quantum_out, self.lsb);
        set(&mut n.accel_bias_walk_mg_sqrt_s, self.drift_mg_sqrt_s);
        set(&mut n.table_tilt_deg, self.tilt_deg);
        set(&mut n.table_rate_scale, self.rate_scale);
        set(&mut n.table_rate_offset_deg_s, self.rate_offset_deg_s);
        set(&mut n.gyro_white_deg_s, self.gyro_noise_deg_s);
        set(&mut n.accel_flicker_mg, self.flicker_mg);
        if let Some(k) = self.gyro_drift_deg_s_sqrt_s {
            // One strength given replaces the unit file's, per axis too.
            n.gyro_bias_walk_deg_s_sqrt_s = k;
            n.gyro_bias_walk_per_axis_deg_s_sqrt_s = None;
        }
        set(&mut n.gyro_flicker_deg_s, self.gyro_flicker_deg_s);
        if let Some(b) = self.gyro_bias_deg_s {
            n.gyro_bias_deg_s = b;
        }
        if self.gyro_scale_ppm.is_some() || self.gyro_misalignment_deg.is_some() {
            let scale = self.gyro_scale_ppm.unwrap_or([0.0; 3]).map(|p| p * 1e-6);
            let mis = self.gyro_misalignment_deg.unwrap_or(0.0).to_radians();
            n.gyro_matrix = estimator::sim::session::gyro_matrix(scale, mis);
        }
        n.validate()?;
        Ok(n)
    }
}

/// Writes the simulated session, advancing `bar` by rows (when given).
pub fn simulate(
    s: &Simulation,
    bar: Option<&indicatif::ProgressBar>,
) -> Result<Simulated, SimulationError> {
    let unit = match &s.unit {
        Some(p) => UnitFile::load(p)?,
        None => UnitFile::paper_unit(),
    };
    let plan = match &s.plan {
        Some(spec) => load_plan(spec)?,
        None => paper_plan(),
    };
    let noise = s.noise.model(&unit)?;
    let hidden = indicatif::ProgressBar::hidden();
    let bar = bar.unwrap_or(&hidden);
    let summary =
        simulate_to_dir_with_progress(&s.out, &unit, &plan, &noise, s.seed, s.force, bar)?;
    Ok(Simulated {
        summary,
        plan,
        noise,
    })
}
