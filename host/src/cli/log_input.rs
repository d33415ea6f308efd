//! The options that say how to read a logger's file, shared by `host segment`, `host apply` and
//! `host noise` (flattened into each, so the three read a file the same way).

use super::CliError;
use app::log_input::{LogInput, LogInputError};
use clap::Args;
use recording::session::import::GyroUnit;
use recording::session::logs::{LogFormat, LogSource};

/// How to read a logger's file. A text file needs its units and its time; a PX4 ULog, an ArduPilot
/// DataFlash log or a ROS 2 bag (MCAP) states them, and is told by its content.
#[derive(Clone, Debug, Args)]
pub(crate) struct LogInputArgs {
    /// Text files: the accelerometer x,y,z and gyro x,y,z column names, in that order, or their
    /// indices (0-based) in a file with or without a header.
    #[arg(
        long,
        value_name = "AX,AY,AZ,GX,GY,GZ",
        default_value = "acc_x,acc_y,acc_z,gyr_x,gyr_y,gyr_z"
    )]
    pub columns: String,
    /// Text files: the column with the time stamps, by name or index (0-based), or `none` (then
    /// --rate-hz); their unit is detected, or --time-unit.
    #[arg(long, value_name = "NAME")]
    pub time_column: Option<String>,
    /// Text files: the time column's unit, s, ms, us or ns (default: detected from its median step
    /// and span).
    #[arg(long, value_name = "UNIT")]
    pub time_unit: Option<String>,
    /// The sample rate, Hz. Text files: when the file has no time column (a sample index is
    /// ignored). Binary logs: every sample re-timed at this rate from the first stamp (for a host's
    /// or driver's stamps, which come in bursts), with the rate the stamps imply said beside it.
    #[arg(long, value_name = "HZ", value_parser = recording::limits::real(recording::limits::MIN_LOGGER_RATE_HZ, recording::limits::MAX_SAMPLE_RATE_HZ))]
    pub rate_hz: Option<f64>,
    /// Text files: the accelerometer's unit, m/s2, g, LSB or V (kept as the calibration's output
    /// unit). Binary logs are in m/s².
    #[arg(long, value_name = "UNIT")]
    pub acc_unit: Option<String>,
    /// Text files, with --acc-unit LSB: the counts of zero force (an unsigned output's mid-scale,
    /// e.g. 32768), one value or one per axis (X,Y,Z), subtracted before anything else; the
    /// calibration's biases stay in the logger's own counts.
    #[arg(long, value_name = "N[,NY,NZ]", allow_negative_numbers = true)]
    pub acc_offset: Option<String>,
    /// Text files: the gyro's unit, deg/s, rad/s, or LSB (counts, with --gyro-lsb-per-dps).
    /// Binary logs are in rad/s.
    #[arg(long, value_name = "UNIT")]
    pub gyro_unit: Option<String>,
    /// Text files, with --gyro-unit LSB: the gyro's nominal scale, counts per °/s (from its data
    /// sheet, e.g. 16.4 or 131); the turns fit the true scale.
    #[arg(long, value_name = "X", value_parser = recording::limits::real(1e-3, 1e6))]
    pub gyro_lsb_per_dps: Option<f64>,
    /// Text files, with --gyro-unit LSB: the counts of zero rate (an unsigned output's mid-scale,
    /// e.g. 32768), one value or one per axis (X,Y,Z), subtracted before the scale; give the same
    /// to `apply` on the raw log.
    #[arg(long, value_name = "N[,NY,NZ]", allow_negative_numbers = true)]
    pub gyro_offset: Option<String>,
    /// Text files: the column with the unit's temperature, °C (a row whose temperature is not a
    /// number keeps its values; only its temperature is missing). Binary logs carry their own.
    #[arg(long, value_name = "NAME")]
    pub temp_column: Option<String>,
    /// Text files: lines before the header to skip (a logger's preamble; default: a header naming
    /// the columns asked for is looked for in the first lines, and a header-less file of numbers
    /// is read with --columns given by index, e.g. 0,1,2,3,4,5).
    #[arg(long, value_name = "N", value_parser = recording::limits::whole_u64(1, 1_000_000))]
    pub skip_lines: Option<u64>,
    /// PX4 ULog and ArduPilot DataFlash: which IMU of a vehicle with several (ULog's multi_id,
    /// DataFlash's I; default 0).
    #[arg(long, value_name = "N", value_parser = recording::limits::whole_u32(0, u8::MAX as u32))]
    pub instance: Option<u32>,
    /// ROS 2 MCAP: the sensor_msgs/msg/Imu topic (default: the bag's only one).
    #[arg(long, value_name = "NAME")]
    pub topic: Option<String>,
}

