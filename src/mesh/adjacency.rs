//! Vertex adjacency in compressed sparse row (CSR) form.
//!
//! For every vertex `i` the neighbours `j` (vertices sharing an edge with `i`) are stored sorted
//! by index in one flat array. Every slot `s` of that array is a *directed* edge `i → j`; the
//! slot of the reverse edge `j → i` is [`Adjacency::reverse`]. Per-directed-edge quantities
//! (the transport angle ρᵢⱼ, regression weights) live in arrays parallel to the slots.
//!
//! The number of faces sharing each undirected edge is kept too, so boundary edges (one face)
//! and non-manifold edges (three or more) are known.

use rayon::prelude::*;

/// Vertices per parallel work item.
const CHUNK: usize = 4096;

/// The next corner of a triangle.
const NEXT: [usize; 3] = [1, 2, 0];

/// Vertex-to-vertex adjacency of a triangle mesh, in CSR form.
#[derive(Clone, Debug, Default)]
pub struct Adjacency {
    offsets: Vec<u32>,
    neighbors: Vec<u32>,
    /// Number of faces sharing the undirected edge of each slot.
    edge_faces: Vec<u16>,
    reverse: Vec<u32>,
}

impl Adjacency {
    /// Builds the adjacency of `num_vertices` vertices from triangles.
    ///
    /// Linear time: a counting sort gives each vertex its faces, and each vertex then sorts its
    /// own few neighbours (in parallel). Deterministic whatever the thread count.
    pub fn from_faces(num_vertices: usize, faces: &[[u32; 3]]) -> Self {
        Self::from_vertex_faces(faces, &super::VertexFaces::from_faces(num_vertices, faces))
    }

    /// [`Adjacency::from_faces`] reusing the vertex-to-face incidence `vf` of `faces`.
    pub fn from_vertex_faces(faces: &[[u32; 3]], vf: &super::VertexFaces) -> Self {
        let num_vertices = vf.offsets().len().saturating_sub(1);
        // Each vertex's neighbours sorted, with multiplicity (= faces sharing the edge), gathered
        // once per fixed chunk of vertices into the chunk's own arrays.
        let chunks: Vec<(Vec<u32>, Vec<u16>, Vec<u32>)> = (0..num_vertices.div_ceil(CHUNK))
            .into_par_iter()
            .map(|c| {
                let (v0, v1) = (c * CHUNK, num_vertices.min((c + 1) * CHUNK));
                let corners = (vf.offsets()[v1] - vf.offsets()[v0]) as usize;
                let (mut nb, mut ef) = (Vec::with_capacity(corners), Vec::with_capacity(corners));
                let (mut valence, mut buf) = (Vec::with_capacity(v1 - v0), Vec::new());
                for v in v0..v1 {
                    buf.clear();
                    for &(f, c) in vf.of(v) {
                        // The other two corners (v is corner c; a face may repeat a vertex).
                        let f = &faces[f as usize];
                        for w in [f[NEXT[c as usize]], f[NEXT[NEXT[c as usize]]]] {
                            if w as usize != v {
                                buf.push(w);
                            }
                        }
                    }
                    buf.sort_unstable();
                    let start = nb.len();
                    for (m, &w) in buf.iter().enumerate() {
                        if m > 0 && buf[m - 1] == w {
                            let last: &mut u16 = ef.last_mut().expect("a neighbour before");
                            *last = last.saturating_add(1);
                        } else {
                            nb.push(w);
                            ef.push(1u16);
                        }
                    }
                    valence.push((nb.len() - start) as u32);
                }
                (nb, ef, valence)
            })
            .collect();
        let mut offsets = Vec::with_capacity(num_vertices + 1);
        offsets.push(0u32);
        for (_, _, valence) in &chunks {
            for &n in valence {
                offsets.push(offsets[offsets.len() - 1] + n);
            }
        }
        let total = offsets[num_vertices] as usize;
        let (mut neighbors, mut edge_faces) = (vec![0u32; total], vec![0u16; total]);
        let mut pieces = Vec::with_capacity(chunks.len());
        let (mut rest_n, mut rest_e) = (&mut neighbors[..], &mut edge_faces[..]);
        for chunk in &chunks {
            let (head_n, tail_n) = std::mem::take(&mut rest_n).split_at_mut(chunk.0.len());
            let (head_e, tail_e) = std::mem::take(&mut rest_e).split_at_mut(chunk.0.len());
            pieces.push((chunk, head_n, head_e));
            (rest_n, rest_e) = (tail_n, tail_e);
        }
        pieces.into_par_iter().for_each(|((nb, ef, _), n, e)| {
            n.copy_from_slice(nb);
            e.copy_from_slice(ef);
        });
        drop(chunks);
        let mut adj = Adjacency { offsets, neighbors, edge_faces, reverse: Vec::new() };
        // Rows by increasing i: the k-th slot towards j met is j's k-th smallest neighbour, i
        // itself (the adjacency is symmetric and sorted), so one cursor per row gives the slot.
        let mut reverse = vec![0u32; total];
        let mut cursor = adj.offsets[..num_vertices].to_vec();
        for (s, r) in reverse.iter_mut().enumerate() {
            let j = adj.neighbors[s] as usize;
            *r = cursor[j];
            cursor[j] += 1;
        }
        adj.reverse = reverse;
        adj
    }

