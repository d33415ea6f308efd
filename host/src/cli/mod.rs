//! The command line: `host simulate`, `host calibrate`, `host plan --check`. `main.rs` only parses
//! and prints the error; everything else is here, testable.

pub mod apply;
pub mod device;
pub mod export;
pub mod noise;

use crate::calibration_files::{now_unix_s, write_calibration_files, OutputError};
use crate::estimate::{
    calibrate_session_stats, predict, CalibrationOutcome, EstimateError, EstimateOptions, Method,
    PredictSettings, ReferenceChoice,
};
use crate::export::ExportError;
use crate::report::compare::{compare, CompareError};
use crate::report::document::{
    navigation_check, report, NavigationCheckArgs, ReportError, ReportOptions,
};
use crate::session::builtin::{load_plan, paper_plan};
use crate::session::{read_session, ReadOptions, RecordingError, Session};
use crate::session::{Plan, PlanError};
use crate::sim::{simulate_to_dir_with_progress, NoiseModel, SimulateError};
use crate::ui::progress_bar;
use crate::unit_file::{UnitFile, UnitFileError};
use clap::{Args, Parser, Subcommand};
use device::{CalibratePortOptions, DeviceCliError, PortArgs};
use shared::UnitId;
use std::path::{Path, PathBuf};
use std::time::Instant;

/// Calibrate a strap-down tri-axis accelerometer unit (static + dynamic, with lever arms).
#[derive(Debug, Parser)]
#[command(name = "host", version, about)]
pub struct Cli {
    /// What to do.
    #[command(subcommand)]
    pub command: Command,
    /// No progress bars (they are drawn only on a terminal anyway).
    #[arg(long, short, global = true)]
    pub quiet: bool,
}

/// The subcommands.
#[derive(Debug, Subcommand)]
pub enum Command {
    /// Simulate a session: a virtual unit on a virtual rate table, written as a recording.
    Simulate(SimulateArgs),
    /// Estimate the calibration from a recorded session (--input), or live from a device (--port).
    Calibrate(CalibrateArgs),
    /// Check a plan: its segments and the predicted 1σ of every parameter (Cramér–Rao bound).
    Plan(PlanArgs),
    /// Write the report of a session calibrated by a calibration: figures (PNG, SVG) and
    /// report.html / report.md with Tables 1–4 and the navigation replay.
    Report(ReportArgs),
    /// The paper's navigation check on a simulated session of its unit: position drift without
    /// compensation, with static and with static + dynamic compensation.
    NavigationCheck(NavigationCheckCliArgs),
    /// Two calibrations of one unit side by side, each difference in units of its combined 1σ.
    Compare {
        /// First calibration.toml.
        a: PathBuf,
        /// Second calibration.toml.
        b: PathBuf,
    },
    /// A calibration in another tool's format: kalibr, fusion-c, c-header, json, px4, ardupilot
    /// (or the TOML conversions plain, fusion, all).
    Export(export::ExportArgs),
    /// Apply a calibration to a recording with the device's own compensation code: CSV of the
    /// specific force per row (segment,t_s,f_x_g,f_y_g,f_z_g).
    Apply(apply::ApplyArgs),
    /// Noise of a still recording: overlapping Allan deviation per axis, fitted white noise density,
    /// bias instability and random walk; table, figure, and the figures Kalibr needs (noise.json).
    Noise(noise::NoiseArgs),
    /// Write a calibration (calibration.bin, or a calibration.toml encoded for the unit) to a device,
    /// reset it and check that it applied it.
    Flash {
        /// How to reach the device.
        #[command(flatten)]
        port: PortArgs,
        /// calibration.bin or calibration.toml.
        #[arg(long, value_name = "FILE")]
        calibration: PathBuf,
    },
    /// Read the calibration stored on a device, as a unit file (stdout, or --out FILE).
    Read {
        /// How to reach the device.
        #[command(flatten)]
        port: PortArgs,
        /// Where to write it (default: stdout).
        #[arg(long, value_name = "FILE")]
        out: Option<PathBuf>,
    },
    /// Show a device's live compensated output.
    Monitor {
        /// How to reach the device.
        #[command(flatten)]
        port: PortArgs,
        /// Samples averaged per line.
        #[arg(long, default_value_t = 100)]
        window: u32,
        /// Stop after this many lines (default: run until interrupted).
        #[arg(long)]
        count: Option<u64>,
    },
}

