//! What the reader tells the user about a recording it read, the same for every use of it
//! (`segment`, `apply`) and every format: rows left out, damaged or cut-short lines, the time
//! stamps repaired (`crate::session::repair`) and the jumps left in them.

use super::Recording;
use crate::session::note::Note;
use crate::spelling::UserOption;
use std::fmt;

/// Where a repair's places are counted from.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Places {
    /// The recording is the whole file: a repair names its samples' places in it.
    InFile,
    /// The recording is one window of a longer file (`super::super::logs::read_log_windows`):
    /// its repairs and time jumps are said on the log's scale (`LogScale`), not here.
    InWindow,
}

impl Recording {
    /// The reader's warnings about this recording: rows left out, damaged or cut-short lines, the
    /// time stamps repaired, time jumps.
    pub fn reader_warnings(&self, places: Places) -> Vec<Note> {
        let mut warnings = self.read_notes.clone();
        if self.skipped_rows > 0 {
            warnings.push(Note::SkippedRows {
                count: self.skipped_rows,
            });
        }
        if let Some(&first) = self.overlong_lines.first() {
            warnings.push(Note::OverlongLines {
                count: self.overlong_lines.len(),
                first,
            });
        }
        if let Some(line) = self.unterminated_line {
            warnings.push(Note::Unterminated { line });
        }
        if places == Places::InFile {
            for (what, repairs) in &self.time_repairs {
                warnings.extend(Note::time_repairs(Some(what), repairs));
            }
            warnings.extend(self.time_jumps());
        }
        warnings
    }
}

impl Note {
    /// The notes of a text file's reader.
    pub(in crate::session) fn fmt_text(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            Note::SkippedRows { count } => {
                write!(f, "{count} row(s) with NaN or infinite values left out")
            }
            Note::OverlongLines { count, first } => write!(
                f,
                "{count} line(s) longer than {} bytes left out as damaged (line {first}{})",
                super::MAX_LINE_BYTES,
                if *count > 1 { ", …" } else { "" }
            ),
            Note::Unterminated { line } => write!(
                f,
                "line {line}, the last, has no line end: the file was cut short; that line is left \
                 out"
            ),
            Note::Preamble {
                lines,
                header_line,
                spelling,
            } => write!(
                f,
                "{lines} line(s) before the header on line {header_line} skipped (a logger's \
                 preamble; {} to say how many)",
                spelling.given(UserOption::SkipLines, "N")
            ),
            Note::NoHeader { line } => write!(
                f,
                "no header: line {line} is data, its columns taken by index"
            ),
            Note::GyroFilled {
                no_gyro,
                no_acc,
                unfilled,
                fill_rows,
            } => {
                write!(
                    f,
                    "{no_gyro} row(s) without gyro values and {no_acc} with the gyro's alone (a \
                     logger writing each sensor's packets in rows of their own, or cells left \
                     empty): the accelerometer's rows take the gyro's rate interpolated from the \
                     nearest rows that have one"
                )?;
                if *unfilled > 0 {
                    write!(
                        f,
                        " ({unfilled} with none within {fill_rows} rows left out)"
                    )?;
                }
                Ok(())
            }
            Note::GyroMidScale {
                mid,
                bits,
                bias_dps,
                offset,
                spelling,
            } => write!(
                f,
                "every gyro count sits near {mid} on all three axes, the mid-scale of a {bits}-bit \
                 unsigned output: read as a bias of {bias_dps:.0} °/s, more than a calibration \
                 can hold; if that is the gyro's zero rate, give {}",
                spelling.given(UserOption::GyroOffset, offset)
            ),
            _ => Ok(()),
        }
    }
}
