//! Growing cylinders and cones over a part's planar regions (module docs of [`super`], step 2).

use std::cmp::Reverse;
use std::collections::BinaryHeap;

use nalgebra::Vector3;

use super::fit;
use super::primitive::{Primitive, SurfaceKind};
use super::{MAX_CHORD_DEVIATION_DEG, MAX_STEP_DEG};
use crate::mesh::planar::{planar_regions_within, PlanarRegions, NO_REGION};
use crate::mesh::Mesh;

type V3 = Vector3<f64>;

/// The planar regions as a graph: per region its vertices, faces and neighbours.
pub(super) struct RegionGraph {
    pub(super) regions: PlanarRegions,
    /// CSR: the vertices of each region.
    vert_start: Vec<u32>,
    verts: Vec<u32>,
    /// CSR: neighbouring regions and the angle to each (radians).
    nb_start: Vec<u32>,
    nbs: Vec<(u32, f64)>,
    /// Per region: the mean of its vertices.
    pub(super) centroid: Vec<V3>,
    /// The two faces across each manifold edge, and the edge's length.
    pub(super) face_pairs: Vec<(u32, u32, f64)>,
}

impl RegionGraph {
    /// The graph of `mesh`'s planar regions, flat within `eps`
    /// ([`crate::mesh::planar::planar_regions_within`]).
    pub(super) fn new(mesh: &Mesh, eps: f64) -> Self {
        let regions = planar_regions_within(mesh, eps);
        let nr = regions.normal.len();
        let mut pairs: Vec<(u32, u32)> = Vec::with_capacity(3 * mesh.num_faces());
        for (f, t) in mesh.faces.iter().enumerate() {
            let r = regions.face_region[f];
            if r != NO_REGION {
                pairs.extend(t.iter().map(|&v| (r, v)));
            }
        }
        pairs.sort_unstable();
        pairs.dedup();
        let (vert_start, verts) = csr(nr, &pairs);
        let mut edges: Vec<(u32, u32, u32)> = Vec::with_capacity(3 * mesh.num_faces());
        for (f, t) in mesh.faces.iter().enumerate() {
            for k in 0..3 {
                let (a, b) = (t[k], t[(k + 1) % 3]);
                edges.push((a.min(b), a.max(b), f as u32));
            }
        }
        edges.sort_unstable();
        let mut links: Vec<(u32, u32)> = Vec::new();
        let mut face_pairs: Vec<(u32, u32, f64)> = Vec::new();
        for run in edges.chunk_by(|x, y| (x.0, x.1) == (y.0, y.1)) {
            if let [x, y] = run {
                let len = (mesh.positions[x.1 as usize] - mesh.positions[x.0 as usize]).norm();
                face_pairs.push((x.2, y.2, len));
                let (r, s) = (regions.face_region[x.2 as usize], regions.face_region[y.2 as usize]);
                if r != s && r != NO_REGION && s != NO_REGION {
                    links.push((r, s));
                    links.push((s, r));
                }
            }
        }
        links.sort_unstable();
        links.dedup();
        let (nb_start, nb) = csr(nr, &links);
        let nbs = nb_start
            .windows(2)
            .enumerate()
            .flat_map(|(r, w)| {
                let n = regions.normal[r];
                nb[w[0] as usize..w[1] as usize]
                    .iter()
                    .map(|&s| (s, n.dot(&regions.normal[s as usize]).clamp(-1.0, 1.0).acos()))
                    .collect::<Vec<_>>()
            })
            .collect();
        let centroid = vert_start
            .windows(2)
            .map(|w| {
                let vs = &verts[w[0] as usize..w[1] as usize];
                vs.iter().map(|&v| mesh.positions[v as usize]).sum::<V3>() / vs.len().max(1) as f64
            })
            .collect();
        RegionGraph { regions, vert_start, verts, nb_start, nbs, centroid, face_pairs }
    }

    pub(super) fn verts(&self, r: u32) -> &[u32] {
        &self.verts[self.vert_start[r as usize] as usize..self.vert_start[r as usize + 1] as usize]
    }

    pub(super) fn neighbours(&self, r: u32) -> &[(u32, f64)] {
        &self.nbs[self.nb_start[r as usize] as usize..self.nb_start[r as usize + 1] as usize]
    }