/// `host simulate`.
#[derive(Debug, Args)]
pub struct SimulateArgs {
    /// Session directory to write (plan.toml, samples.csv, truth.toml).
    #[arg(long, value_name = "DIR")]
    pub out: PathBuf,
    /// Unit file of the unit to simulate (default: the paper's unit). Its [noise] table, if any,
    /// replaces the default noise; the flags below override both.
    #[arg(long, value_name = "FILE")]
    pub unit: Option<PathBuf>,
    /// Plan file, or a built-in plan's name: paper (default), oblique, short, short-oblique, quick-oblique.
    #[arg(long, value_name = "FILE|NAME")]
    pub plan: Option<String>,
    /// Seed of the noise.
    #[arg(long, default_value_t = 1)]
    pub seed: u64,
    /// Replace an existing samples.csv in DIR.
    #[arg(long)]
    pub force: bool,
    /// Start from no noise at all (then add what the flags below ask for).
    #[arg(long)]
    pub no_noise: bool,
    /// Accelerometer white noise per sample, 1σ, mg [default: 1].
    #[arg(long, value_name = "MG")]
    pub noise_mg: Option<f64>,
    /// ADC quantisation step in the output unit (V or LSB); 0 = none [default: 0].
    #[arg(long, value_name = "STEP")]
    pub lsb: Option<f64>,
    /// Accelerometer bias random walk, mg/√s [default: 0].
    #[arg(long, value_name = "MG_SQRT_S")]
    pub drift_mg_sqrt_s: Option<f64>,
    /// Table attitude error: random tilt of each mount, 1σ per axis, degrees [default: 0].
    #[arg(long, value_name = "DEG")]
    pub tilt_deg: Option<f64>,
    /// Table rate scale error, fraction (1e-4 = 100 ppm) [default: 0].
    #[arg(long, value_name = "FRACTION", allow_hyphen_values = true)]
    pub rate_scale: Option<f64>,
    /// Table rate offset, °/s [default: 0].
    #[arg(long, value_name = "DEG_S", allow_hyphen_values = true)]
    pub rate_offset_deg_s: Option<f64>,
    /// Gyro white noise per sample, 1σ, °/s [default: 0.05].
    #[arg(long, value_name = "DEG_S")]
    pub gyro_noise_deg_s: Option<f64>,
    /// Gyro bias, body axes, °/s, as X,Y,Z [default: 0,0,0].
    #[arg(
        long,
        value_name = "X,Y,Z",
        value_delimiter = ',',
        num_args = 1,
        allow_hyphen_values = true
    )]
    pub gyro_bias_deg_s: Option<Vec<f64>>,
}

/// `host calibrate`: from a recorded session (`--input`) or live from a device (`--port`).
#[derive(Debug, Args)]
pub struct CalibrateArgs {
    /// Session directory (plan.toml + samples.csv).
    #[arg(long, value_name = "DIR", conflicts_with = "port")]
    pub input: Option<PathBuf>,
    /// Calibrate a device live: its serial port (or QEMU's pty), or `sim` for the built-in simulated
    /// device. Records the session, estimates, writes the files, flashes, resets and verifies.
    #[arg(long, value_name = "PORT|sim")]
    pub port: Option<String>,
    /// With --port: baud rate of the serial port.
    #[arg(long, default_value_t = crate::device::serial::DEFAULT_BAUD, requires = "port")]
    pub baud: u32,
    /// With --port: seconds to wait for each answer of the device.
    #[arg(long, default_value_t = 5.0, requires = "port")]
    pub timeout_s: f64,
    /// With --port sim: the simulated unit's parameters (default: the paper's unit).
    #[arg(long, value_name = "FILE", requires = "port")]
    pub sim_unit: Option<PathBuf>,
    /// With --port: plan file or built-in name (default: oblique with a virtual table, else paper).
    #[arg(long, value_name = "FILE|NAME", requires = "port")]
    pub plan: Option<String>,
    /// With --port: samples per streamed window (default: a 50th of the device's rate).
    #[arg(long, requires = "port")]
    pub window: Option<u32>,
    /// With --port: largest compensated error accepted at a verification position, mg.
    #[arg(long, default_value_t = 1.0, requires = "port")]
    pub verify_tolerance_mg: f64,
    /// Where to write calibration.toml and calibration.bin (default: the session directory).
    #[arg(long, value_name = "OUT")]
    pub out_dir: Option<PathBuf>,
    /// Estimator: joint (static and lever arms together, default) or paper (the paper's eq. 24).
    #[arg(long, value_enum, default_value_t = MethodArg::Joint)]
    pub method: MethodArg,
    /// Point the lever arms are given relative to: the table axis (paper) or the sensing points' centroid.
    #[arg(long, value_enum, default_value_t = ReferenceArg::TableAxis)]
    pub reference: ReferenceArg,
}

