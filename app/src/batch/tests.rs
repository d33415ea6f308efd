//! A lot of 50 simulated units with unit-to-unit spread, one of them bad; a lot of six with a bad
//! gyro; the screening of temperature coefficients and of repeated unit ids.

use super::*;
use estimator::calibration_files::CALIBRATION_TOML;
use estimator::sim::{simulate_to_dir, NoiseModel};
use estimator::unit_file::UnitFile;
use recording::session::builtin::builtin_plan;
use shared::rng::Rng;

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
    // Every row has every column.
    let columns = csv.lines().next().unwrap().split(',').count();
    assert!(csv.lines().all(|l| l.split(',').count() == columns));
    // Existing results are not overwritten without --force.
    let again = run_batch(&sessions[..1], &out, &opts, &ProgressBar::hidden()).unwrap();
    assert!(again.units[0].error.as_deref().unwrap().contains("--force"));
}

fn unit_with(value: f64, sigma: f64) -> UnitResult {
    unit_with_parameter("bias_x", value, Some(sigma))
}

fn unit_with_parameter(name: &str, value: f64, sigma: Option<f64>) -> UnitResult {
    UnitResult {
        session: format!("{value}"),
        rows: 1,
        summary: Some(CalibrationDocument::new(CalibrationSummary {
            unit_id: None,
            parameters: vec![outputs::summary::Parameter {
                name: name.into(),
                unit: "V".into(),
                value,
                sigma,
            }],
            undetermined: Vec::new(),
            temperature: None,
            calibration: None,
            chi2: 1.0,
            dof: 1,
            chi2_per_dof: 1.0,
            thermal_fit: None,
            checks: Vec::new(),
            passed: true,
            warnings: Vec::new(),
            in_package_size_effect: None,
            gyro_bias_walk_deg_s_sqrt_s: None,
            gyro_walk: None,
            bias_walk: None,
        })),
        error: None,
        outliers: Vec::new(),
        same_unit_id_as: Vec::new(),
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
    let warnings = flag_outliers(&mut small, 5.0);
    assert!(small.iter().all(|u| u.passed));
    // Its empty outlier columns say why, once.
    assert_eq!(warnings.len(), 1, "{warnings:?}");
    assert!(
        warnings[0].contains("3 calibrated unit(s), fewer than the 5"),
        "{warnings:?}"
    );
}

/// Five good units and one with a 5 % gyro scale error on x and a 5 °/s gyro bias: its
/// accelerometers are the others', so only the gyro's screening can catch it. The units are one
/// design without a production spread (six units are too few to tell a 0.05° spread from an
/// outlier: the MAD of six draws is itself uncertain by about half).
#[test]
fn six_units_one_with_a_bad_gyro_is_flagged() {
    let dir = tempfile::tempdir().unwrap();
    let input = dir.path().join("lot");
    let plan = builtin_plan("quick-oblique").unwrap().unwrap();
    let bad = 3u64;
    for i in 0..6u64 {
        let mut unit = UnitFile::paper_unit();
        unit.unit_id = Some(format!("{:024x}", 0xB000 + i));
        if i == bad {
            let mut matrix = [[1.0, 0.0, 0.0], [0.0, 1.0, 0.0], [0.0, 0.0, 1.0]];
            matrix[0][0] = 1.05;
            unit.gyro = Some(estimator::unit_file::GyroSection {
                bias_rad_s: [5f64.to_radians(), 0.0, 0.0],
                matrix,
                bias_rad_s_1sigma: None,
                matrix_1sigma: None,
            });
        }
        let noise = NoiseModel::default();
        simulate_to_dir(
            &input.join(format!("unit{i}")),
            &unit,
            &plan,
            &noise,
            40 + i,
            false,
        )
        .unwrap();
    }
    let sessions = find_sessions(&input).unwrap();
    let opts = BatchOptions {
        estimate: EstimateOptions::default(),
        limits: Limits::default(),
        outlier_z: 5.0,
        // More than the lot has sessions: one thread per session at most.
        jobs: Some(64),
    };
    let out = dir.path().join("out");
    let lot = run_batch(&sessions, &out, &opts, &ProgressBar::hidden()).unwrap();
    assert_eq!(lot.threads, 6);
    let failed: Vec<(&str, &Vec<(String, f64)>)> = lot
        .failed()
        .iter()
        .map(|u| (u.session.as_str(), &u.outliers))
        .collect();
    assert_eq!(failed.len(), 1, "{failed:#?}");
    assert_eq!(failed[0].0, format!("unit{bad}"));
    let flagged: Vec<&str> = failed[0].1.iter().map(|(n, _)| n.as_str()).collect();
    assert!(
        flagged.contains(&"gyro_g_xx") && flagged.contains(&"gyro_bias_x"),
        "{flagged:?}"
    );
    // Its accelerometers are not what flagged it.
    assert!(
        flagged.iter().all(|n| n.starts_with("gyro_")),
        "{flagged:?}"
    );
    // The CSV has the gyro's columns with their 1σ, the bad unit's value in them.
    let csv = to_csv(&lot);
    let header: Vec<&str> = csv.lines().next().unwrap().split(',').collect();
    let col = |name: &str| header.iter().position(|h| *h == name).unwrap();
    for name in [
        "gyro_g_xx_sigma",
        "gyro_bias_z_sigma",
        "temp_scale_x_c1_sigma",
    ] {
        col(name);
    }
    let bad_row: Vec<&str> = csv
        .lines()
        .find(|l| l.starts_with(&format!("unit{bad},")))
        .unwrap()
        .split(',')
        .collect();
    let g_xx: f64 = bad_row[col("gyro_g_xx")].parse().unwrap();
    let g_sigma: f64 = bad_row[col("gyro_g_xx_sigma")].parse().unwrap();
    assert!((g_xx - 1.05).abs() < 5.0 * g_sigma, "{g_xx} ± {g_sigma}");
    // No temperature model in this lot: its cells are empty, not zero.
    assert_eq!(bad_row[col("temp_scale_x_c1")], "");
}

#[test]
fn temperature_coefficients_are_screened_and_values_without_sigma_are_not() {
    let c1 = |v: f64| unit_with_parameter("temp_scale_x_c1", v, Some(2.5e-7));
    let mut lot: Vec<UnitResult> = [1.5e-4, 1.501e-4, 1.499e-4, 1.5e-4, 1.5005e-4]
        .iter()
        .map(|&v| c1(v))
        .collect();
    // 20σ off.
    lot.push(c1(1.5e-4 + 20.0 * 2.5e-7));
    // Above its chosen degree (no 1σ): the model's 0, not a measurement to screen.
    lot.push(unit_with_parameter("temp_scale_x_c1", 0.0, None));
    flag_outliers(&mut lot, 5.0);
    let flagged: Vec<&str> = lot
        .iter()
        .filter(|u| !u.passed)
        .map(|u| u.session.as_str())
        .collect();
    assert_eq!(flagged, vec![format!("{}", 1.5e-4 + 20.0 * 2.5e-7)]);
}

#[test]
fn units_claiming_one_id_fail_naming_each_other() {
    let mut lot: Vec<UnitResult> = (0..3).map(|i| unit_with(f64::from(i), 1.0)).collect();
    let names = ["lot/a", "lot/b", "lot/c"];
    for (u, name) in lot.iter_mut().zip(names) {
        u.session = name.into();
    }
    let id = |u: &mut UnitResult, hex: &str| {
        u.summary.as_mut().unwrap().summary.unit_id = Some(hex.into())
    };
    id(&mut lot[0], "00000000000000000000a001");
    id(&mut lot[1], "00000000000000000000a002");
    id(&mut lot[2], "00000000000000000000A001");
    flag_outliers(&mut lot, 5.0);
    assert!(lot[1].passed);
    assert_eq!(lot[0].same_unit_id_as, vec!["lot/c"]);
    assert_eq!(lot[2].same_unit_id_as, vec!["lot/a"]);
    assert!(!lot[0].passed && !lot[2].passed);
    assert!(
        lot[0].why_failed().contains("lot/c"),
        "{}",
        lot[0].why_failed()
    );
    // Sessions recorded without an id (all zero) are not one unit.
    let mut lot: Vec<UnitResult> = (0..2).map(|i| unit_with(f64::from(i), 1.0)).collect();
    for u in &mut lot {
        id(u, "000000000000000000000000");
    }
    flag_outliers(&mut lot, 5.0);
    assert!(lot.iter().all(|u| u.passed));
}

/// Six units in volts and one in m/s²: a bias of 9.8 "per g" is not an outlier of volts. Each unit
/// is screened among the units of its own output unit, the lot says it mixes them, and each row of
/// the summary names its unit.
#[test]
fn a_lot_of_mixed_output_units_is_screened_unit_by_unit() {
    let dir = tempfile::tempdir().unwrap();
    let input = dir.path().join("lot");
    let out = dir.path().join("out");
    let plan = builtin_plan("quick-oblique").unwrap().unwrap();
    let noise = NoiseModel::default();
    let mut rng = Rng::new(7, 3);
    for i in 0..6u64 {
        let unit = lot_unit(i, &mut rng);
        let session = input.join(format!("unit{i:02}"));
        simulate_to_dir(&session, &unit, &plan, &noise, 40 + i, false).unwrap();
    }
    let unit = shared::OutputUnit::MetresPerSecondSquared;
    let metric = UnitFile::from_calibration(
        &estimator::sim::handheld::logger_unit(unit),
        Some(UnitId::parse_hex("00000000000000000000b0b0").unwrap()),
        None,
    );
    let mut metric_plan = plan.clone();
    metric_plan.output_unit = unit;
    simulate_to_dir(
        &input.join("unit99"),
        &metric,
        &metric_plan,
        &noise,
        99,
        false,
    )
    .unwrap();
    let sessions = find_sessions(&input).unwrap();
    let opts = BatchOptions {
        estimate: EstimateOptions::default(),
        limits: Limits::default(),
        outlier_z: 5.0,
        jobs: Some(2),
    };
    let lot = run_batch(&sessions, &out, &opts, &ProgressBar::hidden()).unwrap();
    assert!(
        lot.units.iter().all(|u| u.error.is_none()),
        "{:?}",
        lot.failed()
    );
    let outliers: Vec<_> = lot
        .units
        .iter()
        .filter(|u| !u.outliers.is_empty())
        .collect();
    assert!(outliers.is_empty(), "{outliers:?}");
    assert_eq!(lot.warnings.len(), 1, "{:?}", lot.warnings);
    assert!(
        lot.warnings[0].contains("6 in V, 1 in m/s2"),
        "{:?}",
        lot.warnings
    );
    let csv = to_csv(&lot);
    let header: Vec<&str> = csv.lines().next().unwrap().split(',').collect();
    let col = header.iter().position(|h| *h == "output_unit").unwrap();
    let units: Vec<String> = csv
        .lines()
        .skip(1)
        .map(|l| l.split(',').nth(col).unwrap().to_string())
        .collect();
    assert_eq!(units, ["V", "V", "V", "V", "V", "V", "m/s2"]);
}

/// The temperature fit's worst χ²/dof (the figure the verdict checks) has its column; a unit
/// without a temperature model leaves it empty, not zero.
#[test]
fn the_temperature_fit_chi2_has_its_column() {
    let mut warm = unit_with(1.0, 0.1);
    let mut cold = unit_with(2.0, 0.1);
    warm.session = "warm".into();
    cold.session = "cold".into();
    if let Some(doc) = warm.summary.as_mut() {
        doc.summary.thermal_fit = Some(outputs::summary::ThermalFitSummary {
            chi2: [1722.0, 10.0, 10.0],
            dof: [10, 10, 10],
            chi2_per_dof: [172.2, 1.0, 1.0],
            worst_chi2_per_dof: 172.2,
        });
    }
    let csv = to_csv(&LotSummary {
        units: vec![warm, cold],
        rows: 2,
        seconds: 0.0,
        threads: 1,
        outlier_z: 5.0,
        warnings: Vec::new(),
    });
    let header: Vec<&str> = csv.lines().next().unwrap().split(',').collect();
    let col = header
        .iter()
        .position(|h| *h == "thermal_chi2_per_dof")
        .unwrap_or_else(|| panic!("{header:?}"));
    let cell = |session: &str| -> String {
        let row = csv.lines().find(|l| l.starts_with(session)).unwrap();
        row.split(',').nth(col).unwrap().to_string()
    };
    assert_eq!(cell("warm,").parse::<f64>().unwrap(), 172.2);
    assert_eq!(cell("cold,"), "");
}
