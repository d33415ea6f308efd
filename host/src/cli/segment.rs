//! `host segment`: one continuous logger recording (a hand-held session) → a session directory that
//! `host calibrate --input` reads, a table and a figure of what was found, and the gyro's `G` and
//! bias from the hand turns (`gyro.toml`).

use super::output::Output;
use super::CliError;
use app::handheld::table_turn::FoundTableTurn;
use app::handheld::{find, SegmentChoices, SegmentedSession};
use app::simulate_hand::{HandSimulation, HandWriteError};
use clap::Args;
use estimator::estimate::handheld_gyro::{HandGyroError, HandGyroFit};
use outputs::report::plot::{self, Formats};
use recording::limits::SIMULATED_HAND_RATE_HZ;
use recording::output_file::OutputDir;
use recording::session::coverage::Coverage;
use recording::session::from_recording::normal_gravity_m_s2;
use recording::session::import::MAX_ROWS;
use recording::session::import::{six_digits, Recording};
use recording::session::logs::{read_log_keeping, DEFAULT_MAX_SAMPLES};
use recording::session::note::Note;
use recording::session::segment::{PositionSet, SegmentOptions, Segmentation};
use recording::session::Plan;
use shared::chain::Chain;
use shared::linalg;
use std::fmt::Write as _;
use std::path::PathBuf;

pub(crate) use app::handheld::gyro::GYRO_FILE;

mod present;
use present::{document, figure, Written};

/// `host segment`.
#[derive(Debug, Args)]
pub(crate) struct SegmentArgs {
    /// The logger's file: text (CSV, tab- or white-space separated, a header line naming the
    /// columns), PX4 ULog, ArduPilot DataFlash (.bin) or ROS 2 MCAP, told by its content.
    #[arg(long, value_name = "FILE")]
    pub input: PathBuf,
    /// Session directory to write (plan.toml, samples.csv, gyro.toml, segments.svg/png).
    #[arg(long, value_name = "DIR")]
    pub out: PathBuf,
    /// How to read it (text: columns, time, units; binary logs: instance, topic).
    #[command(flatten)]
    pub log: super::log_input::LogInputArgs,
    /// Prior 1σ of a six-face session's faces, degrees (how well the cube sits on its faces;
    /// default 2). Refused unless the still positions are found to be the six faces of a cube.
    #[arg(long, value_name = "DEG", value_parser = recording::limits::real(0.01, 10.0))]
    pub face_sigma_deg: Option<f64>,
    /// The six faces as you set the unit down, one label per still interval in the order found
    /// (x+, x-, y+, y-, z+, z-; e.g. `z+,x+,y+,z-,x-,y-`): a six-face session, checked against the
    /// data, whatever the automatic labelling finds.
    #[arg(long, value_name = "LABELS", value_delimiter = ',', value_parser = face_label)]
    pub faces: Option<Vec<(usize, f64)>>,
    /// Most samples of each sensor stream held in memory at once (about 200 bytes each). A binary
    /// log with more is read again, and only its still positions and the turns between them are
    /// kept, the first this many; what is left out is said.
    #[arg(long, value_name = "N", default_value_t = DEFAULT_MAX_SAMPLES as u64, value_parser = recording::limits::whole_u64(1000, MAX_ROWS as u64))]
    pub max_samples: u64,
    /// Shortest still interval kept, s.
    #[arg(long, default_value_t = 1.0, value_name = "S", value_parser = recording::limits::real(0.1, recording::limits::MAX_SEGMENT_DURATION_S))]
    pub min_still_s: f64,
    /// Fixed limits on a still window's spread (rms over the axes: accelerometer in mg of the
    /// measured gravity, gyro in °/s) instead of the sensor's own noise floor and a hand's tremor,
    /// for when the automatic choice is wrong (e.g. `--still-threshold 15,6`).
    #[arg(long, value_name = "MG,DEG_S", value_parser = still_threshold)]
    pub still_threshold: Option<recording::session::segment::StillThreshold>,
    /// Replace an existing session in DIR.
    #[arg(long)]
    pub force: bool,
    /// One JSON document on stdout (the intervals, the attitudes given, the gyro fit); the table
    /// and everything else for people on stderr.
    #[arg(long)]
    pub json: bool,
    /// Do not fit the gyro (when its columns are known to be unusable). The accelerometer's axes are
    /// then unchecked for a mirror image: only the gyro's turns can see one.
    #[arg(long)]
    pub no_gyro: bool,
    /// The unit's id (24 hex digits), written into the session's plan so that its calibration is
    /// bound to the unit.
    #[arg(long, value_name = "HEX")]
    pub unit_id: Option<String>,
    /// Local gravity at the site, m/s² (the calibration's m/s² output is scaled by it; default
    /// 9.80665, or from --latitude).
    #[arg(long, value_name = "M_S2", value_parser = recording::limits::real(9.7, 9.9), conflicts_with = "latitude")]
    pub gravity: Option<f64>,
    /// The site's latitude, degrees: local gravity from the WGS 84 normal gravity formula.
    #[arg(long, value_name = "DEG", allow_negative_numbers = true, value_parser = recording::limits::real(-90.0, 90.0))]
    pub latitude: Option<f64>,
    /// The site's height above the ellipsoid, m (with --latitude).
    #[arg(long, value_name = "M", allow_negative_numbers = true, value_parser = recording::limits::real(-500.0, 9000.0))]
    pub height_m: Option<f64>,
}

