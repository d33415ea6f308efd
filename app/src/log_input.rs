//! How to read a logger's file, as typed options ([`LogInput`]): the columns, the time, the units,
//! raw counts' offset and scale, the IMU of a binary log. The command line's flags and Python's
//! keyword arguments both become a `LogInput`; its checks name the options as the caller spells
//! them ([`Spelling`]).

use recording::session::import::{
    gyro_unit_and_scale, parse_acc_unit, GyroUnit, GyroUnitFault, ImportOptions, TimeSource,
    TimeUnit, DEFAULT_COLUMNS,
};
use recording::session::logs::LogSource;
use recording::spelling::{Spelling, UserOption};
use shared::OutputUnit;

/// How to read a logger's file. A text file needs its units and its time; a PX4 ULog, an ArduPilot
/// DataFlash log or a ROS 2 bag (MCAP) states them.
#[derive(Clone, Debug, PartialEq)]
pub struct LogInput {
    /// Text files: the accelerometer x, y, z and gyro x, y, z column names, in that order.
    pub columns: Vec<String>,
    /// Text files: the column with the time stamps (else `rate_hz`).
    pub time_column: Option<String>,
    /// Text files: the time column's unit, s, ms, us or ns (default: detected).
    pub time_unit: Option<String>,
    /// Text files without a time column: the sample rate, Hz.
    pub rate_hz: Option<f64>,
    /// Text files: the accelerometer's unit, m/s2, g, LSB or V.
    pub acc_unit: Option<String>,
    /// Text files in counts: the counts of zero force, one value or one per axis.
    pub acc_offset: Option<Vec<f64>>,
    /// Text files: the gyro's unit, deg/s, rad/s or LSB (with `gyro_lsb_per_dps`).
    pub gyro_unit: Option<String>,
    /// A gyro in counts: its nominal scale, counts per °/s.
    pub gyro_lsb_per_dps: Option<f64>,
    /// A gyro in counts: the counts of zero rate, one value or one per axis.
    pub gyro_offset: Option<Vec<f64>>,
    /// Text files: the column with the unit's temperature, °C.
    pub temp_column: Option<String>,
    /// Text files: lines before the header to skip (default: a preamble is found).
    pub skip_lines: Option<u64>,
    /// ULog and DataFlash: which IMU (default 0).
    pub instance: Option<u8>,
    /// MCAP: the Imu topic (default: the bag's only one).
    pub topic: Option<String>,
    /// How the caller names these options in messages.
    pub spelling: Spelling,
}

impl LogInput {
    /// Nothing given (the default columns, a binary log's own units), the messages spelled as the
    /// caller spells its options.
    pub fn new(spelling: Spelling) -> LogInput {
        LogInput {
            columns: DEFAULT_COLUMNS.map(String::from).to_vec(),
            time_column: None,
            time_unit: None,
            rate_hz: None,
            acc_unit: None,
            acc_offset: None,
            gyro_unit: None,
            gyro_lsb_per_dps: None,
            gyro_offset: None,
            temp_column: None,
            skip_lines: None,
            instance: None,
            topic: None,
            spelling,
        }
    }
}

