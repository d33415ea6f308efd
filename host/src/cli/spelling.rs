//! The command line's names of the options ([`UserOption`]): the crates below it name an option by
//! its meaning and receive [`FLAGS`] from here, so that the flags are written once, beside the
//! parser that reads them.

use recording::spelling::{Spelling, Syntax, UserOption};

/// The command line's spelling: `--acc-unit g`, `--acc-unit 'furlong'`, `--no-gyro`.
pub(crate) const FLAGS: Spelling = Spelling::new(flag, Syntax::Flags);

/// The option's flag (`--acc-unit`). An option without a flag does not compile.
fn flag(option: UserOption) -> &'static str {
    match option {
        UserOption::Columns => "--columns",
        UserOption::TimeColumn => "--time-column",
        UserOption::TimeUnit => "--time-unit",
        UserOption::RateHz => "--rate-hz",
        UserOption::AccUnit => "--acc-unit",
        UserOption::AccOffset => "--acc-offset",
        UserOption::GyroUnit => "--gyro-unit",
        UserOption::GyroLsbPerDps => "--gyro-lsb-per-dps",
        UserOption::Instance => "--instance",
        UserOption::Topic => "--topic",
        UserOption::NoGyro => "--no-gyro",
        UserOption::TemperatureC => "--temperature-c",
        UserOption::DeviceId => "--device-id",
        UserOption::GyroDeviceId => "--gyro-device-id",
        UserOption::DriverScale => "--driver-scale",
        UserOption::AllowUndetermined => "--allow-undetermined",
        UserOption::AllowOutOfRange => "--allow-out-of-range",
        UserOption::Noise => "--noise",
        UserOption::Method => "--method",
        UserOption::Reference => "--reference",
        UserOption::SinglePackage => "--single-package",
        UserOption::MaxSamples => "--max-samples",
        UserOption::TempColumn => "--temp-column",
        UserOption::GyroOffset => "--gyro-offset",
        UserOption::StillThreshold => "--still-threshold",
        UserOption::SkipLines => "--skip-lines",
        UserOption::StaticRun => "--static-run",
        UserOption::RateRun => "--rate-run",
        UserOption::Calibration => "--calibration",
        UserOption::BiasWalkFrom => "--bias-walk-from",
        UserOption::BiasWalk => "--bias-walk",
        UserOption::Unit => "--unit",
        UserOption::IgnoreUnitId => "--ignore-unit-id",
        UserOption::Input => "--input",
        UserOption::Out => "--out",
        UserOption::Force => "--force",
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn each_caller_reads_its_own_names() {
        assert_eq!(FLAGS.given(UserOption::AccUnit, "g"), "--acc-unit g");
        assert_eq!(FLAGS.given(UserOption::RateHz, "HZ"), "--rate-hz HZ");
        assert_eq!(FLAGS.quoted(UserOption::GyroUnit, "x"), "--gyro-unit 'x'");
        assert_eq!(FLAGS.switch(UserOption::NoGyro), "--no-gyro");
        assert_eq!(FLAGS.name(UserOption::GyroLsbPerDps), "--gyro-lsb-per-dps");
    }

    #[test]
    fn every_option_has_its_own_flag() {
        let names: Vec<&str> = UserOption::ALL.iter().map(|&o| FLAGS.name(o)).collect();
        for name in &names {
            assert!(name.starts_with("--") && !name.contains('_'), "{name}");
            assert_eq!(
                names.iter().filter(|n| *n == name).count(),
                1,
                "{name} twice"
            );
        }
    }
}
