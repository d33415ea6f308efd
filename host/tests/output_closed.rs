//! Every subcommand with its standard output on a full disk (`> /dev/full`) and into a pipe whose
//! reader is gone (`| head` that has exited): a command that prints fails with exit 1 and `cannot
//! write to standard output`, never a panic (exit 101); its files are written before that. Every
//! subcommand prints something on stdout, so none may exit 0 here; `read --port sim` is the one
//! exception (a fresh simulated device holds no calibration to print).

use std::path::{Path, PathBuf};
use std::process::{Command, Output, Stdio};

mod common;
use common::host;

/// The simulated device's unit id (`--port sim`), so that a calibration binds to it.
const SIM_UNIT_ID: &str = "53494d2d50415045522d3031";

fn s(p: &Path) -> String {
    p.to_str().unwrap().to_string()
}

fn ok(args: &[&str]) {
    let (ok, _, stderr) = host(args);
    assert!(ok, "{args:?}: {stderr}");
}

/// The inputs the commands need: two calibrated sessions of the simulated device's unit, a lot of
/// one unit, and a hand-held logger CSV.
struct Fixture {
    dir: tempfile::TempDir,
    session: PathBuf,
    other: PathBuf,
    lot: PathBuf,
    raw: PathBuf,
}

impl Fixture {
    fn new() -> Fixture {
        let dir = tempfile::tempdir().unwrap();
        let calibrated = |name: &str, seed: &str| {
            let p = dir.path().join(name);
            ok(&[
                "-q",
                "simulate",
                "--out",
                &s(&p),
                "--plan",
                "short",
                "--seed",
                seed,
            ]);
            let plan = std::fs::read_to_string(p.join("plan.toml")).unwrap();
            std::fs::write(
                p.join("plan.toml"),
                format!("unit_id = \"{SIM_UNIT_ID}\"\n{plan}"),
            )
            .unwrap();
            ok(&["-q", "calibrate", "--input", &s(&p)]);
            p
        };
        let session = calibrated("s1", "1");
        let other = calibrated("s2", "2");
        let lot = dir.path().join("lot");
        std::fs::create_dir_all(lot.join("u1")).unwrap();
        for f in ["plan.toml", "samples.csv"] {
            std::fs::copy(session.join(f), lot.join("u1").join(f)).unwrap();
        }
        let raw = dir.path().join("raw.csv");
        ok(&["-q", "simulate-hand", "--out", &s(&raw), "--rate-hz", "50"]);
        Fixture {
            dir,
            session,
            other,
            lot,
            raw,
        }
    }

    /// A fresh path for one run's output.
    fn fresh(&self, name: &str, run: usize) -> String {
        s(&self.dir.path().join(format!("out-{name}-{run}")))
    }

    /// A cheap valid invocation of every subcommand, by its name.
    fn cases(&self, run: usize) -> Vec<(&'static str, Vec<String>)> {
        let cal = s(&self.session.join("calibration.toml"));
        let bin = s(&self.session.join("calibration.bin"));
        let v = |args: &[&str]| args.iter().map(|a| a.to_string()).collect::<Vec<_>>();
        vec![
            (
                "simulate",
                v(&[
                    "simulate",
                    "--out",
                    &self.fresh("sim", run),
                    "--plan",
                    "short",
                ]),
            ),
            (
                "calibrate",
                v(&[
                    "calibrate",
                    "--input",
                    &s(&self.session),
                    "--out-dir",
                    &self.fresh("cal", run),
                ]),
            ),
            (
                "calibrate",
                v(&[
                    "calibrate",
                    "--port",
                    "sim",
                    "--plan",
                    "quick-oblique",
                    "--out-dir",
                    &self.fresh("live", run),
                ]),
            ),
            (
                "segment",
                v(&[
                    "segment",
                    "--input",
                    &s(&self.raw),
                    "--out",
                    &self.fresh("seg", run),
                    "--time-column",
                    "t",
                    "--acc-unit",
                    "m/s2",
                    "--gyro-unit",
                    "deg/s",
                ]),
            ),
            (
                "simulate-hand",
                v(&[
                    "simulate-hand",
                    "--out",
                    &format!("{}.csv", self.fresh("hand", run)),
                    "--rate-hz",
                    "20",
                ]),
            ),
            ("plan", v(&["plan", "--check", "short"])),
            (
                "report",
                v(&[
                    "report",
                    "--input",
                    &s(&self.session),
                    "--out-dir",
                    &self.fresh("report", run),
                    "--no-png",
                ]),
            ),
            (
                "navigation-check",
                v(&["navigation-check", "--duration-s", "1"]),
            ),
            (
                "compare",
                v(&["compare", &cal, &s(&self.other.join("calibration.toml"))]),
            ),
            (
                "export",
                v(&["export", "--calibration", &cal, "--format", "json"]),
            ),
            (
                "apply",
                v(&["apply", "--calibration", &cal, "--input", &s(&self.session)]),
            ),
            ("noise", v(&["noise", "--input", &s(&self.session)])),
            (
                "batch",
                v(&[
                    "batch",
                    "--input",
                    &s(&self.lot),
                    "--out",
                    &self.fresh("batch", run),
                ]),
            ),
            (
                "flash",
                v(&["flash", "--port", "sim", "--calibration", &bin]),
            ),
            ("read", v(&["read", "--port", "sim"])),
            ("monitor", v(&["monitor", "--port", "sim", "--count", "3"])),
            (
                "bringup",
                v(&["bringup", "--port", "sim", "--seconds", "0.5"]),
            ),
        ]
    }
}

