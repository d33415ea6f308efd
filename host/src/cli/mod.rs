//! The command line, one file per subcommand (its argument struct and its `run`), over the domain
//! modules. This is all the crate exports ([`Cli`], whose help the tests read, and [`main`], which
//! `main.rs` calls); everything else is the crate's own, testable here.
//!
//! | subcommand | file | domain code |
//! |---|---|---|
//! | `simulate` | `simulate` | [`estimator::sim`] → [`recording::session::writer`] |
//! | `calibrate --input` | `calibrate` | [`recording::session::reader`] → [`estimator::estimate`] → [`outputs::report::text`], [`estimator::calibration_files`] |
//! | `calibrate --port` | `calibrate` | [`device::procedure`] over `port` |
//! | `plan --check` | `plan` | [`estimator::estimate::predict`] |
//! | `segment`, `simulate-hand` | `segment` | [`recording::session::import`] → [`recording::session::segment`] → [`recording::session::from_recording`], [`estimator::estimate::handheld_gyro`]; [`estimator::sim::handheld`] |
//! | `report` | `report` | [`outputs::report::document`] over [`outputs::report::data`] |
//! | `navigation-check` | `navigation_check` | [`mod@outputs::report::navigation_check`] on [`estimator::sim`] |
//! | `compare` | `compare` | [`outputs::report::compare`] |
//! | `export` | `export` (`export_log`: the ids and slots of `--log`) | [`outputs::export`], [`app::autopilot`] |
//! | `apply` | `apply` | [`outputs::apply`] over [`recording::session::reader`] |
//! | `noise` | `noise` | [`outputs::noise`] |
//! | `batch` | `batch` | [`app::batch`] (rayon) over [`estimator::estimate`] |
//! | `flash`, `read`, `monitor` | `flash`, `read`, `monitor` | [`device`] over `port` |
//! | `bringup` | `bringup` | [`device::bringup`] over `port` |
//!
//! `segment`, `apply` and `noise` read a logger's file with the one set of input options,
//! `log_input`.
//!
//! Every command fails with the one `CliError` (`error`); `output` decides where its output goes
//! (`--json`, `--quiet`). `spelling` holds the flags' names: the crates below name an option by its
//! meaning and are handed `spelling::FLAGS`.

pub(crate) mod apply;
#[cfg(test)]
mod apply_offset_tests;
#[cfg(test)]
mod autopilot_tests;
pub(crate) mod batch;
pub(crate) mod bringup;
pub(crate) mod calibrate;
pub(crate) mod compare;
#[cfg(test)]
mod damaged_log_tests;
pub(crate) mod error;
pub(crate) mod export;
mod export_log;
pub(crate) mod flash;
#[cfg(test)]
mod log_fixture_tests;
pub(crate) mod log_input;
#[cfg(test)]
mod long_log_tests;
pub(crate) mod monitor;
pub(crate) mod navigation_check;
pub(crate) mod noise;
#[cfg(test)]
mod nominal_scale_tests;
pub(crate) mod output;
pub(crate) mod plan;
pub(crate) mod port;
pub(crate) mod read;
#[cfg(test)]
mod reference_fits_tests;
pub(crate) mod report;
pub(crate) mod segment;
#[cfg(test)]
mod segment_tests;
pub(crate) mod simulate;
pub(crate) mod spelling;
#[cfg(test)]
mod tests;
#[cfg(test)]
mod text_temperature_tests;
#[cfg(test)]
mod window_marks_tests;

pub(crate) use error::CliError;

use clap::{Parser, Subcommand};
use estimator::unit_file::UnitFile;
use shared::chain::Chain;
use std::path::Path;

/// Calibrate a strap-down tri-axis accelerometer unit (static + dynamic, with lever arms).
#[derive(Debug, Parser)]
#[command(name = "host", version, about)]
pub struct Cli {
    /// What to do.
    #[command(subcommand)]
    pub(crate) command: Command,
    /// Quiet: no progress bars and no human-readable results (warnings and errors still go to
    /// stderr; --json documents still go to stdout).
    #[arg(long, short, global = true)]
    pub(crate) quiet: bool,
}

