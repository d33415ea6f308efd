//! [`apply_log`]: a calibration applied to a logger's file (any format `host segment` reads).

use super::{check_still, output_line, Applier, ApplyError, ApplySummary, StillSums};
use crate::calibration_guard::{meet, Meeting, Other};
use crate::note::Note as OutputNote;
use recording::session::import::{Places, Recording};
use recording::session::logs::{read_log_windows, LogError, LogRead, LogSource, LogWindows};
use recording::session::note::Note;
use recording::session::segment::{
    find_intervals_by, gyro_unit_suspect, rest_floors, Interval, RestFloors, SegmentError,
    SegmentOptions,
};
use recording::session::Row;
use recording::spelling::Spelling;
use shared::compensator::LeverMode;
use shared::{Calibration, OutputUnit};
use std::io::Write;
use std::path::Path;

/// Samples per stream read into memory at once: a log within it is read whole, a longer one window
/// by window (`session::logs::read_log_windows`), so that the memory `apply` needs does not grow
/// with the file.
pub const APPLY_MAX_SAMPLES: usize = recording::session::logs::DEFAULT_MAX_SAMPLES;

/// Applies `cal` to the logger's file at `path`, writing the CSV to `out`. The log has no unit id
/// and no segments: the output unit and the temperature are checked as for a session, the ω̇
/// estimate restarts at every gap in the time stamps (more than five periods), and the still
/// intervals found in the log must compensate to 1 g (and rest, with a gyro calibration). A log
/// of more than [`APPLY_MAX_SAMPLES`] per stream is read and compensated window by window, the
/// device's state carried from one window to the next.
pub fn apply_log(
    path: &Path,
    source: &LogSource,
    cal: &Calibration,
    mode: LeverMode,
    assume_temp_c: Option<f64>,
    out: &mut dyn Write,
) -> Result<ApplySummary, ApplyError> {
    apply_log_within(
        path,
        source,
        cal,
        &Setting {
            mode,
            assume_temp_c,
        },
        APPLY_MAX_SAMPLES,
        out,
    )
}

/// How the calibration is applied: the lever-arm mode and a temperature to assume.
#[derive(Clone, Copy, Debug)]
pub struct Setting {
    /// The lever-arm terms applied.
    pub mode: LeverMode,
    /// The temperature to assume for a log without one, °C.
    pub assume_temp_c: Option<f64>,
}

/// [`apply_log`] reading at most `max_samples` per stream at once.
pub fn apply_log_within(
    path: &Path,
    source: &LogSource,
    cal: &Calibration,
    setting: &Setting,
    max_samples: usize,
    out: &mut dyn Write,
) -> Result<ApplySummary, ApplyError> {
    let mut csv = CsvOut {
        out,
        fmt: ryu::Buffer::new(),
        g: cal.gravity_m_s2,
    };
    let windows = match read_log_windows(path, source, max_samples).map_err(ApplyError::Log)? {
        LogRead::Whole(log) => {
            let rec = &log.recording;
            meet_log(rec, cal, setting.assume_temp_c)?;
            let prepared = Prepared::new(
                rec,
                cal,
                setting.mode,
                setting.assume_temp_c,
                source.spelling,
            )?;
            csv.header()?;
            let mut summary = prepared.run(rec, cal, &mut |i, f, a| csv.row(rec.t_s[i], f, a))?;
            let mut notes = log.warnings;
            notes.extend(rec.reader_warnings(Places::InFile));
            summary
                .warnings
                .splice(0..0, notes.into_iter().map(OutputNote::Reader));
            return Ok(summary);
        }
        LogRead::Windows(w) => w,
    };
    let floors = log_floors(&windows, source.spelling)?;
    csv.header()?;
    let mut run: Option<Run> = None;
    let mut notes = WindowNotes::default();
    let mut scale = windows.scale();
    for k in 0..windows.len() {
        let Some(window) = windows.read(k).map_err(ApplyError::Log)? else {
            continue;
        };
        scale.add(&window);
        let log = window.log;
        let rec = &log.recording;
        let mut said = log.warnings;
        said.extend(rec.reader_warnings(Places::InWindow));
        notes.add(windows.span(k), said);
        if rec.is_empty() {
            continue;
        }
        meet_log(rec, cal, setting.assume_temp_c)?;
        let run = match &mut run {
            Some(r) => r,
            None => run.insert(Run::new(
                Applier::new(cal, setting.mode, rec.rate_hz)?,
                cal,
                rec.rate_hz,
            )),
        };
        run.assume_temperature(rec, setting.assume_temp_c);
        let stills = stills_of(rec, floors.as_ref(), source.spelling)?;
        run.rows(rec, &stills, &mut |i, f, a| csv.row(rec.t_s[i], f, a))?;
    }
    let Some(run) = run else {
        return Err(ApplyError::Log(LogError::NoRecording {
            path: path.to_path_buf(),
            rows: 0,
        }));
    };
    let mut summary = run.finish();
    let mut warnings = vec![OutputNote::ReadInWindows {
        max_samples,
        windows: windows.len(),
    }];
    warnings.extend(notes.into_warnings(windows.len()));
    warnings.extend(scale.notes().into_iter().map(OutputNote::Reader));
    summary.warnings.splice(0..0, warnings);
    Ok(summary)
}

