//! The terminal side of long operations: progress bars on stderr, drawn only on a terminal and never
//! with `--quiet`, so logs and pipes get none.

use indicatif::{ProgressBar, ProgressDrawTarget, ProgressStyle};
use std::io::IsTerminal;

/// A progress bar counting items (rows, windows) on stderr, hidden unless stderr is a terminal and
/// `quiet` is false.
pub fn progress_bar(total: u64, message: &'static str, quiet: bool) -> ProgressBar {
    styled_bar(
        total,
        message,
        quiet,
        "{msg} [{bar:40}] {human_pos}/{human_len} ({eta} left)",
    )
}

/// A progress bar counting bytes on stderr, hidden unless stderr is a terminal and `quiet` is false.
pub(crate) fn progress_bar_bytes(total: u64, message: &'static str, quiet: bool) -> ProgressBar {
    styled_bar(
        total,
        message,
        quiet,
        "{msg} [{bar:40}] {bytes}/{total_bytes} ({bytes_per_sec}, {eta} left)",
    )
}

fn styled_bar(total: u64, message: &'static str, quiet: bool, template: &str) -> ProgressBar {
    if quiet || !std::io::stderr().is_terminal() {
        return ProgressBar::hidden();
    }
    let bar = ProgressBar::with_draw_target(Some(total), ProgressDrawTarget::stderr());
    let style = ProgressStyle::with_template(template)
        .unwrap_or_else(|_| ProgressStyle::default_bar())
        .progress_chars("=> ");
    bar.set_style(style);
    bar.set_message(message);
    bar
}

/// A step without a count (reading a log, a fit, drawing figures): a spinner with its message and
/// the time spent so far on stderr, cleared when the step ends or is abandoned by an error; hidden
/// unless stderr is a terminal and `quiet` is false.
pub fn step(message: impl Into<std::borrow::Cow<'static, str>>, quiet: bool) -> ProgressBar {
    if quiet || !std::io::stderr().is_terminal() {
        return ProgressBar::hidden();
    }
    let bar = ProgressBar::with_draw_target(None, ProgressDrawTarget::stderr())
        .with_finish(indicatif::ProgressFinish::AndClear);
    let style = ProgressStyle::with_template("{spinner} {msg} ({elapsed})")
        .unwrap_or_else(|_| ProgressStyle::default_spinner());
    bar.set_style(style);
    bar.set_message(message);
    bar.enable_steady_tick(std::time::Duration::from_millis(120));
    bar
}
