//! `host`: a thin clap layer over the library (`host::cli`). Exit status: 0 success, 1 error, 2 usage
//! (clap's and ours), 3 a check failed (`CliError::exit_code` in `host::cli`).

fn main() {
    host::cli::main()
}
