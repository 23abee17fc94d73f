//! Process-level tuning of mimalloc, the allocator of the `grainline` binary and the benchmarks.
//!
//! The pipeline frees arrays of hundreds of megabytes between stages and allocates new ones
//! (the loader's corner lists, the geometry's stencils, the solver's Jacobian). mimalloc returns
//! freed memory to the operating system after a second (its `purge_delay`), so a later stage's
//! arrays are fresh pages that the kernel must zero on first touch. On the 1M-vertex core
//! benchmark (`examples/bench_core`) the run took 80,910 page faults and 24.0 s of CPU; with
//! freed memory kept, 765 and 19.3 s (`perf stat -e page-faults,task-clock`). [`keep_freed_memory`]
//! keeps freed memory committed for reuse until the process ends; the peak resident memory does
//! not grow (the benchmark's peak stays ~720 MB), since memory is kept only to be reused.

/// mimalloc's `mi_option_purge_delay`: the 16th entry of `mi_option_e` in the v3 `mimalloc.h`
/// that libmimalloc-sys builds (default 1000 ms; -1 never purges).
const MI_OPTION_PURGE_DELAY: libmimalloc_sys::mi_option_t = 15;

/// Keeps memory freed to mimalloc committed until the process exits instead of returning it to
/// the system after a second. Call once at start-up from a program whose global allocator is
/// mimalloc; with another allocator it changes nothing.
pub fn keep_freed_memory() {
    // SAFETY: mi_option_set only stores an integer in mimalloc's option table; it is safe to call
    // at any time from any thread.
    unsafe { libmimalloc_sys::mi_option_set(MI_OPTION_PURGE_DELAY, -1) }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_option_index_is_the_purge_delay() {
        // A different mimalloc would make index 15 another option: its default (1000 ms in
        // mimalloc v3's options.c) and the value we set identify it.
        if std::env::var_os("MIMALLOC_PURGE_DELAY").is_none() {
            assert_eq!(unsafe { libmimalloc_sys::mi_option_get(MI_OPTION_PURGE_DELAY) }, 1000);
        }
        keep_freed_memory();
        assert_eq!(unsafe { libmimalloc_sys::mi_option_get(MI_OPTION_PURGE_DELAY) }, -1);
    }
}
