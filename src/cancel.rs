//! Cancelling long work from outside: a shared flag ([`Cancel`]) and the check points that read
//! it ([`checkpoint`]).
//!
//! A caller that may lose interest in a computation (the editor, when the page's connection
//! closes or a newer edit supersedes a solve) makes a [`Cancel`], runs the work inside
//! [`Cancel::scope`] on its own thread, and calls [`Cancel::cancel`] from another thread. The
//! long loops of the library — the refinement's levels, the solver's iterations, the stages of a
//! preparation or a solve, one edit after another — call [`checkpoint`], which fails with
//! [`Error::Cancelled`] once the flag of the scope they run in is set. Outside a scope (every
//! command-line run) a check point is one thread-local read and never fails, so nothing in the
//! library knows who may cancel it, and no signature carries the flag.
//!
//! The scope is the calling thread's: work handed to rayon's workers is not checked inside
//! them, only between the parallel steps, on the thread that made the scope. A cancelled
//! computation returns its error from the next check point; the caller must keep nothing it
//! made (it is not a result).
//!
//! A testing aid: [`CHECKPOINT_PAUSE_ENV`] makes every check point inside a scope pause before
//! it reads the flag, so that a test can make work slow by a known amount, cancel it, and see
//! it stop (docs/formats.md). Outside a scope it changes nothing.

use std::cell::RefCell;
use std::sync::atomic::{AtomicBool, Ordering};
use std::sync::{Arc, OnceLock};
use std::time::Duration;

use crate::{Error, Result};

/// A flag shared by the thread doing the work and the ones that may cancel it. Clones share
/// the flag.
#[derive(Clone, Debug, Default)]
pub struct Cancel(Arc<AtomicBool>);

thread_local! {
    /// The flags of the scopes the current thread runs in, innermost last.
    static SCOPES: RefCell<Vec<Cancel>> = const { RefCell::new(Vec::new()) };
}

/// Pops the scope it was made for, also when the work panics.
struct ScopeGuard;

impl Drop for ScopeGuard {
    fn drop(&mut self) {
        SCOPES.with(|s| s.borrow_mut().pop());
    }
}

impl Cancel {
    /// A flag not set.
    pub fn new() -> Cancel {
        Cancel::default()
    }

    /// Sets the flag: the work in its scopes stops at its next check point.
    pub fn cancel(&self) {
        self.0.store(true, Ordering::Release);
    }

    /// Whether the flag is set.
    pub fn is_cancelled(&self) -> bool {
        self.0.load(Ordering::Acquire)
    }

    /// Runs `work` on this thread with this flag read by every [`checkpoint`] it reaches
    /// (an enclosing scope's flag is still read too).
    pub fn scope<T>(&self, work: impl FnOnce() -> T) -> T {
        SCOPES.with(|s| s.borrow_mut().push(self.clone()));
        let _guard = ScopeGuard;
        work()
    }
}

/// The environment variable that makes every [`checkpoint`] inside a [`Cancel::scope`] pause
/// this many milliseconds (at most 10 000) before it reads the flag: a testing aid (the
/// editor's tests make a request slow by a known amount with it). Read once; unset, or not a
/// whole number, no pause.
pub const CHECKPOINT_PAUSE_ENV: &str = "GRAINLINE_TEST_CHECKPOINT_PAUSE_MS";

/// The pause [`CHECKPOINT_PAUSE_ENV`] asks for.
fn pause() -> Option<Duration> {
    static PAUSE: OnceLock<Option<Duration>> = OnceLock::new();
    *PAUSE.get_or_init(|| {
        let ms: u64 = std::env::var(CHECKPOINT_PAUSE_ENV).ok()?.trim().parse().ok()?;
        Some(Duration::from_millis(ms.min(10_000)))
    })
}

/// Fails with [`Error::Cancelled`] naming `stage` when a scope this thread runs in was
/// cancelled; else (and always outside a scope) `Ok`.
pub fn checkpoint(stage: &'static str) -> Result<()> {
    let scoped = SCOPES.with(|s| !s.borrow().is_empty());
    if !scoped {
        return Ok(());
    }
    if let Some(d) = pause() {
        std::thread::sleep(d);
    }
    let cancelled = SCOPES.with(|s| s.borrow().iter().any(Cancel::is_cancelled));
    if cancelled {
        Err(Error::Cancelled { stage })
    } else {
        Ok(())
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn check_points_fail_only_inside_a_cancelled_scope() {
        assert!(checkpoint("a").is_ok());
        let c = Cancel::new();
        c.scope(|| assert!(checkpoint("a").is_ok()));
        c.cancel();
        let e = c.scope(|| checkpoint("solve")).unwrap_err();
        assert!(matches!(e, Error::Cancelled { stage: "solve" }), "{e}");
        // The scope ended with the work: this thread is not cancelled any more.
        assert!(checkpoint("a").is_ok());
        // Another thread's scope is its own.
        let other = Cancel::new();
        let t = std::thread::spawn(move || other.scope(|| checkpoint("b").is_ok()));
        assert!(t.join().unwrap());
    }
}