/// `host simulate-hand`.
#[derive(Debug, Args)]
pub(crate) struct SimulateHandArgs {
    /// The CSV to write (a `.truth.toml` with the simulated unit and gyro is written next to it).
    #[arg(long, value_name = "FILE")]
    pub out: PathBuf,
    /// Seed.
    #[arg(long, default_value_t = 1, value_parser = recording::limits::whole_u64(0, u64::MAX))]
    pub seed: u64,
    /// Sample rate, Hz.
    #[arg(long, default_value_t = 200.0, value_name = "HZ", value_parser = recording::limits::real(SIMULATED_HAND_RATE_HZ.0, SIMULATED_HAND_RATE_HZ.1))]
    pub rate_hz: f64,
    /// Accelerometer unit written: m/s2, g or LSB (4096 per g, quantised).
    #[arg(long, default_value = "m/s2", value_name = "UNIT")]
    pub acc_unit: String,
    /// With --acc-unit LSB: counts added to every accelerometer value (an unsigned output's
    /// mid-scale zero, e.g. 32768); the truth file's biases include it.
    #[arg(long, value_name = "N", value_parser = recording::limits::real(0.0, 1e7))]
    pub acc_offset: Option<f64>,
    /// Gyro unit written: deg/s, rad/s or LSB (whole counts at --gyro-lsb-per-dps).
    #[arg(long, default_value = "deg/s", value_name = "UNIT")]
    pub gyro_unit: String,
    /// With --gyro-unit LSB: counts per °/s written.
    #[arg(long, value_name = "X", value_parser = recording::limits::real(1e-3, 1e6))]
    pub gyro_lsb_per_dps: Option<f64>,
    /// A six-face session instead: a cube set down on its six faces (each placed 1° off its body
    /// axis), turned over by hand between them, consumer-MEMS noise (150 µg/√Hz).
    #[arg(long)]
    pub six_faces: bool,
    /// With --six-faces: how many times the cube is turned over through its six faces.
    #[arg(long, default_value_t = 1, requires = "six_faces", value_parser = recording::limits::whole_u32(1, 10))]
    pub rounds: u32,
    /// At each position, one whole turn about the vertical flat on the table (either way, 4–6 s,
    /// rocking by 0.1°, the unit 3 cm from the turn's axis), set back against its stop to 0.05° and
    /// held again: the classic bench method's turn about each axis (docs/model.md §7.2).
    #[arg(long)]
    pub table_turns: bool,
    /// Replace an existing file.
    #[arg(long)]
    pub force: bool,
}

