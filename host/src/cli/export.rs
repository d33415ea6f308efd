//! `host export`: a calibration in another tool's format.

use super::output::Output;
use super::CliError;
use clap::Args;
use estimator::unit_file::{UnitFile, UnitFileError};
use outputs::export::kalibr::KalibrNoise;
use outputs::export::{render, ExportFormat, ExportInput, ExportOptions};
use recording::output_file::write_atomic;
use std::path::PathBuf;

/// `host export`.
#[derive(Debug, Args)]
pub(crate) struct ExportArgs {
    /// The calibration (a unit file, e.g. calibration.toml); with `--instance all`, none: each IMU
    /// is calibrated from the --log.
    #[arg(long, value_name = "FILE")]
    pub calibration: Option<PathBuf>,
    /// The format.
    #[arg(long, value_enum, default_value_t = ExportFormat::All)]
    pub format: ExportFormat,
    /// Where to write it (default: stdout); for c a directory, where the package goes.
    #[arg(long, value_name = "FILE|DIR")]
    pub out: Option<PathBuf>,
    /// Replace an existing --out file.
    #[arg(long)]
    pub force: bool,
    /// The noise figures for Kalibr: noise.json written by `host noise`.
    #[arg(long, value_name = "NOISE.json")]
    pub noise: Option<PathBuf>,
    /// Kalibr's rostopic of the IMU (default: /imu0).
    #[arg(long, value_name = "TOPIC")]
    pub rostopic: Option<String>,
    /// For kalibr, px4, ardupilot: m/s² per output unit of the driver's reading (default: 1 for a
    /// calibration in m/s², 9.80665 for one in g; required for V and LSB).
    #[arg(long, value_name = "M_S2_PER_UNIT", allow_negative_numbers = true, value_parser = recording::limits::real(1e-9, recording::limits::MAX_LIMIT))]
    pub driver_scale: Option<f64>,
    /// For px4 and ardupilot: the vehicle's log (PX4 ULog, ArduPilot DataFlash) the calibration was
    /// made from: the device ids of its IMU and the slot each holds are read from the log's
    /// parameters (PX4's sensor_accel.device_id and CAL_ACCn_ID, ArduPilot's INS_ACC*_ID).
    #[arg(long, value_name = "LOG")]
    pub log: Option<PathBuf>,
    /// With --log: the IMU the calibration is for (ULog's multi_id, DataFlash's I; default 0), or
    /// `all`: calibrate each IMU of the vehicle from the hand-held session the log holds and write
    /// one file with every slot.
    #[arg(long, value_name = "N|all", value_parser = instance_choice)]
    pub instance: Option<InstanceChoice>,
    /// For px4 and ardupilot: the accelerometer's calibration slot (PX4's n of CAL_ACCn_*, 0..3;
    /// ArduPilot's INS_ACC*, INS_ACC2*, INS_ACC3*: 0..2); default: the one the --log gives, else 0.
    #[arg(long, value_name = "N", value_parser = recording::limits::whole_u32(0, 3))]
    pub slot: Option<u32>,
    /// For px4 and ardupilot: the accelerometer's device id as the vehicle reports it (PX4's
    /// CAL_ACCn_ID, ArduPilot's INS_ACC_ID); default: the --log's; required by both.
    #[arg(long, value_name = "ID", value_parser = recording::limits::whole_u32(1, u32::MAX))]
    pub device_id: Option<u32>,
    /// For px4 and ardupilot: the gyro's device id (CAL_GYRO0_ID, INS_GYR_ID); without it no gyro
    /// offsets are written.
    #[arg(long, value_name = "ID", value_parser = recording::limits::whole_u32(1, u32::MAX))]
    pub gyro_device_id: Option<u32>,
    /// For px4: the vehicle's MAVLink system id (QGroundControl refuses a file from another one;
    /// default: 1).
    #[arg(long, value_parser = recording::limits::whole_u32(1, 255))]
    pub sysid: Option<u32>,
    /// For px4: the autopilot's MAVLink component id (default: 1).
    #[arg(long, value_parser = recording::limits::whole_u32(1, 255))]
    pub compid: Option<u32>,
    /// Write values outside the target's documented range (with a warning) instead of refusing.
    #[arg(long)]
    pub allow_out_of_range: bool,
    /// Write entries the calibration did not determine (marked UNDETERMINED) instead of refusing.
    #[arg(long)]
    pub allow_undetermined: bool,
}

