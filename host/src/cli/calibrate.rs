//! `host calibrate`: from a recorded session (`--input DIR`), or live from a device (`--port`, the
//! procedure of [`device::procedure`]).

use super::output::Output;
use super::port::{connect, PortArgs};
use super::CliError;
use crate::limits;
use app::{self, CalibrateOptions, VerificationSummary};
use clap::Args;
use device::operator::{AutomaticOperator, Operator, TerminalOperator};
use device::procedure::{self, ProcedureOptions};
use device::sim_hand::HandOperator;
use device::view;
use device::AnyTransport;
use estimator::calibration_files::now_unix_s;
use estimator::estimate::{BiasWalk, CalibrationOutcome, EstimateOptions, Method, ReferenceChoice};
use outputs::summary::Limits;
use recording::session::{self, ReadOptions};
use std::path::PathBuf;
use std::time::Instant;

/// `host calibrate`: from a recorded session (`--input`) or live from a device (`--port`).
#[derive(Debug, Args)]
#[command(mut_args(outputs::summary::pass_fail_limits))]
pub(crate) struct CalibrateArgs {
    /// Session directory (plan.toml + samples.csv).
    #[arg(long, value_name = "DIR", conflicts_with = "port")]
    pub input: Option<PathBuf>,
    /// Calibrate a device live: its serial port (or QEMU's pty), `sim` for the built-in simulated
    /// device on its virtual table, or `sim-hand` for it held in a simulated hand (the hand-held
    /// procedure). Records the session, estimates, writes the files, flashes, resets and verifies.
    #[arg(long, value_name = "PORT|sim|sim-hand")]
    pub port: Option<String>,
    /// With a serial --port: its baud rate (default: 115200).
    #[arg(
        long,
        requires = "port",
        value_parser = recording::limits::whole_u32(limits::MIN_BAUD, limits::MAX_BAUD)
    )]
    pub baud: Option<u32>,
    /// With a serial --port: seconds to wait for each answer of the device (default: 5).
    #[arg(
        long,
        requires = "port",
        value_parser = recording::limits::real(limits::MIN_TIMEOUT_S, limits::MAX_TIMEOUT_S)
    )]
    pub timeout_s: Option<f64>,
    /// With --port sim or sim-hand: the simulated unit's parameters (default: the paper's unit).
    #[arg(long, value_name = "FILE", requires = "port")]
    pub sim_unit: Option<PathBuf>,
    /// With --port: plan file or built-in name (default: oblique with a virtual table, hand for
    /// sim-hand, else paper).
    #[arg(long, value_name = "FILE|NAME", requires = "port")]
    pub plan: Option<String>,
    /// With --port: samples per streamed window (default: a 50th of the device's rate).
    #[arg(long, requires = "port", value_parser = recording::limits::whole_u32(1, limits::MAX_WINDOW))]
    pub window: Option<u32>,
    /// With --port: largest compensated error accepted at a verification position, mg (default: 1).
    #[arg(
        long,
        requires = "port",
        value_parser = recording::limits::real(recording::limits::MIN_LIMIT, limits::MAX_TOLERANCE_MG)
    )]
    pub verify_tolerance_mg: Option<f64>,
    /// With --port: verify again, at rest, at this temperature, °C: `--port sim` sets its virtual
    /// chamber there; with a real board the operator brings it there (a hot plate or a chamber) and
    /// its temperature reading is checked to within 2 °C.
    #[arg(
        long,
        value_name = "C",
        requires = "port",
        value_parser = recording::limits::real(VERIFY_TEMP_MIN_C, VERIFY_TEMP_MAX_C)
    )]
    pub verify_temp_c: Option<f64>,
    /// With --port: show the session on a live page (attitude, stillness, coverage, what to do next,
    /// the result), served read-only on 127.0.0.1 at a free port (printed; opened in the browser
    /// where $BROWSER or a display is set) until Enter after the result. A simulated device (`sim`,
    /// `sim-hand`) then runs at a real one's pace, so that the page can be followed.
    #[arg(long, requires = "port")]
    pub view: bool,
    /// Verbose: the fit's full tables (segments, residuals, gyro, observability) before the short
    /// result block; `host report` has them too.
    #[arg(short, long)]
    pub verbose: bool,
    /// Where to write calibration.toml and calibration.bin (default: the session directory).
    #[arg(long = "out", visible_alias = "out-dir", value_name = "OUT")]
    pub out_dir: Option<PathBuf>,
    /// Replace an existing calibration (and, with --port, an existing recording) in the output
    /// directory.
    #[arg(long)]
    pub force: bool,
    /// The estimator: --method, --reference, --single-package.
    #[command(flatten)]
    pub estimator: EstimatorArgs,
    /// Print the result as one JSON document on stdout (parameters, 1σ, χ², checks); the report and
    /// progress go to stderr.
    #[arg(long)]
    pub json: bool,
    /// Pass/fail limits: a failed check exits nonzero (after writing the files).
    #[command(flatten)]
    pub limits: Limits,
}

