//! [`apply_log`]: a calibration applied to a logger's file (any format `host segment` reads).

use super::{check_still, output_line, Applier, ApplyError, ApplySummary, StillSums};
use crate::calibration_guard::{meet, Meeting, Other};
use crate::session::import::Recording;
use crate::session::logs::{read_log, LogSource};
use crate::session::segment::{
    find_intervals, gyro_unit_suspect, Interval, SegmentError, SegmentOptions,
};
use crate::session::Row;
use shared::compensator::LeverMode;
use shared::{Calibration, OutputUnit};
use std::io::Write;
use std::path::Path;

/// Applies `cal` to the logger's file at `path`, writing the CSV to `out`. The log has no unit id
/// and no segments: the output unit and the temperature are checked as for a session, the ω̇
/// estimate restarts at every gap in the time stamps (more than five periods), and the still
/// intervals found in the log must compensate to 1 g (and rest, with a gyro calibration).
pub fn apply_log(
    path: &Path,
    source: &LogSource,
    cal: &Calibration,
    mode: LeverMode,
    assume_temp_c: Option<f64>,
    out: &mut dyn Write,
) -> Result<ApplySummary, ApplyError> {
    let log = read_log(path, source).map_err(ApplyError::Log)?;
    let rec = &log.recording;
    let other = Other {
        name: "the log",
        unit_id: None,
        output_unit: Some(rec.acc_unit.unwrap_or(OutputUnit::Lsb)),
        frame: None,
        temperatures: super::temperatures(rec.temp_c.is_some(), assume_temp_c),
    };
    meet(Meeting::Apply, &super::mine(cal, None), &other)?;
    let prepared = Prepared::new(rec, cal, mode, assume_temp_c)?;
    let write_err = |e: std::io::Error| {
        ApplyError::Recording(crate::session::RecordingError::Io {
            path: Path::new("(output)").to_path_buf(),
            source: e,
        })
    };
    writeln!(out, "{}", super::APPLY_HEADER).map_err(write_err)?;
    let g = cal.gravity_m_s2;
    let mut fmt = ryu::Buffer::new();
    let mut summary = prepared.run(rec, cal, &mut |i, f, applier| {
        let line = output_line("log", rec.t_s[i], f, applier, g, &mut fmt);
        out.write_all(line.as_bytes()).map_err(write_err)
    })?;
    summary.warnings.splice(0..0, log.warnings);
    Ok(summary)
}

/// What [`Prepared::run`] hands each row to: its index, its specific force (m/s², `None` for a row
/// with a non-finite value) and the applier (its corrected rate).
pub type RowSink<'a> = dyn FnMut(usize, Option<[f32; 3]>, &Applier) -> Result<(), ApplyError> + 'a;

/// A calibration ready to be applied to a recording held in memory (a logger's file read whole, or
/// arrays): the compensator and ω̇ estimator, and the still intervals found in the recording, each
/// of which must compensate to 1 g (and rest, with a gyro calibration).
pub struct Prepared {
    applier: Applier,
    stills: Vec<Interval>,
}

impl Prepared {
    /// Checks what can be checked before the rows: a temperature for a temperature model, a sample
    /// rate for the ω̇ estimator, and a gyro that rests where the accelerometer does.
    pub fn new(
        rec: &Recording,
        cal: &Calibration,
        mode: LeverMode,
        assume_temp_c: Option<f64>,
    ) -> Result<Prepared, ApplyError> {
        let other = Other {
            name: "the recording",
            unit_id: None,
            output_unit: None,
            frame: None,
            temperatures: super::temperatures(rec.temp_c.is_some(), assume_temp_c),
        };
        meet(Meeting::Apply, &super::mine(cal, None), &other)?;
        let mut applier = Applier::new(cal, mode, rec.rate_hz)?;
        if let (Some(t), None) = (assume_temp_c, &rec.temp_c) {
            applier.compensator.refresh(t as f32);
        }
        // No still interval at all is a flight log, unless the accelerometer is still and only the
        // gyro moves: then the rest check cannot be skipped, it has failed.
        let stills = match find_intervals(rec, &SegmentOptions::default()) {
            Ok(s) => s.stills,
            Err(SegmentError::NoStill {
                acc_mg, gyro_deg_s, ..
            }) if gyro_unit_suspect(acc_mg, gyro_deg_s) => {
                return Err(ApplyError::GyroNeverAtRest { acc_mg, gyro_deg_s })
            }
            Err(_) => Vec::new(),
        };
        Ok(Prepared { applier, stills })
    }

    /// Compensates every row of `rec` as the device does, handing each row's index and result (NaN
    /// rows `None`) to `row`, then checks the still intervals. The ω̇ estimate restarts at every gap
    /// in the time stamps (more than five periods).
    pub fn run(
        mut self,
        rec: &Recording,
        cal: &Calibration,
        row: &mut RowSink<'_>,
    ) -> Result<ApplySummary, ApplyError> {
        let (applier, stills) = (&mut self.applier, &self.stills);
        let mut sums = vec![StillSums::default(); stills.len()];
        let g = cal.gravity_m_s2;
        let mut summary = ApplySummary::default();
        let (mut piece, mut still) = (0usize, 0usize);
        let gap_s = 5.0 / rec.rate_hz;
        for i in 0..rec.len() {
            if i > 0 && rec.t_s[i] - rec.t_s[i - 1] > gap_s {
                piece += 1;
            }
            let r = Row {
                segment: "log",
                segment_index: piece,
                t_s: rec.t_s[i],
                u: rec.acc[i],
                w_rad_s: rec.gyro_rad_s[i],
                temp_c: rec.temp_c.as_ref().map(|t| t[i]),
            };
            let f = applier.row(&r);
            summary.rows += 1;
            while still < stills.len() && stills[still].end <= i {
                still += 1;
            }
            match f {
                Some(f) if still < stills.len() && stills[still].start <= i => {
                    let s = &mut sums[still];
                    for j in 0..3 {
                        s.f_g[j] += f64::from(f[j]) / g;
                        s.w_rad_s[j] += f64::from(applier.last_rate_rad_s[j]);
                    }
                    s.rows += 1;
                }
                Some(_) => {}
                None => summary.non_finite_rows += 1,
            }
            row(i, f, applier)?;
        }
        for (k, (iv, s)) in stills.iter().zip(&sums).enumerate() {
            let name = format!("still {:02} (t = {:.1} s)", k + 1, iv.start_s);
            check_still(&name, s, cal.gyro.is_some())?;
        }
        if applier.flagged_rows > 0 {
            summary
                .warnings
                .push(super::flagged_warning(applier.flagged_rows));
        }
        Ok(summary)
    }
}
