//! Half-edge connectivity of a triangle mesh, with every edge classified.
//!
//! Half-edge `h = 3f + c` runs from corner `c` of face `f` to corner `c + 1 (mod 3)`; the face
//! lies on its left. The outgoing half-edges of every vertex are stored in CSR form. Edges are
//! classified after ordering the half-edges by undirected key with two counting sorts: no
//! hashing, O(V + F) work whatever the vertex valences, deterministic.
//!
//! An undirected edge is classified by the half-edges along it:
//! one — [`EdgeKind::Boundary`]; two in opposite directions — [`EdgeKind::Manifold`] (they are
//! twins); two in the same direction — [`EdgeKind::Inconsistent`] (the two faces are oriented
//! inconsistently); three or more — [`EdgeKind::NonManifold`]. Only manifold half-edges have a
//! twin.

use rayon::prelude::*;

use super::{FaceId, VertexId};
use crate::{Error, Result};

/// No half-edge (a missing twin).
pub const NO_HALFEDGE: u32 = u32::MAX;

/// The class of an undirected edge.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum EdgeKind {
    /// One face.
    Boundary,
    /// Two faces traversing it in opposite directions.
    Manifold,
    /// Two faces traversing it in the same direction.
    Inconsistent,
    /// Three or more faces.
    NonManifold,
}

const REP_BIT: u8 = 0x80;

/// Half-edge connectivity (see the module documentation).
#[derive(Clone, Debug, Default)]
pub struct HalfEdges {
    faces: Vec<[u32; 3]>,
    out_offsets: Vec<u32>,
    out_edges: Vec<u32>,
    out_dest: Vec<u32>,
    twin: Vec<u32>,
    /// `EdgeKind as u8`, with `REP_BIT` set on one half-edge per undirected edge.
    kind: Vec<u8>,
    num_edges: usize,
    steps: u64,
    /// The edge with the most half-edges along it: (its representative, that count).
    widest: (u32, u32),
}

impl HalfEdges {
    /// Builds the connectivity of `num_vertices` vertices and the triangles `faces`.
    ///
    /// Fails (instead of panicking) when a face refers to a vertex that does not exist or the
    /// mesh has more half-edges than `u32` can index.
    pub fn new(num_vertices: usize, faces: &[[u32; 3]]) -> Result<Self> {
        let invalid = |m: String| Error::InvalidMesh { path: "<mesh>".into(), message: m };
        if faces.len() >= (u32::MAX / 3) as usize || num_vertices >= u32::MAX as usize {
            return Err(invalid(format!("too large: {} faces", faces.len())));
        }
        if let Some(f) = faces.iter().position(|f| f.iter().any(|&v| v as usize >= num_vertices)) {
            return Err(invalid(format!("face {f} refers to a vertex ≥ {num_vertices}")));
        }
        let mut he = HalfEdges { faces: faces.to_vec(), ..Default::default() };
        he.build_out_lists(num_vertices);
        let (twin, kind, num_edges, steps, widest) = he.classify_all(num_vertices);
        (he.twin, he.kind, he.num_edges, he.steps, he.widest) =
            (twin, kind, num_edges, steps, widest);
        Ok(he)
    }

    /// The outgoing half-edges of every vertex (by increasing index) and their end vertices, by
    /// one counting sort of the corners.
    fn build_out_lists(&mut self, nv: usize) {
        // The outgoing half-edge of corner c of face f is 3f + c, towards the next corner.
        let mut offsets = vec![0u32; nv + 1];
        for f in &self.faces {
            for &v in f {
                offsets[v as usize + 1] += 1;
            }
        }
        for v in 0..nv {
            offsets[v + 1] += offsets[v];
        }
        let mut fill = offsets[..nv].to_vec();
        let nh = 3 * self.faces.len();
        let (mut edges, mut dest) = (vec![0u32; nh], vec![0u32; nh]);
        for (fi, f) in self.faces.iter().enumerate() {
            for (c, &v) in f.iter().enumerate() {
                let slot = &mut fill[v as usize];
                edges[*slot as usize] = 3 * fi as u32 + c as u32;
                dest[*slot as usize] = f[(c + 1) % 3];
                *slot += 1;
            }
        }
        (self.out_offsets, self.out_edges, self.out_dest) = (offsets, edges, dest);
    }

