//! Writing a calibration result: `calibration.toml` (the unit-file schema plus 1σ, so that
//! `host simulate --unit calibration.toml` round-trips) and `calibration.bin` (the device blob).

use crate::estimate::CalibrationOutcome;
use crate::unit_file::UnitFile;
use shared::blob::{BlobError, ParameterBlob};
use shared::UnitId;
use std::path::{Path, PathBuf};

/// File name of the TOML result.
pub const CALIBRATION_TOML: &str = "calibration.toml";
/// File name of the blob.
pub(crate) const CALIBRATION_BIN: &str = "calibration.bin";
/// File name `calibration.toml` takes when its unit failed its checks (pass/fail limits or the
/// device's verification): nothing that looks for an accepted calibration picks it up.
pub(crate) const FAILED_TOML: &str = "calibration.FAILED.toml";
/// File name `calibration.bin` takes when its unit failed its checks.
pub(crate) const FAILED_BIN: &str = "calibration.FAILED.bin";

/// What was written.
#[derive(Clone, Debug)]
pub struct WrittenCalibration {
    /// Path of `calibration.toml`.
    pub toml_path: PathBuf,
    /// Path of `calibration.bin`.
    pub bin_path: PathBuf,
    /// The blob's bytes.
    pub blob: Vec<u8>,
}

/// Why the result could not be written.
#[derive(Debug, thiserror::Error)]
pub enum OutputError {
    /// The calibration does not encode (it fails the device's own validation).
    #[error("the estimated calibration cannot be stored on a device")]
    Blob(#[source] BlobError),
    /// A file could not be written.
    #[error("cannot write {}", .0.display())]
    Io(PathBuf, #[source] std::io::Error),
    /// A calibration is already there and `--force` was not given.
    #[error(
        "{} already exists: choose another output directory (--out) or replace it (--force)",
        .0.display()
    )]
    Exists(PathBuf),
}

/// Seconds since the Unix epoch (0 if the clock is before it).
pub fn now_unix_s() -> u64 {
    std::time::SystemTime::now()
        .duration_since(std::time::UNIX_EPOCH)
        .map_or(0, |d| d.as_secs())
}

/// `YYYYMMDDTHHMMSSZ` of a Unix time (the proleptic Gregorian calendar, H. Hinnant's
/// days-to-civil algorithm).
pub fn utc_stamp(unix_s: u64) -> String {
    let days = (unix_s / 86_400) as i64;
    let secs = unix_s % 86_400;
    let z = days + 719_468;
    let era = z.div_euclid(146_097);
    let doe = z - era * 146_097;
    let yoe = (doe - doe / 1460 + doe / 36_524 - doe / 146_096) / 365;
    let doy = doe - (365 * yoe + yoe / 4 - yoe / 100);
    let mp = (5 * doy + 2) / 153;
    let d = doy - (153 * mp + 2) / 5 + 1;
    let m = if mp < 10 { mp + 3 } else { mp - 9 };
    let y = yoe + era * 400 + i64::from(m <= 2);
    format!(
        "{y:04}{m:02}{d:02}T{:02}{:02}{:02}Z",
        secs / 3600,
        secs / 60 % 60,
        secs % 60
    )
}

/// The blob of an outcome for `unit_id`.
pub fn blob_bytes(
    outcome: &CalibrationOutcome,
    unit_id: UnitId,
    created_unix_s: u64,
) -> Result<Vec<u8>, BlobError> {
    let blob = ParameterBlob {
        unit_id,
        calibration: outcome.calibration,
        created_unix_s,
    };
    let (bytes, n) = blob.to_bytes()?;
    Ok(bytes[..n].to_vec())
}

/// Refuses to go on when `out_dir` already holds a calibration and `force` is false: called before
/// any work (reading a session, recording, flashing), so a run is never wasted on a refusal at its end.
pub fn refuse_overwrite(out_dir: &Path, force: bool) -> Result<(), OutputError> {
    if force {
        return Ok(());
    }
    for name in [CALIBRATION_TOML, CALIBRATION_BIN, FAILED_TOML, FAILED_BIN] {
        let p = out_dir.join(name);
        if p.exists() {
            return Err(OutputError::Exists(p));
        }
    }
    Ok(())
}

