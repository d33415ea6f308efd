//! The autopilot round trip, as a drone integrator runs it: a vehicle's own log (written by the
//! tests' log writers with the vehicle's parameters) through `host segment` → `host calibrate` →
//! `host export --log`, against the same sensor's raw samples and the log's own ids and slots.

use super::log_fixture_tests::{command, fixture};
use super::segment::segment;
use super::{calibrate, export, Command};
use estimator::sim::handheld::{logger_unit, simulate_hand, HandSpec};
use recording::testkit::{
    ardupilot_default_params, write_dataflash_imus, write_ulog_imus, LogSample, UlogImu, UlogParam,
};
use shared::OutputUnit;
use std::collections::BTreeMap;
use std::path::{Path, PathBuf};

/// A simulated hand-held session's raw samples (the sensor's own output, m/s² and rad/s).
fn raw_session(seed: u64) -> Vec<LogSample> {
    let sim = simulate_hand(
        &logger_unit(OutputUnit::MetresPerSecondSquared),
        &HandSpec::standard(seed),
    );
    sim.rows
        .iter()
        .enumerate()
        .map(|(k, &(t, a, g))| LogSample {
            t_s: t,
            acc: a.map(|x| x as f32),
            gyro: g.map(|x| x as f32),
            temp_c: 30.0 + 1e-5 * k as f32,
        })
        .collect()
}

/// A vehicle's calibration of IMU `instance` as its PARM messages carry it: non-default offsets and
/// scales (up to 0.94 m/s² and 3.6 %, as real logs carry), gyro offsets and a board rotation.
fn vehicle_params(instance: u8, orientation: f32) -> Vec<(String, f32)> {
    let sfx = if instance == 0 {
        String::new()
    } else {
        (instance + 1).to_string()
    };
    let k = f32::from(instance);
    let mut v: Vec<(String, f32)> = ardupilot_default_params(3)
        .into_iter()
        .filter(|(n, _)| {
            !(n.starts_with(&format!("INS_ACC{sfx}OFFS"))
                || n.starts_with(&format!("INS_ACC{sfx}SCAL"))
                || n.starts_with(&format!("INS_GYR{sfx}OFFS"))
                || n == "AHRS_ORIENTATION")
        })
        .collect();
    v.push(("AHRS_ORIENTATION".into(), orientation));
    for (i, axis) in ["X", "Y", "Z"].iter().enumerate() {
        v.push((
            format!("INS_ACC{sfx}OFFS_{axis}"),
            [0.94, -0.31, 0.52][i] - 0.2 * k,
        ));
        v.push((
            format!("INS_ACC{sfx}SCAL_{axis}"),
            [1.036, 0.981, 1.012][i] + 0.004 * k,
        ));
        v.push((format!("INS_GYR{sfx}OFFS_{axis}"), [0.02, -0.011, 0.005][i]));
    }
    v
}

/// The samples as ArduPilot logs them (`_rotate_and_correct_accel`, `_rotate_and_correct_gyro`:
/// offsets, scales, then the board rotation, in `float`), with the rotation `rot`.
fn as_logged(
    raw: &[LogSample],
    params: &[(String, f32)],
    instance: u8,
    rot: fn([f32; 3]) -> [f32; 3],
) -> Vec<LogSample> {
    let p: BTreeMap<&str, f32> = params.iter().map(|(n, v)| (n.as_str(), *v)).collect();
    let sfx = if instance == 0 {
        String::new()
    } else {
        (instance + 1).to_string()
    };
    let get = |stem: &str, axis: usize| p[format!("{stem}_{}", ["X", "Y", "Z"][axis]).as_str()];
    raw.iter()
        .map(|s| {
            let acc = std::array::from_fn(|i| {
                (s.acc[i] - get(&format!("INS_ACC{sfx}OFFS"), i))
                    * get(&format!("INS_ACC{sfx}SCAL"), i)
            });
            let gyro = std::array::from_fn(|i| s.gyro[i] - get(&format!("INS_GYR{sfx}OFFS"), i));
            LogSample {
                acc: rot(acc),
                gyro: rot(gyro),
                ..*s
            }
        })
        .collect()
}

/// `Vector3::rotate(ROTATION_ROLL_180)` (`AP_Math/vector3.cpp`).
fn roll_180(v: [f32; 3]) -> [f32; 3] {
    [v[0], -v[1], -v[2]]
}

