//! Writing a result file atomically and never over an existing file unless asked.
//!
//! The content goes to a temporary file next to the target (same directory, so the final step is a
//! rename on one file system); it is synced and then moved into place. Without `force` the move is a
//! hard link, which fails if the target appeared meanwhile, so an existing file is never replaced
//! even by a race. An error or a drop before [`OutputFile::commit`] removes the temporary file and
//! leaves the target as it was.
//!
//! A result directory ([`OutputDir`], `host batch --out`) is built the same way: whole, in a hidden
//! directory beside the target, and renamed into place at the end, so an interrupted run (a Ctrl-C)
//! leaves the target as it was and only a `.NAME.PID.partial` directory that no command reads.

use std::fs::File;
use std::io::{BufWriter, Write};
use std::path::{Path, PathBuf};

/// Why a result file could not be written.
#[derive(Debug, thiserror::Error)]
pub enum OutputFileError {
    /// The target exists and overwriting was not allowed.
    #[error(
        "{} already exists; choose another name or allow replacing it (--force)",
        .0.display()
    )]
    Exists(PathBuf),
    /// A file system operation failed.
    #[error("cannot write {}", .0.display())]
    Io(PathBuf, #[source] std::io::Error),
    /// A directory to replace holds files that are not an earlier result of this command (it lacks
    /// the named marker file): `--force` never replaces such a directory.
    #[error(
        "{} holds files that are not an earlier result of this command (it has no {}); \
         --force replaces only such a result: choose another output directory",
        .0.display(),
        .1
    )]
    NotOurs(PathBuf, &'static str),
    /// `--force` would replace a directory that also holds files no command of this tool writes.
    #[error(
        "{} holds {} that this tool did not write ({}); --force replaces a result directory \
         whole, so choose another directory",
        .0.display(),
        if .1.len() == 1 { "a file" } else { "files" },
        .1.join(", ")
    )]
    Foreign(PathBuf, Vec<String>),
}

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
        let temp = partial_beside(target);
        let file = File::create(&temp).map_err(|e| OutputFileError::Io(temp.clone(), e))?;
        Ok(OutputFile {
            target: target.to_path_buf(),
            temp,
            writer: Some(BufWriter::with_capacity(1 << 16, file)),
            force,
        })
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

/// The temporary name beside `target` that a result is built under: `.NAME.PID.partial`, hidden,
/// in the same directory (so the final rename stays on one file system), and this process's own.
fn partial_beside(target: &Path) -> PathBuf {
    let name = target
        .file_name()
        .map_or_else(|| "output".into(), |n| n.to_string_lossy().into_owned());
    target.with_file_name(format!(".{name}.{}.partial", std::process::id()))
}

/// Replaces `target` whole or not at all, for a writer that takes a path (a plotting backend):
/// `write` writes a temporary file beside it whose name ends as the target's does (the backend
/// tells the format by the extension), renamed over `target` when complete and removed
/// otherwise. `io` maps a failed rename to the writer's error.
pub fn replace_through_path<E>(
    target: &Path,
    write: impl FnOnce(&Path) -> Result<(), E>,
    io: impl FnOnce(std::io::Error) -> E,
) -> Result<(), E> {
    let mut temp = partial_beside(target).into_os_string();
    if let Some(ext) = target.extension() {
        temp.push(".");
        temp.push(ext);
    }
    let temp = PathBuf::from(temp);
    let done = write(&temp).and_then(|()| std::fs::rename(&temp, target).map_err(io));
    if done.is_err() {
        let _ = std::fs::remove_file(&temp);
    }
    done
}

/// A result directory being built in a hidden directory beside its target; it appears at the
/// target, whole, only on [`OutputDir::commit`] (see the module documentation). A drop before that
/// removes what was built.
pub struct OutputDir {
    target: PathBuf,
    temp: PathBuf,
    force: bool,
    marker: &'static str,
    committed: bool,
}