/// Runs `host ARGS` with stdout on /dev/full (`full`) or on a connection whose reader is gone.
///
/// The reader is closed before the child starts, not after: closing it after the spawn raced the
/// child, and a command whose few lines reached the pipe's buffer first exited 0 (correctly: nothing
/// it wrote was lost yet). A stream socket pair stands for the pipe (std's `io::pipe` is newer than
/// the workspace's `rust-version`): a write whose peer is closed fails with `EPIPE`, as on a pipe.
fn run(args: &[String], full: bool) -> Output {
    let mut cmd = Command::new(env!("CARGO_BIN_EXE_host"));
    cmd.args(args).stderr(Stdio::piped());
    if full {
        cmd.stdout(std::fs::File::create("/dev/full").unwrap());
    } else {
        let (writer, reader) = std::os::unix::net::UnixStream::pair().unwrap();
        drop(reader);
        cmd.stdout(std::os::fd::OwnedFd::from(writer));
    }
    cmd.output().unwrap()
}

/// How many times the cases run (`OUTPUT_CLOSED_ROUNDS`, default 1): the fixture is made once, so a
/// search for a race (hundreds of rounds) costs only the commands.
fn rounds() -> usize {
    std::env::var("OUTPUT_CLOSED_ROUNDS")
        .ok()
        .and_then(|r| r.parse().ok())
        .unwrap_or(1)
}

#[test]
fn every_subcommand_fails_cleanly_on_a_closed_or_full_stdout() {
    let fixture = Fixture::new();
    let names: Vec<String> = {
        use clap::CommandFactory;
        host::cli::Cli::command()
            .get_subcommands()
            .map(|c| c.get_name().to_string())
            .collect()
    };
    let mut problems = Vec::new();
    let mut runs = 0;
    let runs_of_each = (0..rounds()).flat_map(|_| [true, false]);
    for (k, full) in runs_of_each.enumerate() {
        let cases = fixture.cases(k);
        // Every subcommand has a case: a new one must be added here.
        for n in &names {
            if !cases.iter().any(|(c, _)| c == n) {
                problems.push(format!("no case for subcommand {n}"));
            }
        }
        for (name, args) in cases {
            let out = run(&args, full);
            runs += 1;
            let stderr = String::from_utf8_lossy(&out.stderr);
            let how = if full { "/dev/full" } else { "closed pipe" };
            if name == "read" {
                // A fresh simulated device holds no calibration, so `read --port sim` fails before
                // it has anything for stdout; it must still fail cleanly.
                if out.status.code() != Some(1) || !stderr.contains("holds no calibration") {
                    problems.push(format!("read ({how}): {:?} {stderr}", out.status.code()));
                }
                continue;
            }
            if stderr.contains("panicked") || out.status.code() != Some(1) {
                problems.push(format!(
                    "{name} ({how}): exit {:?}, stderr: {stderr}",
                    out.status.code()
                ));
            } else if !stderr.contains("error: cannot write to standard output") {
                problems.push(format!("{name} ({how}): wrong message: {stderr}"));
            }
        }
    }
    println!("{runs} runs with stdout on /dev/full or a closed pipe");
    assert!(problems.is_empty(), "{}", problems.join("\n"));
}
