//! Text files as loggers write them: no header, a preamble before the header, empty cells, and
//! time stamps a host wrote in bursts.

use super::*;

fn read(text: &str, options: &ImportOptions) -> Result<Recording, ImportError> {
    read_logger(text.as_bytes(), Path::new("test.csv"), options)
}

/// `n` rows at 100 Hz with no header: time, still z up in m/s², a gyro ramp in x (so that each
/// row's values are its own).
fn body(n: usize) -> String {
    (0..n)
        .map(|i| {
            format!(
                "{:.2},0.01,-0.02,9.81,{:.4},0,0\n",
                i as f64 * 0.01,
                0.001 * i as f64
            )
        })
        .collect()
}

fn by_index(time: TimeSource) -> ImportOptions {
    ImportOptions {
        columns: ["1", "2", "3", "4", "5", "6"].map(String::from),
        ..ImportOptions::new(
            time,
            OutputUnit::MetresPerSecondSquared,
            GyroUnit::RadPerS,
            crate::testkit::SPELLING,
        )
    }
}

#[test]
fn a_header_less_file_is_read_by_column_index_and_named_as_such_when_read_by_name() {
    let text = body(300);
    // Columns 1, 2, 3 (acc), 4, 5, 6 (gyro), time 0.
    let rec = read(&text, &by_index(TimeSource::Column("0".into()))).unwrap();
    assert_eq!(rec.len(), 300, "the first line is data too");
    assert_eq!(rec.acc[0], [0.01, -0.02, 9.81]);
    assert!((rec.rate_hz - 100.0).abs() < 1e-6, "{}", rec.rate_hz);
    assert!(
        rec.read_notes
            .iter()
            .any(|n| n.to_string().contains("no header")),
        "{:?}",
        rec.read_notes
    );
    // No time column: the rate.
    let rec = read(&text, &by_index(TimeSource::RateHz(50.0))).unwrap();
    assert_eq!(rec.len(), 300);
    // Asked for by name, the file says it has no header and how to give the columns.
    let named = ImportOptions::new(
        TimeSource::Column("t".into()),
        OutputUnit::MetresPerSecondSquared,
        GyroUnit::RadPerS,
        crate::testkit::SPELLING,
    );
    let e = read(&text, &named).unwrap_err().to_string();
    assert!(
        e.contains("no header") && e.contains("<Columns> 0,1,2,3,4,5"),
        "{e}"
    );
}

#[test]
fn a_preamble_before_the_header_is_found_or_skipped_as_told() {
    let header = "t,acc_x,acc_y,acc_z,gyr_x,gyr_y,gyr_z\n";
    let data: String = (0..300)
        .map(|i| format!("{:.2},0.01,-0.02,9.81,0,0,0\n", i as f64 * 0.01))
        .collect();
    let text = format!("MicroLogger v3.1\nserial 0042, firmware 7\nrate 100 Hz\n{header}{data}");
    let o = ImportOptions::new(
        TimeSource::Column("t".into()),
        OutputUnit::MetresPerSecondSquared,
        GyroUnit::RadPerS,
        crate::testkit::SPELLING,
    );
    let found = read(&text, &o).unwrap();
    assert_eq!(found.len(), 300);
    assert!(
        found.read_notes.iter().any(|n| n
            .to_string()
            .contains("3 line(s) before the header on line 4")),
        "{:?}",
        found.read_notes
    );
    let told = read(
        &text,
        &ImportOptions {
            skip_lines: 3,
            ..o.clone()
        },
    )
    .unwrap();
    assert_eq!((told.len(), told.acc.clone()), (300, found.acc.clone()));
    assert!(told.read_notes.is_empty(), "{:?}", told.read_notes);
    // Told wrong: the line after the lines skipped is the header, and it names no such column.
    let e = read(&text, &ImportOptions { skip_lines: 2, ..o })
        .unwrap_err()
        .to_string();
    assert!(
        e.contains("'acc_x' is not in the header (rate, 100, Hz)"),
        "{e}"
    );
}

#[test]
fn empty_cells_cost_that_rows_stream_never_the_file() {
    // A logger interleaving accelerometer and gyro packets: each row leaves the other's cells
    // empty. The gyro ramps by 0.001 rad/s per row.
    let mut text = String::from("t,acc_x,acc_y,acc_z,gyr_x,gyr_y,gyr_z\n");
    for i in 0..400 {
        let t = i as f64 * 0.005;
        if i % 2 == 0 {
            text.push_str(&format!("{t:.3},0.01,-0.02,9.81,,,\n"));
        } else {
            text.push_str(&format!("{t:.3},,,,{:.4},0,0\n", 0.001 * i as f64));
        }
    }
    let o = ImportOptions::new(
        TimeSource::Column("t".into()),
        OutputUnit::MetresPerSecondSquared,
        GyroUnit::RadPerS,
        crate::testkit::SPELLING,
    );
    let rec = read(&text, &o).unwrap();
    // The accelerometer's rows, each with the gyro between its neighbours (the first has none
    // before it and is left out).
    assert_eq!(rec.len(), 199, "{:?}", rec.read_notes);
    assert!((rec.rate_hz - 100.0).abs() < 1e-6, "{}", rec.rate_hz);
    for (t, g) in rec.t_s.iter().zip(&rec.gyro_rad_s) {
        let want = 0.001 * (t / 0.005);
        assert!((g[0] - want).abs() < 1e-9, "at {t}: {g:?}, want {want}");
    }
    let said = rec
        .reader_warnings(Places::InFile)
        .iter()
        .map(ToString::to_string)
        .collect::<Vec<_>>()
        .join("\n");
    assert!(said.contains("200 row(s) without gyro values"), "{said}");
    assert!(!said.contains("NaN"), "{said}");
    // A single empty cell: that row's gyro comes from its neighbours, the file is read.
    let mut one = String::from("t,acc_x,acc_y,acc_z,gyr_x,gyr_y,gyr_z\n");
    for i in 0..300 {
        let gx = if i == 150 {
            String::new()
        } else {
            "0.5".into()
        };
        one.push_str(&format!("{:.2},0,0,9.81,{gx},0,0\n", i as f64 * 0.01));
    }
    let rec = read(&one, &o).unwrap();
    assert_eq!(rec.len(), 300);
    assert_eq!(rec.gyro_rad_s[150], [0.5, 0.0, 0.0]);
}

#[test]
fn host_stamped_bursts_are_re_timed_at_the_rate_the_stamps_fit() {
    // 99.3 Hz read by a host 10 samples at a time, each read's samples 2 ms apart.
    let mut text = String::from("t,acc_x,acc_y,acc_z,gyr_x,gyr_y,gyr_z\n");
    for i in 0..6000 {
        let t = ((i / 10 + 1) * 10) as f64 / 99.3 + 0.002 * (i % 10) as f64;
        text.push_str(&format!("{t:.6},0.01,-0.02,9.81,0,0,0\n"));
    }
    let o = ImportOptions::new(
        TimeSource::Column("t".into()),
        OutputUnit::MetresPerSecondSquared,
        GyroUnit::RadPerS,
        crate::testkit::SPELLING,
    );
    let rec = read(&text, &o).unwrap();
    assert!((rec.rate_hz - 99.3).abs() < 0.01, "{}", rec.rate_hz);
    let said = rec
        .reader_warnings(Places::InFile)
        .iter()
        .map(ToString::to_string)
        .collect::<Vec<_>>()
        .join("\n");
    assert!(
        said.contains("bursts") && said.contains("99.300 Hz"),
        "{said}"
    );
}
