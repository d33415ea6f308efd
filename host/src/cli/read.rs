//! `host read`: the calibration stored on a device, as a unit file.

use super::port::{connect, PortArgs};
use super::CliError;
use crate::unit_file::UnitFile;
use clap::Args;
use shared::blob;
use std::path::{Path, PathBuf};

/// `host read`.
#[derive(Debug, Args)]
pub struct ReadArgs {
    /// How to reach the device.
    #[command(flatten)]
    pub port: PortArgs,
    /// Where to write it (default: stdout).
    #[arg(long, value_name = "FILE")]
    pub out: Option<PathBuf>,
}

/// `host read --port P [--out FILE]`: the calibration on the device, as `calibration.toml`.
pub fn run(port: &PortArgs, out: Option<&Path>) -> Result<(), CliError> {
    let mut client = connect(port)?;
    let identity = client.identify()?;
    let bytes = client.read_calibration()?;
    let src = PathBuf::from(format!("<device {}>", identity.unit_id));
    let blob = blob::decode(&bytes).map_err(|e| CliError::Blob(src, e))?;
    let text = UnitFile::from_calibration(&blob.calibration, Some(blob.unit_id), None).to_toml();
    match out {
        Some(p) => {
            std::fs::write(p, &text).map_err(|e| CliError::Io(p.to_path_buf(), e))?;
            println!(
                "wrote the calibration of unit {} to {}",
                blob.unit_id,
                p.display()
            );
        }
        None => print!("{text}"),
    }
    Ok(())
}
