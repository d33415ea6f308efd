//! `--port`: how the device commands reach a device. `--port sim` is the simulated device in-process
//! (the paper's unit on a virtual table, running the firmware's own logic); `--port sim-hand` the same
//! unit without a table, turned by a simulated hand when the hand-held procedure asks; any other
//! value is a serial port (a board's UART bridge or USB CDC-ACM port, or the pty of the firmware
//! running in QEMU).

use super::CliError;
use crate::device::serial::{SerialTransport, DEFAULT_BAUD};
use crate::device::sim::SimDevice;
use crate::device::{AnyTransport, DeviceClient};
use crate::limits;
use crate::unit_file::UnitFile;
use std::path::PathBuf;
use std::time::Duration;

/// The spelling of the simulated device.
pub(crate) const SIM_PORT: &str = "sim";
/// The spelling of the simulated device held in a simulated hand.
pub(crate) const SIM_HAND_PORT: &str = "sim-hand";

/// How to reach the device.
#[derive(clap::Args, Clone, Debug)]
pub struct PortArgs {
    /// Serial port of the device (e.g. /dev/ttyACM0, or the pty QEMU prints), `sim` for the built-in
    /// simulated device on its virtual table, or `sim-hand` for it held in a simulated hand (the
    /// hand-held procedure, as with a board and no table).
    #[arg(long)]
    pub port: String,
    /// Baud rate of the serial port (no effect on a pty or on `sim`).
    #[arg(long, default_value_t = DEFAULT_BAUD, value_parser = limits::whole_u32(limits::MIN_BAUD, limits::MAX_BAUD))]
    pub baud: u32,
    /// Seconds to wait for each answer before declaring the device silent.
    #[arg(long, default_value_t = 5.0, value_parser = limits::real(limits::MIN_TIMEOUT_S, limits::MAX_TIMEOUT_S))]
    pub timeout_s: f64,
    /// With `--port sim` or `sim-hand`: the simulated unit's parameters (unit file; default: the
    /// paper's unit).
    #[arg(long)]
    pub sim_unit: Option<PathBuf>,
}

impl PortArgs {
    /// Checks the numbers before anything is opened or written.
    pub(crate) fn validate(&self) -> Result<(), CliError> {
        crate::limits::positive_at_most(
            "--timeout-s",
            self.timeout_s,
            crate::limits::MAX_TIMEOUT_S,
        )?;
        Ok(())
    }
}

/// Opens the device named by `--port`.
pub fn connect(args: &PortArgs) -> Result<DeviceClient<AnyTransport>, CliError> {
    args.validate()?;
    let transport = if args.port == SIM_PORT || args.port == SIM_HAND_PORT {
        let unit = match &args.sim_unit {
            Some(p) => UnitFile::load(p).map_err(CliError::Unit)?,
            None => UnitFile::paper_unit(),
        };
        let truth = unit
            .to_calibration()
            .map_err(|m| CliError::Usage(format!("--sim-unit: {m}")))?;
        let dev = if args.port == SIM_HAND_PORT {
            SimDevice::hand_held(truth)
        } else {
            SimDevice::new(truth)
        }
        .map_err(|e| CliError::Usage(e.to_string()))?;
        AnyTransport::Sim(Box::new(dev))
    } else {
        AnyTransport::Serial(SerialTransport::open(&args.port, args.baud)?)
    };
    Ok(DeviceClient::new(
        transport,
        Duration::from_secs_f64(args.timeout_s),
    ))
}