/// Why the options cannot read a file; each names the options as the caller spells them.
#[derive(Debug, thiserror::Error)]
pub enum LogInputError {
    /// Not six column names.
    #[error("{} needs six names: acc x,y,z then gyro x,y,z", .0.name(UserOption::Columns))]
    ColumnCount(Spelling),
    /// An empty column name.
    #[error(
        "{} has an empty name: give six names, acc x,y,z then gyro x,y,z",
        .0.name(UserOption::Columns)
    )]
    EmptyColumn(Spelling),
    /// One column named for two quantities.
    #[error(
        "column '{name}' is named twice in {}/{}: each of acc x,y,z, gyro x,y,z and the time must \
         be its own column",
        .spelling.name(UserOption::Columns),
        .spelling.name(UserOption::TimeColumn)
    )]
    ColumnTwice {
        /// The name.
        name: String,
        /// The caller's names of the options.
        spelling: Spelling,
    },
    /// Neither or both of a time column and a rate.
    #[error(
        "a text file needs exactly one of {} or {}",
        .0.given(UserOption::TimeColumn, "NAME"),
        .0.given(UserOption::RateHz, "HZ")
    )]
    TimeSource(Spelling),
    /// A time unit that is none of s, ms, us, ns.
    #[error("{}: use s, ms, us or ns", .spelling.given(UserOption::TimeUnit, .given))]
    TimeUnit {
        /// The unit given.
        given: String,
        /// The caller's names of the options.
        spelling: Spelling,
    },
    /// A time unit with a rate.
    #[error(
        "{} applies to {}, not to {}",
        .0.name(UserOption::TimeUnit),
        .0.name(UserOption::TimeColumn),
        .0.name(UserOption::RateHz)
    )]
    TimeUnitWithRate(Spelling),
    /// No or an unknown accelerometer unit.
    #[error(
        "{}: a text file needs its accelerometer unit, m/s2, g, LSB or V",
        .spelling.quoted(UserOption::AccUnit, .given)
    )]
    AccUnit {
        /// The unit given ("" for none).
        given: String,
        /// The caller's names of the options.
        spelling: Spelling,
    },
    /// An offset for an accelerometer not in counts.
    #[error(
        "{} is for raw counts: give {}, or drop {} (the unit is {unit})",
        .spelling.name(UserOption::AccOffset),
        .spelling.given(UserOption::AccUnit, "LSB"),
        .spelling.name(UserOption::AccOffset)
    )]
    AccOffsetNotCounts {
        /// The accelerometer unit given.
        unit: String,
        /// The caller's names of the options.
        spelling: Spelling,
    },
    /// An offset of neither one nor three finite values.
    #[error(
        "{}: give the counts of zero force, one number (e.g. 32768) or three (X,Y,Z)",
        .spelling.given(UserOption::AccOffset, format!("{:?}", .given))
    )]
    AccOffsetValues {
        /// The values given.
        given: Vec<f64>,
        /// The caller's names of the options.
        spelling: Spelling,
    },
    /// A gyro offset for a gyro not in counts.
    #[error(
        "{} is for raw counts: give {} with {}, or drop {} (the unit is {unit})",
        .spelling.name(UserOption::GyroOffset),
        .spelling.given(UserOption::GyroUnit, "LSB"),
        .spelling.name(UserOption::GyroLsbPerDps),
        .spelling.name(UserOption::GyroOffset)
    )]
    GyroOffsetNotCounts {
        /// The gyro unit given.
        unit: String,
        /// The caller's names of the options.
        spelling: Spelling,
    },
    /// A gyro offset of neither one nor three finite values.
    #[error(
        "{}: give the counts of zero rate, one number (e.g. 32768) or three (X,Y,Z)",
        .spelling.given(UserOption::GyroOffset, format!("{:?}", .given))
    )]
    GyroOffsetValues {
        /// The values given.
        given: Vec<f64>,
        /// The caller's names of the options.
        spelling: Spelling,
    },
    /// A gyro in counts without its scale.
    #[error(
        "{} needs the gyro's nominal scale: add {} (counts per °/s from its data sheet, e.g. 16.4 \
         at ±2000 °/s, 131 at ±250 °/s); the turns then fit the true scale",
        .0.given(UserOption::GyroUnit, "LSB"),
        .0.given(UserOption::GyroLsbPerDps, "X")
    )]
    GyroNeedsScale(Spelling),
    /// A scale for a gyro not in counts.
    #[error(
        "{} is for a gyro in counts: give {} (not '{given}')",
        .spelling.name(UserOption::GyroLsbPerDps),
        .spelling.given(UserOption::GyroUnit, "LSB")
    )]
    GyroScaleNotCounts {
        /// The gyro unit given.
        given: String,
        /// The caller's names of the options.
        spelling: Spelling,
    },
    /// No or an unknown gyro unit.
    #[error(
        "{}: a text file needs its gyro unit, deg/s, rad/s or LSB (with {})",
        .spelling.quoted(UserOption::GyroUnit, .given),
        .spelling.name(UserOption::GyroLsbPerDps)
    )]
    GyroUnit {
        /// The unit given ("" for none).
        given: String,
        /// The caller's names of the options.
        spelling: Spelling,
    },
}

