//! Smooth patches: the part cut along its sharp edges (docs/math.md §3, "Patches").
//!
//! A CAD export's flat faces, cylinders and fillets meet at sharp edges, and every vertex of a
//! flat face sits on one. A vertex normal averaged across such an edge tilts the face's frames
//! (up to 45° at a right angle), and with them the grain, ℓ and everything after. So the part
//! is split into patches first: two faces belong to one patch when a chain of edges whose
//! dihedral angle is at most the crease angle joins them. A vertex shared by k patches becomes
//! k vertices, one per patch (the first patch in face order keeps its index; the others are
//! appended, in vertex order), so each patch has its own normal, frame and grain there, and
//! nothing downstream averages across the edge.
//!
//! A sharp edge that does not separate two patches (a crease that ends inside a smooth
//! region, as on a scan's noise) splits nothing: the region stays one patch. A mesh without
//! sharp edges is returned as it was.

use nalgebra::Vector3;

use crate::mesh::planar::{planar_regions, NO_REGION};
use crate::mesh::Mesh;

/// The patches of a mesh.
#[derive(Clone, Debug, PartialEq)]
pub struct Patches {
    /// The patch of each face, numbered in the order of their first faces.
    pub face_patch: Vec<u32>,
    /// Number of patches.
    pub count: usize,
    /// Edges between two faces whose dihedral angle exceeds the crease angle.
    pub sharp_edges: usize,
}

/// The size of each patch: what a brush of a given width can reach.
#[derive(Clone, Debug, PartialEq)]
pub struct PatchSizes {
    /// Per patch, its area.
    pub area: Vec<f64>,
    /// Per patch, its width w = 2A/P: its area over half its perimeter (the sharp edges and
    /// boundary edges around it). A strip of width w has this width; a disk of radius ρ has
    /// ρ; a brush wider than w finds no room on the patch for a stroke.
    pub width: Vec<f64>,
}

impl Patches {
    /// The area and width of each patch of `mesh` (whose faces these patches number).
    pub fn sizes(&self, mesh: &Mesh) -> PatchSizes {
        let mut area = vec![0.0; self.count];
        let mut perimeter = vec![0.0; self.count];
        let mut edges: Vec<(u32, u32, u32)> = Vec::with_capacity(3 * mesh.num_faces());
        for (f, t) in mesh.faces.iter().enumerate() {
            let [a, b, c] = t.map(|v| mesh.positions[v as usize]);
            area[self.face_patch[f] as usize] += 0.5 * (b - a).cross(&(c - a)).norm();
            for k in 0..3 {
                let (u, v) = (t[k], t[(k + 1) % 3]);
                edges.push((u.min(v), u.max(v), f as u32));
            }
        }
        edges.sort_unstable();
        for run in edges.chunk_by(|x, y| (x.0, x.1) == (y.0, y.1)) {
            let len =
                (mesh.positions[run[0].1 as usize] - mesh.positions[run[0].0 as usize]).norm();
            // Each patch on this edge with no other face of its own there has it on its rim.
            for e in run {
                let p = self.face_patch[e.2 as usize];
                let own = run.iter().filter(|x| self.face_patch[x.2 as usize] == p).count();
                if own == 1 {
                    perimeter[p as usize] += len;
                }
            }
        }
        let width = area
            .iter()
            .zip(&perimeter)
            .map(|(a, p)| if *p > 0.0 { 2.0 * a / p } else { f64::INFINITY })
            .collect();
        PatchSizes { area, width }
    }
}

/// A patch whose area is below this share of the part's is not a face of the part but a
/// fold in its tessellation (a scan's noise, a dent): it joins the neighbour it shares the
/// most sharp edge length with.
pub const MIN_PATCH_AREA_SHARE: f64 = 1e-3;

