//! Curved faces drawn on the surfaces they approximate (docs/math.md §3, "Recognized
//! surfaces"): a chord of a recognized curved surface is cut into n² sub-triangles whose
//! corners are moved onto the surface, so the preview's outline and what hides what follow
//! the surface, not the strips — a torus exported at 15° chords shows a round silhouette,
//! as its 1° export does.
//!
//! Each sub-triangle keeps its corners' barycentrics in the chord, so a sample still names its
//! face and a point of the chord, which the shading projects onto the surface as before.
//!
//! * **Where points go.** Inside a chord of a curved surface, onto the surface (its nearest
//!   point). On an edge between two chords of one surface, likewise. On an edge where the
//!   surface meets another recognized surface (a crease, or a plane), onto the curve where the
//!   two meet (Newton's steps x ← x − Jᵀ(JJᵀ)⁻¹d on the two signed distances d, J their
//!   normals; at a tangent junction, where JJᵀ is singular, onto the lower-numbered surface):
//!   a plane face beside a curved one is cut too, so its rim follows the same curve and no
//!   crack opens. An edge to a face on no surface, or on the part's boundary, stays straight.
//! * **One count.** Every cut face is cut n × n, n = ⌈θ / [`SUB_STEP_DEG`]⌉ for the largest
//!   angle θ between a curved surface's normals at the corners of one of its chords, at most
//!   [`MAX_SUBDIVISION`] and at most what keeps the sub-triangles within
//!   [`MAX_SUB_TRIANGLES`]; so both faces of an edge cut it at the same points, and a point on
//!   an edge is computed from the edge's lower-numbered vertex, bit for bit the same from both
//!   sides.

use nalgebra::Vector3;

use crate::geometry::surfaces::FaceSurfaces;

type V3 = Vector3<f64>;

/// The angle between the surface normals at a sub-triangle's corners, at most (degrees).
pub const SUB_STEP_DEG: f64 = 1.5;

/// The most sub-triangles along a chord's edge.
pub const MAX_SUBDIVISION: usize = 24;

/// The most sub-triangles drawn in all (a coarse export of a large part gets fewer per chord).
pub const MAX_SUB_TRIANGLES: usize = 400_000;

/// Newton's steps onto the curve where two surfaces meet.
const MEET_STEPS: usize = 8;

/// A corner of a sub-triangle: its position and its barycentrics (corners 1 and 2) in the
/// chord.
pub(super) type SubCorner = (V3, [f64; 2]);

/// Where the points of a face's edge go.
#[derive(Clone, Copy, PartialEq)]
enum Edge {
    /// Along the chord's edge.
    Straight,
    /// Onto the face's own surface.
    Own,
    /// Onto the curve where the face's surface meets this one.
    Meet(u32),
}

/// How each face is drawn.
pub(super) struct Displacement<'a> {
    surfaces: &'a FaceSurfaces,
    /// Sub-triangles along a cut face's edge.
    n: usize,
    /// Per face, where its edges' points go (edge k: corners k, k + 1); `None`: drawn as it is.
    edges: Vec<Option<[Edge; 3]>>,
    /// Per vertex, the lowest-numbered vertex at the same position (a part cut into patches
    /// has a copy of each vertex on a crease for each side).
    canon: Vec<u32>,
}

