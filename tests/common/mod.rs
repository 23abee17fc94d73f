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

#[path = "../support/rs274.rs"]
mod rs274;
#[allow(unused_imports)] // not every test binary runs check-gcode
pub use rs274::{ensure_rs274, run_checker};