/// Writes a simulated hand-held session as a logger CSV (`t,acc_x,…,gyr_z`): 24 positions held 3–5 s
/// with hand tremor, turns of 1–3 s up to 180 °/s, 1 mg noise, a gyro with 0.5 % scale, 0.5°
/// misalignment and 0.5 °/s bias (`app::simulate_hand`). Returns the number of rows.
pub(crate) fn simulate_hand_command(a: &SimulateHandArgs) -> Result<usize, CliError> {
    let request = HandSimulation {
        seed: a.seed,
        rate_hz: a.rate_hz,
        acc_unit: a.acc_unit.clone(),
        acc_offset: a.acc_offset,
        gyro_unit: a.gyro_unit.clone(),
        gyro_lsb_per_dps: a.gyro_lsb_per_dps,
        six_face_rounds: a.six_faces.then_some(a.rounds),
        table_turns: a.table_turns,
        spelling: super::spelling::FLAGS,
    };
    let sim = request
        .run()
        .map_err(|e| CliError::Usage(Chain(&e).to_string()))?;
    let truth_path = sim.write(&a.out, a.force).map_err(|e| match e {
        HandWriteError::Exists(p) => CliError::Usage(format!(
            "{} exists: choose another --out or add --force to replace it",
            p.display()
        )),
        HandWriteError::Csv(p, e) => CliError::Write(p, e),
        HandWriteError::Truth(e) => e.into(),
    })?;
    crate::outln!(
        "wrote {} ({} rows, {} positions, {} Hz, {} and {}) and {}",
        a.out.display(),
        sim.session.rows.len(),
        sim.session.holds.len(),
        a.rate_hz,
        sim.acc_unit.symbol(),
        sim.gyro_symbol,
        truth_path.display()
    )?;
    Ok(sim.session.rows.len())
}

/// What `host segment` found and wrote.
pub(crate) struct SegmentOutcome {
    /// The recording.
    pub recording: Recording,
    /// The intervals.
    pub segmentation: Segmentation,
    /// The session plan written.
    pub plan: Plan,
    /// The gyro fit, or why there is none.
    pub gyro: Result<HandGyroFit, HandGyroError>,
    /// The whole turns on the table found, used or not.
    pub table_turns: Vec<FoundTableTurn>,
}

/// Runs `host segment` from the command line (`--quiet` silences the human text).
pub(crate) fn run(a: &SegmentArgs, quiet: bool) -> Result<(), CliError> {
    let out = Output {
        json: a.json,
        quiet,
    };
    segment_to(a, &out).map(|_| ())
}

/// Runs `host segment`, printing the table and the gyro result (to stdout, or stderr with `--json`);
/// the tests' entry, which look at what it found.
#[cfg(test)]
pub(crate) fn segment(a: &SegmentArgs) -> Result<SegmentOutcome, CliError> {
    segment_to(
        a,
        &Output {
            json: a.json,
            quiet: false,
        },
    )
}

