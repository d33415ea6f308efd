//! Reading a session directory (`plan.toml` + `samples.csv`, `docs/recording-format.md`).
//!
//! The reader streams: it holds one line and one [`SegmentAccumulator`] per plan segment, never the
//! rows, so a session of 10⁷ rows is reduced in one pass in constant memory. The CSV dialect is the
//! one the writer produces (no quoting needed: segment names cannot contain commas or quotes), read
//! tolerantly: CRLF line ends, a UTF-8 byte-order mark, blank lines, spaces around fields and
//! double-quoted fields are accepted. Everything else that is wrong is an error naming the line and
//! column, except a final line without a line end, which is a recording cut short: it is skipped with
//! a warning (its last number may be cut mid-digits and still parse, so it is never trusted). A line
//! longer than [`MAX_LINE_BYTES`] is an error, so memory stays bounded whatever the file holds (a link
//! to `/dev/zero` is refused after 4 KiB).

use super::error::shorten;
use super::note::Note;
use super::plan::{Plan, RecordingVersion};
use super::stats::{SegmentAccumulator, SegmentStats};
use super::thermal::is_glitch;
use super::{RecordingError, PLAN_FILE, SAMPLES_FILE};
use crate::limits::MAX_LINE_BYTES;
use std::fs::File;
use std::io::{BufRead, BufReader, Read};
use std::path::Path;

/// How to read a session.
#[derive(Clone, Copy, Debug, Default)]
pub struct ReadOptions {
    /// Never draw a progress bar (it is drawn only on a terminal anyway).
    pub quiet: bool,
}

/// What the reader saw besides the statistics.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct ReadReport {
    /// Data rows read (including rejected ones).
    pub rows: u64,
    /// Bytes of `samples.csv` read.
    pub bytes: u64,
    /// Rows left out because a value was NaN or infinite, all segments.
    pub rejected_rows: u64,
    /// Plan segments with no usable row (they are absent from the statistics).
    pub segments_without_rows: Vec<String>,
    /// What the reader noticed, one note per problem (said with `Display`).
    pub warnings: Vec<Note>,
    /// Per plan segment, the steps between its consecutive rows' time stamps.
    pub steps: Vec<StepCount>,
}

/// A session reduced to its statistics.
#[derive(Clone, Debug)]
pub struct Session {
    /// The plan.
    pub plan: Plan,
    /// One entry per plan segment that has usable rows, in plan order.
    pub stats: Vec<SegmentStats>,
    /// What else the reader found.
    pub report: ReadReport,
}

/// Reads `dir/plan.toml` and reduces `dir/samples.csv` to per-segment statistics, streaming.
pub fn read_session(dir: &Path, options: &ReadOptions) -> Result<Session, RecordingError> {
    let plan = Plan::load(&dir.join(PLAN_FILE))?;
    let path = dir.join(SAMPLES_FILE);
    let io = |source| RecordingError::Io {
        path: path.clone(),
        source,
    };
    let file = File::open(&path).map_err(io)?;
    let len = file.metadata().map_err(io)?.len();
    let bar = crate::ui::progress_bar_bytes(len, "reading samples.csv", options.quiet);
    let reader = BufReader::with_capacity(1 << 20, bar.wrap_read(file));
    let result = read_samples(reader, &plan, &path);
    bar.finish_and_clear();
    let (stats, report) = result?;
    check_time_base(&stats, &report, &plan, &path)?;
    Ok(Session {
        plan,
        stats,
        report,
    })
}

/// Trims ASCII spaces/tabs and one pair of surrounding double quotes.
#[inline]
fn clean(field: &str) -> &str {
    let f = field.trim_ascii();
    match f.strip_prefix('"').and_then(|f| f.strip_suffix('"')) {
        Some(inner) => inner.trim_ascii(),
        None => f,
    }
}

/// One data row as parsed, handed to the callback of [`read_samples_each`] (the tools that need
/// every row, such as `apply` and the noise analysis, read through the same parser as the statistics).
#[derive(Clone, Copy, Debug)]
pub struct Row<'r> {
    /// Segment name.
    pub segment: &'r str,
    /// Index of the segment in the plan.
    pub segment_index: usize,
    /// Time, s.
    pub t_s: f64,
    /// Accelerometer outputs, output unit.
    pub u: [f64; 3],
    /// Gyro rate, body axes, rad/s.
    pub w_rad_s: [f64; 3],
    /// The unit's temperature, °C (format 3 recordings only).
    pub temp_c: Option<f64>,
}

/// A parsed data row: its segment, values (`t_s`, three outputs, three rates, `temp_c`) and line.
#[derive(Clone, Copy, Debug)]
struct Parsed {
    idx: usize,
    v: [f64; 8],
    line: u64,
}

