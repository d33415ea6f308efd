//! The recording of a calibration session: `plan.toml` + `samples.csv` in a directory
//! (format documented in `docs/recording-format.md`).

pub mod plan;
pub mod stats;

pub use plan::{OutputUnitName, Plan, PlanError, SegmentPlan};
pub use stats::{SegmentAccumulator, SegmentStats};
