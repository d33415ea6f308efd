//! Reproduces the paper's story with the tool, through the library, and prints the navigation
//! position errors against their targets (`docs/paper-reproduction.md`, `docs/reproduce.sh`):
//!
//! 1. simulate the paper's unit (`reference/paper-unit.toml`) on the paper's plan, 1 mg white noise,
//!    seed 1, into `OUT/session` (what `host simulate` does);
//! 2. calibrate it with the joint method into `OUT/calibration/` and with the paper's eq. 24 into
//!    `OUT/calibration-eq24/` (what `host calibrate` does), and compare the two;
//! 3. write the report (figures, `report.html`, `report.md`) into `OUT/report/` (`host report`);
//! 4. export the joint calibration in the other tools' conventions (`host export --format all`).
//!
//! Usage: `cargo run --release -p host --example reproduce -- [OUT] [COPY_PNGS_TO]`
//! (OUT defaults to `target/paper-reproduction`).

use app::report::report;
use estimator::calibration_files::write_calibration_files;
use estimator::estimate::{calibrate_session_stats, EstimateOptions, Method};
use estimator::sim::{simulate_to_dir, NoiseModel};
use estimator::unit_file::UnitFile;
use outputs::export::{toml_forms::render as export, ExportFormat};
use outputs::report::compare::compare;
use outputs::report::{render_position_targets, ReportOptions};
use recording::session::builtin::paper_plan;
use recording::session::{read_session, ReadOptions};
use shared::UnitId;
use std::path::PathBuf;

const SEED: u64 = 1;

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let mut args = std::env::args().skip(1);
    let out = PathBuf::from(
        args.next()
            .unwrap_or_else(|| "target/paper-reproduction".into()),
    );
    let copy_to = args.next().map(PathBuf::from);
    let session = out.join("session");

    let unit = UnitFile::paper_unit();
    let noise = NoiseModel::default();
    let sim = simulate_to_dir(&session, &unit, &paper_plan(), &noise, SEED, true)?;
    println!(
        "simulated {} rows of the paper's plan ({} mg white noise, {} °/s gyro noise, seed {SEED}) into {}",
        sim.rows,
        noise.accel_white_mg,
        noise.gyro_white_deg_s,
        session.display()
    );

    let s = read_session(&session, &ReadOptions { quiet: true })?;
    let unit_id = UnitId([0; 12]);
    let joint = calibrate_session_stats(&s.plan, &s.stats, &EstimateOptions::default())?;
    // The example regenerates its own output directory on every run: replacing is its purpose.
    let joint_files = write_calibration_files(&out.join("calibration"), &joint, unit_id, 0, true)?;
    let eq24 = calibrate_session_stats(
        &s.plan,
        &s.stats,
        &EstimateOptions {
            method: Method::Paper,
            ..EstimateOptions::default()
        },
    )?;
    let eq24_files =
        write_calibration_files(&out.join("calibration-eq24"), &eq24, unit_id, 0, true)?;
    println!(
        "\n{}",
        outputs::report::render_session(&joint, &s.plan, &s.stats)
    );

    println!("Joint least squares (A) against the paper's eq. 24 (B):");
    println!(
        "{}",
        compare(&joint_files.toml_path, &eq24_files.toml_path)?.render()
    );

    let report_dir = out.join("report");
    let summary = report(
        &session,
        &joint_files.toml_path,
        &report_dir,
        &ReportOptions::new(recording::testkit::SPELLING),
    )?;
    println!("{}", summary.render());
    println!("{}", render_position_targets(&summary.data.navigation));

    let conversions = out.join("calibration").join("conversions.toml");
    std::fs::write(&conversions, export(&joint.calibration, ExportFormat::All)?)?;
    println!(
        "conversions (plain, Fusion, Kalibr): {}",
        conversions.display()
    );

    if let Some(dir) = copy_to {
        std::fs::create_dir_all(&dir)?;
        for f in &summary.files {
            if f.extension().is_some_and(|e| e == "png") {
                let to = dir.join(f.file_name().unwrap_or_default());
                std::fs::copy(f, &to)?;
                println!("copied {}", to.display());
            }
        }
    }
    Ok(())
}
