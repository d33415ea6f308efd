//! Why a log cannot be read ([`LogError`]), and why its IMU cannot ([`ImuError`]); each says what
//! to do.

use super::{dataflash, mcap, ulog, LogFormat, LogSource};
use crate::session::import::{ImportError, TimeSource, TimeUnit};
use crate::spelling::{Spelling, UserOption};
use std::path::PathBuf;

/// Why a log cannot be read; each says what to do.
#[derive(Debug, thiserror::Error)]
pub enum LogError {
    /// Not readable.
    #[error("cannot read {path}")]
    Io {
        /// The file.
        path: PathBuf,
        /// The cause.
        source: std::io::Error,
    },
    /// A text file's problem.
    #[error(transparent)]
    Text(#[from] ImportError),
    /// Binary, but none of the formats read.
    #[error(
        "{path} is not a format this tool reads (it starts with bytes {head}): give a text file \
         (CSV), a PX4 ULog, an ArduPilot DataFlash .bin or a ROS 2 bag in MCAP{advice}"
    )]
    UnknownFormat {
        /// The file.
        path: PathBuf,
        /// Its first bytes, hex.
        head: String,
        /// What it looks like, and the conversion that makes it one of them.
        advice: ForeignFormat,
    },
    /// A text file without its units and columns.
    #[error(
        "{} is a text file: give its units ({} and {}) and its time ({} or {})",
        .0.display(),
        .1.name(UserOption::AccUnit),
        .1.name(UserOption::GyroUnit),
        .1.given(UserOption::TimeColumn, "NAME"),
        .1.given(UserOption::RateHz, "HZ")
    )]
    TextNeedsOptions(PathBuf, Spelling),
    /// Text options on a binary log, which states its own units.
    #[error(
        "{path} is a {} log, which states its own units (m/s², rad/s) and time: leave out {option}",
        format.name()
    )]
    TextOptionOnBinary {
        /// The file.
        path: PathBuf,
        /// Its format.
        format: LogFormat,
        /// The options given.
        option: String,
    },
    /// A ULog's problem.
    #[error("{path}")]
    Ulog {
        /// The file.
        path: PathBuf,
        /// The cause.
        source: ulog::UlogError,
    },
    /// A DataFlash log's problem.
    #[error("{path}")]
    DataFlash {
        /// The file.
        path: PathBuf,
        /// The cause.
        source: dataflash::DataFlashError,
    },
    /// An MCAP file's problem.
    #[error("{path}")]
    Mcap {
        /// The file.
        path: PathBuf,
        /// The cause.
        source: mcap::McapError,
    },
    /// A stream the vehicle corrected before logging it, whose correction cannot be undone.
    #[error("{path}")]
    NotUndone {
        /// The file.
        path: PathBuf,
        /// Why.
        source: super::ardupilot::UndoError,
    },
    /// An IMU instance or an MCAP topic asked of a format that has no such thing.
    #[error("{path} is a {} log: {option} does not apply to it; leave it out", format.name())]
    OptionNotForFormat {
        /// The file.
        path: PathBuf,
        /// Its format.
        format: LogFormat,
        /// The option given.
        option: &'static str,
    },
    /// Too few samples to read as a recording.
    #[error("{path}: only {rows} IMU samples: too few to read as a recording (at least 2)")]
    NoRecording {
        /// The file.
        path: PathBuf,
        /// Samples found.
        rows: usize,
    },
    /// Too few samples for a session.
    #[error(
        "{path}: only {rows} IMU samples: a hand-held session needs minutes of data (positions \
         of 3–5 s and the turns between them)"
    )]
    TooFewSamples {
        /// The file.
        path: PathBuf,
        /// Samples found.
        rows: usize,
    },
}

