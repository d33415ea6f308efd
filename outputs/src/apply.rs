//! Applying a calibration to a recording offline, with the device's own per-sample code.
//!
//! Each row goes through exactly what the firmware's pipeline does with a sample: the gyro rate
//! into `shared::omega_dot::OmegaDotEstimator` (same sample rate, same corner fraction
//! `firmware::pipeline::OMEGA_DOT_CORNER_FRACTION`), then `shared::Compensator::compensate` in `f32`
//! (`docs/model.md` §3, §10). The result is therefore bit for bit what a device with this calibration
//! would output for the same outputs and rates. Two differences from a device, both because a
//! recording is not one continuous stream: the ω̇ estimator restarts at every segment change (the
//! unit was remounted in between, so a difference across the gap means nothing), and a row with a
//! non-finite value restarts it too (as on the device) and gives `NaN` outputs instead of a number.
//!
//! Output: `segment,t_s,f_x_g,f_y_g,f_z_g,w_x_rad_s,w_y_rad_s,w_z_rad_s` — the specific force at the
//! body origin, body axes, in g (the compensator's m/s² divided by the calibration's gravity, in
//! f64), and the corrected body rate the device used for it (the calibration's gyro `G⁻¹(w − b)`,
//! docs/model.md §8; the gyro's reading where the calibration has no gyro), rad/s.
//!
//! A logger's file (`apply_log`) is read by `session::logs`, whole when it holds at most
//! [`APPLY_MAX_SAMPLES`] per stream and window by window when longer (the device's state carried
//! from one window to the next), so that the memory needed does not grow with the file. It has no
//! segments: its rows are written with the segment `log`, and the still intervals
//! `session::segment` finds in it (in each window) are the ones checked to compensate to 1 g.

mod log;
mod offset;

pub use log::{apply_log, apply_log_within, Prepared, Setting, APPLY_MAX_SAMPLES};
pub use offset::{log_offset, LogOffset};

use crate::calibration_guard::{
    check_rest_rate, meet, Frame, GuardError, Meeting, Mine, Other, Temperatures,
};
use firmware::pipeline::OMEGA_DOT_CORNER_FRACTION;
use recording::output_file::OutputFileError;
use recording::session::logs::LogError;
use recording::session::{read_samples_each, Plan, PlanError, RecordingError, Row};
use recording::session::{PLAN_FILE, SAMPLES_FILE};
use shared::compensator::{Compensator, CompensatorError, LeverMode};
use shared::omega_dot::{OmegaDotError, OmegaDotEstimator};
use shared::{BodyAngularAccel, BodyRate, Calibration, SensorOutputs, UnitId};
use std::io::{BufReader, Write};
use std::path::Path;

/// Largest relative difference of a still segment's compensated |f| from 1 g for a calibration to
/// fit a recording: a calibrated unit is within a few mg; a wrong unit, output unit or scale is off
/// by tens of percent or by a factor.
pub(crate) const MAX_STILL_G_ERROR: f64 = 0.05;

/// The header of the output, exactly.
pub const APPLY_HEADER: &str = "segment,t_s,f_x_g,f_y_g,f_z_g,w_x_rad_s,w_y_rad_s,w_z_rad_s";

