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
        let vf = super::VertexFaces::from_faces(num_vertices, faces);
        // Each vertex's sorted neighbours with multiplicity (= faces sharing the edge).
        let ring = |v: usize, buf: &mut Vec<u32>| {
            buf.clear();
            for &(f, _) in vf.of(v) {
                for &w in &faces[f as usize] {
                    if w as usize != v {
                        buf.push(w);
                    }
                }
            }
            buf.sort_unstable();
        };
        let valence: Vec<u32> = (0..num_vertices)
            .into_par_iter()
            .map_init(Vec::new, |buf, v| {
                ring(v, buf);
                let mut n = buf.len() as u32;
                for k in 1..buf.len() {
                    n -= (buf[k] == buf[k - 1]) as u32;
                }
                n
            })
            .collect();
        let mut offsets = Vec::with_capacity(num_vertices + 1);
        offsets.push(0u32);
        for v in 0..num_vertices {
            offsets.push(offsets[v] + valence[v]);
        }
        let entries: Vec<(u32, u16)> = (0..num_vertices)
            .into_par_iter()
            .map_init(Vec::new, |buf, v| {
                ring(v, buf);
                let mut out: Vec<(u32, u16)> = Vec::with_capacity(valence[v] as usize);
                for &w in buf.iter() {
                    match out.last_mut() {
                        Some(last) if last.0 == w => last.1 = last.1.saturating_add(1),
                        _ => out.push((w, 1)),
                    }
                }
                out
            })
            .flatten_iter()
            .collect();
        let (neighbors, edge_faces): (Vec<u32>, Vec<u16>) = entries.into_iter().unzip();
        let mut adj = Adjacency { offsets, neighbors, edge_faces, reverse: Vec::new() };
        adj.reverse = (0..num_vertices)
            .into_par_iter()
            .flat_map_iter(|i| {
                let adj = &adj;
                adj.slots(i).map(move |s| {
                    adj.slot(adj.target(s), i as u32).expect("adjacency is symmetric") as u32
                })
            })
            .collect();
        adj
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
}