/// The calibration file of an outcome: the unit-file schema with every 1σ the estimate has (the
/// accelerometer's `[uncertainty]`, the gyro's and the temperature model's), exactly what
/// `calibration.toml` holds; the machine-readable summaries are made from it too.
pub fn calibration_unit_file(outcome: &CalibrationOutcome, unit_id: Option<UnitId>) -> UnitFile {
    let mut file = UnitFile::from_calibration(
        &outcome.calibration,
        unit_id,
        Some(outcome.uncertainty.clone()),
    );
    file.frame = Some(crate::unit_file::FrameSection::of(
        &outcome.static_split.frame,
    ));
    // The raw log's counts of zero force, which the biases hold (apply checks them).
    file.statics.raw_offset_lsb = outcome.acc_offset;
    // A single-package fit's three lever arms are one point, and the file says so (docs/model.md §4.7).
    if let (Some(d), true) = (file.dynamic.as_mut(), outcome.single_package) {
        d.package = recording::session::Package::Single;
    }
    // The estimate's 1σ beside the values that `from_calibration` wrote.
    if let (Some(section), Some(g)) = (file.gyro.as_mut(), outcome.gyro.as_ref()) {
        section.bias_rad_s_1sigma = Some(g.bias_rad_s_1sigma);
        section.matrix_1sigma = Some(g.matrix_1sigma);
    }
    if let (Some(section), Some(fit)) = (file.temperature.as_mut(), &outcome.thermal) {
        section.zero_bias_degree = Some(fit.zero_bias_degree);
        section.scale_degree = Some(fit.scale_degree);
        section.zero_bias_out_per_c_1sigma = Some(fit.zero_bias_sigma);
        section.scale_rel_per_c_1sigma = Some(fit.scale_sigma);
        section.gyro_bias_degree = fit.gyro_bias_degree;
        section.gyro_bias_rad_s_per_c_1sigma =
            fit.model.gyro_bias_rad_s_per_c.map(|_| fit.gyro_bias_sigma);
    }
    file
}

/// Writes both files into `out_dir` (created if needed), as a pair: both are written beside their
/// final names (`.calibration.toml.new`, `.calibration.bin.new`) and renamed only when both are
/// complete, so a failure (a full disk) leaves the old pair or no pair, never a new `.toml` beside an
/// old `.bin`. An existing pair is replaced only with `force`.
pub fn write_calibration_files(
    out_dir: &Path,
    outcome: &CalibrationOutcome,
    unit_id: UnitId,
    created_unix_s: u64,
    force: bool,
) -> Result<WrittenCalibration, OutputError> {
    refuse_overwrite(out_dir, force)?;
    let blob = blob_bytes(outcome, unit_id, created_unix_s).map_err(OutputError::Blob)?;
    std::fs::create_dir_all(out_dir).map_err(|e| OutputError::Io(out_dir.to_path_buf(), e))?;
    let text = calibration_unit_file(outcome, Some(unit_id)).to_toml();
    let toml_path = out_dir.join(CALIBRATION_TOML);
    let bin_path = out_dir.join(CALIBRATION_BIN);
    let toml_new = out_dir.join(format!(".{CALIBRATION_TOML}.new"));
    let bin_new = out_dir.join(format!(".{CALIBRATION_BIN}.new"));
    let staged = write_synced(&toml_new, text.as_bytes())
        .and_then(|()| write_synced(&bin_new, &blob))
        .and_then(|()| std::fs::rename(&bin_new, &bin_path).map_err(|e| (bin_path.clone(), e)))
        .and_then(|()| std::fs::rename(&toml_new, &toml_path).map_err(|e| (toml_path.clone(), e)));
    if let Err((p, e)) = staged {
        let _ = std::fs::remove_file(&toml_new);
        let _ = std::fs::remove_file(&bin_new);
        return Err(OutputError::Io(p, e));
    }
    Ok(WrittenCalibration {
        toml_path,
        bin_path,
        blob,
    })
}