/// Why a calibration could not be applied.
#[derive(Debug, thiserror::Error)]
pub enum ApplyError {
    /// The log's stream is already corrected by the vehicle's own calibration.
    #[error(
        "the log's IMU samples are {0}, which the vehicle has already corrected with its own \
         calibration: applying this calibration would correct them a second time (as `segment` \
         refuses to calibrate from them). Apply it to a log of the sensor's raw topics \
         (sensor_accel and sensor_gyro: PX4's SDLOG_PROFILE 'high rate' or logger_topics.txt)"
    )]
    AlreadyCorrected(&'static str),
    /// The calibration does not give a compensator.
    #[error("the calibration cannot be applied")]
    Compensator(#[source] CompensatorError),
    /// The calibration cannot meet the recording ([`crate::calibration_guard`]).
    #[error(transparent)]
    Guard(#[from] GuardError),
    /// The recording's sample rate does not give an ω̇ estimator.
    #[error("the recording's sample_rate_hz = {0} cannot be used for the ω̇ estimate")]
    SampleRate(f64, #[source] OmegaDotError),
    /// A still segment's compensated specific force is not 1 g: the calibration does not fit.
    #[error(
        "still segment '{segment}' compensates to |f| = {f_g:.4} g, not 1 g (at most \
         {:.0} % off is plausible): this calibration does not fit this recording (another \
         unit, output unit or scale)",
        MAX_STILL_G_ERROR * 100.0
    )]
    NotOneG {
        /// The segment.
        segment: String,
        /// Its mean |f|, g.
        f_g: f64,
    },
    /// The recording could not be read.
    #[error(transparent)]
    Recording(#[from] RecordingError),
    /// The output could not be written.
    #[error(transparent)]
    Output(OutputFileError),
    /// A logger's file could not be read.
    #[error(transparent)]
    Log(LogError),
    /// The accelerometer is still somewhere, the gyro nowhere.
    #[error(
        "no stretch of the recording is at rest: where the accelerometer is still ({acc_mg:.1} mg \
         of noise) the gyro moves {gyro_deg_s:.1} °/s, 57× a still gyro's, as a gyro in °/s read as \
         rad/s does: the gyro's unit does not fit this recording"
    )]
    GyroNeverAtRest {
        /// The quietest accelerometer noise, mg.
        acc_mg: f64,
        /// The gyro's noise there, °/s.
        gyro_deg_s: f64,
    },
    /// A raw log's offset that contradicts the one the calibration was made with (or a recorded
    /// one that is no number).
    #[error(
        "{}{calibration} was made from counts read with {} counts of zero force \
         (raw_offset_lsb), which its biases hold: {}",
        .given.map_or(String::new(), |g| format!("--acc-offset {}: ", offset::counts(g))),
        offset::counts(*.recorded),
        if .recorded.iter().all(|x| x.is_finite()) {
            format!(
                "the log's own counts are compensated, so another offset contradicts it; give \
                 --acc-offset {} or leave it out (the calibration's is then used)",
                offset::counts(*.recorded)
            )
        } else {
            "fix or remove raw_offset_lsb in the calibration".to_string()
        }
    )]
    RawOffset {
        /// The calibration file.
        calibration: String,
        /// The offset given (`None`: the calibration's own is not a number).
        given: Option<[f64; 3]>,
        /// The calibration's.
        recorded: [f64; 3],
    },
}

/// The device's per-sample state for one recording.
#[derive(Clone, Debug)]
pub struct Applier {
    compensator: Compensator,
    omega_dot: OmegaDotEstimator,
    segment: Option<usize>,
    /// Rows between two temperature refreshes (the device refreshes a few times a second).
    refresh_rows: u64,
    /// Rows since the last refresh (`None`: none yet).
    since_refresh: Option<u64>,
    /// Rows compensated outside the calibration's valid temperature range (the device flags them).
    flagged_rows: u64,
    /// The corrected body rate of the last finite sample, rad/s (what the lever-arm terms used).
    last_rate_rad_s: [f32; 3],
}

impl Applier {
    /// The compensator of `cal` in `mode` and the device's ω̇ estimator for `sample_rate_hz`.
    pub fn new(
        cal: &Calibration,
        mode: LeverMode,
        sample_rate_hz: f64,
    ) -> Result<Self, ApplyError> {
        let compensator = Compensator::new(cal, mode).map_err(ApplyError::Compensator)?;
        let fs = sample_rate_hz as f32;
        let omega_dot = OmegaDotEstimator::new(fs, fs * OMEGA_DOT_CORNER_FRACTION)
            .map_err(|e| ApplyError::SampleRate(sample_rate_hz, e))?;
        Ok(Applier {
            compensator,
            omega_dot,
            segment: None,
            refresh_rows: (sample_rate_hz / f64::from(firmware::pipeline::TEMPERATURE_REFRESH_HZ))
                .max(1.0) as u64,
            since_refresh: None,
            flagged_rows: 0,
            last_rate_rad_s: [0.0; 3],
        })
    }

