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
    /// `--force` would replace a directory holding files no command of this tool writes.
    Foreign(PathBuf, Vec<String>),
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
            OutputFileError::Foreign(p, names) => write!(
                f,
                "{} holds {} that this tool did not write ({}); --force replaces a result directory \
                 whole, so choose another directory",
                p.display(),
                if names.len() == 1 { "an entry" } else { "entries" },
                names.join(", ")
            ),
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

/// Extensions of the files this tool writes into a result directory (sessions, calibrations,
/// reports, figures); anything else in a directory that `--force` would replace is refused.
const OWN_EXTENSIONS: [&str; 8] = ["toml", "csv", "bin", "svg", "png", "html", "md", "json"];

/// A result directory built beside its target and moved into place whole, so that an interrupted
/// run (an error, Ctrl-C) leaves either the earlier directory or none, never a half-written one that
/// a later command accepts, and `--force` leaves no stale file of an earlier run. The directory is
/// built in `.NAME.PID.partial` next to the target; an earlier directory is moved aside and removed
/// only after the new one is in place.
pub struct OutputDir {
    target: PathBuf,
    temp: PathBuf,
    force: bool,
    committed: bool,
}

impl OutputDir {
    /// Starts building `target`. Fails at once, before any work, if it exists and `force` is false,
    /// or if it holds anything this tool does not write (a directory, a file of another kind).
    pub fn create(target: &Path, force: bool) -> Result<OutputDir, OutputFileError> {
        let io = |p: &Path| {
            let p = p.to_path_buf();
            move |e| OutputFileError::Io(p, e)
        };
        if target.exists() && !is_empty_dir(target) {
            if !force {
                return Err(OutputFileError::Exists(target.to_path_buf()));
            }
            let foreign = foreign_entries(target).map_err(io(target))?;
            if !foreign.is_empty() {
                return Err(OutputFileError::Foreign(target.to_path_buf(), foreign));
            }
        }
        let name = target
            .file_name()
            .map_or_else(|| "output".into(), |n| n.to_string_lossy().into_owned());
        let temp = target.with_file_name(format!(".{name}.{}.partial", std::process::id()));
        if temp.exists() {
            std::fs::remove_dir_all(&temp).map_err(io(&temp))?;
        }
        std::fs::create_dir_all(&temp).map_err(io(&temp))?;
        Ok(OutputDir {
            target: target.to_path_buf(),
            temp,
            force,
            committed: false,
        })
    }

    /// Where to write the directory's files until [`OutputDir::commit`].
    pub fn path(&self) -> &Path {
        &self.temp
    }

    /// The final path.
    pub fn target(&self) -> &Path {
        &self.target
    }

    /// Moves the built directory into place (replacing the earlier one when `force` was given).
    pub fn commit(mut self) -> Result<(), OutputFileError> {
        let io = |p: &Path, e| OutputFileError::Io(p.to_path_buf(), e);
        let old = self.temp.with_extension("old");
        if is_empty_dir(&self.target) {
            std::fs::remove_dir(&self.target).map_err(|e| io(&self.target, e))?;
        }
        let replacing = self.target.exists();
        if replacing {
            if !self.force {
                return Err(OutputFileError::Exists(self.target.clone()));
            }
            std::fs::rename(&self.target, &old).map_err(|e| io(&self.target, e))?;
        }
        std::fs::rename(&self.temp, &self.target).map_err(|e| io(&self.target, e))?;
        self.committed = true;
        if replacing {
            std::fs::remove_dir_all(&old).map_err(|e| io(&old, e))?;
        }
        Ok(())
    }
}

impl Drop for OutputDir {
    fn drop(&mut self) {
        if !self.committed {
            let _ = std::fs::remove_dir_all(&self.temp);
        }
    }
}

/// An existing directory with nothing in it (made ahead of the command: nothing to lose).
fn is_empty_dir(p: &Path) -> bool {
    std::fs::read_dir(p).is_ok_and(|mut d| d.next().is_none())
}

/// The entries of `dir` that no command of this tool writes.
fn foreign_entries(dir: &Path) -> std::io::Result<Vec<String>> {
    let mut foreign = Vec::new();
    for entry in std::fs::read_dir(dir)? {
        let entry = entry?;
        let name = entry.file_name().to_string_lossy().into_owned();
        let own = entry.file_type()?.is_file()
            && Path::new(&name)
                .extension()
                .and_then(|e| e.to_str())
                .is_some_and(|e| OWN_EXTENSIONS.contains(&e));
        if !own {
            foreign.push(name);
        }
    }
    foreign.sort();
    Ok(foreign)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_directory_is_replaced_whole_or_not_at_all() {
        let root = tempfile::tempdir().unwrap();
        let target = root.path().join("session");
        std::fs::create_dir(&target).unwrap();
        // Not there yet (or empty): built aside, appears on commit.
        let d = OutputDir::create(&target, false).unwrap();
        std::fs::write(d.path().join("plan.toml"), "one").unwrap();
        std::fs::write(d.path().join("gyro.toml"), "stale").unwrap();
        assert!(!target.join("plan.toml").exists());
        d.commit().unwrap();
        assert_eq!(std::fs::read(target.join("plan.toml")).unwrap(), b"one");
        // Without force: refused before any work.
        assert!(matches!(
            OutputDir::create(&target, false),
            Err(OutputFileError::Exists(_))
        ));
        // Dropped before commit (an error on the way): the earlier directory is untouched.
        let d = OutputDir::create(&target, true).unwrap();
        std::fs::write(d.path().join("plan.toml"), "two").unwrap();
        drop(d);
        assert_eq!(std::fs::read(target.join("plan.toml")).unwrap(), b"one");
        // Replaced whole: the earlier run's other files are gone.
        let d = OutputDir::create(&target, true).unwrap();
        std::fs::write(d.path().join("plan.toml"), "three").unwrap();
        d.commit().unwrap();
        assert_eq!(std::fs::read(target.join("plan.toml")).unwrap(), b"three");
        assert!(!target.join("gyro.toml").exists());
        assert_eq!(std::fs::read_dir(root.path()).unwrap().count(), 1);
        // A directory with files of another kind is never replaced.
        std::fs::write(target.join("notes.txt"), "mine").unwrap();
        match OutputDir::create(&target, true) {
            Err(OutputFileError::Foreign(_, names)) => assert_eq!(names, ["notes.txt"]),
            other => panic!("{:?}", other.map(|_| ())),
        }
    }

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