impl ExportArgs {
    /// Refuses a format-specific option given with a format it does not act on (it would be
    /// ignored), naming the formats it is for.
    fn refuse_options_not_for_format(&self) -> Result<(), CliError> {
        use ExportFormat::{Ardupilot, FusionC, Kalibr, KalibrIntrinsics, Px4};
        let options: [(&str, bool, &[ExportFormat]); 12] = [
            ("--log", self.log.is_some(), &[Px4, Ardupilot]),
            ("--instance", self.instance.is_some(), &[Px4, Ardupilot]),
            ("--slot", self.slot.is_some(), &[Px4, Ardupilot]),
            ("--noise", self.noise.is_some(), &[Kalibr]),
            ("--rostopic", self.rostopic.is_some(), &[Kalibr]),
            (
                "--driver-scale",
                self.driver_scale.is_some(),
                &[Kalibr, KalibrIntrinsics, Px4, Ardupilot],
            ),
            ("--device-id", self.device_id.is_some(), &[Px4, Ardupilot]),
            (
                "--gyro-device-id",
                self.gyro_device_id.is_some(),
                &[Px4, Ardupilot],
            ),
            ("--sysid", self.sysid.is_some(), &[Px4]),
            ("--compid", self.compid.is_some(), &[Px4]),
            (
                "--allow-out-of-range",
                self.allow_out_of_range,
                &[Px4, Ardupilot],
            ),
            (
                "--allow-undetermined",
                self.allow_undetermined,
                &[KalibrIntrinsics, FusionC],
            ),
        ];
        let name = |f: &ExportFormat| {
            clap::ValueEnum::to_possible_value(f).map_or_else(String::new, |v| v.get_name().into())
        };
        for (flag, given, formats) in options {
            if given && !formats.contains(&self.format) {
                let names: Vec<String> = formats.iter().map(name).collect();
                return Err(CliError::Usage(format!(
                    "{flag} does not apply to --format {}: it is for {}; leave it out",
                    name(&self.format),
                    names.join(", ")
                )));
            }
        }
        Ok(())
    }
}

