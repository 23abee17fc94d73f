//! The `grainline` command: a thin layer over the library.

mod cli;

use std::process::ExitCode;

use clap::Parser;

fn main() -> ExitCode {
    let args = cli::Cli::parse();
    // Sparse factorizations run sequentially: their rounding must not depend on the thread
    // count (outputs are byte-identical at any --threads).
    faer::set_global_parallelism(faer::Par::Seq);
    if let Some(n) = args.threads {
        // Results never depend on the thread count; this only bounds the CPU used.
        let _ = rayon::ThreadPoolBuilder::new().num_threads(n.max(1)).build_global();
    }
    match cli::run(args) {
        Ok(()) => ExitCode::SUCCESS,
        Err(e) => {
            eprintln!("grainline: error: {e:#}");
            ExitCode::from(1)
        }
    }
}
