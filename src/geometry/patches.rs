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
//!
//! **On a noisy part** the facets' dihedral angles are the noise's as much as the surface's:
//! with vertex heights off by σ (RMS, independent), the dihedral across an edge is off by
//! σ_d = σ·√(1/H_a² + 1/H_b² + ((1 − t_a)/H_a + (1 − t_b)/H_b)² + (t_a/H_a + t_b/H_b)²), H the
//! two faces' heights over the edge and t the feet of those heights along it (the slopes across
//! the edge are (h_opposite − h_foot)/H); 2.31 σ/s on equilateral faces of edge s. A scan with
//! σ a quarter of its spacing makes dihedrals of 36° RMS, and a crease angle of 40° cut it into
//! hundreds of patches. So given the part's height noise ([`PatchOptions::height_noise`]), an
//! edge is sharp only when its dihedral is also beyond [`NOISE_CREASE_SIGMAS`] σ_d: an angle
//! the noise makes at no more than a few edges in a thousand, which close no patch.

use std::collections::HashMap;

use nalgebra::Vector3;

use super::surfaces::Surfaces;
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

/// How far beyond the noise's own spread σ_d a dihedral must be to read as a crease on a noisy
/// part (module docs): three standard deviations, which a Gaussian passes at 0.27 % of the
/// edges, scattered, so that no chain of them closes a patch.
pub const NOISE_CREASE_SIGMAS: f64 = 3.0;

/// What [`patches_with`] cuts at.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct PatchOptions {
    /// The crease angle, degrees (≥ 180: one patch per connected component).
    pub crease_angle_deg: f64,
    /// The part's height noise σ (RMS, scene units; 0 for a clean part): a dihedral within
    /// [`NOISE_CREASE_SIGMAS`] of the spread it gives an edge is not sharp (module docs).
    pub height_noise: f64,
}

/// [`patches_with`] on a clean part: cut at `crease_angle_deg` alone.
pub fn patches(mesh: &Mesh, crease_angle_deg: f64) -> Patches {
    patches_with(mesh, &PatchOptions { crease_angle_deg, height_noise: 0.0 })
}

/// The spread σ_d the height noise `sigma` gives the dihedral angle (radians) across the edge
/// `p`–`q` between faces whose third corners are `a` and `b` (module docs); infinite when a
/// face has no height over the edge.
pub fn noise_dihedral(
    p: &Vector3<f64>,
    q: &Vector3<f64>,
    a: &Vector3<f64>,
    b: &Vector3<f64>,
    sigma: f64,
) -> f64 {
    let e = q - p;
    let len2 = e.norm_squared();
    // The height of `c` over the edge's line and the foot of that height along it (0 at p).
    let foot = |c: &Vector3<f64>| {
        let t = (c - p).dot(&e) / len2;
        ((c - p - e * t).norm(), t)
    };
    let ((ha, ta), (hb, tb)) = (foot(a), foot(b));
    if !(ha > 0.0 && hb > 0.0 && len2 > 0.0) {
        return f64::INFINITY;
    }
    let (ia, ib) = (1.0 / ha, 1.0 / hb);
    let at_p = (1.0 - ta) * ia + (1.0 - tb) * ib;
    let at_q = ta * ia + tb * ib;
    sigma * (ia * ia + ib * ib + at_p * at_p + at_q * at_q).sqrt()
}

/// Faces joined across every edge that is not sharp — a dihedral angle at most
/// `crease_angle_deg`, or on a noisy part within the noise's spread there (module docs) —
/// then every patch smaller than [`MIN_PATCH_AREA_SHARE`] of the part joined to the neighbour
/// it shares the longest sharp edges with. A face of zero area joins its neighbours.
pub fn patches_with(mesh: &Mesh, options: &PatchOptions) -> Patches {
    patches_on_surfaces(mesh, options, None)
}

