//! Planar regions: the flat faces of a part as a CAD export meshes them (docs/math.md §3,
//! "Flat regions").
//!
//! A CAD system meshes a flat face of a part with no vertex inside it: a fan of slivers from
//! rim to rim, every vertex on the face's outline. Where the face meets a fillet or a gently
//! curved face tangentially, its vertices are shared with that face's first strip, and an
//! averaged normal leans towards the curve by half the strip's step — on every vertex of the
//! face, so the whole face shades, projects a grain and highlights as if it were curved.
//!
//! A *planar region* is a set of faces joined across manifold edges whose unit normals agree
//! with the region's first face within [`FLAT_COS`] (10⁻⁴ rad). A vertex on several regions
//! takes the plane of the *widest* one (width w = 2·area / perimeter: the plane a fillet's
//! strips meet is many times wider than a strip) when it is [`WIDER`] times wider than every
//! other region there, holds at least two faces, and no face at the vertex leans more than
//! 30° from it ([`TANGENT_COS`]: a tangent blend, not a crease). The tangent plane of a
//! surface that a fillet meets tangentially is the flat face's own, so that is exact there;
//! strips of equal width (a fillet's or a cylinder's inside, a curved grid's planar quads)
//! leave their vertices to the averaged normal.

use nalgebra::Vector3;
use rayon::prelude::*;

use super::{Mesh, VertexFaces};

/// Faces whose unit normals agree this closely (within 1e-4 rad) lie in one plane (here, in
/// refinement and in the geometry's flat regions).
pub const FLAT_COS: f64 = 1.0 - 5e-9;

/// Beyond this angle from a flat face's plane, a face meets it at a crease, not tangentially.
pub const TANGENT_COS: f64 = 0.866_025_403_784_438_6; // cos 30°

/// How many times wider than every other region at a vertex a planar region must be to fix
/// the vertex's normal.
pub const WIDER: f64 = 4.0;

/// No region: a face of zero area.
pub const NO_REGION: u32 = u32::MAX;

/// The planar regions of a mesh.
#[derive(Clone, Debug, PartialEq)]
pub struct PlanarRegions {
    /// The region of each face ([`NO_REGION`] for a face of zero area), numbered in the order
    /// of their first faces.
    pub face_region: Vec<u32>,
    /// Per region: its first face's unit normal.
    pub normal: Vec<Vector3<f64>>,
    /// Per region: the number of its faces.
    pub faces: Vec<u32>,
    /// Per region: twice its area over its perimeter.
    pub width: Vec<f64>,
}

/// The unit normal of face `f`, or `None` for a face of zero area.
fn face_normal(mesh: &Mesh, f: usize) -> Option<Vector3<f64>> {
    let [a, b, c] = mesh.face_positions(f);
    let n = (b - a).cross(&(c - a));
    let len = n.norm();
    (len > 0.0 && len.is_finite()).then(|| n / len)
}

/// Per face, the face across each of its edges (edge k joins corners k and k + 1), or
/// [`NO_REGION`] on a boundary or non-manifold edge (it joins nothing). Sorting the edges
/// keeps this O(F log F) whatever the valences (a polygon fanned from one corner).
fn face_neighbours(mesh: &Mesh) -> Vec<[u32; 3]> {
    let mut edges: Vec<(u32, u32, u32, u8)> = Vec::with_capacity(3 * mesh.num_faces());
    for (f, t) in mesh.faces.iter().enumerate() {
        for k in 0..3 {
            let (a, b) = (t[k], t[(k + 1) % 3]);
            edges.push((a.min(b), a.max(b), f as u32, k as u8));
        }
    }
    // Keys are distinct, so the unstable sort's order is the same at any thread count.
    edges.par_sort_unstable();
    let mut out = vec![[NO_REGION; 3]; mesh.num_faces()];
    for run in edges.chunk_by(|x, y| (x.0, x.1) == (y.0, y.1)) {
        if let [x, y] = run {
            out[x.2 as usize][x.3 as usize] = y.2;
            out[y.2 as usize][y.3 as usize] = x.2;
        }
    }
    out
}

/// Groups `mesh`'s faces into planar regions (module docs). O(F log F); the same result at
/// any thread count.
pub fn planar_regions(mesh: &Mesh) -> PlanarRegions {
    planar_regions_within(mesh, 0.0)
}