impl LogInput {
    /// What to read: the text options when any is given (checked whole), the instance and topic.
    pub fn source(&self) -> Result<LogSource, LogInputError> {
        let text_given = self.acc_unit.is_some()
            || self.gyro_unit.is_some()
            || self.time_column.is_some()
            || self.time_unit.is_some()
            || self.acc_offset.is_some()
            || self.gyro_lsb_per_dps.is_some()
            || self.gyro_offset.is_some()
            || self.temp_column.is_some()
            || self.skip_lines.is_some();
        // The rate alone is a binary log's re-timing; with the text options, a text file's time.
        Ok(LogSource {
            text: if text_given {
                Some(self.import_options()?)
            } else {
                None
            },
            instance: self.instance,
            topic: self.topic.clone(),
            spelling: self.spelling,
            rate_hz: if text_given { None } else { self.rate_hz },
        })
    }

    /// The text reader's options: six distinct column names, one time source, the units.
    pub fn import_options(&self) -> Result<ImportOptions, LogInputError> {
        let sp = self.spelling;
        let columns: [String; 6] = self
            .columns
            .iter()
            .map(|s| s.trim().to_string())
            .collect::<Vec<_>>()
            .try_into()
            .map_err(|_| LogInputError::ColumnCount(sp))?;
        // The reader matches names case-insensitively: a name given twice would read one column
        // twice and make the fit singular, far from the cause.
        let mut seen: Vec<&str> = columns.iter().map(String::as_str).collect();
        // "none": the file has no time column (its rate is given).
        let time_column = self
            .time_column
            .as_deref()
            .filter(|c| !c.trim().eq_ignore_ascii_case("none"));
        seen.extend(time_column);
        seen.extend(self.temp_column.as_deref().map(str::trim));
        for (k, name) in seen.iter().enumerate() {
            if name.is_empty() {
                return Err(LogInputError::EmptyColumn(sp));
            }
            if let Some(first) = seen[..k].iter().find(|n| n.eq_ignore_ascii_case(name)) {
                return Err(LogInputError::ColumnTwice {
                    name: first.to_string(),
                    spelling: sp,
                });
            }
        }
        let time = match (time_column, self.rate_hz) {
            (Some(c), None) => TimeSource::Column(c.to_string()),
            (None, Some(hz)) => TimeSource::RateHz(hz),
            _ => return Err(LogInputError::TimeSource(sp)),
        };
        let time_unit = match (&self.time_unit, &time) {
            (None, _) => None,
            (Some(u), TimeSource::Column(_)) => {
                Some(TimeUnit::parse(u).ok_or_else(|| LogInputError::TimeUnit {
                    given: u.clone(),
                    spelling: sp,
                })?)
            }
            (Some(_), TimeSource::RateHz(_)) => return Err(LogInputError::TimeUnitWithRate(sp)),
        };
        let acc = self.acc_unit.as_deref().unwrap_or("");
        let acc_unit = parse_acc_unit(acc).ok_or_else(|| LogInputError::AccUnit {
            given: acc.to_string(),
            spelling: sp,
        })?;
        let (gyro_unit, gyro_lsb_per_dps) = self.text_gyro_unit()?;
        Ok(ImportOptions {
            columns,
            time,
            acc_unit,
            gyro_unit,
            time_unit,
            acc_offset: self.text_acc_offset(acc_unit)?,
            gyro_lsb_per_dps,
            gyro_offset: self.text_gyro_offset(gyro_lsb_per_dps.is_some())?,
            temp_column: self.temp_column.as_ref().map(|c| c.trim().to_string()),
            skip_lines: self.skip_lines.unwrap_or(0),
            spelling: sp,
        })
    }

    /// The offset: one value for every axis or three, for an accelerometer in counts only.
    fn text_acc_offset(&self, unit: OutputUnit) -> Result<[f64; 3], LogInputError> {
        let Some(v) = &self.acc_offset else {
            return Ok([0.0; 3]);
        };
        if unit != OutputUnit::Lsb {
            return Err(LogInputError::AccOffsetNotCounts {
                unit: self.acc_unit.clone().unwrap_or_default(),
                spelling: self.spelling,
            });
        }
        per_axis(v).ok_or_else(|| LogInputError::AccOffsetValues {
            given: v.clone(),
            spelling: self.spelling,
        })
    }