/// Whether `target` may be replaced: it does not exist or is an empty directory; or `force` and it
/// is a directory with `marker` in it (an earlier result of the same command).
fn check_replaceable(
    target: &Path,
    force: bool,
    marker: &'static str,
) -> Result<(), OutputFileError> {
    let io = |e| OutputFileError::Io(target.to_path_buf(), e);
    let mut entries = match std::fs::read_dir(target) {
        Ok(entries) => entries,
        Err(e) if e.kind() == std::io::ErrorKind::NotFound => return Ok(()),
        // Not a directory (a file): never ours to replace.
        Err(_) if target.exists() && force => {
            return Err(OutputFileError::NotOurs(target.to_path_buf(), marker))
        }
        Err(_) if target.exists() => return Err(OutputFileError::Exists(target.to_path_buf())),
        Err(e) => return Err(io(e)),
    };
    if entries.next().is_none() {
        return Ok(());
    }
    if !force {
        return Err(OutputFileError::Exists(target.to_path_buf()));
    }
    if !target.join(marker).is_file() {
        return Err(OutputFileError::NotOurs(target.to_path_buf(), marker));
    }
    let foreign = foreign_files(target).map_err(io)?;
    if !foreign.is_empty() {
        return Err(OutputFileError::Foreign(target.to_path_buf(), foreign));
    }
    Ok(())
}

/// Extensions of the files this tool writes into a result directory (sessions, calibrations,
/// reports, figures, summaries).
const OWN_EXTENSIONS: [&str; 8] = ["toml", "csv", "bin", "svg", "png", "html", "md", "json"];

/// The files directly in `dir` of a kind no command of this tool writes (a user's notes beside an
/// earlier result): a directory holding one is never replaced.
fn foreign_files(dir: &Path) -> std::io::Result<Vec<String>> {
    let mut foreign = Vec::new();
    for entry in std::fs::read_dir(dir)? {
        let entry = entry?;
        let name = entry.file_name().to_string_lossy().into_owned();
        let own = Path::new(&name)
            .extension()
            .and_then(|e| e.to_str())
            .is_some_and(|e| OWN_EXTENSIONS.contains(&e));
        if entry.file_type()?.is_file() && !own {
            foreign.push(name);
        }
    }
    foreign.sort();
    Ok(foreign)
}

impl OutputDir {
    /// Starts building `target`. Refuses at once, before any work, when `target` exists and is not
    /// an empty directory, unless `force` and it holds `marker` (the file every result of the
    /// command has, e.g. `summary.json`): `--force` never replaces a directory of other files.
    pub fn create(
        target: &Path,
        force: bool,
        marker: &'static str,
    ) -> Result<OutputDir, OutputFileError> {
        check_replaceable(target, force, marker)?;
        let io = |p: &Path, e| OutputFileError::Io(p.to_path_buf(), e);
        let temp = partial_beside(target);
        if let Some(parent) = temp.parent().filter(|p| !p.as_os_str().is_empty()) {
            std::fs::create_dir_all(parent).map_err(|e| io(parent, e))?;
        }
        // Left by an interrupted run that had this process id: that run is gone.
        if temp.exists() {
            std::fs::remove_dir_all(&temp).map_err(|e| io(&temp, e))?;
        }
        std::fs::create_dir(&temp).map_err(|e| io(&temp, e))?;
        Ok(OutputDir {
            target: target.to_path_buf(),
            temp,
            force,
            marker,
            committed: false,
        })
    }

    /// Where to write the result's files now (the hidden directory).
    pub fn path(&self) -> &Path {
        &self.temp
    }

