//! The recording of a calibration session: `plan.toml` + `samples.csv` in a directory
//! (format documented in `docs/recording-format.md`).

pub mod builtin;
pub mod csv_io;
pub mod plan;
pub mod stats;

pub use csv_io::{
    read_samples, read_session, ReadOptions, ReadReport, RecordingError, Session, SessionWriter,
    PLAN_FILE, SAMPLES_FILE, SAMPLES_HEADER,
};
pub use plan::{OutputUnitName, Plan, PlanError, SegmentPlan};
pub use stats::{SegmentAccumulator, SegmentStats};
