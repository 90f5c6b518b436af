//! `tracer`: parse the command line, call the library, report errors.

mod cli;

use clap::Parser;

/// Large blocks on huge pages: faster BVH traversal and builds on big meshes
/// (see `tracer::huge_pages`).
#[global_allocator]
static ALLOCATOR: tracer::huge_pages::HugePageAlloc = tracer::huge_pages::HugePageAlloc;

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
