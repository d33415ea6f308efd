//! `host export --log`: the device ids and slots from the vehicle's own log, and `--instance all`,
//! every IMU of the vehicle calibrated from the log and written into one parameter file.

use super::export::{write_text, ExportArgs, InstanceChoice};
use super::output::Output;
use super::CliError;
use app::autopilot::{calibrate_each_imu, VehicleLog};
use app::handheld::SegmentChoices;
use app::CalibrateOptions;
use outputs::export::params::{render_ardupilot_slots, render_px4_slots};
use outputs::export::{ExportFormat, ExportInput};
use recording::session::from_recording::SIX_FACE_PRIOR_DEG;
use recording::session::logs::{LogFormat, DEFAULT_MAX_SAMPLES};
use recording::session::segment::SegmentOptions;
use std::path::Path;

/// Reads the `--log`'s parameters, refusing a log of the other autopilot than `--format`.
pub(super) fn vehicle_log(a: &ExportArgs, log: &Path) -> Result<VehicleLog, CliError> {
    let v = VehicleLog::read(log)?;
    let (wanted, other) = match a.format {
        ExportFormat::Px4 => (LogFormat::Ulog, "ardupilot"),
        _ => (LogFormat::DataFlash, "px4"),
    };
    if v.format != wanted {
        return Err(CliError::Usage(format!(
            "{} is a {} log: its ids and slots are that autopilot's; export it with --format {other}",
            log.display(),
            v.format.name()
        )));
    }
    Ok(v)
}

/// `input` with the device ids and slots of the `--instance` the log gives, where the command line
/// does not give them.
pub(super) fn with_log_ids<'a>(
    a: &ExportArgs,
    v: &VehicleLog,
    mut input: ExportInput<'a>,
) -> Result<ExportInput<'a>, CliError> {
    let instance = match a.instance {
        Some(InstanceChoice::One(n)) => n,
        _ => 0,
    };
    let ids = v.ids(instance)?;
    let o = &mut input.options;
    if o.device_id.is_none() {
        o.device_id = Some(ids.accel.device_id);
    }
    if o.slot.is_none() {
        o.slot = Some(ids.accel.slot);
    }
    if let (None, Some(g)) = (o.gyro_device_id, ids.gyro) {
        o.gyro_device_id = Some(g.device_id);
        o.gyro_slot = Some(g.slot);
    }
    Ok(input)
}

/// `--instance all`: each IMU the log names, calibrated from the log, in one file.
pub(super) fn run_all(a: &ExportArgs, v: &VehicleLog, quiet: bool) -> Result<(), CliError> {
    for (flag, given) in [
        ("--device-id", a.device_id.is_some()),
        ("--gyro-device-id", a.gyro_device_id.is_some()),
        ("--slot", a.slot.is_some()),
    ] {
        if given {
            return Err(CliError::Usage(format!(
                "{flag} names one sensor, and --instance all writes each IMU with the id and slot \
                 its log gives: leave {flag} out, or export one IMU with --instance N"
            )));
        }
    }
    let instances = v.instances()?;
    let choices = SegmentChoices {
        segment: SegmentOptions::new(super::spelling::FLAGS),
        unit_id: None,
        gravity_m_s2: shared::STANDARD_GRAVITY_M_S2,
        fit_gyro: true,
        face_sigma_deg: SIX_FACE_PRIOR_DEG,
        faces: None,
    };
    let imus = calibrate_each_imu(
        v,
        &instances,
        &choices,
        &CalibrateOptions::new(super::spelling::FLAGS),
        DEFAULT_MAX_SAMPLES,
    )?;
    let out = Output { json: false, quiet };
    let mut inputs = Vec::new();
    for imu in &imus {
        for w in &imu.warnings {
            out.warn(format_args!("IMU instance {}: {w}", imu.ids.instance));
        }
        let invalid = |m| {
            CliError::Unit(estimator::unit_file::UnitFileError::Invalid(
                v.path.clone(),
                m,
            ))
        };
        let cal = imu.unit.to_calibration().map_err(invalid)?;
        let mut input = ExportInput {
            unit: &imu.unit,
            cal,
            noise: None,
            rostopic: "/imu0",
            driver_scale_m_s2_per_out: a.driver_scale,
            options: outputs::export::ExportOptions {
                allow_out_of_range: a.allow_out_of_range,
                allow_undetermined: a.allow_undetermined,
                sysid: u8::try_from(a.sysid.unwrap_or(1)).unwrap_or(u8::MAX),
                compid: u8::try_from(a.compid.unwrap_or(1)).unwrap_or(u8::MAX),
                ..outputs::export::ExportOptions::new(super::spelling::FLAGS)
            },
        };
        input.options.device_id = Some(imu.ids.accel.device_id);
        input.options.slot = Some(imu.ids.accel.slot);
        if let Some(g) = imu.ids.gyro {
            input.options.gyro_device_id = Some(g.device_id);
            input.options.gyro_slot = Some(g.slot);
        }
        inputs.push(input);
    }
    let text = match a.format {
        ExportFormat::Px4 => render_px4_slots(&inputs)?,
        _ => render_ardupilot_slots(&inputs)?,
    };
    write_text(a, &text, quiet)
}
