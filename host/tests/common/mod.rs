//! Running the built `host` binary, shared by the integration tests.

use std::path::Path;
use std::process::Command;

/// Runs `host ARGS` (in `cwd` when given): success, stdout, stderr.
pub fn host_in(cwd: Option<&Path>, args: &[&str]) -> (bool, String, String) {
    let mut cmd = Command::new(env!("CARGO_BIN_EXE_host"));
    cmd.args(args);
    if let Some(d) = cwd {
        cmd.current_dir(d);
    }
    let out = cmd.output().expect("the host binary runs");
    (
        out.status.success(),
        String::from_utf8_lossy(&out.stdout).into_owned(),
        String::from_utf8_lossy(&out.stderr).into_owned(),
    )
}

/// How a `simulate-hand` CSV is read: its time column `t`, m/s² and °/s.
#[allow(dead_code)] // not every test file uses it
pub const HAND_CSV_READING: [&str; 6] = [
    "--time-column",
    "t",
    "--acc-unit",
    "m/s2",
    "--gyro-unit",
    "deg/s",
];

/// `host segment` arguments for a `simulate-hand` CSV ([`HAND_CSV_READING`]) into `out`.
#[allow(dead_code)] // not every test file uses it
pub fn hand_segment_args<'a>(csv: &'a str, out: &'a str) -> Vec<&'a str> {
    let mut v = vec!["segment", "--input", csv, "--out", out];
    v.extend(HAND_CSV_READING);
    v
}

/// Runs `host ARGS` unless it is still running after `limit`, when it is killed and `None` returned.
///
/// For the inputs that are endless (`/dev/zero`) or huge: a reader without a bound never ends on
/// them, and this tells that apart from one that refuses them however loaded the machine is; the
/// limit is a guard against a hang, not a measure of speed.
#[allow(dead_code)]
pub fn host_within(args: &[&str], limit: std::time::Duration) -> Option<(bool, String, String)> {
    use std::io::Read;
    let mut child = Command::new(env!("CARGO_BIN_EXE_host"))
        .args(args)
        .stdout(std::process::Stdio::piped())
        .stderr(std::process::Stdio::piped())
        .spawn()
        .expect("the host binary runs");
    let drain = |mut r: Box<dyn Read + Send>| {
        std::thread::spawn(move || {
            let mut text = String::new();
            let _ = r.read_to_string(&mut text);
            text
        })
    };
    let stdout = drain(Box::new(child.stdout.take().unwrap()));
    let stderr = drain(Box::new(child.stderr.take().unwrap()));
    let started = std::time::Instant::now();
    let status = loop {
        if let Some(status) = child.try_wait().unwrap() {
            break Some(status);
        }
        if started.elapsed() > limit {
            child.kill().unwrap();
            child.wait().unwrap();
            break None;
        }
        std::thread::sleep(std::time::Duration::from_millis(10));
    };
    let (stdout, stderr) = (stdout.join().unwrap(), stderr.join().unwrap());
    status.map(|s| (s.success(), stdout, stderr))
}

/// Runs `host ARGS` in the current directory.
#[allow(dead_code)] // not every test file uses both
pub fn host(args: &[&str]) -> (bool, String, String) {
    host_in(None, args)
}

/// The gyro of [`thermal_gyro_session`]'s unit: `[gyro]` of a unit file (w = G·ω + b, rad/s), and a
/// gyro bias that moves with temperature (rad/s per °C, per axis).
#[allow(dead_code)]
pub const THERMAL_GYRO_SECTION: &str = "[gyro]\nbias_rad_s = [0.01, -0.02, 0.015]\n\
     matrix = [[1.005, 0.002, -0.001], [0.001, 0.995, 0.003], [-0.002, 0.001, 1.01]]\n";

/// Writes a session of a unit with a known gyro and temperature model into `dir/name` (seed
/// `seed`): `host/units/thermal-mems.toml` with [`THERMAL_GYRO_SECTION`] and a gyro bias of
/// 2e-5 rad/s/°C on x, recorded on the `thermal-soak` plan (2 s a segment) followed by
/// `quick-oblique`'s spins at the reference temperature, so that one session calibrates the
/// accelerometers, the lever arms, the gyro and the temperature model. Returns the session
/// directory; the simulator's truth is its `truth.toml`.
#[allow(dead_code)]
pub fn thermal_gyro_session(dir: &Path, name: &str, seed: u64) -> std::path::PathBuf {
    let root = Path::new(env!("CARGO_MANIFEST_DIR"));
    let read = |p: &str| std::fs::read_to_string(root.join(p)).unwrap();
    let soak =
        read("../recording/plans/thermal-soak.toml").replace("duration_s = 20", "duration_s = 2");
    let quick = read("../recording/plans/quick-oblique.toml");
    let spins = &quick[quick.find("[[segment]]\nname = \"x+ 200\"").unwrap()..];
    let plan = format!(
        "{soak}\n{}",
        spins.replace("duration_s = 1\n", "duration_s = 1\ntemp_c = 25\n")
    );
    let unit = read("units/thermal-mems.toml")
        .replace(
            "[temperature]",
            &format!("{THERMAL_GYRO_SECTION}\n[temperature]"),
        )
        .replace(
            "[thermal]",
            "gyro_bias_rad_s_per_c = [[2e-5, 0.0, 0.0], [0.0, 0.0, 0.0], [0.0, 0.0, 0.0]]\n\n[thermal]",
        );
    let plan_path = dir.join(format!("{name}-plan.toml"));
    let unit_path = dir.join(format!("{name}-unit.toml"));
    std::fs::write(&plan_path, plan).unwrap();
    std::fs::write(&unit_path, unit).unwrap();
    let out = dir.join(name);
    let (ok, _, stderr) = host(&[
        "-q",
        "simulate",
        "--out",
        out.to_str().unwrap(),
        "--unit",
        unit_path.to_str().unwrap(),
        "--plan",
        plan_path.to_str().unwrap(),
        "--seed",
        &seed.to_string(),
    ]);
    assert!(ok, "{stderr}");
    out
}