impl<'a> Displacement<'a> {
    /// The displacement of `faces` on `surfaces`, or `None` when no face needs one.
    pub(super) fn new(
        positions: &[V3],
        faces: &[[u32; 3]],
        surfaces: &'a FaceSurfaces,
    ) -> Option<Displacement<'a>> {
        let step = SUB_STEP_DEG.to_radians();
        let mut theta: f64 = 0.0;
        for (f, t) in faces.iter().enumerate() {
            let Some(prim) = surfaces.curved(f) else { continue };
            let n = t.map(|v| prim.normal_at(&positions[v as usize]));
            for k in 0..3 {
                let a = n[k].dot(&n[(k + 1) % 3]).abs().min(1.0).acos();
                if a.is_finite() {
                    theta = theta.max(a);
                }
            }
        }
        let canon = canonical_vertices(positions);
        let edges = edge_kinds(faces, &canon, surfaces);
        let cut = edges.iter().filter(|e| e.is_some()).count();
        let budget = ((MAX_SUB_TRIANGLES / cut.max(1)) as f64).sqrt().floor() as usize;
        let n = ((theta / step).ceil() as usize).min(MAX_SUBDIVISION).min(budget);
        (n > 1).then_some(Displacement { surfaces, n, edges, canon })
    }

    /// The sub-triangles of face `f` (corners `tri`, counter-clockwise as the face), or `None`
    /// when it is drawn as it is.
    pub(super) fn sub_triangles(
        &self,
        positions: &[V3],
        f: usize,
        tri: &[u32; 3],
    ) -> Option<Vec<[SubCorner; 3]>> {
        let edges = self.edges[f]?;
        let n = self.n;
        // Grid point (i, j): barycentrics (n − i − j, i, j) / n.
        let corner = |i: usize, j: usize| -> SubCorner {
            let w = [n - i - j, i, j];
            let bary = [i as f64 / n as f64, j as f64 / n as f64];
            (self.point(positions, (f, tri, &edges), w), bary)
        };
        let mut out = Vec::with_capacity(n * n);
        for j in 0..n {
            for i in 0..n - j {
                let (a, b, c) = (corner(i, j), corner(i + 1, j), corner(i, j + 1));
                out.push([a, b, c]);
                if i + j + 1 < n {
                    out.push([b, corner(i + 1, j + 1), c]);
                }
            }
        }
        Some(out)
    }

    /// The point of face `f` with integer barycentric weights `w` (sum `n`), where the module
    /// docs put it.
    fn point(
        &self,
        positions: &[V3],
        (f, tri, edges): (usize, &[u32; 3], &[Edge; 3]),
        w: [usize; 3],
    ) -> V3 {
        let n = self.n;
        let zeros = w.iter().filter(|&&x| x == 0).count();
        if zeros == 2 {
            let k = w.iter().position(|&x| x == n).unwrap_or(0);
            return positions[tri[k] as usize];
        }
        let own = self.surfaces.of[f];
        if zeros == 1 {
            // On edge k (corners k, k + 1), from its lower-numbered vertex.
            let k = (w.iter().position(|&x| x == 0).unwrap_or(0) + 1) % 3;
            let (a, b) = (k, (k + 1) % 3);
            let c = |k: usize| self.canon[tri[k] as usize];
            let (lo, hi) = if (c(a), tri[a]) < (c(b), tri[b]) { (a, b) } else { (b, a) };
            let t = w[hi] as f64 / n as f64;
            let (p, q) = (positions[tri[lo] as usize], positions[tri[hi] as usize]);
            let chord = p + (q - p) * t;
            return match edges[k] {
                Edge::Straight => chord,
                Edge::Own => self.onto(own, &chord),
                Edge::Meet(other) => self.meet(own.min(other), own.max(other), &chord),
            };
        }
        let chord = (0..3).map(|k| positions[tri[k] as usize] * (w[k] as f64 / n as f64)).sum();
        self.onto(own, &chord)
    }

    /// The point of surface `s` nearest `p` (`p` itself when that is not finite).
    fn onto(&self, s: u32, p: &V3) -> V3 {
        let Some(prim) = self.surfaces.primitives.get(s as usize) else { return *p };
        let q = prim.nearest(p, &prim.normal_at(p));
        if q.iter().all(|x| x.is_finite()) {
            q
        } else {
            *p
        }
    }

    /// A point near `p` on both surfaces `a` < `b` (module docs).
    fn meet(&self, a: u32, b: u32, p: &V3) -> V3 {
        let prims = &self.surfaces.primitives;
        let (Some(pa), Some(pb)) = (prims.get(a as usize), prims.get(b as usize)) else {
            return *p;
        };
        let mut x = *p;
        for _ in 0..MEET_STEPS {
            let (na, nb) = (pa.normal_at(&x), pb.normal_at(&x));
            let (da, db) = (pa.signed_distance(&x), pb.signed_distance(&x));
            let c = na.dot(&nb);
            let det = 1.0 - c * c;
            if det.is_nan() || det <= TANGENT_DET {
                return self.onto(a, &x);
            }
            // (JJᵀ)⁻¹d for J = [na; nb]: JJᵀ = [1 c; c 1].
            let (ya, yb) = ((da - c * db) / det, (db - c * da) / det);
            let next = x - na * ya - nb * yb;
            if !next.iter().all(|v| v.is_finite()) {
                return self.onto(a, p);
            }
            x = next;
        }
        x
    }
}

/// Below this 1 − cos² of the angle between two surfaces' normals (2°), they meet
/// tangentially.
const TANGENT_DET: f64 = 1.2e-3;

/// Per face, where its edges' points go, or `None` for a face drawn as it is: faces of curved
/// surfaces, and faces of other recognized surfaces (planes) that share an edge with one.
fn edge_kinds(
    faces: &[[u32; 3]],
    canon: &[u32],
    surfaces: &FaceSurfaces,
) -> Vec<Option<[Edge; 3]>> {
    let on =
        |f: usize| surfaces.of.get(f).is_some_and(|&s| (s as usize) < surfaces.primitives.len());
    let mut edges: Vec<(u32, u32, u32, u8)> = Vec::new();
    for (f, t) in faces.iter().enumerate() {
        if on(f) {
            for k in 0..3 {
                let (a, b) = (canon[t[k] as usize], canon[t[(k + 1) % 3] as usize]);
                edges.push((a.min(b), a.max(b), f as u32, k as u8));
            }
        }
    }
    edges.sort_unstable();
    let mut out: Vec<Option<[Edge; 3]>> = vec![None; faces.len()];
    let curved = |f: u32| surfaces.curved(f as usize).is_some();
    for (f, e) in out.iter_mut().enumerate() {
        if curved(f as u32) {
            *e = Some([Edge::Straight; 3]);
        }
    }
    for run in edges.chunk_by(|x, y| (x.0, x.1) == (y.0, y.1)) {
        let [x, y] = run else { continue };
        let (sx, sy) = (surfaces.of[x.2 as usize], surfaces.of[y.2 as usize]);
        if sx == sy {
            if curved(x.2) {
                for z in [x, y] {
                    if let Some(e) = &mut out[z.2 as usize] {
                        e[z.3 as usize] = Edge::Own;
                    }
                }
            }
        } else if curved(x.2) || curved(y.2) {
            for (z, other) in [(x, sy), (y, sx)] {
                let e = out[z.2 as usize].get_or_insert([Edge::Straight; 3]);
                e[z.3 as usize] = Edge::Meet(other);
            }
        }
    }
    out
}