    /// One sample exactly as the device treats it: specific force, m/s², `f32`; `None` for a sample
    /// with a non-finite value (which also restarts the ω̇ estimate).
    pub fn sample(&mut self, u: &[f32; 3], w_rad_s: &[f32; 3]) -> Option<[f32; 3]> {
        if !u.iter().chain(w_rad_s).all(|v| v.is_finite()) {
            self.omega_dot.reset();
            return None;
        }
        // As on the device: the gyro's reading corrected to the body rate (docs/model.md §8) feeds both
        // the ω̇ estimator and the lever-arm terms; a calibration without a gyro leaves it untouched.
        let w = self.compensator.correct_rate(w_rad_s).rad_s;
        self.last_rate_rad_s = w;
        let wd = *self.omega_dot.update(&w);
        Some(self.compensate(u, &w, &wd))
    }

    /// The corrected body rate of the last finite sample, rad/s (`host apply`'s `w_*_rad_s` columns).
    pub fn rate_rad_s(&self) -> [f32; 3] {
        self.last_rate_rad_s
    }

    /// The compensation step alone, with a given (corrected) body rate and ω̇ (the firmware pipeline's
    /// `compensate`).
    pub fn compensate(&self, u: &[f32; 3], w_rad_s: &[f32; 3], wd_rad_s2: &[f32; 3]) -> [f32; 3] {
        let u = SensorOutputs { raw: *u };
        let f = if self.compensator.mode() == LeverMode::Off {
            self.compensator.compensate_static(&u)
        } else {
            self.compensator.compensate(
                &u,
                &BodyRate { rad_s: *w_rad_s },
                &BodyAngularAccel { rad_s2: *wd_rad_s2 },
            )
        };
        f.m_s2
    }

    /// The ω̇ estimator's state (its last output is what the next [`Applier::sample`] builds on).
    pub fn omega_dot_estimator(&self) -> &OmegaDotEstimator {
        &self.omega_dot
    }

    /// One recorded row: restarts the ω̇ estimate on a segment change, refreshes the temperature model
    /// with the row's temperature at the device's pace (docs/model.md §9), then [`Applier::sample`].
    pub fn row(&mut self, row: &Row<'_>) -> Option<[f32; 3]> {
        if self.segment != Some(row.segment_index) {
            self.omega_dot.reset();
            self.segment = Some(row.segment_index);
        }
        if let Some(t) = row.temp_c {
            let due = self.since_refresh.is_none_or(|n| n >= self.refresh_rows);
            if due {
                self.compensator.refresh(t as f32);
                self.since_refresh = Some(0);
            }
            self.since_refresh = self.since_refresh.map(|n| n + 1);
            if self.compensator.temperature_state().is_flagged() {
                self.flagged_rows += 1;
            }
        }
        self.sample(&row.u.map(|v| v as f32), &row.w_rad_s.map(|v| v as f32))
    }
}

/// What `apply_session` (or [`Prepared::run`]) did.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct ApplySummary {
    /// Rows written (one per input row).
    pub rows: u64,
    /// Rows written as `NaN` because an input value was not finite.
    pub non_finite_rows: u64,
    /// Warnings of the reader (cut-short last line, empty segments, …), and rows outside the
    /// calibration's temperature range.
    pub warnings: Vec<crate::note::Note>,
    /// Notes: an explicit choice the data already satisfied (the unit id ignored where no ids
    /// differ).
    pub notes: Vec<String>,
}

/// How the calibration's unit id binds it to a recording.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum UnitBinding {
    /// The calibration's id (`None`: it has none), checked against the recording's.
    Bound(Option<UnitId>),
    /// The calibration's id, not checked (the user's choice, [`UserOption::IgnoreUnitId`](recording::spelling::UserOption::IgnoreUnitId)): a note
    /// where the ids do not differ.
    Ignored(Option<UnitId>),
}