    /// Fills `out` (one value per slot) with `f(i, s)` for every slot `s` of every vertex `i`,
    /// in parallel over fixed chunks of vertices (the result does not depend on the threads).
    pub fn fill_slots<T: Send>(&self, out: &mut [T], f: impl Fn(usize, usize) -> T + Sync) {
        assert_eq!(out.len(), self.num_slots(), "one value per slot");
        let none: &mut [()] = &mut vec![(); out.len()];
        par_vertex_slices(&self.offsets, out, none, |i, vals, _, _| {
            for (x, s) in vals.iter_mut().zip(self.slots(i)) {
                *x = f(i, s);
            }
        });
    }

    /// Number of vertices.
    #[inline]
    pub fn num_vertices(&self) -> usize {
        self.offsets.len().saturating_sub(1)
    }

    /// Number of directed edges (twice the number of undirected edges).
    #[inline]
    pub fn num_slots(&self) -> usize {
        self.neighbors.len()
    }

    /// Number of undirected edges.
    #[inline]
    pub fn num_edges(&self) -> usize {
        self.neighbors.len() / 2
    }

    /// The slot range of vertex `i`.
    #[inline]
    pub fn slots(&self, i: usize) -> std::ops::Range<usize> {
        self.offsets[i] as usize..self.offsets[i + 1] as usize
    }

    /// The neighbours of vertex `i`, sorted by index.
    #[inline]
    pub fn neighbors(&self, i: usize) -> &[u32] {
        &self.neighbors[self.slots(i)]
    }

    /// Number of neighbours of vertex `i` (its valence).
    #[inline]
    pub fn valence(&self, i: usize) -> usize {
        (self.offsets[i + 1] - self.offsets[i]) as usize
    }

    /// The target vertex of slot `s`.
    #[inline]
    pub fn target(&self, s: usize) -> usize {
        self.neighbors[s] as usize
    }

    /// The slot of the reverse directed edge of slot `s`.
    #[inline]
    pub fn reverse(&self, s: usize) -> usize {
        self.reverse[s] as usize
    }

    /// The slot of the directed edge `i → j`, if the edge exists.
    pub fn slot(&self, i: usize, j: u32) -> Option<usize> {
        let r = self.slots(i);
        self.neighbors[r.clone()].binary_search(&j).ok().map(|k| r.start + k)
    }

    /// Number of faces sharing the undirected edge of slot `s` (1 on the boundary).
    #[inline]
    pub fn edge_face_count(&self, s: usize) -> usize {
        self.edge_faces[s] as usize
    }

    /// True when the undirected edge of slot `s` has exactly one face.
    #[inline]
    pub fn is_boundary_slot(&self, s: usize) -> bool {
        self.edge_faces[s] == 1
    }

    /// True when vertex `i` lies on a boundary edge (or has no neighbour at all).
    pub fn is_boundary_vertex(&self, i: usize) -> bool {
        let r = self.slots(i);
        r.is_empty() || self.edge_faces[r].contains(&1)
    }