/// `--method`.
#[derive(Clone, Copy, Debug, PartialEq, Eq, clap::ValueEnum)]
pub enum MethodArg {
    /// Static part and lever arms in one weighted least-squares fit.
    Joint,
    /// The paper's two steps: static fit, then eq. 24 per lever-arm component.
    Paper,
}

/// `--reference`.
#[derive(Clone, Copy, Debug, PartialEq, Eq, clap::ValueEnum)]
pub enum ReferenceArg {
    /// The point of the body on the table's spin axis (the paper's assumption).
    TableAxis,
    /// The centroid of the three sensing points.
    Centroid,
}

/// `host report`.
#[derive(Debug, Args)]
pub struct ReportArgs {
    /// Session directory (plan.toml + samples.csv).
    #[arg(long, value_name = "DIR")]
    pub input: PathBuf,
    /// The calibration to judge (calibration.toml; default: DIR/calibration.toml).
    #[arg(long, value_name = "FILE")]
    pub calibration: Option<PathBuf>,
    /// Where to write the figures and pages (default: DIR/report).
    #[arg(long, value_name = "OUT")]
    pub out_dir: Option<PathBuf>,
    /// The static segment to replay for the navigation check (default: the first static one).
    #[arg(long, value_name = "NAME")]
    pub static_run: Option<String>,
    /// The rotating segment to replay (default: the fastest constant-rate one).
    #[arg(long, value_name = "NAME")]
    pub rate_run: Option<String>,
    /// Length of the replayed navigation runs, s.
    #[arg(long, default_value_t = 60.0)]
    pub duration_s: f64,
    /// No PNG figures (SVG only).
    #[arg(long)]
    pub no_png: bool,
}

/// `host navigation-check`.
#[derive(Debug, Args)]
pub struct NavigationCheckCliArgs {
    /// Seed of the simulated session's noise.
    #[arg(long, default_value_t = 1)]
    pub seed: u64,
    /// Length of the replayed navigation runs, s.
    #[arg(long, default_value_t = 60.0)]
    pub duration_s: f64,
    /// Where to write the figures and pages (default: nothing written).
    #[arg(long, value_name = "OUT")]
    pub out_dir: Option<PathBuf>,
    /// Unit file of the simulated unit (default: the paper's unit).
    #[arg(long, value_name = "FILE")]
    pub unit: Option<PathBuf>,
    /// Plan file or built-in name (default: paper).
    #[arg(long, value_name = "FILE|NAME")]
    pub plan: Option<String>,
}

/// `host plan`.
#[derive(Debug, Args)]
pub struct PlanArgs {
    /// Plan file (or built-in plan name) to check.
    #[arg(long, value_name = "FILE|NAME")]
    pub check: String,
    /// Accelerometer white noise per sample, 1σ, mg.
    #[arg(long, value_name = "MG", default_value_t = 1.0)]
    pub noise_mg: f64,
    /// Gyro white noise per sample, 1σ, °/s.
    #[arg(long, value_name = "DEG_S", default_value_t = 0.05)]
    pub gyro_noise_deg_s: f64,
    /// Unit file giving the scale factors and lever arms to predict for (default: the paper's unit).
    #[arg(long, value_name = "FILE")]
    pub unit: Option<PathBuf>,
}

/// Why a command failed. Each message names the problem and, where there is one, the fix.
#[derive(Debug)]
pub enum CliError {
    /// Reading or writing a session.
    Recording(RecordingError),
    /// A plan.
    Plan(PlanError),
    /// A unit file.
    Unit(UnitFileError),
    /// The simulator.
    Simulate(SimulateError),
    /// The estimator.
    Estimate(EstimateError),
    /// Writing the result.
    Output(OutputError),
    /// A command talking to a device.
    Device(DeviceCliError),
    /// `host report` / `host navigation-check`.
    Report(ReportError),
    /// `host compare`.
    Compare(CompareError),
    /// `host export`.
    Export(ExportError),
    /// `host apply`.
    Apply(crate::apply::ApplyError),
    /// `host noise`.
    Noise(crate::noise::NoiseError),
    /// A result file could not be written.
    Written(crate::output_file::OutputFileError),
    /// The command line is incomplete.
    Usage(String),
}

