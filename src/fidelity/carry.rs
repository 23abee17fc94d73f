//! Where the strokes must carry an edit (issue 47; docs/math.md §10, "Strokes that carry the
//! edit"): the points of an edit's designed key highlight that the placement leaves *between*
//! two strokes.
//!
//! The grain a brush leaves at a point p is the direction of the stroke that brushed it at the
//! foot q of p on that stroke (the grooves of a brush moved along a curve are its parallel
//! offsets, tangent to it at q). With g = hᵀu the key highlight's function (math.md §2), the
//! as-brushed g at p is therefore the designed g at q, up to the change of h between p and q:
//!
//! ```text
//! g_b(p) ≈ h(p)ᵀ u(q),   q = foot of p on its stroke
//! ```
//!
//! Where the designed highlight C = {g = 0} crosses the strokes, each stroke carries its own
//! zero and the rebuilt highlight steps from stroke to stroke by at most |q − p| cos α (α the
//! angle between C and the grain). Where C runs *along* the grain (α → 0) one stroke's band
//! holds a long stretch of C while g(q) stays away from zero, and the rebuilt highlight lands
//! wherever the band ends: up to half a spacing off. There the one placement that keeps C is a
//! stroke to either side of it: g(q) then has opposite signs on the two strokes and the
//! rebuilt highlight is the line between their bands — C itself when C lies midway.
//!
//! [`straddle_points`] lists the midpoints of the designed highlight's segments inside the
//! edits' supports where C meets the grain at less than [`MAX_STRADDLE_ANGLE_DEG`], most
//! nearly parallel first: the placement (`grainline_toolpaths::PlacementOptions::straddle`)
//! seeds a stroke half a spacing to either side of each, as long as both lie a spacing from
//! every stroke already placed.

use nalgebra::Vector3;

use super::segments::{corner_g, zero_segment};
use super::support_faces;
use crate::edit::EditReport;
use crate::highlight::Symmetry;
use crate::mesh::Mesh;

/// Segments of the highlight that meet the grain at less than this angle are straddled.
pub const MAX_STRADDLE_ANGLE_DEG: f64 = 30.0;

/// A point of an edit's designed key highlight to be left between two strokes.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct StraddlePoint {
    /// The face it lies on.
    pub face: usize,
    /// Its barycentric coordinates in that face.
    pub bary: [f64; 3],
    /// The angle between the highlight and the grain there, degrees (0: along the grain).
    pub angle_deg: f64,
}

/// The points of the designed key highlight (`h`, grain `u`: world unit vectors per vertex)
/// inside the supports of the edits with a shape (bend, expand, curve) where it runs within
/// [`MAX_STRADDLE_ANGLE_DEG`] of the grain: one per highlight segment, at its midpoint, sorted
/// by that angle (then by face).
pub fn straddle_points(
    mesh: &Mesh,
    h: &[Vector3<f64>],
    u: &[Vector3<f64>],
    symmetry: Symmetry,
    reports: &[EditReport],
) -> Vec<StraddlePoint> {
    let mut faces: Vec<usize> = reports
        .iter()
        .filter_map(|r| r.shape.as_ref())
        .flat_map(|s| support_faces(mesh, s.support()))
        .collect();
    faces.sort_unstable();
    faces.dedup();
    let n = mesh.num_vertices();
    let cos_max = MAX_STRADDLE_ANGLE_DEG.to_radians().cos();
    let mut out: Vec<StraddlePoint> = faces
        .into_iter()
        .filter_map(|f| {
            let face = mesh.faces.get(f)?;
            if face.iter().any(|&v| v as usize >= n) {
                return None;
            }
            let g = corner_g(face, h, u, symmetry)?;
            let p = mesh.face_positions(f);
            let [a, b] = zero_segment(&p, &g)?;
            let m = (a + b) * 0.5;
            let bary = barycentric(&p, &m)?;
            let grain = grain_at(face, u, symmetry, &bary, &p)?;
            let along = (b - a).try_normalize(0.0)?;
            let c = along.dot(&grain).abs();
            (c >= cos_max).then(|| StraddlePoint {
                face: f,
                bary,
                angle_deg: c.clamp(-1.0, 1.0).acos().to_degrees(),
            })
        })
        .collect();
    out.sort_by(|x, y| x.angle_deg.total_cmp(&y.angle_deg).then(x.face.cmp(&y.face)));
    out
}

/// Barycentric coordinates of `m` (in the plane of `p`); `None` for a degenerate triangle.
fn barycentric(p: &[Vector3<f64>; 3], m: &Vector3<f64>) -> Option<[f64; 3]> {
    let (e1, e2, d) = (p[1] - p[0], p[2] - p[0], m - p[0]);
    let (a, b, c) = (e1.dot(&e1), e1.dot(&e2), e2.dot(&e2));
    let (x, y) = (d.dot(&e1), d.dot(&e2));
    let det = a * c - b * b;
    if !(det.abs() > 0.0) {
        return None;
    }
    let (l1, l2) = ((c * x - b * y) / det, (a * y - b * x) / det);
    let out = [1.0 - l1 - l2, l1, l2];
    out.iter().all(|x| x.is_finite()).then_some(out)
}

/// The grain at barycentric `bary` of a face: its corners' directions blended (a line field's
/// aligned to the first corner) and projected onto the face's plane; `None` where that
/// vanishes.
fn grain_at(
    face: &[u32; 3],
    u: &[Vector3<f64>],
    symmetry: Symmetry,
    bary: &[f64; 3],
    p: &[Vector3<f64>; 3],
) -> Option<Vector3<f64>> {
    let first = *u.get(face[0] as usize)?;
    let mut sum = Vector3::zeros();
    for k in 0..3 {
        let mut uk = *u.get(face[k] as usize)?;
        if symmetry == Symmetry::Line && uk.dot(&first) < 0.0 {
            uk = -uk;
        }
        sum += uk * bary[k];
    }
    let normal = (p[1] - p[0]).cross(&(p[2] - p[0])).try_normalize(0.0)?;
    (sum - normal * normal.dot(&sum)).try_normalize(1e-12)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn barycentric_of_a_point_in_a_hand_triangle() {
        let p = [Vector3::zeros(), Vector3::new(2.0, 0.0, 0.0), Vector3::new(0.0, 4.0, 0.0)];
        let b = barycentric(&p, &Vector3::new(0.5, 1.0, 0.0)).unwrap();
        for (x, want) in b.iter().zip([0.5, 0.25, 0.25]) {
            assert!((x - want).abs() < 1e-12, "{b:?}");
        }
        assert!(barycentric(&[p[0], p[1], p[1] * 2.0], &p[0]).is_none());
    }
}
