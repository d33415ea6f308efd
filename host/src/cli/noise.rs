//! `host noise`: Allan deviation and noise terms of a still recording.

use super::CliError;
use clap::Args;
use estimator::unit_file::{UnitFile, UnitFileError};
use outputs::calibration_guard::Meeting;
use outputs::export::convert;
use outputs::noise::{analyse, analyse_log, is_samples_csv, NoiseError};
use outputs::report::plot::{render, Formats};
use recording::output_file::write_atomic;
use std::path::PathBuf;

/// `host noise`.
#[derive(Debug, Args)]
pub(crate) struct NoiseArgs {
    /// A session directory (its longest static segment is used), a samples.csv, or a logger's file
    /// (any format `host segment` reads, with the same options; its longest still interval).
    #[arg(long, value_name = "SESSION_DIR|samples.csv|FILE")]
    pub input: PathBuf,
    /// How to read a logger's file.
    #[command(flatten)]
    pub log: super::log_input::LogInputArgs,
    /// A calibration, to analyse the accelerometer in m/s² (needed for Kalibr's accelerometer figures).
    #[arg(long, value_name = "FILE")]
    pub calibration: Option<PathBuf>,
    /// Directory for noise.json, allan.csv and the figure allan.svg/.png.
    #[arg(long, value_name = "DIR")]
    pub out: Option<PathBuf>,
    /// Replace existing files in --out.
    #[arg(long)]
    pub force: bool,
    /// Print the result as one JSON document on stdout (the table goes to stderr).
    #[arg(long)]
    pub json: bool,
}

/// Runs `host noise`.
pub(crate) fn run(a: &NoiseArgs, quiet: bool) -> Result<(), CliError> {
    if a.log.temp_column.is_some() {
        return Err(CliError::Usage(
            "--temp-column: the noise analysis does not use the temperature (it measures the \
             still stretches' noise); leave it out"
                .into(),
        ));
    }
    let cal = match &a.calibration {
        Some(p) => {
            let unit = UnitFile::load(p)?;
            let cal = unit
                .to_calibration()
                .map_err(|m| CliError::Unit(UnitFileError::Invalid(p.clone(), m)))?;
            let id = unit
                .unit_id()
                .map_err(|m| CliError::Unit(UnitFileError::Invalid(p.clone(), m)))?;
            let plan_path = a.input.join(recording::session::PLAN_FILE);
            let plan = if a.input.is_dir() && plan_path.exists() {
                Some(recording::session::Plan::load(&plan_path)?)
            } else {
                None
            };
            // A logger's file (or a bare samples.csv) is met once read: its output unit then.
            let other = match &plan {
                Some(plan) => outputs::apply::recording(plan, None),
                None => outputs::calibration_guard::Other {
                    name: "the recording",
                    unit_id: None,
                    output_unit: None,
                    frame: None,
                    temperatures: outputs::calibration_guard::Temperatures::None,
                },
            };
            let mine = outputs::apply::mine(&cal, id);
            outputs::calibration_guard::meet(Meeting::Noise, &mine, &other)
                .map_err(|e| CliError::Noise(e.into()))?;
            let plain = convert(&cal).map_err(|e| CliError::Export(e.into()))?.plain;
            Some((plain, cal.statics.output_unit))
        }
        None => None,
    };
    let plain = cal.as_ref().map(|c| &c.0);
    let report = if a.input.is_dir() || is_samples_csv(&a.input) {
        a.log.refuse_for_session(&a.input)?;
        analyse(&a.input, plain, super::spelling::FLAGS, quiet)
    } else {
        let with_unit = cal.as_ref().map(|(p, u)| (p, *u));
        analyse_log(&a.input, &a.log.source(&a.input)?, with_unit, quiet)
    }
    .map_err(CliError::Noise)?;
    let out = super::output::Output {
        json: a.json,
        quiet,
    };
    for w in &report.warnings {
        out.warn(w);
    }
    let json = serde_json::to_string_pretty(&report).map_err(|source| CliError::Json {
        what: "the noise report",
        source,
    })?;
    if let Some(dir) = &a.out {
        std::fs::create_dir_all(dir).map_err(|e| {
            CliError::Written(recording::output_file::OutputFileError::Io(dir.clone(), e))
        })?;
        write_atomic(&dir.join("noise.json"), json.as_bytes(), a.force)
            .map_err(CliError::Written)?;
        write_atomic(&dir.join("allan.csv"), report.csv().as_bytes(), a.force)
            .map_err(CliError::Written)?;
        let fig = render(&report.figure(), dir, Formats::default())
            .map_err(|e| CliError::Noise(NoiseError::Figure(e)))?;
        for w in &fig.warnings {
            out.warn(w);
        }
    }
    out.human(report.render())?;
    if let Some(dir) = &a.out {
        out.line(format_args!(
            "wrote noise.json, allan.csv and the figure into {}",
            dir.display()
        ))?;
    }
    if a.json {
        crate::outln!("{json}")?;
    }
    Ok(())
}