    /// Whether another neighbour of `r`, as wide as `s` (within a factor of two), meets `r` at
    /// `angle` (within 1 %): `s` continues a run of strips through `r`.
    pub(super) fn is_paired(&self, r: u32, s: u32, angle: f64) -> bool {
        let x = self.regions.width[s as usize];
        self.neighbours(r).iter().any(|&(q, b)| {
            let y = self.regions.width[q as usize];
            q != s && x <= 2.0 * y && y <= 2.0 * x && (angle - b).abs() <= 0.01 * angle.max(b)
        })
    }

    /// Whether two of the region's neighbours meet it at the same angle (within 1 %): an inner
    /// strip of a fillet, a trapezoid inside a band.
    pub(super) fn is_regular(&self, r: u32) -> bool {
        let nb = self.neighbours(r);
        let w = self.regions.width[r as usize];
        let alike = |s: u32| {
            let x = self.regions.width[s as usize];
            x <= 2.0 * w && w <= 2.0 * x
        };
        nb.iter().enumerate().any(|(i, a)| {
            a.1 > 1e-4
                && alike(a.0)
                && nb[i + 1..]
                    .iter()
                    .any(|b| alike(b.0) && (a.1 - b.1).abs() <= 0.01 * a.1.max(b.1))
        })
    }
}

/// Compressed rows of sorted (row, value) pairs.
fn csr(rows: usize, pairs: &[(u32, u32)]) -> (Vec<u32>, Vec<u32>) {
    let mut start = vec![0u32; rows + 1];
    for &(r, _) in pairs {
        start[r as usize + 1] += 1;
    }
    for i in 0..rows {
        start[i + 1] += start[i];
    }
    (start, pairs.iter().map(|p| p.1).collect())
}

/// Which kinds a fit may return.
#[derive(Clone, Copy, PartialEq, Eq)]
pub(super) enum Kinds {
    /// Cylinders and cones: a strip or a band on its own, over-determined along it.
    Ruled,
    /// Any kind, spheres and tori too.
    All,
}

/// The best primitive through `points` (simplest first: cylinder, cone, then with
/// [`Kinds::All`] sphere and torus), if one passes within `tol` of every point.
pub(super) fn best_fit(
    points: &[V3],
    normals: &[V3],
    lines: &[(V3, V3)],
    tol: f64,
    kinds: Kinds,
) -> Option<Primitive> {
    if points.is_empty() {
        return None;
    }
    let within = |p: Option<Primitive>| p.filter(|p| fit::max_residual(p, points) <= tol);
    // A radius beyond 10⁶ times the points' extent is a plane's, not a curve's.
    let (lo, hi) = points.iter().fold((points[0], points[0]), |(lo, hi), p| (lo.inf(p), hi.sup(p)));
    let max_radius = 1e6 * (hi - lo).norm();
    let sound = |p: Option<Primitive>| p.filter(|p| p.is_sound(10.0 * tol, max_radius));
    let cylinder = within(sound(fit::cylinder(points, normals)));
    let cone = fit::band_axis(lines).and_then(|(o, a)| within(sound(fit::cone(points, &o, &a))));
    // A cone band that is nearly flat (a turned fillet's ring beside its plane) also fits a
    // cylinder of a huge radius within the rounding: of two that fit, the closer one.
    match (cylinder, cone) {
        (Some(c), Some(k)) => {
            let closer = fit::max_residual(&k, points) < fit::max_residual(&c, points);
            return Some(if closer { k } else { c });
        }
        (Some(c), None) | (None, Some(c)) => return Some(c),
        (None, None) if kinds == Kinds::Ruled => return None,
        (None, None) => {}
    }
    if let Some(s) = within(sound(fit::sphere(points))) {
        return Some(s);
    }
    let (o, a) = fit::revolution_axis(lines)?;
    within(sound(fit::torus(points, &o, &a, tol)))
}

/// A set of regions grown from one seed.
struct Growth {
    regions: Vec<u32>,
    points: Vec<V3>,
    normals: Vec<V3>,
    lines: Vec<(V3, V3)>,
}