/// The per-segment reduction, fed one line at a time; every parsed row also goes to `sink`.
struct Reducer<'a, S> {
    sink: S,
    path: &'a Path,
    names: Vec<&'a str>,
    accs: Vec<SegmentAccumulator>,
    first_rejected: Vec<Option<u64>>,
    current: usize,
    line_no: u64,
    report: ReadReport,
    /// Per plan segment: the last row's time stamp, and the steps between rows.
    last_t: Vec<Option<f64>>,
    steps: Vec<StepCount>,
    /// The plan's sample period, s.
    period_s: f64,
    /// The segment of the previous row in the file.
    previous_row: Option<usize>,
    /// Per plan segment: steps between consecutive rows that are gaps, repeats or backward steps
    /// (count, first line and step, s).
    time_jumps: Vec<(u64, Option<(u64, f64)>)>,
    /// The last accepted temperature reading (time stamp, °C), the row held back for the check
    /// against the next one, and per plan segment the glitches left out (count, first line, °C).
    last_temp: Option<(f64, f64)>,
    pending: Option<Parsed>,
    temp_glitches: Vec<(u64, Option<(u64, f64)>)>,
    /// The plan's version, which says the columns and names them in errors.
    version: RecordingVersion,
    /// `version.has_temperature()`, looked up once: a ninth column, `temp_c`.
    temperature: bool,
}

