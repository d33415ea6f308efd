//! `host apply`: a calibration applied to a recording with the device's own compensation code.

use super::CliError;
use clap::{Args, ValueEnum};
use estimator::unit_file::{UnitFile, UnitFileError};
use outputs::apply::{apply_log, apply_session, log_offset, ApplyError, ApplySummary, UnitBinding};
use recording::output_file::OutputFile;
use recording::session::logs::LogSource;
use recording::session::{PLAN_FILE, SAMPLES_FILE};
use shared::{LeverMode, OutputUnit};
use std::io::Write;
use std::path::{Path, PathBuf};

/// `host apply`.
#[derive(Debug, Args)]
pub(crate) struct ApplyArgs {
    /// The calibration (calibration.toml or any unit file).
    #[arg(long, value_name = "FILE")]
    pub calibration: PathBuf,
    /// The session directory (plan.toml + samples.csv), or a logger's file (any format `host
    /// segment` reads, with the same options).
    #[arg(long, value_name = "SESSION_DIR|FILE")]
    pub input: PathBuf,
    /// How to read a logger's file (not for a session directory).
    #[command(flatten)]
    pub log: super::log_input::LogInputArgs,
    /// Where to write the CSV (default: stdout).
    #[arg(long, value_name = "FILE.csv")]
    pub out: Option<PathBuf>,
    /// Replace an existing --out file.
    #[arg(long)]
    pub force: bool,
    /// Which lever-arm terms to apply, as the device's lever mode (default: full). With a
    /// calibration whose lever arms are all zero every mode is the static compensation (a note
    /// says so).
    #[arg(long, value_enum)]
    pub lever: Option<LeverArg>,
    /// Apply even when the calibration's and the recording's unit ids differ (where they do not,
    /// or there are none, a note says so).
    #[arg(long)]
    pub ignore_unit_id: bool,
    /// The unit's temperature, °C, for a calibration with a temperature model applied to a recording
    /// without a temp_c column (refused without it).
    #[arg(
        long,
        value_name = "C",
        allow_negative_numbers = true,
        value_parser = recording::limits::real(-100.0, 200.0)
    )]
    pub temperature_c: Option<f64>,
}

