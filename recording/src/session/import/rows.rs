//! A text file's rows: its header and separator, where the options' columns are, and each data row
//! parsed and kept as the [`Keeper`] says.

use super::lines::{next_line, next_line_end, Counted, LineEnd};
use super::time::detect_time_unit;
use super::{ImportError, ImportOptions, Recording, TimeSource, MAX_OVERLONG_LINES};
use crate::session::logs::keep::{Admit, Keeper};
use crate::session::logs::resume::Marker;
use crate::session::note::Note;
use crate::spelling::UserOption;
use std::io::BufRead;
use std::path::Path;

/// The field separator: a comma, else a semicolon or tab if the header uses one, else white space
/// (`' '`: any run of spaces and tabs, as MATLAB's and many tools' text files have).
pub(super) fn separator(header: &str) -> char {
    [',', ';', '\t']
        .into_iter()
        .find(|c| header.contains(*c))
        .unwrap_or(if header.trim().contains(' ') {
            ' '
        } else {
            ','
        })
}

/// The fields of a line split at `sep` (white space: at any run of it).
pub(super) fn split_fields(text: &str, sep: char) -> Vec<&str> {
    if sep == ' ' {
        text.split_whitespace().map(clean).collect()
    } else {
        text.split(sep).map(clean).collect()
    }
}

/// A comment line (`#` first), which a logger's file may have before its header and among its rows.
pub(super) fn is_comment(text: &str) -> bool {
    text.trim_start_matches('\u{feff}')
        .trim_start()
        .starts_with('#')
}

pub(super) fn clean(field: &str) -> &str {
    field.trim().trim_matches('"').trim()
}

/// A text file's header as found: its column names (indices "0", "1", … for a header-less file),
/// the separator, its line number, and where the file is header-less, its first data row's text.
pub(super) struct Header {
    pub(super) names: Vec<String>,
    pub(super) sep: char,
    pub(super) line: u64,
    /// A header-less file's first line, which is data.
    pub(super) first_row: Option<String>,
    /// Lines before the header that are neither blank nor comments (a logger's preamble).
    pub(super) preamble: u64,
}

/// Lines looked at for the header when the first one does not name the columns asked for.
const PREAMBLE_LINES: usize = 64;

/// A line of numbers only: a header-less file's data.
fn numeric(text: &str, sep: char) -> bool {
    let f = split_fields(text, sep);
    !f.is_empty() && f.iter().all(|x| x.is_empty() || x.parse::<f64>().is_ok())
}

/// Whether the header's names are all numbers: the file has no header.
pub(super) fn all_numbers(names: &[String]) -> bool {
    !names.is_empty() && names.iter().all(|x| x.parse::<f64>().is_ok())
}

/// Whether `names` are all column indices (the columns given as `0,1,2,3,4,5`).
fn by_index(options: &ImportOptions) -> bool {
    options.columns.iter().all(|c| c.parse::<usize>().is_ok())
}

/// Whether the line `fields` names every column the options ask for.
fn names_all(fields: &[&str], options: &ImportOptions) -> bool {
    let has = |name: &str| fields.iter().any(|h| h.eq_ignore_ascii_case(name));
    options.columns.iter().all(|c| has(c))
        && match &options.time {
            TimeSource::Column(t) => has(t),
            TimeSource::RateHz(_) => true,
        }
}