impl std::fmt::Display for CliError {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match self {
            CliError::Recording(e) => write!(f, "{e}"),
            CliError::Plan(e) => write!(f, "{e}"),
            CliError::Unit(e) => write!(f, "{e}"),
            CliError::Simulate(e) => write!(f, "{e}"),
            CliError::Estimate(e) => write!(f, "{e}"),
            CliError::Output(e) => write!(f, "{e}"),
            CliError::Device(e) => write!(f, "{e}"),
            CliError::Report(e) => write!(f, "{e}"),
            CliError::Compare(e) => write!(f, "{e}"),
            CliError::Export(e) => write!(f, "{e}"),
            CliError::Apply(e) => write!(f, "{e}"),
            CliError::Noise(e) => write!(f, "{e}"),
            CliError::Written(e) => write!(f, "{e}"),
            CliError::Usage(m) => write!(f, "{m}"),
        }
    }
}

impl std::error::Error for CliError {}

impl From<RecordingError> for CliError {
    fn from(e: RecordingError) -> Self {
        CliError::Recording(e)
    }
}
impl From<PlanError> for CliError {
    fn from(e: PlanError) -> Self {
        CliError::Plan(e)
    }
}
impl From<UnitFileError> for CliError {
    fn from(e: UnitFileError) -> Self {
        CliError::Unit(e)
    }
}
impl From<EstimateError> for CliError {
    fn from(e: EstimateError) -> Self {
        CliError::Estimate(e)
    }
}
impl From<ReportError> for CliError {
    fn from(e: ReportError) -> Self {
        CliError::Report(e)
    }
}
impl From<CompareError> for CliError {
    fn from(e: CompareError) -> Self {
        CliError::Compare(e)
    }
}
impl From<crate::apply::ApplyError> for CliError {
    fn from(e: crate::apply::ApplyError) -> Self {
        CliError::Apply(e)
    }
}

impl From<ExportError> for CliError {
    fn from(e: ExportError) -> Self {
        CliError::Export(e)
    }
}
impl From<DeviceCliError> for CliError {
    fn from(e: DeviceCliError) -> Self {
        CliError::Device(e)
    }
}
impl From<OutputError> for CliError {
    fn from(e: OutputError) -> Self {
        CliError::Output(e)
    }
}
impl From<SimulateError> for CliError {
    fn from(e: SimulateError) -> Self {
        CliError::Simulate(e)
    }
}

/// Runs a parsed command line, printing to stdout (results) and stderr (warnings, progress).
pub fn run(cli: Cli) -> Result<(), CliError> {
    match cli.command {
        Command::Simulate(a) => simulate(&a, cli.quiet).map(|_| ()),
        Command::Calibrate(a) if a.port.is_some() => calibrate_live(&a, cli.quiet),
        Command::Calibrate(a) => calibrate(&a, cli.quiet).map(|_| ()),
        Command::Plan(a) => plan_check(&a).map(|_| ()),
        Command::Report(a) => report_command(&a),
        Command::NavigationCheck(a) => navigation_check_command(&a),
        Command::Compare { a, b } => {
            print!("{}", compare(&a, &b)?.render());
            Ok(())
        }
        Command::Export(a) => export::export_command(&a, cli.quiet),
        Command::Apply(a) => apply::apply_command(&a, cli.quiet),
        Command::Noise(a) => noise::noise_command(&a, cli.quiet),
        Command::Flash { port, calibration } => Ok(device::flash(&port, &calibration)?),
        Command::Read { port, out } => Ok(device::read(&port, out.as_deref())?),
        Command::Monitor {
            port,
            window,
            count,
        } => Ok(device::monitor(&port, window, count)?),
    }
}

fn load_unit(path: Option<&Path>) -> Result<UnitFile, CliError> {
    Ok(match path {
        Some(p) => UnitFile::load(p)?,
        None => UnitFile::paper_unit(),
    })
}

