//! What a mesh load is asked ([`LoadOptions`]) and what it gives ([`LoadedMesh`], its
//! [`LoadReport`] and the file's [`MeshFormat`]), shared by the OBJ loader
//! ([`super::load`]) and the STL and PLY readers (`raw.rs`).

use super::{Mesh, Units};

/// What to do with zero-area faces.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum DegeneratePolicy {
    /// Drop them and count them in the report (the default).
    #[default]
    Drop,
    /// Refuse the mesh with an error naming the first few.
    Error,
}

/// Options of [`load_obj`](super::load::load_obj) and [`load_mesh`](super::load::load_mesh).
#[derive(Clone, Debug)]
pub struct LoadOptions {
    /// Keep only the object (or group) with this name; `None` merges every object.
    pub object: Option<String>,
    /// Weld positions closer than this distance (in file units) before anything else. `None`
    /// welds nothing, except that [`load_mesh`](super::load::load_mesh) welds an STL at 0 (identical positions).
    pub weld: Option<f64>,
    /// Unit of the file's coordinates.
    pub units: Units,
    /// Uniform scale applied to the positions after loading.
    pub scale: f64,
    /// Accept non-manifold edges and vertices instead of refusing the mesh.
    pub allow_nonmanifold: bool,
    /// What to do with zero-area faces.
    pub degenerate: DegeneratePolicy,
    /// Accept faces oriented inconsistently with a neighbour instead of refusing the mesh.
    pub allow_inconsistent_orientation: bool,
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
            allow_inconsistent_orientation: false,
        }
    }
}

impl LoadOptions {
    /// Options that accept every structural problem, to report it (what `inspect` uses).
    pub fn tolerant(mut self) -> Self {
        self.allow_nonmanifold = true;
        self.allow_inconsistent_orientation = true;
        self.degenerate = DegeneratePolicy::Drop;
        self
    }
}

/// The file formats grainline reads a mesh from.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, serde::Serialize)]
#[serde(rename_all = "lowercase")]
pub enum MeshFormat {
    /// Wavefront OBJ (text).
    #[default]
    Obj,
    /// STL, binary or ASCII.
    Stl,
    /// PLY, ASCII or binary (either byte order).
    Ply,
}

impl MeshFormat {
    /// The format's name as messages and reports write it (`obj`, `stl`, `ply`).
    pub fn as_str(self) -> &'static str {
        match self {
            MeshFormat::Obj => "obj",
            MeshFormat::Stl => "stl",
            MeshFormat::Ply => "ply",
        }
    }
}

/// What loading did to the file's contents.
#[derive(Clone, Debug, Default, serde::Serialize)]
pub struct LoadReport {
    /// The file's format.
    pub format: MeshFormat,
    /// Vertices as listed in the file.
    pub file_vertices: usize,
    /// Vertices removed because no face used them.
    pub unreferenced_vertices: usize,
    /// Vertices merged into another by welding.
    pub welded_vertices: usize,
    /// Zero-area faces dropped.
    pub dropped_degenerate_faces: usize,
    /// Triangles in the file (after splitting polygons, before dropping any).
    pub file_triangles: usize,
    /// Polygons with more than three corners that were split into triangles.
    pub polygons_split: usize,
    /// Object and group names in the file, in order, each once.
    pub objects: Vec<String>,
    /// Corners without a texture coordinate in a file with some (the UVs are then dropped).
    pub corners_without_uv: usize,
    /// Statements with an unknown keyword, ignored.
    pub ignored_statements: usize,
    /// Edges with three or more faces (only non-zero when accepted).
    pub nonmanifold_edges: usize,
    /// Vertices whose faces form several fans (only non-zero when accepted).
    pub nonmanifold_vertices: usize,
    /// Edges whose two faces are oriented inconsistently (only non-zero when accepted).
    pub inconsistent_orientation_edges: usize,
    /// 1-based file `v` number of every mesh vertex (for STL and PLY: 1 + its 0-based place
    /// among the file's vertices, three per triangle in an STL).
    #[serde(skip)]
    pub source_vertex: Vec<u32>,
    /// 1-based line of the `f` statement of every mesh face (of its facet or element in an
    /// ASCII STL or PLY; 0 in a binary file).
    #[serde(skip)]
    pub face_line: Vec<u32>,
    /// The file's number of every mesh face's element: the 1-based triangle of an STL, the
    /// 0-based face element of a PLY; empty for an OBJ.
    #[serde(skip)]
    pub face_index: Vec<u32>,
}

/// A loaded mesh and the report of what loading did.
#[derive(Clone, Debug)]
pub struct LoadedMesh {
    /// The mesh, in scene units.
    pub mesh: Mesh,
    /// What loading changed.
    pub report: LoadReport,
}
