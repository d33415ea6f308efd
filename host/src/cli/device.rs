//! The commands that talk to a device: `calibrate --port`, `flash`, `read`, `monitor`.
//!
//! `--port sim` is the simulated device in-process (the paper's unit on a virtual table, running the
//! firmware's own logic); any other value is a serial port (a board's UART bridge, or the pty of the
//! firmware running in QEMU).

use crate::calibration_files::{self, OutputError};
use crate::device::procedure::{
    self, AutomaticOperator, Operator, ProcedureError, ProcedureOptions, TerminalOperator,
};
use crate::device::serial::{SerialTransport, DEFAULT_BAUD};
use crate::device::sim::SimDevice;
use crate::device::{DeviceClient, LinkError, Transport};
use crate::estimate::EstimateOptions;
use crate::session::{self, PlanError};
use crate::unit_file::{UnitFile, UnitFileError};
use shared::blob::{self, BlobError, ParameterBlob};
use shared::wire::{SampleFlags, StreamKind};
use std::path::{Path, PathBuf};
use std::time::Duration;

/// The spelling of the simulated device.
pub const SIM_PORT: &str = "sim";

/// How to reach the device.
#[derive(clap::Args, Clone, Debug)]
pub struct PortArgs {
    /// Serial port of the device (e.g. /dev/ttyACM0, or the pty QEMU prints), or `sim` for the built-in
    /// simulated device.
    #[arg(long)]
    pub port: String,
    /// Baud rate of the serial port (no effect on a pty or on `sim`).
    #[arg(long, default_value_t = DEFAULT_BAUD)]
    pub baud: u32,
    /// Seconds to wait for each answer before declaring the device silent.
    #[arg(long, default_value_t = 5.0)]
    pub timeout_s: f64,
    /// With `--port sim`: the simulated unit's parameters (unit file; default: the paper's unit).
    #[arg(long)]
    pub sim_unit: Option<PathBuf>,
}

/// `host calibrate --port …` settings (the CLI fills them from `calibrate`'s flags).
#[derive(Clone, Debug)]
pub struct CalibratePortOptions {
    /// Plan file or built-in plan name (default: `oblique` on a device with a virtual table, else `paper`).
    pub plan: Option<String>,
    /// Output directory (default: `calibration-<unit id>`).
    pub out_dir: Option<PathBuf>,
    /// Samples per streamed window (default: a 50th of the device's rate).
    pub window: Option<u32>,
    /// Estimator settings.
    pub estimate: EstimateOptions,
    /// Largest compensated error accepted at a verification position, mg.
    pub verify_tolerance_mg: f64,
    /// Replace an existing recording and calibration in `out_dir`.
    pub force: bool,
    /// No progress bars or progress lines.
    pub quiet: bool,
}

/// Why a device command failed.
#[derive(Debug)]
pub enum DeviceCliError {
    /// The link.
    Link(LinkError),
    /// The procedure.
    Procedure(ProcedureError),
    /// A plan.
    Plan(PlanError),
    /// A unit file.
    Unit(UnitFileError),
    /// A blob file.
    Blob(PathBuf, BlobError),
    /// A blob made for another unit.
    WrongUnit {
        /// The blob's unit.
        blob: String,
        /// The device's unit.
        device: String,
    },
    /// A file.
    Io(PathBuf, std::io::Error),
    /// Writing a result.
    Output(OutputError),
    /// A bad option.
    Usage(String),
    /// The procedure ran but the verification failed.
    VerificationFailed,
    /// Standard output is closed or full; the device and the files were written before it.
    Stdout(std::io::Error),
}

impl std::fmt::Display for DeviceCliError {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match self {
            DeviceCliError::Link(e) => e.fmt(f),
            DeviceCliError::Procedure(e) => e.fmt(f),
            DeviceCliError::Plan(e) => e.fmt(f),
            DeviceCliError::Unit(e) => e.fmt(f),
            DeviceCliError::Blob(p, e) => write!(f, "{}: {e}", p.display()),
            DeviceCliError::WrongUnit { blob, device } => write!(
                f,
                "this calibration was made for unit {blob}, the device is unit {device}: calibrate this \
                 unit, or flash its own calibration"
            ),
            DeviceCliError::Io(p, e) => write!(f, "{}: {e}", p.display()),
            DeviceCliError::Output(e) => e.fmt(f),
            DeviceCliError::Usage(m) => f.write_str(m),
            DeviceCliError::Stdout(e) => write!(
                f,
                "cannot write to standard output ({e}); the files and the device were written before this"
            ),
            DeviceCliError::VerificationFailed => f.write_str(
                "FAIL: the calibration is on the device but its compensated output is outside the tolerance \
                 at some verification positions (see above)",
            ),
        }
    }
}

