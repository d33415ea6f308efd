//! The README's "Load it" recipes, run as written in a fresh directory, each file checked by its
//! consumer's own rules: PX4's QGroundControl parameter file (five tab-separated fields, ids as
//! type 6 integers), ArduPilot's parameter file (`NAME,VALUE`, its device ids, the note on
//! `INS_GYR_CAL`), Kalibr's `imu.yaml` (the keys its `ConfigReader.py` reads, from a still
//! recording with known noise), and the C package, built and run. The Python recipe is run by
//! `python/tests/test_readme.py`.

use std::path::Path;
use std::process::Command;

fn section() -> String {
    let readme =
        std::fs::read_to_string(concat!(env!("CARGO_MANIFEST_DIR"), "/../README.md")).unwrap();
    readme
        .split("## Load it")
        .nth(1)
        .and_then(|s| s.split("\n## ").next())
        .expect("the README has a Load it section")
        .to_string()
}

fn run(dir: &Path, c: &str) {
    let out = Command::new(env!("CARGO_BIN_EXE_host"))
        .args(c.split_whitespace())
        .current_dir(dir)
        .output()
        .unwrap();
    assert!(
        out.status.success(),
        "{c}: {}",
        String::from_utf8_lossy(&out.stderr)
    );
}

/// `NAME` → value of a parameter file's lines (`split` the field separator, name and value at
/// `name_at` and `name_at + 1`), comments left out.
fn params(text: &str, split: char, name_at: usize) -> Vec<(String, String)> {
    text.lines()
        .filter(|l| !l.starts_with('#') && !l.trim().is_empty())
        .map(|l| {
            let f: Vec<&str> = l.split(split).collect();
            (f[name_at].to_string(), f[name_at + 1].to_string())
        })
        .collect()
}

/// The still recording the Kalibr recipe reads, logged like `hand.csv` (`t`, m/s², °/s), at rest
/// with +z up for 300 s at 200 Hz: on every axis white noise of density `N` and a random walk `K`
/// (accelerometer m/s²/√Hz and m/s³/√Hz, gyro °/s/√Hz and °/s²/√Hz), strong enough for 300 s to
/// determine both (K at about 5σ).
const STILL_ACC_N_K: (f64, f64) = (1.0e-3, 1.2e-3);
const STILL_GYRO_N_K_DEG: (f64, f64) = (0.01, 0.012);

fn write_still_csv(path: &Path) {
    use std::fmt::Write;
    let (rate_hz, rows) = (200.0f64, 60_000usize);
    let mut rng = shared::rng::Rng::new(5, 0);
    let mut walk = [0.0f64; 6];
    let mut text = String::from("t,acc_x,acc_y,acc_z,gyr_x,gyr_y,gyr_z\n");
    for k in 0..rows {
        write!(text, "{}", k as f64 / rate_hz).unwrap();
        for (j, w) in walk.iter_mut().enumerate() {
            let (n, kw) = if j < 3 {
                STILL_ACC_N_K
            } else {
                STILL_GYRO_N_K_DEG
            };
            *w += kw / rate_hz.sqrt() * rng.normal();
            let g = if j == 2 { 9.80665 } else { 0.0 };
            write!(text, ",{}", g + *w + n * rate_hz.sqrt() * rng.normal()).unwrap();
        }
        text.push('\n');
    }
    std::fs::write(path, text).unwrap();
}

/// Kalibr's `imu.yaml` (`kalibr_common/ConfigReader.py`, `ImuParameters`): the noise figures in
/// its units (the worst axis), within 10 % (N) and 35 % (K, whose 1σ is about 10 % on 300 s) of
/// the recording's.
fn check_kalibr(dir: &Path) {
    let yaml = std::fs::read_to_string(dir.join("imu.yaml")).unwrap();
    let field = |k: &str| -> f64 {
        yaml.lines()
            .find_map(|l| l.strip_prefix(&format!("{k}:")))
            .unwrap_or_else(|| panic!("{k} missing: {yaml}"))
            .split('#')
            .next()
            .unwrap()
            .trim()
            .parse()
            .unwrap()
    };
    let rad = std::f64::consts::PI / 180.0;
    let (an, ak) = STILL_ACC_N_K;
    let (gn, gk) = STILL_GYRO_N_K_DEG;
    for (k, truth, tol) in [
        ("accelerometer_noise_density", an, 0.10),
        ("accelerometer_random_walk", ak, 0.35),
        ("gyroscope_noise_density", gn * rad, 0.10),
        ("gyroscope_random_walk", gk * rad, 0.35),
        ("update_rate", 200.0, 1e-9),
    ] {
        let v = field(k);
        assert!(
            (v / truth - 1.0).abs() < tol,
            "{k} = {v}, simulated {truth}"
        );
    }
    assert!(yaml.contains("rostopic:"), "{yaml}");
}

