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
    remove_temporaries_on_signal();
    let args = cli::Cli::parse();
    // Sparse factorizations run sequentially: their rounding must not depend on the thread
    // count (outputs are byte-identical at any --threads).
    faer::set_global_parallelism(faer::Par::Seq);
    if let Some(n) = args.threads {
        // Results never depend on the thread count; this only bounds the CPU used.
        let cores = std::thread::available_parallelism().map_or(1, |c| c.get());
        let (n, capped) = grainline::limits::worker_threads(n, cores);
        if capped {
            eprintln!(
                "grainline: note: --threads capped at {n} ({}× the {cores} available core(s))",
                grainline::limits::THREADS_PER_CORE
            );
        }
        let _ = rayon::ThreadPoolBuilder::new().num_threads(n).build_global();
    }
    let result = cli::run(args);
    if grainline::output::interrupted() {
        // A signal came (also during the last renames): its handler ends the process with
        // 128 + its number once the renames are done; this thread must not exit first.
        loop {
            std::thread::park();
        }
    }
    match result {
        Ok(()) => ExitCode::SUCCESS,
        Err(e) => {
            eprintln!("grainline: error: {}", grainline::error::escape_control(&message(&e)));
            ExitCode::from(1)
        }
    }
}

/// On SIGINT, SIGTERM or SIGHUP: delete the temporary files of outputs not yet persisted
/// (grainline::output) and exit with 128 + the signal's number. A signal ends the process
/// without running destructors, so `tempfile`'s own cleanup would not run.
fn remove_temporaries_on_signal() {
    use signal_hook::consts::{SIGHUP, SIGINT, SIGTERM};
    let Ok(mut signals) = signal_hook::iterator::Signals::new([SIGINT, SIGTERM, SIGHUP]) else {
        return;
    };
    std::thread::spawn(move || {
        if let Some(sig) = signals.forever().next() {
            let removed = grainline::output::remove_temporaries();
            let name = match sig {
                SIGINT => "SIGINT",
                SIGTERM => "SIGTERM",
                _ => "SIGHUP",
            };
            let renamed = match grainline::output::renamed() {
                0 => String::new(),
                n => {
                    format!("{n} output(s) renamed into place (a set being renamed is finished); ")
                }
            };
            eprintln!(
                "grainline: interrupted by {name}: {removed} temporary file(s) removed; \
                 {renamed}outputs not yet written were left as they were"
            );
            std::process::exit(128 + sig);
        }
    });
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
