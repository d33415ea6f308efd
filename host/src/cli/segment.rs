//! `host segment`: one continuous logger recording (a hand-held session) → a session directory that
//! `host calibrate --input` reads, a table and a figure of what was found, and the gyro's `G` and
//! bias from the hand turns (`gyro.toml`).

use super::output::Output;
use super::CliError;
use crate::estimate::handheld_gyro::{HandGyroError, HandGyroFit};
use crate::output_file::{write_atomic, OutputDir};
use crate::report::plot::{self, Figure, Formats, Panel, Series, SeriesStyle};
use crate::session::from_recording::{normal_gravity_m_s2, plan_for, write_session};
use crate::session::hand_gyro;
use crate::session::import::{
    parse_acc_unit, read_logger_csv, GyroUnit, ImportOptions, Recording, TimeSource,
};
use crate::session::plan::Attitude;
use crate::session::segment::{
    coverage, find_intervals, Coverage, IntervalKind, SegmentOptions, Segmentation,
};
use crate::session::Plan;
use crate::sim::handheld::{logger_unit, simulate_hand, write_logger_csv, HandSpec, LoggerLayout};
use crate::unit_file::UnitFile;
use clap::Args;
use serde::Serialize;
use shared::linalg;
use shared::OutputUnit;
use std::fmt::Write as _;
use std::path::{Path, PathBuf};

pub use crate::session::hand_gyro::GYRO_FILE;

/// `host segment`.
#[derive(Debug, Args)]
pub struct SegmentArgs {
    /// The logger's CSV (a header line naming the columns).
    #[arg(long, value_name = "FILE")]
    pub input: PathBuf,
    /// Session directory to write (plan.toml, samples.csv, gyro.toml, segments.svg/png).
    #[arg(long, value_name = "DIR")]
    pub out: PathBuf,
    /// Accelerometer x,y,z and gyro x,y,z column names, in that order.
    #[arg(
        long,
        value_name = "AX,AY,AZ,GX,GY,GZ",
        default_value = "acc_x,acc_y,acc_z,gyr_x,gyr_y,gyr_z"
    )]
    pub columns: String,
    /// Column with the time in seconds (else --rate-hz).
    #[arg(long, value_name = "NAME")]
    pub time_column: Option<String>,
    /// Sample rate, Hz, when the file has no time column (a sample index is ignored).
    #[arg(long, value_name = "HZ", value_parser = crate::limits::real(crate::limits::MIN_LOGGER_RATE_HZ, crate::limits::MAX_SAMPLE_RATE_HZ))]
    pub rate_hz: Option<f64>,
    /// The accelerometer's unit: m/s2, g, LSB or V (kept as the calibration's output unit).
    #[arg(long, value_name = "UNIT")]
    pub acc_unit: String,
    /// The gyro's unit: deg/s or rad/s.
    #[arg(long, value_name = "UNIT")]
    pub gyro_unit: String,
    /// Shortest still interval kept, s.
    #[arg(long, default_value_t = 1.0, value_name = "S", value_parser = crate::limits::real(0.1, crate::limits::MAX_SEGMENT_DURATION_S))]
    pub min_still_s: f64,
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
    #[arg(long, value_name = "M_S2", value_parser = crate::limits::real(9.7, 9.9), conflicts_with = "latitude")]
    pub gravity: Option<f64>,
    /// The site's latitude, degrees: local gravity from the WGS 84 normal gravity formula.
    #[arg(long, value_name = "DEG", allow_negative_numbers = true, value_parser = crate::limits::real(-90.0, 90.0))]
    pub latitude: Option<f64>,
    /// The site's height above the ellipsoid, m (with --latitude).
    #[arg(long, value_name = "M", allow_negative_numbers = true, value_parser = crate::limits::real(-500.0, 9000.0))]
    pub height_m: Option<f64>,
}

/// `host simulate-hand`.
#[derive(Debug, Args)]
pub struct SimulateHandArgs {
    /// The CSV to write (a `.truth.toml` with the simulated unit and gyro is written next to it).
    #[arg(long, value_name = "FILE")]
    pub out: PathBuf,
    /// Seed.
    #[arg(long, default_value_t = 1, value_parser = crate::limits::whole_u64(0, u64::MAX))]
    pub seed: u64,
    /// Sample rate, Hz.
    #[arg(long, default_value_t = 200.0, value_name = "HZ", value_parser = crate::limits::real(20.0, 10_000.0))]
    pub rate_hz: f64,
    /// Accelerometer unit written: m/s2, g or LSB (4096 per g, quantised).
    #[arg(long, default_value = "m/s2", value_name = "UNIT")]
    pub acc_unit: String,
    /// Gyro unit written: deg/s or rad/s.
    #[arg(long, default_value = "deg/s", value_name = "UNIT")]
    pub gyro_unit: String,
    /// Replace an existing file.
    #[arg(long)]
    pub force: bool,
}