/// Where `apply` writes a log's rows: the CSV, its number formatter and the gravity its g are of.
struct CsvOut<'o> {
    out: &'o mut dyn Write,
    fmt: ryu::Buffer,
    g: f64,
}

impl CsvOut<'_> {
    fn header(&mut self) -> Result<(), ApplyError> {
        writeln!(self.out, "{}", super::APPLY_HEADER).map_err(write_error)
    }

    fn row(&mut self, t_s: f64, f: Option<[f32; 3]>, applier: &Applier) -> Result<(), ApplyError> {
        let line = output_line("log", t_s, f, applier, self.g, &mut self.fmt);
        self.out.write_all(line.as_bytes()).map_err(write_error)
    }
}

fn write_error(e: std::io::Error) -> ApplyError {
    ApplyError::Recording(recording::session::RecordingError::Io {
        path: Path::new("(output)").to_path_buf(),
        source: e,
    })
}

/// What [`Prepared::run`] hands each row to: its index, its specific force (m/s², `None` for a row
/// with a non-finite value) and the applier (its corrected rate).
pub(crate) type RowSink<'a> =
    dyn FnMut(usize, Option<[f32; 3]>, &Applier) -> Result<(), ApplyError> + 'a;

/// A calibration ready to be applied to a recording held in memory (a logger's file read whole, or
/// arrays): the compensator and ω̇ estimator, and the still intervals found in the recording, each
/// of which must compensate to 1 g (and rest, with a gyro calibration).
pub struct Prepared {
    applier: Applier,
    stills: Vec<Interval>,
}

impl Prepared {
    /// Checks what can be checked before the rows: a temperature for a temperature model, a sample
    /// rate for the ω̇ estimator, and a gyro that rests where the accelerometer does.
    pub fn new(
        rec: &Recording,
        cal: &Calibration,
        mode: LeverMode,
        assume_temp_c: Option<f64>,
        spelling: Spelling,
    ) -> Result<Prepared, ApplyError> {
        let other = Other {
            name: "the recording",
            unit_id: None,
            output_unit: None,
            frame: None,
            temperatures: super::temperatures(rec.temp_c.is_some(), assume_temp_c),
        };
        meet(Meeting::Apply, &super::mine(cal, None), &other)?;
        let mut applier = Applier::new(cal, mode, rec.rate_hz)?;
        if let (Some(t), None) = (assume_temp_c, &rec.temp_c) {
            applier.compensator.refresh(t as f32);
        }
        let stills = stills_of(rec, None, spelling)?;
        Ok(Prepared { applier, stills })
    }