/// Reads the header line: after `options.skip_lines` lines, the first line that is neither blank
/// nor a `#` comment; where that one does not name the columns asked for, the first of the next
/// lines that does (a logger's preamble before it is skipped and counted), or with columns given by
/// index, the first line of numbers (a header-less file). Its column names (a byte-order mark and
/// quotes removed), the field separator it uses, and its line number.
pub(super) fn read_header<R: BufRead>(
    r: &mut R,
    buf: &mut Vec<u8>,
    path: &Path,
    options: &ImportOptions,
) -> Result<Header, ImportError> {
    let mut line = 0u64;
    while line < options.skip_lines {
        line += 1;
        if !next_line(r, buf, line)? {
            return Err(ImportError::Empty(path.to_path_buf()));
        }
    }
    let mut first: Option<(String, u64)> = None;
    let mut seen = 0;
    loop {
        line += 1;
        if !next_line(r, buf, line)? {
            break;
        }
        let text = String::from_utf8_lossy(buf)
            .trim_start_matches('\u{feff}')
            .to_string();
        if text.trim().is_empty() || is_comment(&text) {
            continue;
        }
        let sep = separator(&text);
        if by_index(options) && numeric(&text, sep) {
            let names = (0..split_fields(&text, sep).len())
                .map(|i| i.to_string())
                .collect();
            return Ok(Header {
                names,
                sep,
                line,
                first_row: Some(text),
                preamble: seen,
            });
        }
        if names_all(&split_fields(&text, sep), options) {
            return Ok(header(&text, line, seen));
        }
        seen += 1;
        first.get_or_insert((text, line));
        // Told where the header is, or not found in a preamble's length: the first line is it.
        if options.skip_lines > 0 || seen as usize >= PREAMBLE_LINES {
            break;
        }
    }
    match first {
        Some((text, line)) => Ok(header(&text, line, 0)),
        None => Err(ImportError::Empty(path.to_path_buf())),
    }
}

fn header(text: &str, line: u64, preamble: u64) -> Header {
    let sep = separator(text);
    let names: Vec<String> = split_fields(text, sep)
        .into_iter()
        .map(str::to_string)
        .collect();
    Header {
        names,
        sep,
        line,
        first_row: None,
        preamble,
    }
}

/// The resolved time source.
pub(super) enum Time {
    /// The column at this index holds seconds.
    Column(usize),
    /// Row number / rate.
    RateHz(f64),
}

/// Where a row's values are: the header, the separator, and the columns the options name.
pub(super) struct Layout {
    /// The header's column names.
    pub(super) header: Vec<String>,
    /// The field separator.
    pub(super) sep: char,
    /// acc x, y, z, gyro x, y, z column indices.
    pub(super) idx: [usize; 6],
    /// Where the time comes from.
    pub(super) time: Time,
    /// The temperature column, if the options name one.
    pub(super) temp: Option<usize>,
}

impl Layout {
    /// Finds the columns of `options` in `header` (case-insensitively) and checks the sample rate.
    pub(super) fn new(
        header: Vec<String>,
        sep: char,
        options: &ImportOptions,
    ) -> Result<Layout, ImportError> {
        // A column by name, or by its index (0-based) where no column has that name.
        let find = |name: &str, option: UserOption| {
            header
                .iter()
                .position(|h| h.eq_ignore_ascii_case(name))
                .or_else(|| name.parse::<usize>().ok().filter(|i| *i < header.len()))
                .ok_or_else(|| ImportError::MissingColumn {
                    name: name.to_string(),
                    found: header.join(", "),
                    option,
                    spelling: options.spelling,
                })
        };
        let mut idx = [0usize; 6];
        for (k, name) in options.columns.iter().enumerate() {
            idx[k] = find(name, UserOption::Columns)?;
        }
        let temp = (options.temp_column.as_deref())
            .map(|name| find(name, UserOption::TempColumn))
            .transpose()?;
        let time = match &options.time {
            TimeSource::Column(name) => Time::Column(find(name, UserOption::TimeColumn)?),
            TimeSource::RateHz(hz) if hz.is_finite() && *hz > 0.0 => Time::RateHz(*hz),
            TimeSource::RateHz(hz) => return Err(ImportError::BadRate(options.spelling, *hz)),
        };
        Ok(Layout {
            header,
            sep,
            idx,
            time,
            temp,
        })
    }