fn segment_to(a: &SegmentArgs, out: &Output) -> Result<SegmentOutcome, CliError> {
    let source = a.log.source(&a.input)?;
    let choices = choices(a)?;
    // Refused before any work; built aside and moved into place whole (docs/robustness.md).
    let dir = OutputDir::create(&a.out, a.force, recording::session::PLAN_FILE)?;
    let step = recording::ui::step(format!("reading {}", a.input.display()), out.quiet);
    let log = read_log_keeping(&a.input, &source, a.max_samples as usize).map_err(CliError::Log)?;
    step.finish_and_clear();
    time_unit_note(out, &log.recording);
    let step = recording::ui::step("finding the still intervals and the turns", out.quiet);
    let found = find(log.recording, &choices)?;
    step.finish_and_clear();
    let reader_warnings = found.warnings.len();
    let mut warnings = Vec::new();
    for w in Note::texts(&log.warnings)
        .into_iter()
        .chain(found.warnings.iter().cloned())
    {
        warn(out, &mut warnings, w);
    }
    out.human(table(
        &found.recording,
        &found.segmentation,
        &found.coverage,
    ))?;
    let step = recording::ui::step(
        if choices.fit_gyro {
            "choosing the positions and fitting the gyro to the turns"
        } else {
            "choosing the positions"
        },
        out.quiet,
    );
    let s = found.session(&choices)?;
    step.finish_and_clear();
    refuse_unused_face_sigma(a, &s)?;
    for w in &s.warnings[reader_warnings..] {
        warn(out, &mut warnings, w.clone());
    }
    if let Some(advice) = &s.advice {
        out.line(format_args!("advice: {advice}"))?;
    }
    if s.position_set == PositionSet::SixFaces {
        out.line(format_args!("{}", six_face_text(face_sigma_deg(a))))?;
    }
    if !s.table_turns.is_empty() {
        out.line(format_args!("{}", table_turns_text(&s.table_turns)))?;
    }
    if let Ok(fit) = &s.gyro {
        out.human(gyro_text(fit))?;
    }
    if let Some(problems) = s.gyro_problems() {
        return Err(CliError::GyroRefused(problems));
    }
    let step = recording::ui::step("writing the session", out.quiet);
    let rows = s.write(dir.path(), false)?;
    step.finish_and_clear();
    if let Err(e) = &s.gyro {
        out.line(format_args!("gyro: not calibrated: {}", Chain(e)))?;
    }
    let stem = draw_and_commit(&s, dir, out, &mut warnings)?;
    out.line(format_args!(
        "wrote {} ({} rows in {} static segments) and {stem}.svg; next: host calibrate --input {}",
        a.out.display(),
        rows,
        s.plan.segments.len(),
        a.out.display()
    ))?;
    let written = Written {
        rows,
        advice: s.advice.clone(),
        warnings,
        six_faces: s.position_set == PositionSet::SixFaces,
    };
    let outcome = SegmentOutcome {
        recording: s.recording,
        segmentation: s.segmentation,
        plan: s.plan,
        gyro: s.gyro,
        table_turns: s.table_turns,
    };
    out.document(&document(
        a,
        a.log.gyro_unit_symbol(),
        &outcome,
        &s.coverage,
        &written,
    ))?;
    Ok(outcome)
}

/// Draws the segments' figure into the session directory being built and moves the directory into
/// place; the figure's name. A figure that cannot be drawn is a warning, not a lost session.
fn draw_and_commit(
    s: &SegmentedSession,
    dir: OutputDir,
    out: &Output,
    warnings: &mut Vec<String>,
) -> Result<String, CliError> {
    let step = recording::ui::step("drawing the segments' figure", out.quiet);
    let fig = figure(&s.recording, &s.segmentation);
    match plot::render(&fig, dir.path(), Formats::default()) {
        Ok(o) => o
            .warnings
            .into_iter()
            .for_each(|w| warn(out, warnings, w.to_string())),
        Err(e) => warn(out, warnings, Chain(&e).to_string()),
    }
    dir.commit()?;
    step.finish_and_clear();
    Ok(fig.stem.to_string())
}

/// What reading the file left out or detected, on stderr (and into the JSON document's warnings).
/// The time column's unit, when it was detected rather than given (a note, not a warning).
fn time_unit_note(out: &Output, rec: &Recording) {
    if let Some((unit, true)) = rec.time_unit {
        out.note(format_args!(
            "time column read in {} (detected from its median step and span: {} Hz over {} s; \
             --time-unit to say otherwise)",
            unit.symbol(),
            six_digits(rec.rate_hz),
            six_digits(rec.t_s.last().unwrap_or(&0.0) - rec.t_s.first().unwrap_or(&0.0))
        ));
    }
}

/// The six-face prior, degrees: `--face-sigma-deg` or its default.
/// How the log is cut, from the command line (the unit id and site checked).
fn choices(a: &SegmentArgs) -> Result<SegmentChoices, CliError> {
    Ok(SegmentChoices {
        segment: SegmentOptions {
            min_still_s: a.min_still_s,
            still_threshold: a.still_threshold,
            offer_still_threshold: true,
            ..SegmentOptions::new(super::spelling::FLAGS)
        },
        unit_id: unit_and_site(a)?,
        gravity_m_s2: site_gravity_m_s2(a),
        fit_gyro: !a.no_gyro,
        face_sigma_deg: face_sigma_deg(a),
        faces: a.faces.clone(),
    })
}

