//! `host`: a thin clap layer over the library (`host::cli`). Exit status: 0 success, 1 error, 2 usage
//! (clap's and ours), 3 a check failed ([`host::cli::CliError::exit_code`]).

use clap::Parser;

fn main() {
    let cli = host::cli::Cli::parse();
    let json = cli.command.json();
    if let Err(e) = host::cli::run(cli) {
        eprintln!("error: {e}");
        if let Some(doc) = host::cli::error_document(&e).filter(|_| json) {
            use std::io::Write;
            // A closed stdout leaves the message above and the exit status.
            let _ = writeln!(std::io::stdout(), "{doc}");
        }
        std::process::exit(e.exit_code());
    }
}