/// The estimator's flags, shared by `host calibrate` and `host batch`.
#[derive(Clone, Debug, Args)]
pub(crate) struct EstimatorArgs {
    /// Estimator: joint (static and lever arms together, default) or paper (the paper's eq. 24).
    #[arg(long, value_enum, default_value_t = MethodArg::Joint)]
    pub method: MethodArg,
    /// Point the lever arms are given relative to: the table axis (paper) or the sensing points' centroid.
    #[arg(long, value_enum, default_value_t = ReferenceArg::TableAxis)]
    pub reference: ReferenceArg,
    /// The three accelerometers share one package (a MEMS IMU): fit one lever arm, the package's
    /// position, for the three, and report the in-package size effect as not observable
    /// (docs/model.md §4.7). A plan with package = "single" implies it.
    #[arg(long)]
    pub single_package: bool,
    /// The bias random walks: --bias-walk, --bias-walk-estimate, --bias-walk-from, and the gyro's
    /// --gyro-bias-walk.
    #[command(flatten)]
    pub walk: BiasWalkArgs,
}

/// The accelerometers' bias random walk (docs/model.md §11): given, estimated or the unit's own;
/// and the gyro's, given (§11.6); shared by `host calibrate`, `host batch` and `host report` (whose
/// session fit they weigh).
#[derive(Clone, Debug, Default, Args)]
pub(crate) struct BiasWalkArgs {
    /// The accelerometers' bias is a random walk of this strength, mg/√s (the Allan K of
    /// `host noise`, in mg): the segments are weighted with the walk's covariance across the
    /// session (docs/model.md §11). 0 keeps a constant bias. Without it (and without
    /// --bias-walk-from) the walk is estimated from the session, reported with its 1σ, and used
    /// where the session determines it.
    #[arg(
        long,
        value_name = "MG_SQRT_S",
        conflicts_with_all = ["bias_walk_estimate", "bias_walk_from"],
        value_parser = recording::limits::real(0.0, limits::MAX_BIAS_WALK_MG_SQRT_S)
    )]
    pub bias_walk: Option<f64>,
    /// The accelerometers' bias is a random walk whose strength is estimated from the session
    /// (restricted maximum likelihood, reported with its 1σ, used where the session determines
    /// it; docs/model.md §11). The default; the flag states it.
    #[arg(long, conflicts_with = "bias_walk_from")]
    pub bias_walk_estimate: bool,
    // The `[noise]` below is the TOML table's name in the --help text, not a link.
    #[allow(rustdoc::broken_intra_doc_links)]
    /// The accelerometers' bias is a random walk of the unit's own strength, per axis: the Allan K
    /// of `host noise` (its noise.json) or a unit file's [noise] accel_bias_walk_mg_sqrt_s
    /// (docs/model.md §11.3). Refused when the file holds none. The gyro's walk is taken from the
    /// same file where it holds one (its gyro axes' K, or gyro_bias_walk_deg_s_sqrt_s), unless
    /// --gyro-bias-walk is given.
    #[arg(long, value_name = "noise.json|UNIT_FILE")]
    pub bias_walk_from: Option<PathBuf>,
    /// The gyro's bias is a random walk of this strength, °/s/√s (the Allan K of `host noise`'s
    /// gyro axes, in °/s): the gyro model's mean rates are weighted with the walk's covariance
    /// across the session (docs/model.md §11.6). 0 keeps a constant gyro bias. Without it (and
    /// without a gyro figure in --bias-walk-from's file) the gyro's walk is estimated from a
    /// session that spins, reported with its 1σ, and used where the session determines it.
    #[arg(
        long,
        value_name = "DEG_S_SQRT_S",
        value_parser = recording::limits::real(0.0, limits::MAX_GYRO_BIAS_WALK_DEG_S_SQRT_S)
    )]
    pub gyro_bias_walk: Option<f64>,
}