/// Writes a simulated hand-held session as a logger CSV (`t,acc_x,…,gyr_z`): 24 positions held 3–5 s
/// with hand tremor, turns of 1–3 s up to 180 °/s, 1 mg noise, a gyro with 0.5 % scale, 0.5°
/// misalignment and 0.5 °/s bias. Returns the number of rows.
pub(crate) fn simulate_hand_command(a: &SimulateHandArgs) -> Result<usize, CliError> {
    let unit = parse_acc_unit(&a.acc_unit)
        .filter(|u| *u != OutputUnit::Volts)
        .ok_or_else(|| CliError::Usage(format!("--acc-unit {}: use m/s2, g or LSB", a.acc_unit)))?;
    let gyro_unit = GyroUnit::parse(&a.gyro_unit).ok_or_else(|| {
        CliError::Usage(format!("--gyro-unit {}: use deg/s or rad/s", a.gyro_unit))
    })?;
    let truth_path = a.out.with_extension("truth.toml");
    for p in [&a.out, &truth_path] {
        if p.exists() && !a.force {
            return Err(CliError::Usage(format!(
                "{} exists: choose another --out or add --force to replace it",
                p.display()
            )));
        }
    }
    let truth = logger_unit(unit);
    let spec = HandSpec {
        rate_hz: a.rate_hz,
        acc_step: if unit == OutputUnit::Lsb { 1.0 } else { 0.0 },
        ..HandSpec::standard(a.seed)
    };
    let sim = simulate_hand(&truth, &spec);
    let layout = LoggerLayout {
        gyro_deg_s: gyro_unit == GyroUnit::DegPerS,
        ..LoggerLayout::default()
    };
    let io = |p: &Path| {
        let p = p.display().to_string();
        move |e: std::io::Error| CliError::Failed(format!("cannot write {p}: {e}"))
    };
    write_logger_csv(&a.out, &sim.rows, &layout).map_err(io(&a.out))?;
    let g = &spec.gyro;
    let text = format!(
        "{}\n# The simulated gyro: w = matrix·ω_body + bias (true body axes).\n[gyro]\nmatrix = {:?}\nbias_rad_s = {:?}\n",
        UnitFile::from_calibration(&truth, None, None).to_toml(),
        g.matrix,
        g.bias_rad_s
    );
    write_atomic(&truth_path, text.as_bytes(), a.force)?;
    crate::outln!(
        "wrote {} ({} rows, {} positions, {} Hz, {} and {}) and {}",
        a.out.display(),
        sim.rows.len(),
        sim.holds.len(),
        a.rate_hz,
        unit.symbol(),
        gyro_unit.symbol(),
        truth_path.display()
    )?;
    Ok(sim.rows.len())
}

/// What `host segment` found and wrote.
pub struct SegmentOutcome {
    /// The recording.
    pub recording: Recording,
    /// The intervals.
    pub segmentation: Segmentation,
    /// The session plan written.
    pub plan: Plan,
    /// The gyro fit, or why there is none.
    pub gyro: Result<HandGyroFit, HandGyroError>,
}

fn import_options(a: &SegmentArgs) -> Result<ImportOptions, CliError> {
    let names: Vec<String> = a.columns.split(',').map(|s| s.trim().to_string()).collect();
    let columns: [String; 6] = names.try_into().map_err(|_| {
        CliError::Usage("--columns needs six names: acc x,y,z then gyro x,y,z".into())
    })?;
    // The reader matches names case-insensitively: a name given twice would read one column twice
    // and make the fit singular, far from the cause.
    let mut seen: Vec<&str> = columns.iter().map(String::as_str).collect();
    seen.extend(a.time_column.as_deref());
    for (k, name) in seen.iter().enumerate() {
        if name.is_empty() {
            return Err(CliError::Usage(
                "--columns has an empty name: give six names, acc x,y,z then gyro x,y,z".into(),
            ));
        }
        if let Some(first) = seen[..k].iter().find(|n| n.eq_ignore_ascii_case(name)) {
            return Err(CliError::Usage(format!(
                "column '{first}' is named twice in --columns/--time-column: each of acc x,y,z, \
                 gyro x,y,z and the time must be its own column"
            )));
        }
    }
    let time = match (&a.time_column, a.rate_hz) {
        (Some(c), None) => TimeSource::Column(c.clone()),
        (None, Some(hz)) => TimeSource::RateHz(hz),
        _ => {
            return Err(CliError::Usage(
                "give exactly one of --time-column NAME (seconds) or --rate-hz HZ".into(),
            ))
        }
    };
    let acc_unit = parse_acc_unit(&a.acc_unit).ok_or_else(|| {
        CliError::Usage(format!("--acc-unit {}: use m/s2, g, LSB or V", a.acc_unit))
    })?;
    let gyro_unit = GyroUnit::parse(&a.gyro_unit).ok_or_else(|| {
        CliError::Usage(format!("--gyro-unit {}: use deg/s or rad/s", a.gyro_unit))
    })?;
    Ok(ImportOptions {
        columns,
        time,
        acc_unit,
        gyro_unit,
    })
}

