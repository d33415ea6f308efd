//! `host apply`: a calibration applied to a recording with the device's own compensation code.

use super::CliError;
use crate::apply::{apply_session, ApplyError};
use crate::output_file::OutputFile;
use crate::unit_file::{UnitFile, UnitFileError};
use clap::{Args, ValueEnum};
use shared::LeverMode;
use std::io::Write;
use std::path::PathBuf;

/// `host apply`.
#[derive(Debug, Args)]
pub struct ApplyArgs {
    /// The calibration (calibration.toml or any unit file).
    #[arg(long, value_name = "FILE")]
    pub calibration: PathBuf,
    /// The session directory (plan.toml + samples.csv).
    #[arg(long, value_name = "SESSION_DIR")]
    pub input: PathBuf,
    /// Where to write the CSV (default: stdout).
    #[arg(long, value_name = "FILE.csv")]
    pub out: Option<PathBuf>,
    /// Replace an existing --out file.
    #[arg(long)]
    pub force: bool,
    /// Which lever-arm terms to apply, as the device's lever mode.
    #[arg(long, value_enum, default_value_t = LeverArg::Full)]
    pub lever: LeverArg,
    /// Apply even when the calibration's and the recording's unit ids differ.
    #[arg(long)]
    pub ignore_unit_id: bool,
}

/// The device's lever-arm modes.
#[derive(Clone, Copy, Debug, PartialEq, Eq, ValueEnum)]
pub enum LeverArg {
    /// Static compensation only (paper eq. 6).
    Off,
    /// Centripetal and cross terms from ω, no ω̇ term.
    Rate,
    /// All terms, ω̇ from the device's estimator (paper eq. 16).
    Full,
}

impl From<LeverArg> for LeverMode {
    fn from(a: LeverArg) -> Self {
        match a {
            LeverArg::Off => LeverMode::Off,
            LeverArg::Rate => LeverMode::RateOnly,
            LeverArg::Full => LeverMode::RateAndAcceleration,
        }
    }
}

/// Runs `host apply`; the CSV goes to `--out` (atomically) or stdout, the summary to stderr.
pub fn run(a: &ApplyArgs, quiet: bool) -> Result<(), CliError> {
    let unit = UnitFile::load(&a.calibration)?;
    let invalid = |m| CliError::Unit(UnitFileError::Invalid(a.calibration.clone(), m));
    let cal = unit.to_calibration().map_err(invalid)?;
    let cal_unit = if a.ignore_unit_id {
        None
    } else {
        unit.unit_id().map_err(invalid)?
    };
    let mode = a.lever.into();
    let summary = match &a.out {
        Some(path) => {
            let mut file = OutputFile::create(path, a.force).map_err(ApplyError::Output)?;
            let s = apply_session(&a.input, &cal, cal_unit, mode, &mut file)?;
            file.commit().map_err(ApplyError::Output)?;
            s
        }
        None => {
            let mut stdout = StdoutCsv {
                inner: std::io::BufWriter::new(std::io::stdout().lock()),
                failed: None,
            };
            let result = apply_session(&a.input, &cal, cal_unit, mode, &mut stdout);
            // A closed or full stdout is named as such, not as a failure of the recording.
            if let Some(e) = stdout.failed.take() {
                return Err(CliError::Stdout(e));
            }
            let s = result?;
            stdout.flush().map_err(CliError::Stdout)?;
            s
        }
    };
    for w in &summary.warnings {
        eprintln!("warning: {w}");
    }
    if !quiet {
        let dest = a
            .out
            .as_ref()
            .map_or("stdout".to_string(), |p| p.display().to_string());
        eprintln!(
            "applied {} to {} rows ({} with non-finite values written as NaN) -> {dest}",
            a.calibration.display(),
            summary.rows,
            summary.non_finite_rows
        );
    }
    Ok(())
}

/// Standard output for the CSV, remembering why a write failed (`| head`, `> /dev/full`), so that the
/// command reports a closed or full stdout rather than an error of the recording.
struct StdoutCsv<W: Write> {
    inner: W,
    failed: Option<std::io::Error>,
}

impl<W: Write> StdoutCsv<W> {
    fn remember<T>(&mut self, r: std::io::Result<T>) -> std::io::Result<T> {
        r.inspect_err(|e| {
            self.failed.get_or_insert_with(|| match e.raw_os_error() {
                Some(code) => std::io::Error::from_raw_os_error(code),
                None => std::io::Error::from(e.kind()),
            });
        })
    }
}

impl<W: Write> Write for StdoutCsv<W> {
    fn write(&mut self, buf: &[u8]) -> std::io::Result<usize> {
        let r = self.inner.write(buf);
        self.remember(r)
    }

    fn flush(&mut self) -> std::io::Result<()> {
        let r = self.inner.flush();
        self.remember(r)
    }
}
