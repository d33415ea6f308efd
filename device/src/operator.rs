//! Who turns the table during the live procedure: a person at the terminal (instructions on stderr,
//! so that stdout stays for results such as `--json`; Enter on stdin), nobody when the device drives
//! its own virtual table, or the simulated hand of `--port sim-hand` (`sim_hand`).

use super::procedure::ProcedureError;
use std::io::{BufRead, Write};

/// Who turns the table: a person at a terminal, or nobody (the device's virtual table is driven).
pub trait Operator {
    /// Shows a line of progress.
    fn say(&mut self, text: &str);
    /// Asks for a set-up step and waits until it is done.
    fn wait_ready(&mut self, instruction: &str) -> Result<(), ProcedureError>;
    /// Asks for the unit to be turned to a new position and held still (hand-held mode). Nothing is
    /// waited for here: the procedure watches the device's windows until the unit is still again.
    fn turn_unit(&mut self, instruction: &str) {
        self.say(instruction);
    }
    /// A live check failed: keep the segment anyway (`true`) or stop (`false`)?
    fn keep_despite(&mut self, segment: &str, problems: &[String]) -> Result<bool, ProcedureError>;
}

/// An operator at the terminal: instructions on stderr (stdout stays for results, e.g. `--json`),
/// Enter on stdin.
pub struct TerminalOperator;

impl Operator for TerminalOperator {
    fn say(&mut self, text: &str) {
        let _ = writeln!(std::io::stderr(), "{text}");
    }

    fn wait_ready(&mut self, instruction: &str) -> Result<(), ProcedureError> {
        let _ = write!(
            std::io::stderr(),
            "{instruction} — press Enter when ready (Ctrl-C to stop) "
        );
        std::io::stderr()
            .flush()
            .map_err(ProcedureError::Terminal)?;
        let mut line = String::new();
        let n = std::io::stdin()
            .lock()
            .read_line(&mut line)
            .map_err(ProcedureError::Terminal)?;
        if n == 0 {
            return Err(ProcedureError::Aborted("standard input closed".into()));
        }
        Ok(())
    }

    fn keep_despite(&mut self, segment: &str, problems: &[String]) -> Result<bool, ProcedureError> {
        let _ = writeln!(
            std::io::stderr(),
            "segment '{segment}' does not match the plan:"
        );
        for p in problems {
            let _ = writeln!(std::io::stderr(), "  - {p}");
        }
        let _ = write!(
            std::io::stderr(),
            "keep it anyway (the estimator will screen it)? [y/N] "
        );
        std::io::stderr()
            .flush()
            .map_err(ProcedureError::Terminal)?;
        let mut line = String::new();
        std::io::stdin()
            .lock()
            .read_line(&mut line)
            .map_err(ProcedureError::Terminal)?;
        Ok(line.trim().eq_ignore_ascii_case("y"))
    }
}

/// No person: instructions are printed (unless quiet), nothing is waited for, and segments that fail a
/// live check are kept with a warning (the estimator screens them).
pub struct AutomaticOperator {
    /// Print progress lines.
    pub verbose: bool,
    /// Warnings collected from live checks.
    pub warnings: Vec<String>,
}

impl Operator for AutomaticOperator {
    fn say(&mut self, text: &str) {
        if self.verbose {
            let _ = writeln!(std::io::stderr(), "{text}");
        }
    }

    fn wait_ready(&mut self, instruction: &str) -> Result<(), ProcedureError> {
        self.say(instruction);
        Ok(())
    }

    fn keep_despite(&mut self, segment: &str, problems: &[String]) -> Result<bool, ProcedureError> {
        for p in problems {
            let w = format!("segment '{segment}': {p}");
            self.say(&format!("warning: {w}"));
            self.warnings.push(w);
        }
        Ok(true)
    }
}
