//! `host bringup`: the first checks of a freshly flashed board at rest, each with pass/fail and
//! the likely cause of a failure ([`device::bringup`]).

use super::port::{connect, PortArgs};
use super::CliError;
use clap::Args;
use device::bringup::{bringup, bringup_with, Verdict};
use device::bringup_motion::{Operator, Pose, TableOperator};
use device::client::{DeviceClient, LinkError, Transport};
use device::AnyTransport;
use std::io::IsTerminal;
use std::time::Duration;

/// `host bringup`.
#[derive(Debug, Args)]
pub(crate) struct BringupArgs {
    /// How to reach the device.
    #[command(flatten)]
    pub port: PortArgs,
    /// Seconds of samples to measure, the board at rest (the sample rate is timed on this
    /// computer's clock over them).
    #[arg(long, default_value_t = 3.0, value_parser = recording::limits::real(0.5, 60.0))]
    pub seconds: f64,
}

/// A person at this terminal: asked for each pose, answering with Enter.
struct TerminalOperator;

impl<T: Transport> Operator<T> for TerminalOperator {
    fn pose(&mut self, pose: Pose, _: &mut DeviceClient<T>) -> Result<bool, LinkError> {
        let wait = pose == Pose::NoseUp;
        eprintln!(
            "bringup: {}{}",
            pose.instruction(),
            if wait { ", then press Enter" } else { "" }
        );
        if wait {
            let mut line = String::new();
            std::io::stdin()
                .read_line(&mut line)
                .map_err(|e| LinkError::Io("reading the operator's Enter".into(), e))?;
        }
        Ok(true)
    }

    fn rest(&mut self, _: &mut DeviceClient<T>) -> Result<(), LinkError> {
        eprintln!("bringup: stop waving; put the board down");
        Ok(())
    }
}

/// `host bringup --port P`: prints each check and fails (exit status 3) when one fails. The
/// simulated device runs in real time here, so that its rate is measured as a board's; its
/// virtual table takes the poses. On a board, a person at the terminal does (without a terminal
/// the pose checks are skipped, each saying so).
pub(crate) fn run(a: &BringupArgs, quiet: bool) -> Result<(), CliError> {
    let mut client = connect(&a.port)?;
    let measure = Duration::from_secs_f64(a.seconds);
    let report = if let AnyTransport::Sim(dev) = client.transport_mut() {
        dev.pace_real_time();
        bringup_with(&mut client, measure, &mut TableOperator)?
    } else if std::io::stdin().is_terminal() {
        eprintln!("bringup: place the board flat, top up, and keep it still");
        bringup_with(&mut client, measure, &mut TerminalOperator)?
    } else {
        bringup(&mut client, measure)?
    };
    if !quiet {
        crate::out!("{report}")?;
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