    /// Twins, kinds (with the representative bit), the number of undirected edges, the loop
    /// iterations and the widest edge (its representative and its number of half-edges).
    ///
    /// The half-edges are ordered by their undirected key `(min, max)` of end vertices with two
    /// stable counting sorts (by `max`, then by `min`): O(V + H) work whatever the vertex
    /// valences, and within one key by increasing index. Each run of equal keys is one
    /// undirected edge; a half-edge along it is classified by how many of the run's half-edges
    /// run its way (`same`) and the other way (`opp`). A degenerate edge `a → a` counts every
    /// half-edge of its run both ways, as a scan of `a`'s outgoing list would.
    fn classify_all(&self, nv: usize) -> (Vec<u32>, Vec<u8>, usize, u64, (u32, u32)) {
        let nh = 3 * self.faces.len();
        let ends = |h: u32| (self.origin(h), self.dest(h));
        let key = |h: u32| {
            let (a, b) = ends(h);
            (a.min(b), a.max(b))
        };
        // Stable counting sort of `order` by `digit`.
        let counting_sort = |order: &[u32], digit: &dyn Fn(u32) -> u32| -> Vec<u32> {
            let mut start = vec![0u32; nv + 1];
            for &h in order {
                start[digit(h) as usize + 1] += 1;
            }
            for v in 0..nv {
                start[v + 1] += start[v];
            }
            let mut out = vec![0u32; order.len()];
            for &h in order {
                let slot = &mut start[digit(h) as usize];
                out[*slot as usize] = h;
                *slot += 1;
            }
            out
        };
        // Loop iterations of the sorts and the runs (see [`HalfEdges::classify_steps`]).
        let mut steps = 2 * (2 * nh as u64 + nv as u64);
        let all: Vec<u32> = (0..nh as u32).collect();
        let by_max = counting_sort(&all, &|h| key(h).1);
        drop(all);
        let order = counting_sort(&by_max, &|h| key(h).0);
        drop(by_max);
        let (mut twin, mut kind) = (vec![NO_HALFEDGE; nh], vec![0u8; nh]);
        let mut num_edges = 0;
        let mut widest = (NO_HALFEDGE, 0u32);
        let mut i = 0;
        while i < nh {
            let k = key(order[i]);
            let mut j = i + 1;
            while j < nh && key(order[j]) == k {
                j += 1;
            }
            let run = &order[i..j];
            num_edges += 1;
            steps += 3 * run.len() as u64;
            let min_id = run[0]; // runs are by increasing index
            let (a0, _) = ends(run[0]);
            let along_a0 = run.iter().filter(|&&h| ends(h).0 == a0).count() as u32;
            let total = run.len() as u32;
            if total > widest.1 {
                widest = (min_id, total);
            }
            for &h in run {
                let (a, b) = ends(h);
                let (same, opp) = if a == b {
                    (total, total)
                } else if a == a0 {
                    (along_a0, total - along_a0)
                } else {
                    (total - along_a0, along_a0)
                };
                let (t, kd) = match (same, opp) {
                    (1, 0) => (NO_HALFEDGE, EdgeKind::Boundary),
                    // The one other half-edge of the run (for a loop: the last one, as before).
                    (1, 1) => {
                        steps += 2;
                        let other = run.iter().rev().find(|&&g| g != h || a == b);
                        (*other.unwrap_or(&h), EdgeKind::Manifold)
                    }
                    (s, o) if s + o == 2 => (NO_HALFEDGE, EdgeKind::Inconsistent),
                    _ => (NO_HALFEDGE, EdgeKind::NonManifold),
                };
                twin[h as usize] = t;
                kind[h as usize] = kd as u8 | if h == min_id { REP_BIT } else { 0 };
            }
            i = j;
        }
        (twin, kind, num_edges, steps, widest)
    }

    fn out_range(&self, v: u32) -> std::ops::Range<usize> {
        self.out_offsets[v as usize] as usize..self.out_offsets[v as usize + 1] as usize
    }

