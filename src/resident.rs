//! The process's resident memory: its peak since the last reset, for the run report's memory
//! per stage (`StageTime::peak_rss_mb`).
//!
//! Linux keeps the peak resident set size of a process (`VmHWM` in `/proc/self/status`), and
//! writing `5` to `/proc/self/clear_refs` resets it to the current resident size (proc(5)).
//! Resident memory is what the machine gives the run — the allocator's retained pages
//! included, the untouched reserves some libraries allocate (faer's matrix-product workspace:
//! hundreds of MB per thread, never written) excluded. Elsewhere, or when `/proc` cannot be
//! read, nothing is measured.

/// Starts a new peak at the current resident size (the peak of what follows). Process-wide:
/// work on other threads at the same time counts too.
pub fn reset_peak() {
    let _ = std::fs::write("/proc/self/clear_refs", "5");
}

/// The largest resident set size of the process since the last [`reset_peak`] (or its start),
/// bytes; `None` where the system does not say.
pub fn peak_bytes() -> Option<u64> {
    let status = std::fs::read_to_string("/proc/self/status").ok()?;
    let line = status.lines().find(|l| l.starts_with("VmHWM:"))?;
    let kb: u64 = line.split_whitespace().nth(1)?.parse().ok()?;
    Some(kb * 1024)
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A buffer written page by page raises the peak by about its size; after a reset the
    /// peak is the resident size again (Linux only: elsewhere nothing is measured).
    #[test]
    fn the_peak_follows_a_touched_buffer_and_resets() {
        let Some(before) = peak_bytes() else { return };
        let n = 64 << 20;
        let mut v = vec![0u8; n];
        for i in (0..n).step_by(4096) {
            v[i] = 1;
        }
        let with = peak_bytes().unwrap();
        assert!(with >= before.max(n as u64), "{with} after a {n}-byte buffer ({before} before)");
        std::hint::black_box(&v);
        drop(v);
        reset_peak();
        let after = peak_bytes().unwrap();
        assert!(after + (n as u64) / 2 < with, "{after} after the reset, {with} before");
    }
}