    /// Slots whose undirected edge is shared by three or more faces, each edge once (`i < j`).
    pub fn nonmanifold_edges(&self) -> Vec<(u32, u32)> {
        (0..self.num_vertices())
            .flat_map(|i| {
                self.slots(i)
                    .filter(move |&s| self.edge_faces[s] > 2 && (i as u32) < self.neighbors[s])
                    .map(move |s| (i as u32, self.neighbors[s]))
            })
            .collect()
    }
}

/// Calls `f(i, a_i, b_i, scratch)` for every vertex `i`, where `a_i` and `b_i` are the parts of
/// `a` and `b` (one entry per slot) that belong to vertex `i`; in parallel over fixed chunks of
/// vertices, with one scratch buffer per chunk.
fn par_vertex_slices<A: Send, B: Send>(
    offsets: &[u32],
    a: &mut [A],
    b: &mut [B],
    f: impl Fn(usize, &mut [A], &mut [B], &mut Vec<u32>) + Sync,
) {
    let nv = offsets.len().saturating_sub(1);
    let mut pieces = Vec::with_capacity(nv.div_ceil(CHUNK));
    let (mut rest_a, mut rest_b) = (a, b);
    for c in 0..nv.div_ceil(CHUNK) {
        let (v0, v1) = (c * CHUNK, nv.min((c + 1) * CHUNK));
        let len = (offsets[v1] - offsets[v0]) as usize;
        let (head_a, tail_a) = std::mem::take(&mut rest_a).split_at_mut(len);
        let (head_b, tail_b) = std::mem::take(&mut rest_b).split_at_mut(len);
        pieces.push((v0, v1, head_a, head_b));
        (rest_a, rest_b) = (tail_a, tail_b);
    }
    pieces.into_par_iter().for_each(|(v0, v1, sa, sb)| {
        let base = offsets[v0] as usize;
        let mut scratch = Vec::new();
        for i in v0..v1 {
            let r = offsets[i] as usize - base..offsets[i + 1] as usize - base;
            f(i, &mut sa[r.clone()], &mut sb[r], &mut scratch);
        }
    });
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn two_triangles() {
        let adj = Adjacency::from_faces(4, &[[0, 1, 2], [0, 2, 3]]);
        assert_eq!(adj.neighbors(0), &[1, 2, 3]);
        assert_eq!(adj.neighbors(1), &[0, 2]);
        assert_eq!(adj.num_edges(), 5);
        let s = adj.slot(0, 2).unwrap();
        assert_eq!(adj.edge_face_count(s), 2);
        assert_eq!(adj.target(adj.reverse(s)), 0);
        assert!(adj.is_boundary_slot(adj.slot(0, 1).unwrap()));
        assert!(adj.is_boundary_vertex(0));
        assert!(adj.nonmanifold_edges().is_empty());
    }

    #[test]
    fn nonmanifold_fin() {
        let adj = Adjacency::from_faces(5, &[[0, 1, 2], [1, 0, 3], [0, 1, 4]]);
        assert_eq!(adj.nonmanifold_edges(), vec![(0, 1)]);
    }

    #[test]
    fn icosphere_valences_and_reverse_slots() {
        // A k-times subdivided icosahedron has 10·4^k + 2 vertices, 30·4^k edges, the 12
        // original vertices of valence 5 and all others of valence 6.
        let m = crate::generate::icosphere(1.0, 2);
        let adj = Adjacency::from_faces(m.num_vertices(), &m.faces);
        assert_eq!(adj.num_vertices(), 162);
        assert_eq!(adj.num_edges(), 480);
        let fives = (0..162).filter(|&i| adj.valence(i) == 5).count();
        assert_eq!((fives, (0..162).filter(|&i| adj.valence(i) == 6).count()), (12, 150));
        for i in 0..adj.num_vertices() {
            assert!(adj.neighbors(i).windows(2).all(|w| w[0] < w[1]));
            for s in adj.slots(i) {
                let r = adj.reverse(s);
                assert!(adj.slots(adj.target(s)).contains(&r));
                assert_eq!((adj.target(r), adj.reverse(r)), (i, s));
                assert_eq!(adj.edge_face_count(s), 2);
            }
        }
    }
}
