//! Where a command's output goes: with `--json` one JSON document on stdout and everything for
//! people on stderr (so `host calibrate --json | jq .` works while progress bars and prompts still
//! show); without it the human text on stdout. `--quiet` silences the human text (warnings and
//! errors still go to stderr).

use super::CliError;
use serde::Serialize;
use std::fmt::Display;

/// The output channels of one command.
#[derive(Clone, Copy, Debug, Default)]
pub struct Output {
    /// `--json`: stdout carries only the JSON document.
    pub json: bool,
    /// `--quiet`.
    pub quiet: bool,
}

impl Output {
    /// Text for people (a result table, a summary line).
    pub fn human(&self, text: impl Display) {
        if self.quiet {
            return;
        }
        if self.json {
            eprint!("{text}");
        } else {
            print!("{text}");
        }
    }

    /// [`Output::human`] with a line end.
    pub fn line(&self, text: impl Display) {
        self.human(format_args!("{text}\n"));
    }

    /// A warning: always on stderr.
    pub fn warn(&self, text: impl Display) {
        eprintln!("warning: {text}");
    }

    /// The JSON document, when `--json` was given.
    pub fn document<T: Serialize>(&self, value: &T) -> Result<(), CliError> {
        if self.json {
            let text = serde_json::to_string_pretty(value)
                .map_err(|e| CliError::Usage(format!("cannot write the JSON result: {e}")))?;
            println!("{text}");
        }
        Ok(())
    }
}
