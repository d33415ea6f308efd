//! A calibration recording, the lowest layer of the PC calibrator: what a session or a logger's
//! file holds, read with bounded memory and repaired where one sample is damaged, cut into segments
//! and reduced to the per-segment statistics the estimator works on. It knows nothing of the
//! estimator, the simulator, the device or the command line (`ARCHITECTURE.md`).
//!
//! - [`session`]: the plan (and the built-in plans), the per-segment statistics, the streaming
//!   `samples.csv` reader and writer (`docs/recording-format.md`), the loggers' readers (CSV, ULog,
//!   DataFlash, MCAP), the time-stamp repair, segmentation and coverage.
//! - [`limits`]: the bounds every input is held to (line length, segment count, rates, file size)
//!   and the range parsers of the command line's numbers.
//! - [`output_file`]: result files written atomically, never over an existing one unless asked.
//! - [`ui`]: progress bars on a terminal.
//! - [`spelling`]: the options a message may ask for, by their meaning, and the caller's way of
//!   writing them; the names themselves are the edges' (the command line's flags, Python's
//!   keywords).
//! - `testkit` (feature `testkit`): the loggers' formats written from samples and the checks the
//!   readers' tests share, for the tests, fuzz corpora and long-log benchmarks of every crate; the
//!   neutral spelling of the tests below the edges.
#![deny(missing_docs)]

pub mod limits;
pub mod output_file;
pub mod session;
pub mod spelling;
#[cfg(any(test, feature = "testkit"))]
pub mod testkit;
pub mod ui;