    /// Compensates every row of `rec` as the device does, handing each row's index and result (NaN
    /// rows `None`) to `row`, then checks the still intervals. The ω̇ estimate restarts at every gap
    /// in the time stamps (more than five periods).
    pub fn run(
        self,
        rec: &Recording,
        cal: &Calibration,
        row: &mut RowSink<'_>,
    ) -> Result<ApplySummary, ApplyError> {
        let mut run = Run::new(self.applier, cal, rec.rate_hz);
        run.rows(rec, &self.stills, row)?;
        Ok(run.finish())
    }
}

/// The log's side of a meeting with the calibration: its output unit and its temperatures.
fn meet_log(
    rec: &Recording,
    cal: &Calibration,
    assume_temp_c: Option<f64>,
) -> Result<(), ApplyError> {
    // As `segment` refuses it: a stream the vehicle has corrected would be corrected twice.
    if let Some(stream) = rec.corrected_by {
        return Err(ApplyError::AlreadyCorrected(stream));
    }
    let other = Other {
        name: "the log",
        unit_id: None,
        output_unit: Some(rec.acc_unit.unwrap_or(OutputUnit::Lsb)),
        frame: None,
        temperatures: super::temperatures(rec.temp_c.is_some(), assume_temp_c),
    };
    meet(Meeting::Apply, &super::mine(cal, None), &other)?;
    Ok(())
}

/// The still intervals of `rec`, each of which must compensate to 1 g. No still interval at all is
/// a flight log, unless the accelerometer is still and only the gyro moves: then the rest check
/// cannot be skipped, it has failed.
fn stills_of(
    rec: &Recording,
    floors: Option<&RestFloors>,
    spelling: Spelling,
) -> Result<Vec<Interval>, ApplyError> {
    match find_intervals_by(rec, &SegmentOptions::new(spelling), floors) {
        Ok(s) => Ok(s.stills),
        Err(SegmentError::NoStill {
            acc_mg, gyro_deg_s, ..
        }) if gyro_unit_suspect(acc_mg, gyro_deg_s) => {
            Err(ApplyError::GyroNeverAtRest { acc_mg, gyro_deg_s })
        }
        Err(_) => Ok(Vec::new()),
    }
}

/// The noise floors every window of a long log is judged by: each stream's quietest window's, as a
/// whole read takes the quietest stretch of the whole log (a first pass over the windows, holding
/// one window at a time).
fn log_floors(windows: &LogWindows, spelling: Spelling) -> Result<Option<RestFloors>, ApplyError> {
    let mut floors: Option<RestFloors> = None;
    for k in 0..windows.len() {
        let Some(window) = windows.read(k).map_err(ApplyError::Log)? else {
            continue;
        };
        if let Some(f) = rest_floors(&window.log.recording, &SegmentOptions::new(spelling)) {
            floors = Some(floors.map_or(f, |g| g.quieter(f)));
        }
    }
    Ok(floors)
}

/// The device's state carried from row to row, and from one window of a long log to the next:
/// the applier (its ω̇ estimate and temperature refresh), the piece of the log between two gaps,
/// the stills checked so far and what was done.
struct Run<'c> {
    applier: Applier,
    cal: &'c Calibration,
    gap_s: f64,
    piece: usize,
    last_t_s: Option<f64>,
    stills: usize,
    summary: ApplySummary,
}