impl std::error::Error for DeviceCliError {}

impl From<std::io::Error> for DeviceCliError {
    fn from(e: std::io::Error) -> Self {
        DeviceCliError::Stdout(e)
    }
}

impl From<LinkError> for DeviceCliError {
    fn from(e: LinkError) -> Self {
        DeviceCliError::Link(e)
    }
}

/// Either kind of device link.
pub enum AnyTransport {
    /// The in-process simulated device.
    Sim(Box<SimDevice>),
    /// A serial port or pty.
    Serial(SerialTransport),
}

impl Transport for AnyTransport {
    fn send(&mut self, bytes: &[u8]) -> Result<(), LinkError> {
        match self {
            AnyTransport::Sim(d) => d.send(bytes),
            AnyTransport::Serial(s) => s.send(bytes),
        }
    }
    fn receive(&mut self, buf: &mut [u8], timeout: Duration) -> Result<usize, LinkError> {
        match self {
            AnyTransport::Sim(d) => d.receive(buf, timeout),
            AnyTransport::Serial(s) => s.receive(buf, timeout),
        }
    }
}

fn usage(e: crate::limits::RangeError) -> DeviceCliError {
    DeviceCliError::Usage(e.to_string())
}

impl PortArgs {
    /// Checks the numbers before anything is opened or written.
    pub fn validate(&self) -> Result<(), DeviceCliError> {
        crate::limits::positive_at_most(
            "--timeout-s",
            self.timeout_s,
            crate::limits::MAX_TIMEOUT_S,
        )
        .map_err(usage)?;
        Ok(())
    }
}

impl CalibratePortOptions {
    /// Checks the numbers before anything is opened, recorded or flashed.
    pub fn validate(&self) -> Result<(), DeviceCliError> {
        use crate::limits::{count_in, positive_at_most, MAX_TOLERANCE_MG, MAX_WINDOW};
        if let Some(w) = self.window {
            count_in("--window", w, MAX_WINDOW).map_err(usage)?;
        }
        positive_at_most(
            "--verify-tolerance-mg",
            self.verify_tolerance_mg,
            MAX_TOLERANCE_MG,
        )
        .map_err(usage)?;
        Ok(())
    }
}

/// Opens the device named by `--port`.
pub fn connect(args: &PortArgs) -> Result<DeviceClient<AnyTransport>, DeviceCliError> {
    args.validate()?;
    let transport = if args.port == SIM_PORT {
        let unit = match &args.sim_unit {
            Some(p) => UnitFile::load(p).map_err(DeviceCliError::Unit)?,
            None => UnitFile::paper_unit(),
        };
        let truth = unit
            .to_calibration()
            .map_err(|m| DeviceCliError::Usage(format!("--sim-unit: {m}")))?;
        let dev = SimDevice::new(truth).map_err(|e| DeviceCliError::Usage(e.to_string()))?;
        AnyTransport::Sim(Box::new(dev))
    } else {
        AnyTransport::Serial(SerialTransport::open(&args.port, args.baud)?)
    };
    Ok(DeviceClient::new(
        transport,
        Duration::from_secs_f64(args.timeout_s),
    ))
}