impl LogInputArgs {
    /// The flags as the application layer's typed options (named as flags in its messages).
    pub fn input(&self) -> LogInput {
        LogInput {
            columns: self.columns.split(',').map(str::to_string).collect(),
            time_column: self.time_column.clone(),
            time_unit: self.time_unit.clone(),
            rate_hz: self.rate_hz,
            acc_unit: self.acc_unit.clone(),
            // A value that is not a number reads as NaN, which the offset's check refuses (the
            // message then quotes the flag's text, below).
            acc_offset: self.acc_offset.as_ref().map(|text| {
                text.split(',')
                    .map(|x| x.trim().parse::<f64>().unwrap_or(f64::NAN))
                    .collect()
            }),
            gyro_unit: self.gyro_unit.clone(),
            gyro_lsb_per_dps: self.gyro_lsb_per_dps,
            gyro_offset: self.gyro_offset.as_ref().map(|text| {
                text.split(',')
                    .map(|x| x.trim().parse::<f64>().unwrap_or(f64::NAN))
                    .collect()
            }),
            temp_column: self.temp_column.clone(),
            skip_lines: self.skip_lines,
            // Within 0..=255 by its value parser (ULog's multi_id and DataFlash's I are bytes).
            instance: self.instance.map(|i| u8::try_from(i).unwrap_or(u8::MAX)),
            topic: self.topic.clone(),
            spelling: super::spelling::FLAGS,
        }
    }