impl UnitBinding {
    /// The id to check against the recording's, and a note where the check was to be ignored but
    /// no ids differ: the choice is satisfied already, and honoured.
    fn checked_id(self, plan: &Plan) -> (Option<UnitId>, Option<String>) {
        let ignored = match self {
            UnitBinding::Bound(id) => return (id, None),
            UnitBinding::Ignored(id) => id,
        };
        let why = match (ignored, plan.unit_id.as_deref()) {
            (None, _) => "the calibration has no unit id".to_string(),
            (_, None) => "the recording's plan has no unit_id".to_string(),
            (Some(c), Some(r)) if UnitId::parse_hex(r) == Some(c) => {
                format!("the calibration and the recording are both of unit {c}")
            }
            _ => return (None, None),
        };
        let note = format!("note: --ignore-unit-id: {why}, so no id would have been refused");
        (None, Some(note))
    }
}

/// The calibration's side of a meeting with a recording.
pub fn mine(cal: &Calibration, unit_id: Option<UnitId>) -> Mine<'_> {
    Mine {
        name: "the calibration",
        cal,
        unit_id,
    }
}

/// A session's side of a meeting: its plan's unit id, output unit, frame and temperatures
/// (`assume_temp_c`: a temperature given to assume).
pub fn recording(plan: &Plan, assume_temp_c: Option<f64>) -> Other<'static> {
    Other {
        name: "the recording",
        unit_id: plan.unit_id.clone(),
        output_unit: Some(plan.output_unit),
        frame: Some(Frame::of_plan(plan)),
        temperatures: temperatures(plan.has_temperature(), assume_temp_c),
    }
}

/// What a recording gives a temperature model: its own temperatures (`recorded`), or the one to
/// assume.
pub(crate) fn temperatures(recorded: bool, assume_temp_c: Option<f64>) -> Temperatures {
    match (recorded, assume_temp_c) {
        (true, assumed) => Temperatures::Recorded { assumed },
        (false, Some(t)) => Temperatures::Assumed(t),
        (false, None) => Temperatures::None,
    }
}

/// Per still segment, the compensated specific force and the corrected rate summed, for the
/// physical check ([`ApplyError::NotOneG`], [`ApplyError::RestRate`]).
#[derive(Clone, Debug, Default)]
struct StillSums {
    f_g: [f64; 3],
    w_rad_s: [f64; 3],
    rows: u64,
}

/// The physical check of a calibration against a recording's still segments: |f| ≈ 1 g and, when the
/// calibration has a gyro, a rest rate near zero after its bias.
fn check_stills(plan: &Plan, sums: &[StillSums], gyro: bool) -> Result<(), ApplyError> {
    for (sp, s) in plan.segments.iter().zip(sums) {
        if sp.is_static() {
            check_still(&sp.name, s, gyro)?;
        }
    }
    Ok(())
}

/// [`check_stills`] of one still segment (fewer than 10 rows are not judged).
fn check_still(name: &str, s: &StillSums, gyro: bool) -> Result<(), ApplyError> {
    if s.rows < 10 {
        return Ok(());
    }
    let n = s.rows as f64;
    let f = shared::linalg::norm(&s.f_g.map(|v| v / n));
    if f.is_nan() || (f - 1.0).abs() > MAX_STILL_G_ERROR {
        return Err(ApplyError::NotOneG {
            segment: name.to_string(),
            f_g: f,
        });
    }
    let w = shared::linalg::norm(&s.w_rad_s.map(|v| v / n)).to_degrees();
    if gyro {
        check_rest_rate("the calibration", "the recording", name, w)?;
    }
    Ok(())
}

/// One output row: segment, time, the specific force in g and the corrected rate (`NaN` for a row
/// with a non-finite value).
fn output_line(
    segment: &str,
    t_s: f64,
    f: Option<[f32; 3]>,
    applier: &Applier,
    g: f64,
    fmt: &mut ryu::Buffer,
) -> String {
    let (f_g, w) = match f {
        Some(f) => (
            f.map(|v| f64::from(v) / g),
            applier.last_rate_rad_s.map(f64::from),
        ),
        None => ([f64::NAN; 3], [f64::NAN; 3]),
    };
    let mut line = String::with_capacity(160);
    line.push_str(segment);
    line.push(',');
    line.push_str(fmt.format(t_s));
    for v in f_g.into_iter().chain(w) {
        line.push(',');
        line.push_str(if v.is_finite() { fmt.format(v) } else { "NaN" });
    }
    line.push('\n');
    line
}