/// [`planar_regions`], where a face also joins a region when its corners lie within `eps` of
/// the plane of the region's first face (and it faces the same way): the file's rounding
/// tilts a narrow chord's normal by more than [`FLAT_COS`] (a six-digit quad 0.3 mm wide, by
/// 2·10⁻⁴ rad), not its corners off the plane. `eps` = 0 is [`planar_regions`].
pub fn planar_regions_within(mesh: &Mesh, eps: f64) -> PlanarRegions {
    let nf = mesh.num_faces();
    let normals: Vec<Option<Vector3<f64>>> =
        (0..nf).into_par_iter().map(|f| face_normal(mesh, f)).collect();
    let neighbours = face_neighbours(mesh);
    let mut face_region = vec![NO_REGION; nf];
    let (mut normal, mut faces) = (Vec::new(), Vec::new());
    let mut stack = Vec::new();
    for seed in 0..nf {
        let Some(n) = normals[seed] else { continue };
        if face_region[seed] != NO_REGION {
            continue;
        }
        let r = normal.len() as u32;
        let offset = n.dot(&mesh.positions[mesh.faces[seed][0] as usize]);
        let on_plane = |g: usize| {
            eps > 0.0
                && mesh.faces[g]
                    .iter()
                    .all(|&v| (n.dot(&mesh.positions[v as usize]) - offset).abs() <= eps)
        };
        face_region[seed] = r;
        let mut count = 1u32;
        stack.push(seed as u32);
        while let Some(f) = stack.pop() {
            for &g in &neighbours[f as usize] {
                if g == NO_REGION || face_region[g as usize] != NO_REGION {
                    continue;
                }
                let joins = normals[g as usize].is_some_and(|m| {
                    m.dot(&n) >= FLAT_COS || (m.dot(&n) > 0.0 && on_plane(g as usize))
                });
                if joins {
                    face_region[g as usize] = r;
                    count += 1;
                    stack.push(g);
                }
            }
        }
        normal.push(n);
        faces.push(count);
    }
    let width = widths(mesh, &face_region, &neighbours, normal.len());
    PlanarRegions { face_region, normal, faces, width }
}

/// Per region: 2·area / perimeter (the perimeter counts every edge of a region's face whose
/// other side is not in the region).
fn widths(mesh: &Mesh, face_region: &[u32], neighbours: &[[u32; 3]], count: usize) -> Vec<f64> {
    let (mut area, mut perimeter) = (vec![0.0; count], vec![0.0; count]);
    for (f, &r) in face_region.iter().enumerate() {
        if r == NO_REGION {
            continue;
        }
        let p = mesh.face_positions(f);
        area[r as usize] += 0.5 * (p[1] - p[0]).cross(&(p[2] - p[0])).norm();
        for k in 0..3 {
            let g = neighbours[f][k];
            if g == NO_REGION || face_region[g as usize] != r {
                perimeter[r as usize] += (p[(k + 1) % 3] - p[k]).norm();
            }
        }
    }
    area.iter().zip(&perimeter).map(|(a, p)| if *p > 0.0 { 2.0 * a / p } else { 0.0 }).collect()
}

impl PlanarRegions {
    /// Per vertex, the region whose plane fixes its normal (module docs), or `None`: the
    /// widest of the regions its faces lie in, when it holds at least two faces, is [`WIDER`]
    /// times wider than every region not coplanar with it, and no face at the vertex leans
    /// more than 30° from its plane; and a vertex whose faces all lie in a region that fixes
    /// some vertex by that rule (a face of the part, not a strip of a curved face).
    pub fn vertex_planes(&self, mesh: &Mesh, vf: &VertexFaces) -> Vec<Option<u32>> {
        let mut planes: Vec<Option<u32>> =
            (0..mesh.num_vertices()).into_par_iter().map(|v| self.vertex_plane(vf, v)).collect();
        // A region that fixes a vertex is a face of the part, not a strip: it fixes the
        // vertices on it alone too, whose jet fit would otherwise reach past its rim (a
        // flat face's corner fanned to the far side of a tangent bend) and tilt them.
        let mut is_face = vec![false; self.normal.len()];
        for r in planes.iter().flatten() {
            is_face[*r as usize] = true;
        }
        for (v, p) in planes.iter_mut().enumerate() {
            if p.is_none() {
                let mut regions = vf.of(v).iter().map(|&(f, _)| self.face_region[f as usize]);
                if let Some(r) = regions.next() {
                    if r != NO_REGION && is_face[r as usize] && regions.all(|q| q == r) {
                        *p = Some(r);
                    }
                }
            }
        }
        planes
    }