fn none(v: [f32; 3]) -> [f32; 3] {
    v
}

/// `host segment` then `host calibrate` of `log` (with `flags`) into `dir`; the calibration file.
fn calibrate_log(dir: &Path, log: &Path, flags: &str) -> PathBuf {
    let d = dir.display();
    let line = format!(
        "host segment -q --input {} --out {d}/s {flags}",
        log.display()
    );
    let Command::Segment(a) = command(&line) else {
        panic!("{line}")
    };
    segment(&a).unwrap_or_else(|e| panic!("{}: {e}", log.display()));
    let Command::Calibrate(c) = command(&format!("host calibrate --input {d}/s --out-dir {d}/cal"))
    else {
        panic!()
    };
    calibrate::calibrate(&c, true).unwrap();
    dir.join("cal/calibration.toml")
}

/// `host export` with `args` (`--out` added); the file's text.
fn export_text(dir: &Path, args: &str) -> String {
    let out = dir.join("exported.param");
    let line = format!("host export {args} --out {}", out.display());
    let Command::Export(a) = command(&line) else {
        panic!("{line}")
    };
    export::run(&a, true).unwrap_or_else(|e| panic!("{line}: {e}"));
    std::fs::read_to_string(&out).unwrap()
}

/// An ArduPilot `NAME,VALUE` file as a map.
fn ardupilot_values(text: &str) -> BTreeMap<String, f64> {
    text.lines()
        .filter(|l| !l.starts_with('#'))
        .filter_map(|l| l.split_once(','))
        .map(|(n, v)| (n.to_string(), v.parse().unwrap()))
        .collect()
}

/// A QGroundControl file's `name → value` (its five tab-separated columns).
fn px4_values(text: &str) -> BTreeMap<String, f64> {
    text.lines()
        .filter(|l| !l.starts_with('#'))
        .filter_map(|l| {
            let f: Vec<&str> = l.split('\t').collect();
            (f.len() == 5).then(|| (f[2].to_string(), f[3].parse().unwrap()))
        })
        .collect()
}

/// The offsets and scales of `slot` in two ArduPilot files agree within 3 mm/s² and 3·10⁻⁴.
fn assert_same_accel(got: &BTreeMap<String, f64>, want: &BTreeMap<String, f64>, sfx: &str) {
    for axis in ["X", "Y", "Z"] {
        let (o, s) = (
            format!("INS_ACC{sfx}OFFS_{axis}"),
            format!("INS_ACC{sfx}SCAL_{axis}"),
        );
        assert!(
            (got[&o] - want[&o]).abs() < 3e-3,
            "{o}: {} against {}",
            got[&o],
            want[&o]
        );
        assert!(
            (got[&s] - want[&s]).abs() < 3e-4,
            "{s}: {} against {}",
            got[&s],
            want[&s]
        );
    }
}

/// An ArduPilot log whose IMU messages carry the vehicle's non-default INS_ACCOFFS/INS_ACCSCAL and a
/// board rotation: the export made from it, with no --device-id, equals the one made from the
/// sensor's raw samples (offsets within 3 mm/s², scales within 3·10⁻⁴) and carries the log's
/// INS_ACC_ID. Read as logged, the fit would be the leftover: its offsets would be near 0, not the
/// sensor's (the check below that they differ by the vehicle's offsets).
#[test]
fn an_ardupilot_log_exports_the_sensors_calibration_for_its_own_id() {
    let tmp = tempfile::tempdir().unwrap();
    let raw = raw_session(21);
    let raw_log = tmp.path().join("raw.bin");
    std::fs::write(
        &raw_log,
        write_dataflash_imus(&[&raw], &ardupilot_default_params(1)),
    )
    .unwrap();
    let params = vehicle_params(0, 8.0);
    let logged = as_logged(&raw, &params, 0, roll_180);
    let vehicle_log = tmp.path().join("vehicle.bin");
    std::fs::write(&vehicle_log, write_dataflash_imus(&[&logged], &params)).unwrap();

    let want_cal = calibrate_log(&tmp.path().join("raw"), &raw_log, "");
    let got_cal = calibrate_log(&tmp.path().join("vehicle"), &vehicle_log, "");
    let export = |cal: &Path, log: &Path| {
        ardupilot_values(&export_text(
            tmp.path(),
            &format!(
                "--calibration {} --format ardupilot --log {} --force",
                cal.display(),
                log.display()
            ),
        ))
    };
    let want = export(&want_cal, &raw_log);
    let got = export(&got_cal, &vehicle_log);
    assert_same_accel(&got, &want, "");
    assert_eq!(got["INS_ACC_ID"], 2_753_028.0, "the log's INS_ACC_ID");
    assert_eq!(got["INS_GYR_ID"], 2_752_772.0, "the log's INS_GYR_ID");
    // What the vehicle's correction would have left: the sensor's offsets minus the vehicle's.
    let leftover = want["INS_ACCOFFS_X"] - 0.94;
    assert!(
        (got["INS_ACCOFFS_X"] - leftover).abs() > 0.5,
        "{} is the leftover",
        got["INS_ACCOFFS_X"]
    );
}