    /// Loop iterations spent classifying the edges: at most `2·V + 9·H` (V vertices, H
    /// half-edges) whatever the vertex valences — a work counter for tests of the O(V + H)
    /// bound, which no wall-clock test could check reliably.
    pub fn classify_steps(&self) -> u64 {
        self.steps
    }

    /// The edge with the most faces along it (the first such, by half-edge index): one of its
    /// half-edges and its number of faces; `None` for a mesh without faces.
    pub fn widest_edge(&self) -> Option<(u32, usize)> {
        (self.widest.1 > 0).then_some((self.widest.0, self.widest.1 as usize))
    }

    /// Number of vertices.
    pub fn num_vertices(&self) -> usize {
        self.out_offsets.len().saturating_sub(1)
    }

    /// Number of half-edges (three per face).
    pub fn num_halfedges(&self) -> usize {
        self.twin.len()
    }

    /// Number of undirected edges.
    pub fn num_edges(&self) -> usize {
        self.num_edges
    }

    /// The triangles the connectivity was built from.
    pub fn faces(&self) -> &[[u32; 3]] {
        &self.faces
    }

    /// Start vertex of `h`.
    #[inline]
    pub fn origin(&self, h: u32) -> u32 {
        self.faces[(h / 3) as usize][(h % 3) as usize]
    }

    /// End vertex of `h`.
    #[inline]
    pub fn dest(&self, h: u32) -> u32 {
        self.faces[(h / 3) as usize][((h % 3 + 1) % 3) as usize]
    }

    /// The face on the left of `h`.
    #[inline]
    pub fn face(h: u32) -> FaceId {
        FaceId(h / 3)
    }

    /// The next half-edge around the same face.
    #[inline]
    pub fn next(h: u32) -> u32 {
        h - h % 3 + (h % 3 + 1) % 3
    }

    /// The previous half-edge around the same face.
    #[inline]
    pub fn prev(h: u32) -> u32 {
        h - h % 3 + (h % 3 + 2) % 3
    }

    /// The opposite half-edge of a manifold edge.
    #[inline]
    pub fn twin(&self, h: u32) -> Option<u32> {
        let t = self.twin[h as usize];
        (t != NO_HALFEDGE).then_some(t)
    }

    /// The class of the undirected edge of `h`.
    #[inline]
    pub fn kind(&self, h: u32) -> EdgeKind {
        match self.kind[h as usize] & !REP_BIT {
            0 => EdgeKind::Boundary,
            1 => EdgeKind::Manifold,
            2 => EdgeKind::Inconsistent,
            _ => EdgeKind::NonManifold,
        }
    }

    /// True for exactly one half-edge of every undirected edge (the smallest index).
    #[inline]
    pub fn is_representative(&self, h: u32) -> bool {
        self.kind[h as usize] & REP_BIT != 0
    }

    /// The outgoing half-edges of vertex `v`, by increasing index.
    #[inline]
    pub fn outgoing(&self, v: u32) -> &[u32] {
        &self.out_edges[self.out_range(v)]
    }

    /// One half-edge per undirected edge of the given kind, by increasing index.
    pub fn edges_of_kind(&self, kind: EdgeKind) -> Vec<u32> {
        (0..self.num_halfedges() as u32)
            .into_par_iter()
            .filter(|&h| self.is_representative(h) && self.kind(h) == kind)
            .collect()
    }

    /// The faces along the undirected edge of `h`, by increasing index.
    pub fn edge_faces(&self, h: u32) -> Vec<FaceId> {
        let (a, b) = (self.origin(h), self.dest(h));
        let mut out: Vec<FaceId> = self
            .outgoing(a)
            .iter()
            .filter(|&&g| self.dest(g) == b)
            .chain(self.outgoing(b).iter().filter(|&&g| self.dest(g) == a))
            .map(|&g| Self::face(g))
            .collect();
        out.sort_unstable();
        out
    }