    /// Moves the built directory to the target, replacing an earlier result there (moved aside
    /// first, put back if the move fails, deleted after).
    pub fn commit(mut self) -> Result<(), OutputFileError> {
        let io = |p: &Path, e| OutputFileError::Io(p.to_path_buf(), e);
        // Checked again: the target may have appeared or changed while the result was built.
        check_replaceable(&self.target, self.force, self.marker)?;
        let old = self.temp.with_extension("old");
        let moved_aside = match std::fs::remove_dir(&self.target) {
            Ok(()) => false,
            Err(e) if e.kind() == std::io::ErrorKind::NotFound => false,
            // Not empty: an earlier result that `check_replaceable` allowed.
            Err(_) => {
                std::fs::rename(&self.target, &old).map_err(|e| io(&self.target, e))?;
                true
            }
        };
        if let Err(e) = std::fs::rename(&self.temp, &self.target) {
            if moved_aside {
                let _ = std::fs::rename(&old, &self.target);
            }
            return Err(io(&self.target, e));
        }
        self.committed = true;
        if moved_aside {
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

#[cfg(test)]
mod tests {
    use super::*;

    /// A writer that fails halfway leaves the target as it was; one that finishes replaces it; and
    /// neither leaves its temporary file. The temporary's name ends as the target's.
    #[test]
    fn a_path_writer_replaces_whole_or_not_at_all() {
        let dir = tempfile::tempdir().unwrap();
        let target = dir.path().join("fig.png");
        std::fs::write(&target, b"old").unwrap();
        let r: Result<(), String> = replace_through_path(
            &target,
            |temp| {
                assert!(
                    temp.to_string_lossy().ends_with(".png"),
                    "{}",
                    temp.display()
                );
                std::fs::write(temp, b"half").unwrap();
                Err("the drawing failed".into())
            },
            |e| e.to_string(),
        );
        assert_eq!(r.unwrap_err(), "the drawing failed");
        assert_eq!(std::fs::read(&target).unwrap(), b"old");
        let done: Result<(), String> = replace_through_path(
            &target,
            |temp| std::fs::write(temp, b"new").map_err(|e| e.to_string()),
            |e| e.to_string(),
        );
        done.unwrap();
        assert_eq!(std::fs::read(&target).unwrap(), b"new");
        assert_eq!(std::fs::read_dir(dir.path()).unwrap().count(), 1);
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

    #[test]
    fn a_result_directory_with_a_users_file_is_never_replaced() {
        let dir = tempfile::tempdir().unwrap();
        let out = dir.path().join("session");
        let d = OutputDir::create(&out, false, "plan.toml").unwrap();
        std::fs::write(d.path().join("plan.toml"), b"one").unwrap();
        d.commit().unwrap();
        std::fs::write(out.join("notes.txt"), b"mine").unwrap();
        match OutputDir::create(&out, true, "plan.toml") {
            Err(OutputFileError::Foreign(_, names)) => assert_eq!(names, ["notes.txt"]),
            other => panic!("{:?}", other.map(|_| ())),
        }
    }

    /// A directory result appears whole or not at all; it replaces an earlier one only with `force`,
    /// and never a directory of other files.
    #[test]
    fn a_directory_is_replaced_whole_and_only_when_it_is_ours() {
        let dir = tempfile::tempdir().unwrap();
        let out = dir.path().join("out");
        let d = OutputDir::create(&out, false, "summary.json").unwrap();
        std::fs::write(d.path().join("summary.json"), b"one").unwrap();
        assert!(!out.exists(), "nothing at the target before the commit");
        d.commit().unwrap();
        assert_eq!(std::fs::read(out.join("summary.json")).unwrap(), b"one");
        // Without force: refused before any work.
        assert!(matches!(
            OutputDir::create(&out, false, "summary.json"),
            Err(OutputFileError::Exists(_))
        ));
        // Dropped half-way (a failure): the earlier result stays, nothing else is left.
        let d = OutputDir::create(&out, true, "summary.json").unwrap();
        std::fs::write(d.path().join("half"), b"").unwrap();
        drop(d);
        assert_eq!(std::fs::read_dir(dir.path()).unwrap().count(), 1);
        // With force: replaced whole (the old files gone, not merged).
        let d = OutputDir::create(&out, true, "summary.json").unwrap();
        std::fs::write(d.path().join("summary.json"), b"two").unwrap();
        d.commit().unwrap();
        assert_eq!(std::fs::read(out.join("summary.json")).unwrap(), b"two");
        assert_eq!(std::fs::read_dir(&out).unwrap().count(), 1);
        assert_eq!(std::fs::read_dir(dir.path()).unwrap().count(), 1);
        // A directory of other files is never replaced, even with force.
        let other = dir.path().join("home");
        std::fs::create_dir(&other).unwrap();
        std::fs::write(other.join("notes.txt"), b"keep").unwrap();
        assert!(matches!(
            OutputDir::create(&other, true, "summary.json"),
            Err(OutputFileError::NotOurs(..))
        ));
        // Nor a file.
        let file = dir.path().join("file");
        std::fs::write(&file, b"keep").unwrap();
        assert!(matches!(
            OutputDir::create(&file, true, "summary.json"),
            Err(OutputFileError::NotOurs(..))
        ));
        // An empty directory is taken as it is.
        let empty = dir.path().join("empty");
        std::fs::create_dir(&empty).unwrap();
        OutputDir::create(&empty, false, "summary.json")
            .unwrap()
            .commit()
            .unwrap();
    }
}
