use super::*;
use crate::session::import::TimeSource;
use shared::OutputUnit;

fn stream(ts: &[f64], v: impl Fn(f64) -> [f64; 3], temp: Option<f64>) -> Stream {
    let mut s = Stream::default();
    for &t_s in ts {
        s.push(StreamSample {
            t_s,
            v: v(t_s),
            temp_c: temp,
        })
        .unwrap();
    }
    s
}

#[test]
fn the_format_is_told_by_the_first_bytes() {
    assert_eq!(
        LogFormat::detect(b"ULog\x01\x12\x35\x01rest"),
        LogFormat::Ulog
    );
    assert_eq!(
        LogFormat::detect(&[0xA3, 0x95, 0x80, 0x80, 89]),
        LogFormat::DataFlash
    );
    assert_eq!(LogFormat::detect(b"\x89MCAP0\r\n\x01"), LogFormat::Mcap);
    assert_eq!(LogFormat::detect(b"t,acc_x"), LogFormat::Text);
    // A DataFlash header followed by another message type is not taken as a log's start.
    assert_eq!(LogFormat::detect(&[0xA3, 0x95, 0x81]), LogFormat::Text);
}

#[test]
fn the_gyro_is_interpolated_to_the_accelerometers_times_and_gaps_are_not_bridged() {
    // Gyro at 100 Hz with a rate linear in time; accelerometer at 100 Hz, 3 ms later.
    let gt: Vec<f64> = (0..300).map(|i| i as f64 * 0.01).collect();
    let mut at: Vec<f64> = gt.iter().map(|t| t + 0.003).collect();
    // A gyro gap: the accelerometer samples inside it have no partner.
    let kept: Vec<f64> = gt
        .iter()
        .copied()
        .filter(|t| !(1.0..1.5).contains(t))
        .collect();
    let gyro = stream(&kept, |t| [t, -2.0 * t, 0.5], None);
    at.insert(10, at[10]); // a repeated time stamp
    let acc = stream(&at, |_| [0.0, 0.0, 9.81], Some(25.0));
    let (rec, warnings) = pair(acc, gyro, 0.05);
    let i = rec
        .t_s
        .iter()
        .position(|&t| (t - 0.503).abs() < 1e-9)
        .unwrap();
    assert!((rec.gyro_rad_s[i][0] - 0.503).abs() < 1e-12);
    assert!((rec.gyro_rad_s[i][1] + 1.006).abs() < 1e-12);
    assert!(rec.t_s.iter().all(|t| !(0.995..1.5).contains(t)));
    assert_eq!(rec.temp_c.as_ref().map(Vec::len), Some(rec.len()));
    assert!((rec.rate_hz - 100.0).abs() < 1e-6);
    // The repeat (same stamp, same values) is left out and said.
    assert_eq!(rec.time_repairs.len(), 1, "{:?}", rec.time_repairs);
    assert_eq!(rec.time_repairs[0].1.repeats, [11]);
    assert!(
        warnings
            .iter()
            .any(|w| w.to_string().contains("no gyro sample")),
        "{warnings:?}"
    );
    // The last accelerometer sample lies after the last gyro sample: left out too.
    assert!(rec.t_s.last().unwrap() < &2.99);
}

#[test]
fn options_that_do_not_fit_the_format_are_refused() {
    let source = LogSource {
        text: None,
        instance: Some(1),
        topic: None,
        spelling: Default::default(),
        rate_hz: None,
    };
    let text = b"t,acc_x,acc_y,acc_z,gyr_x,gyr_y,gyr_z\n";
    let e = read_log_from(&text[..], text, Path::new("x.csv"), &source).unwrap_err();
    assert!(
        matches!(
            e,
            LogError::OptionNotForFormat {
                option: "<Instance>",
                ..
            }
        ),
        "{e}"
    );
    let source = LogSource {
        instance: None,
        ..source
    };
    let e = read_log_from(&text[..], text, Path::new("x.csv"), &source).unwrap_err();
    assert!(e.to_string().contains("<AccUnit>"), "{e}");
}

#[test]
fn a_binary_file_of_another_format_is_named_as_such() {
    let source = LogSource {
        text: None,
        instance: None,
        topic: None,
        spelling: Default::default(),
        rate_hz: None,
    };
    let sqlite = b"SQLite format 3\0rest";
    let e = read_log_from(&sqlite[..], sqlite, Path::new("bag.db3"), &source).unwrap_err();
    let m = e.to_string();
    assert!(matches!(e, LogError::UnknownFormat { .. }), "{m}");
    assert!(m.contains("53514c69") && m.contains("mcap convert"), "{m}");
    // A ROS 1 bag: the conversion that re-encodes it for ROS 2, not `mcap convert`, whose output
    // keeps ROS 1's encoding.
    let ros1 = b"#ROSBAG V2.0\n\0\0\0rest";
    let e = read_log_from(&ros1[..], ros1, Path::new("a.bag"), &source).unwrap_err();
    let m = e.to_string();
    assert!(
        m.contains("ROS 1 bag: convert it with `rosbags-convert"),
        "{m}"
    );
    assert!(!m.contains("mcap convert"), "{m}");
}

