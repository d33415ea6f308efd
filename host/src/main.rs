//! `host`: a thin clap layer over the library (`host::cli`).

use clap::Parser;

fn main() {
    let cli = host::cli::Cli::parse();
    if let Err(e) = host::cli::run(cli) {
        eprintln!("error: {e}");
        std::process::exit(1);
    }
}