/// Renames the pair in `dir` to `FAILED_BIN` and `FAILED_TOML` (the blob first: it is what
/// could be flashed), because its unit failed a check: the files stay for inspection, under names
/// that say so. An existing failed pair is replaced only with `force`. Returns the new paths of the
/// `.toml` and the `.bin`.
pub fn mark_failed_in(dir: &Path, force: bool) -> Result<(PathBuf, PathBuf), OutputError> {
    let (toml_path, bin_path) = (dir.join(FAILED_TOML), dir.join(FAILED_BIN));
    for p in [&toml_path, &bin_path] {
        if !force && p.exists() {
            return Err(OutputError::Exists(p.clone()));
        }
    }
    for (from, to) in [(CALIBRATION_BIN, &bin_path), (CALIBRATION_TOML, &toml_path)] {
        let from = dir.join(from);
        std::fs::rename(&from, to).map_err(|e| OutputError::Io(from, e))?;
    }
    Ok((toml_path, bin_path))
}

/// Removes an earlier run's failed pair from `dir`, when there is one: a directory holds one
/// result, and an accepted pair written beside a failed one (under `--force`) replaces it.
pub fn remove_failed_in(dir: &Path) -> Result<(), OutputError> {
    for name in [FAILED_BIN, FAILED_TOML] {
        let p = dir.join(name);
        match std::fs::remove_file(&p) {
            Err(e) if e.kind() != std::io::ErrorKind::NotFound => {
                return Err(OutputError::Io(p, e))
            }
            _ => {}
        }
    }
    Ok(())
}

