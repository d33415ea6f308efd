//! Writing a result file atomically and never over an existing file unless asked.
//!
//! The content goes to a temporary file next to the target (same directory, so the final step is a
//! rename on one file system); it is synced and then moved into place. Without `force` the move is a
//! hard link, which fails if the target appeared meanwhile, so an existing file is never replaced
//! even by a race. An error or a drop before [`OutputFile::commit`] removes the temporary file and
//! leaves the target as it was.

use std::fs::File;
use std::io::{BufWriter, Write};
use std::path::{Path, PathBuf};

/// Why a result file could not be written.
#[derive(Debug)]
pub enum OutputFileError {
    /// The target exists and overwriting was not allowed.
    Exists(PathBuf),
    /// A file system operation failed.
    Io(PathBuf, std::io::Error),
}

impl std::fmt::Display for OutputFileError {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match self {
            OutputFileError::Exists(p) => write!(
                f,
                "{} already exists; choose another file or allow overwriting it (--force)",
                p.display()
            ),
            OutputFileError::Io(p, e) => write!(f, "cannot write {}: {e}", p.display()),
        }
    }
}

impl std::error::Error for OutputFileError {}

/// A file being written; it appears at its path only on [`OutputFile::commit`].
pub struct OutputFile {
    target: PathBuf,
    temp: PathBuf,
    writer: Option<BufWriter<File>>,
    force: bool,
}

impl OutputFile {
    /// Starts writing `target`. Fails at once if it exists and `force` is false, before any work.
    pub fn create(target: &Path, force: bool) -> Result<OutputFile, OutputFileError> {
        if !force && target.exists() {
            return Err(OutputFileError::Exists(target.to_path_buf()));
        }
        let name = target
            .file_name()
            .map_or_else(|| "output".into(), |n| n.to_string_lossy().into_owned());
        let temp = target.with_file_name(format!(".{name}.{}.partial", std::process::id()));
        let file = File::create(&temp).map_err(|e| OutputFileError::Io(temp.clone(), e))?;
        Ok(OutputFile {
            target: target.to_path_buf(),
            temp,
            writer: Some(BufWriter::with_capacity(1 << 16, file)),
            force,
        })
    }

    /// The final path.
    pub fn path(&self) -> &Path {
        &self.target
    }

    /// Maps a write error to this file's error.
    pub fn io_error(&self, e: std::io::Error) -> OutputFileError {
        OutputFileError::Io(self.target.clone(), e)
    }

    /// Syncs the content and moves it into place.
    pub fn commit(mut self) -> Result<(), OutputFileError> {
        let io = |p: &Path, e| OutputFileError::Io(p.to_path_buf(), e);
        if let Some(w) = self.writer.take() {
            let file = w.into_inner().map_err(|e| io(&self.temp, e.into_error()))?;
            file.sync_all().map_err(|e| io(&self.temp, e))?;
        }
        if self.force {
            std::fs::rename(&self.temp, &self.target).map_err(|e| io(&self.target, e))?;
        } else {
            match std::fs::hard_link(&self.temp, &self.target) {
                Ok(()) => {}
                Err(e) if e.kind() == std::io::ErrorKind::AlreadyExists => {
                    return Err(OutputFileError::Exists(self.target.clone()));
                }
                Err(e) => return Err(io(&self.target, e)),
            }
            std::fs::remove_file(&self.temp).map_err(|e| io(&self.temp, e))?;
        }
        Ok(())
    }
}

impl Write for OutputFile {
    fn write(&mut self, buf: &[u8]) -> std::io::Result<usize> {
        match &mut self.writer {
            Some(w) => w.write(buf),
            None => Err(std::io::ErrorKind::BrokenPipe.into()),
        }
    }
    fn flush(&mut self) -> std::io::Result<()> {
        match &mut self.writer {
            Some(w) => w.flush(),
            None => Ok(()),
        }
    }
}

impl Drop for OutputFile {
    fn drop(&mut self) {
        // Committed: the temporary name is gone already (renamed or unlinked); otherwise discard it.
        drop(self.writer.take());
        let _ = std::fs::remove_file(&self.temp);
    }
}

/// Writes `bytes` to `target` atomically (see the module documentation).
pub fn write_atomic(target: &Path, bytes: &[u8], force: bool) -> Result<(), OutputFileError> {
    let mut f = OutputFile::create(target, force)?;
    f.write_all(bytes).map_err(|e| f.io_error(e))?;
    f.commit()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn never_overwrites_without_force_and_leaves_no_temporary() {
        let dir = tempfile::tempdir().unwrap();
        let p = dir.path().join("a.csv");
        write_atomic(&p, b"one", false).unwrap();
        assert!(matches!(
            write_atomic(&p, b"two", false),
            Err(OutputFileError::Exists(_))
        ));
        assert_eq!(std::fs::read(&p).unwrap(), b"one");
        write_atomic(&p, b"three", true).unwrap();
        assert_eq!(std::fs::read(&p).unwrap(), b"three");
        // A writer dropped before commit leaves the target alone and no partial file.
        let mut f = OutputFile::create(&p, true).unwrap();
        f.write_all(b"half").unwrap();
        drop(f);
        assert_eq!(std::fs::read(&p).unwrap(), b"three");
        assert_eq!(std::fs::read_dir(dir.path()).unwrap().count(), 1);
    }
}
