//! What the reader tells the user about a recording it read, the same for every use of it
//! (`segment`, `apply`) and every format: rows left out, damaged or cut-short lines, the time
//! stamps repaired (`crate::session::repair`) and the jumps left in them.

use super::{Recording, MAX_LINE_BYTES};

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
    pub fn reader_warnings(&self, places: Places) -> Vec<String> {
        let mut warnings = self.read_notes.clone();
        if self.skipped_rows > 0 {
            warnings.push(format!(
                "{} row(s) with NaN or infinite values left out",
                self.skipped_rows
            ));
        }
        if let Some(first) = self.overlong_lines.first() {
            warnings.push(format!(
                "{} line(s) longer than {} bytes left out as damaged (line {first}{})",
                self.overlong_lines.len(),
                MAX_LINE_BYTES,
                if self.overlong_lines.len() > 1 {
                    ", …"
                } else {
                    ""
                }
            ));
        }
        if let Some(line) = self.unterminated_line {
            warnings.push(format!(
                "line {line}, the last, has no line end: the file was cut short; that line is left \
                 out"
            ));
        }
        if places == Places::InFile {
            for (what, repairs) in &self.time_repairs {
                warnings.extend(repairs.describe(what));
            }
            warnings.extend(self.time_jumps());
        }
        warnings
    }
}
