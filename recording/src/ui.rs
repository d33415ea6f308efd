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
pub fn progress_bar_bytes(total: u64, message: &'static str, quiet: bool) -> ProgressBar {
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
