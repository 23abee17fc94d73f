//! Cotangent edge weights wᵢⱼ = ½(cot α + cot β), clamped at zero.
//!
//! α and β are the angles opposite edge i–j in its (one or two) triangles. The clamp keeps the
//! connection Dirichlet energy Σ wᵢⱼ |e^{ikφⱼ} − e^{ik(φᵢ − ρᵢⱼ)}|² non-negative on meshes with
//! obtuse triangles (math.md §4).

use rayon::prelude::*;

use crate::mesh::{Adjacency, Mesh};

/// Cotangent weight of every adjacency slot (the same value on both directions of an edge).
pub fn cotan_weights(mesh: &Mesh, adj: &Adjacency) -> Vec<f64> {
    // Per face: the cotangent at each corner, attributed to the opposite edge.
    let face_cots: Vec<[f64; 3]> = (0..mesh.num_faces())
        .into_par_iter()
        .map(|f| {
            let p = mesh.face_positions(f);
            let mut c = [0.0; 3];
            for (k, ck) in c.iter_mut().enumerate() {
                let (a, b) = (p[(k + 1) % 3] - p[k], p[(k + 2) % 3] - p[k]);
                let cross = a.cross(&b).norm();
                *ck = if cross > 0.0 { a.dot(&b) / cross } else { 0.0 };
            }
            c
        })
        .collect();
    let mut w = vec![0.0; adj.num_slots()];
    for (f, tri) in mesh.faces.iter().enumerate() {
        for k in 0..3 {
            let (i, j) = (tri[(k + 1) % 3] as usize, tri[(k + 2) % 3]);
            if let Some(s) = adj.slot(i, j) {
                w[s] += 0.5 * face_cots[f][k];
            }
        }
    }
    // Symmetrize exactly and clamp.
    (0..w.len())
        .map(|s| {
            // Each direction of an edge collected the ½cot of the face where it runs i → j.
            (w[s] + w[adj.reverse(s)]).max(0.0)
        })
        .collect()
}