    /// The gyro's offset: one value for every axis or three, for a gyro in counts only.
    fn text_gyro_offset(&self, counts: bool) -> Result<[f64; 3], LogInputError> {
        let Some(v) = &self.gyro_offset else {
            return Ok([0.0; 3]);
        };
        if !counts {
            return Err(LogInputError::GyroOffsetNotCounts {
                unit: self.gyro_unit.clone().unwrap_or_default(),
                spelling: self.spelling,
            });
        }
        per_axis(v).ok_or_else(|| LogInputError::GyroOffsetValues {
            given: v.clone(),
            spelling: self.spelling,
        })
    }

    /// The gyro's unit and scale: counts need their nominal scale, and only counts take one.
    fn text_gyro_unit(&self) -> Result<(GyroUnit, Option<f64>), LogInputError> {
        let sp = self.spelling;
        let gyro = self.gyro_unit.as_deref().unwrap_or("");
        gyro_unit_and_scale(gyro, self.gyro_lsb_per_dps).map_err(|fault| match fault {
            GyroUnitFault::NeedsScale => LogInputError::GyroNeedsScale(sp),
            GyroUnitFault::ScaleNotCounts => LogInputError::GyroScaleNotCounts {
                given: gyro.to_string(),
                spelling: sp,
            },
            GyroUnitFault::Unknown => LogInputError::GyroUnit {
                given: gyro.to_string(),
                spelling: sp,
            },
        })
    }
}

