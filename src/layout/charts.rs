//! Charts and seams: a chart is a set of faces flattened together; seams are the mesh edges
//! between two charts.
//!
//! * **Chart vertices.** Inside a chart, the corners of a mesh vertex that are joined across
//!   the chart's own edges form one chart vertex (a union of corners, so a chart that touches
//!   itself at a vertex gets one chart vertex per fan). A chart is a **disk** when it is
//!   edge-connected, has a boundary and its Euler characteristic V − E + F is 1 (then its genus
//!   is 0 and it has one boundary loop), which is what a flattening needs.
//! * **Cutting** a region that cannot be flattened as it is, in order:
//!   1. along its **sharp creases** — edges whose dihedral angle (between the face normals)
//!      exceeds `crease_angle_deg` — into the pieces they enclose (creases that enclose
//!      nothing are left uncut);
//!   2. by **region growing on normal cones**: from the lowest-numbered face left, faces join
//!      across edges while their normal is within `cone_angle_deg` of the seed's; pieces of
//!      fewer than [`MIN_PIECE`] faces are merged into the neighbour they share most edges with;
//!   3. by **bisection**: two faces far apart (a double breadth-first sweep) grow at the same
//!      pace until they meet, so both halves are edge-connected.
//!
//!   Each piece is flattened again, and cut further if it still fails, down to single
//!   triangles, which always flatten exactly: the process ends on every mesh.

use std::collections::VecDeque;

use nalgebra::Vector3;

use crate::mesh::halfedge::HalfEdges;
use crate::mesh::union_find::UnionFind;
use crate::mesh::Mesh;

/// Pieces from the normal-cone growing with fewer faces than this are merged into a
/// neighbour.
pub const MIN_PIECE: usize = 8;

/// A chart as its own small mesh.
pub(crate) struct ChartMesh {
    /// Mesh faces of the chart, in the region's order.
    pub faces: Vec<u32>,
    /// Triangles in chart vertex ids (same order as `faces`).
    pub tris: Vec<[u32; 3]>,
    /// For each chart vertex, its mesh vertex.
    pub vertex: Vec<u32>,
    /// Boundary edges of the chart (chart vertex ids, in the direction of their face).
    pub boundary: Vec<[u32; 2]>,
    /// V − E + F.
    pub euler: i64,
}

impl ChartMesh {
    /// The chart made of `faces`; `tag[f] == id` marks the faces of the chart and `pos[f]` is
    /// the index of face `f` in `faces`.
    pub(crate) fn new(
        faces: &[u32],
        he: &HalfEdges,
        mesh: &Mesh,
        tag: &[u32],
        pos: &[u32],
        id: u32,
    ) -> ChartMesh {
        let nf = faces.len();
        let local = |h: u32| pos[(h / 3) as usize] * 3 + h % 3;
        let mut uf = UnionFind::new(3 * nf);
        let mut boundary_h = Vec::new();
        for &f in faces {
            for c in 0..3 {
                let h = 3 * f + c;
                match he.twin(h) {
                    Some(t) if tag[(t / 3) as usize] == id => {
                        if f < t / 3 {
                            uf.union(local(h), local(HalfEdges::next(t)));
                            uf.union(local(HalfEdges::next(h)), local(t));
                        }
                    }
                    _ => boundary_h.push(h),
                }
            }
        }
        let (label, nv) = uf.labels();
        let mut vertex = vec![0u32; nv];
        let mut tris = Vec::with_capacity(nf);
        for (i, &f) in faces.iter().enumerate() {
            let t = [label[3 * i], label[3 * i + 1], label[3 * i + 2]];
            for c in 0..3 {
                vertex[t[c] as usize] = mesh.faces[f as usize][c];
            }
            tris.push(t);
        }
        let boundary: Vec<[u32; 2]> = boundary_h
            .iter()
            .map(|&h| [label[local(h) as usize], label[local(HalfEdges::next(h)) as usize]])
            .collect();
        let edges = (3 * nf + boundary.len()) / 2;
        let euler = nv as i64 - edges as i64 + nf as i64;
        ChartMesh { faces: faces.to_vec(), tris, vertex, boundary, euler }
    }

    /// Number of chart vertices.
    pub(crate) fn num_vertices(&self) -> usize {
        self.vertex.len()
    }

    /// Edge-connected (by construction), with a boundary and V − E + F = 1.
    pub(crate) fn is_disk(&self) -> bool {
        self.euler == 1 && !self.boundary.is_empty()
    }

    /// The chart's vertex positions.
    pub(crate) fn positions(&self, mesh: &Mesh) -> Vec<Vector3<f64>> {
        self.vertex.iter().map(|&v| mesh.positions[v as usize]).collect()
    }
}

/// Unit normal of each face (zero for a degenerate face).
pub(crate) fn face_normals(mesh: &Mesh) -> Vec<Vector3<f64>> {
    (0..mesh.num_faces())
        .map(|f| {
            let [a, b, c] = mesh.face_positions(f);
            let n = (b - a).cross(&(c - a));
            let l = n.norm();
            if l > 0.0 && l.is_finite() {
                n / l
            } else {
                Vector3::zeros()
            }
        })
        .collect()
}