/// Faces joined across every edge whose dihedral angle is at most `crease_angle_deg`
/// (≥ 180: one patch per connected component), then every patch smaller than
/// [`MIN_PATCH_AREA_SHARE`] of the part joined to the neighbour it shares the longest sharp
/// edges with. A face of zero area joins its neighbours.
pub fn patches(mesh: &Mesh, crease_angle_deg: f64) -> Patches {
    let cos_theta = crease_angle_deg.clamp(0.0, 180.0).to_radians().cos();
    let normal = |f: usize| {
        let [a, b, c] = mesh.faces[f].map(|v| mesh.positions[v as usize]);
        (b - a).cross(&(c - a)).try_normalize(0.0)
    };
    let normals: Vec<Option<Vector3<f64>>> = (0..mesh.num_faces()).map(normal).collect();
    let mut edges: Vec<(u32, u32, u32)> = Vec::with_capacity(3 * mesh.num_faces());
    for (f, t) in mesh.faces.iter().enumerate() {
        for k in 0..3 {
            let (a, b) = (t[k], t[(k + 1) % 3]);
            edges.push((a.min(b), a.max(b), f as u32));
        }
    }
    edges.sort_unstable();
    let mut parent: Vec<u32> = (0..mesh.num_faces() as u32).collect();
    let mut sharp: Vec<(u32, u32, f64)> = Vec::new();
    for run in edges.chunk_by(|x, y| (x.0, x.1) == (y.0, y.1)) {
        // Faces around one edge (two on a manifold edge): joined unless the edge is sharp.
        let first = run[0].2 as usize;
        for e in &run[1..] {
            let f = e.2 as usize;
            let is_sharp = match (normals[first], normals[f]) {
                (Some(a), Some(b)) => crease_angle_deg < 180.0 && a.dot(&b) < cos_theta,
                _ => false,
            };
            if is_sharp {
                let len =
                    (mesh.positions[run[0].1 as usize] - mesh.positions[run[0].0 as usize]).norm();
                sharp.push((first as u32, f as u32, len));
            } else {
                union(&mut parent, first as u32, f as u32);
            }
        }
    }
    let feature = planar_faces(mesh);
    join_small_patches(mesh, &mut parent, &sharp, &feature);
    let mut label = vec![u32::MAX; mesh.num_faces()];
    let mut face_patch = vec![0u32; mesh.num_faces()];
    let mut count = 0u32;
    for (f, patch) in face_patch.iter_mut().enumerate() {
        let r = find(&mut parent, f as u32) as usize;
        if label[r] == u32::MAX {
            label[r] = count;
            count += 1;
        }
        *patch = label[r];
    }
    let sharp_edges =
        sharp.iter().filter(|&&(a, b, _)| face_patch[a as usize] != face_patch[b as usize]).count();
    Patches { face_patch, count: count as usize, sharp_edges }
}

/// Per face, whether it lies in a planar region of at least two faces
/// ([`crate::mesh::planar`]): a face of a CAD part (a flat face, a strip of a cylinder or a
/// fillet meshed as quads) rather than of a scan, whose neighbouring triangles are never
/// coplanar to 10⁻⁴ rad.
fn planar_faces(mesh: &Mesh) -> Vec<bool> {
    let regions = planar_regions(mesh);
    regions.face_region.iter().map(|&r| r != NO_REGION && regions.faces[r as usize] >= 2).collect()
}

