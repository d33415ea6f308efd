//! A long text log's windows read from the survey's marks (`crate::session::logs::resume`): the
//! rows of the stretches whose times reach a window, each stretch begun at its line with the
//! line and row counts of the whole file, and what is said of the whole file taken from the
//! survey.

use super::lines::Counted;
use super::rows::{first_rows, rows_until, Rows, RowsAt};
use super::{ImportError, Recording};
use crate::session::logs::keep::{Keep, Keeper};
use crate::session::logs::resume::{stretches, Mark, Marker};
use std::io::{BufRead, Seek};
use std::path::Path;
use std::sync::Arc;

/// What a survey of a text file leaves for the windows' passes: its marks, and what a pass over
/// the whole file says whatever its window (the lines too long or cut short, the rows without a
/// finite time).
#[derive(Debug)]
pub(crate) struct Resume {
    marks: Vec<Mark<RowsAt>>,
    overlong_lines: Vec<u64>,
    unterminated_line: Option<u64>,
    untimed: usize,
}

/// The rows of a survey (`keeper` keeps [`Keep::Survey`]), its marks handed to the survey's
/// report; any other pass's rows.
pub(super) fn read_surveying<R: BufRead>(
    r: &mut Counted<R>,
    buf: &mut Vec<u8>,
    rows: &Rows,
    keeper: &mut Keeper,
) -> Result<Recording, ImportError> {
    let mut marker = Marker::for_keep(keeper.keep());
    let rec = super::rows::read_rows(r, buf, rows, keeper, marker.as_mut())?;
    if let (Some(marker), Keep::Survey(report)) = (marker, keeper.keep().clone()) {
        let resume = Resume {
            marks: marker.finish(keeper.take_times()),
            overlong_lines: rec.overlong_lines.clone(),
            unterminated_line: rec.unterminated_line,
            untimed: keeper.untimed(),
        };
        if let Ok(mut r) = report.lock() {
            r.resume = Some(Arc::new(crate::session::logs::resume::Resume::Text(resume)));
        }
    }
    Ok(rec)
}

/// The rows of one window (`keeper` keeps a [`Keep::Span`]) read from the stretches the survey's
/// `resume` marks for its times: the rows and counts a pass over the whole file gives.
pub(super) fn read_stretches<R: BufRead + Seek>(
    r: &mut Counted<R>,
    buf: &mut Vec<u8>,
    rows: &Rows,
    keeper: &mut Keeper,
    resume: &Resume,
    path: &Path,
) -> Result<Recording, ImportError> {
    let (mut rec, mut at) = first_rows(rows, keeper)?;
    let (lo, hi) = keeper.keep().reach();
    for (i, end) in stretches(&resume.marks, lo, hi) {
        // The first stretch begins where the header (and a header-less file's first row) ends.
        if i > 0 {
            let mark = &resume.marks[i];
            r.seek_to(mark.offset).map_err(|source| ImportError::Io {
                path: path.to_path_buf(),
                source,
            })?;
            at = mark.state;
            keeper.resume_count(mark.state.timed);
        }
        rows_until(r, buf, rows, keeper, (&mut rec, &mut at), end, None)?;
    }
    // A row without a finite time is counted by every window's pass.
    rec.skipped_rows = rec.skipped_rows - keeper.untimed() + resume.untimed;
    rec.overlong_lines.clone_from(&resume.overlong_lines);
    rec.unterminated_line = resume.unterminated_line;
    Ok(rec)
}
