//! Loading OBJ files (via tobj) into a validated [`Mesh`].
//!
//! (Being written: see the mesh issue. The types below are the agreed interface.)

use std::path::Path;

use super::{Mesh, Units};
use crate::Result;

/// What to do with zero-area faces.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum DegeneratePolicy {
    /// Drop them and count them in the report (the default).
    #[default]
    Drop,
    /// Refuse the mesh with an error naming the first few.
    Error,
}

/// Options of [`load_obj`].
#[derive(Clone, Debug)]
pub struct LoadOptions {
    /// Keep only the object (or group) with this name; `None` merges every object.
    pub object: Option<String>,
    /// Weld positions closer than this distance (in file units) before anything else.
    pub weld: Option<f64>,
    /// Unit of the file's coordinates.
    pub units: Units,
    /// Uniform scale applied to the positions after loading.
    pub scale: f64,
    /// Accept non-manifold edges and vertices instead of refusing the mesh.
    pub allow_nonmanifold: bool,
    /// What to do with zero-area faces.
    pub degenerate: DegeneratePolicy,
}

impl Default for LoadOptions {
    fn default() -> Self {
        LoadOptions {
            object: None,
            weld: None,
            units: Units::Mm,
            scale: 1.0,
            allow_nonmanifold: false,
            degenerate: DegeneratePolicy::Drop,
        }
    }
}

/// What loading did to the file's contents.
#[derive(Clone, Debug, Default, serde::Serialize)]
pub struct LoadReport {
    /// Vertices as listed in the file.
    pub file_vertices: usize,
    /// Vertices removed because no face used them.
    pub unreferenced_vertices: usize,
    /// Vertices merged into another by welding.
    pub welded_vertices: usize,
    /// Zero-area faces dropped.
    pub dropped_degenerate_faces: usize,
}

/// A loaded mesh and the report of what loading did.
#[derive(Clone, Debug)]
pub struct LoadedMesh {
    /// The mesh, in scene units.
    pub mesh: Mesh,
    /// What loading changed.
    pub report: LoadReport,
}

/// Loads and validates an OBJ file.
pub fn load_obj(path: &Path, options: &LoadOptions) -> Result<LoadedMesh> {
    let _ = (path, options);
    unimplemented!("load_obj is being written")
}
