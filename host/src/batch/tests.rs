//! A lot of 50 simulated units with unit-to-unit spread, one of them bad.

use super::*;
use crate::session::builtin::builtin_plan;
use crate::sim::{simulate_to_dir, NoiseModel, Rng};
use crate::unit_file::UnitFile;

/// The paper's unit with a production spread: biases 2 mg, scale factors 0.2 %, angles 0.05°, 1σ.
pub(crate) fn lot_unit(i: u64, rng: &mut Rng) -> UnitFile {
    let mut u = UnitFile::paper_unit();
    let k = u.statics.scale_v_per_g.unwrap();
    let b = u.statics.zero_bias_v.as_mut().unwrap();
    for j in 0..3 {
        b[j] += 2e-3 * k[j] * rng.normal();
    }
    let s = u.statics.scale_v_per_g.as_mut().unwrap();
    for v in s.iter_mut() {
        *v *= 1.0 + 2e-3 * rng.normal();
    }
    for row in &mut u.statics.installation_angles_deg {
        for a in row.iter_mut() {
            *a += 0.05 * rng.normal();
        }
    }
    u.unit_id = Some(format!("{:024x}", 0xA000 + i));
    u
}

#[test]
fn fifty_units_one_bad_one_flagged() {
    let dir = tempfile::tempdir().unwrap();
    let input = dir.path().join("lot");
    let out = dir.path().join("out");
    let plan = builtin_plan("quick-oblique").unwrap().unwrap();
    let noise = NoiseModel {
        table_tilt_deg: 0.005,
        accel_quantum_out: 1e-5,
        gyro_bias_deg_s: [0.02, -0.01, 0.03],
        ..NoiseModel::default()
    };
    let mut rng = Rng::new(2024, 99);
    let bad = 17u64;
    for i in 0..50u64 {
        let mut unit = lot_unit(i, &mut rng);
        if i == bad {
            // A y-axis bias 25 mg off, against a 2 mg spread.
            let k = unit.statics.scale_v_per_g.unwrap()[1];
            unit.statics.zero_bias_v.as_mut().unwrap()[1] += 25e-3 * k;
        }
        simulate_to_dir(
            &input.join(format!("unit{i:02}")),
            &unit,
            &plan,
            &noise,
            100 + i,
            false,
        )
        .unwrap();
    }
    let sessions = find_sessions(&input).unwrap();
    assert_eq!(sessions.len(), 50);
    let opts = BatchOptions {
        estimate: EstimateOptions::default(),
        // The bad unit is within this limit: only the lot comparison can catch it.
        limits: Limits {
            max_misalignment_deg: Some(2.0),
            max_bias_sigma_mg: Some(1.0),
            ..Limits::default()
        },
        outlier_z: 5.0,
        jobs: Some(2),
        force: false,
    };
    let lot = run_batch(&sessions, &out, &opts, &ProgressBar::hidden()).unwrap();
    assert_eq!(lot.units.len(), 50);
    assert!(
        lot.units.iter().all(|u| u.error.is_none()),
        "{:?}",
        lot.failed()
    );
    let failed = lot.failed();
    assert_eq!(
        failed.len(),
        1,
        "{:#?}",
        failed
            .iter()
            .map(|u| (&u.session, &u.outliers))
            .collect::<Vec<_>>()
    );
    assert_eq!(failed[0].session, format!("unit{bad}"));
    assert!(
        failed[0]
            .outliers
            .iter()
            .any(|(n, z)| n == "bias_y" && *z > 5.0),
        "{:?}",
        failed[0].outliers
    );
    assert_eq!(lot.rows, 50 * 12_000);
    // The files, and the summary CSV with one row per unit.
    assert!(out.join("unit00").join(CALIBRATION_TOML).exists());
    let csv = to_csv(&lot);
    assert_eq!(csv.lines().count(), 51);
    assert!(csv.lines().next().unwrap().contains("bias_y,bias_y_sigma"));
    let bad_row = csv
        .lines()
        .find(|l| l.starts_with(&format!("unit{bad},")))
        .unwrap();
    assert!(bad_row.contains(",false,true,bias_y(z="), "{bad_row}");
    // Existing results are not overwritten without --force.
    let again = run_batch(&sessions[..1], &out, &opts, &ProgressBar::hidden()).unwrap();
    assert!(again.units[0].error.as_deref().unwrap().contains("--force"));
}

fn unit_with(value: f64, sigma: f64) -> UnitResult {
    UnitResult {
        session: format!("{value}"),
        rows: 1,
        summary: Some(CalibrationSummary {
            unit_id: None,
            parameters: vec![crate::summary::Parameter {
                name: "bias_x".into(),
                unit: "V".into(),
                value,
                sigma: Some(sigma),
            }],
            undetermined: Vec::new(),
            temperature: None,
            chi2: 1.0,
            dof: 1,
            chi2_per_dof: 1.0,
            checks: Vec::new(),
            passed: true,
            warnings: Vec::new(),
        }),
        error: None,
        outliers: Vec::new(),
        passed: false,
    }
}

#[test]
fn a_small_lot_of_equal_units_is_not_screened_below_its_own_noise() {
    // Six units whose values differ by noise of 1σ = 1.0: by chance the MAD is tiny (0.01), which
    // alone would make the 1.5σ unit a 100-z outlier; the 1σ floor keeps it a 1.5-z unit.
    let mut lot: Vec<UnitResult> = [0.0, 0.01, -0.01, 0.02, -0.02, 1.5]
        .iter()
        .map(|&v| unit_with(v, 1.0))
        .collect();
    flag_outliers(&mut lot, 5.0);
    assert!(
        lot.iter().all(|u| u.passed),
        "{:?}",
        lot.iter().map(|u| &u.outliers).collect::<Vec<_>>()
    );
    // A unit 10σ off is flagged.
    lot.push(unit_with(10.0, 1.0));
    for u in &mut lot {
        u.outliers.clear();
    }
    flag_outliers(&mut lot, 5.0);
    let flagged: Vec<&str> = lot
        .iter()
        .filter(|u| !u.passed)
        .map(|u| u.session.as_str())
        .collect();
    assert_eq!(flagged, vec!["10"]);
    // Fewer than MIN_LOT units: no screening.
    let mut small: Vec<UnitResult> = [0.0, 0.0, 100.0]
        .iter()
        .map(|&v| unit_with(v, 1.0))
        .collect();
    flag_outliers(&mut small, 5.0);
    assert!(small.iter().all(|u| u.passed));
}
