//! The options a message may ask the user to give, by their meaning ([`UserOption`]), and the
//! caller's way of writing them ([`Spelling`]). The names themselves live at the edge that parses
//! them: the command line's flags (`--acc-unit g`) in the `host` crate, Python's keyword arguments
//! (`acc_unit="g"`) in the Python package. A crate below the edge never spells an option: a
//! message that tells the user which option to give carries the caller's [`Spelling`] and names a
//! [`UserOption`], so that one message serves both callers and neither sees the other's names.

use core::fmt::{self, Debug, Display};

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
    /// A report: the segment the static replay runs on.
    StaticRun,
    /// A report: the segment the rotating replay runs on.
    RateRun,
    /// Noise figures from a recording in m/s²: the calibration that converts its outputs.
    Calibration,
    /// The unit's bias random walks from its noise figures (`noise.json` or a unit file).
    BiasWalkFrom,
    /// The accelerometers' bias random walk, given as a number.
    BiasWalk,
    /// A unit file to simulate.
    Unit,
    /// Accept a calibration whose unit id differs from the recording's.
    IgnoreUnitId,
    /// The recording to read.
    Input,
    /// Where the results go.
    Out,
    /// Replace earlier results.
    Force,
}

impl UserOption {
    /// Every option, for the edges' tests (each has a name at every edge) and for comparing two
    /// spellings.
    pub const ALL: [UserOption; 36] = [
        UserOption::Columns,
        UserOption::TimeColumn,
        UserOption::TimeUnit,
        UserOption::RateHz,
        UserOption::AccUnit,
        UserOption::AccOffset,
        UserOption::GyroUnit,
        UserOption::GyroLsbPerDps,
        UserOption::Instance,
        UserOption::Topic,
        UserOption::NoGyro,
        UserOption::TemperatureC,
        UserOption::DeviceId,
        UserOption::GyroDeviceId,
        UserOption::DriverScale,
        UserOption::AllowUndetermined,
        UserOption::AllowOutOfRange,
        UserOption::Noise,
        UserOption::Method,
        UserOption::Reference,
        UserOption::SinglePackage,
        UserOption::MaxSamples,
        UserOption::TempColumn,
        UserOption::GyroOffset,
        UserOption::StillThreshold,
        UserOption::SkipLines,
        UserOption::StaticRun,
        UserOption::RateRun,
        UserOption::Calibration,
        UserOption::BiasWalkFrom,
        UserOption::BiasWalk,
        UserOption::Unit,
        UserOption::IgnoreUnitId,
        UserOption::Input,
        UserOption::Out,
        UserOption::Force,
    ];

    /// Its value is text (a keyword argument then quotes it).
    pub fn is_text(self) -> bool {
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

/// How an edge writes an option with its value: the syntax, apart from the names.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Syntax {
    /// A command line's: `--acc-unit g`, `--acc-unit 'furlong'`, a bare switch `--no-gyro`, a
    /// pair of values `MG,DEG_S`.
    Flags,
    /// A keyword call's: `acc_unit="g"` (text quoted, numbers not), `no_gyro=True`, a pair of
    /// values `(MG, DEG_S)`.
    Keywords,
}

/// How the caller spells its options: its names (the edge's table) and its [`Syntax`]. Only an
/// edge builds one; the crates below it receive it from their caller and never choose one, so a
/// message cannot name the other caller's option.
#[derive(Clone, Copy)]
pub struct Spelling {
    names: fn(UserOption) -> &'static str,
    syntax: Syntax,
}

impl Spelling {
    /// The caller's spelling: `names` gives each option's name (`--acc-unit`, `acc_unit`).
    pub const fn new(names: fn(UserOption) -> &'static str, syntax: Syntax) -> Spelling {
        Spelling { names, syntax }
    }

    /// How the caller writes an option with its value.
    pub fn syntax(self) -> Syntax {
        self.syntax
    }

    /// The option's name: `--acc-unit` or `acc_unit`.
    pub fn name(self, option: UserOption) -> &'static str {
        (self.names)(option)
    }

    /// The option with a value: `--acc-unit g` or `acc_unit="g"` (a number or placeholder
    /// unquoted: `rate_hz=HZ`).
    pub fn given(self, option: UserOption, value: impl Display) -> String {
        let name = self.name(option);
        match self.syntax {
            Syntax::Flags => format!("{name} {value}"),
            Syntax::Keywords if option.is_text() => format!("{name}=\"{value}\""),
            Syntax::Keywords => format!("{name}={value}"),
        }
    }

    /// The option with a value the user gave, quoted: `--acc-unit 'furlong'` or
    /// `acc_unit="furlong"`.
    pub fn quoted(self, option: UserOption, value: impl Display) -> String {
        let name = self.name(option);
        match self.syntax {
            Syntax::Flags => format!("{name} '{value}'"),
            Syntax::Keywords => format!("{name}=\"{value}\""),
        }
    }

    /// The switch that turns something on or off: `--no-gyro` or `no_gyro=True`.
    pub fn switch(self, option: UserOption) -> String {
        let name = self.name(option);
        match self.syntax {
            Syntax::Flags => name.to_string(),
            Syntax::Keywords => format!("{name}=True"),
        }
    }
}

/// The option with a value as `spelling` writes it, or by its meaning where no caller has spelled it
/// yet (`the Instance option (N)`): a reader called on its own makes its error before the caller's
/// spelling reaches it, and the caller names its options with the error's `spelled`.
pub fn given_by(spelling: Option<Spelling>, option: UserOption, value: impl Display) -> String {
    match spelling {
        Some(s) => s.given(option, value),
        None => format!("the {option:?} option ({value})"),
    }
}

/// Two spellings are the same when they write every option alike (a function's address is no
/// identity: the same table may sit at two addresses).
impl PartialEq for Spelling {
    fn eq(&self, other: &Spelling) -> bool {
        self.syntax == other.syntax
            && UserOption::ALL
                .iter()
                .all(|&o| self.name(o) == other.name(o))
    }
}

impl Eq for Spelling {}

/// Only for tests (feature `testkit`): the neutral test spelling
/// ([`SPELLING`](crate::testkit::SPELLING)), so that a test's options can be built with
/// `..Default::default()`. A build without the feature has no default: the caller spells.
#[cfg(any(test, feature = "testkit"))]
impl Default for Spelling {
    fn default() -> Spelling {
        crate::testkit::SPELLING
    }
}

impl Debug for Spelling {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.debug_struct("Spelling")
            .field("syntax", &self.syntax)
            .finish_non_exhaustive()
    }
}
