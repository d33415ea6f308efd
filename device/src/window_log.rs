//! Every raw window of a live hand-held session, kept as a logger's CSV (`stream.csv`): the
//! recording that `host segment` reads, so that the live session is calibrated from the same
//! samples, by the same use case, as the offline path would calibrate it (docs/model.md §8: the
//! gyro from the hand's turns needs the turns, not only the still positions).
//!
//! One row per window: its centre's time in seconds since the device booted, the mean outputs in
//! the device's output unit and the mean rate in °/s, under the column names the text reader
//! takes by default (`t`, `acc_x` … `gyr_z`). A window whose means are not finite (every sample
//! saturated or bad) costs that row only. The file is flushed at every position and synced at the
//! end, so that what was recorded survives a lost link.

use shared::wire::RawWindow;
use std::fs::File;
use std::io::{BufWriter, Write};
use std::path::{Path, PathBuf};

/// The session's window log in its output directory.
pub(crate) const STREAM_FILE: &str = "stream.csv";

/// Why the window log failed.
#[derive(Debug, thiserror::Error)]
pub enum WindowLogError {
    /// An earlier session's log is there and `--force` was not given.
    #[error(
        "{} exists (an earlier session's): choose another --out or add --force to replace it",
        .path.display()
    )]
    Exists {
        /// The log.
        path: PathBuf,
    },
    /// The log could not be written.
    #[error("cannot write {}", .path.display())]
    Io {
        /// The log.
        path: PathBuf,
        /// The cause.
        #[source]
        source: std::io::Error,
    },
}

impl WindowLogError {
    /// The error of `source` on the log at `path`.
    pub(crate) fn at(path: &Path, source: std::io::Error) -> WindowLogError {
        let path = path.to_path_buf();
        match source.kind() {
            std::io::ErrorKind::AlreadyExists => WindowLogError::Exists { path },
            _ => WindowLogError::Io { path, source },
        }
    }
}

/// The open log.
pub(crate) struct WindowLog {
    out: BufWriter<File>,
    path: PathBuf,
    /// Seconds per sample and the window's half length in samples.
    sample_period_s: f64,
    half_window: f64,
    rows: u64,
    /// The first write error, reported at [`WindowLog::finish`].
    failed: Option<std::io::Error>,
}

impl WindowLog {
    /// Creates the log at `path` for windows of `window_samples` at `sample_rate_hz`; an existing
    /// file is replaced only with `force`.
    pub(crate) fn create(
        path: &Path,
        sample_rate_hz: f64,
        window_samples: u32,
        force: bool,
    ) -> Result<WindowLog, WindowLogError> {
        let err = |source| WindowLogError::at(path, source);
        let file = std::fs::OpenOptions::new()
            .write(true)
            .create(true)
            .create_new(!force)
            .truncate(true)
            .open(path)
            .map_err(err)?;
        let mut out = BufWriter::new(file);
        let columns = recording::session::import::DEFAULT_COLUMNS.join(",");
        writeln!(out, "{},{columns}", crate::hand_session::LOG_TIME_COLUMN).map_err(err)?;
        Ok(WindowLog {
            out,
            path: path.to_path_buf(),
            sample_period_s: 1.0 / sample_rate_hz.max(1.0),
            half_window: f64::from(window_samples) / 2.0,
            rows: 0,
            failed: None,
        })
    }

    /// Appends one window (a window without finite means is left out).
    pub(crate) fn push(&mut self, w: &RawWindow) {
        let finite = w
            .mean_raw
            .iter()
            .chain(&w.mean_rate_rad_s)
            .all(|x| x.is_finite());
        if !finite || self.failed.is_some() {
            return;
        }
        let t = (w.first_sample as f64 + self.half_window) * self.sample_period_s;
        // As f64, the value exactly: the reader's number is the device's window mean.
        let u = w.mean_raw.map(f64::from);
        let d = w.mean_rate_rad_s.map(|x| f64::from(x).to_degrees());
        let row = writeln!(
            self.out,
            "{t},{},{},{},{},{},{}",
            u[0], u[1], u[2], d[0], d[1], d[2]
        );
        match row {
            Ok(()) => self.rows += 1,
            Err(e) => self.failed = Some(e),
        }
    }

    /// Pushes what is buffered to the file (at the end of each position).
    pub(crate) fn flush(&mut self) {
        if let Err(e) = self.out.flush() {
            self.failed.get_or_insert(e);
        }
    }

    /// Closes the log, synced; the rows written, or the first write error.
    pub(crate) fn finish(mut self) -> Result<(PathBuf, u64), WindowLogError> {
        let err = WindowLogError::at;
        if let Some(e) = self.failed.take() {
            return Err(err(&self.path, e));
        }
        let file = self
            .out
            .into_inner()
            .map_err(|e| err(&self.path, e.into_error()))?;
        file.sync_all().map_err(|e| err(&self.path, e))?;
        Ok((self.path, self.rows))
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use shared::wire::SampleFlags;

    fn window(first_sample: u64, u: [f32; 3], w: [f32; 3]) -> RawWindow {
        RawWindow {
            first_sample,
            count: 20,
            mean_raw: u,
            var_raw: [0.0; 3],
            mean_rate_rad_s: w,
            var_rate_rad2_s2: [0.0; 3],
            mean_temp_c: f32::NAN,
            rejected: 0,
            dropped_frames: 0,
            flags: SampleFlags::default(),
        }
    }

    /// The log is what the text reader reads back: times at the windows' centres, outputs as
    /// given, the rate in °/s; a window of bad samples costs its row only; nothing is replaced
    /// without `force`.
    #[test]
    fn the_log_reads_back_as_a_recording_and_a_bad_window_costs_its_row() {
        let dir = tempfile::tempdir().unwrap();
        let path = dir.path().join(STREAM_FILE);
        let mut log = WindowLog::create(&path, 1000.0, 20, false).unwrap();
        log.push(&window(0, [2.5, 2.5, 2.9], [0.01, 0.0, 0.0]));
        log.push(&window(20, [f32::NAN, 2.5, 2.9], [0.0; 3]));
        log.push(&window(40, [2.4, 2.6, 2.9], [0.0, -1.0, 0.0]));
        let (_, rows) = log.finish().unwrap();
        assert_eq!(rows, 2);
        let text = std::fs::read_to_string(&path).unwrap();
        let lines: Vec<&str> = text.lines().collect();
        assert_eq!(lines[0], "t,acc_x,acc_y,acc_z,gyr_x,gyr_y,gyr_z");
        let row: Vec<f64> = lines[2].split(',').map(|x| x.parse().unwrap()).collect();
        assert!((row[0] - 0.050).abs() < 1e-12, "centre of samples 40..60");
        assert_eq!(row[1], f64::from(2.4f32));
        assert!((row[5] + 1f64.to_degrees()).abs() < 1e-9, "°/s");
        let again = WindowLog::create(&path, 1000.0, 20, false).err().unwrap();
        assert!(again.to_string().contains("add --force"), "{again}");
        assert!(WindowLog::create(&path, 1000.0, 20, true).is_ok());
    }
}