/// The subcommands.
#[derive(Debug, Subcommand)]
pub(crate) enum Command {
    /// Simulate a session: a virtual unit on a virtual rate table, written as a recording.
    Simulate(simulate::SimulateArgs),
    /// Estimate the calibration from a recorded session (--input), or live from a device (--port).
    Calibrate(calibrate::CalibrateArgs),
    /// Cut one continuous logger recording (a hand-held session) into a session for
    /// `calibrate --input`: still intervals, a table and a figure, and the gyro from the hand turns.
    Segment(segment::SegmentArgs),
    /// Write a simulated hand-held session as one logger CSV (to try `host segment` without a unit).
    SimulateHand(segment::SimulateHandArgs),
    /// Check a plan: its segments and the predicted 1σ of every parameter (Cramér–Rao bound).
    Plan(plan::PlanArgs),
    /// Write the report of a session calibrated by a calibration: figures (PNG, SVG) and
    /// report.html / report.md with Tables 1–4 and the navigation replay.
    Report(report::ReportArgs),
    /// The paper's navigation check on a simulated session of its unit: position drift without
    /// compensation, with static and with static + dynamic compensation.
    NavigationCheck(navigation_check::NavigationCheckCliArgs),
    /// Two calibrations of one unit side by side, each difference in units of its combined 1σ.
    Compare(compare::CompareArgs),
    /// A calibration in another tool's format: kalibr, fusion-c, c, c-header, json, px4, ardupilot
    /// (or the TOML conversions plain, fusion, all).
    Export(export::ExportArgs),
    /// Apply a calibration to a recording with the device's own compensation code: CSV of the
    /// specific force and corrected rate per row
    /// (segment,t_s,f_x_g,f_y_g,f_z_g,w_x_rad_s,w_y_rad_s,w_z_rad_s), from a session or a logger's file.
    Apply(apply::ApplyArgs),
    /// Noise of a still recording: overlapping Allan deviation per axis, fitted white noise density,
    /// bias instability and random walk; table, figure, and the figures Kalibr needs (noise.json).
    Noise(noise::NoiseArgs),
    /// Calibrate a production lot (a directory of sessions) in parallel: one summary (CSV, JSON) with
    /// each unit's parameters, 1σ, χ² and pass/fail; outlier units of the lot flagged.
    Batch(batch::BatchArgs),
    /// Write a calibration (calibration.bin, or a calibration.toml encoded for the unit) to a device,
    /// reset it and check that it applied it.
    Flash(flash::FlashArgs),
    /// Read the calibration stored on a device, as a unit file (stdout, or --out FILE).
    Read(read::ReadArgs),
    /// Show a device's live compensated output.
    Monitor(monitor::MonitorArgs),
    /// First checks of a freshly flashed board at rest: identity, samples, rate, losses,
    /// temperature, axes, gravity, gyro; each with pass/fail and the likely cause.
    Bringup(bringup::BringupArgs),
}

impl Command {
    /// Whether the command line asked for one JSON document on stdout (`--json`).
    pub(crate) fn json(&self) -> bool {
        match self {
            Command::Calibrate(a) => a.json,
            Command::Batch(a) => a.json,
            Command::Compare(a) => a.json,
            Command::Noise(a) => a.json,
            Command::Plan(a) => a.json,
            Command::Segment(a) => a.json,
            _ => false,
        }
    }
}

/// The document `--json` gets on stdout when a command fails before its own document: the error
/// and the exit status. A command that ran to the end and failed a check has printed its own
/// document (with `passed: false`), and gets no second one (`None`).
pub(crate) fn error_document(e: &CliError) -> Option<String> {
    let code = e.exit_code();
    if code == error::EXIT_CHECK_FAILED {
        return None;
    }
    let kind = if code == error::EXIT_USAGE {
        "usage"
    } else {
        "error"
    };
    Some(output::error_json(&Chain(e).to_string(), kind, code))
}

/// The command-line program: parses the arguments, runs the command and exits with its status.
/// Under `--json` a refusal by the parser or a failed command also prints the error document on
/// stdout (help and version print as usual).
pub fn main() {
    let cli = Cli::try_parse().unwrap_or_else(|e| {
        if let Some(doc) = output::parse_error_document(&e, std::env::args_os()) {
            use std::io::Write;
            let _ = e.print();
            let _ = writeln!(std::io::stdout(), "{doc}");
            std::process::exit(e.exit_code());
        }
        e.exit()
    });
    let json = cli.command.json();
    if let Err(e) = run(cli) {
        eprintln!("error: {}", Chain(&e));
        if let Some(doc) = error_document(&e).filter(|_| json) {
            use std::io::Write;
            // A closed stdout leaves the message above and the exit status.
            let _ = writeln!(std::io::stdout(), "{doc}");
        }
        std::process::exit(e.exit_code());
    }
}

/// Runs a parsed command line, printing to stdout (results) and stderr (warnings, progress).
pub(crate) fn run(cli: Cli) -> Result<(), CliError> {
    match cli.command {
        Command::Simulate(a) => simulate::run(&a, cli.quiet).map(|_| ()),
        Command::Calibrate(a) => calibrate::run(&a, cli.quiet),
        Command::Plan(a) => plan::run(&a, cli.quiet).map(|_| ()),
        Command::Report(a) => report::run(&a, cli.quiet),
        Command::NavigationCheck(a) => navigation_check::run(&a, cli.quiet),
        Command::Compare(a) => compare::run(&a, cli.quiet),
        Command::Export(a) => export::run(&a, cli.quiet),
        Command::Apply(a) => apply::run(&a, cli.quiet),
        Command::Noise(a) => noise::run(&a, cli.quiet),
        Command::Batch(a) => batch::run(&a, cli.quiet),
        Command::Segment(a) => segment::run(&a, cli.quiet),
        Command::SimulateHand(a) => segment::simulate_hand_command(&a).map(|_| ()),
        Command::Flash(a) => flash::run(&a.port, &a.calibration, cli.quiet),
        Command::Read(a) => read::run(&a),
        Command::Monitor(a) => monitor::run(&a, cli.quiet),
        Command::Bringup(a) => bringup::run(&a, cli.quiet),
    }
}

/// The unit file at `path`, or the paper's unit.
fn load_unit(path: Option<&Path>) -> Result<UnitFile, CliError> {
    Ok(match path {
        Some(p) => UnitFile::load(p)?,
        None => UnitFile::paper_unit(),
    })
}