impl BiasWalkArgs {
    /// Whether any walk is asked for.
    pub(crate) fn any(&self) -> bool {
        self.bias_walk.is_some_and(|w| w > 0.0)
            || self.bias_walk_estimate
            || self.bias_walk_from.is_some()
    }

    /// The gyro's bias walk given on the command line, °/s/√s (0: a constant gyro bias).
    pub(crate) fn gyro_walk(&self) -> f64 {
        self.gyro_bias_walk.unwrap_or(0.0)
    }

    /// The walks these flags ask for: the accelerometers', the gyro's (°/s/√s, 0 for a constant
    /// gyro bias), and whether the gyro's is to be estimated (none given). Without a flag both are
    /// estimated from the session (docs/model.md §11.3, §11.6). `--bias-walk-from`'s file is read
    /// here; `--gyro-bias-walk` takes the place of its gyro figure.
    pub(crate) fn walks(&self) -> Result<(BiasWalk, f64, bool), CliError> {
        if let Some(path) = &self.bias_walk_from {
            let from_file = app::walk_source::walk_from_file(path, super::spelling::FLAGS)?;
            let gyro = self.gyro_bias_walk.or(from_file.gyro_deg_s_sqrt_s);
            let accel = BiasWalk::FromUnit(from_file.accel);
            return Ok((accel, gyro.unwrap_or(0.0), gyro.is_none()));
        }
        let accel = match (self.bias_walk, self.bias_walk_estimate) {
            (_, true) | (None, false) => BiasWalk::Estimate,
            (Some(mg), false) if mg > 0.0 => BiasWalk::Given(mg),
            _ => BiasWalk::Off,
        };
        Ok((accel, self.gyro_walk(), self.gyro_bias_walk.is_none()))
    }

    /// Sets the walks these flags ask for on `options` ([`Self::walks`]); the paper's method,
    /// which weighs no walk, keeps a constant bias unless a walk was asked for (then
    /// [`EstimatorArgs::refuse`] has refused it).
    pub(crate) fn set(&self, options: &mut EstimateOptions) -> Result<(), CliError> {
        let (accel, gyro, estimate_gyro) = self.walks()?;
        let joint = options.method == Method::Joint;
        options.bias_walk = if joint || self.any() {
            accel
        } else {
            BiasWalk::Off
        };
        options.gyro_bias_walk_deg_s_sqrt_s = gyro;
        options.gyro_bias_walk_estimate = estimate_gyro && joint;
        // A gyro walk not asked for by itself (from the unit's noise figures, or none): where the
        // session has no gyro model it is left out, not refused.
        options.gyro_bias_walk_from_unit = self.gyro_bias_walk.is_none();
        Ok(())
    }
}

impl EstimatorArgs {
    /// Refuses flags that cannot apply together, before any work: the bias walk weighs the joint
    /// fit's segments (docs/model.md §11), and `--method paper` is the paper's eq. 24 as published.
    pub(crate) fn refuse(&self) -> Result<(), CliError> {
        if self.walk.any() && self.method == MethodArg::Paper {
            return Err(CliError::Usage(
                "--bias-walk, --bias-walk-estimate and --bias-walk-from weigh the joint fit's \
                 segments with the walk (docs/model.md §11); --method paper is the paper's eq. 24 \
                 as published: leave one out"
                    .into(),
            ));
        }
        if self.walk.gyro_walk() > 0.0 && self.method == MethodArg::Paper {
            return Err(CliError::Usage(
                "--gyro-bias-walk weighs the gyro model's mean rates with the walk (docs/model.md \
                 §11.6); --method paper estimates no gyro model: leave one out"
                    .into(),
            ));
        }
        Ok(())
    }

