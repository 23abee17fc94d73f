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

/// A fresh scratch directory `grainline-{prefix}-{pid}-{name}` under the system's temporary
/// directory (emptied first).
pub fn scratch_dir(prefix: &str, name: &str) -> PathBuf {
    let d = std::env::temp_dir().join(format!("grainline-{prefix}-{}-{name}", std::process::id()));
    let _ = std::fs::remove_dir_all(&d);
    std::fs::create_dir_all(&d).unwrap();
    d
}

/// Runs the `grainline` binary built with the tests.
pub fn grainline(args: &[&str]) -> std::process::Output {
    std::process::Command::new(env!("CARGO_BIN_EXE_grainline")).args(args).output().unwrap()
}

/// Asserts the command succeeded, showing its standard error when it did not.
pub fn ok(o: &std::process::Output) {
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
}

/// A JSON file, parsed.
pub fn read_json(p: &std::path::Path) -> serde_json::Value {
    serde_json::from_slice(&std::fs::read(p).unwrap()).unwrap()
}

/// FIELD.json's per-vertex vectors under `key` (positions, normals, `u`, …).
pub fn json_vectors(v: &serde_json::Value, key: &str) -> Vec<nalgebra::Vector3<f64>> {
    let a = v[key].as_array().unwrap_or_else(|| panic!("FIELD.json has no {key}"));
    a.iter()
        .map(|p| {
            let c: Vec<f64> = p.as_array().unwrap().iter().map(|x| x.as_f64().unwrap()).collect();
            nalgebra::Vector3::new(c[0], c[1], c[2])
        })
        .collect()
}
