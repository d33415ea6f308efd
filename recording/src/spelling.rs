//! How the caller names the input options in its messages: the command line's flags
//! (`--acc-unit g`) or a library's keyword arguments (`acc_unit="g"`). An error that tells the user
//! which option to give carries the caller's [`Spelling`], so that one message serves both callers
//! and neither sees the other's names.

use core::fmt::Display;

/// An option that a message may ask the user to give or change.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum UserOption {
    /// The six column names of a text file.
    Columns,
    /// A text file's time column.
    TimeColumn,
    /// The time column's unit.
    TimeUnit,
    /// The sample rate of a text file without a time column.
    RateHz,
    /// The accelerometer's unit.
    AccUnit,
    /// Raw counts' zero force.
    AccOffset,
    /// The gyro's unit.
    GyroUnit,
    /// A gyro in counts: its nominal scale.
    GyroLsbPerDps,
    /// Which IMU of a ULog or DataFlash log.
    Instance,
    /// Which topic of an MCAP bag.
    Topic,
    /// Leave the gyro out of the session.
    NoGyro,
    /// The temperature to assume for a recording without one.
    TemperatureC,
    /// An export: the autopilot's accelerometer id.
    DeviceId,
    /// An export: the autopilot's gyro id.
    GyroDeviceId,
    /// An export: the driver's m/s² per output unit.
    DriverScale,
    /// An export: write undetermined entries, marked.
    AllowUndetermined,
    /// An export: write values outside the target's documented range, with a warning.
    AllowOutOfRange,
    /// An export: the noise analysis (`noise.json`).
    Noise,
    /// The estimator's method.
    Method,
    /// The lever arms' reference point.
    Reference,
    /// One lever arm for the three accelerometers of one package.
    SinglePackage,
    /// Samples kept in memory at once from a long log.
    MaxSamples,
    /// A text file's temperature column.
    TempColumn,
    /// Raw gyro counts' zero rate.
    GyroOffset,
    /// Fixed limits on a still window's spread instead of the noise floor's.
    StillThreshold,
    /// Lines before a text file's header.
    SkipLines,
}

impl UserOption {
    /// The option's name as a keyword argument (`acc_unit`).
    fn keyword(self) -> &'static str {
        match self {
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
        }
    }

    /// The option's command-line flag (`--acc-unit`).
    fn flag(self) -> &'static str {
        match self {
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
        }
    }

    /// Its value is text (a keyword argument then quotes it).
    fn is_text(self) -> bool {
        matches!(
            self,
            UserOption::TimeColumn
                | UserOption::TempColumn
                | UserOption::TimeUnit
                | UserOption::AccUnit
                | UserOption::GyroUnit
                | UserOption::Topic
                | UserOption::Noise
                | UserOption::Method
                | UserOption::Reference
        )
    }
}

/// How the caller spells its options (default: the command line's flags).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum Spelling {
    /// `--acc-unit g`.
    #[default]
    Flags,
    /// `acc_unit="g"`.
    Keywords,
}

impl Spelling {
    /// The option's name: `--acc-unit` or `acc_unit`.
    pub fn name(self, option: UserOption) -> &'static str {
        match self {
            Spelling::Flags => option.flag(),
            Spelling::Keywords => option.keyword(),
        }
    }

    /// The option with a value: `--acc-unit g` or `acc_unit="g"` (a number or placeholder
    /// unquoted: `rate_hz=HZ`).
    pub fn given(self, option: UserOption, value: impl Display) -> String {
        match self {
            Spelling::Flags => format!("{} {value}", option.flag()),
            Spelling::Keywords if option.is_text() => format!("{}=\"{value}\"", option.keyword()),
            Spelling::Keywords => format!("{}={value}", option.keyword()),
        }
    }

    /// The option with a value the user gave, quoted: `--acc-unit 'furlong'` or
    /// `acc_unit="furlong"`.
    pub fn quoted(self, option: UserOption, value: impl Display) -> String {
        match self {
            Spelling::Flags => format!("{} '{value}'", option.flag()),
            Spelling::Keywords => format!("{}=\"{value}\"", option.keyword()),
        }
    }

    /// The switch that turns something off: `--no-gyro` or `no_gyro=True`.
    pub fn switch(self, option: UserOption) -> String {
        match self {
            Spelling::Flags => option.flag().to_string(),
            Spelling::Keywords => format!("{}=True", option.keyword()),
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn each_caller_reads_its_own_names() {
        let (f, k) = (Spelling::Flags, Spelling::Keywords);
        assert_eq!(f.given(UserOption::AccUnit, "g"), "--acc-unit g");
        assert_eq!(k.given(UserOption::AccUnit, "g"), "acc_unit=\"g\"");
        assert_eq!(k.given(UserOption::RateHz, "HZ"), "rate_hz=HZ");
        assert_eq!(f.quoted(UserOption::GyroUnit, "x"), "--gyro-unit 'x'");
        assert_eq!(k.quoted(UserOption::GyroUnit, "x"), "gyro_unit=\"x\"");
        assert_eq!(k.switch(UserOption::NoGyro), "no_gyro=True");
        assert_eq!(f.name(UserOption::GyroLsbPerDps), "--gyro-lsb-per-dps");
    }
}