/// One finite value for every axis, or three: an offset as given.
fn per_axis(v: &[f64]) -> Option<[f64; 3]> {
    match *v {
        _ if v.iter().any(|x| !x.is_finite()) => None,
        [n] => Some([n; 3]),
        [x, y, z] => Some([x, y, z]),
        _ => None,
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use recording::testkit::{KEYWORD_SPELLING, SPELLING};

    fn text(spelling: Spelling) -> LogInput {
        LogInput {
            rate_hz: Some(100.0),
            acc_unit: Some("g".into()),
            gyro_unit: Some("deg/s".into()),
            spelling,
            ..LogInput::new(SPELLING)
        }
    }

    /// One check, two callers: each reads its own option names, never the other's.
    #[test]
    fn a_refusal_names_the_callers_options() {
        let e = |i: LogInput| i.source().unwrap_err().to_string();
        let bad_unit = |sp| LogInput {
            acc_unit: Some("furlong".into()),
            ..text(sp)
        };
        assert_eq!(
            e(bad_unit(SPELLING)),
            "<AccUnit> 'furlong': a text file needs its accelerometer unit, m/s2, g, LSB or V"
        );
        assert_eq!(
            e(bad_unit(KEYWORD_SPELLING)),
            "<AccUnit>=\"furlong\": a text file needs its accelerometer unit, m/s2, g, LSB or V"
        );
        let counts = |sp| LogInput {
            gyro_unit: Some("LSB".into()),
            ..text(sp)
        };
        let m = e(counts(KEYWORD_SPELLING));
        assert!(m.starts_with("<GyroUnit>=\"LSB\" needs") && m.contains("<GyroLsbPerDps>=X"));
        assert!(!m.contains("--"), "{m}");
        let offset = |sp| LogInput {
            acc_unit: Some("LSB".into()),
            acc_offset: Some(vec![1.0, 2.0]),
            ..text(sp)
        };
        assert!(e(offset(KEYWORD_SPELLING)).starts_with("<AccOffset>=[1.0, 2.0]: give"));
        let both = LogInput {
            time_column: Some("t".into()),
            ..text(KEYWORD_SPELLING)
        };
        assert_eq!(
            e(both),
            "a text file needs exactly one of <TimeColumn>=\"NAME\" or <RateHz>=HZ"
        );
    }

    /// With the flags' spelling every refusal is word for word the command line's message from
    /// before the options became typed (the texts below are those messages).
    #[test]
    fn each_refusal_names_its_options_by_the_callers_spelling() {
        let base = || text(SPELLING);
        let cases: Vec<(LogInput, &str)> = vec![
            (
                LogInput {
                    columns: vec!["a".into(), "b".into()],
                    ..base()
                },
                "<Columns> needs six names: acc x,y,z then gyro x,y,z",
            ),
            (
                LogInput {
                    columns: ["a", "b", "", "d", "e", "f"].map(String::from).to_vec(),
                    ..base()
                },
                "<Columns> has an empty name: give six names, acc x,y,z then gyro x,y,z",
            ),
            (
                LogInput {
                    columns: ["a", "b", "c", "d", "e", "A"].map(String::from).to_vec(),
                    ..base()
                },
                "column 'a' is named twice in <Columns>/<TimeColumn>: each of acc x,y,z, gyro \
                 x,y,z and the time must be its own column",
            ),
            (
                LogInput {
                    rate_hz: None,
                    ..base()
                },
                "a text file needs exactly one of <TimeColumn> NAME or <RateHz> HZ",
            ),
            (
                LogInput {
                    rate_hz: None,
                    time_column: Some("t".into()),
                    time_unit: Some("h".into()),
                    ..base()
                },
                "<TimeUnit> h: use s, ms, us or ns",
            ),
            (
                LogInput {
                    time_unit: Some("s".into()),
                    ..base()
                },
                "<TimeUnit> applies to <TimeColumn>, not to <RateHz>",
            ),
            (
                LogInput {
                    acc_offset: Some(vec![1.0]),
                    ..base()
                },
                "<AccOffset> is for raw counts: give <AccUnit> LSB, or drop <AccOffset> (the \
                 unit is g)",
            ),
            (
                LogInput {
                    gyro_unit: Some("LSB".into()),
                    ..base()
                },
                "<GyroUnit> LSB needs the gyro's nominal scale: add <GyroLsbPerDps> X (counts \
                 per °/s from its data sheet, e.g. 16.4 at ±2000 °/s, 131 at ±250 °/s); the turns \
                 then fit the true scale",
            ),
            (
                LogInput {
                    gyro_lsb_per_dps: Some(16.4),
                    ..base()
                },
                "<GyroLsbPerDps> is for a gyro in counts: give <GyroUnit> LSB (not 'deg/s')",
            ),
            (
                LogInput {
                    gyro_unit: Some("x".into()),
                    ..base()
                },
                "<GyroUnit> 'x': a text file needs its gyro unit, deg/s, rad/s or LSB (with \
                 <GyroLsbPerDps>)",
            ),
        ];
        for (input, want) in cases {
            assert_eq!(input.source().unwrap_err().to_string(), want);
        }
    }

    #[test]
    fn one_or_three_finite_offsets_are_taken() {
        let with = |v: Vec<f64>| {
            LogInput {
                acc_unit: Some("LSB".into()),
                acc_offset: Some(v),
                ..text(SPELLING)
            }
            .import_options()
            .map(|o| o.acc_offset)
        };
        assert_eq!(with(vec![5.0]).unwrap(), [5.0; 3]);
        assert_eq!(with(vec![1.0, 2.0, 3.0]).unwrap(), [1.0, 2.0, 3.0]);
        assert!(with(vec![f64::NAN]).is_err());
        assert!(with(vec![]).is_err());
    }

    /// A gyro's offset is for counts only, one or three finite values, named as the caller
    /// spells it.
    #[test]
    fn a_gyro_offset_is_for_counts_one_or_three_values() {
        let with = |unit: &str, v: Vec<f64>, spelling| {
            LogInput {
                gyro_unit: Some(unit.into()),
                gyro_lsb_per_dps: (unit == "LSB").then_some(16.4),
                gyro_offset: Some(v),
                ..text(spelling)
            }
            .import_options()
            .map(|o| o.gyro_offset)
        };
        assert_eq!(with("LSB", vec![32768.0], SPELLING).unwrap(), [32768.0; 3]);
        assert_eq!(
            with("LSB", vec![1.0, 2.0, 3.0], SPELLING).unwrap(),
            [1.0, 2.0, 3.0]
        );
        let e = with("LSB", vec![1.0, 2.0], KEYWORD_SPELLING).unwrap_err();
        assert!(
            e.to_string().starts_with("<GyroOffset>=[1.0, 2.0]: give"),
            "{e}"
        );
        let e = with("deg/s", vec![32768.0], SPELLING).unwrap_err();
        assert!(
            e.to_string()
                .starts_with("<GyroOffset> is for raw counts: give <GyroUnit> LSB"),
            "{e}"
        );
    }
}
