//! `host report` and `host compare` end to end, through files: a simulated session on disk, its
//! calibration written as `calibration.toml`, then the report and the comparison read those files.

use app::report::report;
use estimator::calibration_files::write_calibration_files;
use estimator::estimate::{calibrate_session_stats, EstimateOptions, Method};
use estimator::sim::{simulate_to_dir, NoiseModel};
use estimator::unit_file::UnitFile;
use outputs::export::{toml_forms::render as export, ExportFormat};
use outputs::report::compare::compare;
use outputs::report::plot::png_dimensions;
use outputs::report::{Compensation, ReportOptions, REPORT_HTML, REPORT_MD};
use recording::session::builtin::load_plan;
use recording::session::{read_session, ReadOptions};
use shared::UnitId;

#[test]
fn report_and_compare_from_files() {
    let tmp = tempfile::tempdir().unwrap();
    let session = tmp.path().join("session");
    let plan = load_plan("short").unwrap();
    simulate_to_dir(
        &session,
        &UnitFile::paper_unit(),
        &plan,
        &NoiseModel::default(),
        3,
        true,
    )
    .unwrap();
    let s = read_session(&session, &ReadOptions { quiet: true }).unwrap();
    let joint = calibrate_session_stats(&s.plan, &s.stats, &EstimateOptions::default()).unwrap();
    let id = UnitId([7; 12]);
    let a = write_calibration_files(&tmp.path().join("joint"), &joint, id, 0, false).unwrap();

    let out = tmp.path().join("report");
    let summary = report(
        &session,
        &a.toml_path,
        &out,
        &ReportOptions::new(recording::testkit::SPELLING),
    )
    .unwrap();
    // Every figure as PNG and SVG, and the two pages.
    assert_eq!(summary.files.len(), 4 * 2 + 2, "{:?}", summary.files);
    for f in &summary.files {
        let bytes = std::fs::read(f).unwrap();
        match f.extension().and_then(|e| e.to_str()) {
            Some("png") => assert!(png_dimensions(&bytes).is_some(), "{}", f.display()),
            Some("svg") => assert!(bytes.starts_with(b"<svg")),
            _ => {}
        }
    }
    assert_eq!(summary.page, out.join(REPORT_HTML));
    let md = std::fs::read_to_string(out.join(REPORT_MD)).unwrap();
    assert!(md.contains("Table 3. Lever arms") && md.contains("navigation_static.png"));
    // The calibration read from the file compensates this session's segments to their noise.
    for r in &summary.data.segments {
        let e = r.error_g(Compensation::Full);
        for j in 0..3 {
            assert!(e[j].abs() < 6.0 * r.sigma_g[j], "{} {j}: {e:?}", r.name);
        }
    }
    assert!(summary.render().contains("Navigation check"));

    // Compared with itself: 0σ everywhere; with the paper's eq. 24 on the same data: a few σ at most
    // on the determined parameters.
    let same = compare(&a.toml_path, &a.toml_path).unwrap();
    assert!(same.rows.iter().all(|r| r.diff_sigma == Some(0.0)));
    let eq24 = calibrate_session_stats(
        &s.plan,
        &s.stats,
        &EstimateOptions {
            method: Method::Paper,
            ..EstimateOptions::default()
        },
    )
    .unwrap();
    let b = write_calibration_files(&tmp.path().join("eq24"), &eq24, id, 0, false).unwrap();
    let t = compare(&a.toml_path, &b.toml_path).unwrap();
    let worst = t.worst().unwrap();
    assert!(worst.diff_sigma.unwrap().abs() < 5.0, "{}", t.render());

    // The export of the file's calibration has the three forms.
    let cal = UnitFile::load(&a.toml_path)
        .unwrap()
        .to_calibration()
        .unwrap();
    let text = export(&cal, ExportFormat::All).unwrap();
    for table in ["[plain]", "[fusion]", "[kalibr]"] {
        assert!(text.contains(table), "{text}");
    }
}
