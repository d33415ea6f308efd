//! What a person reads.
//!
//! - [`text`]: the terminal text of a calibration and of a plan's prediction, with [`mod@format`] (the one
//!   `± 1σ` formatter) and [`thermal`] (the temperature model's part).
//! - [`segment_rows`]: the one table of each segment's outputs before and after compensation, through
//!   the device's own compensator (the terminal text and the report both show it).
//! - The HTML/Markdown report of `host report`: [`data`] (the numbers: segments before and after
//!   compensation, χ², navigation replays) → [`figures`] (what each figure shows) and [`page`] (the
//!   document model: Tables 1–4) → [`plot`] (plotters, PNG/SVG, with [`axes`]: legends beside the
//!   data, labels that never collide, decade ticks) and `markup` (Markdown, HTML) →
//!   [`document`] (the files).
//! - [`navigation`]: the paper's navigation check — the drift integration and the replay of a segment;
//!   [`mod@navigation_check`]: what `host navigation-check` shows (`app::navigation_check` runs it).
//! - [`compare`]: two calibrations side by side, and the `host export` text.
//! - [`summary_block`]: the short block of results that ends `host calibrate`; `gyro_section`: the
//!   report's gyro section (G, b, 1σ, the spins' residuals).

pub mod axes;
pub mod compare;
pub mod data;
pub mod document;
pub mod figures;
#[cfg(test)]
mod fit_text_tests;
pub mod format;
mod gyro_section;
pub(crate) mod markup;
pub mod navigation;
pub mod navigation_check;
pub mod page;
pub mod plot;
pub mod summary_block;
#[cfg(test)]
mod tests;
pub mod text;
pub mod thermal;

pub use data::{
    build_report, segment_rows, session_fit_options, Compensation, NamedRun, ReportData,
    ReportError, ReportOptions, SegmentRow,
};
pub use document::{write_report, ReportSummary, REPORT_HTML, REPORT_MD};
pub use navigation::render_position_targets;
pub use navigation_check::NavigationCheck;
pub use text::{render, render_excluded, render_prediction, render_session};
