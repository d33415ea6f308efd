//! `host flash`: write a calibration to a device, reset it and check that it applied it.

use super::port::{connect, PortArgs};
use super::CliError;
use clap::Args;
use device::procedure::ProcedureError;
use estimator::calibration_files;
use estimator::unit_file::{UnitFile, UnitFileError};
use outputs::calibration_guard::{meet, Meeting, Mine, Other, Temperatures};
use shared::blob::{self, ParameterBlob};
use shared::wire::Identity;
use std::path::{Path, PathBuf};

/// `host flash`.
#[derive(Debug, Args)]
pub(crate) struct FlashArgs {
    /// How to reach the device.
    #[command(flatten)]
    pub port: PortArgs,
    /// calibration.bin or calibration.toml.
    #[arg(long, value_name = "FILE")]
    pub calibration: PathBuf,
}

/// `host flash --port P --calibration FILE`: writes `calibration.bin` (or a `calibration.toml`, encoded
/// for the connected unit), resets the device and checks it applied it.
pub(crate) fn run(port: &PortArgs, calibration: &Path, quiet: bool) -> Result<(), CliError> {
    // The file is read (bounded: `/dev/zero` is refused at once) and checked before the device is
    // touched.
    let is_toml = calibration.extension().is_some_and(|e| e == "toml");
    let (cal, unit_id, file_bytes) = if is_toml {
        let unit = UnitFile::load(calibration).map_err(CliError::Unit)?;
        let cal = unit
            .to_calibration()
            .map_err(|e| CliError::Unit(UnitFileError::Invalid(calibration.to_path_buf(), e)))?;
        (cal, unit.unit_id().ok().flatten(), Vec::new())
    } else {
        let bytes = recording::limits::read_bounded(calibration, blob::BLOB_MAX_LEN as u64)
            .map_err(|e| CliError::Io(calibration.to_path_buf(), e))?;
        let decoded =
            blob::decode(&bytes).map_err(|e| CliError::Blob(calibration.to_path_buf(), e))?;
        (decoded.calibration, Some(decoded.unit_id), bytes)
    };
    let name = calibration.display().to_string();
    let mine = Mine {
        name: &name,
        cal: &cal,
        unit_id,
    };
    // Before the device is known, only what the file alone can fail (its scales).
    meet(Meeting::Flash, &mine, &device_side(None))?;
    let mut client = connect(port)?;
    let identity = client.identify()?;
    meet(Meeting::Flash, &mine, &device_side(Some(&identity)))?;
    let bytes = if is_toml {
        let blob = ParameterBlob {
            unit_id: identity.unit_id,
            calibration: cal,
            created_unix_s: calibration_files::now_unix_s(),
        };
        let (buf, n) = blob
            .to_bytes()
            .map_err(|e| CliError::Blob(calibration.to_path_buf(), e))?;
        buf[..n].to_vec()
    } else {
        file_bytes
    };
    client.write_calibration(&bytes)?;
    let after = client.reset()?;
    let back = client.read_calibration()?;
    if back != bytes {
        return Err(CliError::Procedure(ProcedureError::ReadBackMismatch));
    }
    super::output::Output { json: false, quiet }.line(format_args!(
        "flashed {} bytes to unit {}; after reset: {:?}",
        bytes.len(),
        identity.unit_id,
        after.calibration
    ))?;
    Ok(())
}

/// The device's side of a meeting (`None`: not connected yet, nothing of it known).
pub(crate) fn device_side(identity: Option<&Identity>) -> Other<'static> {
    Other {
        name: "the device",
        unit_id: identity.map(|i| i.unit_id.to_string()),
        output_unit: identity.map(|i| i.output_unit),
        frame: None,
        temperatures: Temperatures::None,
    }
}