#[test]
fn readme_load_it_recipes_work_as_written() {
    let section = section();
    let commands: Vec<&str> = section
        .lines()
        .filter_map(|l| l.strip_prefix("host "))
        .collect();
    assert_eq!(commands.len(), 8, "{commands:?}");
    let dir = tempfile::tempdir().unwrap();
    write_still_csv(&dir.path().join("still.csv"));
    for c in &commands {
        run(dir.path(), c);
    }
    // PX4: QGroundControl reads `sysid compid name value type`, tab-separated (type 6 an int32).
    let px4 = std::fs::read_to_string(dir.path().join("px4.params")).unwrap();
    for line in px4.lines().filter(|l| !l.starts_with('#') && !l.is_empty()) {
        assert_eq!(line.split('\t').count(), 5, "{line}");
    }
    let px4 = params(&px4.replace('\t', " "), ' ', 2);
    let get = |p: &[(String, String)], k: &str| {
        p.iter()
            .find(|(n, _)| n == k)
            .map(|(_, v)| v.clone())
            .unwrap_or_else(|| panic!("{k} missing"))
    };
    assert_eq!(get(&px4, "CAL_ACC0_ID"), "1310988");
    // PX4's `param load` resets every parameter before it reads a binary file: the PX4 file and the
    // README's PX4 recipe name it only to forbid it, and give `param set` and `param save` instead.
    let px4_text = std::fs::read_to_string(dir.path().join("px4.params")).unwrap();
    let px4_recipe = section
        .split("- **PX4**")
        .nth(1)
        .and_then(|s| s.split("- **ArduPilot**").next())
        .unwrap();
    for (what, text) in [
        ("the PX4 file", px4_text.as_str()),
        ("the README", px4_recipe),
    ] {
        let flat = text.replace("\n# ", " ").replace('\n', " ").to_lowercase();
        assert_eq!(
            flat.matches("param load").count(),
            flat.matches("never `param load`").count()
                + flat.matches("never with px4's `param load`").count(),
            "{what} names `param load` as a step: {text}"
        );
        assert!(
            flat.contains("param set") && flat.contains("param save"),
            "{what}: {text}"
        );
    }
    assert!(px4_text.contains("IMU_GYRO_CAL_EN"), "{px4_text}");
    assert_eq!(get(&px4, "CAL_GYRO0_ID"), "1310996");
    for k in ["CAL_ACC0_XSCALE", "CAL_ACC0_YSCALE", "CAL_ACC0_ZSCALE"] {
        let v: f64 = get(&px4, k).parse().unwrap();
        assert!((v - 1.0).abs() < 0.05, "{k} = {v}");
    }
    // ArduPilot: `NAME,VALUE`; the ids it compares at start-up, and what to do about INS_GYR_CAL.
    let ap_text = std::fs::read_to_string(dir.path().join("ardupilot.parm")).unwrap();
    let ap = params(&ap_text, ',', 0);
    assert_eq!(get(&ap, "INS_ACC_ID"), "2753028");
    assert_eq!(get(&ap, "INS_GYR_ID"), "2752772");
    for k in ["INS_ACCOFFS_X", "INS_ACCOFFS_Y", "INS_ACCOFFS_Z"] {
        let v: f64 = get(&ap, k).parse().unwrap();
        assert!(v.abs() <= 3.5, "{k} = {v} outside ArduPilot's range");
    }
    assert!(ap_text.contains("INS_GYR_CAL = 0"), "{ap_text}");
    check_kalibr(dir.path());
    // The C package: built with the README's own line and run.
    let acal = dir.path().join("acal");
    let cc = section
        .split('`')
        .find(|s| s.starts_with("cc "))
        .expect("the README gives the cc line");
    let out = Command::new("sh")
        .arg("-c")
        .arg(format!("{cc} && ./example"))
        .current_dir(&acal)
        .output()
        .expect("sh runs");
    assert!(
        out.status.success(),
        "{cc}: {}",
        String::from_utf8_lossy(&out.stderr)
    );
    assert!(!out.stdout.is_empty());
}