/// `host calibrate --port`: runs the whole procedure and ends with a pass/fail line.
pub fn calibrate_port(port: &PortArgs, a: &CalibratePortOptions) -> Result<(), DeviceCliError> {
    a.validate()?;
    let mut client = connect(port)?;
    let identity = client.identify()?;
    let plan = match &a.plan {
        Some(spec) => session::builtin::load_plan(spec),
        None => procedure::default_plan(&identity),
    }
    .map_err(DeviceCliError::Plan)?;
    let out_dir = procedure::default_out_dir(a.out_dir.as_deref(), &identity);
    let mut opts = ProcedureOptions::new(plan, out_dir);
    opts.window_samples = a.window;
    opts.estimate = a.estimate.clone();
    opts.verify_tolerance_mg = a.verify_tolerance_mg;
    opts.force = a.force;
    opts.quiet = a.quiet;
    let mut auto = AutomaticOperator {
        verbose: !a.quiet,
        warnings: Vec::new(),
    };
    let mut person = TerminalOperator;
    let op: &mut dyn Operator = if procedure::has_virtual_table(&identity) {
        &mut auto
    } else {
        &mut person
    };
    let result = procedure::run(&mut client, &opts, op).map_err(DeviceCliError::Procedure)?;
    for w in &result.warnings {
        crate::outln!("warning: {w}")?;
    }
    let worst = result
        .verification
        .iter()
        .map(|v| v.error_mg)
        .fold(0.0, f64::max);
    if result.passed {
        crate::outln!(
            "PASS: unit {} calibrated, stored and verified at {} positions (worst error {worst:.3} mg ≤ {} mg); \
             results in {}",
            result.identity.unit_id,
            result.verification.len(),
            opts.verify_tolerance_mg,
            opts.out_dir.display()
        )?;
        Ok(())
    } else {
        crate::outln!(
            "FAIL: worst verification error {worst:.3} mg > {} mg",
            opts.verify_tolerance_mg
        )?;
        Err(DeviceCliError::VerificationFailed)
    }
}

/// `host flash --port P --calibration FILE`: writes `calibration.bin` (or a `calibration.toml`, encoded
/// for the connected unit), resets the device and checks it applied it.
pub fn flash(port: &PortArgs, calibration: &Path) -> Result<(), DeviceCliError> {
    // The file is read and checked before the device is touched.
    let is_toml = calibration.extension().is_some_and(|e| e == "toml");
    let unit = if is_toml {
        Some(UnitFile::load(calibration).map_err(DeviceCliError::Unit)?)
    } else {
        None
    };
    let file_bytes = if is_toml {
        Vec::new()
    } else {
        let bytes = crate::limits::read_bounded(calibration, blob::BLOB_MAX_LEN as u64)
            .map_err(|e| DeviceCliError::Io(calibration.to_path_buf(), e))?;
        blob::decode(&bytes).map_err(|e| DeviceCliError::Blob(calibration.to_path_buf(), e))?;
        bytes
    };
    let mut client = connect(port)?;
    let identity = client.identify()?;
    let bytes = if let Some(unit) = unit {
        if let Ok(Some(id)) = unit.unit_id() {
            if id != identity.unit_id {
                return Err(DeviceCliError::WrongUnit {
                    blob: id.to_string(),
                    device: identity.unit_id.to_string(),
                });
            }
        }
        let cal = unit.to_calibration().map_err(DeviceCliError::Usage)?;
        let blob = ParameterBlob {
            unit_id: identity.unit_id,
            calibration: cal,
            created_unix_s: calibration_files::now_unix_s(),
        };
        let (buf, n) = blob
            .to_bytes()
            .map_err(|e| DeviceCliError::Blob(calibration.to_path_buf(), e))?;
        buf[..n].to_vec()
    } else {
        let bytes = file_bytes;
        let decoded =
            blob::decode(&bytes).map_err(|e| DeviceCliError::Blob(calibration.to_path_buf(), e))?;
        if decoded.unit_id != identity.unit_id {
            return Err(DeviceCliError::WrongUnit {
                blob: decoded.unit_id.to_string(),
                device: identity.unit_id.to_string(),
            });
        }
        bytes
    };
    client.write_calibration(&bytes)?;
    let after = client.reset()?;
    let back = client.read_calibration()?;
    if back != bytes {
        return Err(DeviceCliError::Procedure(ProcedureError::ReadBackMismatch));
    }
    crate::outln!(
        "flashed {} bytes to unit {}; after reset: {:?}",
        bytes.len(),
        identity.unit_id,
        after.calibration
    )?;
    Ok(())
}

