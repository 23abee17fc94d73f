//! Mixed Voronoi vertex areas (Meyer, Desbrun, Schröder & Barr 2003, §3.3).
//!
//! Each triangle gives each corner its Voronoi share,
//! `A_a = (|ab|² cot γ + |ac|² cot β) / 8` (β, γ the angles at b and c),
//! unless the triangle is obtuse: then the obtuse corner takes half the triangle's area and the
//! two others a quarter each. The shares of a triangle add up to its area, so the vertex areas
//! sum to the surface area exactly (up to rounding).

use nalgebra::Vector3;
use rayon::prelude::*;

use super::normals::VertexFaces;
use crate::mesh::Mesh;

/// The three corner shares of one triangle's area.
pub fn triangle_corner_areas(p: [Vector3<f64>; 3]) -> [f64; 3] {
    let e = [p[2] - p[1], p[0] - p[2], p[1] - p[0]]; // e[k] opposite corner k
    let l2 = [e[0].norm_squared(), e[1].norm_squared(), e[2].norm_squared()];
    let area = 0.5 * e[1].cross(&e[2]).norm();
    if area <= 0.0 || !area.is_finite() {
        return [0.0; 3];
    }
    // dot of the two edges leaving corner k: negative when corner k is obtuse.
    let corner_dot = |k: usize| -e[(k + 1) % 3].dot(&e[(k + 2) % 3]);
    if let Some(k) = (0..3).find(|&k| corner_dot(k) < 0.0) {
        let mut a = [0.25 * area; 3];
        a[k] = 0.5 * area;
        return a;
    }
    // cot of the angle at corner k = dot / (2 area).
    let cot = |k: usize| corner_dot(k) / (2.0 * area);
    [
        (l2[2] * cot(2) + l2[1] * cot(1)) / 8.0,
        (l2[0] * cot(0) + l2[2] * cot(2)) / 8.0,
        (l2[1] * cot(1) + l2[0] * cot(0)) / 8.0,
    ]
}

/// Mixed Voronoi area of every vertex.
pub fn vertex_areas(mesh: &Mesh, vf: &VertexFaces) -> Vec<f64> {
    let corner: Vec<[f64; 3]> = (0..mesh.num_faces())
        .into_par_iter()
        .map(|f| triangle_corner_areas(mesh.face_positions(f)))
        .collect();
    (0..mesh.num_vertices())
        .into_par_iter()
        .map(|v| vf.of(v).iter().map(|&(f, c)| corner[f as usize][c as usize]).sum())
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn right_isoceles_splits_by_voronoi() {
        // Right angle at corner 0: the circumcentre is the hypotenuse midpoint.
        let a = triangle_corner_areas([
            Vector3::zeros(),
            Vector3::new(1.0, 0.0, 0.0),
            Vector3::new(0.0, 1.0, 0.0),
        ]);
        assert!((a[0] - 0.25).abs() < 1e-15);
        assert!((a[1] - 0.125).abs() < 1e-15 && (a[2] - 0.125).abs() < 1e-15);
    }

    #[test]
    fn obtuse_rule() {
        let a = triangle_corner_areas([
            Vector3::zeros(),
            Vector3::new(2.0, 0.0, 0.0),
            Vector3::new(1.0, 0.2, 0.0),
        ]);
        let area = 0.2;
        assert!((a[2] - 0.5 * area).abs() < 1e-15);
        assert!((a[0] - 0.25 * area).abs() < 1e-15);
    }
}
