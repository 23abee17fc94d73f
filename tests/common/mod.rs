//! Helpers shared by the integration tests.

use std::path::PathBuf;

/// The path of a mesh in `../shared/meshes`, or `None` (after saying so) when `../shared` is
/// absent, so tests that need it skip on a bare clone.
pub fn shared_mesh(name: &str) -> Option<PathBuf> {
    let p = PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("../shared/meshes").join(name);
    if p.exists() {
        Some(p)
    } else {
        eprintln!("skipping: {} not found (../shared is absent)", p.display());
        None
    }
}
