//! Mesh-loading flags shared by every command that reads a mesh.

use std::path::PathBuf;

use clap::Args;
use grainline::mesh::load::{DegeneratePolicy, LoadOptions};
use grainline::mesh::Units;

/// How to read a mesh file.
#[derive(Debug, Args)]
pub struct MeshArgs {
    /// The mesh file: OBJ, STL (binary or ASCII) or PLY (ASCII or binary).
    pub mesh: PathBuf,
    /// Load only the object or group with this name (default: merge all).
    #[arg(long, value_name = "NAME")]
    pub object: Option<String>,
    /// Weld vertices closer than TOL (file units) before anything else (an STL is welded at 0,
    /// identical positions, without it).
    #[arg(long, value_name = "TOL")]
    pub weld: Option<f64>,
    /// Unit of the file's coordinates: mm, cm, m or in.
    #[arg(long, default_value = "mm")]
    pub units: Units,
    /// Uniform scale applied after loading.
    #[arg(long, default_value_t = 1.0)]
    pub scale: f64,
    /// Accept non-manifold edges and vertices.
    #[arg(long)]
    pub allow_nonmanifold: bool,
    /// Refuse zero-area faces instead of dropping them.
    #[arg(long)]
    pub strict_degenerate: bool,
}

impl MeshArgs {
    /// The library's load options for these flags.
    pub fn load_options(&self) -> LoadOptions {
        LoadOptions {
            object: self.object.clone(),
            weld: self.weld,
            units: self.units,
            scale: self.scale,
            allow_nonmanifold: self.allow_nonmanifold,
            degenerate: if self.strict_degenerate {
                DegeneratePolicy::Error
            } else {
                DegeneratePolicy::Drop
            },
            ..LoadOptions::default()
        }
    }
}
