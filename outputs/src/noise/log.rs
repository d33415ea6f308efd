//! `host noise` on a logger's file (any format `host segment` reads): the longest still interval
//! `session::segment` finds in it is analysed like a session's longest static segment.

use super::{analyse_signals, NoiseError, NoiseReport, Signals, MAX_SAMPLES};
use crate::calibration_guard::Meeting;
use crate::export::PlainMatrices;
use recording::session::logs::{read_log_within, LogSource};
use recording::session::note::Note;
use recording::session::segment::{find_intervals, SegmentOptions};
use recording::session::SAMPLES_HEADER;
use shared::OutputUnit;
use std::io::{BufRead, Read};
use std::path::Path;

/// True when the file at `path` is a recording's `samples.csv` (its first line is the session
/// format's header) rather than a logger's file.
pub fn is_samples_csv(path: &Path) -> bool {
    let Ok(file) = std::fs::File::open(path) else {
        return false;
    };
    let mut first = Vec::new();
    let limit = recording::limits::MAX_LINE_BYTES as u64;
    let read = std::io::BufReader::new(file)
        .take(limit)
        .read_until(b'\n', &mut first);
    read.is_ok() && String::from_utf8_lossy(&first).starts_with(SAMPLES_HEADER)
}

/// Analyses the longest still interval of the logger's file at `path`; `calibration` (with its
/// output unit) turns the accelerometer outputs into m/s².
pub fn analyse_log(
    path: &Path,
    source: &LogSource,
    calibration: Option<(&PlainMatrices, OutputUnit)>,
    quiet: bool,
) -> Result<NoiseReport, NoiseError> {
    let step = recording::ui::step(format!("reading {}", path.display()), quiet);
    // A log longer than one analysis is read again and only its still stretches are kept, the
    // first MAX_SAMPLES: no more than one analysis takes (recording's `logs::keep`).
    let log = read_log_within(path, source, MAX_SAMPLES, None)?;
    step.finish_and_clear();
    let rec = &log.recording;
    let unit = rec.acc_unit.unwrap_or(OutputUnit::Lsb);
    if let Some((_, cal_unit)) = calibration {
        crate::calibration_guard::check_output_units(
            Meeting::Noise,
            "the calibration",
            cal_unit,
            "the log",
            unit,
        )?;
    }
    let seg =
        find_intervals(rec, &SegmentOptions::new(source.spelling)).map_err(NoiseError::NoStill)?;
    let best = seg
        .stills
        .iter()
        .enumerate()
        .max_by_key(|(_, iv)| iv.end - iv.start)
        .ok_or_else(|| {
            NoiseError::NoStillData(format!("{} has no still interval", path.display()))
        })?;
    let (k, iv) = best;
    let end = iv.end.min(iv.start + MAX_SAMPLES);
    let mut data: [Vec<f64>; 6] = Default::default();
    // The logger's own counts (the offset it was read with added back), which a calibration made
    // from them applies to (`crate::apply`); a constant changes no Allan deviation.
    for i in iv.start..end {
        for j in 0..3 {
            data[j].push(rec.acc[i][j] + rec.acc_offset[j]);
            data[3 + j].push(rec.gyro_rad_s[i][j]);
        }
    }
    let s = Signals {
        segment: format!("still {:02} (t = {:.1} s)", k + 1, iv.start_s),
        rate_hz: rec.rate_hz,
        data,
        cut: end < iv.end,
        acc_unit: Some(unit),
    };
    let mut report = analyse_signals(
        s,
        path.display().to_string(),
        calibration.map(|c| c.0),
        source.spelling,
        quiet,
    )?;
    let mut warnings = Note::texts(&log.warnings);
    warnings.append(&mut report.warnings);
    report.warnings = warnings;
    Ok(report)
}
