//! Charts and seams: a chart is a set of faces flattened together; seams are the mesh edges
//! between two charts.
//!
//! * **Chart vertices.** Inside a chart, the corners of a mesh vertex that are joined across
//!   the chart's own edges form one chart vertex (a union of corners, so a chart that touches
//!   itself at a vertex gets one chart vertex per fan). A chart is a **disk** when it is
//!   edge-connected, has a boundary and its Euler characteristic V − E + F is 1 (then its genus
//!   is 0 and it has one boundary loop). It is **planar** (a disk with holes) when its genus
//!   is 0: V − E + F = 2 − b for its b ≥ 1 boundary loops; such a chart flattens as it is.
//! * **Cutting** a region that cannot be flattened as it is, in order:
//!   1. along its **sharp creases** — edges whose dihedral angle (between the face normals)
//!      exceeds `crease_angle_deg` — into the pieces they enclose (creases that enclose
//!      nothing are left uncut);
//!   2. by **region growing on normal cones**: from the lowest-numbered face left, faces join
//!      across edges while their smoothed normal (`smoothed_normals`) is within
//!      `cone_angle_deg` of the seed's; the borders are smoothed (`smooth_labels`), pieces
//!      split into edge-connected parts, and parts of fewer than [`MIN_PIECE`] faces are
//!      merged into the neighbour they share most edges with;
//!   3. by **bisection**: two faces far apart (a double breadth-first sweep) grow at the same
//!      pace until they meet, so both halves are edge-connected.
//!
//!   Each piece is flattened again, and cut further if it still fails, down to single
//!   triangles, which always flatten exactly: the process ends on every mesh.
//! * **Noisy parts** ([`NOISE_FRACTION`]): their crease pieces of fewer than [`MIN_PIECE`]
//!   faces are merged into neighbours (`absorb_small`), and after every cut the faces around
//!   a vertex where one piece's fan reaches [`WRAP_ANGLE`] join that piece (`unwrap_fans`).

use std::collections::VecDeque;

use nalgebra::Vector3;

use crate::mesh::halfedge::HalfEdges;
use crate::mesh::union_find::UnionFind;
use crate::mesh::Mesh;

/// Pieces from the normal-cone growing with fewer faces than this are merged into a
/// neighbour.
pub const MIN_PIECE: usize = 8;

/// Rounds of normal smoothing before the cone test (`smoothed_normals`).
pub const NORMAL_SMOOTHING: usize = 3;