/// The noise model of `host simulate`: defaults, then the unit file's `[noise]`, then the flags.
pub fn noise_from_args(a: &SimulateArgs, unit: &UnitFile) -> Result<NoiseModel, CliError> {
    let mut n = if a.no_noise {
        NoiseModel::none()
    } else {
        NoiseModel::from_unit_file(unit)?.unwrap_or_default()
    };
    let set = |dst: &mut f64, v: Option<f64>| {
        if let Some(v) = v {
            *dst = v;
        }
    };
    set(&mut n.accel_white_mg, a.noise_mg);
    set(&mut n.accel_quantum_out, a.lsb);
    set(&mut n.accel_bias_walk_mg_sqrt_s, a.drift_mg_sqrt_s);
    set(&mut n.table_tilt_deg, a.tilt_deg);
    set(&mut n.table_rate_scale, a.rate_scale);
    set(&mut n.table_rate_offset_deg_s, a.rate_offset_deg_s);
    set(&mut n.gyro_white_deg_s, a.gyro_noise_deg_s);
    if let Some(b) = &a.gyro_bias_deg_s {
        n.gyro_bias_deg_s = b
            .as_slice()
            .try_into()
            .map_err(|_| CliError::Usage("--gyro-bias-deg-s takes three values: X,Y,Z".into()))?;
    }
    n.validate()?;
    Ok(n)
}

/// `host simulate`.
pub fn simulate(a: &SimulateArgs, quiet: bool) -> Result<crate::sim::SimulationSummary, CliError> {
    let unit = load_unit(a.unit.as_deref())?;
    let plan = match &a.plan {
        Some(spec) => load_plan(spec)?,
        None => paper_plan(),
    };
    let noise = noise_from_args(a, &unit)?;
    let bar = progress_bar(0, "simulating", quiet);
    let summary =
        simulate_to_dir_with_progress(&a.out, &unit, &plan, &noise, a.seed, a.force, &bar)?;
    for note in &summary.notes {
        eprintln!("note: {note}");
    }
    println!(
        "simulated {} rows ({} segments, {} Hz, seed {}) into {}",
        summary.rows,
        plan.segments.len(),
        plan.sample_rate_hz,
        a.seed,
        a.out.display()
    );
    println!(
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
    );
    Ok(summary)
}

/// Reads a session with the progress bar, printing the reader's warnings to stderr.
pub fn read_session_verbose(dir: &Path, quiet: bool) -> Result<Session, CliError> {
    let session = read_session(dir, &ReadOptions { quiet })?;
    for w in &session.report.warnings {
        eprintln!("warning: {w}");
    }
    Ok(session)
}

/// The estimator options of `host calibrate`'s flags.
pub fn estimate_options(a: &CalibrateArgs) -> EstimateOptions {
    EstimateOptions {
        method: match a.method {
            MethodArg::Joint => Method::Joint,
            MethodArg::Paper => Method::Paper,
        },
        reference: match a.reference {
            ReferenceArg::TableAxis => ReferenceChoice::TableAxis,
            ReferenceArg::Centroid => ReferenceChoice::Centroid,
        },
        ..EstimateOptions::default()
    }
}

/// `host calibrate --port PORT`: the live procedure (`crate::device::procedure`) against a device.
pub fn calibrate_live(a: &CalibrateArgs, quiet: bool) -> Result<(), CliError> {
    let port = PortArgs {
        port: a.port.clone().unwrap_or_default(),
        baud: a.baud,
        timeout_s: a.timeout_s,
        sim_unit: a.sim_unit.clone(),
    };
    let options = CalibratePortOptions {
        plan: a.plan.clone(),
        out_dir: a.out_dir.clone(),
        window: a.window,
        estimate: estimate_options(a),
        verify_tolerance_mg: a.verify_tolerance_mg,
        quiet,
    };
    Ok(device::calibrate_port(&port, &options)?)
}