    /// The text-file options given, by their flags (a text file's columns, time and units: what a
    /// binary log or a session directory states itself).
    fn text_options_given(&self) -> Vec<&'static str> {
        let default_columns = self.columns == recording::session::import::DEFAULT_COLUMNS.join(",");
        [
            ("--columns", !default_columns),
            ("--time-column", self.time_column.is_some()),
            ("--time-unit", self.time_unit.is_some()),
            ("--rate-hz", self.rate_hz.is_some()),
            ("--acc-unit", self.acc_unit.is_some()),
            ("--acc-offset", self.acc_offset.is_some()),
            ("--gyro-unit", self.gyro_unit.is_some()),
            ("--gyro-lsb-per-dps", self.gyro_lsb_per_dps.is_some()),
            ("--gyro-offset", self.gyro_offset.is_some()),
            ("--temp-column", self.temp_column.is_some()),
            ("--skip-lines", self.skip_lines.is_some()),
        ]
        .into_iter()
        .filter_map(|(flag, given)| given.then_some(flag))
        .collect()
    }

    /// What to read from `input`: the text options when any is given (checked whole by the
    /// application layer), the instance and topic. Text options on a binary log are refused by
    /// name before they are checked as a text file's (a log that states its units needs none).
    pub fn source(&self, input: &std::path::Path) -> Result<LogSource, CliError> {
        // A binary log takes --rate-hz alone: it re-times the samples (the stamps a host's
        // driver wrote in bursts, say), and what the stamps imply is said beside it.
        let mut text = self.text_options_given();
        if text == ["--rate-hz"] {
            text.clear();
        }
        let format = log_format(input);
        if let Some(format) = format {
            self.refuse_for_format(input, format)?;
        }
        if !text.is_empty() {
            if let Some(format) = format.filter(|f| *f != LogFormat::Text) {
                return Err(CliError::Usage(format!(
                    "{} is in the {} format, which states its columns, time and units: {} {} not \
                     apply to it; leave {} out",
                    input.display(),
                    format.name(),
                    text.join(", "),
                    if text.len() == 1 { "does" } else { "do" },
                    if text.len() == 1 { "it" } else { "them" },
                )));
            }
        }
        self.input()
            .source()
            .map_err(|e| match (e, &self.acc_offset) {
                // The offset as the command line wrote it, not as it was read.
                (LogInputError::AccOffsetValues { .. }, Some(text)) => CliError::Usage(format!(
                    "--acc-offset {text}: give the counts of zero force, one number (e.g. 32768) \
                     or three (X,Y,Z)"
                )),
                (LogInputError::GyroOffsetValues { .. }, _) => CliError::Usage(format!(
                    "--gyro-offset {}: give the counts of zero rate, one number (e.g. 32768) or \
                     three (X,Y,Z)",
                    self.gyro_offset.as_deref().unwrap_or_default()
                )),
                (e, _) => CliError::LogInput(e),
            })
    }

    /// Refuses `--instance` and `--topic` where the format has no such thing (a usage error, found
    /// before the file is read).
    fn refuse_for_format(
        &self,
        input: &std::path::Path,
        format: LogFormat,
    ) -> Result<(), CliError> {
        let instance = matches!(format, LogFormat::Ulog | LogFormat::DataFlash);
        let topic = format == LogFormat::Mcap;
        let wrong = [
            ("--instance", self.instance.is_some() && !instance),
            ("--topic", self.topic.is_some() && !topic),
        ]
        .into_iter()
        .find_map(|(flag, wrong)| wrong.then_some(flag));
        match wrong {
            Some(flag) => Err(CliError::Usage(format!(
                "{} is in the {} format: {flag} does not apply to it (--instance is for PX4 ULog \
                 and ArduPilot DataFlash, --topic for ROS 2 MCAP); leave it out",
                input.display(),
                format.name()
            ))),
            None => Ok(()),
        }
    }

    /// Refuses these options for an input that is a session directory (they would be ignored),
    /// naming the ones given.
    pub fn refuse_for_session(&self, input: &std::path::Path) -> Result<(), CliError> {
        let mut given = self.text_options_given();
        given.extend(self.instance.map(|_| "--instance"));
        given.extend(self.topic.as_ref().map(|_| "--topic"));
        if !given.is_empty() {
            return Err(CliError::Usage(format!(
                "{} is a session directory, whose plan.toml states its units and time: the \
                 logger's file options do not apply ({}); leave them out",
                input.display(),
                given.join(", ")
            )));
        }
        Ok(())
    }

    /// The gyro unit of the input as the user named it (binary logs: rad/s).
    pub fn gyro_unit(&self) -> GyroUnit {
        self.gyro_unit
            .as_deref()
            .and_then(GyroUnit::parse)
            .unwrap_or(GyroUnit::RadPerS)
    }

    /// The gyro unit's symbol as the user named it: "LSB" for counts, else [`Self::gyro_unit`]'s.
    pub fn gyro_unit_symbol(&self) -> &'static str {
        match self.gyro_lsb_per_dps {
            Some(_) => "LSB",
            None => self.gyro_unit().symbol(),
        }
    }
}

/// The log format `input` starts with (`None`: unreadable here; the reader then says why).
fn log_format(input: &std::path::Path) -> Option<LogFormat> {
    use std::io::Read;
    let mut head = [0u8; 64];
    let file = std::fs::File::open(input).ok()?;
    let n = file.take(head.len() as u64).read(&mut head).ok()?;
    Some(LogFormat::detect(&head[..n]))
}