/// Applies `cal` to the session in `dir`, writing the CSV to `out` (streaming, constant memory).
/// `unit` is the calibration's unit id and whether it is checked against the plan's;
/// `assume_temp_c` is the temperature of a recording without one. The meeting is checked first
/// ([`crate::calibration_guard::meet`]); the still segments are then checked to compensate to 1 g
/// (`MAX_STILL_G_ERROR`).
pub fn apply_session(
    dir: &Path,
    cal: &Calibration,
    unit: UnitBinding,
    mode: LeverMode,
    assume_temp_c: Option<f64>,
    out: &mut dyn Write,
) -> Result<ApplySummary, ApplyError> {
    let plan = Plan::load(&dir.join(PLAN_FILE))
        .map_err(|e: PlanError| ApplyError::from(RecordingError::from(e)))?;
    let (cal_unit, id_note) = unit.checked_id(&plan);
    meet(
        Meeting::Apply,
        &mine(cal, cal_unit),
        &recording(&plan, assume_temp_c),
    )?;
    let mut applier = Applier::new(cal, mode, plan.sample_rate_hz)?;
    if let (Some(t), false) = (assume_temp_c, plan.has_temperature()) {
        applier.compensator.refresh(t as f32);
    }
    let mut stills = vec![StillSums::default(); plan.segments.len()];
    let path = dir.join(SAMPLES_FILE);
    let file = std::fs::File::open(&path).map_err(|source| RecordingError::Io {
        path: path.clone(),
        source,
    })?;
    let write_err = |source: std::io::Error| RecordingError::Io {
        path: Path::new("(output)").to_path_buf(),
        source,
    };
    writeln!(out, "{APPLY_HEADER}").map_err(write_err)?;
    let g = cal.gravity_m_s2;
    let mut summary = ApplySummary::default();
    let mut fmt = ryu::Buffer::new();
    let (_, report) = read_samples_each(
        BufReader::with_capacity(1 << 20, file),
        &plan,
        &path,
        |row| {
            let f = applier.row(row);
            summary.rows += 1;
            if let Some(f) = f {
                let s = &mut stills[row.segment_index];
                let w = applier.last_rate_rad_s;
                for j in 0..3 {
                    s.f_g[j] += f64::from(f[j]) / g;
                    s.w_rad_s[j] += f64::from(w[j]);
                }
                s.rows += 1;
            }
            if f.is_none() {
                summary.non_finite_rows += 1;
            }
            let line = output_line(row.segment, row.t_s, f, &applier, g, &mut fmt);
            out.write_all(line.as_bytes()).map_err(write_err)
        },
    )?;
    summary.warnings = report
        .warnings
        .into_iter()
        .map(crate::note::Note::Reader)
        .collect();
    summary.notes.extend(id_note);
    check_stills(&plan, &stills, cal.gyro.is_some())?;
    if applier.flagged_rows > 0 {
        summary
            .warnings
            .push(crate::note::Note::RowsOutsideTemperatureRange {
                rows: applier.flagged_rows,
            });
    }
    Ok(summary)
}

#[cfg(test)]
mod tests {
    use super::*;
    use estimator::sim::{simulate_to_dir, NoiseModel};
    use estimator::unit_file::UnitFile;
    use firmware::testvectors::{COMP_CASES, OMEGA_DOT_RATE_CORNER_HZ, OMEGA_DOT_SEQ};
    use recording::session::builtin::builtin_plan;
    use shared::forward::TableState;

    fn f(bits: &[u32; 3]) -> [f32; 3] {
        bits.map(f32::from_bits)
    }

    /// Parses the output CSV: (segment, t_s, f_g) per row.
    fn parse(csv: &str) -> Vec<(String, f64, [f64; 3])> {
        let mut lines = csv.lines();
        assert_eq!(lines.next(), Some(APPLY_HEADER));
        lines
            .map(|l| {
                let v: Vec<&str> = l.split(',').collect();
                assert_eq!(v.len(), 8, "{l}");
                let n = |k: usize| v[k].parse::<f64>().unwrap();
                (v[0].to_string(), n(1), [n(2), n(3), n(4)])
            })
            .collect()
    }