/// A ULog whose IMU's accelerometer is in slot 1 (CAL_ACC0_ID holds another sensor's id): the export
/// writes CAL_ACC1_* with the sensor's device id, and nothing in slot 0, which would un-calibrate
/// the other sensor (PX4 takes the first slot whose id matches: `FindCurrentCalibrationIndex`).
#[test]
fn a_ulog_sensor_in_slot_1_is_exported_to_slot_1() {
    let tmp = tempfile::tempdir().unwrap();
    let raw: Vec<LogSample> = raw_session(22).into_iter().take(400).collect();
    let (acc_id, gyro_id) = (1_311_004u32, 1_311_012u32);
    let params = [
        ("CAL_ACC0_ID", UlogParam::Int(1_310_988)),
        ("CAL_ACC1_ID", UlogParam::Int(acc_id as i32)),
        ("CAL_ACC1_XOFF", UlogParam::Float(0.1)),
        ("CAL_GYRO0_ID", UlogParam::Int(1_310_996)),
        ("CAL_GYRO1_ID", UlogParam::Int(gyro_id as i32)),
    ];
    let imu = UlogImu {
        samples: &raw,
        accel_id: acc_id,
        gyro_id,
    };
    let log = tmp.path().join("vehicle.ulg");
    std::fs::write(&log, write_ulog_imus(&[imu], &params, None)).unwrap();
    let text = export_text(
        tmp.path(),
        &format!(
            "--calibration {} --format px4 --log {}",
            fixture("hand.truth.toml").display(),
            log.display()
        ),
    );
    let v = px4_values(&text);
    assert_eq!(v["CAL_ACC1_ID"], f64::from(acc_id), "{text}");
    assert!(v.contains_key("CAL_ACC1_XOFF") && v.contains_key("CAL_ACC1_ZSCALE"));
    assert_eq!(v["CAL_GYRO1_ID"], f64::from(gyro_id), "{text}");
    assert!(
        !v.keys()
            .any(|k| k.starts_with("CAL_ACC0") || k.starts_with("CAL_GYRO0")),
        "slot 0 written: {text}"
    );
    // The slot and id the command line gives win over the log's.
    let text = export_text(
        tmp.path(),
        &format!(
            "--calibration {} --format px4 --log {} --slot 2 --device-id 77 --force",
            fixture("hand.truth.toml").display(),
            log.display()
        ),
    );
    assert_eq!(px4_values(&text)["CAL_ACC2_ID"], 77.0, "{text}");
}