    /// The estimator options these flags ask for; `--bias-walk-from`'s file is read here.
    pub fn options(&self) -> Result<EstimateOptions, CliError> {
        let mut options = EstimateOptions {
            method: match self.method {
                MethodArg::Joint => Method::Joint,
                MethodArg::Paper => Method::Paper,
            },
            reference: match self.reference {
                ReferenceArg::TableAxis => ReferenceChoice::TableAxis,
                ReferenceArg::Centroid => ReferenceChoice::Centroid,
            },
            single_package: self.single_package,
            ..EstimateOptions::new(super::spelling::FLAGS)
        };
        self.walk.set(&mut options)?;
        Ok(options)
    }
}

/// `--method`.
#[derive(Clone, Copy, Debug, PartialEq, Eq, clap::ValueEnum)]
pub(crate) enum MethodArg {
    /// Static part and lever arms in one weighted least-squares fit.
    Joint,
    /// The paper's two steps: static fit, then eq. 24 per lever-arm component.
    Paper,
}

/// `--reference`.
#[derive(Clone, Copy, Debug, PartialEq, Eq, clap::ValueEnum)]
pub(crate) enum ReferenceArg {
    /// The point of the body on the table's spin axis (the paper's assumption).
    TableAxis,
    /// The centroid of the three sensing points.
    Centroid,
}

/// Runs `host calibrate`: live with `--port`, else from `--input`.
pub(crate) fn run(a: &CalibrateArgs, quiet: bool) -> Result<(), CliError> {
    a.estimator.refuse()?;
    // `--bias-walk-from`'s file, read before a device is opened or a session read.
    a.estimator.options()?;
    if a.verbose && quiet {
        return Err(CliError::Usage(
            "--verbose does not apply with --quiet, which prints no tables: leave one out".into(),
        ));
    }
    // A recording read from a directory has no live session: --view would be silently ignored.
    if a.view && a.port.is_none() {
        return Err(CliError::Usage(
            "--view shows a device session as it runs (--port); a recording read with --input \
             has none to show: leave --view out"
                .into(),
        ));
    }
    if a.port.is_some() {
        calibrate_live(a, quiet)
    } else {
        calibrate(a, quiet).map(|_| ())
    }
}

/// What `host calibrate`'s flags ask of the calibration: the estimator and the limits.
pub(crate) fn calibrate_options(a: &CalibrateArgs) -> Result<CalibrateOptions, CliError> {
    Ok(CalibrateOptions {
        estimate: a.estimator.options()?,
        limits: a.limits,
    })
}