/// Writes and syncs one file, naming it in the error.
fn write_synced(path: &Path, bytes: &[u8]) -> Result<(), (PathBuf, std::io::Error)> {
    use std::io::Write;
    let io = |e| (path.to_path_buf(), e);
    let mut f = std::fs::File::create(path).map_err(io)?;
    f.write_all(bytes).map_err(io)?;
    f.sync_all().map_err(io)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::estimate::{calibrate_session_stats, EstimateOptions};
    use crate::sim::testkit::{self, TableErrors};
    use shared::rng::Rng;

    fn outcome() -> CalibrationOutcome {
        let plan = testkit::better_plan(shared::OutputUnit::Volts);
        let stats = testkit::noisy_stats(
            &plan,
            &testkit::paper_unit(),
            1e-4,
            TableErrors::default(),
            &mut Rng::new(3, 0),
        );
        calibrate_session_stats(&plan, &stats, &EstimateOptions::default()).unwrap()
    }

    /// A pair is replaced only with `force`; a failure half-way (here the `.bin` cannot take its
    /// name) leaves no new `.toml` beside the old `.bin` and no staged files.
    #[test]
    fn the_pair_is_written_whole_or_not_at_all_and_never_over_one_without_force() {
        let o = outcome();
        let dir = tempfile::tempdir().unwrap();
        let first = write_calibration_files(dir.path(), &o, UnitId([1; 12]), 1, false).unwrap();
        let e = write_calibration_files(dir.path(), &o, UnitId([2; 12]), 2, false).unwrap_err();
        assert!(matches!(e, OutputError::Exists(_)), "{e}");
        assert_eq!(std::fs::read(&first.bin_path).unwrap(), first.blob);
        let second = write_calibration_files(dir.path(), &o, UnitId([2; 12]), 2, true).unwrap();
        assert_eq!(std::fs::read(&second.bin_path).unwrap(), second.blob);

        let broken = tempfile::tempdir().unwrap();
        std::fs::create_dir(broken.path().join(CALIBRATION_BIN)).unwrap();
        std::fs::write(broken.path().join(CALIBRATION_BIN).join("x"), b"keep").unwrap();
        let e = write_calibration_files(broken.path(), &o, UnitId([3; 12]), 3, true).unwrap_err();
        assert!(matches!(e, OutputError::Io(..)), "{e}");
        let names: Vec<String> = std::fs::read_dir(broken.path())
            .unwrap()
            .map(|e| e.unwrap().file_name().to_string_lossy().into_owned())
            .collect();
        assert_eq!(names, vec![CALIBRATION_BIN.to_string()], "{names:?}");
    }

    /// `[frame]` says what the body axes are, from what fixed them: the fixture's nominal ups, the
    /// faces a unit was set down on (`attitude = "face"`), or, with every position free, the
    /// accelerometer triad's own axes, where accelerometer x's angles are exactly 0°, 90°, 90°
    /// (docs/model.md §7).
    #[test]
    fn the_calibration_file_states_its_body_frame() {
        use crate::unit_file::FrameKind;
        use recording::session::plan::Attitude;
        let mut fixture = testkit::many_mounts_plan();
        fixture.segments.retain(|s| s.is_static());
        let on_faces = |face: Attitude, other: Attitude| {
            let mut p = fixture.clone();
            for s in &mut p.segments {
                let axis = s.up_b.iter().filter(|c| c.abs() == 1.0).count() == 1;
                s.attitude = if axis { face } else { other };
                s.attitude_sigma_deg = axis.then_some(1.0);
            }
            p
        };
        let faces = on_faces(Attitude::Face, Attitude::Free);
        let free = on_faces(Attitude::Free, Attitude::Free);
        let truth = testkit::paper_unit();
        for (plan, kind) in [
            (&fixture, FrameKind::Fixture),
            (&faces, FrameKind::Faces),
            (&free, FrameKind::Accelerometer),
        ] {
            let stats = testkit::noisy_stats(
                plan,
                &truth,
                testkit::paper_noise(&truth),
                TableErrors::default(),
                &mut Rng::new(5, 0),
            );
            let out = calibrate_session_stats(plan, &stats, &EstimateOptions::default()).unwrap();
            let dir = tempfile::tempdir().unwrap();
            let w = write_calibration_files(dir.path(), &out, UnitId([4; 12]), 0, false).unwrap();
            let file = UnitFile::load(&w.toml_path).unwrap();
            let frame = file.frame.clone().unwrap();
            assert_eq!(frame.kind, kind, "{kind:?}: {frame:?}");
            assert_eq!(frame.axes, out.static_split.frame.kind().axes());
            let x_angles = file.statics.installation_angles_deg[0];
            let conventional = x_angles == [0.0, 90.0, 90.0];
            assert_eq!(
                conventional,
                kind == FrameKind::Accelerometer,
                "{x_angles:?}"
            );
            if kind == FrameKind::Faces {
                let f = out.static_split.frame;
                let six = crate::estimate::BodyFrame::Faces {
                    faces: 6,
                    prior_deg: 1.0,
                };
                assert_eq!(f, six, "{f}");
            }
        }
    }

    #[test]
    fn the_calibration_file_carries_the_estimated_gyro() {
        let plan = recording::session::builtin::builtin_plan("short-oblique")
            .unwrap()
            .unwrap();
        let truth = testkit::paper_unit();
        let g = crate::sim::session::gyro_matrix([5e-3, -5e-3, 5e-3], 0.5f64.to_radians());
        let b = [0.008, -0.008, 0.008];
        let errors = TableErrors {
            gyro_noise_rad_s: 0.05f64.to_radians(),
            gyro: Some((g, b)),
            ..TableErrors::default()
        };
        let mut rng = Rng::new(3, 0);
        let noise = 1e-3 * truth.statics.scale_out_per_g[0];
        let stats = testkit::noisy_stats(&plan, &truth, noise, errors, &mut rng);
        let out = calibrate_session_stats(&plan, &stats, &EstimateOptions::default()).unwrap();
        let dir = tempfile::tempdir().unwrap();
        let id = UnitId::parse_hex("000102030405060708090a0b").unwrap();
        let w = write_calibration_files(dir.path(), &out, id, 0, false).unwrap();
        let text = std::fs::read_to_string(&w.toml_path).unwrap();
        assert!(
            text.contains("[gyro]")
                && text.contains("bias_rad_s = [")
                && text.contains("matrix = ["),
            "{text}"
        );
        let back = UnitFile::load(&w.toml_path).unwrap().gyro.unwrap();
        let sb = back.bias_rad_s_1sigma.unwrap();
        let sg = back.matrix_1sigma.unwrap();
        for i in 0..3 {
            assert!((back.bias_rad_s[i] - b[i]).abs() < 5.0 * sb[i], "b{i}");
            for j in 0..3 {
                // Within 5σ (the misalignment's 1σ includes the body frame's alignment).
                assert!(
                    (back.matrix[i][j] - g[i][j]).abs() < 5.0 * sg[i][j],
                    "G{i}{j}"
                );
            }
        }
    }
}