/// `host read --port P [--out FILE]`: the calibration on the device, as `calibration.toml`.
pub fn read(port: &PortArgs, out: Option<&Path>) -> Result<(), DeviceCliError> {
    let mut client = connect(port)?;
    let identity = client.identify()?;
    let bytes = client.read_calibration()?;
    let src = PathBuf::from(format!("<device {}>", identity.unit_id));
    let blob = blob::decode(&bytes).map_err(|e| DeviceCliError::Blob(src, e))?;
    let text = UnitFile::from_calibration(&blob.calibration, Some(blob.unit_id), None).to_toml();
    match out {
        Some(p) => {
            std::fs::write(p, &text).map_err(|e| DeviceCliError::Io(p.to_path_buf(), e))?;
            crate::outln!(
                "wrote the calibration of unit {} to {}",
                blob.unit_id,
                p.display()
            )?;
        }
        None => crate::out!("{text}")?,
    }
    Ok(())
}

/// `host monitor --port P [--window N] [--count N]`: live compensated output with its flags.
pub fn monitor(port: &PortArgs, window: u32, count: Option<u64>) -> Result<(), DeviceCliError> {
    crate::limits::count_in("--window", window, crate::limits::MAX_WINDOW).map_err(usage)?;
    let mut client = connect(port)?;
    let identity = client.identify()?;
    let g = shared::STANDARD_GRAVITY_M_S2;
    crate::outln!(
        "unit {} ({:?}), calibration {:?}; compensated specific force in g, {} samples per line",
        identity.unit_id,
        identity.board,
        identity.calibration,
        window
    )?;
    client.start_stream(StreamKind::CompensatedWindows, window.max(1))?;
    let mut n = 0u64;
    while count.is_none_or(|c| n < c) {
        let w = client.next_compensated_window()?;
        let flags = [
            (SampleFlags::UNCALIBRATED, "UNCALIBRATED"),
            (SampleFlags::SATURATED, "SATURATED"),
            (SampleFlags::NON_FINITE, "NON-FINITE"),
            (SampleFlags::FRAMES_DROPPED, "DROPPED"),
        ]
        .iter()
        .filter(|(bit, _)| w.flags.has(*bit))
        .map(|(_, name)| *name)
        .collect::<Vec<_>>()
        .join(",");
        crate::outln!(
            "{:10.3} s  f = ({:+.6}, {:+.6}, {:+.6}) g  ω = ({:+8.2}, {:+8.2}, {:+8.2}) °/s  {}",
            w.first_sample as f64 / f64::from(identity.sample_rate_hz.max(1)),
            f64::from(w.mean_m_s2[0]) / g,
            f64::from(w.mean_m_s2[1]) / g,
            f64::from(w.mean_m_s2[2]) / g,
            f64::from(w.mean_rate_rad_s[0]).to_degrees(),
            f64::from(w.mean_rate_rad_s[1]).to_degrees(),
            f64::from(w.mean_rate_rad_s[2]).to_degrees(),
            if flags.is_empty() {
                "calibrated"
            } else {
                &flags
            }
        )?;
        n += 1;
    }
    client.stop_stream()?;
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::device::sim::SIM_UNIT_ID;
    use shared::wire::DeviceError;
    use shared::UnitId;

    fn sim() -> PortArgs {
        PortArgs {
            port: SIM_PORT.into(),
            baud: DEFAULT_BAUD,
            timeout_s: 1.0,
            sim_unit: None,
        }
    }

    fn blob_file(dir: &Path, unit: UnitId) -> PathBuf {
        let cal = UnitFile::paper_unit().to_calibration().unwrap();
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
        flash(&sim(), &blob_file(dir.path(), SIM_UNIT_ID)).unwrap();
        let e = flash(&sim(), &blob_file(dir.path(), UnitId(*b"ANOTHER-UNIT"))).unwrap_err();
        assert!(matches!(e, DeviceCliError::WrongUnit { .. }), "{e}");
        assert!(e.to_string().contains("made for unit"), "{e}");
        // A corrupt file is refused before anything reaches the device.
        std::fs::write(dir.path().join("bad.bin"), b"ACAL garbage").unwrap();
        let e = flash(&sim(), &dir.path().join("bad.bin")).unwrap_err();
        assert!(matches!(e, DeviceCliError::Blob(..)), "{e}");
    }

    #[test]
    fn read_of_an_uncalibrated_device_is_a_typed_error_and_monitor_streams() {
        let e = read(&sim(), None).unwrap_err();
        assert!(
            matches!(
                e,
                DeviceCliError::Link(LinkError::Device(DeviceError::NoCalibration))
            ),
            "{e}"
        );
        monitor(&sim(), 100, Some(3)).unwrap();
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
}