/// `--still-threshold MG,DEG_S`: two positive limits.
fn still_threshold(text: &str) -> Result<recording::session::segment::StillThreshold, String> {
    let v: Vec<f64> = text
        .split(',')
        .map(|x| x.trim().parse::<f64>().unwrap_or(f64::NAN))
        .collect();
    match v[..] {
        [mg, dps] if mg > 0.0 && mg <= 1000.0 && dps > 0.0 && dps <= 100.0 => {
            Ok(recording::session::segment::StillThreshold {
                acc_mg: mg,
                gyro_deg_s: dps,
            })
        }
        _ => Err(format!(
            "'{text}' is not MG,DEG_S: give the accelerometer's limit in mg (0–1000) and the \
             gyro's in °/s (0–100), e.g. 15,6"
        )),
    }
}

/// One `--faces` label.
fn face_label(text: &str) -> Result<(usize, f64), String> {
    recording::session::coverage::face_label(text)
        .ok_or_else(|| format!("'{text}' is not a face: use x+, x-, y+, y-, z+ or z-"))
}

fn face_sigma_deg(a: &SegmentArgs) -> f64 {
    a.face_sigma_deg
        .unwrap_or(recording::session::from_recording::SIX_FACE_PRIOR_DEG)
}

/// `--face-sigma-deg` acts only on a six-face session: elsewhere it would change nothing, so it is a
/// usage error (found once the still positions are known).
fn refuse_unused_face_sigma(a: &SegmentArgs, s: &SegmentedSession) -> Result<(), CliError> {
    if a.face_sigma_deg.is_none() || s.position_set == PositionSet::SixFaces {
        return Ok(());
    }
    Err(CliError::Usage(format!(
        "--face-sigma-deg does not apply: the {} still positions found are not the six faces of a \
         cube (each within {}° of a body axis, all six present), so no face prior is used; leave \
         it out",
        s.plan.segments.iter().filter(|p| p.is_static()).count(),
        recording::session::segment::SIX_FACE_DEG
    )))
}

/// What a six-face session is taken as (stdout, with the table).
fn six_face_text(face_sigma_deg: f64) -> String {
    format!(
        "six-face session: fewer than {} distinct positions, each within {}° of a body axis once \
         the faces' own biases and scales are taken out, and all six faces present: taken as the \
         faces of a cube, each the nominal body axis up with a \
         {face_sigma_deg}° attitude prior (--face-sigma-deg); the prior fixes the body frame and \
         the fit estimates each face's placement (docs/model.md §7.1)",
        recording::session::segment::MIN_POSITIONS,
        recording::session::segment::SIX_FACE_DEG
    )
}

/// The unit id given (checked, lower case) and the site options' consistency, before any work.
fn unit_and_site(a: &SegmentArgs) -> Result<Option<String>, CliError> {
    if a.height_m.is_some() && a.latitude.is_none() {
        return Err(CliError::Usage(
            "--height-m needs --latitude (the site's gravity comes from both)".into(),
        ));
    }
    match &a.unit_id {
        Some(hex) if shared::UnitId::parse_hex(hex).is_none() => Err(CliError::Usage(format!(
            "--unit-id {hex}: give the unit's id as 24 hex digits"
        ))),
        // The all-zero id is what a calibration without a unit is bound to: it binds nothing, and
        // a device never has it.
        Some(hex) if shared::UnitId::parse_hex(hex) == Some(shared::UnitId::default()) => {
            Err(CliError::Usage(format!(
                "--unit-id {hex}: the all-zero id means \"no unit\" (a device never has it); give \
                 the unit's own id (host read --port PORT shows it), or leave --unit-id out"
            )))
        }
        id => Ok(id.as_ref().map(|h| h.to_ascii_lowercase())),
    }
}

/// The site's gravity: given, from the latitude (WGS 84 normal gravity), or standard.
fn site_gravity_m_s2(a: &SegmentArgs) -> f64 {
    match (a.gravity, a.latitude) {
        (Some(g), _) => g,
        (None, Some(lat)) => normal_gravity_m_s2(lat, a.height_m.unwrap_or(0.0)),
        (None, None) => shared::STANDARD_GRAVITY_M_S2,
    }
}

/// A warning on stderr, kept for the JSON document.
fn warn(out: &Output, warnings: &mut Vec<String>, text: String) {
    out.warn(&text);
    warnings.push(text);
}