/// Runs `host export`.
pub(crate) fn run(a: &ExportArgs, quiet: bool) -> Result<(), CliError> {
    a.refuse_options_not_for_format()?;
    if a.instance.is_some() && a.log.is_none() {
        return Err(CliError::Usage(
            "--instance chooses an IMU of the vehicle's --log: give --log LOG (or leave \
             --instance out)"
                .into(),
        ));
    }
    let vehicle = match &a.log {
        Some(log) => Some(super::export_log::vehicle_log(a, log)?),
        None => None,
    };
    let calibration = match (&a.calibration, a.instance) {
        (None, Some(InstanceChoice::All)) => {
            let vehicle = vehicle.as_ref().ok_or_else(|| {
                CliError::Usage("--instance all calibrates each IMU of a --log: give --log".into())
            })?;
            return super::export_log::run_all(a, vehicle, quiet);
        }
        (Some(_), Some(InstanceChoice::All)) => return Err(CliError::Usage(
            "--instance all calibrates each IMU from the --log itself: leave out --calibration \
                 (or give --instance N for the IMU this calibration is of)"
                .into(),
        )),
        (None, _) => {
            return Err(CliError::Usage(
                "give --calibration FILE (or --log LOG --instance all to calibrate each IMU of a \
                 vehicle's log)"
                    .into(),
            ))
        }
        (Some(c), _) => c,
    };
    let unit = UnitFile::load(calibration)?;
    let invalid = |m| CliError::Unit(UnitFileError::Invalid(calibration.clone(), m));
    let cal = unit.to_calibration().map_err(invalid)?;
    let noise: Option<KalibrNoise> = match &a.noise {
        Some(p) => Some(outputs::noise::load_kalibr_noise(p).map_err(CliError::Noise)?),
        None => None,
    };
    let input = ExportInput {
        unit: &unit,
        cal,
        noise: noise.as_ref(),
        rostopic: a.rostopic.as_deref().unwrap_or("/imu0"),
        driver_scale_m_s2_per_out: a.driver_scale,
        options: ExportOptions {
            allow_out_of_range: a.allow_out_of_range,
            allow_undetermined: a.allow_undetermined,
            device_id: a.device_id,
            gyro_device_id: a.gyro_device_id,
            slot: a.slot.and_then(|n| u8::try_from(n).ok()),
            gyro_slot: None,
            // Within 1..=255 by their parsers.
            sysid: u8::try_from(a.sysid.unwrap_or(1)).unwrap_or(u8::MAX),
            compid: u8::try_from(a.compid.unwrap_or(1)).unwrap_or(u8::MAX),
            spelling: super::spelling::FLAGS,
        },
    };
    if a.format == ExportFormat::C {
        return write_c_package(a, &input, quiet);
    }
    let input = match &vehicle {
        Some(v) => super::export_log::with_log_ids(a, v, input)?,
        None => input,
    };
    let text = render(&input, a.format)?;
    write_text(a, &text, quiet)
}

/// Writes an export's text to `--out` (or stdout), its `# WARNING:` lines said on stderr too.
pub(super) fn write_text(a: &ExportArgs, text: &str, quiet: bool) -> Result<(), CliError> {
    // What the writer accepted only because it was told to: said where a person sees it too.
    let out = Output { json: false, quiet };
    for w in text.lines().filter_map(|l| l.strip_prefix("# WARNING: ")) {
        out.warn(w);
    }
    match &a.out {
        Some(p) => {
            write_atomic(p, text.as_bytes(), a.force).map_err(CliError::Written)?;
            out.line(format_args!("wrote {}", p.display()))?;
        }
        // The export itself is the result: nothing else goes to stdout, and -q does not silence it.
        None => crate::out!("{text}")?,
    }
    Ok(())
}

/// `--instance`: one IMU, or each.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(crate) enum InstanceChoice {
    /// The IMU of this instance.
    One(u8),
    /// Every IMU the log has.
    All,
}

fn instance_choice(text: &str) -> Result<InstanceChoice, String> {
    if text == "all" {
        return Ok(InstanceChoice::All);
    }
    text.parse::<u8>()
        .map(InstanceChoice::One)
        .map_err(|_| format!("'{text}' is not an IMU instance: give 0..255 or all"))
}

/// `c`: the self-contained C package (constants header, decoder, the device's per-sample
/// correction) into the `--out` directory, every file atomically; nothing is written when one would
/// replace an existing file without `--force`.
fn write_c_package(a: &ExportArgs, input: &ExportInput<'_>, quiet: bool) -> Result<(), CliError> {
    let dir = a.out.as_ref().ok_or_else(|| {
        CliError::Usage(
            "--format c writes a package of files (acal_calibration.h, the decoder and the \
             device's per-sample correction): give --out DIR"
                .into(),
        )
    })?;
    let files = outputs::export::c::write_package(dir, input, a.force)?;
    Output { json: false, quiet }.line(format_args!(
        "wrote {} in {}: build acal_blob.c and acal_device.c with your firmware (-ffp-contract=off); \
         example.c shows their use",
        files.join(", "),
        dir.display()
    ))?;
    Ok(())
}