impl<'a, S: FnMut(&Row<'_>) -> Result<(), RecordingError>> Reducer<'a, S> {
    fn new(plan: &'a Plan, version: RecordingVersion, path: &'a Path, sink: S) -> Self {
        Reducer {
            sink,
            path,
            names: plan.segments.iter().map(|s| s.name.as_str()).collect(),
            accs: plan
                .segments
                .iter()
                .map(|s| SegmentAccumulator::new(s.name.clone()))
                .collect(),
            first_rejected: vec![None; plan.segments.len()],
            last_t: vec![None; plan.segments.len()],
            steps: vec![StepCount::default(); plan.segments.len()],
            period_s: 1.0 / plan.sample_rate_hz,
            previous_row: None,
            time_jumps: vec![(0, None); plan.segments.len()],
            last_temp: None,
            pending: None,
            temp_glitches: vec![(0, None); plan.segments.len()],
            current: 0,
            line_no: 1,
            report: ReadReport::default(),
            version,
            temperature: version.has_temperature(),
        }
    }

    /// One complete line (its `\n` removed), whose commas are at `commas[..n_commas]` (only the first
    /// eight are recorded). `self.line_no` is its number.
    #[inline]
    fn line(
        &mut self,
        line: &str,
        commas: &[usize; 8],
        n_commas: usize,
    ) -> Result<(), RecordingError> {
        let last = if self.temperature { 8 } else { 7 };
        if n_commas != last {
            if line.trim_ascii().is_empty() {
                return Ok(());
            }
            return Err(self.field_count(n_commas + 1));
        }
        // The last field ends at the line end, before an optional CR.
        let end = line.strip_suffix('\r').map_or(line.len(), str::len);
        let field = |k: usize| -> &str {
            let from = if k == 0 { 0 } else { commas[k - 1] + 1 };
            let to = if k == last { end } else { commas[k] };
            &line[from..to]
        };
        let name = clean(field(0));
        let idx = if self.names[self.current] == name {
            self.current
        } else {
            let Some(i) = self.names.iter().position(|n| *n == name) else {
                return Err(RecordingError::UnknownSegment {
                    path: self.path.to_path_buf(),
                    line: self.line_no,
                    name: name.to_string(),
                });
            };
            self.current = i;
            i
        };
        let mut v = [0.0f64; 8];
        for (k, slot) in v[..last].iter_mut().enumerate() {
            let text = field(k + 1);
            *slot = match text.parse::<f64>() {
                Ok(x) => x,
                // Spaces or quotes around the number: the slow path.
                Err(_) => clean(text)
                    .parse::<f64>()
                    .map_err(|_| RecordingError::Number {
                        path: self.path.to_path_buf(),
                        line: self.line_no,
                        column: k + 2,
                        text: shorten(clean(text)),
                    })?,
            };
        }
        self.report.rows += 1;
        let row = Parsed {
            idx,
            v,
            line: self.line_no,
        };
        if !self.temperature {
            return self.process(row, false);
        }
        // A temperature is judged against the next one too: each row is processed one row late.
        match self.pending.replace(row) {
            Some(p) => {
                let glitch = self.is_glitch(&p, Some(&row));
                self.process(p, glitch)
            }
            None => Ok(()),
        }
    }

    /// Whether row `p`'s temperature is a glitch between the last accepted reading and `next`'s.
    fn is_glitch(&self, p: &Parsed, next: Option<&Parsed>) -> bool {
        p.v[7].is_finite()
            && is_glitch(
                self.last_temp,
                (p.v[0], p.v[7]),
                next.map(|n| (n.v[0], n.v[7])),
            )
    }

    /// The row held back for the temperature check, at the end of the file.
    fn flush(&mut self) -> Result<(), RecordingError> {
        match self.pending.take() {
            Some(p) => {
                let glitch = self.is_glitch(&p, None);
                self.process(p, glitch)
            }
            None => Ok(()),
        }
    }

    /// One parsed row into the sink, the time checks and its segment's statistics (a temperature
    /// `glitch` leaves the row out, noted).
    fn process(&mut self, p: Parsed, glitch: bool) -> Result<(), RecordingError> {
        let Parsed { idx, v, line } = p;
        if glitch {
            let g = &mut self.temp_glitches[idx];
            g.0 += 1;
            g.1.get_or_insert((line, v[7]));
        } else if self.temperature && v[7].is_finite() {
            self.last_temp = Some((v[0], v[7]));
        }
        (self.sink)(&Row {
            segment: self.names[idx],
            segment_index: idx,
            t_s: v[0],
            u: [v[1], v[2], v[3]],
            w_rad_s: [v[4], v[5], v[6]],
            temp_c: (self.temperature && !glitch).then(|| v[7]),
        })?;
        self.time_step(idx, v[0], line);
        let acc = &mut self.accs[idx];
        let before = acc.count();
        if glitch {
            self.report.rejected_rows += 1;
            return Ok(());
        }
        if self.temperature {
            acc.push_with_temperature(v[0], &[v[1], v[2], v[3]], &[v[4], v[5], v[6]], v[7]);
        } else {
            acc.push(v[0], &[v[1], v[2], v[3]], &[v[4], v[5], v[6]]);
        }
        if acc.count() == before {
            self.report.rejected_rows += 1;
            self.first_rejected[idx].get_or_insert(line);
        }
        Ok(())
    }

    /// The step from the segment's previous row to this one's time stamp `t_s` (line `line`).
    fn time_step(&mut self, idx: usize, t_s: f64, line: u64) {
        let follows = self.previous_row == Some(idx);
        self.previous_row = Some(idx);
        let Some(prev) = self.last_t[idx].replace(t_s) else {
            return;
        };
        let dt = t_s - prev;
        let off_rate = !(dt > 0.0 && dt <= GAP_PERIODS * self.period_s);
        if follows && off_rate {
            let g = &mut self.time_jumps[idx];
            g.0 += 1;
            g.1.get_or_insert((line, dt));
        }
        let c = &mut self.steps[idx];
        c.steps += 1;
        if !off_rate {
            c.near += 1;
            c.near_sum_s += dt;
        }
        if dt > 0.0 && dt < 100.0 * self.period_s {
            c.short += 1;
            c.short_sum_s += dt;
        }
    }

    /// The line after the last complete one has more than [`MAX_LINE_BYTES`] bytes.
    fn line_too_long(&self) -> RecordingError {
        RecordingError::LineTooLong {
            path: self.path.to_path_buf(),
            line: self.line_no + 1,
        }
    }

    fn field_count(&self, found: usize) -> RecordingError {
        RecordingError::FieldCount {
            path: self.path.to_path_buf(),
            line: self.line_no,
            found,
            version: self.version,
        }
    }

    /// Complete lines, each ending in `\n`.
    fn lines(&mut self, bytes: &[u8]) -> Result<(), RecordingError> {
        let text = match std::str::from_utf8(bytes) {
            Ok(t) => t,
            Err(e) => {
                let bad_line = bytes[..e.valid_up_to()]
                    .iter()
                    .filter(|&&b| b == b'\n')
                    .count() as u64;
                return Err(RecordingError::NotText {
                    path: self.path.to_path_buf(),
                    line: self.line_no + 1 + bad_line,
                });
            }
        };
        // One pass over the bytes finds both the commas and the line end (cheaper than searching
        // for each separator with memchr, for fields of ~20 bytes).
        let bytes = text.as_bytes();
        let mut i = 0;
        while i < bytes.len() {
            let start = i;
            let mut commas = [0usize; 8];
            let mut n_commas = 0;
            while bytes[i] != b'\n' {
                if bytes[i] == b',' {
                    if n_commas < 8 {
                        commas[n_commas] = i - start;
                    }
                    n_commas += 1;
                }
                i += 1;
                if i == bytes.len() {
                    // Callers pass complete lines only; be safe anyway.
                    break;
                }
            }
            self.line_no += 1;
            self.line(&text[start..i], &commas, n_commas)?;
            i += 1;
        }
        Ok(())
    }
}

/// Reduces the rows of `samples.csv` (header included) to statistics per plan segment.
/// `path` is only used in messages.
pub fn read_samples<R: BufRead>(
    reader: R,
    plan: &Plan,
    path: &Path,
) -> Result<(Vec<SegmentStats>, ReadReport), RecordingError> {
    read_samples_each(reader, plan, path, |_| Ok(()))
}

