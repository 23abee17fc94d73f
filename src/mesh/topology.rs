//! Topology of a triangle mesh: ordered one-rings, boundary vertices and loops, connected
//! components, Euler characteristic and genus.
//!
//! * **One-ring** of `v`: its neighbours counter-clockwise around the face normals (faces are
//!   CCW, so around `v` the faces follow `h → twin(prev(h))`). The ring of a boundary vertex
//!   starts at the boundary neighbour whose edge has the faces on its left (`v → w` boundary
//!   half-edge) and ends at the other boundary neighbour, so it has one more vertex than faces.
//!   A non-manifold vertex (several fans of faces) gets the ring of its first fan only.
//! * **Boundary loops**: chains of boundary edges (one face), walked with the faces on the left;
//!   at a vertex where several fans meet, a loop continues within the fan it arrived in.
//! * **Euler characteristic** χ = V − E + F, and per component the **genus** from
//!   χ = 2 − 2g − b (b boundary loops); the genus is given only for manifold components.
//!
//! Everything is O(F) and deterministic whatever the thread count.

use rayon::prelude::*;
use serde::Serialize;

use super::halfedge::{EdgeKind, HalfEdges};
use super::union_find::UnionFind;
use super::{FaceId, Mesh, VertexId};
use crate::Result;

const BOUNDARY: u8 = 1;
const MULTI_FAN: u8 = 2;
const BAD_EDGE: u8 = 4;
const BLOCK: usize = 4096;

/// One connected component (faces connected through shared vertices).
#[derive(Clone, Debug, PartialEq, Eq, Serialize)]
pub struct Component {
    /// Vertices.
    pub vertices: usize,
    /// Undirected edges.
    pub edges: usize,
    /// Triangles.
    pub faces: usize,
    /// Boundary loops.
    pub boundary_loops: usize,
    /// χ = V − E + F.
    pub euler_characteristic: i64,
    /// g from χ = 2 − 2g − b; `None` when the component is not manifold (or χ is inconsistent
    /// with a closed-up orientable surface).
    pub genus: Option<u32>,
}

/// The ordered one-ring of a vertex.
#[derive(Clone, Copy, Debug)]
pub struct OneRing<'a> {
    /// Neighbours, counter-clockwise around the normal.
    pub vertices: &'a [VertexId],
    /// `faces[i]` is the triangle `(v, vertices[i], vertices[i + 1])` (indices mod the length for
    /// a closed ring); an open (boundary) ring has one face fewer than vertices.
    pub faces: &'a [FaceId],
    /// True for a boundary vertex: the ring starts and ends on the boundary.
    pub open: bool,
}

/// The topology of a mesh (see the module documentation).
#[derive(Clone, Debug, Default)]
pub struct Topology {
    he: HalfEdges,
    ring_offsets: Vec<u32>,
    ring: Vec<VertexId>,
    ring_face_offsets: Vec<u32>,
    ring_faces: Vec<FaceId>,
    flags: Vec<u8>,
    loop_offsets: Vec<u32>,
    loops: Vec<VertexId>,
    vertex_component: Vec<u32>,
    components: Vec<Component>,
    boundary_components: usize,
}

/// Walks the first fan of faces around `v` counter-clockwise, calling `visit` with each outgoing
/// half-edge. Returns the number of faces visited and whether the fan is open (a boundary).
pub(crate) fn walk_fan(he: &HalfEdges, v: u32, mut visit: impl FnMut(u32)) -> (usize, bool) {
    let out = he.outgoing(v);
    let Some(&first) = out.first() else { return (0, false) };
    let start = out.iter().copied().find(|&h| he.twin(h).is_none()).unwrap_or(first);
    let mut h = start;
    let mut n = 0;
    loop {
        visit(h);
        n += 1;
        match he.twin(HalfEdges::prev(h)) {
            None => return (n, true),
            Some(t) if t == start || n >= out.len() => return (n, false),
            Some(t) => h = t,
        }
    }
}