/// `host calibrate --input DIR`: read (with a progress bar), estimate, print the report, write
/// `OUT/calibration.toml` and `OUT/calibration.bin`.
pub fn calibrate(a: &CalibrateArgs, quiet: bool) -> Result<CalibrationOutcome, CliError> {
    let input = a.input.as_deref().ok_or_else(|| {
        CliError::Usage(
            "calibrate needs --input DIR (a recorded session: plan.toml + samples.csv) or \
             --port PORT (a device; `--port sim` for the built-in simulated one)"
                .into(),
        )
    })?;
    if a.plan.is_some() || a.window.is_some() || a.sim_unit.is_some() {
        return Err(CliError::Usage(
            "--plan, --window and --sim-unit are for --port; a recorded session is read with its own \
             plan.toml (edit that file to change the plan)"
                .into(),
        ));
    }
    let started = Instant::now();
    let session = read_session_verbose(input, quiet)?;
    let read_s = started.elapsed().as_secs_f64();
    println!(
        "read {} rows ({:.1} MB) of {} segments from {} in {:.2} s ({:.2} M rows/s)",
        session.report.rows,
        session.report.bytes as f64 / 1e6,
        session.stats.len(),
        input.display(),
        read_s,
        session.report.rows as f64 / read_s.max(1e-9) / 1e6
    );
    let outcome = calibrate_session_stats(&session.plan, &session.stats, &estimate_options(a))?;
    println!();
    print!("{}", crate::report::render(&outcome));
    let unit_id = match &session.plan.unit_id {
        Some(hex) => UnitId::parse_hex(hex).unwrap_or_default(),
        None => {
            eprintln!(
                "warning: plan.toml has no unit_id: calibration.bin is bound to the all-zero unit id; \
                 add unit_id = \"<24 hex digits>\" to plan.toml to bind it to the unit"
            );
            UnitId::default()
        }
    };
    let out_dir = a.out_dir.as_deref().unwrap_or(input);
    let written = write_calibration_files(out_dir, &outcome, unit_id, now_unix_s())?;
    println!(
        "wrote {} and {} ({} bytes, unit {unit_id})",
        written.toml_path.display(),
        written.bin_path.display(),
        written.blob.len()
    );
    Ok(outcome)
}

/// `host report`.
pub fn report_command(a: &ReportArgs) -> Result<(), CliError> {
    let calibration = a
        .calibration
        .clone()
        .unwrap_or_else(|| a.input.join(crate::calibration_files::CALIBRATION_TOML));
    let out_dir = a.out_dir.clone().unwrap_or_else(|| a.input.join("report"));
    let mut options = ReportOptions {
        navigation_duration_s: a.duration_s,
        static_run: a.static_run.clone(),
        rate_run: a.rate_run.clone(),
        ..ReportOptions::default()
    };
    options.formats.png = !a.no_png;
    let summary = report(&a.input, &calibration, &out_dir, &options)?;
    print!("{}", summary.render());
    Ok(())
}

/// `host navigation-check`.
pub fn navigation_check_command(a: &NavigationCheckCliArgs) -> Result<(), CliError> {
    let mut args = NavigationCheckArgs {
        seed: a.seed,
        out_dir: a.out_dir.clone(),
        ..NavigationCheckArgs::default()
    };
    args.report.navigation_duration_s = a.duration_s;
    if let Some(p) = &a.unit {
        args.unit = UnitFile::load(p)?;
    }
    if let Some(spec) = &a.plan {
        args.plan = load_plan(spec)?;
    }
    print!("{}", navigation_check(&args)?.render());
    Ok(())
}

/// `host plan --check`: the plan's segments and the predicted 1σ of every parameter.
pub fn plan_check(a: &PlanArgs) -> Result<crate::estimate::Prediction, CliError> {
    let plan = load_plan(&a.check)?;
    let unit = load_unit(a.unit.as_deref())?;
    let truth = unit.to_calibration().map_err(|m| {
        CliError::Unit(UnitFileError::Invalid(
            a.unit.clone().unwrap_or_else(|| "<paper unit>".into()),
            m,
        ))
    })?;
    if !(a.noise_mg.is_finite() && a.noise_mg > 0.0) {
        return Err(CliError::Usage(format!(
            "--noise-mg {} must be a positive number",
            a.noise_mg
        )));
    }
    print_plan(&plan);
    let k = truth.statics.scale_out_per_g;
    let settings = PredictSettings {
        noise_out_per_sample_1sigma: k.map(|k| a.noise_mg * 1e-3 * k.abs()),
        gyro_noise_rad_s: a.gyro_noise_deg_s.to_radians(),
        ..PredictSettings::white(0.0)
    };
    let prediction = predict(&plan, &truth, &settings)?;
    println!();
    println!(
        "noise: {} mg per sample on each accelerometer, {} °/s on the gyro",
        a.noise_mg, a.gyro_noise_deg_s
    );
    print!("{}", crate::report::render_prediction(&prediction));
    Ok(prediction)
}

