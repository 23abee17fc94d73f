//! Profiles closed by tangency (module docs of [`super`], step 3): a round exported with two
//! strips (three rings), or a crown written as one fan of triangles from its rim to its pole,
//! passes through too few profile points to fix its circle — any three points lie on one. A
//! CAD round is tangent to the faces it blends, so the neighbour it meets tangentially is the
//! missing condition: the circle through the rings must meet that neighbour's surface with
//! the same normal (within [`G1_TOLERANCE_DEG`]) where the export's chord visibly turns
//! (by [`MIN_CHORD_TURN`] tolerances or more), which no chord of a polygonal profile does by
//! chance — a free profile's chords turn alike, and the circle through three of them leans
//! half a turn off the next.

use nalgebra::Vector3;

use super::grow::RegionGraph;
use super::primitive::Primitive;
use super::G1_TOLERANCE_DEG;
use crate::mesh::Mesh;

type V3 = Vector3<f64>;

/// How many times [`G1_TOLERANCE_DEG`] the export's chord must turn from the neighbour at a
/// tangent junction for the tangency to count: a chord that is itself nearly tangent tells
/// nothing about the circle.
pub const MIN_CHORD_TURN: f64 = 2.0;

/// Fewest region pairs along a junction that must all be tangent (a quarter of a ring at
/// the coarsest 30° export).
const MIN_PAIRS: usize = 3;

/// The surface each region lies on so far, to read a neighbour's normal.
pub(super) struct Owners {
    /// Per region, an index into `prims`, or `u32::MAX`.
    region: Vec<u32>,
    prims: Vec<Primitive>,
}

impl Owners {
    /// The owners of `grown`'s regions among `regions` regions.
    pub(super) fn new(grown: &[(Primitive, Vec<u32>)], regions: usize) -> Owners {
        let mut region = vec![u32::MAX; regions];
        for (k, (_, rs)) in grown.iter().enumerate() {
            for &r in rs {
                region[r as usize] = k as u32;
            }
        }
        Owners { region, prims: grown.iter().map(|(p, _)| *p).collect() }
    }

    /// `regions` now lie on `prim`.
    pub(super) fn assign(&mut self, regions: &[u32], prim: &Primitive) {
        let k = self.prims.len() as u32;
        self.prims.push(*prim);
        for &r in regions {
            self.region[r as usize] = k;
        }
    }

    /// The surface normal of region `s` at `p`: its surface's, or its own plane's.
    fn normal(&self, g: &RegionGraph, s: u32, p: &V3) -> V3 {
        match self.region[s as usize] {
            u32::MAX => g.regions.normal[s as usize],
            k => self.prims[k as usize].normal_at(p),
        }
    }

    /// A key for the surface of region `s` (its own region when it has none).
    fn side(&self, s: u32) -> u64 {
        match self.region[s as usize] {
            u32::MAX => (1u64 << 32) | s as u64,
            k => k as u64,
        }
    }
}

/// Whether `prim`, through `run`'s regions, meets one neighbouring surface tangentially all
/// along their junction while the run's chords turn from it (module docs).
pub(super) fn tangent_to_a_neighbour(
    g: &RegionGraph,
    mesh: &Mesh,
    owners: &Owners,
    run: &[u32],
    prim: &Primitive,
) -> bool {
    let g1 = G1_TOLERANCE_DEG.to_radians();
    let in_run = |s: u32| run.contains(&s);
    // Per neighbouring surface: (pairs, pairs tangent).
    let mut sides: Vec<(u64, usize, usize)> = Vec::new();
    for &r in run {
        let chord = g.regions.normal[r as usize];
        for &(s, _) in g.neighbours(r) {
            if in_run(s) {
                continue;
            }
            let shared: Vec<V3> = g
                .verts(r)
                .iter()
                .filter(|v| g.verts(s).binary_search(v).is_ok())
                .map(|&v| mesh.positions[v as usize])
                .collect();
            if shared.is_empty() {
                continue;
            }
            let tangent = shared.iter().all(|p| {
                let n = owners.normal(g, s, p);
                let err = angle(&prim.normal_at(p), &n);
                err <= g1 && angle(&chord, &n) >= MIN_CHORD_TURN * g1
            });
            let key = owners.side(s);
            match sides.iter_mut().find(|e| e.0 == key) {
                Some(e) => {
                    e.1 += 1;
                    e.2 += tangent as usize;
                }
                None => sides.push((key, 1, tangent as usize)),
            }
        }
    }
    sides.iter().any(|&(_, pairs, tangent)| pairs >= MIN_PAIRS && tangent == pairs)
}

/// The angle between two lines (normals of either orientation), radians.
fn angle(a: &V3, b: &V3) -> f64 {
    let c = a.dot(b).abs() / (a.norm() * b.norm());
    if c.is_finite() {
        c.min(1.0).acos()
    } else {
        std::f64::consts::FRAC_PI_2
    }
}

/// The sphere centred on the axis (`o`, `a`) through a pole fan's rim and its pole, if every
/// one of `points` lies within `tol` of it: the centre's height c on the axis solves
/// ρᵢ² + (hᵢ − c)² = (h_p − c)² for the rim points (ρᵢ, hᵢ) and the pole's height h_p, in
/// the least-squares sense.
pub(super) fn fan_sphere(points: &[V3], (o, a): (V3, V3), tol: f64) -> Option<Primitive> {
    let pole = points.iter().min_by(|p, q| {
        let d = |x: &V3| (x - o).cross(&a).norm();
        d(p).total_cmp(&d(q))
    })?;
    let hp = (pole - o).dot(&a);
    let (mut num, mut den) = (0.0, 0.0);
    for p in points {
        let h = (p - o).dot(&a);
        let rho2 = (p - o).cross(&a).norm_squared();
        // 2 (h_p − h) c = h_p² − h² − ρ²
        let x = 2.0 * (hp - h);
        num += x * (hp * hp - h * h - rho2);
        den += x * x;
    }
    let c = num / den;
    let center = o + a * c;
    let radius = (hp - c).abs();
    if !(c.is_finite() && radius.is_finite() && radius > 0.0) {
        return None;
    }
    let prim = Primitive::Sphere { center: center.into(), radius };
    points.iter().all(|p| prim.signed_distance(p).abs() <= tol).then_some(prim)
}