/// A text file's temperature column: read beside the values, a missing reading ("nan", an empty
/// field, text) costs only that row's temperature, and a column with no reading at all is a log
/// without temperature, said so, as in the binary formats.
#[test]
fn a_text_files_temperature_column_is_read_and_a_missing_reading_keeps_its_row() {
    let text = |temp: &dyn Fn(usize) -> String| {
        let mut s = String::from("t,acc_x,acc_y,acc_z,gyr_x,gyr_y,gyr_z,temp\n");
        for i in 0..300 {
            let e = 1e-3 * ((i * 7 % 11) as f64 - 5.0);
            s.push_str(&format!(
                "{},{e},{},{},0.01,{e},0,{}\n",
                i as f64 * 0.01,
                -e,
                9.81 + e,
                temp(i)
            ));
        }
        s
    };
    let mut options = ImportOptions::new(
        TimeSource::Column("t".into()),
        OutputUnit::MetresPerSecondSquared,
        crate::session::import::GyroUnit::RadPerS,
        crate::testkit::SPELLING,
    );
    options.temp_column = Some("temp".into());
    let source = LogSource {
        text: Some(options),
        instance: None,
        topic: None,
        spelling: crate::testkit::SPELLING,
        rate_hz: None,
    };
    let some = text(&|i| match i {
        10 => "nan".into(),
        20 => String::new(),
        30 => "n/a".into(),
        _ => format!("{}", 20.0 + i as f64 / 100.0),
    });
    let log = read_log_from(
        some.as_bytes(),
        some.as_bytes(),
        Path::new("x.csv"),
        &source,
    )
    .unwrap();
    let rec = &log.recording;
    assert_eq!(rec.len(), 300);
    let temp = rec.temp_c.as_ref().unwrap();
    assert_eq!(temp[5], 20.0 + 5.0 / 100.0);
    assert_eq!(temp[299], 20.0 + 299.0 / 100.0);
    assert!(temp[10].is_nan() && temp[20].is_nan() && temp[30].is_nan());
    assert_eq!(temp.iter().filter(|t| t.is_finite()).count(), 297);
    assert!(
        log.warnings.iter().any(|w| w
            .to_string()
            .contains("3 of 300 samples have no temperature reading")),
        "{:?}",
        log.warnings
    );

    let none = text(&|_| "NaN".into());
    let log = read_log_from(
        none.as_bytes(),
        none.as_bytes(),
        Path::new("x.csv"),
        &source,
    )
    .unwrap();
    assert_eq!(log.recording.len(), 300);
    assert_eq!(log.recording.temp_c, None);
    assert!(
        log.warnings
            .iter()
            .any(|w| w.to_string().contains("NaN in every sample")),
        "{:?}",
        log.warnings
    );

    // A column the file does not have is named with the columns it has.
    let mut missing = source.clone();
    if let Some(o) = missing.text.as_mut() {
        o.temp_column = Some("temperature".into());
    }
    let e = read_log_from(
        some.as_bytes(),
        some.as_bytes(),
        Path::new("x.csv"),
        &missing,
    )
    .unwrap_err();
    assert!(e.to_string().contains("temperature"), "{e}");
}

/// An exact repeat of a sample without a temperature reading (NaN) is a repeat like any other:
/// left out, not spread as a sample of its own (which bent the rate).
#[test]
fn an_exact_repeat_without_a_temperature_reading_is_left_out() {
    let mut t: Vec<f64> = (0..400).map(|i| i as f64 * 0.01).collect();
    t.insert(201, t[200]);
    let values = |t: f64| [t.sin(), 0.0, 9.81];
    let acc = stream(&t, values, Some(f64::NAN));
    let gyro = stream(&t, values, None);
    let (rec, _) = pair(acc, gyro, 0.05);
    assert_eq!(rec.len(), 400);
    let repairs = &rec.time_repairs;
    assert!(
        repairs
            .iter()
            .any(|(_, r)| r.repeats == [201] && r.spread.is_empty()),
        "{repairs:?}"
    );
    assert_eq!(rec.rate_hz, 100.0);
}
