//! `--port`: how the device commands reach a device. `--port sim` is the simulated device in-process
//! (the paper's unit on a virtual table, running the firmware's own logic); `--port sim-hand` the same
//! unit without a table, turned by a simulated hand when the hand-held procedure asks; any other
//! value is a serial port (a board's UART bridge or USB CDC-ACM port, or the pty of the firmware
//! running in QEMU).

use super::CliError;
use crate::limits;
use device::serial::{SerialTransport, DEFAULT_BAUD};
use device::sim::SimDevice;
use device::{AnyTransport, DeviceClient};
use estimator::unit_file::{UnitFile, UnitFileError};
use std::path::PathBuf;
use std::time::Duration;

/// The spelling of the simulated device.
pub(crate) const SIM_PORT: &str = "sim";
/// The spelling of the simulated device held in a simulated hand.
pub(crate) const SIM_HAND_PORT: &str = "sim-hand";

/// How to reach the device.
#[derive(clap::Args, Clone, Debug)]
pub(crate) struct PortArgs {
    /// Serial port of the device (e.g. /dev/ttyACM0, or the pty QEMU prints), `sim` for the built-in
    /// simulated device on its virtual table, or `sim-hand` for it held in a simulated hand (the
    /// hand-held procedure, as with a board and no table).
    #[arg(long)]
    pub port: String,
    /// A serial port's baud rate (default: 115200; no effect on a pty, refused for `sim`).
    #[arg(long, value_parser = recording::limits::whole_u32(limits::MIN_BAUD, limits::MAX_BAUD))]
    pub baud: Option<u32>,
    /// A serial port's seconds to wait for each answer before declaring the device silent
    /// (default: 5; refused for `sim`, which always answers at once).
    #[arg(long, value_parser = recording::limits::real(limits::MIN_TIMEOUT_S, limits::MAX_TIMEOUT_S))]
    pub timeout_s: Option<f64>,
    /// With `--port sim` or `sim-hand`: the simulated unit's parameters (unit file; default: the
    /// paper's unit).
    #[arg(long)]
    pub sim_unit: Option<PathBuf>,
}

/// Seconds to wait for each answer of a serial device, unless `--timeout-s` says otherwise.
pub(crate) const DEFAULT_TIMEOUT_S: f64 = 5.0;

impl PortArgs {
    /// Checks the numbers and that each option applies to the port before anything is opened or
    /// written.
    pub(crate) fn validate(&self) -> Result<(), CliError> {
        recording::limits::positive_at_most(
            "--timeout-s",
            self.timeout_s(),
            crate::limits::MAX_TIMEOUT_S,
        )?;
        refuse_for_port(
            &self.port,
            self.baud,
            self.timeout_s,
            self.sim_unit.is_some(),
        )
    }

    /// The answer timeout, s.
    pub(crate) fn timeout_s(&self) -> f64 {
        self.timeout_s.unwrap_or(DEFAULT_TIMEOUT_S)
    }
}

/// Refuses the serial line's options on the simulated device (it has no line and always answers
/// at once) and `--sim-unit` on a real port (there is no simulated unit to set).
pub(crate) fn refuse_for_port(
    port: &str,
    baud: Option<u32>,
    timeout_s: Option<f64>,
    sim_unit: bool,
) -> Result<(), CliError> {
    let sim = port == SIM_PORT || port == SIM_HAND_PORT;
    let serial_given: Vec<&str> = [
        ("--baud", baud.is_some()),
        ("--timeout-s", timeout_s.is_some()),
    ]
    .into_iter()
    .filter_map(|(flag, given)| given.then_some(flag))
    .collect();
    if sim && !serial_given.is_empty() {
        return Err(CliError::Usage(format!(
            "{} {} not apply to --port {port}: the simulated device has no serial line and answers \
             at once; leave {} out",
            serial_given.join(" and "),
            if serial_given.len() == 1 { "does" } else { "do" },
            if serial_given.len() == 1 { "it" } else { "them" },
        )));
    }
    if !sim && sim_unit {
        return Err(CliError::Usage(format!(
            "--sim-unit does not apply to --port {port}: it sets the simulated unit of --port \
             {SIM_PORT} or {SIM_HAND_PORT}; leave it out"
        )));
    }
    Ok(())
}

/// Opens the device named by `--port`.
pub(crate) fn connect(args: &PortArgs) -> Result<DeviceClient<AnyTransport>, CliError> {
    args.validate()?;
    let transport = if args.port == SIM_PORT || args.port == SIM_HAND_PORT {
        let (unit, name) = match &args.sim_unit {
            Some(p) => (UnitFile::load(p).map_err(CliError::Unit)?, p.clone()),
            None => (UnitFile::paper_unit(), PathBuf::from("<paper unit>")),
        };
        let truth = unit
            .to_calibration()
            .map_err(|e| CliError::Unit(UnitFileError::Invalid(name, e)))?;
        let dev = if args.port == SIM_HAND_PORT {
            SimDevice::hand_held(truth)
        } else {
            SimDevice::new(truth)
        }
        .map_err(CliError::SimDevice)?;
        AnyTransport::Sim(Box::new(dev))
    } else {
        AnyTransport::Serial(SerialTransport::open(
            &args.port,
            args.baud.unwrap_or(DEFAULT_BAUD),
        )?)
    };
    Ok(DeviceClient::new(
        transport,
        Duration::from_secs_f64(args.timeout_s()),
    ))
}
