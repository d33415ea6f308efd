//! Two logs joined one after the other, the second's time restarting: read as two logs, the second
//! after the first, said so; not sorted into one that jumps between two attitudes every sample.

use recording::session::import::{GyroUnit, ImportOptions, Places, TimeSource};
use recording::session::logs::{read_log, LogSource};
use recording::session::segment::{find_intervals, SegmentOptions};
use recording::testkit::log_fixture;
use shared::OutputUnit;

#[test]
fn two_logs_joined_with_their_time_restarting_are_read_one_after_the_other() {
    let none = LogSource::default();
    let hand = read_log(&log_fixture("hand.ulg"), &none).unwrap().recording;
    let n = hand.len();
    let mut text = String::from("t,acc_x,acc_y,acc_z,gyr_x,gyr_y,gyr_z\n");
    // The second log: the same session, 1 mm/s² apart (another log, not a copy).
    let second = |k: usize, i: usize| hand.acc[i].map(|a| a + 1e-3 * k as f64);
    for k in 0..2 {
        for i in 0..n {
            let [ax, ay, az] = second(k, i);
            let [gx, gy, gz] = hand.gyro_rad_s[i];
            let t = hand.t_s[i] - hand.t_s[0];
            text.push_str(&format!("{t:.4},{ax},{ay},{az},{gx},{gy},{gz}\n"));
        }
    }
    let tmp = tempfile::tempdir().unwrap();
    let path = tmp.path().join("joined.csv");
    std::fs::write(&path, text).unwrap();
    let source = LogSource {
        text: Some(ImportOptions::new(
            TimeSource::Column("t".into()),
            OutputUnit::MetresPerSecondSquared,
            GyroUnit::RadPerS,
            recording::testkit::SPELLING,
        )),
        ..none
    };
    let log = read_log(&path, &source).unwrap_or_else(|e| panic!("{e}"));
    let rec = &log.recording;
    let said = rec.reader_warnings(Places::InFile);
    println!("{said:#?}");
    assert_eq!(rec.len(), 2 * n);
    assert!(rec.t_s.windows(2).all(|w| w[1] > w[0]));
    // The second log follows the first whole.
    for (row, k, i) in [(n - 1, 0, n - 1), (n, 1, 0), (2 * n - 1, 1, n - 1)] {
        let want = second(k, i);
        let off = (0..3)
            .map(|j| (rec.acc[row][j] - want[j]).abs())
            .fold(0.0, f64::max);
        assert!(off < 1e-9, "row {row}: {:?} against {want:?}", rec.acc[row]);
    }
    let restart = said
        .iter()
        .find(|w| w.to_string().contains("the stamps restart 1 time(s)"));
    assert!(
        restart.is_some_and(|w| w
            .to_string()
            .contains(&format!("data row {} stamped 0.000000 s", n + 1))),
        "{said:?}"
    );
    let once = find_intervals(&hand, &SegmentOptions::default()).unwrap();
    let twice = find_intervals(rec, &SegmentOptions::default()).unwrap();
    assert_eq!(twice.stills.len(), 2 * once.stills.len());
}
