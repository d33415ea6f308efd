//! A text file's rows: its header and separator, where the options' columns are, and each data row
//! parsed and kept as the [`Keeper`] says.

use super::lines::{next_line, next_line_end, LineEnd};
use super::time::detect_time_unit;
use super::{ImportError, ImportOptions, Recording, TimeSource, MAX_OVERLONG_LINES};
use crate::session::logs::keep::{Admit, Keeper};
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

/// Reads the header line (after any blank or `#` comment lines): its column names (a byte-order mark
/// and quotes removed), the field separator it uses, and its line number.
pub(super) fn read_header<R: BufRead>(
    r: &mut R,
    buf: &mut Vec<u8>,
    path: &Path,
) -> Result<(Vec<String>, char, u64), ImportError> {
    let mut line = 0u64;
    let header_text = loop {
        line += 1;
        if !next_line(r, buf, line)? {
            return Err(ImportError::Empty(path.to_path_buf()));
        }
        let text = String::from_utf8_lossy(buf)
            .trim_start_matches('\u{feff}')
            .to_string();
        if !text.trim().is_empty() && !is_comment(&text) {
            break text;
        }
    };
    let sep = separator(&header_text);
    let header: Vec<String> = split_fields(&header_text, sep)
        .into_iter()
        .map(str::to_string)
        .collect();
    Ok((header, sep, line))
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
        let find = |name: &str| {
            header
                .iter()
                .position(|h| h.eq_ignore_ascii_case(name))
                .ok_or_else(|| ImportError::MissingColumn {
                    name: name.to_string(),
                    found: header.join(", "),
                    spelling: options.spelling,
                })
        };
        let mut idx = [0usize; 6];
        for (k, name) in options.columns.iter().enumerate() {
            idx[k] = find(name)?;
        }
        let temp = options.temp_column.as_deref().map(find).transpose()?;
        let time = match &options.time {
            TimeSource::Column(name) => Time::Column(find(name)?),
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
        let number = |i: usize| -> Result<f64, ImportError> {
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
    /// The time column's unit, s (1 with a rate).
    pub(super) seconds_per_unit: f64,
}

/// Reads the data rows after the header that `keeper` keeps into a recording (blank lines
/// ignored, rows with a value that is not finite counted and left out).
pub(super) fn read_rows<R: BufRead>(
    r: &mut R,
    buf: &mut Vec<u8>,
    rows: &Rows,
    keeper: &mut Keeper,
) -> Result<Recording, ImportError> {
    let Rows {
        layout,
        options,
        header_line,
        seconds_per_unit,
    } = *rows;
    let gyro_scale = options.gyro_rad_s_per_unit();
    let mut rec = Recording {
        acc_unit: Some(options.acc_unit),
        temp_c: layout.temp.map(|_| Vec::new()),
        ..Recording::default()
    };
    let mut line = header_line;
    let mut row_index = 0u64;
    loop {
        line += 1;
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
        // A window's pass reads only the time of a row outside its span (`Keeper::passes`): the
        // passes before it read the whole row.
        if keeper.passes(|| Some(layout.time_only(&text, row_index)? * seconds_per_unit)) {
            row_index += 1;
            continue;
        }
        let (mut v, t_s, temp_c) = layout.parse_row(&text, line, row_index)?;
        for j in 0..3 {
            v[3 + j] -= options.gyro_offset[j];
        }
        row_index += 1;
        if !v.iter().all(|x| x.is_finite()) || !t_s.is_finite() {
            rec.skipped_rows += 1;
            continue;
        }
        let acc = [v[0], v[1], v[2]];
        let admit = keeper.admit(t_s * seconds_per_unit, &acc, rec.len());
        if layout.temp.is_some() {
            keeper.temperature(temp_c);
        }
        match admit {
            Admit::Keep => push_row(&mut rec, v, t_s, temp_c, gyro_scale),
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
    }
    Ok(rec)
}

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
