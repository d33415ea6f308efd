//! The terminal: stdout writes that return an error where `println!` would panic (the progress bars
//! are [`recording::ui`]'s).

/// Writes to stdout, returning the error that `println!` would panic on: a closed pipe
/// (`host … | head -2`) or a full disk (`> /dev/full`) becomes a clear error of the command.
pub(crate) fn write_stdout(args: std::fmt::Arguments<'_>) -> std::io::Result<()> {
    use std::io::Write;
    let mut out = std::io::stdout().lock();
    out.write_fmt(args)?;
    out.flush()
}

/// `println!` that returns an `io::Result` instead of panicking (see `write_stdout`).
#[macro_export]
macro_rules! outln {
    () => { $crate::ui::write_stdout(format_args!("\n")) };
    ($($t:tt)*) => { $crate::ui::write_stdout(format_args!("{}\n", format_args!($($t)*))) };
}

/// `print!` that returns an `io::Result` instead of panicking (see `write_stdout`).
#[macro_export]
macro_rules! out {
    ($($t:tt)*) => { $crate::ui::write_stdout(format_args!($($t)*)) };
}
