//! Python's names of the options ([`UserOption`]): its keyword arguments. The crates below name an
//! option by its meaning and receive [`KEYWORDS`] from here, so that a refusal names the argument
//! the Python caller gives, never a command-line flag.

use recording::spelling::{Spelling, Syntax, UserOption};

/// Python's spelling: `acc_unit="g"`, `rate_hz=HZ`, `no_gyro=True`.
pub(crate) const KEYWORDS: Spelling = Spelling::new(keyword, Syntax::Keywords);

/// The option's keyword argument (`acc_unit`). An option without one does not compile.
fn keyword(option: UserOption) -> &'static str {
    match option {
        UserOption::Columns => "columns",
        UserOption::TimeColumn => "time_column",
        UserOption::TimeUnit => "time_unit",
        UserOption::RateHz => "rate_hz",
        UserOption::AccUnit => "acc_unit",
        UserOption::AccOffset => "acc_offset",
        UserOption::GyroUnit => "gyro_unit",
        UserOption::GyroLsbPerDps => "gyro_lsb_per_dps",
        UserOption::Instance => "instance",
        UserOption::Topic => "topic",
        UserOption::NoGyro => "no_gyro",
        UserOption::TemperatureC => "temp_c",
        UserOption::DeviceId => "device_id",
        UserOption::GyroDeviceId => "gyro_device_id",
        UserOption::DriverScale => "driver_scale",
        UserOption::AllowUndetermined => "allow_undetermined",
        UserOption::AllowOutOfRange => "allow_out_of_range",
        UserOption::Noise => "noise",
        UserOption::Method => "method",
        UserOption::Reference => "reference",
        UserOption::SinglePackage => "single_package",
        UserOption::MaxSamples => "max_samples",
        UserOption::TempColumn => "temp_column",
        UserOption::GyroOffset => "gyro_offset",
        UserOption::StillThreshold => "still_threshold",
        UserOption::SkipLines => "skip_lines",
        UserOption::StaticRun => "static_run",
        UserOption::RateRun => "rate_run",
        UserOption::Calibration => "calibration",
        UserOption::BiasWalkFrom => "bias_walk_from",
        UserOption::BiasWalk => "bias_walk",
        UserOption::Unit => "unit",
        UserOption::IgnoreUnitId => "ignore_unit_id",
        UserOption::Input => "input",
        UserOption::Out => "out",
        UserOption::Force => "force",
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn each_caller_reads_its_own_names() {
        assert_eq!(KEYWORDS.given(UserOption::AccUnit, "g"), "acc_unit=\"g\"");
        assert_eq!(KEYWORDS.given(UserOption::RateHz, "HZ"), "rate_hz=HZ");
        assert_eq!(
            KEYWORDS.quoted(UserOption::GyroUnit, "x"),
            "gyro_unit=\"x\""
        );
        assert_eq!(KEYWORDS.switch(UserOption::NoGyro), "no_gyro=True");
        assert_eq!(KEYWORDS.name(UserOption::GyroLsbPerDps), "gyro_lsb_per_dps");
    }

    #[test]
    fn every_option_has_its_own_keyword() {
        let names: Vec<&str> = UserOption::ALL.iter().map(|&o| KEYWORDS.name(o)).collect();
        for name in &names {
            assert!(!name.contains('-') && !name.is_empty(), "{name}");
            assert_eq!(
                names.iter().filter(|n| *n == name).count(),
                1,
                "{name} twice"
            );
        }
    }
}