/// The device's lever-arm modes.
#[derive(Clone, Copy, Debug, PartialEq, Eq, ValueEnum)]
pub(crate) enum LeverArg {
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
pub(crate) fn run(a: &ApplyArgs, quiet: bool) -> Result<(), CliError> {
    let unit = UnitFile::load(&a.calibration)?;
    let invalid = |m| CliError::Unit(UnitFileError::Invalid(a.calibration.clone(), m));
    let cal = unit.to_calibration().map_err(invalid)?;
    let cal_unit = unit.unit_id().map_err(invalid)?;
    let unit_ids = if a.ignore_unit_id {
        UnitBinding::Ignored(cal_unit)
    } else {
        UnitBinding::Bound(cal_unit)
    };
    let out = super::output::Output { json: false, quiet };
    options_for_calibration(a, &cal, &out)?;
    let mode = a.lever.unwrap_or(LeverArg::Full).into();
    let source = if a.input.is_dir() {
        a.log.refuse_for_session(&a.input)?;
        None
    } else {
        if a.ignore_unit_id {
            out.note(format!(
                "note: --ignore-unit-id: {} is a logger's file, which carries no unit id, so no id \
                 would have been refused",
                a.input.display()
            ));
        }
        let mut source = a.log.source(&a.input)?;
        read_with_calibrations_offset(&mut source, &unit, a, &out)?;
        Some(source)
    };
    let apply = |w: &mut dyn Write| {
        // Reading, compensating and writing run row by row together: one step.
        let _step = recording::ui::step(
            format!("applying the calibration to {}", a.input.display()),
            quiet,
        );
        match &source {
            None => apply_session(&a.input, &cal, unit_ids, mode, a.temperature_c, w),
            Some(s) => apply_log(&a.input, s, &cal, mode, a.temperature_c, w),
        }
        // An option that would be ignored is a usage error, found only once the input is read
        // (`CliError::exit_code`).
        .map_err(CliError::from)
    };
    let summary: ApplySummary = match &a.out {
        Some(path) => {
            refuse_own_input(path, &a.input)?;
            let mut file = OutputFile::create(path, a.force).map_err(ApplyError::Output)?;
            let s = apply(&mut file)?;
            file.commit().map_err(ApplyError::Output)?;
            s
        }
        None => {
            let mut stdout = StdoutCsv {
                inner: std::io::BufWriter::new(std::io::stdout().lock()),
                failed: None,
            };
            let result = apply(&mut stdout);
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
        out.warn(w);
    }
    for n in &summary.notes {
        out.note(n);
    }
    let dest = a
        .out
        .as_ref()
        .map_or("stdout".to_string(), |p| p.display().to_string());
    let line = format!(
        "applied {} to {} rows ({} with non-finite values written as NaN) -> {dest}",
        a.calibration.display(),
        summary.rows,
        summary.non_finite_rows
    );
    // With the CSV on stdout the summary goes beside it, to stderr; with --out it is the result.
    match &a.out {
        Some(_) => out.line(line)?,
        None => out.note(line),
    }
    Ok(())
}

/// The options that meet the calibration: a lever mode it already satisfies (no lever arms: every
/// mode is the static compensation) is honoured with a note; a temperature for a calibration
/// without a temperature model would change nothing and is refused.
fn options_for_calibration(
    a: &ApplyArgs,
    cal: &shared::Calibration,
    out: &super::output::Output,
) -> Result<(), CliError> {
    if let Some(lever) = a.lever {
        if cal.lever_arms.r_m.iter().flatten().all(|r| *r == 0.0) {
            out.note(format!(
                "note: the lever arms of {} are all zero, so --lever {} gives the static \
                 compensation, as every lever mode does",
                a.calibration.display(),
                lever
                    .to_possible_value()
                    .map_or_else(String::new, |v| v.get_name().to_owned())
            ));
        }
    }
    if a.temperature_c.is_some() && cal.temperature.is_none() {
        return Err(CliError::Usage(format!(
            "--temperature-c does not apply: {} has no temperature model, so no temperature \
             changes its result; leave it out",
            a.calibration.display()
        )));
    }
    if a.log.temp_column.is_some() && cal.temperature.is_none() {
        return Err(CliError::Usage(format!(
            "--temp-column does not apply: {} has no temperature model, so the log's \
             temperatures change nothing in its result; leave it out",
            a.calibration.display()
        )));
    }
    Ok(())
}

/// A raw log in counts is read with the counts of zero force the calibration was made with
/// (`outputs::apply::log_offset`): `--acc-offset` must be that one, and may be left out.
fn read_with_calibrations_offset(
    source: &mut LogSource,
    unit: &UnitFile,
    a: &ApplyArgs,
    out: &super::output::Output,
) -> Result<(), CliError> {
    let Some(text) = source
        .text
        .as_mut()
        .filter(|t| t.acc_unit == OutputUnit::Lsb)
    else {
        return Ok(());
    };
    let given = a.log.acc_offset.is_some().then_some(text.acc_offset);
    let name = a.calibration.display().to_string();
    let offset = log_offset(&name, unit.statics.raw_offset_lsb, given)?;
    text.acc_offset = offset.read_with;
    if let Some(note) = offset.note {
        out.note(note);
    }
    Ok(())
}

/// `--out` must not name a file of the recording it reads (`--force` would replace the input while
/// it is being read).
fn refuse_own_input(out: &Path, input: &Path) -> Result<(), CliError> {
    let canonical = |p: &Path| std::fs::canonicalize(p).unwrap_or_else(|_| p.to_path_buf());
    if input.is_file() && canonical(out) == canonical(input) {
        return Err(CliError::Usage(format!(
            "--out {} is the logger's file it reads: write the result elsewhere",
            out.display()
        )));
    }
    let dir = std::fs::canonicalize(input).unwrap_or_else(|_| input.to_path_buf());
    let parent = out
        .parent()
        .filter(|p| !p.as_os_str().is_empty())
        .unwrap_or(Path::new("."));
    let out_dir = std::fs::canonicalize(parent).unwrap_or_else(|_| parent.to_path_buf());
    let name = out.file_name().and_then(|n| n.to_str()).unwrap_or("");
    if out_dir == dir && [SAMPLES_FILE, PLAN_FILE].contains(&name) {
        return Err(CliError::Usage(format!(
            "--out {} is the recording's own {name}: write the result elsewhere",
            out.display()
        )));
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
