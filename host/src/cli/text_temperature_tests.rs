//! A logger's CSV with the unit's temperature in a column (`host segment --temp-column`): the
//! fixtures' hand-held session, its temperature rising 24 → 24.6 °C with a missing reading every
//! 97th row. Every row is kept, the session records each row's temperature as the logger wrote
//! it, and the calibration is the one without the column (the simulated unit has no temperature
//! dependence, and a hand-held session determines no temperature model).

use super::log_fixture_tests::{assert_as_good, csv_reference, segment_and_calibrate};
use std::collections::HashMap;

/// The temperature the logger wrote at row `i` of `n`, `None` where it has no reading.
fn written(i: usize, n: usize) -> Option<f64> {
    (i % 97 != 50).then(|| 24.0 + 0.6 * i as f64 / n as f64)
}

#[test]
fn a_temperature_column_reaches_the_session_and_a_missing_reading_keeps_its_row() {
    let tmp = tempfile::tempdir().unwrap();
    let (csv_ug, csv_bias) = csv_reference(&tmp.path().join("csv"));
    let plain = std::fs::read_to_string(tmp.path().join("csv/hand.csv")).unwrap();
    let lines: Vec<&str> = plain.lines().collect();
    let n = lines.len() - 1;
    let mut text = format!("{},temp\n", lines[0]);
    let mut by_time: HashMap<i64, Option<f64>> = HashMap::new();
    for (i, line) in lines[1..].iter().enumerate() {
        let t: f64 = line.split(',').next().unwrap().parse().unwrap();
        let temp = written(i, n);
        by_time.insert((t * 1e6).round() as i64, temp);
        let field = temp.map_or("nan".to_string(), |c| c.to_string());
        text.push_str(&format!("{line},{field}\n"));
    }
    let dir = tmp.path().join("temp");
    std::fs::create_dir_all(&dir).unwrap();
    let input = dir.join("hand-temp.csv");
    std::fs::write(&input, text).unwrap();
    let (ug, bias) = segment_and_calibrate(
        &dir,
        &input,
        "--time-column t --acc-unit m/s2 --gyro-unit rad/s --temp-column temp",
    );
    println!(
        "without the column: {csv_ug:.1} µg, {csv_bias:.4} °/s; with it: {ug:.1} µg, {bias:.4} °/s"
    );
    assert_as_good("with the column", (ug, bias), (csv_ug, csv_bias));

    let samples = std::fs::read_to_string(dir.join("s/samples.csv")).unwrap();
    let mut rows = samples.lines();
    assert!(rows.next().unwrap().ends_with(",temp_c"));
    let (mut checked, mut missing) = (0, 0);
    for row in rows {
        let f: Vec<&str> = row.split(',').collect();
        let t: f64 = f[1].parse().unwrap();
        let temp: f64 = f[f.len() - 1].parse().unwrap();
        let want = by_time[&((t * 1e6).round() as i64)];
        match want {
            Some(c) => assert!((temp - c).abs() < 1e-9, "t {t}: {temp} for {c}"),
            None => {
                assert!(temp.is_nan(), "t {t}: {temp} where the logger wrote none");
                missing += 1;
            }
        }
        checked += 1;
    }
    println!("{checked} session rows checked, {missing} without a reading, kept");
    assert!(checked > 3000 && missing > 10, "{checked} {missing}");
}