/// [`patches_with`] on a part whose surfaces were recognized
/// ([`crate::geometry::surfaces`]): an edge between two faces on recognized surfaces is sharp
/// exactly when the surfaces meet there at a crease ([`Surfaces::crease_between`]: one
/// surface's strips never, a tangent junction never, a chamfer's shallow edge always);
/// other edges as [`patches_with`] says. A patch of recognized faces is a face of the part,
/// never joined to a neighbour for its size.
pub fn patches_on_surfaces(
    mesh: &Mesh,
    options: &PatchOptions,
    surfaces: Option<&Surfaces>,
) -> Patches {
    let crease_angle_deg = options.crease_angle_deg;
    let cos_theta = crease_angle_deg.clamp(0.0, 180.0).to_radians().cos();
    let normal = |f: usize| {
        let [a, b, c] = mesh.faces[f].map(|v| mesh.positions[v as usize]);
        (b - a).cross(&(c - a)).try_normalize(0.0)
    };
    // The corner of face `f` opposite the edge (u, v).
    let opposite = |f: usize, u: u32, v: u32| {
        let t = mesh.faces[f];
        let w = t.iter().copied().find(|&w| w != u && w != v).unwrap_or(t[0]);
        mesh.positions[w as usize]
    };
    let beyond_noise = |u: u32, v: u32, f: usize, g: usize, dot: f64| {
        if options.height_noise.is_nan() || options.height_noise <= 0.0 {
            return true;
        }
        let (p, q) = (mesh.positions[u as usize], mesh.positions[v as usize]);
        let spread =
            noise_dihedral(&p, &q, &opposite(f, u, v), &opposite(g, u, v), options.height_noise);
        let limit = NOISE_CREASE_SIGMAS * spread;
        limit < std::f64::consts::PI && dot.clamp(-1.0, 1.0).acos() > limit
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
            // `mesh.crease_angle` 180 keeps every component whole, recognized or not.
            let recognized = surfaces
                .filter(|_| crease_angle_deg < 180.0)
                .and_then(|s| s.crease_between(mesh, first, f, run[0].0, run[0].1));
            let is_sharp = match (normals[first], normals[f]) {
                _ if recognized.is_some() => recognized == Some(true),
                (Some(a), Some(b)) => {
                    let dot = a.dot(&b);
                    crease_angle_deg < 180.0
                        && dot < cos_theta
                        && beyond_noise(run[0].0, run[0].1, first, f, dot)
                }
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
    let mut feature = planar_faces(mesh);
    if let Some(s) = surfaces {
        for (f, &id) in s.face_surface.iter().enumerate().take(feature.len()) {
            feature[f] |= id != super::surfaces::NO_SURFACE;
        }
    }
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
    // Per patch (by root), the sharp edges out of it (indices into `sharp`), merged smaller
    // into larger as patches join: a noisy part's thousands of small patches each scanning
    // every sharp edge made this quadratic.
    let mut edges_of: HashMap<u32, Vec<u32>> = HashMap::new();
    for (i, &(a, b, _)) in sharp.iter().enumerate() {
        let (ra, rb) = (find(parent, a), find(parent, b));
        if ra != rb {
            edges_of.entry(ra).or_default().push(i as u32);
            edges_of.entry(rb).or_default().push(i as u32);
        }
    }
    for (_, root) in small {
        let r = find(parent, root);
        if patch_area[r as usize] >= MIN_PATCH_AREA_SHARE * total {
            continue; // grown by an earlier join
        }
        // The shared sharp length with each neighbouring patch, summed in the edges' order.
        let mut own = edges_of.remove(&r).unwrap_or_default();
        own.sort_unstable();
        own.dedup();
        let mut shared: Vec<(u32, f64)> = Vec::new();
        for &(a, b, len) in own.iter().map(|&i| &sharp[i as usize]) {
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
            let n = find(parent, r);
            patch_area[n as usize] = joined;
            let mut other = edges_of.remove(&q).unwrap_or_default();
            if other.len() < own.len() {
                std::mem::swap(&mut other, &mut own);
            }
            other.extend(own);
            edges_of.insert(n, other);
        } else {
            edges_of.insert(r, own);
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

    /// A 40 × 40 grid of unit squares ([`crate::generate::Grid`]), folded up by 90° along
    /// x = 20 when `fold`, each vertex moved along its side's normal by Gaussian noise of RMS
    /// `sigma` (a fixed LCG and Box–Muller: the same mesh every run).
    fn noisy_sheet(sigma: f64, fold: bool) -> Mesh {
        let mut state = 0x2545_f491_4f6c_dd1du64;
        let mut uniform = || {
            state = state
                .wrapping_mul(6_364_136_223_846_793_005)
                .wrapping_add(1_442_695_040_888_963_407);
            ((state >> 11) as f64 + 0.5) / (1u64 << 53) as f64
        };
        let mut mesh = crate::generate::Grid::new(40, 40)
            .build(|s, t| Vector3::new((40.0 * s).round(), (40.0 * t).round(), 0.0));
        for p in &mut mesh.positions {
            let g = (-2.0 * uniform().ln()).sqrt() * (std::f64::consts::TAU * uniform()).cos();
            *p = if fold && p.x > 20.0 {
                Vector3::new(20.0 - sigma * g, p.y, p.x - 20.0)
            } else {
                Vector3::new(p.x, p.y, sigma * g)
            };
        }
        mesh
    }

    /// Equilateral faces of edge s: σ_d = 4σ / (√3 s).
    #[test]
    fn the_noise_s_dihedral_spread_on_equilateral_faces() {
        let (p, q) = (Vector3::new(0.0, 0.0, 0.0), Vector3::new(1.0, 0.0, 0.0));
        let h = 3f64.sqrt() / 2.0;
        let (a, b) = (Vector3::new(0.5, h, 0.0), Vector3::new(0.5, -h, 0.0));
        let want = 4.0 * 0.1 / 3f64.sqrt();
        assert!((noise_dihedral(&p, &q, &a, &b, 0.1) - want).abs() < 1e-12);
        // A face with no height over the edge: any dihedral is the noise's.
        assert!(noise_dihedral(&p, &q, &Vector3::new(2.0, 0.0, 0.0), &b, 0.1).is_infinite());
    }

    #[test]
    fn a_noisy_sheet_is_one_patch_and_its_fold_still_cuts_it() {
        // σ a quarter of the spacing: facet dihedrals of about 30° RMS, cut at 40° into many
        // patches unless the noise is known.
        let sheet = noisy_sheet(0.25, false);
        let blind = patches(&sheet, 40.0);
        assert!(blind.count > 5, "{} patches", blind.count);
        let o = PatchOptions { crease_angle_deg: 40.0, height_noise: 0.25 };
        assert_eq!(patches_with(&sheet, &o).count, 1);
        // A 90° fold is beyond a lighter noise's reach (σ = 0.08: 3 σ_d of about 30° on these
        // right triangles) and still cuts the sheet in two.
        let folded = noisy_sheet(0.08, true);
        let o = PatchOptions { crease_angle_deg: 40.0, height_noise: 0.08 };
        let p = patches_with(&folded, &o);
        assert_eq!(p.count, 2, "{p:?}");
    }
}