impl Growth {
    fn push(&mut self, g: &RegionGraph, mesh: &Mesh, stamp: &mut [u32], id: u32, r: u32) {
        self.regions.push(r);
        for &v in g.verts(r) {
            if stamp[v as usize] != id {
                stamp[v as usize] = id;
                self.points.push(mesh.positions[v as usize]);
            }
        }
        let n = g.regions.normal[r as usize];
        self.normals.push(n);
        self.lines.push((g.centroid[r as usize], n));
    }
}

/// Whether region `r` lies on `prim`: its vertices within `tol`, and the surface's normal at
/// each of them within `spread` of the region's own ([`MAX_CHORD_DEVIATION_DEG`]).
pub(super) fn region_on(
    g: &RegionGraph,
    mesh: &Mesh,
    r: u32,
    prim: &Primitive,
    tol: f64,
    spread: f64,
) -> bool {
    let n = g.regions.normal[r as usize];
    let cos = spread.min(std::f64::consts::FRAC_PI_2).cos();
    g.verts(r).iter().all(|&v| {
        let p = mesh.positions[v as usize];
        prim.signed_distance(&p).abs() <= tol && prim.normal_at(&p).dot(&n).abs() >= cos
    })
}

/// Grows a cylinder or a cone from `seed` (module docs of [`super`], step 2); the regions it took and its primitive.
///
/// `id` stamps the vertices and regions this growth has seen (unique per call); regions in
/// `banned` are not taken as the seed's first partner. On failure, the first partner taken
/// (if any) is returned, so that the caller can try the seed again without it: two trapezoids
/// of neighbouring bands of a finely exported turned face fit a sphere, and no cone after.
pub(super) fn grow(
    g: &RegionGraph,
    mesh: &Mesh,
    taken: &[bool],
    (stamp, seen): (&mut [u32], &mut [u32]),
    (seed, id, banned): (u32, u32, &[u32]),
    tol: f64,
) -> Result<(Vec<u32>, Primitive), Option<u32>> {
    let max_step = MAX_STEP_DEG.to_radians();
    let spread = MAX_CHORD_DEVIATION_DEG.to_radians();
    let mut set = Growth { regions: vec![], points: vec![], normals: vec![], lines: vec![] };
    // Stamped with the seed: the vertices in the set, the regions queued.
    set.push(g, mesh, stamp, id, seed);
    // Regions as wide as the seed (within a factor of two: the strips of one surface) are
    // tried first, then the smoothest crossing first: a fillet's last strip meets the plate,
    // or a band the next face, across half a step, before it meets its own neighbours.
    let w = g.regions.width[seed as usize];
    let unlike = |s: u32| {
        let x = g.regions.width[s as usize];
        !(x <= 2.0 * w && w <= 2.0 * x)
    };
    // Then the strips that continue a run: a neighbour met at the angle another neighbour of
    // the same width meets the region at (the next strip of a fillet, the next trapezoid of a
    // band) before a lone crossing — at 30° chords a 26.6° chamfer edge is smoother than the
    // skirt's own strip edges, and only their pairing tells them apart.
    let mut heap: BinaryHeap<Reverse<(bool, bool, u64, u32)>> = BinaryHeap::new();
    let enqueue =
        |heap: &mut BinaryHeap<Reverse<(bool, bool, u64, u32)>>, seen: &mut [u32], r: u32| {
            for &(s, angle) in g.neighbours(r) {
                if !taken[s as usize] && angle <= max_step && seen[s as usize] != id {
                    seen[s as usize] = id;
                    let lone = !g.is_paired(r, s, angle);
                    heap.push(Reverse((unlike(s), lone, angle.to_bits(), s)));
                }
            }
        };
    seen[seed as usize] = id;
    enqueue(&mut heap, seen, seed);
    let mut model: Option<Primitive> = None;
    let mut refit_at = 6usize;
    // Regions the model refused: tried again against a model refitted to the whole set once
    // the queue runs dry (a cone fitted to three trapezoids of a band written with six digits
    // strays by more than the rounding a quarter turn on; the band's whole ring does not).
    let mut deferred: Vec<u32> = Vec::new();
    let mut retried_at = 0usize;
    loop {
        let Some(Reverse((_, _, _, r))) = heap.pop() else {
            if deferred.is_empty() || set.regions.len() == retried_at || model.is_none() {
                break;
            }
            retried_at = set.regions.len();
            model = best_fit(&set.points, &set.normals, &set.lines, tol, Kinds::Ruled);
            if model.is_none() {
                return Err(set.regions.get(1).copied());
            }
            for r in deferred.drain(..) {
                heap.push(Reverse((unlike(r), false, 0, r)));
            }
            continue;
        };
        // A strip or a band is a quad at least (two triangles); lone triangles (a pole's fan,
        // a scan's) join a surface afterwards, if they lie on it.
        if g.regions.faces[r as usize] < 2 || (set.regions.len() == 1 && banned.contains(&r)) {
            continue;
        }
        let accept = match &model {
            Some(m) => region_on(g, mesh, r, m, tol, spread),
            None => {
                let mut trial: Vec<V3> = set.points.clone();
                let new = g.verts(r).iter().filter(|&&v| stamp[v as usize] != id);
                trial.extend(new.map(|&v| mesh.positions[v as usize]));
                let mut normals = set.normals.clone();
                normals.push(g.regions.normal[r as usize]);
                let mut lines = set.lines.clone();
                lines.push((g.centroid[r as usize], g.regions.normal[r as usize]));
                // Before the set fixes a cylinder or a cone, any primitive through it will do
                // (two strips of a cylinder, three trapezoids of a band).
                let fit = best_fit(&trial, &normals, &lines, tol, Kinds::All).filter(|f| {
                    set.regions.iter().chain([&r]).all(|&q| region_on(g, mesh, q, f, tol, spread))
                });
                // The set fixes its surface once it is three regions and bulges off its plane
                // by more than the rounding can fake ([`MIN_BULGE`] tolerances): three strips of
                // a 2° export written with six digits fit cylinders of many radii.
                if set.regions.len() + 1 >= 3 && fit::flatness(&trial) > MIN_BULGE * tol {
                    model = fit
                        .filter(|f| matches!(f.kind(), SurfaceKind::Cylinder | SurfaceKind::Cone));
                }
                fit.is_some()
            }
        };
        if !accept {
            if model.is_some() {
                deferred.push(r);
            }
            continue;
        }
        set.push(g, mesh, stamp, id, r);
        enqueue(&mut heap, seen, r);
        if set.regions.len() >= refit_at {
            refit_at *= 2;
            model = best_fit(&set.points, &set.normals, &set.lines, tol, Kinds::Ruled);
            if model.is_none() {
                return Err(set.regions.get(1).copied());
            }
        }
    }
    let partner = set.regions.get(1).copied();
    if set.regions.len() < 3 {
        return Err(partner);
    }
    match best_fit(&set.points, &set.normals, &set.lines, tol, Kinds::Ruled) {
        Some(prim) if fit::flatness(&set.points) > MIN_BULGE * tol => Ok((set.regions, prim)),
        _ => Err(partner),
    }
}

