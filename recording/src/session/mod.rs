//! The recording of a calibration session: `plan.toml` + `samples.csv` in a directory
//! (format documented in `docs/recording-format.md`).
//!
//! - [`plan`]: the plan file (segments, attitudes, rates), its checks and its [`RecordingVersion`]
//!   (which version holds what); [`builtin`]: the plans
//!   shipped with the tool.
//! - [`stats`]: the per-segment sufficient statistics everything downstream works on.
//! - [`reader`]: the streaming `samples.csv` reader (constant memory, one pass); [`writer`]: the
//!   writer that syncs at every segment end; [`error`]: what can go wrong with either;
//!   [`thermal`]: the optional `temp_c` column and its per-segment statistics.
//! - A logger's file without a plan: [`import`] reads its CSV (units, columns, sample rate),
//!   [`segment`] finds the still positions and the spins in it (`host segment`), [`coverage`]
//!   judges the positions found (distinct, directions missed, a cube's six faces), and
//!   [`from_recording`] turns what was found into a plan and statistics for the estimator;
//!   [`logs`] reads the binary logs (PX4 ULog, ArduPilot DataFlash, ROS 2 MCAP) and tells them
//!   from text by their first bytes; [`repair`] mends the damaged time stamps of every reader's
//!   samples by one set of rules, with `bursts` (a host's bursts of stamps, re-timed from the fitted
//!   rate) and `restart` (logs joined with their time restarting); `rest` judges stillness against
//!   each stream's own noise floor for [`segment`]; [`note`]: what every reader tells the user
//!   besides the samples (rows left out, stamps repaired), as values with one wording each.
//! - [`toml_check`]: the arrays of a TOML file that serde would silently cut short.

pub mod builtin;
pub mod bursts;
pub mod coverage;
pub mod error;
pub mod from_recording;
pub mod import;
pub mod logs;
pub mod note;
pub mod plan;
pub mod reader;
pub mod repair;
pub mod rest;
mod restart;
pub mod segment;
pub mod stats;
pub mod thermal;
pub mod toml_check;
pub mod writer;

pub use error::RecordingError;
pub use plan::{Package, Plan, PlanError, RecordingVersion, SegmentPlan};
pub use reader::{
    read_samples, read_samples_each, read_session, ReadOptions, ReadReport, Row, Session,
};
pub use stats::{SegmentAccumulator, SegmentStats};
pub use writer::SessionWriter;

/// The plan file inside a session directory.
pub const PLAN_FILE: &str = "plan.toml";
/// The samples file inside a session directory.
pub const SAMPLES_FILE: &str = "samples.csv";
/// The header of `samples.csv` in versions 1 and 2 ([`RecordingVersion::samples_header`] says which
/// a plan has).
pub const SAMPLES_HEADER: &str = "segment,t_s,u_x,u_y,u_z,w_x,w_y,w_z";
/// Column names, in order.
pub(crate) const COLUMNS: [&str; 8] = ["segment", "t_s", "u_x", "u_y", "u_z", "w_x", "w_y", "w_z"];
/// The header of `samples.csv` version 3: version 2's and the unit's temperature, °C.
pub(crate) const SAMPLES_HEADER_TEMPERATURE: &str = "segment,t_s,u_x,u_y,u_z,w_x,w_y,w_z,temp_c";
/// Column names of version 3, in order.
pub(crate) const COLUMNS_TEMPERATURE: [&str; 9] = [
    "segment", "t_s", "u_x", "u_y", "u_z", "w_x", "w_y", "w_z", "temp_c",
];
