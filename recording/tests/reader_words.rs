//! What each reader says of a damaged log, word for word: one `check` per reader renders what a
//! user is told (the rows read and their rate, or the refusal; then every note, the log's own and
//! the recording's, as `segment` prints them) against a snapshot. A change of wording shows here as
//! a diff to review; `UPDATE_EXPECT=1 cargo test -p recording --test reader_words` rewrites the
//! snapshots after a deliberate one. The logs are written here from stated samples
//! (`recording::testkit`), each with one kind of damage a logger or a disk makes.

use expect_test::{expect, Expect};
use recording::session::import::Places;
use recording::session::logs::{read_log_from, LogSource};
use recording::testkit::{
    csv_source, still_sample, write_csv, write_dataflash, write_mcap, write_mcap_unstamped,
    write_mcap_with, write_ulog, LogSample,
};
use std::path::Path;

/// A unit at rest, z up, 100 Hz, 3 s.
fn still() -> Vec<LogSample> {
    (0..300).map(|k| still_sample(k, 100.0)).collect()
}

/// What a user is told of `bytes` read as the file `name` (its extension names a text file).
fn said(bytes: &[u8], name: &str, source: &LogSource) -> String {
    match read_log_from(bytes, bytes, Path::new(name), source) {
        Err(e) => format!("refused: {}\n", shared::chain::Chain(&e)),
        Ok(log) => {
            let rec = &log.recording;
            let mut out = format!("{} rows at {:.3} Hz\n", rec.len(), rec.rate_hz);
            let notes = log.warnings.iter().map(|w| w.to_string());
            for note in notes.chain(
                rec.reader_warnings(Places::InFile)
                    .iter()
                    .map(|w| w.to_string()),
            ) {
                out.push_str(&format!("- {note}\n"));
            }
            out
        }
    }
}

fn check_ulog(bytes: &[u8], expect: Expect) {
    expect.assert_eq(&said(bytes, "log.ulg", &LogSource::default()));
}

fn check_dataflash(bytes: &[u8], expect: Expect) {
    expect.assert_eq(&said(bytes, "log.bin", &LogSource::default()));
}

fn check_mcap(bytes: &[u8], expect: Expect) {
    expect.assert_eq(&said(bytes, "log.mcap", &LogSource::default()));
}

fn check_text(bytes: &[u8], expect: Expect) {
    expect.assert_eq(&said(bytes, "log.csv", &csv_source()));
}

/// Three samples with values that are not finite.
fn with_nan(mut s: Vec<LogSample>) -> Vec<LogSample> {
    s[40].acc[1] = f32::NAN;
    s[41].gyro[2] = f32::INFINITY;
    s[200].acc = [f32::NAN; 3];
    s
}

/// Two neighbours' stamps swapped, and one stamp 0.5 s early.
fn with_stamps_out_of_order(mut s: Vec<LogSample>) -> Vec<LogSample> {
    let t = s[100].t_s;
    s[100].t_s = s[101].t_s;
    s[101].t_s = t;
    s[250].t_s -= 0.5;
    s
}

