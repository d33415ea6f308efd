//! Writing a session directory (`plan.toml` + `samples.csv`, `docs/recording-format.md`) as it is
//! recorded or simulated.

use super::plan::RecordingVersion;
use super::{Plan, RecordingError, PLAN_FILE, SAMPLES_FILE};
use std::fs::File;
use std::io::{BufWriter, Write};
use std::path::{Path, PathBuf};

/// Writes a session directory: `plan.toml` first, then `samples.csv` row by row through a buffer that
/// is flushed to the disk at every segment end, so that whatever happens later, the segments recorded
/// so far are on disk and readable (a crash mid-segment leaves at most a partial last line, which the
/// reader skips with a warning).
pub struct SessionWriter {
    dir: PathBuf,
    samples_path: PathBuf,
    out: BufWriter<File>,
    names: Vec<String>,
    current: Option<usize>,
    rows: u64,
    line: Vec<u8>,
    float: ryu::Buffer,
    /// The plan's version: with temperature, rows end with `temp_c`.
    version: RecordingVersion,
}

impl SessionWriter {
    /// Creates `dir` (and parents) if needed, writes and syncs `plan.toml`, and starts `samples.csv`.
    /// Refuses to replace an existing `samples.csv` unless `overwrite`.
    pub fn create(
        dir: &Path,
        plan: &Plan,
        overwrite: bool,
    ) -> Result<SessionWriter, RecordingError> {
        plan.validate()?;
        let version = plan.version()?;
        let io = |path: &Path| {
            let path = path.to_path_buf();
            move |source| RecordingError::Io { path, source }
        };
        std::fs::create_dir_all(dir).map_err(io(dir))?;
        let samples_path = dir.join(SAMPLES_FILE);
        if !overwrite && samples_path.exists() {
            return Err(RecordingError::Exists(samples_path));
        }
        let plan_path = dir.join(PLAN_FILE);
        write_synced(&plan_path, plan.to_toml().as_bytes()).map_err(io(&plan_path))?;
        let file = File::create(&samples_path).map_err(io(&samples_path))?;
        let mut out = BufWriter::with_capacity(1 << 20, file);
        out.write_all(version.samples_header().as_bytes())
            .and_then(|_| out.write_all(b"\n"))
            .and_then(|_| out.flush())
            .map_err(io(&samples_path))?;
        Ok(SessionWriter {
            dir: dir.to_path_buf(),
            samples_path,
            out,
            names: plan.segments.iter().map(|s| s.name.clone()).collect(),
            current: None,
            rows: 0,
            line: Vec::with_capacity(256),
            float: ryu::Buffer::new(),
            version,
        })
    }

    /// The session directory.
    pub fn dir(&self) -> &Path {
        &self.dir
    }

    /// True when rows carry the unit's temperature (the plan's version has `temp_c`).
    pub fn has_temperature(&self) -> bool {
        self.version.has_temperature()
    }

    /// Rows written so far.
    pub fn rows(&self) -> u64 {
        self.rows
    }

    /// Appends one sample of `segment` to a recording without temperature (format version 1 or 2).
    /// Changing segment ends the previous one (flush to disk). Floats are written in their shortest
    /// exact form, so they read back bit for bit.
    pub fn write_row(
        &mut self,
        segment: &str,
        t_s: f64,
        u: &[f64; 3],
        w_rad_s: &[f64; 3],
    ) -> Result<(), RecordingError> {
        if self.has_temperature() {
            return Err(RecordingError::WriterTemperature {
                version: self.version,
            });
        }
        self.append(segment, t_s, u, w_rad_s, None)
    }

    /// Appends one sample of `segment` with the unit's temperature, °C (format version 3).
    pub fn write_row_with_temperature(
        &mut self,
        segment: &str,
        t_s: f64,
        u: &[f64; 3],
        w_rad_s: &[f64; 3],
        temp_c: f64,
    ) -> Result<(), RecordingError> {
        if !self.has_temperature() {
            return Err(RecordingError::WriterTemperature {
                version: self.version,
            });
        }
        self.append(segment, t_s, u, w_rad_s, Some(temp_c))
    }

    fn append(
        &mut self,
        segment: &str,
        t_s: f64,
        u: &[f64; 3],
        w_rad_s: &[f64; 3],
        temp_c: Option<f64>,
    ) -> Result<(), RecordingError> {
        let idx = match self.current {
            Some(i) if self.names[i] == segment => i,
            previous => {
                let i = self
                    .names
                    .iter()
                    .position(|n| n == segment)
                    .ok_or_else(|| RecordingError::WriterSegment(segment.to_string()))?;
                if previous.is_some() {
                    self.end_segment()?;
                }
                self.current = Some(i);
                i
            }
        };
        self.line.clear();
        self.line.extend_from_slice(self.names[idx].as_bytes());
        for v in std::iter::once(&t_s).chain(u).chain(w_rad_s).chain(&temp_c) {
            self.line.push(b',');
            self.line
                .extend_from_slice(self.float.format(*v).as_bytes());
        }
        self.line.push(b'\n');
        self.out
            .write_all(&self.line)
            .map_err(|source| RecordingError::Io {
                path: self.samples_path.clone(),
                source,
            })?;
        self.rows += 1;
        Ok(())
    }

    /// Ends the current segment: everything written so far goes to the disk.
    pub fn end_segment(&mut self) -> Result<(), RecordingError> {
        self.current = None;
        self.out
            .flush()
            .and_then(|_| self.out.get_ref().sync_data())
            .map_err(|source| RecordingError::Io {
                path: self.samples_path.clone(),
                source,
            })
    }

    /// Ends the recording; returns the number of rows written.
    pub fn finish(mut self) -> Result<u64, RecordingError> {
        self.end_segment()?;
        Ok(self.rows)
    }
}

fn write_synced(path: &Path, bytes: &[u8]) -> std::io::Result<()> {
    let mut f = File::create(path)?;
    f.write_all(bytes)?;
    f.sync_all()
}
