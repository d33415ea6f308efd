//! `host bringup`: the first checks of a freshly flashed board at rest, each with pass/fail and
//! the likely cause of a failure ([`crate::device::bringup`]).

use super::port::{connect, PortArgs};
use super::CliError;
use crate::device::bringup::{bringup, Verdict};
use crate::device::AnyTransport;
use crate::limits;
use clap::Args;
use std::time::Duration;

/// `host bringup`.
#[derive(Debug, Args)]
pub struct BringupArgs {
    /// How to reach the device.
    #[command(flatten)]
    pub port: PortArgs,
    /// Seconds of samples to measure, the board at rest (the sample rate is timed on this
    /// computer's clock over them).
    #[arg(long, default_value_t = 3.0, value_parser = limits::real(0.5, 60.0))]
    pub seconds: f64,
}

/// `host bringup --port P`: prints each check and fails (exit status 3) when one fails. The
/// simulated device runs in real time here, so that its rate is measured as a board's.
pub fn run(a: &BringupArgs, quiet: bool) -> Result<(), CliError> {
    let mut client = connect(&a.port)?;
    if let AnyTransport::Sim(dev) = client.transport_mut() {
        dev.pace_real_time();
    }
    let report = bringup(&mut client, Duration::from_secs_f64(a.seconds))?;
    if !quiet {
        for c in &report.checks {
            let verdict = match c.verdict {
                Verdict::Pass => "PASS",
                Verdict::Fail => "FAIL",
                Verdict::Skipped => "SKIP",
            };
            crate::outln!("{verdict}  {:<28} {}", c.name, c.detail)?;
            if let Some(cause) = &c.cause {
                crate::outln!("      likely cause: {cause}")?;
            }
        }
    }
    if report.passed() {
        return Ok(());
    }
    let failed: Vec<&str> = report
        .checks
        .iter()
        .filter(|c| c.verdict == Verdict::Fail)
        .map(|c| c.name)
        .collect();
    Err(CliError::ChecksFailed(format!(
        "bring-up: {}",
        failed.join(", ")
    )))
}