/// `host calibrate --input DIR`: read (with a progress bar), estimate, print the report, write
/// `OUT/calibration.toml` and `OUT/calibration.bin`.
pub(crate) fn calibrate(a: &CalibrateArgs, quiet: bool) -> Result<CalibrationOutcome, CliError> {
    let input = a.input.as_deref().ok_or_else(|| {
        CliError::Usage(
            "calibrate needs --input DIR (a recorded session: plan.toml + samples.csv) or \
             --port PORT (a device; `--port sim` for the built-in simulated one)"
                .into(),
        )
    })?;
    refuse_device_options(a)?;
    let out = Output {
        json: a.json,
        quiet,
    };
    let out_dir = a.out_dir.as_deref().unwrap_or(input);
    // Refused before the (possibly long) read, not after it.
    estimator::calibration_files::refuse_overwrite(out_dir, a.force)?;
    let started = Instant::now();
    let (session, mut calibrated) =
        app::calibrate_session_dir(input, &calibrate_options(a)?, &ReadOptions { quiet })?;
    let read_s = started.elapsed().as_secs_f64();
    for w in &session.report.warnings {
        out.warn(w);
    }
    if calibrated.unit_id.is_none() {
        out.warn(
            "plan.toml has no unit_id: calibration.bin is bound to the all-zero unit id; \
             add unit_id = \"<24 hex digits>\" to plan.toml to bind it to the unit",
        );
    }
    let unit_id = calibrated.bound_unit_id();
    // The files first: a closed or full stdout (`| head`, `> /dev/full`) must not lose the result.
    // A unit that fails its checks keeps its files, under names that say so.
    let written = app::write_result(out_dir, &mut calibrated, now_unix_s(), a.force)?;
    let written = app::settle_files(&mut calibrated, written, a.force)?;
    out.line(format_args!(
        "read {} rows ({:.1} MB) of {} segments from {} in {:.2} s ({:.2} M rows/s)",
        session.report.rows,
        session.report.bytes as f64 / 1e6,
        session.stats.len(),
        input.display(),
        read_s,
        session.report.rows as f64 / read_s.max(1e-9) / 1e6
    ))?;
    if calibrated.gyro_from_hand_turns {
        out.line(format_args!(
            "gyro: from the hand turns ({})",
            input.join(super::segment::GYRO_FILE).display()
        ))?;
    }
    out.line("")?;
    if a.verbose {
        out.human(outputs::report::render_session(
            &calibrated.outcome,
            &session.plan,
            &session.stats,
        ))?;
    } else {
        // The full report lists them too; without it they are still named, never left silent.
        out.human(outputs::report::render_excluded(
            &calibrated.outcome.excluded,
        ))?;
    }
    out.line(format_args!(
        "wrote {} and {} ({} bytes, unit {unit_id})",
        written.toml_path.display(),
        written.bin_path.display(),
        written.blob.len()
    ))?;
    out.human(outputs::report::summary_block::render_summary_block(
        &calibrated.document.summary,
    ))?;
    out.human(outputs::report::summary_block::next_line(
        &written.toml_path,
    ))?;
    out.document(&calibrated.document)?;
    if !calibrated.document.summary.passed {
        return Err(CliError::ChecksFailed(
            calibrated.document.summary.failures(),
        ));
    }
    Ok(calibrated.outcome)
}

/// Refuses, for a recorded session, the options that act only on a device (`--port`): it has no
/// device to talk to, record with or verify.
fn refuse_device_options(a: &CalibrateArgs) -> Result<(), CliError> {
    if a.plan.is_some() || a.window.is_some() || a.sim_unit.is_some() {
        return Err(CliError::Usage(
            "--plan, --window and --sim-unit are for --port; a recorded session is read with its own \
             plan.toml (edit that file to change the plan)"
                .into(),
        ));
    }
    let device_given: Vec<&str> = [
        ("--baud", a.baud.is_some()),
        ("--timeout-s", a.timeout_s.is_some()),
        ("--verify-tolerance-mg", a.verify_tolerance_mg.is_some()),
    ]
    .into_iter()
    .filter_map(|(flag, given)| given.then_some(flag))
    .collect();
    if !device_given.is_empty() {
        return Err(CliError::Usage(format!(
            "{} {} for --port: a recorded session has no device to talk to or verify; leave {} out",
            device_given.join(", "),
            if device_given.len() == 1 { "is" } else { "are" },
            if device_given.len() == 1 {
                "it"
            } else {
                "them"
            },
        )));
    }
    if a.verify_temp_c.is_some() {
        return Err(CliError::Usage(
            "--verify-temp-c verifies the calibration stored on a device (--port); a recorded session \
             has no device to verify: give --port, or leave --verify-temp-c out"
                .into(),
        ));
    }
    Ok(())
}

/// Checks the live run's `--window` and returns its verification tolerance, mg, before any device
/// is touched.
fn live_bounds(a: &CalibrateArgs) -> Result<f64, CliError> {
    if let Some(w) = a.window {
        recording::limits::count_in("--window", w, crate::limits::MAX_WINDOW)?;
    }
    let verify_tolerance_mg = a
        .verify_tolerance_mg
        .unwrap_or(ProcedureOptions::DEFAULT_VERIFY_TOLERANCE_MG);
    recording::limits::positive_at_most(
        "--verify-tolerance-mg",
        verify_tolerance_mg,
        crate::limits::MAX_TOLERANCE_MG,
    )?;
    Ok(verify_tolerance_mg)
}

