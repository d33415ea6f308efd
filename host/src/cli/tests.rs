//! Tests of the command line: parsing, and each command run end to end on the simulator or the
//! simulated device.

use super::calibrate::{calibrate, calibrate_options};
use super::port::{connect, PortArgs, SIM_PORT};
use super::simulate::noise_from_args;
use super::*;
use clap::CommandFactory;
use device::sim::SIM_UNIT_ID;
use device::LinkError;
use estimator::estimate::Method;
use estimator::sim::NoiseModel;
use outputs::export::ExportFormat;
use shared::blob::ParameterBlob;
use shared::wire::DeviceError;
use shared::UnitId;
use std::path::PathBuf;

fn parse(args: &[&str]) -> Cli {
    Cli::try_parse_from(std::iter::once("host").chain(args.iter().copied())).unwrap()
}

/// `host simulate --help` names every built-in plan (its list is written out in the help).
#[test]
fn simulate_help_names_every_built_in_plan() {
    let mut cmd = Cli::command();
    let help = cmd
        .find_subcommand_mut("simulate")
        .expect("simulate is a subcommand")
        .render_long_help()
        .to_string();
    for (name, _) in recording::session::builtin::BUILTIN_PLANS {
        assert!(
            help.contains(name),
            "`host simulate --help` omits the plan {name}"
        );
    }
}

#[test]
fn the_command_line_is_well_formed() {
    Cli::command().debug_assert();
    let cli = parse(&[
        "simulate",
        "--out",
        "d",
        "--seed",
        "9",
        "--gyro-bias-deg-s",
        "0.1,-0.2,0.3",
        "--rate-offset-deg-s",
        "-0.5",
    ]);
    let Command::Simulate(a) = cli.command else {
        panic!("not simulate")
    };
    let n = noise_from_args(&a, &UnitFile::paper_unit()).unwrap();
    assert_eq!(n.gyro_bias_deg_s, [0.1, -0.2, 0.3]);
    assert_eq!(n.table_rate_offset_deg_s, -0.5);
    assert_eq!(n.accel_white_mg, 1.0);
    let Command::Calibrate(c) = parse(&["calibrate", "--input", "x", "--method", "paper"]).command
    else {
        panic!("not calibrate")
    };
    assert_eq!(
        calibrate_options(&c).unwrap().estimate.method,
        Method::Paper
    );
    // The estimator's flags are one set, shared by calibrate and batch.
    let Command::Calibrate(c) = parse(&["calibrate", "--input", "x", "--single-package"]).command
    else {
        panic!("not calibrate")
    };
    assert!(calibrate_options(&c).unwrap().estimate.single_package);
    let Command::Batch(b) = parse(&[
        "batch",
        "--input",
        "i",
        "--out",
        "o",
        "--single-package",
        "--reference",
        "centroid",
    ])
    .command
    else {
        panic!("not batch")
    };
    let o = b.estimator.options().unwrap();
    assert!(o.single_package);
    assert_eq!(o.reference, estimator::estimate::ReferenceChoice::Centroid);
    assert!(Cli::try_parse_from(["host", "calibrate", "--method", "best"]).is_err());
    let Command::Calibrate(c) = parse(&["calibrate", "--input", "d", "--plan", "paper"]).command
    else {
        panic!("not calibrate")
    };
    let e = calibrate(&c, true).unwrap_err().to_string();
    assert!(e.contains("--plan") && e.contains("plan.toml"), "{e}");
    let Command::Calibrate(c) = parse(&[
        "calibrate",
        "--port",
        "sim",
        "--plan",
        "short",
        "--window",
        "20",
    ])
    .command
    else {
        panic!("not calibrate")
    };
    assert_eq!((c.port.as_deref(), c.window), (Some("sim"), Some(20)));
    let Command::Flash(flash::FlashArgs { port, calibration }) =
        parse(&["flash", "--port", "/dev/ttyACM0", "--calibration", "c.bin"]).command
    else {
        panic!("not flash")
    };
    assert_eq!(
        (port.port.as_str(), calibration),
        ("/dev/ttyACM0", PathBuf::from("c.bin"))
    );
}

