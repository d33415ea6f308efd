//! Every numeric option of every subcommand, walked from clap's command tree, gets NaN, ±inf, -1, 0
//! and 1e300: each is refused as a usage error naming the option and its range (before any work: the
//! refusal comes from the parser), or accepted only inside the range the option declares. An option
//! whose value parser is a plain number parser instead of one of `host::limits`' range parsers fails
//! the sweep, so a new numeric option cannot be added unchecked.

use clap::builder::ValueParser;
use clap::{CommandFactory, Parser};
use host::cli::Cli;

mod common;
use common::host;

/// The values every numeric option gets.
const HOSTILE: [&str; 6] = ["NaN", "inf", "-inf", "-1", "0", "1e300"];

/// Options bounded elsewhere, not by a range parser: `batch --jobs` is bounded where its thread pool
/// is built. Each entry is (subcommand, long name).
const BOUNDED_ELSEWHERE: [(&str, &str); 1] = [("batch", "jobs")];

/// A command line each subcommand parses (the sweep adds one option to it); the files need not
/// exist, since the sweep only parses.
fn base(sub: &str) -> &'static [&'static str] {
    match sub {
        "simulate" => &["--out", "o"],
        "calibrate" => &["--port", "sim"],
        "segment" => &[
            "--input",
            "i.csv",
            "--out",
            "o",
            "--acc-unit",
            "g",
            "--gyro-unit",
            "deg/s",
        ],
        "simulate-hand" => &["--out", "o.csv"],
        "plan" => &["--check", "paper"],
        "report" | "noise" => &["--input", "i"],
        "navigation-check" => &[],
        "compare" => &["a.toml", "b.toml"],
        "export" => &["--calibration", "c.toml"],
        "apply" => &["--calibration", "c.toml", "--input", "i"],
        "batch" => &["--input", "i", "--out", "o"],
        "flash" => &["--port", "sim", "--calibration", "c.bin"],
        "read" | "monitor" | "bringup" => &["--port", "sim"],
        other => panic!("the sweep has no base command line for `{other}`: add one to base()"),
    }
}

/// The value parsers of numbers: an argument whose parser yields one of these types is numeric.
fn numeric_types() -> Vec<ValueParser> {
    vec![
        clap::value_parser!(f64).into(),
        clap::value_parser!(f32).into(),
        clap::value_parser!(u8).into(),
        clap::value_parser!(u16).into(),
        clap::value_parser!(u32).into(),
        clap::value_parser!(u64).into(),
        clap::value_parser!(usize).into(),
        clap::value_parser!(i8).into(),
        clap::value_parser!(i16).into(),
        clap::value_parser!(i32).into(),
        clap::value_parser!(i64).into(),
        clap::value_parser!(isize).into(),
    ]
}

/// A declared range, read from the parser's refusal of NaN (which every range parser refuses).
#[derive(Debug)]
enum Declared {
    /// `(min, max]` or `[min, max]`.
    Real { min: f64, open: bool, max: f64 },
    /// `min..=max`.
    Whole { min: f64, max: f64 },
}

impl Declared {
    fn parse(message: &str) -> Option<Declared> {
        let text = message
            .split("give a number in ")
            .nth(1)?
            .lines()
            .next()?
            .trim();
        if let Some((lo, hi)) = text.split_once("..=") {
            return Some(Declared::Whole {
                min: lo.parse().ok()?,
                max: hi.parse().ok()?,
            });
        }
        let open = text.starts_with('(');
        let inner = text.strip_prefix(['(', '['])?.strip_suffix(']')?;
        let (lo, hi) = inner.split_once(", ")?;
        Some(Declared::Real {
            min: lo.parse().ok()?,
            open,
            max: hi.parse().ok()?,
        })
    }

    fn contains(&self, v: f64) -> bool {
        match *self {
            Declared::Real { min, open, max } => {
                v.is_finite() && v <= max && (v > min || (!open && v == min))
            }
            Declared::Whole { min, max } => v.fract() == 0.0 && v >= min && v <= max,
        }
    }
}

/// A message fit for a person: no run of more than 20 digits (a float printed in full).
fn longest_digit_run(text: &str) -> usize {
    text.split(|c: char| !c.is_ascii_digit())
        .map(str::len)
        .max()
        .unwrap_or(0)
}

/// One numeric option of one subcommand.
struct NumericOption {
    sub: String,
    long: String,
}

fn numeric_options() -> Vec<NumericOption> {
    let numeric = numeric_types();
    let mut found = Vec::new();
    for sub in Cli::command().get_subcommands() {
        for arg in sub.get_arguments() {
            if !arg.get_action().takes_values() {
                continue;
            }
            let id = arg.get_value_parser().type_id();
            if !numeric.iter().any(|p| p.type_id() == id) {
                continue;
            }
            let long = arg
                .get_long()
                .unwrap_or_else(|| {
                    panic!("{} {}: a numeric positional", sub.get_name(), arg.get_id())
                })
                .to_string();
            if BOUNDED_ELSEWHERE.contains(&(sub.get_name(), long.as_str())) {
                continue;
            }
            found.push(NumericOption {
                sub: sub.get_name().to_string(),
                long,
            });
        }
    }
    found
}

