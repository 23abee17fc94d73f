//! Triangle meshes: the data grainline works on, how they are loaded and validated, and their
//! connectivity.
//!
//! A [`Mesh`] is an indexed triangle mesh in scene units. Faces are counter-clockwise seen from
//! the side their normal points to (right-hand rule). UVs and file normals, when present, are
//! attributes *per face corner*, so seams and hard edges are represented exactly.

pub mod adjacency;
pub(crate) mod degenerate;
pub mod halfedge;
pub mod load;
mod loaded;
mod parse;
pub mod planar;
mod ply;
mod raw;
pub mod refine;
pub mod report;
mod scan;
mod scan_parallel;
mod stl;
pub mod topology;
pub(crate) mod union_find;
pub mod uv_charts;
pub(crate) mod validate;
pub mod vertex_faces;
pub mod weld;
pub mod write;

pub use adjacency::Adjacency;
pub use vertex_faces::VertexFaces;

use nalgebra::{Vector2, Vector3};
use serde::{Deserialize, Serialize};

/// Index of a vertex of a [`Mesh`].
#[derive(Clone, Copy, Debug, PartialEq, Eq, PartialOrd, Ord, Hash, Serialize, Deserialize)]
pub struct VertexId(pub u32);

/// Index of a triangle of a [`Mesh`].
#[derive(Clone, Copy, Debug, PartialEq, Eq, PartialOrd, Ord, Hash, Serialize, Deserialize)]
pub struct FaceId(pub u32);

impl VertexId {
    /// The index as `usize`.
    #[inline]
    pub fn index(self) -> usize {
        self.0 as usize
    }
}

impl FaceId {
    /// The index as `usize`.
    #[inline]
    pub fn index(self) -> usize {
        self.0 as usize
    }
}

/// Length unit of a mesh and of every length grainline writes.
#[derive(
    Clone, Copy, Debug, Default, PartialEq, Eq, Serialize, Deserialize, schemars::JsonSchema,
)]
#[serde(rename_all = "lowercase")]
pub enum Units {
    /// Millimetres (the default: what CNC machines and sheet-metal drawings use).
    #[default]
    Mm,
    /// Centimetres.
    Cm,
    /// Metres.
    M,
    /// Inches.
    In,
}

impl Units {
    /// Length of one unit in millimetres.
    pub fn in_mm(self) -> f64 {
        match self {
            Units::Mm => 1.0,
            Units::Cm => 10.0,
            Units::M => 1000.0,
            Units::In => 25.4,
        }
    }

    /// The unit's short name as written in files (`mm`, `cm`, `m`, `in`).
    pub fn as_str(self) -> &'static str {
        match self {
            Units::Mm => "mm",
            Units::Cm => "cm",
            Units::M => "m",
            Units::In => "in",
        }
    }
}

impl std::str::FromStr for Units {
    type Err = crate::Error;
    fn from_str(s: &str) -> crate::Result<Self> {
        match s {
            "mm" => Ok(Units::Mm),
            "cm" => Ok(Units::Cm),
            "m" => Ok(Units::M),
            "in" => Ok(Units::In),
            _ => Err(crate::Error::invalid_arg(
                "units",
                format!("unknown unit {s:?}; expected mm, cm, m or in"),
            )),
        }
    }
}

/// A per-face-corner attribute: `values[corners[f][c]]` is the value at corner `c` of face `f`.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct CornerAttribute<T> {
    /// The distinct attribute values.
    pub values: Vec<T>,
    /// For each face, the index into `values` of each of its three corners.
    pub corners: Vec<[u32; 3]>,
}

impl<T: Copy> CornerAttribute<T> {
    /// The values at the three corners of face `f`.
    #[inline]
    pub fn face(&self, f: usize) -> [T; 3] {
        let c = self.corners[f];
        [self.values[c[0] as usize], self.values[c[1] as usize], self.values[c[2] as usize]]
    }
}

/// An indexed triangle mesh in scene units.
#[derive(Clone, Debug, Default)]
pub struct Mesh {
    /// Vertex positions.
    pub positions: Vec<Vector3<f64>>,
    /// Triangles as vertex indices, counter-clockwise around their outward normal.
    pub faces: Vec<[u32; 3]>,
    /// Texture coordinates per face corner (the OBJ `vt`), if the file has them.
    pub uv: Option<CornerAttribute<Vector2<f64>>>,
    /// Normals per face corner (the OBJ `vn`), if the file has them.
    pub normals: Option<CornerAttribute<Vector3<f64>>>,
    /// The unit of `positions`.
    pub units: Units,
}

impl Mesh {
    /// Builds a mesh from positions and triangles, without UVs or normals.
    pub fn from_triangles(positions: Vec<Vector3<f64>>, faces: Vec<[u32; 3]>) -> Self {
        Mesh { positions, faces, ..Default::default() }
    }

    /// Number of vertices.
    #[inline]
    pub fn num_vertices(&self) -> usize {
        self.positions.len()
    }

    /// Number of triangles.
    #[inline]
    pub fn num_faces(&self) -> usize {
        self.faces.len()
    }

    /// The three corner positions of face `f`.
    #[inline]
    pub fn face_positions(&self, f: usize) -> [Vector3<f64>; 3] {
        let [a, b, c] = self.faces[f];
        [self.positions[a as usize], self.positions[b as usize], self.positions[c as usize]]
    }

    /// Total surface area.
    pub fn area(&self) -> f64 {
        (0..self.num_faces())
            .map(|f| {
                let [a, b, c] = self.face_positions(f);
                0.5 * (b - a).cross(&(c - a)).norm()
            })
            .sum()
    }

    /// Axis-aligned bounding box `(min, max)`; `None` for a mesh without vertices.
    pub fn bounding_box(&self) -> Option<(Vector3<f64>, Vector3<f64>)> {
        let first = *self.positions.first()?;
        Some(self.positions.iter().fold((first, first), |(lo, hi), p| (lo.inf(p), hi.sup(p))))
    }

    /// Scales every position by `s` (units are unchanged).
    pub fn scale(&mut self, s: f64) {
        for p in &mut self.positions {
            *p *= s;
        }
    }
}