fn print_plan(plan: &Plan) {
    println!(
        "{} segments at {} Hz, output unit {}, g = {} m/s²",
        plan.segments.len(),
        plan.sample_rate_hz,
        plan.output_unit.symbol(),
        plan.gravity_m_s2
    );
    for s in &plan.segments {
        let rate = match s.rate_end_deg_s {
            Some(r1) if r1 != s.rate_deg_s => format!("{} → {} °/s", s.rate_deg_s, r1),
            _ if s.is_static() => "static".to_string(),
            _ => format!("{} °/s", s.rate_deg_s),
        };
        println!(
            "  {:<14} up_b = [{:+.4}, {:+.4}, {:+.4}]  {:<16} {}",
            s.name,
            s.up_b[0],
            s.up_b[1],
            s.up_b[2],
            rate,
            s.duration_s
                .map_or("(no duration)".into(), |d| format!("{d} s"))
        );
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use clap::CommandFactory;

    fn parse(args: &[&str]) -> Cli {
        Cli::try_parse_from(std::iter::once("host").chain(args.iter().copied())).unwrap()
    }

    #[test]
    fn the_command_line_is_well_formed() {
        Cli::command().debug_assert();
        let cli = parse(&[
            "simulate",
            "--out",
            "d",
            "--seed",
            "9",
            "--gyro-bias-deg-s",
            "0.1,-0.2,0.3",
            "--rate-offset-deg-s",
            "-0.5",
        ]);
        let Command::Simulate(a) = cli.command else {
            panic!("not simulate")
        };
        let n = noise_from_args(&a, &UnitFile::paper_unit()).unwrap();
        assert_eq!(n.gyro_bias_deg_s, [0.1, -0.2, 0.3]);
        assert_eq!(n.table_rate_offset_deg_s, -0.5);
        assert_eq!(n.accel_white_mg, 1.0);
        let Command::Calibrate(c) =
            parse(&["calibrate", "--input", "x", "--method", "paper"]).command
        else {
            panic!("not calibrate")
        };
        assert_eq!(estimate_options(&c).method, Method::Paper);
        assert!(Cli::try_parse_from(["host", "calibrate", "--method", "best"]).is_err());
        let Command::Calibrate(c) =
            parse(&["calibrate", "--input", "d", "--plan", "paper"]).command
        else {
            panic!("not calibrate")
        };
        let e = calibrate(&c, true).unwrap_err().to_string();
        assert!(e.contains("--plan") && e.contains("plan.toml"), "{e}");
        let Command::Calibrate(c) = parse(&[
            "calibrate",
            "--port",
            "sim",
            "--plan",
            "short",
            "--window",
            "20",
        ])
        .command
        else {
            panic!("not calibrate")
        };
        assert_eq!((c.port.as_deref(), c.window), (Some("sim"), Some(20)));
        let Command::Flash { port, calibration } =
            parse(&["flash", "--port", "/dev/ttyACM0", "--calibration", "c.bin"]).command
        else {
            panic!("not flash")
        };
        assert_eq!(
            (port.port.as_str(), calibration),
            ("/dev/ttyACM0", PathBuf::from("c.bin"))
        );
    }

    #[test]
    fn report_compare_export_and_navigation_check_parse() {
        let Command::Report(r) = parse(&["report", "--input", "s", "--no-png"]).command else {
            panic!("not report")
        };
        assert!(r.no_png && r.calibration.is_none() && r.duration_s == 60.0);
        let Command::Compare { a, b } = parse(&["compare", "a.toml", "b.toml"]).command else {
            panic!("not compare")
        };
        assert_eq!((a, b), (PathBuf::from("a.toml"), PathBuf::from("b.toml")));
        let Command::Export(export::ExportArgs { format, .. }) =
            parse(&["export", "--calibration", "c.toml", "--format", "fusion"]).command
        else {
            panic!("not export")
        };
        assert_eq!(format, crate::export::ExportFormat::Fusion);
        assert!(
            Cli::try_parse_from(["host", "export", "--calibration", "c", "--format", "x"]).is_err()
        );
        let Command::NavigationCheck(n) =
            parse(&["navigation-check", "--seed", "3", "--plan", "short"]).command
        else {
            panic!("not navigation-check")
        };
        assert_eq!((n.seed, n.plan.as_deref()), (3, Some("short")));
    }

    #[test]
    fn noise_flags_override_the_unit_files_noise_table() {
        let mut unit = UnitFile::paper_unit();
        unit.other.insert(
            "noise".into(),
            toml::Value::Table(
                toml::from_str("accel_white_mg = 2.0\ntable_tilt_deg = 0.01").unwrap(),
            ),
        );
        let Command::Simulate(a) = parse(&["simulate", "--out", "d", "--noise-mg", "0.5"]).command
        else {
            panic!()
        };
        let n = noise_from_args(&a, &unit).unwrap();
        assert_eq!((n.accel_white_mg, n.table_tilt_deg), (0.5, 0.01));
        let Command::Simulate(a) = parse(&["simulate", "--out", "d", "--no-noise"]).command else {
            panic!()
        };
        assert_eq!(noise_from_args(&a, &unit).unwrap(), NoiseModel::none());
    }

    /// simulate (short oblique plan, the paper's unit, 1 mg) → calibrate → every parameter within
    /// 5 reported σ of the truth, the σ of the right size, and the files readable.
    #[test]
    fn simulate_then_calibrate_recovers_the_unit() {
        let dir = tempfile::tempdir().unwrap();
        let session = dir.path().join("session");
        let Command::Simulate(s) = parse(&[
            "simulate",
            "--out",
            session.to_str().unwrap(),
            "--plan",
            "short-oblique",
            "--seed",
            "21",
        ])
        .command
        else {
            panic!()
        };
        simulate(&s, true).unwrap();
        let out = dir.path().join("out");
        let Command::Calibrate(c) = parse(&[
            "calibrate",
            "--input",
            session.to_str().unwrap(),
            "--out-dir",
            out.to_str().unwrap(),
        ])
        .command
        else {
            panic!()
        };
        let o = calibrate(&c, true).unwrap();
        let truth = UnitFile::load(&session.join("truth.toml"))
            .unwrap()
            .to_calibration()
            .unwrap();
        let (est, u) = (&o.calibration, &o.uncertainty);
        for i in 0..3 {
            let db = est.statics.zero_bias_out[i] - truth.statics.zero_bias_out[i];
            assert!(db.abs() < 5.0 * u.zero_bias_1sigma[i], "bias {i}: {db}");
            let dk = est.statics.scale_out_per_g[i] - truth.statics.scale_out_per_g[i];
            assert!(dk.abs() < 5.0 * u.scale_per_g_1sigma[i], "scale {i}: {dk}");
            for j in 0..3 {
                let da = est.statics.installation_angles_deg[i][j]
                    - truth.statics.installation_angles_deg[i][j];
                assert!(
                    da.abs() < 5.0 * u.installation_angles_deg_1sigma[i][j],
                    "θ{i}{j}: {da}"
                );
                let dr = est.lever_arms.r_m[i][j] - truth.lever_arms.r_m[i][j];
                let sr = u.lever_arms_m_1sigma[i][j];
                assert!(u.lever_arms_observable[i][j], "r{i}{j} observable");
                assert!(dr.abs() < 5.0 * sr && sr < 60e-6, "r{i}{j}: {dr} ± {sr}");
            }
        }
        // The files: calibration.toml reads back as a unit file (so `simulate --unit` round-trips),
        // calibration.bin decodes for the (all-zero) unit id of a plan without one.
        let back = UnitFile::load(&out.join("calibration.toml")).unwrap();
        assert!(back.uncertainty.is_some());
        let bin = std::fs::read(out.join("calibration.bin")).unwrap();
        let blob = shared::blob::decode_for_unit(&bin, UnitId::default()).unwrap();
        assert_eq!(blob.calibration, o.calibration);
    }

    #[test]
    fn plan_check_predicts_what_the_oblique_plan_adds() {
        let check = |plan: &str| {
            let Command::Plan(a) = parse(&["plan", "--check", plan]).command else {
                panic!()
            };
            plan_check(&a).unwrap()
        };
        let paper = check("paper");
        let oblique = check("oblique");
        // r1y (across axis x): ~0.3 mm with the paper's plan, ~15 µm or better with the oblique mounts.
        let k = paper.labels.iter().position(|l| l == "r1y").unwrap();
        assert!(paper.sigma[k] > 1e-4 && !paper.lever_arms_observable[0][1]);
        assert!(oblique.sigma[k] < 2e-5 && oblique.lever_arms_observable[0][1]);
        let Command::Plan(a) = parse(&["plan", "--check", "nope.toml"]).command else {
            panic!()
        };
        assert!(plan_check(&a).unwrap_err().to_string().contains("built-in"));
    }

    #[test]
    fn calibrate_without_input_says_what_to_give() {
        let Command::Calibrate(c) = parse(&["calibrate"]).command else {
            panic!()
        };
        let e = calibrate(&c, true).unwrap_err().to_string();
        assert!(e.contains("--input DIR"), "{e}");
    }
}