fn argv(o: &NumericOption, value: &str) -> Vec<String> {
    let mut v = vec!["host".to_string(), o.sub.clone()];
    v.extend(base(&o.sub).iter().map(|s| s.to_string()));
    v.push(format!("--{}={value}", o.long));
    v
}

/// Checks a refusal: a usage error (exit 2) whose message starts `error:`, names the option and the
/// range, has no panic and no endless number. Returns the message.
fn check_refusal(o: &NumericOption, value: &str, e: &clap::Error) -> String {
    let text = e.render().to_string();
    let what = format!("{} --{}={value}", o.sub, o.long);
    assert_eq!(e.exit_code(), 2, "{what}: {text}");
    assert!(text.starts_with("error:"), "{what}: {text}");
    assert!(!text.contains("panicked"), "{what}: {text}");
    assert!(longest_digit_run(&text) <= 20, "{what}: {text}");
    assert!(
        text.contains(&format!("--{}", o.long)) && text.contains("give a number in "),
        "{what}: not refused by a range parser of host::limits (a plain number parser, or the base \
         command line does not parse): {text}"
    );
    text
}

#[test]
fn every_numeric_option_refuses_nan_infinity_and_out_of_range_values() {
    let options = numeric_options();
    let mut problems = Vec::new();
    let (mut tried, mut refused, mut accepted) = (0, 0, 0);
    for sub in Cli::command().get_subcommands() {
        let mut v = vec!["host", sub.get_name()];
        v.extend(base(sub.get_name()));
        if let Err(e) = Cli::try_parse_from(&v) {
            problems.push(format!("base command line {v:?} does not parse: {e}"));
        }
    }
    for o in &options {
        // Every range parser refuses NaN and names its range; a plain f64 parser accepts NaN, a
        // plain integer parser refuses it without a range.
        let declared = match Cli::try_parse_from(argv(o, "NaN")) {
            Ok(_) => {
                problems.push(format!(
                    "{} --{}: NaN accepted (a plain number parser: use recording::limits::real, whole_u32 \
                     or whole_u64)",
                    o.sub, o.long
                ));
                continue;
            }
            Err(e) => {
                let text = e.render().to_string();
                match Declared::parse(&text) {
                    Some(d) => d,
                    None => {
                        problems.push(format!(
                            "{} --{}: NaN refused without a declared range (a plain number parser?): {text}",
                            o.sub, o.long
                        ));
                        continue;
                    }
                }
            }
        };
        for value in HOSTILE {
            tried += 1;
            match Cli::try_parse_from(argv(o, value)) {
                Err(e) => {
                    check_refusal(o, value, &e);
                    refused += 1;
                }
                Ok(_) => {
                    let v: f64 = value.parse().unwrap();
                    if !declared.contains(v) {
                        problems.push(format!(
                            "{} --{}={value} accepted outside its declared range {declared:?}",
                            o.sub, o.long
                        ));
                    }
                    accepted += 1;
                }
            }
        }
    }
    println!(
        "{tried} (subcommand, option, value) triples over {} numeric options: {refused} refused, \
         {accepted} accepted inside their range",
        options.len()
    );
    assert!(problems.is_empty(), "{}", problems.join("\n"));
    assert!(options.len() >= 40 && tried == options.len() * HOSTILE.len() && refused > 0);
}

#[test]
fn the_binary_refuses_a_sample_with_exit_2_before_any_work() {
    // NaN and 1e300 of every numeric option through the real binary: exit 2, `error:` first, the
    // option named, no panic; the base command lines name files that do not exist, so a refusal
    // about a file would mean the number was checked too late.
    let mut runs = 0;
    for o in numeric_options() {
        for value in ["NaN", "1e300"] {
            let args = argv(&o, value);
            let out = std::process::Command::new(env!("CARGO_BIN_EXE_host"))
                .args(&args[1..])
                .output()
                .unwrap();
            let stderr = String::from_utf8_lossy(&out.stderr);
            let what = format!("{} --{}={value}", o.sub, o.long);
            assert_eq!(out.status.code(), Some(2), "{what}: {stderr}");
            assert!(stderr.starts_with("error:"), "{what}: {stderr}");
            assert!(!stderr.contains("panicked"), "{what}: {stderr}");
            assert!(longest_digit_run(&stderr) <= 20, "{what}: {stderr}");
            assert!(
                stderr.contains(&format!("--{}", o.long)),
                "{what}: {stderr}"
            );
            runs += 1;
        }
    }
    assert!(runs > 0);
}