/// Joins every patch (root in `parent`) of less than [`MIN_PATCH_AREA_SHARE`] of the part's
/// area to the neighbour across the greatest length of `sharp` edges, smallest patch first —
/// unless every face of the patch, and every face across its sharp edges, is `feature` (a
/// small face of a CAD part: a chamfer, a notch, a small hole's wall, which a shop brushes as
/// a face of its own; joined, it would bend its neighbour's normals across the sharp edge
/// between them).
fn join_small_patches(
    mesh: &Mesh,
    parent: &mut [u32],
    sharp: &[(u32, u32, f64)],
    feature: &[bool],
) {
    let area = |f: usize| {
        let [a, b, c] = mesh.faces[f].map(|v| mesh.positions[v as usize]);
        0.5 * (b - a).cross(&(c - a)).norm()
    };
    let mut patch_area = vec![0.0f64; mesh.num_faces()];
    let mut total = 0.0;
    for f in 0..mesh.num_faces() {
        let a = area(f);
        patch_area[find(parent, f as u32) as usize] += a;
        total += a;
    }
    let mut all_feature = vec![true; mesh.num_faces()];
    for (f, &is) in feature.iter().enumerate() {
        all_feature[find(parent, f as u32) as usize] &= is;
    }
    // ... and every face across its sharp edges is of a CAD face too: a face of a CAD part
    // meets faces of the part. Two coplanar slivers standing on a scan or a sculpt (one
    // tetrahedron's cut, for a marching mesher) meet the mesher's triangles around them.
    for &(a, b, _) in sharp {
        let (ra, rb) = (find(parent, a), find(parent, b));
        if ra != rb {
            all_feature[ra as usize] &= feature[b as usize];
            all_feature[rb as usize] &= feature[a as usize];
        }
    }
    let mut small: Vec<(f64, u32)> = (0..mesh.num_faces() as u32)
        .filter(|&f| {
            parent[f as usize] == f
                && patch_area[f as usize] < MIN_PATCH_AREA_SHARE * total
                && !all_feature[f as usize]
        })
        .map(|f| (patch_area[f as usize], f))
        .collect();
    small.sort_by(|a, b| a.0.total_cmp(&b.0).then(a.1.cmp(&b.1)));
    for (_, root) in small {
        let r = find(parent, root);
        if patch_area[r as usize] >= MIN_PATCH_AREA_SHARE * total {
            continue; // grown by an earlier join
        }
        // The shared sharp length with each neighbouring patch.
        let mut shared: Vec<(u32, f64)> = Vec::new();
        for &(a, b, len) in sharp {
            let (ra, rb) = (find(parent, a), find(parent, b));
            let other = match (ra == r, rb == r) {
                (true, false) => rb,
                (false, true) => ra,
                _ => continue,
            };
            match shared.iter_mut().find(|(p, _)| *p == other) {
                Some(s) => s.1 += len,
                None => shared.push((other, len)),
            }
        }
        let best = shared.iter().copied().reduce(|x, y| {
            if y.1 > x.1 || (y.1 == x.1 && y.0 < x.0) {
                y
            } else {
                x
            }
        });
        if let Some((q, _)) = best {
            let joined = patch_area[r as usize] + patch_area[q as usize];
            union(parent, r, q);
            patch_area[find(parent, r) as usize] = joined;
        }
    }
}

fn find(parent: &mut [u32], mut x: u32) -> u32 {
    while parent[x as usize] != x {
        let p = parent[parent[x as usize] as usize];
        parent[x as usize] = p;
        x = p;
    }
    x
}

fn union(parent: &mut [u32], a: u32, b: u32) {
    let (ra, rb) = (find(parent, a), find(parent, b));
    if ra != rb {
        // The smaller root stays the root: the labels do not depend on the order of unions.
        let (lo, hi) = (ra.min(rb), ra.max(rb));
        parent[hi as usize] = lo;
    }
}

/// A mesh whose vertices are split between its patches.
#[derive(Clone, Debug)]
pub struct SplitMesh {
    /// The mesh: the part's vertices keep their indices, the copies are appended.
    pub mesh: Mesh,
    /// For each appended vertex (index `n + k` for a part of `n` vertices), the part's vertex
    /// it copies.
    pub copies_of: Vec<u32>,
    /// The patches (of the faces, which keep their order).
    pub patches: Patches,
}

