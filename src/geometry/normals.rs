//! Per-vertex normals.
//!
//! The default is the angle-weighted normal (Thürmer & Wüthrich 1998): the sum of the incident
//! face normals weighted by the corner angle at the vertex. It is independent of how the
//! one-ring is triangulated, unlike the area-weighted one. The jet fit ([`super::curvature`])
//! refines it further.

use nalgebra::Vector3;
use rayon::prelude::*;

use crate::mesh::Mesh;
pub use crate::mesh::VertexFaces;

/// How the initial vertex normals are computed.
#[derive(
    Clone,
    Copy,
    Debug,
    Default,
    PartialEq,
    Eq,
    serde::Serialize,
    serde::Deserialize,
    schemars::JsonSchema,
)]
#[serde(rename_all = "kebab-case")]
pub enum NormalSource {
    /// Face normals weighted by the corner angle (the default).
    #[default]
    AngleWeighted,
    /// Face normals weighted by the face area.
    AreaWeighted,
    /// The file's normals (`vn`), averaged over the corners of each vertex; falls back to
    /// angle-weighted where the file has none.
    File,
}

/// The direction used where a vertex has no usable normal (an isolated vertex, or a vertex
/// whose faces all have zero area): +Z. Such vertices are counted by [`vertex_normals`].
pub const FALLBACK_NORMAL: Vector3<f64> = Vector3::new(0.0, 0.0, 1.0);

/// Unit face normals (zero vector for a zero-area face): the normals of [`face_data`].
pub fn face_normals(mesh: &Mesh) -> Vec<Vector3<f64>> {
    face_data(mesh).into_iter().map(|f| f.normal).collect()
}

/// A face's unit normal (zero for a zero-area face) and its interior angles at its three
/// corners, in the face's vertex order.
#[derive(Clone, Copy, Debug)]
pub struct FaceData {
    /// Unit normal, or zero.
    pub normal: Vector3<f64>,
    /// Interior angles (they add up to π).
    pub angles: [f64; 3],
}

/// [`FaceData`] of every face. The corner angles share the face's cross product:
/// αₐ = atan2(|e_ab × e_ac|, e_ab·e_ac), likewise at b, and α_c = π − αₐ − α_b (an absolute error
/// of a few ulps of π, which is what a normal weight needs; one atan2 and no cross product
/// fewer per corner than [`corner_angle`] at each corner).
pub fn face_data(mesh: &Mesh) -> Vec<FaceData> {
    (0..mesh.num_faces())
        .into_par_iter()
        .map(|f| {
            let [a, b, c] = mesh.face_positions(f);
            let (ab, ac, bc) = (b - a, c - a, c - b);
            let n = ab.cross(&ac);
            let len = n.norm();
            let normal = if len > 0.0 && len.is_finite() { n / len } else { Vector3::zeros() };
            let alpha = len.atan2(ab.dot(&ac));
            let beta = len.atan2(-ab.dot(&bc));
            let gamma = (std::f64::consts::PI - alpha - beta).max(0.0);
            FaceData { normal, angles: [alpha, beta, gamma] }
        })
        .collect()
}

/// Interior angle of a triangle at `a` (between `b − a` and `c − a`), robust for tiny angles.
#[inline]
pub fn corner_angle(a: &Vector3<f64>, b: &Vector3<f64>, c: &Vector3<f64>) -> f64 {
    let (u, v) = (b - a, c - a);
    u.cross(&v).norm().atan2(u.dot(&v))
}

/// Per-vertex unit normals and the number of vertices that took [`FALLBACK_NORMAL`].
///
/// Accumulates per face and reduces per vertex through `vertex_faces` so the sum order, and
/// hence every bit of the result, is independent of the thread count.
pub fn vertex_normals(
    mesh: &Mesh,
    vertex_faces: &VertexFaces,
    source: NormalSource,
) -> (Vec<Vector3<f64>>, usize) {
    vertex_normals_from_faces(mesh, vertex_faces, &face_data(mesh), source)
}

/// [`vertex_normals`] from the mesh's face normals and corner angles (as [`face_data`] gives
/// them).
pub fn vertex_normals_from_faces(
    mesh: &Mesh,
    vertex_faces: &VertexFaces,
    faces: &[FaceData],
    source: NormalSource,
) -> (Vec<Vector3<f64>>, usize) {
    let file_avg = match (source, &mesh.normals) {
        (NormalSource::File, Some(_)) => Some(file_vertex_normals(mesh, vertex_faces)),
        _ => None,
    };
    let normals: Vec<Vector3<f64>> = (0..mesh.num_vertices())
        .into_par_iter()
        .map(|v| {
            if let Some(n) = file_avg.as_ref().and_then(|f| f[v]) {
                return n;
            }
            let mut sum = Vector3::zeros();
            for &(f, c) in vertex_faces.of(v) {
                let face = &faces[f as usize];
                let w = match source {
                    NormalSource::AreaWeighted => {
                        let fv = mesh.faces[f as usize];
                        let p = |k: usize| mesh.positions[fv[(c as usize + k) % 3] as usize];
                        0.5 * (p(1) - p(0)).cross(&(p(2) - p(0))).norm()
                    }
                    _ => face.angles[c as usize],
                };
                sum += w * face.normal;
            }
            normalize_or(sum, FALLBACK_NORMAL)
        })
        .collect();
    let fallback = (0..mesh.num_vertices())
        .into_par_iter()
        .filter(|&v| {
            vertex_faces.of(v).iter().all(|&(f, _)| faces[f as usize].normal == Vector3::zeros())
        })
        .count();
    (normals, fallback)
}

fn file_vertex_normals(mesh: &Mesh, vf: &VertexFaces) -> Vec<Option<Vector3<f64>>> {
    let attr = mesh.normals.as_ref().expect("checked by caller");
    (0..mesh.num_vertices())
        .into_par_iter()
        .map(|v| {
            let sum: Vector3<f64> = vf
                .of(v)
                .iter()
                .map(|&(f, c)| attr.values[attr.corners[f as usize][c as usize] as usize])
                .sum();
            let n = sum.norm();
            (n > 1e-12 && n.is_finite()).then(|| sum / n)
        })
        .collect()
}

/// `v / |v|`, or `fallback` when `v` is zero or not finite.
#[inline]
pub fn normalize_or(v: Vector3<f64>, fallback: Vector3<f64>) -> Vector3<f64> {
    let n = v.norm();
    if n > 1e-300 && n.is_finite() {
        v / n
    } else {
        fallback
    }
}
