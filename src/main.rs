//! The `grainline` command: a thin layer over the library.

mod cli;

use std::process::ExitCode;

use clap::Parser;

// mimalloc instead of the system allocator: on the 1M-vertex core benchmark (examples/bench_core)
// it halves load + geometry time (2.2–3.0 s → 1.5 s), which is dominated by large short-lived
// allocations; `keep_freed_memory` below saves the re-zeroing of freed pages (grainline::allocator).
#[global_allocator]
static GLOBAL: mimalloc::MiMalloc = mimalloc::MiMalloc;

fn main() -> ExitCode {
    grainline::allocator::keep_freed_memory();
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
            eprintln!("grainline: error: {}", message(&e));
            ExitCode::from(1)
        }
    }
}

/// The error and its causes on one line, leaving out a cause whose text the message already
/// ends with (the library's errors already print their source, e.g. "file: No such file").
fn message(e: &anyhow::Error) -> String {
    let mut out = String::new();
    for cause in e.chain() {
        let text = cause.to_string();
        if out.is_empty() {
            out = text;
        } else if !out.ends_with(&text) {
            out = format!("{out}: {text}");
        }
    }
    out
}