/// How many times the tolerance a grown surface must stand off its own best plane to be read
/// as curved: strips of a fine export whose chords' sagitta is within the file's rounding
/// (a 2 mm fillet at 1° chords in float32) fit a cylinder of any large radius, and are left
/// to the jet fit, which reads them well.
pub const MIN_BULGE: f64 = 10.0;

/// Module docs of [`super`], step 5: regions not yet on a surface (a sphere's pole fan, the
/// end triangles of a strip) join a neighbouring surface they lie on, repeatedly.
pub(super) fn absorb(
    g: &RegionGraph,
    mesh: &Mesh,
    prims: &mut [(Primitive, Vec<u32>)],
    owner: &mut [u32],
    tol: f64,
) {
    let spread = MAX_CHORD_DEVIATION_DEG.to_radians();
    let mut queue: Vec<u32> =
        (0..owner.len() as u32).filter(|&r| owner[r as usize] != u32::MAX).collect();
    while let Some(r) = queue.pop() {
        let k = owner[r as usize];
        for &(s, angle) in g.neighbours(r) {
            if owner[s as usize] != u32::MAX || angle > MAX_STEP_DEG.to_radians() {
                continue;
            }
            if region_on(g, mesh, s, &prims[k as usize].0, tol, spread) {
                owner[s as usize] = k;
                prims[k as usize].1.push(s);
                queue.push(s);
            }
        }
    }
}
