//! `host simulate`: a virtual unit on a virtual rate table, written as a recording.

use super::CliError;
use crate::limits;
use app::simulate::{simulate, NoiseChoices, Simulated, Simulation};
use clap::Args;
#[cfg(test)]
use estimator::sim::NoiseModel;
use estimator::sim::SimulationSummary;
#[cfg(test)]
use estimator::unit_file::UnitFile;
use recording::ui::progress_bar;
use std::path::PathBuf;

/// `host simulate`.
#[derive(Debug, Args)]
pub(crate) struct SimulateArgs {
    /// Session directory to write (plan.toml, samples.csv, truth.toml).
    #[arg(long, value_name = "DIR")]
    pub out: PathBuf,
    // The `[noise]` below is the TOML table's name in the --help text, not a link.
    #[allow(rustdoc::broken_intra_doc_links)]
    /// Unit file of the unit to simulate (default: the paper's unit). Its [noise] table, if any,
    /// replaces the default noise; the flags below override both.
    #[arg(long, value_name = "FILE")]
    pub unit: Option<PathBuf>,
    /// Plan file, or a built-in plan's name: paper (default), oblique, short, short-oblique,
    /// quick-oblique, hand, single-package, thermal-soak, thermal-ramp (`host plan --check NAME`
    /// shows one).
    #[arg(long, value_name = "FILE|NAME")]
    pub plan: Option<String>,
    /// Seed of the noise.
    #[arg(long, default_value_t = 1, value_parser = recording::limits::whole_u64(0, u64::MAX))]
    pub seed: u64,
    /// Replace an existing samples.csv in DIR.
    #[arg(long)]
    pub force: bool,
    /// Start from no noise at all (then add what the flags below ask for).
    #[arg(long)]
    pub no_noise: bool,
    /// Accelerometer white noise per sample, 1σ, mg [default: 1].
    #[arg(long, value_name = "MG", value_parser = recording::limits::real(0.0, limits::MAX_SIM_NOISE))]
    pub noise_mg: Option<f64>,
    /// ADC quantisation step in the output unit (V or LSB); 0 = none [default: 0].
    #[arg(long, value_name = "STEP", value_parser = recording::limits::real(0.0, limits::MAX_SIM_NOISE))]
    pub lsb: Option<f64>,
    /// Accelerometer bias random walk, mg/√s [default: 0].
    #[arg(long, value_name = "MG_SQRT_S", value_parser = recording::limits::real(0.0, limits::MAX_SIM_NOISE))]
    pub drift_mg_sqrt_s: Option<f64>,
    /// Table attitude error: random tilt of each mount, 1σ per axis, degrees [default: 0].
    #[arg(long, value_name = "DEG", value_parser = recording::limits::real(0.0, 45.0))]
    pub tilt_deg: Option<f64>,
    /// Table rate scale error, fraction (1e-4 = 100 ppm) [default: 0].
    #[arg(long, value_name = "FRACTION", allow_hyphen_values = true, value_parser = recording::limits::real(-0.5, 0.5))]
    pub rate_scale: Option<f64>,
    /// Table rate offset, °/s [default: 0].
    #[arg(long, value_name = "DEG_S", allow_hyphen_values = true, value_parser = recording::limits::real(-recording::limits::MAX_RATE_DEG_S, recording::limits::MAX_RATE_DEG_S))]
    pub rate_offset_deg_s: Option<f64>,
    /// Gyro white noise per sample, 1σ, °/s [default: 0.05].
    #[arg(long, value_name = "DEG_S", value_parser = recording::limits::real(0.0, limits::MAX_SIM_NOISE))]
    pub gyro_noise_deg_s: Option<f64>,
    /// Gyro bias, body axes, °/s, as X,Y,Z [default: 0,0,0].
    #[arg(
        long,
        value_name = "X,Y,Z",
        value_delimiter = ',',
        num_args = 1,
        allow_hyphen_values = true,
        value_parser = recording::limits::real(-recording::limits::MAX_RATE_DEG_S, recording::limits::MAX_RATE_DEG_S)
    )]
    pub gyro_bias_deg_s: Option<Vec<f64>>,
    /// Gyro scale errors, ppm, as X,Y,Z (with --gyro-misalignment-deg: the gyro matrix) [default: 0].
    #[arg(
        long,
        value_name = "X,Y,Z",
        value_delimiter = ',',
        num_args = 1,
        allow_hyphen_values = true,
        value_parser = recording::limits::real(-1e5, 1e5)
    )]
    pub gyro_scale_ppm: Option<Vec<f64>>,
    /// Gyro misalignment: every off-diagonal entry of the gyro matrix, degrees [default: 0].
    #[arg(long, value_name = "DEG", allow_hyphen_values = true, value_parser = recording::limits::real(-10.0, 10.0))]
    pub gyro_misalignment_deg: Option<f64>,
    /// Accelerometer flicker (1/f) bias noise as its bias instability B, mg [default: 0].
    #[arg(long, value_name = "MG", value_parser = recording::limits::real(0.0, limits::MAX_SIM_NOISE))]
    pub flicker_mg: Option<f64>,
    /// Gyro bias random walk, °/s/√s [default: 0].
    #[arg(long, value_name = "DEG_S_SQRT_S", value_parser = recording::limits::real(0.0, limits::MAX_SIM_NOISE))]
    pub gyro_drift_deg_s_sqrt_s: Option<f64>,
    /// Gyro flicker (1/f) bias noise as its bias instability B, °/s [default: 0].
    #[arg(long, value_name = "DEG_S", value_parser = recording::limits::real(0.0, limits::MAX_SIM_NOISE))]
    pub gyro_flicker_deg_s: Option<f64>,
}