/// `host calibrate --port PORT`: the live procedure (`device::procedure`) against a device;
/// runs the whole procedure and ends with a pass/fail line.
pub(crate) fn calibrate_live(a: &CalibrateArgs, quiet: bool) -> Result<(), CliError> {
    let port = port_args(a);
    let verify_tolerance_mg = live_bounds(a)?;
    let mut client = connect(&port)?;
    let viewed = start_view(a.view, &mut client)?;
    let identity = client.identify()?;
    let plan = match &a.plan {
        Some(spec) => session::builtin::load_plan(spec),
        None => procedure::default_plan(&identity),
    }?;
    refuse_verify_temp_in_hand(a, &identity, &plan)?;
    let out_dir = procedure::default_out_dir(a.out_dir.as_deref(), &identity);
    let mut opts = ProcedureOptions::new(plan, out_dir, super::spelling::FLAGS);
    opts.window_samples = a.window;
    opts.calibrate = calibrate_options(a)?;
    opts.verify_tolerance_mg = verify_tolerance_mg;
    opts.verify_temp_c = a.verify_temp_c;
    opts.force = a.force;
    opts.quiet = quiet;
    let mut auto = AutomaticOperator {
        verbose: !quiet,
        warnings: Vec::new(),
    };
    let mut person = TerminalOperator;
    let hand_cue = match client.transport_mut() {
        AnyTransport::Sim(dev) => dev.hand_cue(),
        AnyTransport::Serial(_) => None,
    };
    let mut hand;
    let op: &mut dyn Operator = if procedure::has_virtual_table(&identity) {
        &mut auto
    } else if let Some(cue) = hand_cue {
        hand = HandOperator { inner: auto, cue };
        &mut hand
    } else {
        &mut person
    };
    let mut result = run_watched(&mut client, &opts, op, viewed.as_ref())?;
    let out = Output {
        json: a.json,
        quiet,
    };
    for w in &result.warnings {
        out.warn(w);
    }
    let worst = result
        .verification
        .iter()
        .map(|v| v.error_mg)
        .fold(0.0, f64::max);
    // The checks alone, before the verification joins them in `passed`.
    let failed_checks = result.calibrated.document.summary.failures();
    result
        .calibrated
        .document
        .set_verification(VerificationSummary {
            worst_error_mg: worst,
            tolerance_mg: opts.verify_tolerance_mg,
            passed: result.passed,
        });
    // The results, on stdout like `calibrate --input`'s; the operator's steps went to stderr.
    if a.verbose {
        out.human(&result.report)?;
    } else {
        out.human(outputs::report::render_excluded(
            &result.calibrated.outcome.excluded,
        ))?;
    }
    let written = app::settle_files(&mut result.calibrated, result.written, a.force)?;
    let shown = (
        &written,
        &result.verification[..],
        result.recording_dir.as_path(),
    );
    present_live_result(&out, shown, &result.calibrated.document, viewed.as_ref())?;
    if !result.passed {
        return Err(CliError::VerificationFailed);
    }
    if !failed_checks.is_empty() {
        return Err(CliError::ChecksFailed(failed_checks));
    }
    out.line(format_args!(
        "PASS: unit {} calibrated, stored and verified at {} positions (worst error {worst:.3} mg ≤ {} mg); \
         results in {}",
        result.identity.unit_id,
        result.verification.len(),
        opts.verify_tolerance_mg,
        opts.out_dir.display()
    ))?;
    Ok(())
}

/// A live run's results: the files and the verification, the result block, the next command, the
/// JSON document; on the live page too, which then stays up until Enter.
fn present_live_result(
    out: &Output,
    (written, verification, recording_dir): (
        &estimator::calibration_files::WrittenCalibration,
        &[procedure::VerificationPoint],
        &std::path::Path,
    ),
    document: &app::CalibrationDocument,
    viewed: Option<&view::Viewed>,
) -> Result<(), CliError> {
    print_written_and_verified(out, written, verification)?;
    out.human(outputs::report::summary_block::render_summary_block(
        &document.summary,
    ))?;
    out.human(outputs::report::summary_block::next_line(
        &written.toml_path,
    ))?;
    if let Some(v) = viewed {
        v.live
            .finish(document, next_commands(written, recording_dir));
    }
    out.document(document)?;
    if let Some(v) = viewed {
        v.linger();
    }
    Ok(())
}

