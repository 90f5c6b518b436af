//! `tracer`: parse the command line, call the library, report errors.

mod cli;

use clap::Parser;

fn main() {
    let cli = cli::Cli::parse();
    match cli::run(cli) {
        Ok(status) => std::process::exit(status),
        Err(e) => {
            eprintln!("error: {e}");
            std::process::exit(1);
        }
    }
}
