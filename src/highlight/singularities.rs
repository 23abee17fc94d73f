//! Singularities of a vertex-based direction field: faces whose index is not 0.
//!
//! Around triangle (a, b, c), each edge i → j contributes the transported angle difference
//! wrapped to (−π/k, π/k], wrap_k(φⱼ + ρᵢⱼ − φᵢ). Their sum minus the sum of the ρ's is an exact
//! multiple of 2π/k (the φ's telescope); the sum of the ρ's is the face's holonomy plus 2π times
//! the index of the *frame* field there, so the holonomy is wrap(Σρ) (the parallel-transport
//! rotation, small on a fine mesh). The field's index is
//!
//! ```text
//! index_f = (Σ_edges wrap_k(Δᵢⱼ) − wrap(Σ_edges ρᵢⱼ)) / 2π,   a multiple of 1/k,
//! ```
//!
//! +1 for u = (x, y)/r, −1 for (x, −y)/r, ±1/2 for half-turn line fields. On a closed surface
//! the indices add up to the Euler characteristic (Poincaré–Hopf).

use nalgebra::Vector3;
use serde::Serialize;

use crate::geometry::connection::wrap_angle;
use crate::geometry::Geometry;
use crate::mesh::Mesh;

/// One singular face.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct Singularity {
    /// The face.
    pub face: u32,
    /// Its centroid (the reported position).
    pub position: [f64; 3],
    /// The index, a non-zero multiple of 1/k.
    pub index: f64,
}

/// The singular faces of the field `phi` (angles in the geometry's frames) of symmetry `k`,
/// by increasing face.
pub fn singularities(mesh: &Mesh, geometry: &Geometry, phi: &[f64], k: u32) -> Vec<Singularity> {
    let mut out = Vec::new();
    for f in 0..mesh.num_faces() {
        let n = face_index(mesh, geometry, phi, f, k);
        if n != 0 {
            let p = mesh.face_positions(f);
            let c: Vector3<f64> = (p[0] + p[1] + p[2]) / 3.0;
            out.push(Singularity {
                face: f as u32,
                position: [c.x, c.y, c.z],
                index: n as f64 / k as f64,
            });
        }
    }
    out
}

/// The index of face `f` in units of 1/k (0 on a face with an edge the adjacency lacks, or with
/// a non-finite angle).
pub fn face_index(mesh: &Mesh, geometry: &Geometry, phi: &[f64], f: usize, k: u32) -> i32 {
    face_index_of(mesh, geometry, |v| phi[v], f, k)
}

/// [`face_index`] of the field whose angle at vertex v is `phi(v)`.
pub fn face_index_of(
    mesh: &Mesh,
    geometry: &Geometry,
    phi: impl Fn(usize) -> f64,
    f: usize,
    k: u32,
) -> i32 {
    let kf = k as f64;
    let adj = &geometry.adjacency;
    let tri = mesh.faces[f];
    let (mut sum_d, mut sum_rho) = (0.0, 0.0);
    for e in 0..3 {
        let (i, j) = (tri[e] as usize, tri[(e + 1) % 3]);
        let Some(s) = adj.slot(i, j) else { return 0 };
        let rho = geometry.transport[s];
        sum_rho += rho;
        sum_d += wrap_angle(kf * (phi(j as usize) + rho - phi(i))) / kf;
    }
    let turns = (sum_d - wrap_angle(sum_rho)) / std::f64::consts::TAU;
    let n = (turns * kf).round();
    if n.is_finite() {
        n as i32
    } else {
        0
    }
}