/// Per vertex, the lowest-numbered vertex at exactly its position.
fn canonical_vertices(positions: &[V3]) -> Vec<u32> {
    let key = |v: u32| positions[v as usize].map(|c| c.to_bits());
    let mut order: Vec<u32> = (0..positions.len() as u32).collect();
    order.sort_unstable_by_key(|&v| (key(v).x, key(v).y, key(v).z, v));
    let mut canon: Vec<u32> = (0..positions.len() as u32).collect();
    for run in order.chunk_by(|&a, &b| key(a) == key(b)) {
        for &v in run {
            canon[v as usize] = run[0];
        }
    }
    canon
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::geometry::surfaces::Primitive;

    /// A prism of `k` strips between z = 0 and z = 1 whose corners lie on the unit cylinder
    /// about z: positions, faces (counter-clockwise outside).
    fn prism(k: usize) -> (Vec<V3>, Vec<[u32; 3]>) {
        let mut pos = Vec::new();
        for i in 0..k {
            let t = std::f64::consts::TAU * i as f64 / k as f64;
            pos.push(V3::new(t.cos(), t.sin(), 0.0));
            pos.push(V3::new(t.cos(), t.sin(), 1.0));
        }
        let mut faces = Vec::new();
        for i in 0..k as u32 {
            let j = (i + 1) % k as u32;
            faces.push([2 * i, 2 * j, 2 * j + 1]);
            faces.push([2 * i, 2 * j + 1, 2 * i + 1]);
        }
        (pos, faces)
    }

    fn cylinder(radius: f64) -> Primitive {
        Primitive::Cylinder { point: [0.0; 3], axis: [0.0, 0.0, 1.0], radius }
    }

    #[test]
    fn sub_triangles_lie_on_the_surface_and_agree_along_shared_edges() {
        let (pos, faces) = prism(12);
        let on = FaceSurfaces { primitives: vec![cylinder(1.0)], of: vec![0; faces.len()] };
        let d = Displacement::new(&pos, &faces, &on).expect("30° chords are cut");
        // ⌈30° / 1.5°⌉, up to the rounding of the corners' normals.
        assert!(d.n == 20 || d.n == 21, "{}", d.n);
        let mut corners: Vec<V3> = Vec::new();
        for (f, t) in faces.iter().enumerate() {
            for sub in d.sub_triangles(&pos, f, t).unwrap() {
                for (p, bary) in sub {
                    // Off the rims (open edges, drawn straight), every point is on the cylinder.
                    if p.z > 1e-12 && p.z < 1.0 - 1e-12 {
                        assert!((p.xy().norm() - 1.0).abs() < 1e-12, "{p:?}");
                    }
                    assert!(bary.iter().all(|b| (-1e-12..=1.0 + 1e-12).contains(b)));
                    corners.push(p);
                }
            }
        }
        // Points on a ruling shared by two faces come out bit for bit the same from both: every
        // distinct point on the ruling through vertex 0 is met by both its faces.
        let on_ruling: Vec<[u64; 3]> = corners
            .iter()
            .filter(|p| p.y == 0.0 && p.x > 0.0)
            .map(|p| p.map(f64::to_bits).into())
            .collect();
        let mut distinct = on_ruling.clone();
        distinct.sort_unstable();
        distinct.dedup();
        assert_eq!(distinct.len(), d.n + 1, "one point per step along the ruling, shared");
        assert_eq!(on_ruling.len(), 2 * 3 * d.n, "each met by both faces' sub-triangles");
    }

    #[test]
    fn a_degenerate_surface_leaves_the_chords_as_they_are() {
        let (pos, faces) = prism(12);
        for bad in [f64::NAN, 0.0, f64::INFINITY] {
            let on = FaceSurfaces { primitives: vec![cylinder(bad)], of: vec![0; faces.len()] };
            if let Some(d) = Displacement::new(&pos, &faces, &on) {
                for (f, t) in faces.iter().enumerate() {
                    for sub in d.sub_triangles(&pos, f, t).into_iter().flatten() {
                        assert!(sub.iter().all(|(p, _)| p.iter().all(|x| x.is_finite())));
                    }
                }
            }
        }
    }
}