#[test]
fn ulog() {
    check_ulog(
        &write_ulog(&still(), Some(150)),
        expect![[r#"
        300 rows at 100.000 Hz
        - the logger dropped data 1 time(s), 20 ms in all; the first at byte 15299 (t = 2.500 s), 20 ms: no still interval or turn should span a dropout
    "#]],
    );
    check_ulog(
        &write_ulog(&with_nan(still()), None),
        expect![[r#"
        298 rows at 100.000 Hz
        - 1 gyro sample(s) with NaN or infinite values left out (the rate interpolated between their neighbours)
        - 2 row(s) with NaN or infinite values left out
    "#]],
    );
    check_ulog(
        &write_ulog(&with_stamps_out_of_order(still()), None),
        expect![[r#"
            300 rows at 100.000 Hz
            - time stamps repaired: 1 isolated stamp(s) that jumped and came back re-timed from their neighbours (IMU sample 251 stamped 3.000000 s, re-timed to 3.500000 s); 2 sample(s) out of order sorted into time order
        "#]],
    );
    let bytes = write_ulog(&still(), None);
    check_ulog(
        &bytes[..bytes.len() - 30],
        expect![[r#"
        299 rows at 100.000 Hz
        - the log's last message (at byte 29852) is cut short: it is left out
        - 1 accelerometer sample(s) with no gyro sample within 50 ms left out
    "#]],
    );
    check_ulog(
        &bytes[..200],
        expect![[r#"
        refused: log.ulg: no IMU samples for instance 0: the log has no sensor_accel, sensor_gyro or sensor_combined topic; log sensor_accel and sensor_gyro (or sensor_combined) and choose the IMU with <Instance> N
    "#]],
    );
}

#[test]
fn dataflash() {
    let mut bytes = write_dataflash(&still());
    let at = bytes.len() / 2;
    bytes.splice(at..at, [0x11, 0xA3, 0x00, 0x42, 0x95, 0x07, 0x00]);
    check_dataflash(
        &bytes,
        expect![[r#"
        299 rows at 100.000 Hz
        - 7 byte(s) that start no known message were skipped, the first at byte 8469 (damage or padding in the log, as pymavlink skips them)
    "#]],
    );
    check_dataflash(
        &write_dataflash(&with_nan(still())),
        expect![[r#"
        298 rows at 100.000 Hz
        - 1 gyro sample(s) with NaN or infinite values left out (the rate interpolated between their neighbours)
        - 2 row(s) with NaN or infinite values left out
    "#]],
    );
    check_dataflash(
        &write_dataflash(&with_stamps_out_of_order(still())),
        expect![[r#"
            300 rows at 100.000 Hz
            - time stamps repaired: 1 isolated stamp(s) that jumped and came back re-timed from their neighbours (IMU sample 251 stamped 2.000000 s, re-timed to 2.500000 s); 2 sample(s) out of order sorted into time order
        "#]],
    );
    let bytes = write_dataflash(&still());
    // Cut one byte into the last message: its sync byte alone is left.
    let last = bytes.windows(2).rposition(|w| w == [0xA3, 0x95]).unwrap();
    check_dataflash(
        &bytes[..last + 1],
        expect![[r#"
        299 rows at 100.000 Hz
        - the log's last message (at byte 16785) is cut short: it is left out
    "#]],
    );
    check_dataflash(
        &bytes[..bytes.len() - 20],
        expect![[r#"
        299 rows at 100.000 Hz
        - the log's last message (at byte 16785) is cut short: it is left out
    "#]],
    );
}

#[test]
fn mcap() {
    check_mcap(
        &write_mcap_unstamped(&still()),
        expect![[r#"
        300 rows at 100.000 Hz
        - the 300 Imu messages have no header stamp (all 0): timed by the bag's log time, when the recorder received them
    "#]],
    );
    check_mcap(
        &write_mcap_with(&still(), None, 0.0, Some(120)),
        expect![[r#"
            300 rows at 100.000 Hz
        "#]],
    );
    check_mcap(
        &write_mcap(&with_nan(still()), None, 0.0),
        expect![[r#"
        298 rows at 100.000 Hz
        - 1 gyro sample(s) with NaN or infinite values left out (the rate interpolated between their neighbours)
        - 2 row(s) with NaN or infinite values left out
    "#]],
    );
    let bytes = write_mcap(&still(), None, 0.0);
    check_mcap(
        &bytes[..bytes.len() / 2],
        expect![[r#"
        refused: log.mcap: not a readable MCAP file (after byte 54734): MCAP file ended in the middle of a record; check it with `mcap doctor`
    "#]],
    );
}

#[test]
fn text() {
    let mut lines: Vec<String> = String::from_utf8(write_csv(&still()))
        .unwrap()
        .lines()
        .map(str::to_string)
        .collect();
    let rest = lines[50].split_once(',').unwrap().1.to_string();
    lines[50] = format!("nan,{rest}");
    lines.insert(
        120,
        "x".repeat(recording::session::import::MAX_LINE_BYTES + 10),
    );
    let repeated = lines[200].clone();
    lines.insert(200, repeated);
    let mut text = lines.join("\n");
    text.truncate(text.len() - 3);
    check_text(
        text.as_bytes(),
        expect![[r#"
        298 rows at 100.000 Hz
        - 1 row(s) with NaN or infinite values left out
        - 1 line(s) longer than 65536 bytes left out as damaged (line 121)
        - line 303, the last, has no line end: the file was cut short; that line is left out
        - time stamps repaired: 1 exact repeat(s) (same stamp, same values) left out (data row 199)
    "#]],
    );
    check_text(
        &write_csv(&with_nan(still())),
        expect![[r#"
        298 rows at 100.000 Hz
        - 1 row(s) without gyro values and 2 with the gyro's alone (a logger writing each sensor's packets in rows of their own, or cells left empty): the accelerometer's rows take the gyro's rate interpolated from the nearest rows that have one
    "#]],
    );
    check_text(
        &write_csv(&with_stamps_out_of_order(still())),
        expect![[r#"
            300 rows at 100.000 Hz
            - time stamps repaired: 1 isolated stamp(s) that jumped and came back re-timed from their neighbours (data row 251 stamped 2.000000 s, re-timed to 2.500000 s); 2 sample(s) out of order sorted into time order
        "#]],
    );
}