    /// The six values (in the logger's units) and the time of data row `row_index` (0-based),
    /// the text of line `line`.
    /// The row's time alone, no value parsed (`None` where it is no finite number: the whole
    /// row's reading then says what is wrong).
    pub(super) fn time_only(&self, text: &str, row_index: u64) -> Option<f64> {
        let t = match self.time {
            Time::RateHz(hz) => return Some(row_index as f64 / hz),
            Time::Column(i) if self.sep == ' ' => text.split_whitespace().nth(i)?,
            Time::Column(i) => text.split(self.sep).nth(i)?,
        };
        clean(t).parse::<f64>().ok().filter(|t| t.is_finite())
    }

    pub(super) fn parse_row(
        &self,
        text: &str,
        line: u64,
        row_index: u64,
    ) -> Result<([f64; 6], f64, f64), ImportError> {
        let fields = split_fields(text, self.sep);
        if fields.len() < self.header.len() {
            return Err(ImportError::ShortRow {
                line,
                fields: fields.len(),
                header: self.header.len(),
            });
        }
        // An empty cell is a missing value (a logger that writes two kinds of packet in one file
        // leaves the other kind's cells empty): read as NaN, as a "nan" is.
        let number = |i: usize| -> Result<f64, ImportError> {
            if fields[i].is_empty() {
                return Ok(f64::NAN);
            }
            fields[i]
                .parse::<f64>()
                .map_err(|_| ImportError::NotANumber {
                    line,
                    column: self.header[i].clone(),
                    text: fields[i].chars().take(40).collect(),
                })
        };
        let idx = &self.idx;
        let v: [f64; 6] = [
            number(idx[0])?,
            number(idx[1])?,
            number(idx[2])?,
            number(idx[3])?,
            number(idx[4])?,
            number(idx[5])?,
        ];
        let t_s = match self.time {
            Time::Column(i) => number(i)?,
            Time::RateHz(hz) => row_index as f64 / hz,
        };
        // A temperature that is not a number is a missing reading, not a damaged row.
        let temp_c = self
            .temp
            .map_or(f64::NAN, |i| fields[i].parse::<f64>().unwrap_or(f64::NAN));
        Ok((v, t_s, temp_c))
    }
}

/// How the data rows are read.
pub(super) struct Rows<'a> {
    pub(super) layout: &'a Layout,
    pub(super) options: &'a ImportOptions,
    pub(super) header_line: u64,
    /// A header-less file's first line, which is data.
    pub(super) first_row: Option<String>,
    /// The time column's unit, s (1 with a rate).
    pub(super) seconds_per_unit: f64,
}

/// Reads the data rows after the header that `keeper` keeps into a recording (blank lines
/// ignored, rows with no finite time or with both streams' values missing counted and left out; a
/// row with one stream missing is kept for [`fill_streams`]); a survey sets `marker`'s marks.
pub(super) fn read_rows<R: BufRead>(
    r: &mut Counted<R>,
    buf: &mut Vec<u8>,
    rows: &Rows,
    keeper: &mut Keeper,
    marker: Option<&mut Marker<RowsAt>>,
) -> Result<Recording, ImportError> {
    let (mut rec, mut at) = first_rows(rows, keeper)?;
    rows_until(r, buf, rows, keeper, (&mut rec, &mut at), None, marker)?;
    Ok(rec)
}

/// Where a text file's rows are read: the last line and the rows read before, in the file's
/// count, and (at a survey's mark) the rows with a finite time before (`Keeper::row_time`).
#[derive(Clone, Copy, Debug)]
pub(crate) struct RowsAt {
    pub(super) line: u64,
    pub(super) row_index: u64,
    pub(super) timed: usize,
}

/// An empty recording of `rows`, with a header-less file's first row read into it, and where the
/// rows after it begin.
pub(super) fn first_rows(
    rows: &Rows,
    keeper: &mut Keeper,
) -> Result<(Recording, RowsAt), ImportError> {
    let mut rec = Recording {
        acc_unit: Some(rows.options.acc_unit),
        temp_c: rows.layout.temp.map(|_| Vec::new()),
        ..Recording::default()
    };
    let mut at = RowsAt {
        line: rows.header_line,
        row_index: 0,
        timed: 0,
    };
    if let Some(text) = &rows.first_row {
        take_row(text, at.line, &mut at.row_index, rows, keeper, &mut rec)?;
    }
    Ok((rec, at))
}

