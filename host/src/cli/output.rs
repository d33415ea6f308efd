//! Where a command's output goes, the one convention of every subcommand (README, "Output and exit
//! status"): results on stdout — the human text, or with `--json` only the JSON document (the human
//! text then goes to stderr, so `host calibrate --json | jq .` works); progress, prompts and warnings
//! on stderr. `--quiet` silences everything but warnings, errors and the JSON document.

use super::CliError;
use serde::Serialize;
use std::fmt::Display;
use std::io::Write;

/// The output channels of one command.
#[derive(Clone, Copy, Debug, Default)]
pub(crate) struct Output {
    /// `--json`: stdout carries only the JSON document.
    pub json: bool,
    /// `--quiet`.
    pub quiet: bool,
}

impl Output {
    /// Text for people (a result table, a summary line). A closed or full stdout is an error of the
    /// command, never a panic; a closed stderr (where the text goes with `--json`) is ignored.
    pub fn human(&self, text: impl Display) -> Result<(), CliError> {
        if self.quiet {
            return Ok(());
        }
        if self.json {
            let _ = write!(std::io::stderr(), "{text}");
            Ok(())
        } else {
            crate::out!("{text}").map_err(CliError::Stdout)
        }
    }

    /// [`Output::human`] with a line end.
    pub fn line(&self, text: impl Display) -> Result<(), CliError> {
        self.human(format_args!("{text}\n"))
    }

    /// A warning: on stderr, with `--quiet` too (its help says so: quiet drops progress and
    /// results, never what may be wrong).
    pub(crate) fn warn(&self, text: impl Display) {
        let _ = writeln!(std::io::stderr(), "warning: {text}");
    }

    /// Progress or a note for the person at the terminal (not a result): on stderr, unless
    /// `--quiet`.
    pub fn note(&self, text: impl Display) {
        if !self.quiet {
            let _ = writeln!(std::io::stderr(), "{text}");
        }
    }

    /// The JSON document, when `--json` was given.
    pub fn document<T: Serialize>(&self, value: &T) -> Result<(), CliError> {
        if self.json {
            let text = serde_json::to_string_pretty(value).map_err(|source| CliError::Json {
                what: "the result",
                source,
            })?;
            crate::outln!("{text}").map_err(CliError::Stdout)?;
        }
        Ok(())
    }
}

/// The one JSON error document: the message, its kind ("usage" or "error") and the exit status.
pub(crate) fn error_json(message: &str, kind: &str, exit_code: i32) -> String {
    serde_json::json!({ "error": message, "kind": kind, "exit_code": exit_code }).to_string()
}

/// The argument parser's own refusal (a value below its bound, an unknown flag) as the document
/// every other usage error gives under `--json`; `None` for help and version, which are no errors,
/// or when `args` do not ask for JSON. The message is the parser's, without its "error: " prefix.
pub(crate) fn parse_error_document(
    e: &clap::Error,
    args: impl IntoIterator<Item = std::ffi::OsString>,
) -> Option<String> {
    let json = args
        .into_iter()
        .take_while(|a| a != "--")
        .any(|a| a == "--json");
    if !json || !e.use_stderr() {
        return None;
    }
    let text = e.render().to_string();
    let message = text.trim().strip_prefix("error: ").unwrap_or(text.trim());
    Some(error_json(message, "usage", e.exit_code()))
}
