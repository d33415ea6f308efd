//! `host flash`: write a calibration to a device, reset it and check that it applied it.

use super::port::{connect, PortArgs};
use super::CliError;
use crate::calibration_files;
use crate::device::procedure::ProcedureError;
use crate::unit_file::UnitFile;
use clap::Args;
use shared::blob::{self, ParameterBlob};
use shared::wire::Identity;
use std::path::{Path, PathBuf};

/// `host flash`.
#[derive(Debug, Args)]
pub struct FlashArgs {
    /// How to reach the device.
    #[command(flatten)]
    pub port: PortArgs,
    /// calibration.bin or calibration.toml.
    #[arg(long, value_name = "FILE")]
    pub calibration: PathBuf,
}

/// `host flash --port P --calibration FILE`: writes `calibration.bin` (or a `calibration.toml`, encoded
/// for the connected unit), resets the device and checks it applied it.
pub fn run(port: &PortArgs, calibration: &Path, quiet: bool) -> Result<(), CliError> {
    // The file is read (bounded: `/dev/zero` is refused at once) and checked before the device is
    // touched.
    let is_toml = calibration.extension().is_some_and(|e| e == "toml");
    let unit = if is_toml {
        let unit = UnitFile::load(calibration).map_err(CliError::Unit)?;
        let cal = unit.to_calibration().map_err(CliError::Usage)?;
        crate::calibration_guard::check_scales(&cal)?;
        Some((unit, cal))
    } else {
        None
    };
    let file_bytes = if is_toml {
        Vec::new()
    } else {
        let bytes = crate::limits::read_bounded(calibration, blob::BLOB_MAX_LEN as u64)
            .map_err(|e| CliError::Io(calibration.to_path_buf(), e))?;
        blob::decode(&bytes).map_err(|e| CliError::Blob(calibration.to_path_buf(), e))?;
        bytes
    };
    let mut client = connect(port)?;
    let identity = client.identify()?;
    let bytes = if let Some((unit, cal)) = unit {
        if let Ok(Some(id)) = unit.unit_id() {
            if id != identity.unit_id {
                return Err(CliError::WrongUnit {
                    blob: id.to_string(),
                    device: identity.unit_id.to_string(),
                });
            }
        }
        check_output_unit(&cal, &identity)?;
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
        let bytes = file_bytes;
        let decoded =
            blob::decode(&bytes).map_err(|e| CliError::Blob(calibration.to_path_buf(), e))?;
        if decoded.unit_id != identity.unit_id {
            return Err(CliError::WrongUnit {
                blob: decoded.unit_id.to_string(),
                device: identity.unit_id.to_string(),
            });
        }
        check_output_unit(&decoded.calibration, &identity)?;
        bytes
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

/// The calibration maps the outputs the device gives: one made in another output unit (m/s² from a
/// logger, volts from the analog board) would compensate numbers of another kind.
fn check_output_unit(cal: &shared::Calibration, identity: &Identity) -> Result<(), CliError> {
    if cal.statics.output_unit != identity.output_unit {
        return Err(CliError::WrongOutputUnit {
            calibration: cal.statics.output_unit.symbol(),
            device: identity.output_unit.symbol(),
        });
    }
    Ok(())
}