/// Reads rows into `rec` from where `at` and `r` stand up to the byte `end` (`None`: the end of
/// the file), setting `marker`'s marks on the way.
pub(super) fn rows_until<R: BufRead>(
    r: &mut Counted<R>,
    buf: &mut Vec<u8>,
    rows: &Rows,
    keeper: &mut Keeper,
    (rec, at): (&mut Recording, &mut RowsAt),
    end: Option<u64>,
    mut marker: Option<&mut Marker<RowsAt>>,
) -> Result<(), ImportError> {
    loop {
        if end.is_some_and(|e| r.position() >= e) {
            break;
        }
        if let Some(m) = marker.as_deref_mut().filter(|m| m.due(keeper.timed())) {
            let state = RowsAt {
                timed: keeper.timed(),
                ..*at
            };
            m.set(r.position(), state, keeper.take_times(), keeper.timed());
        }
        at.line += 1;
        let line = at.line;
        let Some(end) = next_line_end(r, buf, line)? else {
            break;
        };
        if end == LineEnd::Overlong {
            // A damaged line costs that line; a file of them is not a logger's CSV.
            if rec.overlong_lines.len() >= MAX_OVERLONG_LINES {
                return Err(ImportError::OverlongLines { line });
            }
            rec.overlong_lines.push(line);
            continue;
        }
        let text = String::from_utf8_lossy(buf);
        if text.trim().is_empty() || is_comment(&text) {
            continue;
        }
        if end == LineEnd::Unterminated {
            // The last line without its line end: a cut-short file, whose last number may have
            // lost digits and still parse.
            rec.unterminated_line = Some(line);
            break;
        }
        take_row(&text, line, &mut at.row_index, rows, keeper, rec)?;
    }
    Ok(())
}

/// One data row's text, read into `rec` as `keeper` says.
fn take_row(
    text: &str,
    line: u64,
    row_index: &mut u64,
    rows: &Rows,
    keeper: &mut Keeper,
    rec: &mut Recording,
) -> Result<(), ImportError> {
    let Rows {
        layout,
        options,
        seconds_per_unit,
        ..
    } = *rows;
    // A window's pass reads only the time of a row outside its span (`Keeper::passes`): the
    // passes before it read the whole row.
    if keeper.passes(|| Some(layout.time_only(text, *row_index)? * seconds_per_unit)) {
        *row_index += 1;
        return Ok(());
    }
    keeper.row_time(|| Some(layout.time_only(text, *row_index)? * seconds_per_unit));
    let (mut v, t_s, temp_c) = layout.parse_row(text, line, *row_index)?;
    for j in 0..3 {
        v[3 + j] -= options.gyro_offset[j];
    }
    *row_index += 1;
    let acc_ok = v[..3].iter().all(|x| x.is_finite());
    let gyro_ok = v[3..].iter().all(|x| x.is_finite());
    if !(acc_ok || gyro_ok) || !t_s.is_finite() {
        rec.skipped_rows += 1;
        if !t_s.is_finite() {
            keeper.untimed_row();
        }
        return Ok(());
    }
    // A row with one stream missing is admitted as its neighbour's accelerometer sample.
    let acc = if acc_ok {
        [v[0], v[1], v[2]]
    } else {
        rec.acc.last().copied().unwrap_or([0.0; 3])
    };
    let admit = keeper.admit(t_s * seconds_per_unit, &acc, rec.len());
    if layout.temp.is_some() {
        keeper.temperature(temp_c);
    }
    match admit {
        Admit::Keep => {
            if !(acc_ok && gyro_ok) {
                // One stream missing in part: that row's stream is missing, nothing else.
                let missing = if acc_ok { 3 } else { 0 };
                v[missing..missing + 3].fill(f64::NAN);
            }
            push_row(rec, v, t_s, temp_c, options.gyro_rad_s_per_unit());
        }
        Admit::Pass => {}
        Admit::TooMany(max) => {
            let time_unit = match layout.time {
                Time::Column(_) => options
                    .time_unit
                    .or_else(|| detect_time_unit(&rec.t_s, options.spelling).ok()),
                Time::RateHz(_) => None,
            };
            return Err(ImportError::TooManyRows { max, time_unit });
        }
    }
    Ok(())
}

