//! The key light's highlight as segments: the zero set of g = hᵀu per triangle, by linear
//! interpolation of g at the corners (line fields: the corners aligned to the first one).

use nalgebra::Vector3;

use crate::highlight::Symmetry;
use crate::mesh::Mesh;

/// g = hᵀu at the three corners of a face; line fields: corners aligned to the first one.
/// `None` if a corner is out of range, a value is not finite, or a corner has no grain (the
/// zero vector: a vertex no stroke brushed, which shows no anisotropic highlight).
pub(super) fn corner_g(
    face: &[u32; 3],
    h: &[Vector3<f64>],
    u: &[Vector3<f64>],
    symmetry: Symmetry,
) -> Option<[f64; 3]> {
    let idx = face.map(|v| v as usize);
    let ua = *u.get(idx[0])?;
    let mut g = [0.0; 3];
    for k in 0..3 {
        let mut uk = *u.get(idx[k])?;
        if uk.norm_squared() == 0.0 {
            return None;
        }
        if symmetry == Symmetry::Line && k > 0 && uk.dot(&ua) < 0.0 {
            uk = -uk;
        }
        g[k] = h.get(idx[k])?.dot(&uk);
    }
    g.iter().all(|x| x.is_finite()).then_some(g)
}

/// The zero segment of the linear interpolant of `g` over triangle `p` (g ≥ 0 counts as
/// positive); `None` if every corner has the same sign or the segment has no length.
pub(super) fn zero_segment(p: &[Vector3<f64>; 3], g: &[f64; 3]) -> Option<[Vector3<f64>; 2]> {
    let pos = g.map(|x| x >= 0.0);
    let lone = (0..3).find(|&k| pos[k] != pos[(k + 1) % 3] && pos[k] != pos[(k + 2) % 3])?;
    let at = |j: usize| {
        let t = g[lone] / (g[lone] - g[j]);
        p[lone] + (p[j] - p[lone]) * t
    };
    let (a, b) = (at((lone + 1) % 3), at((lone + 2) % 3));
    let ok = (a - b).norm_squared() > 0.0 && a.iter().chain(b.iter()).all(|c| c.is_finite());
    ok.then_some([a, b])
}

/// Zero set of g = hᵀu per triangle (linear interpolation of g at the corners; line fields:
/// corners aligned to the first corner's direction first). World-space segments, in face
/// order; faces with a non-finite value (or `h`, `u` too short) give none.
pub fn highlight_segments(
    mesh: &Mesh,
    h: &[Vector3<f64>],
    u: &[Vector3<f64>],
    symmetry: Symmetry,
) -> Vec<[Vector3<f64>; 2]> {
    let faces: Vec<usize> = (0..mesh.num_faces()).collect();
    segments_on(mesh, h, u, symmetry, &faces)
}

/// [`highlight_segments`] on the faces `faces` alone (face indices, ascending for a result in
/// face order): each segment with its face, the same bits as the whole part's (the editor's
/// drag steps recompute the faces around the vertices they change).
pub fn highlight_segments_of_faces(
    mesh: &Mesh,
    h: &[Vector3<f64>],
    u: &[Vector3<f64>],
    symmetry: Symmetry,
    faces: &[usize],
) -> Vec<(usize, [Vector3<f64>; 2])> {
    indexed_segments(mesh, h, u, symmetry, faces).into_iter().map(|(k, s)| (faces[k], s)).collect()
}

pub(super) fn segments_on(
    mesh: &Mesh,
    h: &[Vector3<f64>],
    u: &[Vector3<f64>],
    symmetry: Symmetry,
    faces: &[usize],
) -> Vec<[Vector3<f64>; 2]> {
    indexed_segments(mesh, h, u, symmetry, faces).into_iter().map(|(_, s)| s).collect()
}

/// [`segments_on`], each with the index in `faces` of its face.
pub(super) fn indexed_segments(
    mesh: &Mesh,
    h: &[Vector3<f64>],
    u: &[Vector3<f64>],
    symmetry: Symmetry,
    faces: &[usize],
) -> Vec<(usize, [Vector3<f64>; 2])> {
    let n = mesh.num_vertices();
    faces
        .iter()
        .enumerate()
        .filter_map(|(k, &f)| {
            let face = mesh.faces.get(f)?;
            if face.iter().any(|&v| v as usize >= n) {
                return None;
            }
            let g = corner_g(face, h, u, symmetry)?;
            Some((k, zero_segment(&mesh.face_positions(f), &g)?))
        })
        .collect()
}

/// [`segments_on`], with the unit normal of each segment's face.
pub(super) fn segments_with_normals(
    mesh: &Mesh,
    h: &[Vector3<f64>],
    u: &[Vector3<f64>],
    symmetry: Symmetry,
    faces: &[usize],
) -> (Vec<[Vector3<f64>; 2]>, Vec<Vector3<f64>>) {
    indexed_segments(mesh, h, u, symmetry, faces)
        .into_iter()
        .map(|(k, s)| {
            let p = mesh.face_positions(faces[k]);
            let normal =
                (p[1] - p[0]).cross(&(p[2] - p[0])).try_normalize(1e-300).unwrap_or_default();
            (s, normal)
        })
        .unzip()
}