    /// A session directory holding `rows` (u, w) of the firmware's test vectors at 1 kHz.
    fn vector_session(dir: &Path, rows: &[([f32; 3], [f32; 3])]) {
        let plan = "output_unit = \"V\"\nsample_rate_hz = 1000\n[[segment]]\nname = \"v\"\n\
                    up_b = [0, 0, 1]\nrate_deg_s = 100\n";
        std::fs::write(dir.join(PLAN_FILE), plan).unwrap();
        let mut s = String::from(recording::session::SAMPLES_HEADER);
        s.push('\n');
        for (k, (u, w)) in rows.iter().enumerate() {
            // f64 of an f32 prints exactly and parses back to the same f32.
            let d = |x: f32| f64::from(x).to_string();
            s.push_str(&format!(
                "v,{},{},{},{},{},{},{}\n",
                k as f64 * 1e-3,
                d(u[0]),
                d(u[1]),
                d(u[2]),
                d(w[0]),
                d(w[1]),
                d(w[2])
            ));
        }
        std::fs::write(dir.join(SAMPLES_FILE), s).unwrap();
    }

    #[test]
    fn bit_for_bit_with_the_firmware_test_vectors() {
        let cal = firmware::paper_unit::calibration();
        let g = cal.gravity_m_s2;
        let (fs, fc) = OMEGA_DOT_RATE_CORNER_HZ;
        assert_eq!(fc, fs * OMEGA_DOT_CORNER_FRACTION);
        // The compensation step in the three modes.
        let modes = [
            LeverMode::Off,
            LeverMode::RateOnly,
            LeverMode::RateAndAcceleration,
        ];
        let appliers = modes.map(|m| Applier::new(&cal, m, f64::from(fs)).unwrap());
        for c in COMP_CASES {
            let (u, w, wd) = (f(&c.u), f(&c.w), f(&c.wd));
            let want = [c.out_static, c.out_rate, c.out_full];
            for (a, want) in appliers.iter().zip(want) {
                assert_eq!(a.compensate(&u, &w, &wd).map(f32::to_bits), want);
            }
        }
        // The ω̇ estimator built from the recording's sample rate, over the firmware's gyro sequence.
        let mut a = Applier::new(&cal, LeverMode::RateAndAcceleration, f64::from(fs)).unwrap();
        for (w, want) in OMEGA_DOT_SEQ {
            let w = f(w);
            assert_eq!(
                a.omega_dot_estimator().clone().update(&w).map(f32::to_bits),
                *want
            );
            assert!(a.sample(&[1.0; 3], &w).is_some());
        }
        // And through the files: session → CSV → the same f32 values (divided by g in f64).
        let dir = tempfile::tempdir().unwrap();
        let rows: Vec<_> = COMP_CASES.iter().map(|c| (f(&c.u), f(&c.w))).collect();
        vector_session(dir.path(), &rows);
        for (mode, pick) in [(LeverMode::Off, 0), (LeverMode::RateOnly, 1)] {
            let mut out = Vec::new();
            let s = apply_session(
                dir.path(),
                &cal,
                UnitBinding::Bound(None),
                mode,
                None,
                &mut out,
            )
            .unwrap();
            assert_eq!(s.rows, COMP_CASES.len() as u64);
            let parsed = parse(std::str::from_utf8(&out).unwrap());
            for (c, (_, _, f_g)) in COMP_CASES.iter().zip(&parsed) {
                let want =
                    [c.out_static, c.out_rate][pick].map(|b| f64::from(f32::from_bits(b)) / g);
                assert_eq!(*f_g, want);
            }
        }
    }