/// [`read_samples`], handing every parsed row (finite or not, in file order) to `each` as well; an
/// error from `each` stops the reading. Memory stays constant: rows are not kept.
pub fn read_samples_each<R: BufRead>(
    mut reader: R,
    plan: &Plan,
    path: &Path,
    each: impl FnMut(&Row<'_>) -> Result<(), RecordingError>,
) -> Result<(Vec<SegmentStats>, ReadReport), RecordingError> {
    let io = |source| RecordingError::Io {
        path: path.to_path_buf(),
        source,
    };
    let version = plan.version()?;
    let mut red = Reducer::new(plan, version, path, each);

    // Header (with an optional UTF-8 byte-order mark and CR).
    let mut line: Vec<u8> = Vec::with_capacity(256);
    let n = (&mut reader)
        .take(MAX_LINE_BYTES as u64 + 1)
        .read_until(b'\n', &mut line)
        .map_err(io)?;
    if n > MAX_LINE_BYTES {
        return Err(RecordingError::LineTooLong {
            path: path.to_path_buf(),
            line: 1,
        });
    }
    red.report.bytes += n as u64;
    let header = line.strip_prefix(b"\xEF\xBB\xBF").unwrap_or(&line);
    let header = String::from_utf8_lossy(header.trim_ascii_end()).into_owned();
    let found: Vec<&str> = header
        .split(',')
        .map(|h| h.trim().trim_matches('"'))
        .collect();
    let columns = version.columns();
    if found != columns {
        let column = (0..columns.len().max(found.len()))
            .find(|&i| found.get(i) != columns.get(i))
            .map_or(1, |i| i + 1);
        return Err(RecordingError::Header {
            path: path.to_path_buf(),
            found: header,
            column,
            version,
        });
    }

    // The body, a buffer at a time: the complete lines of each buffer are parsed in place; a line
    // that straddles two buffers is carried over (copied) alone.
    line.clear();
    let carry = &mut line;
    loop {
        let buf = reader.fill_buf().map_err(io)?;
        if buf.is_empty() {
            break;
        }
        let len = buf.len();
        red.report.bytes += len as u64;
        let mut start = 0;
        if !carry.is_empty() {
            match buf.iter().position(|&b| b == b'\n') {
                Some(p) => {
                    carry.extend_from_slice(&buf[..=p]);
                    red.lines(carry)?;
                    carry.clear();
                    start = p + 1;
                }
                None => {
                    if carry.len() + len > MAX_LINE_BYTES {
                        return Err(red.line_too_long());
                    }
                    carry.extend_from_slice(buf);
                    reader.consume(len);
                    continue;
                }
            }
        }
        let buf_rest = &buf[start..];
        let complete = buf_rest
            .iter()
            .rposition(|&b| b == b'\n')
            .map_or(0, |p| p + 1);
        red.lines(&buf_rest[..complete])?;
        if buf_rest.len() - complete > MAX_LINE_BYTES {
            return Err(red.line_too_long());
        }
        carry.extend_from_slice(&buf_rest[complete..]);
        reader.consume(len);
    }
    let mut report = finish_report(&mut red, carry)?;
    let stats = collect_stats(&red, plan, &mut report);
    report.steps = red.steps;
    Ok((stats, report))
}

/// Fewest steps between a segment's consecutive rows for its time base to be checked.
const TIME_BASE_MIN_STEPS: u64 = 100;

/// A step between consecutive rows longer than this many periods is a gap (rows are missing): the
/// same rule as the logs' readers.
use super::import::GAP_PERIODS;

/// A segment's mean step (over the steps that are no gap) is "at the plan's rate" within this
/// relative difference. The mean, not each step: a logger's stamps jitter by a large part of a
/// period (±1 ms at 200 Hz), and jitter averages out where a wrong time base does not.
const STEP_TOLERANCE: f64 = 0.1;

/// The time steps between consecutive rows of one segment (a segment recorded in several runs has a
/// gap between them, which counts as one step off the rate).
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct StepCount {
    /// Steps seen.
    pub steps: u64,
    /// Of which forward and no gap (at most [`GAP_PERIODS`] of the plan's periods).
    pub near: u64,
    /// Their sum, s (their mean is the segment's period).
    pub near_sum_s: f64,
    /// Sum of the positive steps shorter than 100 periods, s (the rate they imply, for a message).
    pub short_sum_s: f64,
    /// How many those are.
    pub short: u64,
}

/// Each segment's time stamps step at the plan's rate, on the mean of most of their steps
/// ([`RecordingError::TimeBase`]): the rate enters `ω̇` (docs/model.md §5) and the durations, and a
/// mismatch means that the time column is not what it says.
fn check_time_base(
    stats: &[SegmentStats],
    report: &ReadReport,
    plan: &Plan,
    path: &Path,
) -> Result<(), RecordingError> {
    for (seg, c) in plan.segments.iter().zip(&report.steps) {
        let period_s = 1.0 / plan.sample_rate_hz;
        let at_rate = 2 * c.near >= c.steps
            && (c.near_sum_s / c.near as f64 / period_s - 1.0).abs() <= STEP_TOLERANCE;
        if c.steps < TIME_BASE_MIN_STEPS || at_rate {
            continue;
        }
        let span = stats
            .iter()
            .find(|s| s.name == seg.name)
            .map_or(f64::NAN, |s| {
                (s.count - 1) as f64 / (s.t_last_s - s.t_first_s)
            });
        let stamps_hz = if c.short > 0 {
            c.short as f64 / c.short_sum_s
        } else {
            span
        };
        return Err(RecordingError::TimeBase {
            path: path.to_path_buf(),
            segment: seg.name.clone(),
            stamps_hz,
            plan_hz: plan.sample_rate_hz,
        });
    }
    Ok(())
}

/// The final partial line (if any) and the no-rows check.
fn finish_report<S: FnMut(&Row<'_>) -> Result<(), RecordingError>>(
    red: &mut Reducer<'_, S>,
    carry: &[u8],
) -> Result<ReadReport, RecordingError> {
    red.flush()?;
    let report = std::mem::take(&mut red.report);
    if !carry.trim_ascii().is_empty() {
        // Only the last line of a file can lack its line end: the writer ends every row with one, so
        // the recording was cut short, and even a line that parses may have lost digits.
        return Err(RecordingError::CutShort {
            path: red.path.to_path_buf(),
            line: red.line_no + 1,
        });
    }
    if report.rows == 0 {
        return Err(RecordingError::NoRows(red.path.to_path_buf()));
    }
    Ok(report)
}

fn collect_stats<S>(
    red: &Reducer<'_, S>,
    plan: &Plan,
    report: &mut ReadReport,
) -> Vec<SegmentStats> {
    let path = red.path;
    let mut stats = Vec::with_capacity(red.accs.len());
    for (seg, (n, first)) in plan.segments.iter().zip(&red.time_jumps) {
        if let Some((line, dt)) = first {
            report.warnings.push(Note::SegmentTimeJumps {
                segment: seg.name.clone(),
                count: *n,
                line: *line,
                step_s: *dt,
                period_s: 1.0 / plan.sample_rate_hz,
            });
        }
    }
    for (seg, (n, first)) in plan.segments.iter().zip(&red.temp_glitches) {
        if let Some((line, c)) = first {
            report.warnings.push(Note::SegmentTempGlitches {
                segment: seg.name.clone(),
                count: *n,
                line: *line,
                temp_c: *c,
            });
        }
    }
    for ((acc, seg), first_bad) in red.accs.iter().zip(&plan.segments).zip(&red.first_rejected) {
        let st = acc.finish();
        if let Some(line) = first_bad {
            let rejected = st.as_ref().map_or(0, |s| s.rejected_rows);
            report.warnings.push(Note::SegmentNonFinite {
                segment: seg.name.clone(),
                line: *line,
                rejected,
            });
        }
        match st {
            None => {
                report.segments_without_rows.push(seg.name.clone());
                report.warnings.push(Note::SegmentWithoutRows {
                    segment: seg.name.clone(),
                    path: path.to_path_buf(),
                });
            }
            Some(s) => {
                if let Some(d) = seg.duration_s {
                    let expected = d * plan.sample_rate_hz;
                    if (s.count as f64) < 0.5 * expected {
                        report.warnings.push(Note::SegmentShort {
                            segment: seg.name.clone(),
                            rows: s.count,
                            expected,
                            duration_s: d,
                            rate_hz: plan.sample_rate_hz,
                        });
                    }
                }
                stats.push(s);
            }
        }
    }
    stats
}
#[cfg(test)]
mod tests {
    use super::*;
    use crate::session::{SessionWriter, SAMPLES_HEADER};
    use std::path::Path;

    const PLAN: &str = r#"
output_unit = "V"
sample_rate_hz = 100
[[segment]]
name = "x+"
up_b = [1, 0, 0]
duration_s = 1
[[segment]]
name = "x+ 200"
up_b = [1, 0, 0]
rate_deg_s = 200
[[segment]]
name = "z-"
up_b = [0, 0, -1]
"#;

    fn plan() -> Plan {
        Plan::parse(PLAN).unwrap()
    }

    type Row = (&'static str, f64, [f64; 3], [f64; 3]);

    /// Rows of the three segments, with "x+" split in two runs around "x+ 200" (non-contiguous).
    fn rows() -> Vec<Row> {
        let mut v = Vec::new();
        for k in 0..300 {
            let seg = match k {
                0..=99 | 200..=229 => "x+",
                100..=199 => "x+ 200",
                _ => "z-",
            };
            let t = k as f64 * 0.01 + 1e3;
            let x = (k as f64 * 0.731).sin();
            let y = (k as f64 * 1.37).cos();
            v.push((
                seg,
                t,
                [2.4 + 4e-4 * x, 2.38 - 3e-4 * y, 2.43 + 1e-4 * x * y],
                [3.49 + 0.01 * y, 1e-3 * x, -2e-3 * x * y],
            ));
        }
        v
    }

    fn write_session(dir: &Path, rows: &[Row]) {
        let mut w = SessionWriter::create(dir, &plan(), false).unwrap();
        for (s, t, u, g) in rows {
            w.write_row(s, *t, u, g).unwrap();
        }
        assert_eq!(w.finish().unwrap(), rows.len() as u64);
    }

    fn read_text(text: &str) -> Result<(Vec<SegmentStats>, ReadReport), RecordingError> {
        read_samples(text.as_bytes(), &plan(), Path::new("samples.csv"))
    }

    #[test]
    fn round_trip_matches_two_pass_statistics() {
        let dir = tempfile::tempdir().unwrap();
        let rows = rows();
        write_session(dir.path(), &rows);
        let session = read_session(dir.path(), &ReadOptions { quiet: true }).unwrap();
        assert_eq!(session.plan, plan());
        assert_eq!(session.report.rows, 300);
        assert!(session.report.warnings.is_empty(), "{:?}", session.report);
        assert_eq!(session.stats.len(), 3);
        for st in &session.stats {
            let mine: Vec<&Row> = rows.iter().filter(|r| r.0 == st.name).collect();
            let n = mine.len() as f64;
            assert_eq!(st.count, mine.len() as u64);
            assert_eq!(st.t_first_s, mine[0].1);
            assert_eq!(st.t_last_s, mine[mine.len() - 1].1);
            for i in 0..3 {
                let mu = mine.iter().map(|r| r.2[i]).sum::<f64>() / n;
                let mw = mine.iter().map(|r| r.3[i]).sum::<f64>() / n;
                assert!((st.mean_u[i] - mu).abs() < 1e-13, "{}", st.name);
                assert!((st.mean_w_rad_s[i] - mw).abs() < 1e-13);
                for j in 0..3 {
                    let muj = mine.iter().map(|r| r.2[j]).sum::<f64>() / n;
                    let mwj = mine.iter().map(|r| r.3[j]).sum::<f64>() / n;
                    let cu = mine
                        .iter()
                        .map(|r| (r.2[i] - mu) * (r.2[j] - muj))
                        .sum::<f64>()
                        / (n - 1.0);
                    let cw = mine
                        .iter()
                        .map(|r| (r.3[i] - mw) * (r.3[j] - mwj))
                        .sum::<f64>()
                        / (n - 1.0);
                    let wwt = mine.iter().map(|r| r.3[i] * r.3[j]).sum::<f64>() / n;
                    assert!((st.cov_u[i][j] - cu).abs() < 1e-17, "{} {cu}", st.name);
                    assert!((st.cov_w[i][j] - cw).abs() < 1e-15);
                    assert!((st.mean_wwt[i][j] - wwt).abs() < 1e-12);
                }
            }
        }
        // Bit-exact floats: the file re-read row by row equals what was written.
        let text = std::fs::read_to_string(dir.path().join(SAMPLES_FILE)).unwrap();
        let mut lines = text.lines();
        assert_eq!(lines.next(), Some(SAMPLES_HEADER));
        for (line, r) in lines.zip(&rows) {
            let f: Vec<&str> = line.split(',').collect();
            assert_eq!(f[0], r.0);
            assert_eq!(f[1].parse::<f64>().unwrap(), r.1);
            assert_eq!(f[2].parse::<f64>().unwrap(), r.2[0]);
            assert_eq!(f[7].parse::<f64>().unwrap(), r.3[2]);
        }
        // The plan was written first and is what the reader got; no overwriting without asking.
        let e = SessionWriter::create(dir.path(), &plan(), false)
            .err()
            .unwrap();
        assert!(e.to_string().contains("already exists"), "{e}");
    }

    #[test]
    fn lines_straddling_buffers_read_the_same_as_whole() {
        let dir = tempfile::tempdir().unwrap();
        write_session(dir.path(), &rows());
        let text = std::fs::read(dir.path().join(SAMPLES_FILE)).unwrap();
        let whole = read_samples(&text[..], &plan(), Path::new("s")).unwrap();
        for cap in [1, 7, 64, 133, 4096] {
            let r = std::io::BufReader::with_capacity(cap, &text[..]);
            let got = read_samples(r, &plan(), Path::new("s")).unwrap();
            assert_eq!(got, whole, "buffer of {cap} bytes");
            let cut = std::io::BufReader::with_capacity(cap, &text[..text.len() - 5]);
            let got = read_samples(cut, &plan(), Path::new("s")).unwrap_err();
            assert!(
                matches!(got, RecordingError::CutShort { line: 301, .. }),
                "buffer of {cap} bytes: {got}"
            );
        }
    }

    #[test]
    fn tolerant_of_crlf_bom_quotes_spaces_and_blank_lines() {
        let text = "\u{feff}segment,t_s,u_x,u_y,u_z,w_x,w_y,w_z\r\n\
                    \"x+\", 0.0, 2.4, 2.38, 2.43, 0, 0, 0\r\n\
                    \r\n\
                    x+,0.01,2.5,2.38,2.43,0,0,0\r\n";
        let (stats, report) = read_text(text).unwrap();
        assert_eq!(report.rows, 2);
        assert!((stats[0].mean_u[0] - 2.45).abs() < 1e-12);
    }

    #[test]
    fn time_stamps_at_another_rate_than_the_plans_are_refused() {
        let dir = tempfile::tempdir().unwrap();
        // Scaled by 1.5 (a time column in other units): refused, naming both rates.
        let scaled: Vec<Row> = rows()
            .into_iter()
            .map(|(s, t, u, g)| (s, t * 1.5, u, g))
            .collect();
        write_session(dir.path(), &scaled);
        let e = read_session(dir.path(), &ReadOptions { quiet: true })
            .unwrap_err()
            .to_string();
        assert!(e.contains("66.667 Hz") && e.contains("100.000 Hz"), "{e}");
        // At the plan's rate, with a segment recorded in two runs (one long step): accepted.
        let dir = tempfile::tempdir().unwrap();
        write_session(dir.path(), &rows());
        read_session(dir.path(), &ReadOptions { quiet: true }).unwrap();
    }

    #[test]
    fn truncated_last_line_is_refused_naming_it() {
        let dir = tempfile::tempdir().unwrap();
        write_session(dir.path(), &rows());
        let path = dir.path().join(SAMPLES_FILE);
        let full = std::fs::read(&path).unwrap();
        // Cut in the middle of the last line.
        std::fs::write(&path, &full[..full.len() - 9]).unwrap();
        let e = read_session(dir.path(), &ReadOptions { quiet: true })
            .unwrap_err()
            .to_string();
        assert!(e.contains("line 301") && e.contains("cut short"), "{e}");
        // A cut that leaves a short line in the middle (e.g. two files glued) is an error.
        let mut glued = full[..full.len() - 60].to_vec();
        glued.extend_from_slice(b"\nz-,1,2,3,4,5,6,7\n");
        std::fs::write(&path, glued).unwrap();
        let e = read_session(dir.path(), &ReadOptions { quiet: true })
            .unwrap_err()
            .to_string();
        assert!(
            e.contains("line 301") && e.contains("fields, expected 8"),
            "{e}"
        );
    }

    #[test]
    fn nan_rows_are_counted_left_out_and_reported() {
        let text = "segment,t_s,u_x,u_y,u_z,w_x,w_y,w_z\n\
                    x+,0,2.4,2.38,2.43,0,0,0\n\
                    x+,0.01,NaN,2.38,2.43,0,0,0\n\
                    x+,0.02,2.6,2.38,2.43,0,0,inf\n\
                    x+,0.03,2.6,2.38,2.43,0,0,0\n";
        let (stats, report) = read_text(text).unwrap();
        assert_eq!((stats[0].count, stats[0].rejected_rows), (2, 2));
        assert_eq!((report.rows, report.rejected_rows), (4, 2));
        let w = crate::session::note::Note::texts(&report.warnings).join(
            "
",
        );
        assert!(w.contains("'x+'") && w.contains("first at line 3"), "{w}");
        assert!((stats[0].mean_u[0] - 2.5).abs() < 1e-12);
    }

    #[test]
    fn wrong_header_names_the_column_and_the_expected_header() {
        let e = read_text("segment,t,u_x,u_y,u_z,w_x,w_y,w_z\nx+,0,1,1,1,0,0,0\n")
            .unwrap_err()
            .to_string();
        assert!(
            e.contains("line 1, column 2") && e.contains(SAMPLES_HEADER),
            "{e}"
        );
        let e = read_text("").unwrap_err().to_string();
        assert!(e.contains("line 1, column 1"), "{e}");
    }

    /// The header error names the plan's own version and the fix, with the numbers of
    /// docs/recording-format.md: temperature is version 3; versions 1 and 2 have eight columns.
    #[test]
    fn header_error_names_the_plans_recording_version() {
        let eight = "segment,t_s,u_x,u_y,u_z,w_x,w_y,w_z\nx+,0,1,1,1,0,0,0\n";
        let nine = "segment,t_s,u_x,u_y,u_z,w_x,w_y,w_z,temp_c\nx+,0,1,1,1,0,0,0,20\n";
        let read = |version: u32, text: &str| {
            let plan = Plan::parse(&format!("format_version = {version}\n{PLAN}")).unwrap();
            read_samples(text.as_bytes(), &plan, Path::new("samples.csv"))
        };
        let e = read(3, eight).unwrap_err().to_string();
        assert!(
            e.contains("recording format 3,")
                && e.contains(&format!(
                    "exactly '{eight_header}'",
                    eight_header = crate::session::SAMPLES_HEADER_TEMPERATURE
                ))
                && e.contains("set format_version = 2 in the plan (no temperature)"),
            "{e}"
        );
        assert!(read(3, nine).is_ok());
        for version in [1, 2] {
            let e = read(version, nine).unwrap_err().to_string();
            assert!(
                e.contains(&format!("recording format {version},"))
                    && e.contains(&format!("exactly '{SAMPLES_HEADER}'"))
                    && e.contains("set format_version = 3 in the plan to read temp_c"),
                "{e}"
            );
            assert!(read(version, eight).is_ok());
        }
        // The writer's refusal names the version too.
        let dir = tempfile::tempdir().unwrap();
        let v2 = Plan::parse(&format!("format_version = 2\n{PLAN}")).unwrap();
        let mut w = SessionWriter::create(dir.path(), &v2, false).unwrap();
        let e = w
            .write_row_with_temperature("x+", 0.0, &[1.0; 3], &[0.0; 3], 20.0)
            .unwrap_err()
            .to_string();
        assert!(
            e.contains("format_version = 2, which holds no temperature")
                && e.contains("set format_version = 3"),
            "{e}"
        );
    }

    #[test]
    fn non_numeric_field_names_line_and_column() {
        let text = "segment,t_s,u_x,u_y,u_z,w_x,w_y,w_z\n\
                    x+,0,2.4,2.38,2.43,0,0,0\n\
                    x+,0.01,2.4,2.3x8,2.43,0,0,0\n";
        let e = read_text(text).unwrap_err().to_string();
        assert!(
            e.contains("line 3, column 4 (u_y)") && e.contains("'2.3x8' is not a number"),
            "{e}"
        );
        let e = read_text(&text.replace("2.3x8", ""))
            .unwrap_err()
            .to_string();
        assert!(e.contains("line 3, column 4"), "{e}");
    }

    #[test]
    fn segment_missing_from_the_plan_is_an_error_naming_it_and_the_fix() {
        let text = "segment,t_s,u_x,u_y,u_z,w_x,w_y,w_z\n\
                    x+,0,2.4,2.38,2.43,0,0,0\n\
                    y+,0.01,2.4,2.38,2.43,0,0,0\n";
        let e = read_text(text).unwrap_err().to_string();
        assert!(
            e.contains("line 3") && e.contains("'y+' is not in plan.toml") && e.contains("add a"),
            "{e}"
        );
    }

    #[test]
    fn plan_segment_without_rows_is_flagged_and_left_out() {
        let text = "segment,t_s,u_x,u_y,u_z,w_x,w_y,w_z\n\
                    x+,0,2.4,2.38,2.43,0,0,0\n\
                    z-,0.01,2.4,2.38,2.43,0,0,0\n";
        let (stats, report) = read_text(text).unwrap();
        assert_eq!(stats.len(), 2);
        assert_eq!(report.segments_without_rows, vec!["x+ 200".to_string()]);
        let w = crate::session::note::Note::texts(&report.warnings).join(
            "
",
        );
        assert!(
            w.contains("'x+ 200'") && w.contains("no usable rows"),
            "{w}"
        );
        // "x+" plans 1 s at 100 Hz but has one row.
        assert!(w.contains("'x+' has 1 usable rows"), "{w}");
        let e = read_text("segment,t_s,u_x,u_y,u_z,w_x,w_y,w_z\n")
            .unwrap_err()
            .to_string();
        assert!(e.contains("no data rows"), "{e}");
    }

    #[test]
    fn writer_refuses_unknown_segments_and_flushes_each_segment() {
        let dir = tempfile::tempdir().unwrap();
        let mut w = SessionWriter::create(dir.path(), &plan(), false).unwrap();
        w.write_row("x+", 0.0, &[1.0; 3], &[0.0; 3]).unwrap();
        w.write_row("z-", 0.01, &[1.0; 3], &[0.0; 3]).unwrap();
        // Changing segment flushed "x+": it is on disk while the writer is still open.
        let text = std::fs::read_to_string(dir.path().join(SAMPLES_FILE)).unwrap();
        assert_eq!(text.lines().count(), 2, "{text}");
        let e = w.write_row("nope", 0.02, &[1.0; 3], &[0.0; 3]).unwrap_err();
        assert!(e.to_string().contains("'nope'"), "{e}");
        drop(w);
    }
}