/// Flags of vertex `v`: boundary, several fans, touching a non-manifold or inconsistent edge.
pub(crate) fn vertex_flags(he: &HalfEdges, v: u32) -> u8 {
    let (n, open) = walk_fan(he, v, |_| {});
    flags_of(he, v, n, open)
}

fn flags_of(he: &HalfEdges, v: u32, n: usize, open: bool) -> u8 {
    let mut f = if open { BOUNDARY } else { 0 };
    if n < he.outgoing(v).len() {
        f |= MULTI_FAN;
    }
    let bad = |h: u32| matches!(he.kind(h), EdgeKind::NonManifold | EdgeKind::Inconsistent);
    if he.outgoing(v).iter().any(|&h| bad(h) || bad(HalfEdges::prev(h))) {
        f |= BAD_EDGE;
    }
    f
}

/// Vertices with several fans of faces whose edges are all manifold or boundary (vertices on
/// non-manifold or inconsistent edges are reported through those edges).
pub(crate) fn nonmanifold_vertices_from_flags(flags: &[u8]) -> Vec<VertexId> {
    (0..flags.len())
        .filter(|&v| flags[v] & (MULTI_FAN | BAD_EDGE) == MULTI_FAN)
        .map(|v| VertexId(v as u32))
        .collect()
}

struct RingBlock {
    ring: Vec<VertexId>,
    ring_len: Vec<u32>,
    faces: Vec<FaceId>,
    face_len: Vec<u32>,
    flags: Vec<u8>,
}

impl Topology {
    /// Computes the topology of `mesh`. Fails only if a face refers to a missing vertex.
    pub fn new(mesh: &Mesh) -> Result<Self> {
        let he = HalfEdges::new(mesh.num_vertices(), &mesh.faces)?;
        Ok(Self::from_halfedges(he))
    }

    /// Computes the topology from existing half-edge connectivity.
    pub fn from_halfedges(he: HalfEdges) -> Self {
        let mut t = Topology { he, ..Default::default() };
        t.build_rings();
        t.build_loops();
        t.build_components();
        t
    }

    fn build_rings(&mut self) {
        let nv = self.he.num_vertices();
        let he = &self.he;
        let blocks: Vec<RingBlock> = (0..nv.div_ceil(BLOCK))
            .into_par_iter()
            .map(|b| ring_block(he, b * BLOCK..((b + 1) * BLOCK).min(nv)))
            .collect();
        let (mut ro, mut fo) = (Vec::with_capacity(nv + 1), Vec::with_capacity(nv + 1));
        ro.push(0u32);
        fo.push(0u32);
        for b in blocks {
            for (&rl, &fl) in b.ring_len.iter().zip(&b.face_len) {
                ro.push(ro.last().copied().unwrap_or(0) + rl);
                fo.push(fo.last().copied().unwrap_or(0) + fl);
            }
            self.ring.extend_from_slice(&b.ring);
            self.ring_faces.extend_from_slice(&b.faces);
            self.flags.extend_from_slice(&b.flags);
        }
        (self.ring_offsets, self.ring_face_offsets) = (ro, fo);
    }

    fn build_loops(&mut self) {
        let he = &self.he;
        let nh = he.num_halfedges() as u32;
        let mut visited = vec![false; nh as usize];
        let mut offsets = vec![0u32];
        for h0 in 0..nh {
            if visited[h0 as usize] || he.kind(h0) != EdgeKind::Boundary {
                continue;
            }
            let mut h = h0;
            loop {
                visited[h as usize] = true;
                self.loops.push(VertexId(he.origin(h)));
                match next_boundary(he, h) {
                    Some(g) if !visited[g as usize] => h = g,
                    _ => break,
                }
            }
            offsets.push(self.loops.len() as u32);
        }
        self.loop_offsets = offsets;
        let mut uf = UnionFind::new(he.num_vertices());
        let mut on_boundary = vec![false; he.num_vertices()];
        for h in 0..nh {
            if he.kind(h) == EdgeKind::Boundary {
                uf.union(he.origin(h), he.dest(h));
                on_boundary[he.origin(h) as usize] = true;
            }
        }
        self.boundary_components = (0..he.num_vertices() as u32)
            .filter(|&v| on_boundary[v as usize] && uf.find(v) == v)
            .count();
    }

