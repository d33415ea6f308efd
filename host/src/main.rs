//! `host`: a thin clap layer over the library (`host::cli`). Exit status: 0 success, 1 error, 2 usage
//! (clap's and ours), 3 a check failed ([`host::cli::CliError::exit_code`]).

use clap::Parser;

fn main() {
    let cli = host::cli::Cli::parse();
    if let Err(e) = host::cli::run(cli) {
        eprintln!("error: {e}");
        std::process::exit(e.exit_code());
    }
}