#[test]
fn a_column_named_twice_is_named_before_the_file_is_read() {
    let (ok, _, stderr) = host(&[
        "segment",
        "--input",
        "/nonexistent/raw.csv",
        "--out",
        "/nonexistent/out",
        "--acc-unit",
        "g",
        "--gyro-unit",
        "deg/s",
        "--rate-hz",
        "100",
        "--columns",
        "acc_x,acc_x,acc_z,gyr_x,gyr_y,gyr_z",
    ]);
    assert!(!ok);
    assert!(
        stderr.starts_with("error:") && stderr.contains("'acc_x' is named twice"),
        "{stderr}"
    );
    let (ok, _, stderr) = host(&[
        "segment",
        "--input",
        "/nonexistent/raw.csv",
        "--out",
        "/nonexistent/out",
        "--acc-unit",
        "g",
        "--gyro-unit",
        "deg/s",
        "--time-column",
        "GYR_Z",
    ]);
    assert!(!ok);
    assert!(stderr.contains("'gyr_z' is named twice"), "{stderr}");
}

#[test]
fn a_bias_walk_where_it_cannot_apply_is_refused() {
    // The walk is either given or estimated: both is a usage error (exit 2) naming the two, before
    // any work (the session directories do not exist), in both commands that take the estimator's
    // flags; so is either with the paper's method. Each alone parses there (the numeric sweep
    // above checks `--bias-walk`'s range).
    for base in [
        &["calibrate", "--input", "/nonexistent/session"][..],
        &[
            "batch",
            "--input",
            "/nonexistent/lot",
            "--out",
            "/nonexistent/out",
        ][..],
    ] {
        let mut both = base.to_vec();
        both.extend(["--bias-walk", "0.002", "--bias-walk-estimate"]);
        let out = std::process::Command::new(env!("CARGO_BIN_EXE_host"))
            .args(&both)
            .output()
            .unwrap();
        let stderr = String::from_utf8_lossy(&out.stderr);
        assert_eq!(out.status.code(), Some(2), "{both:?}: {stderr}");
        assert!(
            stderr.starts_with("error:")
                && stderr.contains("--bias-walk")
                && stderr.contains("--bias-walk-estimate"),
            "{both:?}: {stderr}"
        );
        // `--bias-walk-from` takes the walk from a file: with either of the others it is a usage
        // error too.
        for other in [&["--bias-walk", "0.002"][..], &["--bias-walk-estimate"][..]] {
            let mut v = base.to_vec();
            v.extend(["--bias-walk-from", "/nonexistent/noise.json"]);
            v.extend(other);
            let out = std::process::Command::new(env!("CARGO_BIN_EXE_host"))
                .args(&v)
                .output()
                .unwrap();
            let stderr = String::from_utf8_lossy(&out.stderr);
            assert_eq!(out.status.code(), Some(2), "{v:?}: {stderr}");
            assert!(stderr.contains("--bias-walk-from"), "{v:?}: {stderr}");
        }
        for alone in [
            &["--bias-walk", "0.002"][..],
            &["--bias-walk-estimate"][..],
            &["--bias-walk-from", "/nonexistent/noise.json"][..],
        ] {
            let mut v = vec!["host"];
            v.extend(base);
            v.extend(alone);
            assert!(Cli::try_parse_from(&v).is_ok(), "{v:?}");
            // The paper's eq. 24 has no weights for a walk: a usage error before any work.
            v.extend(["--method", "paper"]);
            let out = std::process::Command::new(env!("CARGO_BIN_EXE_host"))
                .args(&v[1..])
                .output()
                .unwrap();
            let stderr = String::from_utf8_lossy(&out.stderr);
            assert_eq!(out.status.code(), Some(2), "{v:?}: {stderr}");
            assert!(
                stderr.starts_with("error:") && stderr.contains("--method paper"),
                "{v:?}: {stderr}"
            );
        }
    }
}

#[test]
fn a_walk_from_a_file_without_one_is_refused_naming_the_fix() {
    // A unit file without a `[noise]` walk (the paper's unit) and a noise.json whose K the recording
    // did not determine: a usage error (exit 2) before any work, naming `host noise` and the file.
    let dir = std::env::temp_dir().join(format!("walk-from-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let unit = dir.join("unit.toml");
    std::fs::write(&unit, include_str!("../../reference/paper-unit.toml")).unwrap();
    let walkless = dir.join("walkless.toml");
    std::fs::write(
        &walkless,
        format!(
            "{}\n[noise]\naccel_white_mg = 1.0\n",
            include_str!("../../reference/paper-unit.toml")
        ),
    )
    .unwrap();
    for file in [&unit, &walkless] {
        let f = file.to_str().unwrap();
        for args in [
            &[
                "calibrate",
                "--input",
                "/nonexistent/session",
                "--bias-walk-from",
                f,
            ][..],
            &[
                "batch",
                "--input",
                "/nonexistent/lot",
                "--out",
                "/nonexistent/out",
                "--bias-walk-from",
                f,
            ][..],
        ] {
            let out = std::process::Command::new(env!("CARGO_BIN_EXE_host"))
                .args(args)
                .output()
                .unwrap();
            let stderr = String::from_utf8_lossy(&out.stderr);
            assert_eq!(out.status.code(), Some(2), "{args:?}: {stderr}");
            assert!(
                stderr.contains("host noise") && stderr.contains(f) && stderr.contains("[noise]"),
                "{args:?}: {stderr}"
            );
        }
    }
    std::fs::remove_dir_all(&dir).unwrap();
}