/// The edge-connected pieces of `region` (faces with `tag == id`) when faces may only be
/// joined across half-edges `h` for which `join(h)` holds. Pieces are in order of their first
/// face in `region`.
pub(crate) fn pieces(
    region: &[u32],
    he: &HalfEdges,
    tag: &[u32],
    id: u32,
    join: impl Fn(u32) -> bool,
) -> Vec<Vec<u32>> {
    let mut seen = std::collections::HashSet::with_capacity(region.len());
    let mut out = Vec::new();
    let mut queue = VecDeque::new();
    for &f0 in region {
        if !seen.insert(f0) {
            continue;
        }
        let mut piece = vec![f0];
        queue.push_back(f0);
        while let Some(f) = queue.pop_front() {
            for c in 0..3 {
                let h = 3 * f + c;
                let Some(t) = he.twin(h) else { continue };
                let g = t / 3;
                if tag[g as usize] == id && join(h) && seen.insert(g) {
                    piece.push(g);
                    queue.push_back(g);
                }
            }
        }
        out.push(piece);
    }
    out
}

/// Region growing on normal cones (see the module documentation), small pieces merged.
pub(crate) fn cone_pieces(
    region: &[u32],
    he: &HalfEdges,
    normals: &[Vector3<f64>],
    tag: &[u32],
    id: u32,
    cone_cos: f64,
) -> Vec<Vec<u32>> {
    // piece[f] for faces of the region (index into `out`), via a map over the region.
    let mut piece_of: std::collections::HashMap<u32, usize> =
        std::collections::HashMap::with_capacity(region.len());
    let mut out: Vec<Vec<u32>> = Vec::new();
    let mut queue = VecDeque::new();
    for &f0 in region {
        if piece_of.contains_key(&f0) {
            continue;
        }
        let k = out.len();
        let seed = normals[f0 as usize];
        piece_of.insert(f0, k);
        let mut piece = vec![f0];
        queue.push_back(f0);
        while let Some(f) = queue.pop_front() {
            for c in 0..3 {
                let Some(t) = he.twin(3 * f + c) else { continue };
                let g = t / 3;
                if tag[g as usize] == id
                    && !piece_of.contains_key(&g)
                    && normals[g as usize].dot(&seed) >= cone_cos
                {
                    piece_of.insert(g, k);
                    piece.push(g);
                    queue.push_back(g);
                }
            }
        }
        out.push(piece);
    }
    // Merge small pieces into the neighbour sharing most edges (in piece order; a piece that
    // grew past MIN_PIECE by merges stays).
    let n = out.len();
    let mut target: Vec<usize> = (0..n).collect();
    let find = |target: &Vec<usize>, mut k: usize| {
        while target[k] != k {
            k = target[k];
        }
        k
    };
    let mut size: Vec<usize> = out.iter().map(Vec::len).collect();
    for k in 0..n {
        if size[k] >= MIN_PIECE || find(&target, k) != k {
            continue;
        }
        let mut counts: std::collections::BTreeMap<usize, usize> = Default::default();
        for &f in &out[k] {
            for c in 0..3 {
                let Some(t) = he.twin(3 * f + c) else { continue };
                let g = t / 3;
                if tag[g as usize] != id {
                    continue;
                }
                let p = find(&target, piece_of[&g]);
                if p != k {
                    *counts.entry(p).or_default() += 1;
                }
            }
        }
        // Most shared edges; ties to the lower piece.
        if let Some((&p, _)) = counts.iter().max_by(|a, b| a.1.cmp(b.1).then(b.0.cmp(a.0))) {
            target[k] = p;
            size[p] += size[k];
        }
    }
    let mut merged: Vec<Vec<u32>> = vec![Vec::new(); n];
    for (k, piece) in out.into_iter().enumerate() {
        merged[find(&target, k)].extend(piece);
    }
    merged.into_iter().filter(|p| !p.is_empty()).collect()
}

/// Breadth-first hop distance from `seeds` over the region; returns, for each face of the
/// region (in `region` order), the index of the seed that reached it first, and the last face
/// reached.
fn sweep(region: &[u32], he: &HalfEdges, tag: &[u32], id: u32, seeds: &[u32]) -> (Vec<u8>, u32) {
    let mut owner: std::collections::HashMap<u32, u8> =
        std::collections::HashMap::with_capacity(region.len());
    let mut queue = VecDeque::new();
    for (k, &s) in seeds.iter().enumerate() {
        owner.insert(s, k as u8);
        queue.push_back(s);
    }
    let mut last = seeds[0];
    while let Some(f) = queue.pop_front() {
        last = f;
        let o = owner[&f];
        for c in 0..3 {
            let Some(t) = he.twin(3 * f + c) else { continue };
            let g = t / 3;
            if tag[g as usize] == id && !owner.contains_key(&g) {
                owner.insert(g, o);
                queue.push_back(g);
            }
        }
    }
    (region.iter().map(|f| owner.get(f).copied().unwrap_or(0)).collect(), last)
}

/// Two edge-connected halves of an edge-connected region of at least two faces.
pub(crate) fn bisect(region: &[u32], he: &HalfEdges, tag: &[u32], id: u32) -> Vec<Vec<u32>> {
    let (_, a) = sweep(region, he, tag, id, &[region[0]]);
    let (_, b) = sweep(region, he, tag, id, &[a]);
    let b = if b == a { *region.iter().find(|&&f| f != a).unwrap_or(&a) } else { b };
    let (owner, _) = sweep(region, he, tag, id, &[a, b]);
    let mut halves = vec![Vec::new(), Vec::new()];
    for (i, &f) in region.iter().enumerate() {
        halves[owner[i] as usize].push(f);
    }
    halves.retain(|h| !h.is_empty());
    halves
}