#[test]
fn report_compare_export_and_navigation_check_parse() {
    let Command::Report(r) = parse(&["report", "--input", "s", "--no-png"]).command else {
        panic!("not report")
    };
    assert!(r.no_png && r.calibration.is_none() && r.duration_s == 60.0);
    let Command::Compare(compare::CompareArgs { a, b, .. }) =
        parse(&["compare", "a.toml", "b.toml"]).command
    else {
        panic!("not compare")
    };
    assert_eq!((a, b), (PathBuf::from("a.toml"), PathBuf::from("b.toml")));
    let Command::Export(export::ExportArgs { format, .. }) =
        parse(&["export", "--calibration", "c.toml", "--format", "fusion"]).command
    else {
        panic!("not export")
    };
    assert_eq!(format, ExportFormat::Fusion);
    assert!(
        Cli::try_parse_from(["host", "export", "--calibration", "c", "--format", "x"]).is_err()
    );
    let Command::NavigationCheck(n) =
        parse(&["navigation-check", "--seed", "3", "--plan", "short"]).command
    else {
        panic!("not navigation-check")
    };
    assert_eq!((n.seed, n.plan.as_deref()), (3, Some("short")));
}

#[test]
fn noise_flags_override_the_unit_files_noise_table() {
    let mut unit = UnitFile::paper_unit();
    unit.other.insert(
        "noise".into(),
        toml::Value::Table(toml::from_str("accel_white_mg = 2.0\ntable_tilt_deg = 0.01").unwrap()),
    );
    let Command::Simulate(a) = parse(&["simulate", "--out", "d", "--noise-mg", "0.5"]).command
    else {
        panic!()
    };
    let n = noise_from_args(&a, &unit).unwrap();
    assert_eq!((n.accel_white_mg, n.table_tilt_deg), (0.5, 0.01));
    let Command::Simulate(a) = parse(&["simulate", "--out", "d", "--no-noise"]).command else {
        panic!()
    };
    assert_eq!(noise_from_args(&a, &unit).unwrap(), NoiseModel::none());
}

/// simulate (short oblique plan, the paper's unit, 1 mg) → calibrate → every parameter within
/// 5 reported σ of the truth, the σ of the right size, and the files readable.
#[test]
fn simulate_then_calibrate_recovers_the_unit() {
    let dir = tempfile::tempdir().unwrap();
    let session = dir.path().join("session");
    let Command::Simulate(s) = parse(&[
        "simulate",
        "--out",
        session.to_str().unwrap(),
        "--plan",
        "short-oblique",
        "--seed",
        "21",
    ])
    .command
    else {
        panic!()
    };
    simulate::run(&s, true).unwrap();
    let out = dir.path().join("out");
    let Command::Calibrate(c) = parse(&[
        "calibrate",
        "--input",
        session.to_str().unwrap(),
        "--out-dir",
        out.to_str().unwrap(),
    ])
    .command
    else {
        panic!()
    };
    let o = calibrate(&c, true).unwrap();
    let truth = UnitFile::load(&session.join("truth.toml"))
        .unwrap()
        .to_calibration()
        .unwrap();
    let (est, u) = (&o.calibration, &o.uncertainty);
    for i in 0..3 {
        let db = est.statics.zero_bias_out[i] - truth.statics.zero_bias_out[i];
        assert!(db.abs() < 5.0 * u.zero_bias_1sigma[i], "bias {i}: {db}");
        let dk = est.statics.scale_out_per_g[i] - truth.statics.scale_out_per_g[i];
        assert!(dk.abs() < 5.0 * u.scale_per_g_1sigma[i], "scale {i}: {dk}");
        for j in 0..3 {
            let da = est.statics.installation_angles_deg[i][j]
                - truth.statics.installation_angles_deg[i][j];
            assert!(
                da.abs() < 5.0 * u.installation_angles_deg_1sigma[i][j],
                "θ{i}{j}: {da}"
            );
            let dr = est.lever_arms.r_m[i][j] - truth.lever_arms.r_m[i][j];
            let sr = u.lever_arms_m_1sigma[i][j];
            assert!(u.lever_arms_observable[i][j], "r{i}{j} observable");
            assert!(dr.abs() < 5.0 * sr && sr < 60e-6, "r{i}{j}: {dr} ± {sr}");
        }
    }
    // The files: calibration.toml reads back as a unit file (so `simulate --unit` round-trips),
    // calibration.bin decodes for the (all-zero) unit id of a plan without one.
    let back = UnitFile::load(&out.join("calibration.toml")).unwrap();
    assert!(back.uncertainty.is_some());
    let bin = std::fs::read(out.join("calibration.bin")).unwrap();
    let blob = shared::blob::decode_for_unit(&bin, UnitId::default()).unwrap();
    assert_eq!(blob.calibration, o.calibration);
}

