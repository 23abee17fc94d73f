//! The crate's input: a triangle mesh in UV carrying a direction field ([`FieldMesh`]) and
//! its parts; validated into a [`Domain`](crate::Domain) by `mesh.rs`.

use serde::{Deserialize, Serialize};

use crate::error::{Result, ToolpathError};
use crate::geom::{Metric, Vec2, Vec3};
use std::sync::Arc;

/// Index of a UV vertex.
#[derive(Clone, Copy, Debug, PartialEq, Eq, PartialOrd, Ord, Hash, Serialize, Deserialize)]
pub struct VertexId(pub u32);

/// Index of a UV triangle.
#[derive(Clone, Copy, Debug, PartialEq, Eq, PartialOrd, Ord, Hash, Serialize, Deserialize)]
pub struct FaceId(pub u32);

/// Rotational symmetry of the direction field.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "lowercase")]
pub enum Symmetry {
    /// k = 1: an oriented vector field; strokes follow the arrows.
    Vector,
    /// k = 2: a line field (`d ≡ −d`); corners are aligned to the current heading before
    /// interpolation, so a stroke never reverses.
    Line,
}

impl Symmetry {
    /// `k = 1 → Vector`, `k = 2 → Line`; any other k is an error.
    pub fn from_k(k: u32) -> Result<Symmetry> {
        match k {
            1 => Ok(Symmetry::Vector),
            2 => Ok(Symmetry::Line),
            _ => Err(ToolpathError::InvalidOption {
                name: "symmetry",
                value: k as f64,
                reason: "only k = 1 (vector) and k = 2 (line) fields are supported",
            }),
        }
    }
}

/// Per-vertex directions, expressed in UV coordinates.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(rename_all = "lowercase")]
pub enum Directions {
    /// A UV vector per vertex. Its length matters only near zero: a vanishing vector marks a
    /// singularity.
    Vectors(Vec<Vec2>),
    /// An angle per vertex, radians counter-clockwise from the +U axis (unit length).
    Angles(Vec<f64>),
}

/// Two boundary edges of the UV layout that are the same edge on the part (a UV seam):
/// vertex `a[0]` is glued to `b[0]` and `a[1]` to `b[1]`.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize)]
pub struct SeamPair {
    /// One side of the seam (two UV vertex indices).
    pub a: [u32; 2],
    /// The other side, corresponding vertex by vertex.
    pub b: [u32; 2],
}

/// The crate's input: a UV triangle mesh with a direction field and optional 3D lift.
///
/// UV coordinates are in millimetres for flat-sheet work. When a `metric` (or 3D
/// `positions`, from which it is derived) is given, lengths are measured on the part instead.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct FieldMesh {
    /// UV position per vertex.
    pub uv: Vec<Vec2>,
    /// Triangles as vertex indices (either orientation; mirrored charts are fine).
    pub triangles: Vec<[u32; 3]>,
    /// Direction per vertex.
    pub directions: Directions,
    /// k = 1 or 2.
    pub symmetry: Symmetry,
    /// Optional 3D position per vertex (mm), the lift back onto the part.
    pub positions: Option<Vec<Vec3>>,
    /// Optional 3D unit normal per vertex, for surface following and tilt checks.
    pub normals: Option<Vec<Vec3>>,
    /// Optional first fundamental form per triangle; derived from `positions` when absent,
    /// identity when both are absent.
    pub metric: Option<Vec<Metric>>,
    /// UV seams across which strokes may continue (see [`crate::TraceOptions::cross_seams`]).
    pub seams: Vec<SeamPair>,
    /// Optional per triangle, the grain at its three corners as ambient 3D vectors: with a
    /// [`FieldMesh::surface`], the field inside a triangle on a known surface is their blend
    /// projected onto the surface's tangent plane (`surface.rs`) rather than the UV
    /// directions' blend; `None` for a triangle that keeps the UV blend.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub ambient: Option<Vec<Option<[Vec3; 3]>>>,
    /// The surface each triangle approximates, when the caller knows it: strokes' 3D points
    /// are put on it rather than on the chords (`surface.rs`). Not serialized.
    #[serde(skip)]
    pub surface: Option<SurfaceHook>,
}

impl FieldMesh {
    /// A flat field mesh: UV in mm, no lift, identity metric.
    pub fn new(
        uv: Vec<Vec2>,
        triangles: Vec<[u32; 3]>,
        directions: Directions,
        symmetry: Symmetry,
    ) -> FieldMesh {
        FieldMesh {
            uv,
            triangles,
            directions,
            symmetry,
            positions: None,
            normals: None,
            metric: None,
            seams: Vec::new(),
            ambient: None,
            surface: None,
        }
    }

    /// Attach per-vertex 3D positions and (optionally) normals.
    pub fn with_lift(mut self, positions: Vec<Vec3>, normals: Option<Vec<Vec3>>) -> FieldMesh {
        self.positions = Some(positions);
        self.normals = normals;
        self
    }

    /// Attach a per-triangle first fundamental form.
    pub fn with_metric(mut self, metric: Vec<Metric>) -> FieldMesh {
        self.metric = Some(metric);
        self
    }

    /// Attach the surfaces the triangles approximate and their corners' ambient grain (with
    /// a lift: [`FieldMesh::with_lift`]).
    pub fn with_surface(
        mut self,
        surface: SurfaceHook,
        ambient: Vec<Option<[Vec3; 3]>>,
    ) -> FieldMesh {
        self.surface = Some(surface);
        self.ambient = Some(ambient);
        self
    }

    /// Attach UV seam pairs.
    pub fn with_seams(mut self, seams: Vec<SeamPair>) -> FieldMesh {
        self.seams = seams;
        self
    }
}

/// The surface each triangle of a [`crate::FieldMesh`] approximates.
pub trait SurfaceLift: Send + Sync {
    /// The point of the surface triangle `face` approximates nearest to `p` (a point of the
    /// triangle's chord plane) and the surface's unit normal there (either sign); `None`
    /// where the triangle is the surface (a plane, an unrecognized face).
    fn project(&self, face: u32, p: Vec3) -> Option<(Vec3, Vec3)>;
}

/// A shared [`SurfaceLift`] carried by a [`crate::FieldMesh`] (not serialized: a field mesh
/// read from JSON lifts onto its chords; `surface.rs`).
#[derive(Clone)]
pub struct SurfaceHook(pub Arc<dyn SurfaceLift>);

impl std::fmt::Debug for SurfaceHook {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str("SurfaceHook")
    }
}

impl PartialEq for SurfaceHook {
    fn eq(&self, other: &Self) -> bool {
        std::ptr::addr_eq(Arc::as_ptr(&self.0), Arc::as_ptr(&other.0))
    }
}

impl SurfaceHook {
    /// `p` on face `f`'s surface, with its normal, when both are finite.
    pub(crate) fn project(&self, f: u32, p: Vec3) -> Option<(Vec3, Vec3)> {
        let (q, n) = self.0.project(f, p)?;
        (q.iter().chain(&n).all(|x| x.is_finite())).then_some((q, n))
    }
}
