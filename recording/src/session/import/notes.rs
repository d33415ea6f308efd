//! What the reader tells the user about a recording it read, the same for every use of it
//! (`segment`, `apply`) and every format: rows left out, damaged or cut-short lines, the time
//! stamps repaired (`crate::session::repair`) and the jumps left in them.

use super::Recording;
use crate::session::note::Note;

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