/// Three values of a flag that takes X,Y,Z.
fn three(v: &Option<Vec<f64>>, flag: &str) -> Result<Option<[f64; 3]>, CliError> {
    v.as_deref()
        .map(|v| {
            <[f64; 3]>::try_from(v)
                .map_err(|_| CliError::Usage(format!("{flag} takes three values: X,Y,Z")))
        })
        .transpose()
}

/// The noise the flags ask for, as the application layer takes it.
fn noise_choices(a: &SimulateArgs) -> Result<NoiseChoices, CliError> {
    Ok(NoiseChoices {
        no_noise: a.no_noise,
        noise_mg: a.noise_mg,
        lsb: a.lsb,
        drift_mg_sqrt_s: a.drift_mg_sqrt_s,
        tilt_deg: a.tilt_deg,
        rate_scale: a.rate_scale,
        rate_offset_deg_s: a.rate_offset_deg_s,
        gyro_noise_deg_s: a.gyro_noise_deg_s,
        gyro_bias_deg_s: three(&a.gyro_bias_deg_s, "--gyro-bias-deg-s")?,
        gyro_scale_ppm: three(&a.gyro_scale_ppm, "--gyro-scale-ppm")?,
        gyro_misalignment_deg: a.gyro_misalignment_deg,
        flicker_mg: a.flicker_mg,
        gyro_drift_deg_s_sqrt_s: a.gyro_drift_deg_s_sqrt_s,
        gyro_flicker_deg_s: a.gyro_flicker_deg_s,
    })
}

/// The noise model of `host simulate`: defaults, then the unit file's `[noise]`, then the flags.
#[cfg(test)]
pub(crate) fn noise_from_args(a: &SimulateArgs, unit: &UnitFile) -> Result<NoiseModel, CliError> {
    Ok(noise_choices(a)?.model(unit)?)
}

/// `host simulate`.
pub(crate) fn run(a: &SimulateArgs, quiet: bool) -> Result<SimulationSummary, CliError> {
    let simulation = Simulation {
        out: a.out.clone(),
        unit: a.unit.clone(),
        plan: a.plan.clone(),
        seed: a.seed,
        force: a.force,
        noise: noise_choices(a)?,
    };
    let bar = progress_bar(0, "simulating", quiet);
    let Simulated {
        summary,
        plan,
        noise,
    } = simulate(&simulation, Some(&bar))?;
    let out = super::output::Output { json: false, quiet };
    for note in &summary.notes {
        out.note(format_args!("note: {note}"));
    }
    if !quiet {
        crate::outln!(
            "simulated {} rows ({} segments, {} Hz, seed {}) into {}",
            summary.rows,
            plan.segments.len(),
            plan.sample_rate_hz,
            a.seed,
            a.out.display()
        )?;
        crate::outln!(
            "noise: {:.3} mg white, {:.3} mg/√s bias walk, quantum {}, tilt {} °, rate scale {}, \
             rate offset {} °/s, gyro {:.3} °/s white, gyro bias {:?} °/s",
            noise.accel_white_mg,
            noise.accel_bias_walk_mg_sqrt_s,
            noise.accel_quantum_out,
            noise.table_tilt_deg,
            noise.table_rate_scale,
            noise.table_rate_offset_deg_s,
            noise.gyro_white_deg_s,
            noise.gyro_bias_deg_s
        )?;
    }
    Ok(summary)
}
