//! `tracer`: parse the command line, call the library, report errors.

use clap::Parser;

fn main() {
    let cli = tracer::cli::Cli::parse();
    match tracer::cli::run(cli) {
        Ok(status) => std::process::exit(status),
        Err(e) => {
            eprintln!("error: {e}");
            std::process::exit(1);
        }
    }
}