    /// The endpoints of `h`.
    pub fn endpoints(&self, h: u32) -> (VertexId, VertexId) {
        (VertexId(self.origin(h)), VertexId(self.dest(h)))
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn classify_two_triangles_and_fin() {
        let he = HalfEdges::new(4, &[[0, 1, 2], [0, 2, 3]]).unwrap();
        assert_eq!(he.num_edges(), 5);
        let h = 2; // 2 -> 0 in face 0
        assert_eq!(he.kind(h), EdgeKind::Manifold);
        assert_eq!(he.twin(h), Some(3)); // 0 -> 2 in face 1
        let fin = HalfEdges::new(5, &[[0, 1, 2], [1, 0, 3], [0, 1, 4]]).unwrap();
        assert_eq!(fin.edges_of_kind(EdgeKind::NonManifold).len(), 1);
        let flip = HalfEdges::new(4, &[[0, 1, 2], [0, 1, 3]]).unwrap();
        assert_eq!(flip.edges_of_kind(EdgeKind::Inconsistent), vec![0]);
        assert!(HalfEdges::new(2, &[[0, 1, 2]]).is_err());
    }

    /// The former classification, by scanning both end vertices' out-lists (O(valence) per
    /// half-edge): the reference the counting-sort classification must reproduce exactly.
    fn scan_classify(he: &HalfEdges, h: u32) -> (u32, u8) {
        let (a, b) = (he.origin(h), he.dest(h));
        let (mut same, mut opp, mut cand, mut min_id) = (0u32, 0u32, NO_HALFEDGE, h);
        for &g in he.outgoing(a) {
            if he.dest(g) == b {
                same += 1;
                min_id = min_id.min(g);
            }
        }
        for &g in he.outgoing(b) {
            if he.dest(g) == a {
                opp += 1;
                cand = g;
                min_id = min_id.min(g);
            }
        }
        let (twin, kind) = match (same, opp) {
            (1, 0) => (NO_HALFEDGE, EdgeKind::Boundary),
            (1, 1) => (cand, EdgeKind::Manifold),
            (s, o) if s + o == 2 => (NO_HALFEDGE, EdgeKind::Inconsistent),
            _ => (NO_HALFEDGE, EdgeKind::NonManifold),
        };
        (twin, kind as u8 | if min_id == h { REP_BIT } else { 0 })
    }

    #[test]
    fn classification_matches_the_outlist_scan_on_random_soups() {
        // Random triangles over few vertices: duplicates, flips, fins and repeated corners.
        let mut x: u64 = 0x9e37_79b9_7f4a_7c15;
        let mut next = |m: u64| {
            x ^= x << 13;
            x ^= x >> 7;
            x ^= x << 17;
            (x % m) as u32
        };
        for round in 0..300 {
            let nv = 3 + round % 9;
            let nf = 1 + next(40) as usize;
            let faces: Vec<[u32; 3]> =
                (0..nf).map(|_| [next(nv as u64), next(nv as u64), next(nv as u64)]).collect();
            let he = HalfEdges::new(nv, &faces).unwrap();
            let mut reps = 0;
            for h in 0..he.num_halfedges() as u32 {
                assert_eq!((he.twin[h as usize], he.kind[h as usize]), scan_classify(&he, h));
                reps += he.is_representative(h) as usize;
            }
            assert_eq!(he.num_edges(), reps);
            assert!(he.classify_steps() <= 2 * nv as u64 + 9 * he.num_halfedges() as u64);
        }
    }

    #[test]
    fn icosphere_is_closed_and_manifold() {
        // 10·4^k + 2 vertices, 20·4^k faces, 30·4^k edges (k = 2); every edge has two faces.
        let m = crate::generate::icosphere(1.0, 2);
        let he = HalfEdges::new(m.num_vertices(), &m.faces).unwrap();
        assert_eq!((he.num_vertices(), he.num_halfedges(), he.num_edges()), (162, 960, 480));
        for h in 0..960 {
            assert_eq!(he.kind(h), EdgeKind::Manifold);
            let t = he.twin(h).unwrap();
            assert_eq!((he.twin(t), he.origin(t), he.dest(t)), (Some(h), he.dest(h), he.origin(h)));
            assert_eq!(he.is_representative(h), h < t);
        }
        for v in 0..162 {
            let out = he.outgoing(v);
            assert!(out.windows(2).all(|w| w[0] < w[1]));
            assert!(out.iter().all(|&h| he.origin(h) == v));
            assert_eq!(out.len(), if v < 12 { 5 } else { 6 });
        }
    }
}
