//! `host`: a thin clap layer over the library (`host::cli`). Exit status: 0 success, 1 error, 2 usage
//! (clap's and ours), 3 a check failed ([`host::cli::CliError::exit_code`]).

use clap::Parser;

fn main() {
    let cli = host::cli::Cli::try_parse().unwrap_or_else(|e| {
        // Under --json the parser's own refusals give the same document as every other usage
        // error; help and version print as usual.
        if let Some(doc) = host::cli::output::parse_error_document(&e, std::env::args_os()) {
            use std::io::Write;
            let _ = e.print();
            let _ = writeln!(std::io::stdout(), "{doc}");
            std::process::exit(e.exit_code());
        }
        e.exit()
    });
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
