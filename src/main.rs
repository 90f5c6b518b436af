//! `tracer`: parse the command line, call the library, report errors.

use clap::Parser;

fn main() {
    let cli = tracer::cli::Cli::parse();
    if let Err(e) = tracer::cli::run(cli) {
        eprintln!("error: {e}");
        std::process::exit(1);
    }
}