    fn build_components(&mut self) {
        let he = &self.he;
        let nv = he.num_vertices();
        let mut uf = UnionFind::new(nv);
        for f in he.faces() {
            uf.union(f[0], f[1]);
            uf.union(f[0], f[2]);
        }
        let (labels, _) = uf.labels();
        // Renumber over vertices that have faces; isolated vertices get u32::MAX.
        let mut remap = vec![u32::MAX; nv];
        let mut comps: Vec<Component> = Vec::new();
        let mut manifold: Vec<bool> = Vec::new();
        let mut vc = vec![u32::MAX; nv];
        for v in 0..nv {
            if he.outgoing(v as u32).is_empty() {
                continue;
            }
            let l = labels[v] as usize;
            if remap[l] == u32::MAX {
                remap[l] = comps.len() as u32;
                comps.push(Component {
                    vertices: 0,
                    edges: 0,
                    faces: 0,
                    boundary_loops: 0,
                    euler_characteristic: 0,
                    genus: None,
                });
                manifold.push(true);
            }
            let c = remap[l] as usize;
            vc[v] = c as u32;
            comps[c].vertices += 1;
            if self.flags[v] & (MULTI_FAN | BAD_EDGE) != 0 {
                manifold[c] = false;
            }
        }
        for f in he.faces() {
            comps[vc[f[0] as usize] as usize].faces += 1;
        }
        for h in 0..he.num_halfedges() as u32 {
            if he.is_representative(h) {
                comps[vc[he.origin(h) as usize] as usize].edges += 1;
            }
        }
        for l in 0..self.num_boundary_loops() {
            let v = self.boundary_loop(l)[0];
            comps[vc[v.index()] as usize].boundary_loops += 1;
        }
        for (c, m) in comps.iter_mut().zip(manifold) {
            c.euler_characteristic = c.vertices as i64 - c.edges as i64 + c.faces as i64;
            let twice_g = 2 - c.euler_characteristic - c.boundary_loops as i64;
            if m && twice_g >= 0 && twice_g % 2 == 0 {
                c.genus = Some((twice_g / 2) as u32);
            }
        }
        self.vertex_component = vc;
        self.components = comps;
    }

    /// The half-edge connectivity.
    pub fn halfedges(&self) -> &HalfEdges {
        &self.he
    }

    /// Number of vertices.
    pub fn num_vertices(&self) -> usize {
        self.flags.len()
    }

    /// Number of undirected edges.
    pub fn num_edges(&self) -> usize {
        self.he.num_edges()
    }

