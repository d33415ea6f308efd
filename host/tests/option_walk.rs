//! Every option applies or is refused. This walks clap's command tree: every option of every
//! subcommand must be classified below, either as acting wherever the subcommand accepts it (with
//! the reason) or with the contexts where it has no effect: a session directory instead of a log,
//! a binary log instead of a text file, a calibration without the section it acts on, a format
//! that has no such field, the simulated device instead of a serial port. Each such context is run
//! and must end in a usage error (exit 2) that names the option. A new option that is not in the
//! table fails the walk, so none can be added that is silently ignored somewhere.

use clap::CommandFactory;
use host::cli::Cli;
use std::path::{Path, PathBuf};
use std::process::Command;

mod common;

/// Where an option acts.
enum Verdict {
    /// Wherever the subcommand accepts it; why.
    Everywhere(&'static str),
    /// Not in these contexts (command lines after the subcommand, with the fixtures' placeholders
    /// `{session}`, `{cal}`, `{thermal}`, `{thermal_cal}`, `{ulog}`, `{csv}`, `{tmp}`).
    NotIn(&'static [&'static [&'static str]]),
    /// Without effect in some context that is not refused yet: a known gap, printed and counted
    /// (none at present).
    #[allow(dead_code)]
    Gap(&'static str),
}
use Verdict::{Everywhere, Gap, NotIn};

const ALWAYS_OUTPUT: &str = "names or replaces what the command writes";
const ALWAYS_QUIET: &str = "silences the human-readable output of every run";
const ALWAYS_JSON: &str = "every run ends in a document";
const ALWAYS_SIM: &str = "a simulation's parameter: every simulated run has it";
const ALWAYS_FIT: &str = "a fit's option or limit: every run fits";
const ALWAYS_DEVICE: &str = "every run of this command talks to the device";

/// The log-reading options of `apply` and `noise` (the same set): text-file options refused on a
/// session directory and on a binary log (but `--rate-hz`, which re-times a binary log's samples:
/// `recording::session::logs`' tests); `--instance` and `--topic` on a text file.
fn log_options(sub: &'static str, head: &'static [&'static str]) -> Vec<Case> {
    let mut v = Vec::new();
    let text: [(&str, &[&str]); 11] = [
        ("columns", &["--columns", "a,b,c,d,e,f"]),
        ("time-column", &["--time-column", "t"]),
        ("time-unit", &["--time-unit", "ms"]),
        ("rate-hz", &["--rate-hz", "200"]),
        ("acc-unit", &["--acc-unit", "g"]),
        ("acc-offset", &["--acc-offset", "1"]),
        ("gyro-unit", &["--gyro-unit", "deg/s"]),
        ("gyro-lsb-per-dps", &["--gyro-lsb-per-dps", "65.5"]),
        ("temp-column", &["--temp-column", "temp"]),
        ("gyro-offset", &["--gyro-offset", "32768"]),
        ("skip-lines", &["--skip-lines", "3"]),
    ];
    // `segment` reads logs only: a session directory is no input of it at all.
    let session = sub != "segment";
    for (name, args) in text {
        if session {
            v.push(Case::new(sub, name, head, &["--input", "{session}"], args));
        }
        if name != "rate-hz" {
            v.push(Case::new(sub, name, head, &["--input", "{ulog}"], args));
        }
    }
    // A calibration without a temperature model uses no temperature.
    if sub == "apply" {
        v.push(Case::new(
            sub,
            "temp-column",
            head,
            &[&["--input", "{csv}"][..], &common::HAND_CSV_READING[..]].concat(),
            &["--temp-column", "temp"],
        ));
    }
    // The noise analysis does not use the temperature, whatever the input.
    if sub == "noise" {
        v.push(Case::new(
            sub,
            "temp-column",
            head,
            &[&["--input", "{csv}"][..], &common::HAND_CSV_READING[..]].concat(),
            &["--temp-column", "temp"],
        ));
    }
    for (name, args) in [
        ("instance", &["--instance", "1"][..]),
        ("topic", &["--topic", "/imu"][..]),
    ] {
        if session {
            v.push(Case::new(sub, name, head, &["--input", "{session}"], args));
        }
        v.push(Case::new(
            sub,
            name,
            head,
            &[&["--input", "{csv}"][..], &common::HAND_CSV_READING[..]].concat(),
            args,
        ));
    }
    v
}

/// One refused context: `sub`, then `head`, `input` and `args`.
struct Case {
    sub: &'static str,
    option: &'static str,
    line: Vec<&'static str>,
}

impl Case {
    fn new(
        sub: &'static str,
        option: &'static str,
        head: &[&'static str],
        input: &[&'static str],
        args: &[&'static str],
    ) -> Case {
        let mut line = head.to_vec();
        line.extend_from_slice(input);
        line.extend_from_slice(args);
        Case { sub, option, line }
    }
}

fn table() -> Vec<(&'static str, &'static str, Verdict)> {
    let mut t: Vec<(&str, &str, Verdict)> = Vec::new();
    for sub in [
        "simulate",
        "calibrate",
        "segment",
        "simulate-hand",
        "plan",
        "report",
        "noise",
        "navigation-check",
        "compare",
        "export",
        "apply",
        "batch",
        "flash",
        "read",
        "monitor",
        "bringup",
    ] {
        t.push((sub, "quiet", Everywhere(ALWAYS_QUIET)));
        for o in ["out", "out-dir", "force"] {
            t.push((sub, o, Everywhere(ALWAYS_OUTPUT)));
        }
        t.push((sub, "json", Everywhere(ALWAYS_JSON)));
    }
    for o in [
        "unit",
        "plan",
        "seed",
        "no-noise",
        "noise-mg",
        "lsb",
        "drift-mg-sqrt-s",
        "tilt-deg",
        "rate-scale",
        "rate-offset-deg-s",
        "gyro-noise-deg-s",
        "gyro-bias-deg-s",
        "gyro-scale-ppm",
        "gyro-misalignment-deg",
        "flicker-mg",
        "gyro-drift-deg-s-sqrt-s",
        "gyro-flicker-deg-s",
    ] {
        t.push(("simulate", o, Everywhere(ALWAYS_SIM)));
    }
    for o in [
        "seed",
        "rate-hz",
        "acc-unit",
        "gyro-unit",
        "six-faces",
        "table-turns",
    ] {
        t.push(("simulate-hand", o, Everywhere(ALWAYS_SIM)));
    }
    t.push((
        "segment",
        "rate-hz",
        Everywhere("a text file's rate, or a binary log's samples re-timed: every input is a log"),
    ));
    t.push((
        "simulate-hand",
        "rounds",
        NotIn(&[&["--out", "{tmp}/h.csv", "--rounds", "2"]]),
    ));
    t.push((
        "simulate-hand",
        "acc-offset",
        NotIn(&[&["--out", "{tmp}/h.csv", "--acc-offset", "100"]]),
    ));
    t.push((
        "simulate-hand",
        "gyro-lsb-per-dps",
        NotIn(&[&["--out", "{tmp}/h.csv", "--gyro-lsb-per-dps", "65.5"]]),
    ));
    // calibrate: the device's options on a recorded session.
    for (o, args) in [
        ("sim-unit", &["--sim-unit", "{cal}"][..]),
        ("plan", &["--plan", "short"][..]),
        ("window", &["--window", "4"][..]),
        ("verify-tolerance-mg", &["--verify-tolerance-mg", "2"][..]),
        ("verify-temp-c", &["--verify-temp-c", "45"][..]),
    ] {
        let line: &'static [&'static str] = Box::leak(
            [&["--input", "{session}", "--out-dir", "{tmp}/c"][..], args]
                .concat()
                .into_boxed_slice(),
        );
        t.push(("calibrate", o, NotIn(Box::leak(Box::new([line])))));
    }
    for o in ["input", "port"] {
        t.push(("calibrate", o, Everywhere("the source of the run")));
    }
    t.push((
        "calibrate",
        "verbose",
        NotIn(&[&[
            "--input",
            "{session}",
            "--out",
            "{tmp}/v",
            "-q",
            "--verbose",
        ]]),
    ));
    for o in [
        "method",
        "reference",
        "single-package",
        "max-chi2-per-dof",
        "max-bias-mg",
        "max-misalignment-deg",
        "max-bias-sigma-mg",
    ] {
        t.push(("calibrate", o, Everywhere(ALWAYS_FIT)));
        t.push(("batch", o, Everywhere(ALWAYS_FIT)));
    }
    // The bias walks weight the joint fit; the paper's method has no such weighting (and no gyro
    // model for the gyro's walk to weigh).
    for (o, args) in [
        ("bias-walk", &["--bias-walk", "0.002"][..]),
        ("bias-walk-estimate", &["--bias-walk-estimate"][..]),
        ("bias-walk-from", &["--bias-walk-from", "{cal}"][..]),
        ("gyro-bias-walk", &["--gyro-bias-walk", "0.001"][..]),
    ] {
        for (sub, head) in [
            (
                "calibrate",
                &["--input", "{session}", "--out", "{tmp}/c"][..],
            ),
            ("batch", &["--input", "{tmp}", "--out", "{tmp}/lot"][..]),
        ] {
            let line: &'static [&'static str] = Box::leak(
                [head, &["--method", "paper"][..], args]
                    .concat()
                    .into_boxed_slice(),
            );
            // A rests-only session (the thermal soak) has no gyro model for the gyro's walk.
            let no_gyro_model: &'static [&'static str] = Box::leak(
                [head, args]
                    .concat()
                    .into_iter()
                    .map(|a| if a == "{session}" { "{thermal}" } else { a })
                    .collect::<Vec<_>>()
                    .into_boxed_slice(),
            );
            let lines: &'static [&'static [&'static str]] =
                if o == "gyro-bias-walk" && sub == "calibrate" {
                    Box::leak(Box::new([line, no_gyro_model]))
                } else {
                    Box::leak(Box::new([line]))
                };
            t.push((sub, o, NotIn(lines)));
        }
    }
    for o in [
        "bias-walk",
        "bias-walk-estimate",
        "bias-walk-from",
        "gyro-bias-walk",
    ] {
        t.push((
            "report",
            o,
            Everywhere("every report runs the session's own fit, which the walk weighs"),
        ));
    }
    for o in ["bias-walk", "gyro-bias-walk"] {
        t.push((
            "plan",
            o,
            Everywhere("every plan check predicts its 1σ under the walk it is given"),
        ));
    }
    // The live page follows a device session; a recording read from a directory has none.
    t.push((
        "calibrate",
        "view",
        NotIn(&[&["--input", "{session}", "--out-dir", "{tmp}/c", "--view"]]),
    ));
    for o in ["input", "jobs", "outlier-z"] {
        t.push((
            "batch",
            o,
            Everywhere("every lot run has its sessions, threads and screen"),
        ));
    }
    // export: a format-specific option with another format.
    for (o, args) in [
        ("noise", &["--noise", "{tmp}/noise.json"][..]),
        ("rostopic", &["--rostopic", "/imu1"][..]),
        ("driver-scale", &["--driver-scale", "9.8"][..]),
        ("device-id", &["--device-id", "1234"][..]),
        ("gyro-device-id", &["--gyro-device-id", "1234"][..]),
        ("sysid", &["--sysid", "2"][..]),
        ("compid", &["--compid", "2"][..]),
        ("allow-out-of-range", &["--allow-out-of-range"][..]),
        ("allow-undetermined", &["--allow-undetermined"][..]),
        ("log", &["--log", "{ulog}"][..]),
        ("slot", &["--slot", "1"][..]),
    ] {
        let line: &'static [&'static str] = Box::leak(
            [&["--calibration", "{cal}", "--format", "json"][..], args]
                .concat()
                .into_boxed_slice(),
        );
        t.push(("export", o, NotIn(Box::leak(Box::new([line])))));
    }
    for o in ["calibration", "format"] {
        t.push(("export", o, Everywhere("what is exported, and how")));
    }
    // export: an IMU of a log with another format, or with no log to choose it from.
    t.push((
        "export",
        "instance",
        NotIn(&[
            &[
                "--calibration",
                "{cal}",
                "--format",
                "json",
                "--instance",
                "1",
            ],
            &[
                "--calibration",
                "{cal}",
                "--format",
                "px4",
                "--instance",
                "1",
            ],
        ]),
    ));
    // apply: the temperature to assume, where nothing would use it.
    t.push((
        "apply",
        "temperature-c",
        NotIn(&[
            &[
                "--calibration",
                "{cal}",
                "--input",
                "{session}",
                "--out",
                "{tmp}/a.csv",
                "--temperature-c",
                "30",
            ],
            &[
                "--calibration",
                "{thermal_cal}",
                "--input",
                "{thermal}",
                "--out",
                "{tmp}/a.csv",
                "--temperature-c",
                "30",
            ],
        ]),
    ));
    for o in ["calibration", "input"] {
        t.push(("apply", o, Everywhere("every row is compensated with it")));
    }
    // A choice the data already satisfy is honoured (a note says so): a calibration without lever
    // arms gives the static compensation in every lever mode; no ids to differ is what
    // --ignore-unit-id asks for.
    t.push((
        "apply",
        "lever",
        Everywhere("every mode is applied; without lever arms each is the static compensation"),
    ));
    t.push((
        "apply",
        "ignore-unit-id",
        Everywhere("no id is refused; where none differ, a note says so"),
    ));
    for o in ["input", "calibration"] {
        t.push((
            "noise",
            o,
            Everywhere("the data analysed, and its conversion to g"),
        ));
    }
    // segment reads logs like apply and noise.
    // The hand-held CSV's still positions are spread, not a cube's six faces.
    t.push((
        "segment",
        "face-sigma-deg",
        NotIn(&[&[
            "--out",
            "{tmp}/seg",
            "--input",
            "{csv}",
            "--time-column",
            "t",
            "--acc-unit",
            "m/s2",
            "--gyro-unit",
            "deg/s",
            "--face-sigma-deg",
            "5",
        ]]),
    ));
    for o in [
        "input",
        "max-samples",
        "min-still-s",
        "still-threshold",
        "no-gyro",
        "unit-id",
        "gravity",
        "latitude",
        "height-m",
    ] {
        t.push((
            "segment",
            o,
            Everywhere("every segmented log is cut and bound with it"),
        ));
    }
    t.push((
        "segment",
        "faces",
        Everywhere(
            "labels make the still positions a six-face session, or are refused by the data",
        ),
    ));
    for o in ["check", "noise-mg", "gyro-noise-deg-s", "unit"] {
        t.push(("plan", o, Everywhere("the plan check's inputs")));
    }
    for o in ["input", "calibration", "duration-s", "no-png"] {
        t.push(("report", o, Everywhere("every report has them")));
    }
    t.push((
        "report",
        "rate-run",
        NotIn(&[&[
            "--input",
            "{session}",
            "--out-dir",
            "{tmp}/r",
            "--rate-run",
            "x+",
        ]]),
    ));
    t.push((
        "report",
        "static-run",
        NotIn(&[&[
            "--input",
            "{session}",
            "--out-dir",
            "{tmp}/r",
            "--static-run",
            "x+ 200",
        ]]),
    ));
    for o in ["seed", "duration-s", "unit", "plan"] {
        t.push((
            "navigation-check",
            o,
            Everywhere("the simulated check's inputs"),
        ));
    }
    t.push((
        "compare",
        "max-sigma",
        Everywhere("every comparison is judged by it"),
    ));
    t.push(("flash", "calibration", Everywhere("what is flashed")));
    for o in ["window", "count", "fast"] {
        t.push(("monitor", o, Everywhere("how the stream is shown")));
    }
    t.push(("bringup", "seconds", Everywhere("how long it samples")));
    // The serial line's options on the simulated device; the simulated unit on a serial port.
    for sub in ["calibrate", "flash", "read", "monitor", "bringup"] {
        t.push((
            sub,
            "baud",
            NotIn(leak_line(sub, &["--port", "sim", "--baud", "9600"])),
        ));
        t.push((
            sub,
            "timeout-s",
            NotIn(leak_line(sub, &["--port", "sim", "--timeout-s", "2"])),
        ));
        if sub != "calibrate" {
            t.push((sub, "port", Everywhere(ALWAYS_DEVICE)));
            let real = ["--port", "{tmp}/no-such-tty", "--sim-unit", "{cal}"];
            t.push((sub, "sim-unit", NotIn(leak_line(sub, &real))));
        }
    }
    t
}

/// The command line of a device subcommand with its other required options.
fn leak_line(sub: &str, args: &[&'static str]) -> &'static [&'static [&'static str]] {
    let mut line = args.to_vec();
    if sub == "flash" {
        line.extend(["--calibration", "{bin}"]);
    }
    if sub == "bringup" {
        line.extend(["--seconds", "1"]);
    }
    if sub == "monitor" {
        line.extend(["--count", "1"]);
    }
    let line: &'static [&'static str] = Box::leak(line.into_boxed_slice());
    Box::leak(Box::new([line]))
}

struct Fixtures {
    dir: tempfile::TempDir,
    session: PathBuf,
    thermal: PathBuf,
    csv: PathBuf,
}

fn s(p: &Path) -> String {
    p.to_str().unwrap().to_string()
}

fn run(args: &[String]) -> (Option<i32>, String) {
    let out = Command::new(env!("CARGO_BIN_EXE_host"))
        .args(args)
        .output()
        .unwrap();
    (
        out.status.code(),
        String::from_utf8_lossy(&out.stderr).into_owned(),
    )
}

fn fixtures() -> Fixtures {
    let dir = tempfile::tempdir().unwrap();
    let session = dir.path().join("session");
    let thermal = dir.path().join("thermal");
    let csv = dir.path().join("hand.csv");
    for line in [
        vec!["-q", "simulate", "--plan", "short", "--out", &s(&session)],
        vec!["-q", "calibrate", "--input", &s(&session)],
        vec![
            "-q",
            "simulate",
            "--plan",
            "thermal-soak",
            "--out",
            &s(&thermal),
        ],
        vec!["-q", "calibrate", "--input", &s(&thermal)],
        vec!["-q", "simulate-hand", "--out", &s(&csv)],
    ] {
        let line: Vec<String> = line.into_iter().map(String::from).collect();
        let (code, e) = run(&line);
        assert_eq!(code, Some(0), "{line:?}: {e}");
    }
    Fixtures {
        dir,
        session,
        thermal,
        csv,
    }
}

fn expand(f: &Fixtures, arg: &str) -> String {
    let ulog = recording::testkit::log_fixture("hand.ulg");
    arg.replace("{session}", &s(&f.session))
        .replace("{cal}", &s(&f.session.join("calibration.toml")))
        .replace("{bin}", &s(&f.session.join("calibration.bin")))
        .replace("{thermal_cal}", &s(&f.thermal.join("calibration.toml")))
        .replace("{thermal}", &s(&f.thermal))
        .replace("{ulog}", &s(&ulog))
        .replace("{csv}", &s(&f.csv))
        .replace("{tmp}", &s(f.dir.path()))
}

#[test]
fn every_option_applies_or_is_refused() {
    let table = table();
    let mut cases: Vec<Case> = Vec::new();
    for sub in ["apply", "noise"] {
        cases.extend(log_options(sub, &[]).into_iter().map(|mut c| {
            if sub == "apply" {
                c.line
                    .splice(0..0, ["--calibration", "{cal}", "--out", "{tmp}/a.csv"]);
            }
            c
        }));
    }
    let segment_head: &'static [&'static str] = &["--out", "{tmp}/seg"];
    cases.extend(log_options("segment", segment_head));
    let mut missing = Vec::new();
    let mut everywhere = 0usize;
    let mut gaps = Vec::new();
    for sub in Cli::command().get_subcommands() {
        let name = sub.get_name();
        for arg in sub.get_arguments() {
            let Some(long) = arg.get_long() else { continue };
            if long == "help" {
                continue;
            }
            let logs = ["apply", "noise", "segment"].contains(&name)
                && cases.iter().any(|c| c.sub == name && c.option == long);
            match table.iter().find(|(s, o, _)| *s == name && *o == long) {
                Some((_, _, Everywhere(why))) => {
                    assert!(
                        !why.is_empty(),
                        "{name} --{long}: say why it acts everywhere"
                    );
                    everywhere += 1;
                }
                Some((_, _, Gap(why))) => gaps.push(format!("{name} --{long}: {why}")),
                Some((_, _, NotIn(lines))) => {
                    for line in lines.iter() {
                        cases.push(Case {
                            sub: name_static(name),
                            option: name_static(long),
                            line: line.to_vec(),
                        });
                    }
                }
                None if logs => {}
                None => missing.push(format!("{name} --{long}")),
            }
        }
    }
    assert!(
        missing.is_empty(),
        "options with no verdict (say where each acts, or where it is refused): {missing:?}"
    );
    let f = fixtures();
    let mut failures = Vec::new();
    for c in &cases {
        let mut line = vec![c.sub.to_string()];
        line.extend(c.line.iter().map(|a| expand(&f, a)));
        let (code, stderr) = run(&line);
        let flag = format!("--{}", c.option);
        if code != Some(2) || !stderr.contains(&flag) {
            failures.push(format!(
                "host {}: exit {code:?}: {}",
                line.join(" "),
                stderr.trim()
            ));
        }
    }
    println!(
        "option walk: {} (subcommand, option, context) triples refused as usage errors, {} options \
         acting wherever they are accepted, {} known gaps:",
        cases.len(),
        everywhere,
        gaps.len()
    );
    for g in &gaps {
        println!("  gap: {g}");
    }
    assert!(failures.is_empty(), "not refused:\n{}", failures.join("\n"));
}

fn name_static(s: &str) -> &'static str {
    Box::leak(s.to_string().into_boxed_str())
}