/// The table of intervals.
pub(crate) fn table(rec: &Recording, seg: &Segmentation, cov: &Coverage) -> String {
    let unit = rec.acc_unit.map_or("", |u| u.symbol());
    let mut s = format!(
        "{} still interval(s), {} spin(s), {} short quiet run(s) dropped; thresholds: accelerometer \
         {:.3} mg, gyro {:.3} °/s (a rest's window std, from the sensor's noise floor or \
         --still-threshold)\n",
        seg.stills.len(),
        seg.spins.len(),
        seg.short_dropped,
        seg.acc_threshold / seg.gravity_out * 1e3,
        seg.gyro_threshold_rad_s.to_degrees()
    );
    let _ = writeln!(
        s,
        "  #   start s  duration s   mean direction (x, y, z)     acc noise mg  gyro noise °/s  note"
    );
    for (k, iv) in seg.stills.iter().chain(&seg.spins).enumerate() {
        let acc_mg = linalg::norm(&iv.std_acc) / seg.gravity_out * 1e3;
        let gyro = linalg::norm(&iv.std_gyro_rad_s).to_degrees();
        let note = if k >= seg.stills.len() {
            format!(
                "spin at {:.1} °/s (listed, not used)",
                linalg::norm(&iv.mean_gyro_rad_s).to_degrees()
            )
        } else {
            cov.repeats[k]
                .map(|r| format!("same position as #{}", r + 1))
                .unwrap_or_default()
        };
        let _ = writeln!(
            s,
            "{:>3} {:>9.2} {:>11.2}   ({:+.4}, {:+.4}, {:+.4})   {:>11.3} {:>15.3}  {note}",
            k + 1,
            iv.start_s,
            iv.duration_s,
            iv.direction[0],
            iv.direction[1],
            iv.direction[2],
            acc_mg,
            gyro
        );
    }
    let _ = writeln!(
        s,
        "{} distinct positions (gravity {:.5} {unit} measured)",
        cov.distinct, seg.gravity_out
    );
    s
}

/// How many whole turns on the table were found and used (the refused ones are warnings).
fn table_turns_text(found: &[FoundTableTurn]) -> String {
    let used = found.iter().filter(|t| t.used().is_some()).count();
    format!(
        "whole turns on the table (still before and after at the same position, turned about the \
         vertical): {} found, {used} used as known angles for the gyro (docs/model.md §7.2)",
        found.len()
    )
}

fn gyro_text(fit: &HandGyroFit) -> String {
    // The scale error as every command says it (docs/model.md §8).
    let sc = estimator::estimate::gyro::scale_error(&fit.matrix, &fit.matrix_1sigma);
    let mis = fit.misalignment_deg();
    let table = if fit.table_turns > 0 {
        format!(
            " and {} whole table turns (rms angle error {:.4}°)",
            fit.table_turns, fit.table_rms_residual_deg
        )
    } else {
        String::new()
    };
    let mut s = format!(
        "gyro from {} hand turns{table} (w = G·ω + b, body axes of this session's accelerometer \
         calibration), rms misfit {:.4}°:\n",
        fit.turns, fit.rms_residual_deg
    );
    for i in 0..3 {
        let _ = writeln!(
            s,
            "  {}: scale {:+.0} ± {:.0} ppm, misalignment {:+.4}°, {:+.4}°, bias {:+.4} ± {:.4} °/s",
            ["x", "y", "z"][i],
            sc[i].0 * 1e6,
            sc[i].1 * 1e6,
            mis[i][(i + 1) % 3],
            mis[i][(i + 2) % 3],
            fit.bias_rad_s[i].to_degrees(),
            fit.bias_1sigma_rad_s[i].to_degrees()
        );
    }
    let und = fit.undetermined();
    if und.is_empty() {
        let _ = writeln!(s, "  every entry of G determined to better than 0.1 % (1σ)");
    } else {
        let _ = writeln!(
            s,
            "  not determined to 0.1 % by these turns: {} (turn about more varied axes)",
            und.join(", ")
        );
    }
    s
}

#[cfg(test)]
#[path = "segment_faces_tests.rs"]
mod faces_tests;