impl<'c> Run<'c> {
    fn new(applier: Applier, cal: &'c Calibration, rate_hz: f64) -> Run<'c> {
        Run {
            applier,
            cal,
            gap_s: 5.0 / rate_hz,
            piece: 0,
            last_t_s: None,
            stills: 0,
            summary: ApplySummary::default(),
        }
    }

    /// A window without temperatures, where one is assumed, compensates at that one.
    fn assume_temperature(&mut self, rec: &Recording, assume_temp_c: Option<f64>) {
        if let (Some(t), None) = (assume_temp_c, &rec.temp_c) {
            self.applier.compensator.refresh(t as f32);
        }
    }

    /// Compensates every row of `rec` as the device does, handing each row's index and result (NaN
    /// rows `None`) to `row`, then checks `stills` (intervals of `rec`). The ω̇ estimate restarts
    /// at every gap in the time stamps (more than five periods).
    fn rows(
        &mut self,
        rec: &Recording,
        stills: &[Interval],
        row: &mut RowSink<'_>,
    ) -> Result<(), ApplyError> {
        let applier = &mut self.applier;
        let mut sums = vec![StillSums::default(); stills.len()];
        let g = self.cal.gravity_m_s2;
        let mut still = 0usize;
        for i in 0..rec.len() {
            let t_s = rec.t_s[i];
            if self.last_t_s.is_some_and(|last| t_s - last > self.gap_s) {
                self.piece += 1;
            }
            self.last_t_s = Some(t_s);
            let r = Row {
                segment: "log",
                segment_index: self.piece,
                t_s,
                // The logger's own counts, as the calibration's session held them (its biases
                // hold the offset the log was read with; `super::offset`).
                u: core::array::from_fn(|j| rec.acc[i][j] + rec.acc_offset[j]),
                w_rad_s: rec.gyro_rad_s[i],
                temp_c: rec.temp_c.as_ref().map(|t| t[i]),
            };
            let f = applier.row(&r);
            self.summary.rows += 1;
            while still < stills.len() && stills[still].end <= i {
                still += 1;
            }
            match f {
                Some(f) if still < stills.len() && stills[still].start <= i => {
                    let s = &mut sums[still];
                    for j in 0..3 {
                        s.f_g[j] += f64::from(f[j]) / g;
                        s.w_rad_s[j] += f64::from(applier.last_rate_rad_s[j]);
                    }
                    s.rows += 1;
                }
                Some(_) => {}
                None => self.summary.non_finite_rows += 1,
            }
            row(i, f, applier)?;
        }
        for (iv, s) in stills.iter().zip(&sums) {
            self.stills += 1;
            let name = format!("still {:02} (t = {:.1} s)", self.stills, iv.start_s);
            check_still(&name, s, self.cal.gyro.is_some())?;
        }
        Ok(())
    }

    /// What was done, with the rows flagged for their temperature.
    fn finish(self) -> ApplySummary {
        let mut summary = self.summary;
        if self.applier.flagged_rows > 0 {
            summary
                .warnings
                .push(OutputNote::RowsOutsideTemperatureRange {
                    rows: self.applier.flagged_rows,
                });
        }
        summary
    }
}

/// What the reader said of each window of a long log, each thing said once (two notes that read
/// the same are one): with the window's times where it was said of one window, with the number of
/// windows where of several.
#[derive(Debug, Default)]
struct WindowNotes {
    notes: Vec<WindowNote>,
}

/// One thing the reader said, its text (what tells two notes apart) and the windows it was said
/// of.
#[derive(Debug)]
struct WindowNote {
    text: String,
    note: Note,
    spans: Vec<(f64, f64)>,
}

impl WindowNotes {
    fn add(&mut self, span: (f64, f64), said: Vec<Note>) {
        for n in said {
            let text = n.to_string();
            match self.notes.iter_mut().find(|w| w.text == text) {
                Some(w) => w.spans.push(span),
                None => self.notes.push(WindowNote {
                    text,
                    note: n,
                    spans: vec![span],
                }),
            }
        }
    }

    fn into_warnings(self, windows: usize) -> Vec<OutputNote> {
        self.notes
            .into_iter()
            .map(|w| OutputNote::InWindows {
                note: Box::new(OutputNote::Reader(w.note)),
                spans: w.spans,
                windows,
            })
            .collect()
    }
}