    /// The ordered one-ring of `v` (see the module documentation).
    pub fn one_ring(&self, v: VertexId) -> OneRing<'_> {
        let i = v.index();
        let r = self.ring_offsets[i] as usize..self.ring_offsets[i + 1] as usize;
        let f = self.ring_face_offsets[i] as usize..self.ring_face_offsets[i + 1] as usize;
        OneRing {
            vertices: &self.ring[r],
            faces: &self.ring_faces[f],
            open: self.flags[i] & BOUNDARY != 0,
        }
    }

    /// True when `v` lies on the boundary.
    pub fn is_boundary_vertex(&self, v: VertexId) -> bool {
        self.flags[v.index()] & BOUNDARY != 0
    }

    /// The boundary vertices, by increasing index.
    pub fn boundary_vertices(&self) -> Vec<VertexId> {
        (0..self.num_vertices() as u32)
            .map(VertexId)
            .filter(|&v| self.is_boundary_vertex(v))
            .collect()
    }

    /// Number of boundary loops.
    pub fn num_boundary_loops(&self) -> usize {
        self.loop_offsets.len() - 1
    }

    /// The vertices of boundary loop `l`, in order with the faces on the left; it has as many
    /// edges as vertices.
    pub fn boundary_loop(&self, l: usize) -> &[VertexId] {
        &self.loops[self.loop_offsets[l] as usize..self.loop_offsets[l + 1] as usize]
    }

    /// Connected components of the graph of boundary edges. Equal to the number of boundary
    /// loops when every vertex is manifold; smaller when loops touch at a vertex.
    pub fn num_boundary_components(&self) -> usize {
        self.boundary_components
    }

    /// The connected components, numbered by their first vertex.
    pub fn components(&self) -> &[Component] {
        &self.components
    }

    /// The component of each vertex (`u32::MAX` for a vertex without faces).
    pub fn vertex_component(&self) -> &[u32] {
        &self.vertex_component
    }

    /// χ = V − E + F of the whole mesh.
    pub fn euler_characteristic(&self) -> i64 {
        self.num_vertices() as i64 - self.num_edges() as i64 + self.he.faces().len() as i64
    }

    /// Sum of the components' genera, if every component has one.
    pub fn genus(&self) -> Option<u32> {
        self.components.iter().map(|c| c.genus).sum()
    }

    /// Non-manifold vertices (several fans of faces) whose edges are themselves manifold.
    pub fn nonmanifold_vertices(&self) -> Vec<VertexId> {
        nonmanifold_vertices_from_flags(&self.flags)
    }
}

/// The boundary half-edge that follows boundary half-edge `h` around its loop: the one leaving
/// `dest(h)` at the other end of the same fan of faces (rotating clockwise from `next(h)`).
/// At a non-manifold vertex this keeps each loop inside one fan.
fn next_boundary(he: &HalfEdges, h: u32) -> Option<u32> {
    let mut g = HalfEdges::next(h);
    for _ in 0..=he.outgoing(he.origin(g)).len() {
        match he.twin(g) {
            Some(t) => g = HalfEdges::next(t),
            None => return (he.kind(g) == EdgeKind::Boundary).then_some(g),
        }
    }
    None
}

fn ring_block(he: &HalfEdges, range: std::ops::Range<usize>) -> RingBlock {
    let mut b = RingBlock {
        ring: Vec::new(),
        ring_len: Vec::with_capacity(range.len()),
        faces: Vec::new(),
        face_len: Vec::with_capacity(range.len()),
        flags: Vec::with_capacity(range.len()),
    };
    for v in range {
        let (r0, f0) = (b.ring.len(), b.faces.len());
        let mut last = None;
        let (n, open) = walk_fan(he, v as u32, |h| {
            b.ring.push(VertexId(he.dest(h)));
            b.faces.push(HalfEdges::face(h));
            last = Some(h);
        });
        if let (true, Some(h)) = (open, last) {
            b.ring.push(VertexId(he.origin(HalfEdges::prev(h))));
        }
        b.ring_len.push((b.ring.len() - r0) as u32);
        b.face_len.push((b.faces.len() - f0) as u32);
        b.flags.push(flags_of(he, v as u32, n, open));
    }
    b
}

#[cfg(test)]
mod tests {
    use super::*;
    use nalgebra::Vector3;

    #[test]
    fn fan_of_two_triangles() {
        let p = vec![Vector3::zeros(); 4];
        let m = Mesh::from_triangles(p, vec![[0, 1, 2], [0, 2, 3]]);
        let t = Topology::new(&m).unwrap();
        let r = t.one_ring(VertexId(0));
        assert!(r.open);
        assert_eq!(r.vertices, &[VertexId(1), VertexId(2), VertexId(3)]);
        assert_eq!(r.faces, &[FaceId(0), FaceId(1)]);
        assert_eq!(t.num_boundary_loops(), 1);
        assert_eq!(t.boundary_loop(0).len(), 4);
        assert_eq!(t.euler_characteristic(), 1);
        assert_eq!(t.genus(), Some(0));
    }
}