/// The device `--port` and its link options name.
fn port_args(a: &CalibrateArgs) -> PortArgs {
    PortArgs {
        port: a.port.clone().unwrap_or_default(),
        baud: a.baud,
        timeout_s: a.timeout_s,
        sim_unit: a.sim_unit.clone(),
    }
}

/// `--view`: the live page, served before the device is identified, fed by the client's windows;
/// a watched simulated device runs at a real one's pace, so that the page can be followed.
fn start_view(
    wanted: bool,
    client: &mut device::DeviceClient<AnyTransport>,
) -> Result<Option<view::Viewed>, CliError> {
    if !wanted {
        return Ok(None);
    }
    let v = view::Viewed::start()
        .map_err(|e| CliError::Io(PathBuf::from("http://127.0.0.1"), std::io::Error::other(e)))?;
    client.set_view(v.live.clone());
    if let AnyTransport::Sim(dev) = client.transport_mut() {
        dev.pace_real_time();
    }
    Ok(Some(v))
}

/// The procedure, its every line also on the live page when there is one; a failure is shown
/// there (until Enter) before it is reported.
fn run_watched(
    client: &mut device::DeviceClient<AnyTransport>,
    opts: &ProcedureOptions,
    op: &mut dyn Operator,
    viewed: Option<&view::Viewed>,
) -> Result<procedure::ProcedureOutcome, CliError> {
    let Some(v) = viewed else {
        return Ok(procedure::run(client, opts, op)?);
    };
    let mut shown = view::ViewOperator {
        inner: op,
        live: v.live.clone(),
    };
    procedure::run(client, opts, &mut shown).map_err(|e| {
        v.live.failed(&shared::chain::Chain(&e).to_string());
        v.linger();
        e.into()
    })
}

/// What to run next on a live result, as the page lists it: the report of the recording and an
/// export of the calibration.
fn next_commands(
    written: &estimator::calibration_files::WrittenCalibration,
    recording_dir: &std::path::Path,
) -> Vec<String> {
    vec![
        format!(
            "host report --input {} --calibration {}",
            recording_dir.display(),
            written.toml_path.display()
        ),
        format!(
            "host export --calibration {} --format json",
            written.toml_path.display()
        ),
    ]
}

/// `--verify-temp-c` with the hand-held procedure (a device without a virtual table, a hand-held
/// plan), which verifies |f| = 1 g in the hand's positions at the room's temperature: refused, not
/// silently skipped.
fn refuse_verify_temp_in_hand(
    a: &CalibrateArgs,
    identity: &shared::wire::Identity,
    plan: &session::Plan,
) -> Result<(), CliError> {
    if a.verify_temp_c.is_some()
        && !procedure::has_virtual_table(identity)
        && device::handheld::is_hand_held(plan)
    {
        return Err(CliError::Usage(
            "--verify-temp-c verifies at rest on a table position at a second temperature; the \
             hand-held procedure verifies |f| = 1 g in the positions the hand holds, at the room's \
             temperature: leave --verify-temp-c out, or calibrate on a table plan"
                .into(),
        ));
    }
    Ok(())
}

/// The range of `--verify-temp-c`, °C: what an industrial part and a hot plate reach.
const VERIFY_TEMP_MIN_C: f64 = -55.0;
/// See [`VERIFY_TEMP_MIN_C`].
const VERIFY_TEMP_MAX_C: f64 = 125.0;

/// The files a live calibration wrote (under their final names) and each verification position.
fn print_written_and_verified(
    out: &Output,
    written: &estimator::calibration_files::WrittenCalibration,
    verification: &[procedure::VerificationPoint],
) -> Result<(), CliError> {
    out.line(format_args!(
        "wrote {} and {}",
        written.toml_path.display(),
        written.bin_path.display()
    ))?;
    for v in verification {
        out.line(format_args!(
            "verify {:<36} {:>9}  error {:7.4} mg  {}",
            v.label,
            v.temp_c
                .map_or("— °C".to_string(), |t| format!("{t:.1} °C")),
            v.error_mg,
            if v.pass { "ok" } else { "FAIL" }
        ))?;
    }
    Ok(())
}