    #[test]
    fn recovers_the_simulated_specific_force() {
        let unit = UnitFile::paper_unit();
        let cal = unit.to_calibration().unwrap();
        let mut plan = builtin_plan("quick-oblique").unwrap().unwrap();
        // A spin-up, so that the ω̇ estimate and the tangential term are exercised too.
        plan.segments.push(recording::session::SegmentPlan {
            attitude: Default::default(),
            attitude_sigma_deg: None,
            name: "ramp".into(),
            up_b: [0.6, 0.0, 0.8],
            rate_deg_s: 0.0,
            rate_end_deg_s: Some(400.0),
            duration_s: Some(1.0),
            table_centre_m: Some([0.03, -0.02, 0.01]),
            mount: None,
            ..Default::default()
        });
        let dir = tempfile::tempdir().unwrap();
        simulate_to_dir(dir.path(), &unit, &plan, &NoiseModel::none(), 3, false).unwrap();
        let mut out = Vec::new();
        let s = apply_session(
            dir.path(),
            &cal,
            UnitBinding::Bound(None),
            LeverMode::RateAndAcceleration,
            None,
            &mut out,
        )
        .unwrap();
        let rows = parse(std::str::from_utf8(&out).unwrap());
        assert_eq!(rows.len() as u64, s.rows);
        let g = cal.gravity_m_s2;
        let dt = 1.0 / plan.sample_rate_hz;
        let (mut worst_g, mut checked) = (0.0f64, 0);
        let mut seg_start = (String::new(), 0.0);
        for (name, t, f_g) in &rows {
            if *name != seg_start.0 {
                seg_start = (name.clone(), *t);
            }
            let sp = plan.segments.iter().find(|p| p.name == *name).unwrap();
            let t_local = t - seg_start.1;
            // The ω̇ filter settles in ~10 of its 15-sample lags.
            if t_local < 0.15 {
                continue;
            }
            let d = sp.duration_s.unwrap();
            let r1 = sp.rate_end_deg_s.unwrap_or(sp.rate_deg_s);
            let accel = (r1 - sp.rate_deg_s) / d;
            let table = TableState {
                up_b: sp.up_b,
                rate_rad_s: (sp.rate_deg_s + accel * (t_local / dt).round() * dt).to_radians(),
                accel_rad_s2: accel.to_radians(),
                centre_m: sp.table_centre_m.unwrap_or([0.0; 3]),
            };
            let truth = table.motion(g).f_o.m_s2.map(|v| v / g);
            for j in 0..3 {
                worst_g = worst_g.max((f_g[j] - truth[j]).abs());
            }
            checked += 1;
        }
        assert!(checked > rows.len() / 2, "{checked} of {}", rows.len());
        // f32 arithmetic on ~2 V outputs resolves ~0.3 µg; the lever terms at 200 °/s add rounding.
        assert!(worst_g < 5e-6, "worst error {worst_g} g");
    }

    #[test]
    fn refuses_another_units_calibration() {
        let unit = UnitFile::paper_unit();
        let cal = unit.to_calibration().unwrap();
        let mut plan = builtin_plan("quick-oblique").unwrap().unwrap();
        plan.unit_id = Some("00112233445566778899aabb".into());
        let other = UnitId::parse_hex("ffeeddccbbaa998877665544").unwrap();
        let check = |id| meet(Meeting::Apply, &mine(&cal, id), &recording(&plan, None));
        let err = check(Some(other)).unwrap_err();
        assert!(err.to_string().contains("--ignore-unit-id"), "{err}");
        assert!(
            err.to_string().contains("ffeeddccbbaa998877665544"),
            "{err}"
        );
        assert!(check(UnitId::parse_hex("00112233445566778899AABB")).is_ok());
        assert!(check(None).is_ok());
    }