#[test]
fn plan_check_predicts_what_the_oblique_plan_adds() {
    let check = |plan: &str| {
        let Command::Plan(a) = parse(&["plan", "--check", plan]).command else {
            panic!()
        };
        plan::run(&a, true).unwrap()
    };
    let paper = check("paper");
    let oblique = check("oblique");
    // r1y (across axis x): ~0.3 mm with the paper's plan, ~15 µm or better with the oblique mounts.
    let k = paper.labels.iter().position(|l| l == "r1y").unwrap();
    assert!(paper.sigma[k] > 1e-4 && !paper.lever_arms_observable[0][1]);
    assert!(oblique.sigma[k] < 2e-5 && oblique.lever_arms_observable[0][1]);
    let Command::Plan(a) = parse(&["plan", "--check", "nope.toml"]).command else {
        panic!()
    };
    assert!(shared::chain::Chain(&plan::run(&a, true).unwrap_err())
        .to_string()
        .contains("built-in"));
}

#[test]
fn calibrate_without_input_says_what_to_give() {
    let Command::Calibrate(c) = parse(&["calibrate"]).command else {
        panic!()
    };
    let e = calibrate(&c, true).unwrap_err().to_string();
    assert!(e.contains("--input DIR"), "{e}");
}

fn sim() -> PortArgs {
    PortArgs {
        port: SIM_PORT.into(),
        baud: None,
        timeout_s: None,
        sim_unit: None,
    }
}

fn blob_file(dir: &Path, unit: UnitId) -> PathBuf {
    let cal = shared::params::PAPER_UNIT;
    let (bytes, n) = ParameterBlob {
        unit_id: unit,
        calibration: cal,
        created_unix_s: 5,
    }
    .to_bytes()
    .unwrap();
    let p = dir.join("calibration.bin");
    std::fs::write(&p, &bytes[..n]).unwrap();
    p
}

#[test]
fn flash_writes_resets_and_reads_back_and_refuses_another_units_blob() {
    let dir = tempfile::tempdir().unwrap();
    flash::run(&sim(), &blob_file(dir.path(), SIM_UNIT_ID), false).unwrap();
    let e = flash::run(
        &sim(),
        &blob_file(dir.path(), UnitId(*b"ANOTHER-UNIT")),
        false,
    )
    .unwrap_err();
    assert!(
        matches!(
            e,
            CliError::Guard(outputs::calibration_guard::GuardError::UnitId { .. })
        ),
        "{e}"
    );
    let m = e.to_string();
    assert!(
        m.contains(&UnitId(*b"ANOTHER-UNIT").to_string()) && m.contains(&SIM_UNIT_ID.to_string()),
        "{m}"
    );
    // A corrupt file is refused before anything reaches the device.
    std::fs::write(dir.path().join("bad.bin"), b"ACAL garbage").unwrap();
    let e = flash::run(&sim(), &dir.path().join("bad.bin"), false).unwrap_err();
    assert!(matches!(e, CliError::Blob(..)), "{e}");
}

/// `host read --out` onto an existing calibration: refused before the device is asked unless
/// `--force`; and when the read then fails, the file is as it was and no partial file is left.
#[test]
fn read_never_replaces_a_file_without_force_nor_leaves_half_a_file() {
    let dir = tempfile::tempdir().unwrap();
    let p = dir.path().join("calibration.toml");
    std::fs::write(&p, "mine").unwrap();
    let args = |force| read::ReadArgs {
        port: sim(),
        out: Some(p.clone()),
        force,
    };
    let e = read::run(&args(false)).unwrap_err();
    assert!(matches!(e, CliError::Written(_)), "{e}");
    assert!(e.to_string().contains("--force"), "{e}");
    // With --force the (uncalibrated) device is asked, and its refusal leaves the file alone.
    let e = read::run(&args(true)).unwrap_err();
    assert!(matches!(e, CliError::Link(_)), "{e}");
    assert_eq!(std::fs::read_to_string(&p).unwrap(), "mine");
    let names: Vec<_> = std::fs::read_dir(dir.path()).unwrap().collect();
    assert_eq!(names.len(), 1, "{names:?}");
}

