//! `host report`: a recorded session judged by a calibration. The session is read, the calibration
//! is checked against it (`outputs::calibration_guard`), the session's own fit is run here once
//! (at the calibration's reference point, `outputs::report::session_fit_options`), and the report
//! is built from it and written (`outputs::report`).

use estimator::estimate::calibrate_session_stats;
use estimator::unit_file::UnitFile;
use outputs::calibration_guard::{meet, Meeting};
use outputs::report::{
    build_report, session_fit_options, write_report, ReportError, ReportOptions, ReportSummary,
};
use recording::session::{read_session, Package, ReadOptions};
use std::path::Path;

/// Reads the session in `input_dir` and the calibration file, computes the outputs before and
/// after compensation, the residuals and the navigation replay, and writes the figures (PNG and
/// SVG) and `report.html` / `report.md` into `out_dir`.
pub fn report(
    input_dir: &Path,
    calibration_file: &Path,
    out_dir: &Path,
    options: &ReportOptions,
) -> Result<ReportSummary, ReportError> {
    let unit = UnitFile::load(calibration_file).map_err(ReportError::Unit)?;
    let session =
        read_session(input_dir, &ReadOptions { quiet: true }).map_err(ReportError::Recording)?;
    let cal = unit.to_calibration().map_err(ReportError::Calibration)?;
    // A calibration that cannot meet this session (unit, output unit, scales, frame, a
    // temperature model without temperatures) is refused before anything is computed from it.
    let id = unit.unit_id().map_err(ReportError::Calibration)?;
    let mut session_side = outputs::apply::recording(&session.plan, None);
    session_side.name = "the session";
    meet(
        Meeting::Report,
        &outputs::apply::mine(&cal, id),
        &session_side,
    )?;
    let (plan, stats) = (&session.plan, &session.stats);
    let fit = calibrate_session_stats(plan, stats, &session_fit_options(&cal, options));
    let uncertainty = unit.uncertainty.as_ref();
    let mut data = build_report(plan, stats, &cal, uncertainty, fit, options)?;
    data.warnings
        .extend((session.report.warnings.iter().cloned()).map(outputs::note::Note::Reader));
    // The calibration file says so itself (its rows are then equal, checked when it was read).
    data.single_package |= unit.package() == Package::Single;
    write_report(
        &data,
        out_dir,
        &input_dir.display().to_string(),
        &calibration_file.display().to_string(),
        options.formats,
    )
}
