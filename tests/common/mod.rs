//! Helpers shared by the integration tests.
#![allow(dead_code)]

use std::path::PathBuf;

/// The path of a mesh in `../shared/meshes`, or `None` (after saying so) when `../shared` is
/// absent, so tests that need it skip on a bare clone.
pub fn shared_mesh(name: &str) -> Option<PathBuf> {
    // `GRAINLINE_SHARED` (as the benchmarks read it) names the shared directory elsewhere.
    let root = std::env::var_os("GRAINLINE_SHARED")
        .map(PathBuf::from)
        .unwrap_or_else(|| PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("../shared"));
    let p = root.join("meshes").join(name);
    if p.exists() {
        Some(p)
    } else {
        eprintln!("skipping: {} not found (../shared is absent)", p.display());
        None
    }
}

/// Makes sure LinuxCNC's `rs274` is installed before `check-gcode` (the shared tool at `tool`)
/// runs: its first use installs the Debian package, and tests running in parallel must not start
/// that install at the same time (apt's lock turns all but one into a set-up failure). The first
/// caller installs under an exclusive file lock; the others wait for it.
pub fn ensure_rs274(tool: &std::path::Path) {
    let installed = || {
        std::process::Command::new("sh")
            .args(["-c", "command -v rs274"])
            .output()
            .is_ok_and(|o| o.status.success())
    };
    if installed() {
        return;
    }
    let lock_path = std::env::temp_dir().join("grainline-rs274-install.lock");
    let Ok(lock) = std::fs::File::create(&lock_path) else { return };
    if lock.lock().is_err() || installed() {
        return;
    }
    // Any program makes check-gcode install rs274; its verdict is the tests' business.
    let program = std::env::temp_dir().join(format!("grainline-rs274-{}.ngc", std::process::id()));
    if std::fs::write(&program, "G21\nM2\n").is_ok() {
        let _ = std::process::Command::new("bash").arg(tool).arg(&program).output();
        let _ = std::fs::remove_file(&program);
    }
}