/// Rounds of border smoothing after the cone growing (`smooth_labels`).
pub const BORDER_SMOOTHING: usize = 3;

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
    /// Boundary loops (connected pieces of the boundary edges).
    pub boundary_loops: usize,
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
        let mut loops_uf = UnionFind::new(nv);
        for e in &boundary {
            loops_uf.union(e[0], e[1]);
        }
        let mut on_boundary = vec![false; nv];
        for e in &boundary {
            on_boundary[e[0] as usize] = true;
        }
        let loop_roots: std::collections::BTreeSet<u32> =
            (0..nv as u32).filter(|&v| on_boundary[v as usize]).map(|v| loops_uf.find(v)).collect();
        let boundary_loops = loop_roots.len();
        ChartMesh { faces: faces.to_vec(), tris, vertex, boundary, euler, boundary_loops }
    }

    /// Number of chart vertices.
    pub(crate) fn num_vertices(&self) -> usize {
        self.vertex.len()
    }

    /// Edge-connected (by construction), with a boundary and V − E + F = 1.
    pub(crate) fn is_disk(&self) -> bool {
        self.euler == 1 && !self.boundary.is_empty()
    }

    /// Planar: edge-connected, with a boundary and genus 0 — a disk, or a disk with holes
    /// (V − E + F = 2 − b for b boundary loops). A planar chart flattens as it is: LSCM's
    /// area term sums the signed area over every boundary loop, ARAP pins one vertex, and
    /// the validity test (no flipped triangle, no crossing boundary edges) covers the holes.
    pub(crate) fn is_planar(&self) -> bool {
        self.boundary_loops > 0 && self.euler == 2 - self.boundary_loops as i64
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

/// Face normals smoothed for the cone test: `iterations` rounds of replacing each face's
/// area-weighted normal by the sum over itself and its edge neighbours across edges that are
/// not sharp creases (raw normals' cosine at least `crease_cos`), normalized: a scan's noise
/// no longer splits a smooth patch, and a crease keeps both sides' normals apart.
pub(crate) fn smoothed_normals(
    mesh: &Mesh,
    he: &HalfEdges,
    iterations: usize,
    crease_cos: f64,
) -> Vec<Vector3<f64>> {
    let raw = face_normals(mesh);
    let mut n: Vec<Vector3<f64>> = (0..mesh.num_faces())
        .map(|f| {
            let [a, b, c] = mesh.face_positions(f);
            let w = (b - a).cross(&(c - a));
            if w.iter().all(|x| x.is_finite()) {
                w
            } else {
                Vector3::zeros()
            }
        })
        .collect();
    let area: Vec<f64> = n.iter().map(|w| w.norm()).collect();
    for _ in 0..iterations {
        let unit: Vec<Vector3<f64>> = n
            .iter()
            .zip(&area)
            .map(|(w, &a)| if w.norm() > 0.0 { w * (a / w.norm()) } else { *w })
            .collect();
        n = (0..mesh.num_faces() as u32)
            .map(|f| {
                let mut s = unit[f as usize];
                for c in 0..3 {
                    if let Some(t) = he.twin(3 * f + c) {
                        let g = (t / 3) as usize;
                        if raw[f as usize].dot(&raw[g]) >= crease_cos {
                            s += unit[g];
                        }
                    }
                }
                s
            })
            .collect();
    }
    n.into_iter()
        .map(|w| {
            let l = w.norm();
            if l > 0.0 && l.is_finite() {
                w / l
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

/// Region growing on normal cones (see the module documentation) on smoothed normals
/// (`smoothed_normals`): grown pieces, their borders smoothed (`smooth_labels`), split
/// into edge-connected parts, and parts of fewer than [`MIN_PIECE`] faces merged into a
/// neighbour.
pub(crate) fn cone_pieces(
    region: &[u32],
    he: &HalfEdges,
    normals: &[Vector3<f64>],
    tag: &[u32],
    id: u32,
    cone_cos: f64,
) -> Vec<Vec<u32>> {
    // Index of each region face in `region`.
    let local: std::collections::HashMap<u32, usize> =
        region.iter().enumerate().map(|(i, &f)| (f, i)).collect();
    // Edge neighbours of each region face inside the region (region indices).
    let nbrs: Vec<Vec<usize>> = region
        .iter()
        .map(|&f| {
            (0..3)
                .filter_map(|c| he.twin(3 * f + c).map(|t| t / 3))
                .filter(|&g| tag[g as usize] == id)
                .filter_map(|g| local.get(&g).copied())
                .collect()
        })
        .collect();
    let mut label = vec![usize::MAX; region.len()];
    let mut queue = VecDeque::new();
    let mut k = 0;
    for i0 in 0..region.len() {
        if label[i0] != usize::MAX {
            continue;
        }
        let seed = normals[region[i0] as usize];
        label[i0] = k;
        queue.push_back(i0);
        while let Some(i) = queue.pop_front() {
            for &j in &nbrs[i] {
                if label[j] == usize::MAX && normals[region[j] as usize].dot(&seed) >= cone_cos {
                    label[j] = k;
                    queue.push_back(j);
                }
            }
        }
        k += 1;
    }
    smooth_labels(&mut label, &nbrs, BORDER_SMOOTHING);
    // Edge-connected parts of each label, numbered by first face.
    let mut part = vec![usize::MAX; region.len()];
    let mut parts: Vec<Vec<usize>> = Vec::new();
    for i0 in 0..region.len() {
        if part[i0] != usize::MAX {
            continue;
        }
        let p = parts.len();
        part[i0] = p;
        let mut members = vec![i0];
        queue.push_back(i0);
        while let Some(i) = queue.pop_front() {
            for &j in &nbrs[i] {
                if part[j] == usize::MAX && label[j] == label[i0] {
                    part[j] = p;
                    members.push(j);
                    queue.push_back(j);
                }
            }
        }
        parts.push(members);
    }
    // Merge small parts into the neighbour sharing most edges (in part order; a part that
    // grew past the threshold by merges stays).
    let min_piece = MIN_PIECE;
    let n = parts.len();
    let mut target: Vec<usize> = (0..n).collect();
    let find = |target: &Vec<usize>, mut k: usize| {
        while target[k] != k {
            k = target[k];
        }
        k
    };
    let mut size: Vec<usize> = parts.iter().map(Vec::len).collect();
    for k in 0..n {
        if size[k] >= min_piece || find(&target, k) != k {
            continue;
        }
        let mut counts: std::collections::BTreeMap<usize, usize> = Default::default();
        for &i in &parts[k] {
            for &j in &nbrs[i] {
                let p = find(&target, part[j]);
                if p != k {
                    *counts.entry(p).or_default() += 1;
                }
            }
        }
        // Most shared edges; ties to the lower part.
        if let Some((&p, _)) = counts.iter().max_by(|a, b| a.1.cmp(b.1).then(b.0.cmp(a.0))) {
            target[k] = p;
            size[p] += size[k];
        }
    }
    let mut merged: Vec<Vec<u32>> = vec![Vec::new(); n];
    for (k, members) in parts.into_iter().enumerate() {
        merged[find(&target, k)].extend(members.into_iter().map(|i| region[i]));
    }
    merged.into_iter().filter(|p| !p.is_empty()).collect()
}

/// Smooths the borders between labelled pieces: `rounds` times, every face whose edge
/// neighbours are in majority (two of three) in another piece moves to it (all faces decided
/// from the previous round's labels, so the result does not depend on the order). Removes
/// the one-face teeth and peninsulas that a noisy scan's normals leave on grown borders,
/// which otherwise make flattened boundaries cross.
pub(crate) fn smooth_labels(label: &mut [usize], nbrs: &[Vec<usize>], rounds: usize) {
    for _ in 0..rounds {
        let old = label.to_vec();
        let mut changed = false;
        for (i, ns) in nbrs.iter().enumerate() {
            if ns.len() < 2 {
                continue;
            }
            let (a, b) = (old[ns[0]], old[ns[1]]);
            let c = ns.get(2).map(|&j| old[j]);
            let major = if a == b || Some(a) == c {
                Some(a)
            } else if Some(b) == c {
                Some(b)
            } else {
                None
            };
            if let Some(m) = major {
                if m != old[i] {
                    label[i] = m;
                    changed = true;
                }
            }
        }
        if !changed {
            break;
        }
    }
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

/// A piece's faces around a vertex whose 3D corner angles add up to at least this (2π − 20°)
/// leave too little turn for the vertex to lie on the piece's boundary: a near-isometric or
/// conformal map of the piece wraps its fan there over itself (a noisy scan's saddle vertices
/// carry more than 2π in total, so most of their fan reaches it).
pub const WRAP_ANGLE: f64 = std::f64::consts::TAU - std::f64::consts::PI / 9.0;

/// Moves the faces around every vertex where one piece's fan reaches [`WRAP_ANGLE`] into
/// that piece (rounds decided from the previous round's labels, until none moves, at most
/// [`BORDER_SMOOTHING`] + 1), then splits the pieces into edge-connected parts (in order of
/// their first face in `region`). `pos_in[f]` is the index of face `f` in `region` (faces with
/// `tag == id`). Returns `pieces` unchanged when no face moves or the result would be one
/// piece.
pub(crate) fn unwrap_fans(
    pieces: Vec<Vec<u32>>,
    region: &[u32],
    mesh: &Mesh,
    he: &HalfEdges,
    tag: &[u32],
    pos_in: &[u32],
    id: u32,
) -> Vec<Vec<u32>> {
    if pieces.len() < 2 {
        return pieces;
    }
    let mut label = vec![0u32; region.len()];
    for (k, p) in pieces.iter().enumerate() {
        for &f in p {
            label[pos_in[f as usize] as usize] = k as u32;
        }
    }
    // Every corner of the region: (vertex, region index of its face, 3D angle), by vertex.
    let mut corners: Vec<(u32, u32, f64)> = Vec::with_capacity(3 * region.len());
    for (i, &f) in region.iter().enumerate() {
        let p = mesh.face_positions(f as usize);
        for c in 0..3 {
            let (a, b) = (p[(c + 1) % 3] - p[c], p[(c + 2) % 3] - p[c]);
            let angle = a.cross(&b).norm().atan2(a.dot(&b));
            corners.push((mesh.faces[f as usize][c], i as u32, angle));
        }
    }
    corners.sort_by_key(|c| (c.0, c.1));
    let mut moved_any = false;
    for _round in 0..=BORDER_SMOOTHING {
        let old = label.clone();
        let mut moved = false;
        for fan in corners.chunk_by(|a, b| a.0 == b.0) {
            let first = old[fan[0].1 as usize];
            if fan.iter().all(|c| old[c.1 as usize] == first) {
                continue;
            }
            // The piece whose fan turns most (ties to the lower piece).
            let mut sums: Vec<(u32, f64)> = Vec::new();
            for c in fan {
                let l = old[c.1 as usize];
                match sums.iter_mut().find(|s| s.0 == l) {
                    Some(s) => s.1 += c.2,
                    None => sums.push((l, c.2)),
                }
            }
            let best = sums.iter().fold(sums[0], |b, s| {
                if s.1 > b.1 || (s.1 == b.1 && s.0 < b.0) {
                    *s
                } else {
                    b
                }
            });
            if best.1 >= WRAP_ANGLE {
                for c in fan {
                    if label[c.1 as usize] != best.0 {
                        label[c.1 as usize] = best.0;
                        moved = true;
                    }
                }
            }
        }
        moved_any |= moved;
        if !moved {
            break;
        }
    }
    if !moved_any {
        return pieces;
    }
    let parts = self::pieces(region, he, tag, id, |h| {
        let t = he.twin(h).unwrap_or(h);
        label[pos_in[(h / 3) as usize] as usize] == label[pos_in[(t / 3) as usize] as usize]
    });
    if parts.len() < 2 {
        return pieces;
    }
    parts
}

/// A part is **noisy** when its sharp creases enclose at least this fraction of its faces, and
/// at least [`NOISE_MIN_PIECES`], as pieces of fewer than [`MIN_PIECE`] faces (`is_noisy`): a
/// scan's noise makes sharp edges all over its surface around single faces and slivers
/// (bust_scan: 6,890 such pieces in 119,476 faces, 5.8 %), where a part's real creases enclose
/// a few (the corpus: at most 56 in 8,192 faces, the oloid's 0.7 %; a closed box: 6 in 12).
pub const NOISE_FRACTION: f64 = 0.02;

/// The fewest small crease pieces that make a part noisy (see [`NOISE_FRACTION`]).
pub const NOISE_MIN_PIECES: usize = 256;

/// Whether the crease pieces `pieces` of a part of `faces` faces make it noisy (see
/// [`NOISE_FRACTION`]).
pub(crate) fn is_noisy(pieces: &[Vec<u32>], faces: usize) -> bool {
    let small = pieces.iter().filter(|p| p.len() < MIN_PIECE).count();
    small >= NOISE_MIN_PIECES && small as f64 >= NOISE_FRACTION * faces as f64
}

/// Merges each piece of fewer than [`MIN_PIECE`] faces into the neighbour piece it shares most
/// edges with (in piece order, ties to the lower piece; a piece that grew past the threshold
/// by merges stays), as the normal-cone growing does. On a noisy part each of them would
/// otherwise become a chart, flattened, then merged back into a neighbour one by one.
/// `pos_in[f]` is the index of face `f` in `region` (faces with `tag == id`).
pub(crate) fn absorb_small(
    pieces: Vec<Vec<u32>>,
    region: &[u32],
    he: &HalfEdges,
    tag: &[u32],
    pos_in: &[u32],
    id: u32,
) -> Vec<Vec<u32>> {
    let n = pieces.len();
    if n < 2 || pieces.iter().all(|p| p.len() >= MIN_PIECE) {
        return pieces;
    }
    let mut part = vec![0usize; region.len()];
    for (k, p) in pieces.iter().enumerate() {
        for &f in p {
            part[pos_in[f as usize] as usize] = k;
        }
    }
    let mut target: Vec<usize> = (0..n).collect();
    let find = |target: &Vec<usize>, mut k: usize| {
        while target[k] != k {
            k = target[k];
        }
        k
    };
    let mut size: Vec<usize> = pieces.iter().map(Vec::len).collect();
    for k in 0..n {
        if size[k] >= MIN_PIECE || find(&target, k) != k {
            continue;
        }
        let mut counts: std::collections::BTreeMap<usize, usize> = Default::default();
        for &f in &pieces[k] {
            for c in 0..3 {
                let Some(t) = he.twin(3 * f + c) else { continue };
                let g = (t / 3) as usize;
                if tag[g] == id {
                    let p = find(&target, part[pos_in[g] as usize]);
                    if p != k {
                        *counts.entry(p).or_default() += 1;
                    }
                }
            }
        }
        if let Some((&p, _)) = counts.iter().max_by(|a, b| a.1.cmp(b.1).then(b.0.cmp(a.0))) {
            target[k] = p;
            size[p] += size[k];
        }
    }
    let mut merged: Vec<Vec<u32>> = vec![Vec::new(); n];
    for (k, p) in pieces.into_iter().enumerate() {
        let root = find(&target, k);
        merged[root].extend(p);
    }
    merged.into_iter().filter(|p| !p.is_empty()).collect()
}