/// Runs `host segment` from the command line (`--quiet` silences the human text).
pub fn run(a: &SegmentArgs, quiet: bool) -> Result<(), CliError> {
    let out = Output {
        json: a.json,
        quiet,
    };
    segment_to(a, &out).map(|_| ())
}

/// Runs `host segment`, printing the table and the gyro result (to stdout, or stderr with `--json`).
pub fn segment(a: &SegmentArgs) -> Result<SegmentOutcome, CliError> {
    segment_to(
        a,
        &Output {
            json: a.json,
            quiet: false,
        },
    )
}

fn segment_to(a: &SegmentArgs, out: &Output) -> Result<SegmentOutcome, CliError> {
    let options = import_options(a)?;
    let unit_id = unit_and_site(a)?;
    // Refused before any work; built aside and moved into place whole (docs/robustness.md).
    let dir = OutputDir::create(&a.out, a.force, crate::session::PLAN_FILE)?;
    let rec = read_logger_csv(&a.input, &options).map_err(|e| CliError::Failed(e.to_string()))?;
    let mut warnings = Vec::new();
    if rec.skipped_rows > 0 {
        let w = format!(
            "{} row(s) with NaN or infinite values left out",
            rec.skipped_rows
        );
        warn(out, &mut warnings, w);
    }
    if let Some(line) = rec.unterminated_line {
        let w = format!(
            "line {line}, the last, has no line end: the file was cut short; that line is left out"
        );
        warn(out, &mut warnings, w);
    }
    if let Some(w) = rec.time_jumps() {
        warn(out, &mut warnings, w);
    }
    let seg_options = SegmentOptions {
        min_still_s: a.min_still_s,
        ..SegmentOptions::default()
    };
    let seg = find_intervals(&rec, &seg_options).map_err(|e| CliError::Failed(e.to_string()))?;
    let cov = coverage(&seg.stills, seg_options.same_position_deg);
    out.human(table(&rec, &seg, &cov))?;
    cov.check(seg.stills.len(), seg_options.same_position_deg)
        .map_err(|e| CliError::Failed(e.to_string()))?;
    let advice = cov.advice();
    if let Some(advice) = &advice {
        out.line(format_args!("advice: {advice}"))?;
    }
    let mut plan = plan_for(&rec, &seg);
    plan.unit_id = unit_id;
    plan.gravity_m_s2 = site_gravity_m_s2(a);
    let gyro = if a.no_gyro {
        Err(HandGyroError::NotAsked)
    } else {
        hand_gyro::fit(&rec, &seg, &plan)?
    };
    if let Ok(fit) = &gyro {
        out.human(gyro_text(fit))?;
        let problems = hand_gyro::problems(fit);
        if !problems.is_empty() {
            return Err(CliError::GyroRefused(problems));
        }
    }
    let rows = write_session(dir.path(), &rec, &seg, &plan, false)?;
    match &gyro {
        Ok(fit) => {
            let path = dir.path().join(GYRO_FILE);
            write_atomic(&path, hand_gyro::file_text(fit).as_bytes(), false)?;
        }
        Err(e) => out.line(format_args!("gyro: not calibrated: {e}"))?,
    }
    let fig = figure(&rec, &seg);
    match plot::render(&fig, dir.path(), Formats::default()) {
        Ok(o) => o
            .warnings
            .into_iter()
            .for_each(|w| warn(out, &mut warnings, w)),
        Err(e) => warn(out, &mut warnings, e.to_string()),
    }
    dir.commit()?;
    out.line(format_args!(
        "wrote {} ({} rows in {} static segments) and {}.svg; next: host calibrate --input {}",
        a.out.display(),
        rows,
        plan.segments.len(),
        fig.stem,
        a.out.display()
    ))?;
    let outcome = SegmentOutcome {
        recording: rec,
        segmentation: seg,
        plan,
        gyro,
    };
    let written = Written {
        rows,
        advice,
        warnings,
    };
    out.document(&document(a, options.gyro_unit, &outcome, &cov, &written))?;
    Ok(outcome)
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

/// What was written and said besides the intervals and the fit, for the JSON document.
struct Written {
    rows: u64,
    advice: Option<String>,
    warnings: Vec<String>,
}

/// The `--json` document of `host segment`.
#[derive(Serialize)]
struct SegmentDocument {
    input: String,
    sample_rate_hz: f64,
    /// The accelerometer's unit (the calibration's output unit): `acc_noise` is in it.
    acc_unit: &'static str,
    /// The gyro unit of the input; the document's rates are in rad/s and °/s as named.
    gyro_unit: &'static str,
    /// |mean accelerometer output| at rest, acc_unit.
    gravity_out: f64,
    acc_threshold_mg: f64,
    gyro_threshold_deg_s: f64,
    still_intervals: usize,
    spins: usize,
    short_dropped: usize,
    distinct_positions: usize,
    intervals: Vec<IntervalDocument>,
    gyro: Option<GyroDocument>,
    gyro_not_calibrated: Option<String>,
    advice: Option<String>,
    warnings: Vec<String>,
    out_dir: String,
    rows_written: u64,
}

#[derive(Serialize)]
struct IntervalDocument {
    /// 1-based, as in the table.
    index: usize,
    kind: &'static str,
    start_s: f64,
    duration_s: f64,
    /// Rough up direction from the uncalibrated outputs (unit vector, body axes).
    mean_direction: [f64; 3],
    acc_noise_mg: f64,
    gyro_noise_deg_s: f64,
    /// Spins: the mean rate.
    rate_deg_s: Option<f64>,
    /// Still intervals: the earlier interval (1-based) at the same position.
    same_position_as: Option<usize>,
    /// Still intervals: the attitude given to the session's segment.
    attitude: Option<AttitudeDocument>,
}

/// `free` (no prior, docs/model.md §7) or `axis` (set down on a face: `up_b` with a prior).
#[derive(Serialize)]
struct AttitudeDocument {
    segment: String,
    kind: &'static str,
    up_b: [f64; 3],
    prior_1sigma_deg: Option<f64>,
}

/// The gyro fit; a `null` 1σ is an entry the turns do not determine.
#[derive(Serialize)]
struct GyroDocument {
    turns: usize,
    rms_residual_deg: f64,
    matrix: [[f64; 3]; 3],
    matrix_1sigma: [[f64; 3]; 3],
    bias_rad_s: [f64; 3],
    bias_rad_s_1sigma: [f64; 3],
    undetermined: Vec<String>,
}

fn document(
    a: &SegmentArgs,
    gyro_unit: GyroUnit,
    o: &SegmentOutcome,
    cov: &Coverage,
    w: &Written,
) -> SegmentDocument {
    let (rec, seg) = (&o.recording, &o.segmentation);
    let intervals = seg
        .stills
        .iter()
        .chain(&seg.spins)
        .enumerate()
        .map(|(k, iv)| {
            let sp = o.plan.segments.get(k).filter(|_| k < seg.stills.len());
            IntervalDocument {
                index: k + 1,
                kind: match iv.kind {
                    IntervalKind::Still => "static",
                    IntervalKind::Spin => "spin",
                },
                start_s: iv.start_s,
                duration_s: iv.duration_s,
                mean_direction: iv.direction,
                acc_noise_mg: linalg::norm(&iv.std_acc) / seg.gravity_out * 1e3,
                gyro_noise_deg_s: linalg::norm(&iv.std_gyro_rad_s).to_degrees(),
                rate_deg_s: (iv.kind == IntervalKind::Spin)
                    .then(|| linalg::norm(&iv.mean_gyro_rad_s).to_degrees()),
                same_position_as: cov.repeats.get(k).copied().flatten().map(|r| r + 1),
                attitude: sp.map(|sp| AttitudeDocument {
                    segment: sp.name.clone(),
                    kind: match sp.attitude {
                        Attitude::Free => "free",
                        Attitude::Fixture => "axis",
                    },
                    up_b: sp.up_b,
                    prior_1sigma_deg: sp.attitude_sigma_deg,
                }),
            }
        })
        .collect();
    SegmentDocument {
        input: a.input.display().to_string(),
        sample_rate_hz: rec.rate_hz,
        acc_unit: rec.acc_unit.map_or("", |u| u.symbol()),
        gyro_unit: gyro_unit.symbol(),
        gravity_out: seg.gravity_out,
        acc_threshold_mg: seg.acc_threshold / seg.gravity_out * 1e3,
        gyro_threshold_deg_s: seg.gyro_threshold_rad_s.to_degrees(),
        still_intervals: seg.stills.len(),
        spins: seg.spins.len(),
        short_dropped: seg.short_dropped,
        distinct_positions: cov.distinct,
        intervals,
        gyro: o.gyro.as_ref().ok().map(|f| GyroDocument {
            turns: f.turns,
            rms_residual_deg: f.rms_residual_deg,
            matrix: f.matrix,
            matrix_1sigma: f.matrix_1sigma,
            bias_rad_s: f.bias_rad_s,
            bias_rad_s_1sigma: f.bias_1sigma_rad_s,
            undetermined: f.undetermined(),
        }),
        gyro_not_calibrated: o.gyro.as_ref().err().map(|e| e.to_string()),
        advice: w.advice.clone(),
        warnings: w.warnings.clone(),
        out_dir: a.out.display().to_string(),
        rows_written: w.rows,
    }
}

/// The table of intervals.
pub fn table(rec: &Recording, seg: &Segmentation, cov: &Coverage) -> String {
    let unit = rec.acc_unit.map_or("", |u| u.symbol());
    let mut s = format!(
        "{} still interval(s), {} spin(s), {} short quiet run(s) dropped; thresholds: accelerometer \
         {:.3} mg, gyro {:.3} °/s (window std, from the quietest stretch)\n",
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

fn gyro_text(fit: &HandGyroFit) -> String {
    let sc = fit.scale_rel();
    let mis = fit.misalignment_deg();
    let mut s = format!(
        "gyro from {} hand turns (w = G·ω + b, body axes of this session's accelerometer \
         calibration), rms misfit {:.4}°:\n",
        fit.turns, fit.rms_residual_deg
    );
    for i in 0..3 {
        let _ = writeln!(
            s,
            "  {}: scale {:+.4} % ± {:.4} %, misalignment {:+.4}°, {:+.4}°, bias {:+.4} ± {:.4} °/s",
            ["x", "y", "z"][i],
            sc[i] * 100.0,
            fit.matrix_1sigma[i][i] * 100.0,
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

/// The recording (|acc| and |gyro|) with the still intervals marked.
fn figure(rec: &Recording, seg: &Segmentation) -> Figure {
    let step = (rec.len() / 4000).max(1);
    let series = |label: &str, f: &dyn Fn(usize) -> f64, colour| Series {
        label: label.into(),
        points: (0..rec.len())
            .step_by(step)
            .map(|i| (rec.t_s[i], f(i)))
            .collect(),
        error: None,
        style: SeriesStyle::Line,
        colour,
    };
    let marks = |y: f64| Series {
        label: "still intervals".into(),
        points: seg
            .stills
            .iter()
            .flat_map(|iv| {
                (iv.start..iv.end)
                    .step_by(step.max(10))
                    .map(move |i| (i, y))
            })
            .map(|(i, y)| (rec.t_s[i], y))
            .collect(),
        error: None,
        style: SeriesStyle::Markers,
        colour: 4,
    };
    let unit = rec.acc_unit.map_or("", |u| u.symbol());
    let g = seg.gravity_out;
    Figure {
        stem: "segments".into(),
        title: "Recording and the still intervals found".into(),
        grid: (2, 1),
        size: (1400, 900),
        panels: vec![
            Panel {
                title: "accelerometer magnitude".into(),
                x_desc: "t (s)".into(),
                y_desc: format!("|a| ({unit})"),
                x_categories: None,
                log_y: false,
                series: vec![
                    series("|a|", &|i| linalg::norm(&rec.acc[i]), 2),
                    marks(g * 1.05),
                ],
            },
            Panel {
                title: "gyro magnitude".into(),
                x_desc: "t (s)".into(),
                y_desc: "|w| (°/s)".into(),
                x_categories: None,
                log_y: false,
                series: vec![
                    series("|w|", &|i| linalg::norm(&rec.gyro_rad_s[i]).to_degrees(), 0),
                    marks(0.0),
                ],
            },
        ],
    }
}