/// The IMU a ULog or DataFlash log was asked for is not there, or has too many samples.
#[derive(Debug, thiserror::Error)]
pub enum ImuError {
    /// No IMU samples for the instance.
    #[error(
        "no IMU samples for instance {instance}: the log has {found}; {hint} and choose the IMU \
         with {}",
        crate::spelling::given_by(*.spelling, UserOption::Instance, "N")
    )]
    NoImu {
        /// The instance asked for.
        instance: u8,
        /// The IMU messages or topics and their instances found.
        found: String,
        /// What to log.
        hint: &'static str,
        /// The caller's names of the options: none from a reader, the caller's once
        /// [`read_log_from`](super::read_log_from) has [`spelled`](ImuError::spelled) it.
        spelling: Option<Spelling>,
    },
    /// More samples than are kept at once, from a reader that cannot be read again (a file is read
    /// again: [`read_log_keeping`](super::read_log_keeping)).
    #[error(
        "more than {1} samples in '{0}', the most this reads into memory at once: cut the log"
    )]
    TooManySamples(String, usize),
}

impl LogError {
    /// A stream held more samples than its budget ([`Keep::All`]): the seconds per unit of its
    /// time stamps (`None`: another error, or a text file whose time unit the rows read did not
    /// tell).
    pub(super) fn over_budget(&self, source: &LogSource) -> Option<f64> {
        if let LogError::Text(ImportError::TooManyRows { time_unit, .. }) = self {
            return match source.text.as_ref().map(|o| &o.time) {
                Some(TimeSource::RateHz(_)) => Some(1.0),
                _ => time_unit.map(TimeUnit::seconds),
            };
        }
        matches!(
            self,
            LogError::Ulog {
                source: ulog::UlogError::Imu(ImuError::TooManySamples(..)),
                ..
            } | LogError::DataFlash {
                source: dataflash::DataFlashError::Imu(ImuError::TooManySamples(..)),
                ..
            } | LogError::Mcap {
                source: mcap::McapError::TooManySamples(_),
                ..
            }
        )
        .then_some(1.0)
    }
}

impl ImuError {
    /// The error with the options named as `spelling` does.
    pub fn spelled(self, spelling: Spelling) -> ImuError {
        match self {
            ImuError::NoImu {
                instance,
                found,
                hint,
                ..
            } => ImuError::NoImu {
                instance,
                found,
                hint,
                spelling: Some(spelling),
            },
            e => e,
        }
    }
}

/// A binary file of a format the readers do not take, as far as its first bytes tell.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum ForeignFormat {
    /// A ROS 1 bag (`#ROSBAG`).
    Ros1Bag,
    /// A sqlite3 file (a ROS 2 bag's `.db3`).
    Sqlite,
    /// Anything else.
    Other,
}

impl ForeignFormat {
    /// What a file starting with `head` looks like.
    pub fn of(head: &[u8]) -> ForeignFormat {
        if head.starts_with(b"#ROSBAG") {
            ForeignFormat::Ros1Bag
        } else if head.starts_with(b"SQLite format 3\0") {
            ForeignFormat::Sqlite
        } else {
            ForeignFormat::Other
        }
    }
}

/// The conversion to a ROS 2 bag in MCAP: for a ROS 1 bag rosbags' converter, which re-encodes
/// its messages as ROS 2's CDR (`mcap convert` keeps ROS 1's encoding, which the reader does not
/// take); for a sqlite3 bag `mcap convert`.
impl std::fmt::Display for ForeignFormat {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str(match self {
            ForeignFormat::Ros1Bag => {
                "; this is a ROS 1 bag: convert it with `rosbags-convert --src FILE.bag --dst DIR \
                 --dst-storage mcap` (pip install rosbags) and give the .mcap file in DIR"
            }
            ForeignFormat::Sqlite => {
                "; this is a sqlite3 file (a ROS 2 bag's .db3?): convert it with `mcap convert`"
            }
            ForeignFormat::Other => {
                " (a ROS 1 bag or a sqlite3 ROS 2 bag is converted to one first)"
            }
        })
    }
}
