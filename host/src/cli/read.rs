//! `host read`: the calibration stored on a device, as a unit file.

use super::port::{connect, PortArgs};
use super::CliError;
use clap::Args;
use estimator::unit_file::UnitFile;
use recording::output_file::OutputFile;
use shared::blob;
use std::io::Write;
use std::path::PathBuf;

/// `host read`.
#[derive(Debug, Args)]
pub(crate) struct ReadArgs {
    /// How to reach the device.
    #[command(flatten)]
    pub port: PortArgs,
    /// Where to write it (default: stdout).
    #[arg(long, value_name = "FILE")]
    pub out: Option<PathBuf>,
    /// Replace an existing --out file.
    #[arg(long)]
    pub force: bool,
}

/// `host read --port P [--out FILE [--force]]`: the calibration on the device, as
/// `calibration.toml`. An existing FILE is refused before the device is asked (a calibration is
/// never replaced without `--force`), and the file appears whole or not at all.
pub(crate) fn run(a: &ReadArgs) -> Result<(), CliError> {
    let file = a
        .out
        .as_deref()
        .map(|p| OutputFile::create(p, a.force))
        .transpose()?;
    let mut client = connect(&a.port)?;
    let identity = client.identify()?;
    let bytes = client.read_calibration()?;
    let src = PathBuf::from(format!("<device {}>", identity.unit_id));
    let blob = blob::decode(&bytes).map_err(|e| CliError::Blob(src, e))?;
    let mine = outputs::calibration_guard::Mine {
        name: "the calibration the device holds",
        cal: &blob.calibration,
        unit_id: Some(blob.unit_id),
    };
    outputs::calibration_guard::meet(
        outputs::calibration_guard::Meeting::Read,
        &mine,
        &super::flash::device_side(Some(&identity)),
    )?;
    let text = UnitFile::from_calibration(&blob.calibration, Some(blob.unit_id), None).to_toml();
    match file.zip(a.out.as_ref()) {
        Some((mut f, p)) => {
            f.write_all(text.as_bytes()).map_err(|e| f.io_error(e))?;
            f.commit()?;
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