#[test]
fn read_of_an_uncalibrated_device_is_a_typed_error_and_monitor_streams() {
    let e = read::run(&read::ReadArgs {
        port: sim(),
        out: None,
        force: false,
    })
    .unwrap_err();
    assert!(
        matches!(
            e,
            CliError::Link(LinkError::Device(DeviceError::NoCalibration))
        ),
        "{e}"
    );
    let args = monitor::MonitorArgs {
        port: sim(),
        window: 100,
        count: Some(3),
        fast: true,
    };
    monitor::run(&args, false).unwrap();
    // Unbounded as-fast-as-possible output is refused before anything is opened.
    let e = monitor::run(
        &monitor::MonitorArgs {
            count: None,
            ..args
        },
        false,
    )
    .unwrap_err();
    assert!(e.to_string().contains("--count"), "{e}");
}

#[test]
fn a_missing_serial_port_names_the_port_and_the_fix() {
    let args = PortArgs {
        port: "/dev/does-not-exist".into(),
        ..sim()
    };
    let e = connect(&args).err().unwrap().to_string();
    assert!(
        e.contains("/dev/does-not-exist") && e.contains("plugged in"),
        "{e}"
    );
}

/// Drift-aware by default: without a walk flag `calibrate` estimates both walks from the session;
/// `--bias-walk 0` and `--gyro-bias-walk 0` keep constant biases on request, a given strength takes
/// the estimate's place, and the paper's method (no walk weights) keeps constant biases.
#[test]
fn the_walks_are_estimated_unless_a_flag_says_otherwise() {
    use estimator::estimate::BiasWalk;
    let options = |extra: &[&str]| {
        let mut args = vec!["calibrate", "--input", "x"];
        args.extend_from_slice(extra);
        let Command::Calibrate(c) = parse(&args).command else {
            panic!("not calibrate")
        };
        calibrate_options(&c).unwrap().estimate
    };
    let by_default = options(&[]);
    assert_eq!(by_default.bias_walk, BiasWalk::Estimate);
    assert!(by_default.gyro_bias_walk_estimate);
    let off = options(&["--bias-walk", "0", "--gyro-bias-walk", "0"]);
    assert_eq!(off.bias_walk, BiasWalk::Off);
    assert!(!off.gyro_bias_walk_estimate);
    assert_eq!(off.gyro_bias_walk_deg_s_sqrt_s, 0.0);
    let given = options(&["--bias-walk", "0.002", "--gyro-bias-walk", "0.0005"]);
    assert_eq!(given.bias_walk, BiasWalk::Given(0.002));
    assert!(!given.gyro_bias_walk_estimate);
    assert_eq!(given.gyro_bias_walk_deg_s_sqrt_s, 0.0005);
    let paper = options(&["--method", "paper"]);
    assert_eq!(paper.bias_walk, BiasWalk::Off);
    assert!(!paper.gyro_bias_walk_estimate);
}

/// `plan --check` predicts with the walks the unit's class is expected to have: the
/// single-package plan (a digital MEMS unit) by default under 0.002 mg/√s and 0.0005 °/s/√s,
/// exactly as with those walks given, and its bias 1σ above the prediction without walks; the
/// paper's analog unit without any.
#[test]
fn plan_check_predicts_with_the_walks_of_the_units_class() {
    let check = |args: &[&str]| {
        let mut v = vec!["plan", "--check"];
        v.extend_from_slice(args);
        let Command::Plan(a) = parse(&v).command else {
            panic!()
        };
        plan::run(&a, true).unwrap()
    };
    let by_default = check(&["single-package"]);
    let given = check(&[
        "single-package",
        "--bias-walk",
        "0.002",
        "--gyro-bias-walk",
        "0.0005",
    ]);
    let none = check(&[
        "single-package",
        "--bias-walk",
        "0",
        "--gyro-bias-walk",
        "0",
    ]);
    assert_eq!(by_default.sigma, given.sigma);
    // The paper's order: the bias of x first.
    let k = 0;
    assert!(
        by_default.sigma[k] > none.sigma[k],
        "{} against {}",
        by_default.sigma[k],
        none.sigma[k]
    );
    let paper = check(&["paper"]);
    let paper_none = check(&["paper", "--bias-walk", "0"]);
    assert_eq!(paper.sigma, paper_none.sigma);
}