/// Splits `mesh`'s vertices between the `patches`: a vertex whose faces lie in k patches gets
/// k − 1 copies. `None` when no vertex is shared by two patches.
pub fn split_patches(mesh: &Mesh, patches: &Patches) -> Option<SplitMesh> {
    let n = mesh.num_vertices();
    // Per vertex, the patch that keeps it: the patch of its first face in face order.
    let mut keeper = vec![u32::MAX; n];
    for (f, t) in mesh.faces.iter().enumerate() {
        for &v in t {
            if keeper[v as usize] == u32::MAX {
                keeper[v as usize] = patches.face_patch[f];
            }
        }
    }
    // Every (vertex, other patch) pair, in vertex order then patch order: one copy each.
    let mut pairs: Vec<(u32, u32)> = Vec::new();
    for (f, t) in mesh.faces.iter().enumerate() {
        let p = patches.face_patch[f];
        pairs.extend(t.iter().filter(|&&v| keeper[v as usize] != p).map(|&v| (v, p)));
    }
    if pairs.is_empty() {
        return None;
    }
    pairs.sort_unstable();
    pairs.dedup();
    let mut out = mesh.clone();
    let copies_of: Vec<u32> = pairs.iter().map(|&(v, _)| v).collect();
    out.positions.extend(copies_of.iter().map(|&v| mesh.positions[v as usize]));
    for (f, t) in out.faces.iter_mut().enumerate() {
        let p = patches.face_patch[f];
        for v in t.iter_mut() {
            if keeper[*v as usize] != p {
                let k = pairs.binary_search(&(*v, p)).expect("every pair is listed");
                *v = (n + k) as u32;
            }
        }
    }
    Some(SplitMesh { mesh: out, copies_of, patches: patches.clone() })
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A unit cube of 12 triangles, outward.
    fn cube() -> Mesh {
        let p: Vec<Vector3<f64>> = (0..8)
            .map(|i| Vector3::new((i & 1) as f64, ((i >> 1) & 1) as f64, ((i >> 2) & 1) as f64))
            .collect();
        let quads =
            [[0, 2, 3, 1], [4, 5, 7, 6], [0, 1, 5, 4], [2, 6, 7, 3], [0, 4, 6, 2], [1, 3, 7, 5]];
        let faces = quads.iter().flat_map(|q| [[q[0], q[1], q[2]], [q[0], q[2], q[3]]]).collect();
        Mesh::from_triangles(p, faces)
    }

    #[test]
    fn a_cube_is_six_patches_of_four_vertices_each() {
        let m = cube();
        let p = patches(&m, 40.0);
        assert_eq!(p.count, 6);
        assert_eq!(p.sharp_edges, 12);
        let s = split_patches(&m, &p).unwrap();
        // Every corner of the cube is on three faces: 8 kept + 16 copies.
        assert_eq!(s.mesh.num_vertices(), 24);
        assert_eq!(s.copies_of.len(), 16);
        // Each patch's two triangles share a diagonal and no vertex with another patch.
        for a in 0..6 {
            for b in 0..6 {
                if a == b {
                    continue;
                }
                let vs = |k: usize| [s.mesh.faces[2 * k], s.mesh.faces[2 * k + 1]].concat();
                assert!(vs(a).iter().all(|v| !vs(b).contains(v)), "patches {a} and {b}");
            }
        }
        // Positions are copied.
        for (k, &v) in s.copies_of.iter().enumerate() {
            assert_eq!(s.mesh.positions[8 + k], m.positions[v as usize]);
        }
        // Each side: area 1, perimeter 4, width 2·1/4.
        let sizes = p.sizes(&m);
        assert!(sizes.area.iter().all(|a| (a - 1.0).abs() < 1e-12), "{:?}", sizes.area);
        assert!(sizes.width.iter().all(|w| (w - 0.5).abs() < 1e-12), "{:?}", sizes.width);
    }

    #[test]
    fn a_smooth_mesh_splits_nothing() {
        let m = crate::generate::cylinder(10.0, 20.0, 32, 4);
        let p = patches(&m, 40.0);
        assert_eq!(p.count, 1);
        assert!(split_patches(&m, &p).is_none());
        // A crease angle of 180° keeps every component whole.
        let cube = cube();
        let p = patches(&cube, 180.0);
        assert_eq!((p.count, p.sharp_edges), (1, 0));
        assert!(split_patches(&cube, &p).is_none());
    }
}
