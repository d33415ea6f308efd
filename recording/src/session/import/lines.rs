//! A logger CSV's lines, bounded: a line is read up to [`MAX_LINE_BYTES`]; a longer one is skipped
//! to its line end (a damaged line, not the rest of the log) and one with no end within
//! [`MAX_SKIPPED_LINE_BYTES`] refuses the file (docs/robustness.md, "Damaged time stamps").

use super::{ImportError, MAX_LINE_BYTES};
use std::io::{BufRead, Read, Seek, SeekFrom};
use std::path::PathBuf;

/// A reader that counts the bytes taken from it: where a line begins in the file, for the marks a
/// survey sets (`crate::session::logs::resume`).
#[derive(Debug)]
pub(crate) struct Counted<R> {
    inner: R,
    position: u64,
}

impl<R> Counted<R> {
    /// `inner`, whose next byte is the file's byte `position`.
    pub(crate) fn new(inner: R, position: u64) -> Counted<R> {
        Counted { inner, position }
    }

    /// The file's byte the next read takes.
    pub(crate) fn position(&self) -> u64 {
        self.position
    }
}

impl<R: Read> Read for Counted<R> {
    fn read(&mut self, buf: &mut [u8]) -> std::io::Result<usize> {
        let n = self.inner.read(buf)?;
        self.position += n as u64;
        Ok(n)
    }
}

impl<R: BufRead> BufRead for Counted<R> {
    fn fill_buf(&mut self) -> std::io::Result<&[u8]> {
        self.inner.fill_buf()
    }

    fn consume(&mut self, amt: usize) {
        self.position += amt as u64;
        self.inner.consume(amt);
    }
}

impl<R: Seek> Counted<R> {
    /// Goes to the file's byte `position`.
    pub(crate) fn seek_to(&mut self, position: u64) -> std::io::Result<()> {
        self.position = self.inner.seek(SeekFrom::Start(position))?;
        Ok(())
    }
}

/// Reads the next line (without its line end) into `buf`; `Ok(false)` at the end of the input.
pub(super) fn next_line<R: BufRead>(
    r: &mut R,
    buf: &mut Vec<u8>,
    line: u64,
) -> Result<bool, ImportError> {
    match next_line_end(r, buf, line)? {
        Some(LineEnd::Overlong) => Err(ImportError::LineTooLong { line }),
        read => Ok(read.is_some()),
    }
}

/// How a line read by [`next_line_end`] ended.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(super) enum LineEnd {
    /// At its line end.
    Ended,
    /// At the end of the file (a cut-short recording's last line).
    Unterminated,
    /// Longer than [`MAX_LINE_BYTES`]: skipped up to its line end, `buf` empty (a damaged line).
    Overlong,
}

/// How far past [`MAX_LINE_BYTES`] an overlong line is skipped to find its end; a file with no
/// line end that far is not a logger's CSV (`/dev/zero`, a binary file).
const MAX_SKIPPED_LINE_BYTES: u64 = 16 << 20;

/// Skips to the next line end, reading at most [`MAX_SKIPPED_LINE_BYTES`]; `false` when the file
/// or that limit ends first.
fn skip_line<R: BufRead>(r: &mut R) -> std::io::Result<bool> {
    let mut skipped = 0u64;
    while skipped < MAX_SKIPPED_LINE_BYTES {
        let buf = r.fill_buf()?;
        if buf.is_empty() {
            return Ok(false);
        }
        if let Some(i) = buf.iter().position(|&b| b == b'\n') {
            r.consume(i + 1);
            return Ok(true);
        }
        let n = buf.len();
        r.consume(n);
        skipped += n as u64;
    }
    Ok(false)
}

/// [`next_line`], saying how the line ended.
pub(super) fn next_line_end<R: BufRead>(
    r: &mut R,
    buf: &mut Vec<u8>,
    line: u64,
) -> Result<Option<LineEnd>, ImportError> {
    let io = |source| ImportError::Io {
        path: PathBuf::new(),
        source,
    };
    buf.clear();
    let n = r
        .by_ref()
        .take(MAX_LINE_BYTES as u64 + 1)
        .read_until(b'\n', buf)
        .map_err(|source| ImportError::Io {
            path: PathBuf::new(),
            source,
        })?;
    if n == 0 {
        return Ok(None);
    }
    let ended = buf.last() == Some(&b'\n');
    if ended {
        buf.pop();
    } else if buf.len() > MAX_LINE_BYTES {
        buf.clear();
        return match skip_line(r).map_err(io)? {
            true => Ok(Some(LineEnd::Overlong)),
            false => Err(ImportError::LineTooLong { line }),
        };
    }
    if buf.last() == Some(&b'\r') {
        buf.pop();
    }
    Ok(Some(if ended {
        LineEnd::Ended
    } else {
        LineEnd::Unterminated
    }))
}