/// Rows with one stream missing (a logger that writes accelerometer and gyro packets in rows of
/// their own, or a cell left empty): a row without its gyro takes the rate interpolated in time
/// between the nearest rows before and after it that have one (within [`FILL_ROWS`] rows; else the
/// row is left out), and rows with the gyro alone are left out once they have served for that.
/// Returns what was done, for the user.
pub(super) fn fill_streams(rec: &mut Recording) -> Option<Note> {
    let gyro_ok = |v: &[f64; 3]| v.iter().all(|x| x.is_finite());
    let acc_ok = |v: &[f64; 3]| v.iter().all(|x| x.is_finite());
    let no_gyro = rec.gyro_rad_s.iter().filter(|g| !gyro_ok(g)).count();
    let no_acc = rec.acc.iter().filter(|a| !acc_ok(a)).count();
    if no_gyro + no_acc == 0 {
        return None;
    }
    let n = rec.len();
    let with_gyro: Vec<usize> = (0..n).filter(|&i| gyro_ok(&rec.gyro_rad_s[i])).collect();
    let mut keep = vec![true; n];
    let mut unfilled = 0;
    for i in 0..n {
        if !acc_ok(&rec.acc[i]) {
            keep[i] = false;
            continue;
        }
        if gyro_ok(&rec.gyro_rad_s[i]) {
            continue;
        }
        let k = with_gyro.partition_point(|&j| j < i);
        let near = |j: usize| j.abs_diff(i) <= FILL_ROWS;
        match (
            k.checked_sub(1).map(|k| with_gyro[k]),
            with_gyro.get(k).copied(),
        ) {
            (Some(a), Some(b)) if near(a) && near(b) => {
                let (ta, tb, t) = (rec.t_s[a], rec.t_s[b], rec.t_s[i]);
                let f = if tb > ta {
                    ((t - ta) / (tb - ta)).clamp(0.0, 1.0)
                } else {
                    0.5
                };
                let (ga, gb) = (rec.gyro_rad_s[a], rec.gyro_rad_s[b]);
                rec.gyro_rad_s[i] = core::array::from_fn(|j| ga[j] + f * (gb[j] - ga[j]));
            }
            _ => {
                keep[i] = false;
                unfilled += 1;
            }
        }
    }
    let mut k = 0;
    rec.t_s.retain(|_| (keep[k], k += 1).0);
    k = 0;
    rec.acc.retain(|_| (keep[k], k += 1).0);
    k = 0;
    rec.gyro_rad_s.retain(|_| (keep[k], k += 1).0);
    if let Some(t) = &mut rec.temp_c {
        k = 0;
        t.retain(|_| (keep[k], k += 1).0);
    }
    Some(Note::GyroFilled {
        no_gyro,
        no_acc,
        unfilled,
        fill_rows: FILL_ROWS,
    })
}

/// A row without its gyro takes it from rows at most this many rows away.
const FILL_ROWS: usize = 16;

/// Appends a row of finite values `v` at `t_s` (temperature `temp_c`, where the recording has
/// one) to `rec`, its gyro converted with `gyro_scale` (rad/s per unit). A repeated or earlier
/// time stamp is kept here and mended by `repair` once the file is read.
pub(super) fn push_row(rec: &mut Recording, v: [f64; 6], t_s: f64, temp_c: f64, gyro_scale: f64) {
    if let Some(t) = &mut rec.temp_c {
        t.push(temp_c);
    }
    rec.t_s.push(t_s);
    rec.acc.push([v[0], v[1], v[2]]);
    rec.gyro_rad_s
        .push([v[3] * gyro_scale, v[4] * gyro_scale, v[5] * gyro_scale]);
}