    /// A calibration that carries the gyro's errors: the applier turns the gyro's reading into the
    /// body rate as the device does, so a spin with a 0.5 %, 0.5°, 0.5 °/s gyro is compensated to the
    /// truth; reading the gyro as perfect leaves a quarter of a milli-g at this rate.
    #[test]
    fn the_gyro_correction_is_applied_before_the_lever_arm_terms() {
        use shared::forward::{BodyMotion, ForwardModel};
        use shared::{BodyAngularAccel, BodyRate, BodySpecificForce};
        let mut cal = shared::params::PAPER_UNIT;
        let gyro = firmware::paper_unit::typical_gyro();
        cal.gyro = Some(gyro);
        let model = ForwardModel::new(&cal).unwrap();
        let omega = [2.0, -1.5, 3.0];
        let f = [3.0, -4.0, 8.0];
        let u = model
            .outputs(&BodyMotion {
                f_o: BodySpecificForce { m_s2: f },
                omega: BodyRate { rad_s: omega },
                omega_dot: BodyAngularAccel { rad_s2: [0.0; 3] },
            })
            .raw
            .map(|v| v as f32);
        let g = shared::linalg::mat_vec(&gyro.matrix, &omega);
        let w: [f32; 3] = core::array::from_fn(|i| (g[i] + gyro.bias_rad_s[i]) as f32);
        let mut perfect_cal = cal;
        perfect_cal.gyro = None;
        let mut with = Applier::new(&cal, LeverMode::RateAndAcceleration, 1000.0).unwrap();
        let mut without =
            Applier::new(&perfect_cal, LeverMode::RateAndAcceleration, 1000.0).unwrap();
        let (mut a, mut b) = ([0.0f32; 3], [0.0f32; 3]);
        for _ in 0..200 {
            a = with.sample(&u, &w).unwrap();
            b = without.sample(&u, &w).unwrap();
        }
        let err = |x: [f32; 3]| {
            (0..3)
                .map(|i| (f64::from(x[i]) - f[i]).abs() / shared::STANDARD_GRAVITY_M_S2)
                .fold(0.0, f64::max)
        };
        assert!(err(a) < 20e-6, "corrected: {} g", err(a));
        assert!(err(b) > 200e-6, "uncorrected: {} g", err(b));
    }

    /// A calibration with a temperature model: rows recorded at 45 °C are compensated at 45 °C (the
    /// model of docs/model.md §9 applied by the device's refresh), not at the reference; rows outside
    /// the valid range are counted for the warning.
    #[test]
    fn rows_are_compensated_at_their_temperature() {
        use shared::sensor_models::poly_no_constant;
        let mut cal = shared::params::PAPER_UNIT;
        let thermal = firmware::paper_unit::typical_thermal_model();
        cal.temperature = Some(thermal);
        let (fitted, _) = cal.statics.to_fitted().unwrap();
        let f_g = [0.3, -0.5, 0.81];
        // The outputs of the unit at temperature t, static (docs/model.md §9).
        let outputs = |t: f64| -> [f32; 3] {
            let dt = t - thermal.reference_c;
            let mf = shared::linalg::mat_vec(&fitted.m_out_per_g, &f_g);
            core::array::from_fn(|i| {
                (fitted.zero_bias_out[i]
                    + poly_no_constant(&thermal.zero_bias_out_per_c[i], dt)
                    + (1.0 + poly_no_constant(&thermal.scale_rel_per_c[i], dt)) * mf[i])
                    as f32
            })
        };
        let err_ug = |f: [f32; 3]| {
            (0..3)
                .map(|i| (f64::from(f[i]) / cal.gravity_m_s2 - f_g[i]).abs() * 1e6)
                .fold(0.0, f64::max)
        };
        let run = |t: f64, with_temp: bool| {
            let mut a = Applier::new(&cal, LeverMode::Off, 1000.0).unwrap();
            let u = outputs(t);
            let mut last = [0.0f32; 3];
            for k in 0..10 {
                let row = Row {
                    segment: "s",
                    segment_index: 0,
                    t_s: k as f64 * 1e-3,
                    u: u.map(f64::from),
                    w_rad_s: [0.0; 3],
                    temp_c: with_temp.then_some(t),
                };
                last = a.row(&row).unwrap();
            }
            (err_ug(last), a.flagged_rows)
        };
        let (at_45, flagged) = run(45.0, true);
        assert!(
            at_45 < 2.0 && flagged == 0,
            "45 °C: {at_45} µg, {flagged} flagged"
        );
        let (ignored, _) = run(45.0, false);
        assert!(ignored > 1000.0, "without the temperature: {ignored} µg");
        let (_, flagged) = run(90.0, true);
        assert_eq!(flagged, 10);
    }
}
