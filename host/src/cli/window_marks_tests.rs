//! The real recordings other people's loggers made (`host/tests/fixtures/corpus/`), read window
//! by window from the survey's marks against a pass over the whole file (the synthetic damaged
//! logs are `recording`'s own test, `tests/windows_from_marks.rs`).

use recording::session::import::{GyroUnit, ImportOptions, TimeSource};
use recording::session::logs::LogSource;
use recording::testkit::assert_windows_from_marks;
use shared::OutputUnit;
use std::path::Path;

/// A file of the corpus of real recordings, unpacked into `dir` when it is zstd-compressed.
fn corpus_file(dir: &Path, name: &str) -> std::path::PathBuf {
    let corpus = Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/fixtures/corpus");
    recording::testkit::unpacked(&corpus.join(name), dir)
}

/// The real recordings other people's loggers made, read window by window with a budget that
/// cuts each into many windows: every window read from the marks is the window a pass over the
/// whole file reads (their stamps as those loggers wrote them: a flight's, host-stamped bag's
/// lost packets, a device's own clock).
#[test]
fn real_recordings_read_from_the_marks_are_the_windows_a_whole_pass_reads() {
    let tmp = tempfile::tempdir().unwrap();
    let mut xio = ImportOptions::new(
        TimeSource::Column("Time (s)".into()),
        OutputUnit::StandardGravity,
        GyroUnit::DegPerS,
        crate::cli::spelling::FLAGS,
    );
    xio.columns = [
        "Accelerometer X (g)",
        "Accelerometer Y (g)",
        "Accelerometer Z (g)",
        "Gyroscope X (deg/s)",
        "Gyroscope Y (deg/s)",
        "Gyroscope Z (deg/s)",
    ]
    .map(String::from);
    let mut imucal = ImportOptions::new(
        TimeSource::RateHz(102.4),
        OutputUnit::MetresPerSecondSquared,
        GyroUnit::DegPerS,
        crate::cli::spelling::FLAGS,
    );
    imucal.columns = ["acc_x", "acc_y", "acc_z", "gyr_x", "gyr_y", "gyr_z"].map(String::from);
    let text = |options: ImportOptions| LogSource {
        text: Some(options),
        ..LogSource::default()
    };
    let cases = [
        ("px4ulogrs_quadrotor_local.ulg.zst", LogSource::default()),
        ("pyulog_sample.ulg.zst", LogSource::default()),
        ("imutools_ardrone_imu_ros2.mcap.zst", LogSource::default()),
        ("xio_fusion_sensor_data.csv.zst", text(xio)),
        ("imucal_ferraris_session.csv.zst", text(imucal)),
    ];
    for (name, source) in cases {
        let path = corpus_file(tmp.path(), name);
        for max_samples in [800, 3000] {
            assert_windows_from_marks(
                &path,
                &source,
                max_samples,
                &format!("{name}, budget {max_samples}"),
            );
        }
    }
}