    fn vertex_plane(&self, vf: &VertexFaces, v: usize) -> Option<u32> {
        let regions = || {
            vf.of(v).iter().map(|&(f, _)| self.face_region[f as usize]).filter(|&r| r != NO_REGION)
        };
        let first = regions().next()?;
        if regions().all(|r| r == first) {
            return None;
        }
        let best = regions().reduce(|a, b| {
            let (wa, wb) = (self.width[a as usize], self.width[b as usize]);
            if wb > wa || (wb == wa && b < a) {
                b
            } else {
                a
            }
        })?;
        let (n, w) = (self.normal[best as usize], self.width[best as usize]);
        if self.faces[best as usize] < 2 {
            return None;
        }
        let fits = regions().all(|r| {
            let m = self.normal[r as usize];
            r == best
                || (m.dot(&n) >= TANGENT_COS
                    && (m.dot(&n) >= FLAT_COS || w >= WIDER * self.width[r as usize]))
        });
        fits.then_some(best)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A flat face 0 ≤ x ≤ 10, 0 ≤ y ≤ 4 meshed as two triangles, meeting along x = 10 a
    /// fillet of radius 1 bending down in `steps` strips of 90°/steps each.
    fn plane_and_fillet(steps: usize) -> Mesh {
        let mut p = vec![
            Vector3::new(0.0, 0.0, 0.0),
            Vector3::new(0.0, 4.0, 0.0),
            Vector3::new(10.0, 0.0, 0.0),
            Vector3::new(10.0, 4.0, 0.0),
        ];
        let mut faces = vec![[0, 2, 3], [0, 3, 1]];
        for s in 1..=steps {
            let a = s as f64 * std::f64::consts::FRAC_PI_2 / steps as f64;
            let (x, z) = (10.0 + a.sin(), a.cos() - 1.0);
            p.push(Vector3::new(x, 0.0, z));
            p.push(Vector3::new(x, 4.0, z));
            let (a0, a1, b0, b1) =
                (2 * s as u32, 2 * s as u32 + 1, 2 * s as u32 + 2, 2 * s as u32 + 3);
            faces.push([a0, b0, b1]);
            faces.push([a0, b1, a1]);
        }
        Mesh::from_triangles(p, faces)
    }

    #[test]
    fn the_plane_a_fillet_meets_fixes_its_rim_and_strips_fix_nothing() {
        let m = plane_and_fillet(6);
        let vf = VertexFaces::new(&m);
        let r = planar_regions(&m);
        // The plane, and each strip's two triangles.
        assert_eq!(r.normal.len(), 7);
        assert_eq!(r.faces[0], 2);
        assert!((r.width[0] - 2.0 * 40.0 / 28.0).abs() < 1e-12);
        let planes = r.vertex_planes(&m, &vf);
        // The rim x = 10 takes the plane; the fillet's inner vertices are on two strips of one
        // width.
        assert_eq!(planes[2], Some(0));
        assert_eq!(planes[3], Some(0));
        // The plane's far side lies on the plane alone, a plane that fixes its rim.
        assert_eq!(planes[0], Some(0));
        assert_eq!(planes[1], Some(0));
        assert!(planes[4..].iter().all(|p| p.is_none()));
    }

    #[test]
    fn a_crease_or_a_narrow_plane_fixes_nothing() {
        // One strip of 90°: its chord meets the plane at a crease of 45°.
        let m = plane_and_fillet(1);
        let vf = VertexFaces::new(&m);
        let r = planar_regions(&m);
        assert!(r.vertex_planes(&m, &vf).iter().all(|p| p.is_none()));
        // A cylinder's planar quads: every vertex between strips of one width.
        let c = crate::generate::cylinder(10.0, 20.0, 32, 4);
        let vf = VertexFaces::new(&c);
        let r = planar_regions(&c);
        assert!(r.vertex_planes(&c, &vf).iter().all(|p| p.is_none()));
    }
}