/// A vehicle with three IMUs, each corrected by its own slot's parameters before logging: one
/// `--instance all` pass calibrates each and writes one file with the three slots, each slot with
/// its IMU's id and the calibration its raw samples give.
#[test]
fn a_three_imu_log_gives_one_file_with_three_slots() {
    let tmp = tempfile::tempdir().unwrap();
    let raw = raw_session(23);
    let mut params: Vec<(String, f32)> = ardupilot_default_params(3)
        .into_iter()
        .filter(|(n, _)| !(n.contains("OFFS_") || n.contains("SCAL_")))
        .collect();
    let mut logged = Vec::new();
    for i in 0..3u8 {
        let p = vehicle_params(i, 0.0);
        let sfx = if i == 0 {
            String::new()
        } else {
            (i + 1).to_string()
        };
        let own = |n: &str| {
            ["INS_ACC{}OFFS", "INS_ACC{}SCAL", "INS_GYR{}OFFS"]
                .iter()
                .any(|stem| n.starts_with(&stem.replace("{}", &sfx)))
        };
        params.extend(p.iter().filter(|(n, _)| own(n)).cloned());
        logged.push(as_logged(&raw, &p, i, none));
    }
    let three = tmp.path().join("three.bin");
    let imus: Vec<&[LogSample]> = logged.iter().map(Vec::as_slice).collect();
    std::fs::write(&three, write_dataflash_imus(&imus, &params)).unwrap();
    let raw_log = tmp.path().join("raw.bin");
    std::fs::write(
        &raw_log,
        write_dataflash_imus(&[&raw], &ardupilot_default_params(1)),
    )
    .unwrap();
    let raw_cal = calibrate_log(&tmp.path().join("raw"), &raw_log, "");
    let want = ardupilot_values(&export_text(
        tmp.path(),
        &format!(
            "--calibration {} --format ardupilot --log {}",
            raw_cal.display(),
            raw_log.display()
        ),
    ));
    let got = ardupilot_values(&export_text(
        tmp.path(),
        &format!(
            "--format ardupilot --log {} --instance all --force",
            three.display()
        ),
    ));
    for (i, sfx) in ["", "2", "3"].iter().enumerate() {
        assert_eq!(
            got[&format!("INS_ACC{sfx}_ID")],
            2_753_028.0 + 8.0 * i as f64,
            "slot {i}"
        );
        let in_slot0: BTreeMap<String, f64> = want
            .iter()
            .map(|(n, v)| (n.replacen("INS_ACC", &format!("INS_ACC{sfx}"), 1), *v))
            .collect();
        assert_same_accel(&got, &in_slot0, sfx);
    }
}

/// A PX4 vehicle with three IMUs, the log's parameters holding their ids in slots 2, 0 and 1:
/// `--instance all` writes one QGroundControl file with each IMU's calibration in the slot its id
/// holds, each as its own raw samples give it.
#[test]
fn a_three_imu_ulog_gives_one_file_with_each_imu_in_its_slot() {
    let tmp = tempfile::tempdir().unwrap();
    let raw = raw_session(24);
    let ids = [1_310_988u32, 1_311_004, 1_311_020];
    let imus: Vec<UlogImu<'_>> = ids
        .iter()
        .map(|&id| UlogImu {
            samples: &raw,
            accel_id: id,
            gyro_id: id + 4,
        })
        .collect();
    let slots = [2usize, 0, 1];
    let mut params = Vec::new();
    for (imu, &slot) in slots.iter().enumerate() {
        let name: &'static str = Box::leak(format!("CAL_ACC{slot}_ID").into_boxed_str());
        params.push((name, UlogParam::Int(ids[imu] as i32)));
    }
    let log = tmp.path().join("three.ulg");
    std::fs::write(&log, write_ulog_imus(&imus, &params, None)).unwrap();
    let one = tmp.path().join("one.ulg");
    std::fs::write(&one, write_ulog_imus(&imus[..1], &params, None)).unwrap();
    let want_cal = calibrate_log(&tmp.path().join("one"), &one, "");
    let want = px4_values(&export_text(
        tmp.path(),
        &format!(
            "--calibration {} --format px4 --log {}",
            want_cal.display(),
            one.display()
        ),
    ));
    let text = export_text(
        tmp.path(),
        &format!(
            "--format px4 --log {} --instance all --force",
            log.display()
        ),
    );
    let got = px4_values(&text);
    for (imu, &slot) in slots.iter().enumerate() {
        assert_eq!(
            got[&format!("CAL_ACC{slot}_ID")],
            f64::from(ids[imu]),
            "{text}"
        );
        for axis in ["X", "Y", "Z"] {
            let (o, s) = (format!("{axis}OFF"), format!("{axis}SCALE"));
            let (go, wo) = (
                got[&format!("CAL_ACC{slot}_{o}")],
                want[&format!("CAL_ACC2_{o}")],
            );
            let (gs, ws) = (
                got[&format!("CAL_ACC{slot}_{s}")],
                want[&format!("CAL_ACC2_{s}")],
            );
            assert!(
                (go - wo).abs() < 3e-3 && (gs - ws).abs() < 3e-4,
                "slot {slot}: {text}"
            );
        }
    }
}
