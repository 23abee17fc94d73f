//! Adaptive refinement (docs/math.md §12): the edges longer than a per-face target length are
//! split at their midpoints until none is, so that an edit finer than the part's triangles can
//! be represented by a field that lives on vertices.
//!
//! One level marks every edge longer than the smaller target of its two faces, closes the marks
//! by the longest-edge rule (a face with a marked edge has its longest edge marked), then
//! splits: a face with three marked edges becomes four (the regular 1-to-4 split); a face with
//! one marked edge — always its longest — is bisected into two; a face with two is bisected
//! along its longest edge and the half holding the other marked edge is bisected again. The
//! mesh stays conforming, and since every split starts at a longest edge the angles stay
//! bounded away from zero (Rivara's longest-edge bisection).
//!
//! A new vertex sits at the Phong-tessellation point of its edge (Boubekeur & Alexa 2008)
//! with shape factor 1/2: the midpoint moved halfway towards the tangent planes of the edge's
//! two vertices, which puts it on the surface to second order (the paper's visual default 3/4
//! overshoots by a quarter of the chord's sagitta, and the refined part came out bumpy: its
//! jet-fitted curvature doubled at new vertices). Across a crease (vertex normals more than 30°
//! apart) the midpoint stays on the edge. Vertex normals are the input's with Max's weights
//! (exact on a sphere), carried to new vertices as normalised means.
//!
//! The input's vertices keep their indices; new vertices are appended, and each records the
//! edge it split ([`Refined::parents`]), so per-vertex data can be carried over. Corner
//! attributes (UVs, normals) are split per face corner: a seam edge gets one midpoint value per
//! side.

use std::collections::HashMap;

use nalgebra::Vector3;

use super::{CornerAttribute, Mesh};
use crate::{Error, Result};

/// How far [`refine`] may go.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct RefineOptions {
    /// Most levels of splitting (each at most halves an edge).
    pub max_levels: usize,
    /// Most vertices refinement may add.
    pub max_new_vertices: usize,
    /// The scene key named when the budget is exceeded.
    pub budget_key: &'static str,
}

impl Default for RefineOptions {
    fn default() -> Self {
        RefineOptions { max_levels: 8, max_new_vertices: 2_000_000, budget_key: "mesh.refine" }
    }
}

/// The refined mesh and where its new vertices came from.
#[derive(Clone, Debug)]
pub struct Refined {
    /// The refined mesh (the input's vertices first, with their indices).
    pub mesh: Mesh,
    /// For the k-th added vertex (index `original + k`), the edge (two vertex indices, either
    /// possibly added earlier) whose midpoint it is.
    pub parents: Vec<[u32; 2]>,
    /// The unit normal the Phong points were placed with, per vertex of the refined mesh: the
    /// input's (given, or Max-weighted, or its flat region's plane), and for each new vertex
    /// the normalised mean of its edge's two (its plane's inside a flat region).
    pub normals: Vec<Vector3<f64>>,
    /// Levels of splitting done.
    pub levels: usize,
    /// Faces of the input that were split.
    pub faces_split: usize,
}

impl Refined {
    /// Number of vertices added.
    pub fn added(&self) -> usize {
        self.parents.len()
    }

    /// Extends per-vertex data of the input to the refined mesh: each new vertex gets
    /// `mid(parent a, parent b)`. `data` must have one value per vertex of the input.
    pub fn extend<T: Clone>(&self, data: &mut Vec<T>, mid: impl Fn(&T, &T) -> T) {
        for p in &self.parents {
            let v = mid(&data[p[0] as usize], &data[p[1] as usize]);
            data.push(v);
        }
    }
}

/// Angle between the vertex normals of an edge beyond which its midpoint is not curved.
const CREASE_COS: f64 = 0.866_025_403_784_438_6; // cos 30°

pub use super::planar::FLAT_COS;

/// Fewest faces around a flat vertex: a corner of a curved quad grid has one quad's two
/// coplanar triangles.
pub const MIN_FLAT_FACES: usize = 3;

/// Phong tessellation's shape factor: ½ is exact to second order (module docs).
const PHONG_ALPHA: f64 = 0.5;

/// Refines `mesh` until no edge is longer than the smaller `target` of its faces (one target
/// length per face, scene units; `f64::INFINITY` where nothing is asked). Refuses, naming
/// `options.budget_key`, when more than `options.max_new_vertices` would be added.
pub fn refine(mesh: &Mesh, target: &[f64], options: &RefineOptions) -> Result<Refined> {
    refine_with(mesh, target, options, &|_, _, inherited| inherited, None)
}

/// The target length of a face a split makes, from its corners, their unit normals (the ones
/// the Phong points were placed with: [`Refined::normals`]) and its parent's target.
pub type Retarget<'a> = &'a dyn Fn(&[Vector3<f64>; 3], &[Vector3<f64>; 3], f64) -> f64;

/// [`refine`] asking `retarget` for the target of every face a split makes (its corners, their
/// normals and its parent's target in, its own out; [`refine`] keeps the parent's). A target that follows
/// where a face is — the edits' regions — keeps a long sliver touched by a brush from being
/// split along its whole length.
///
/// `normals`, one per input vertex, replace the Max-weighted normals the Phong points are
/// placed with (the planes of flat regions still take precedence). A scan's 1-ring normals
/// are as noisy as its slivers are thin — Max's weights grow as 1/|e|, so a sliver's face
/// decides — and Phong points placed with them fold the split faces over; the geometry's
/// normals fitted at the noise's scale ([`crate::mesh`] has none: the caller passes them)
/// keep the new vertices on the surface the fit sees.
pub fn refine_with(
    mesh: &Mesh,
    target: &[f64],
    options: &RefineOptions,
    retarget: Retarget<'_>,
    normals: Option<&[Vector3<f64>]>,
) -> Result<Refined> {
    if target.len() != mesh.num_faces() {
        return Err(Error::invalid_arg(
            "refine",
            format!("{} targets for {} faces", target.len(), mesh.num_faces()),
        ));
    }
    if normals.is_some_and(|n| n.len() != mesh.num_vertices()) {
        return Err(Error::invalid_arg(
            "refine",
            format!(
                "normals for {} of {} vertices",
                normals.map_or(0, <[_]>::len),
                mesh.num_vertices()
            ),
        ));
    }
    let (nrm, face_plane) = face_planes(mesh, normals);
    let mut state = State {
        pos: mesh.positions.clone(),
        nrm,
        plane: flat_planes(mesh),
        rim: Vec::new(),
        faces: mesh.faces.clone(),
        face_plane,
        origin: (0..mesh.num_faces() as u32).collect(),
        target: target.to_vec(),
        uv: mesh.uv.clone(),
        normals: mesh.normals.clone(),
        parents: Vec::new(),
    };
    state.rim = rim_planes(mesh, &state.plane);
    let mut levels = 0;
    for _ in 0..options.max_levels {
        crate::cancel::checkpoint("refinement")?;
        let Some(plan) = state.plan() else { break };
        let added = plan.marked.iter().filter(|m| **m).count();
        if state.parents.len() + added > options.max_new_vertices {
            return Err(Error::setting(
                options.budget_key,
                format!(
                    "refining the mesh for the edits would add more than {} vertices; give the \
                     brushes a larger radius (or curves a larger width), or set \
                     `mesh.refine.mode: \"none\"`",
                    options.max_new_vertices
                ),
            ));
        }
        state.split(&plan, retarget);
        levels += 1;
    }
    let mut split = vec![false; mesh.num_faces()];
    let mut count = vec![0u32; mesh.num_faces()];
    for &o in &state.origin {
        count[o as usize] += 1;
    }
    for (f, c) in count.iter().enumerate() {
        split[f] = *c > 1;
    }
    let refined = Mesh {
        positions: state.pos,
        faces: state.faces,
        uv: state.uv,
        normals: state.normals,
        units: mesh.units,
    };
    Ok(Refined {
        mesh: refined,
        normals: state.nrm,
        parents: state.parents,
        levels,
        faces_split: split.iter().filter(|s| **s).count(),
    })
}

/// Per interior vertex with at least three faces, the unit normal of its faces when they all
/// lie in one plane (within [`FLAT_COS`]; faces of zero area do not count), else `None`: the vertices inside a flat
/// region of the part as loaded. They are classified once, before any split: a new vertex on
/// the region's curved rim may lie a little off the plane, and would make its flat neighbours
/// look curved.
fn flat_planes(mesh: &Mesh) -> Vec<Option<Vector3<f64>>> {
    // (the first face's unit normal, whether every face so far agrees)
    let mut seen: Vec<Option<(Vector3<f64>, bool)>> = vec![None; mesh.num_vertices()];
    for f in &mesh.faces {
        let p = f.map(|v| mesh.positions[v as usize]);
        let Some(n) = (p[1] - p[0]).cross(&(p[2] - p[0])).try_normalize(1e-300) else {
            continue;
        };
        for &v in f {
            let s = &mut seen[v as usize];
            match s {
                None => *s = Some((n, true)),
                Some((first, agree)) => *agree &= first.dot(&n) >= FLAT_COS,
            }
        }
    }
    // Two faces (one quad of a curved grid's corner) or a boundary vertex (the first strip of a
    // ruled surface meshed along its rulings is planar) do not make a flat region.
    let mut count = vec![0usize; mesh.num_vertices()];
    let mut edges: HashMap<[u32; 2], u32> = HashMap::new();
    for f in &mesh.faces {
        for k in 0..3 {
            count[f[k] as usize] += 1;
            let (a, b) = (f[k], f[(k + 1) % 3]);
            *edges.entry([a.min(b), a.max(b)]).or_insert(0) += 1;
        }
    }
    let mut boundary = vec![false; mesh.num_vertices()];
    for (e, n) in &edges {
        if *n == 1 {
            boundary[e[0] as usize] = true;
            boundary[e[1] as usize] = true;
        }
    }
    seen.into_iter()
        .enumerate()
        .map(|(v, s)| {
            s.and_then(|(n, agree)| {
                (agree && count[v] >= MIN_FLAT_FACES && !boundary[v]).then_some(n)
            })
        })
        .collect()
}

/// Per vertex of the part as loaded on the rim of a flat region ([`State::rim`]): not flat,
/// every flat vertex it shares a face with in one plane, and itself on that plane (within 1e-6
/// of its distance to them).
fn rim_planes(
    mesh: &Mesh,
    plane: &[Option<Vector3<f64>>],
) -> Vec<Option<(Vector3<f64>, Vector3<f64>)>> {
    // (plane, a point of it, still one plane)
    type Seen = Option<(Vector3<f64>, Vector3<f64>, bool)>;
    let mut seen: Vec<Seen> = vec![None; mesh.num_vertices()];
    for f in &mesh.faces {
        for &w in f {
            let Some(n) = plane[w as usize] else { continue };
            let pw = mesh.positions[w as usize];
            for &v in f {
                let v = v as usize;
                if plane[v].is_some() {
                    continue;
                }
                let d = mesh.positions[v] - pw;
                let on = d.dot(&n).abs() <= 1e-6 * d.norm();
                match &mut seen[v] {
                    s @ None => *s = Some((n, pw, on)),
                    Some((q, _, ok)) => *ok &= on && q.dot(&n) >= FLAT_COS,
                }
            }
        }
    }
    seen.into_iter().map(|s| s.and_then(|(n, p, ok)| ok.then_some((n, p)))).collect()
}

/// The planes of a CAD export's flat faces ([`super::planar`]): the vertex normals
/// ([`vertex_normals`]) with the vertices a planar region fixes set to its plane's normal, and
/// per input face the plane of its region when that region fixes some vertex (a face of the
/// part, not a strip of a fillet). An edge inside such a region splits on the plane (the Phong
/// point of normals that lean towards a tangent fillet would lift the flat face), and so does
/// an edge between two of its fixed vertices (their normals are the plane's).
fn face_planes(
    mesh: &Mesh,
    given: Option<&[Vector3<f64>]>,
) -> (Vec<Vector3<f64>>, Vec<Option<Vector3<f64>>>) {
    let mut nrm = match given {
        Some(n) => n.iter().map(|v| v.try_normalize(1e-300).unwrap_or_else(Vector3::z)).collect(),
        None => vertex_normals(mesh),
    };
    let regions = super::planar::planar_regions(mesh);
    let vf = super::VertexFaces::new(mesh);
    let mut is_face = vec![false; regions.normal.len()];
    for (v, r) in regions.vertex_planes(mesh, &vf).into_iter().enumerate() {
        if let Some(r) = r {
            let p = regions.normal[r as usize];
            nrm[v] = if p.dot(&nrm[v]) < 0.0 { -p } else { p };
            is_face[r as usize] = true;
        }
    }
    let face_plane = regions
        .face_region
        .iter()
        .map(|&r| {
            (r != super::planar::NO_REGION && is_face[r as usize])
                .then(|| regions.normal[r as usize])
        })
        .collect();
    (nrm, face_plane)
}

/// Vertex normals with Max's weights (Max 1999, "Weights for computing vertex normals from
/// facet normals"): each incident face adds (e₁ × e₂)/(|e₁|²|e₂|²) for its two edges e₁, e₂
/// out of the vertex, which is exact when the vertex and its neighbours lie on a sphere —
/// the Phong points of [`State::midpoint`] are only as good as these normals. Zero-area
/// neighbourhoods get +z.
fn vertex_normals(mesh: &Mesh) -> Vec<Vector3<f64>> {
    let mut n = vec![Vector3::zeros(); mesh.num_vertices()];
    for f in &mesh.faces {
        let p = f.map(|v| mesh.positions[v as usize]);
        for k in 0..3 {
            let (e1, e2) = (p[(k + 1) % 3] - p[k], p[(k + 2) % 3] - p[k]);
            let w = e1.norm_squared() * e2.norm_squared();
            if w > 0.0 && w.is_finite() {
                n[f[k] as usize] += e1.cross(&e2) / w;
            }
        }
    }
    n.into_iter().map(|v| v.try_normalize(1e-300).unwrap_or_else(Vector3::z)).collect()
}

struct State {
    pos: Vec<Vector3<f64>>,
    nrm: Vec<Vector3<f64>>,
    /// Per vertex, the plane (unit normal) of the flat region it lies inside: for the input's
    /// vertices, the normal of their faces when all lie in one plane ([`flat_planes`]); a new
    /// vertex on an edge out of such a vertex inherits its plane.
    plane: Vec<Option<Vector3<f64>>>,
    /// Per vertex on the rim of a flat region (not flat itself, but sharing a face with a flat
    /// vertex, and lying on its plane): that plane's unit normal and a point of it. An edge
    /// along the rim keeps its new vertex on the plane ([`rim_planes`]).
    rim: Vec<Option<(Vector3<f64>, Vector3<f64>)>>,
    faces: Vec<[u32; 3]>,
    /// Per input face, the plane of the CAD face it lies in ([`face_planes`]).
    face_plane: Vec<Option<Vector3<f64>>>,
    /// The input face each face descends from.
    origin: Vec<u32>,
    target: Vec<f64>,
    uv: Option<CornerAttribute<nalgebra::Vector2<f64>>>,
    normals: Option<CornerAttribute<Vector3<f64>>>,
    parents: Vec<[u32; 2]>,
}

/// One level's marks: the edges (as vertex pairs, in order of first appearance), the three
/// edges of each face (edge k joins corners k and k + 1) and which edges are split.
struct Plan {
    edges: Vec<[u32; 2]>,
    face_edges: Vec<[u32; 3]>,
    marked: Vec<bool>,
    /// Each face's longest edge (0, 1 or 2).
    longest: Vec<usize>,
}

/// The children of a face whose edges `m` are marked (the longest, `l`, among them whenever
/// any is), as corner slots: 0..3 the face's corners, 3..6 the midpoints of its edges 0, 1, 2
/// (edge k joins corners k and k + 1). Every child keeps the face's orientation.
fn children(m: [bool; 3], l: usize) -> Vec<[usize; 3]> {
    match m.iter().filter(|x| **x).count() {
        0 => vec![[0, 1, 2]],
        3 => vec![[0, 3, 5], [3, 1, 4], [5, 4, 2], [3, 4, 5]],
        count => {
            // Bisect the longest edge (a, b) at ml towards c; with a second marked edge, split
            // the half it lies in from ml.
            let (a, b, c) = (l, (l + 1) % 3, (l + 2) % 3);
            let ml = 3 + l;
            if count == 1 {
                vec![[a, ml, c], [ml, b, c]]
            } else if m[b] {
                // Edge (b, c) is edge b.
                let mb = 3 + b;
                vec![[a, ml, c], [ml, b, mb], [ml, mb, c]]
            } else {
                // Edge (c, a) is edge c.
                let mc = 3 + c;
                vec![[a, ml, mc], [mc, ml, c], [ml, b, c]]
            }
        }
    }
}

impl State {
    fn len(&self, e: [u32; 2]) -> f64 {
        (self.pos[e[1] as usize] - self.pos[e[0] as usize]).norm()
    }

    /// The marks of one level, closed by the longest-edge rule; `None` if nothing is split.
    fn plan(&self) -> Option<Plan> {
        let mut index: HashMap<[u32; 2], u32> = HashMap::with_capacity(self.faces.len() * 2);
        let mut edges: Vec<[u32; 2]> = Vec::new();
        let mut face_edges = Vec::with_capacity(self.faces.len());
        for f in &self.faces {
            let mut fe = [0u32; 3];
            for k in 0..3 {
                let (a, b) = (f[k], f[(k + 1) % 3]);
                let key = [a.min(b), a.max(b)];
                fe[k] = *index.entry(key).or_insert_with(|| {
                    edges.push(key);
                    (edges.len() - 1) as u32
                });
            }
            face_edges.push(fe);
        }
        let mut marked = vec![false; edges.len()];
        let mut any = false;
        for (f, fe) in face_edges.iter().enumerate() {
            let t = self.target[f];
            if !t.is_finite() {
                continue;
            }
            for &e in fe {
                if self.len(edges[e as usize]) > t {
                    marked[e as usize] = true;
                    any = true;
                }
            }
        }
        if !any {
            return None;
        }
        // Longest-edge closure; marks only grow, so this ends.
        let longest: Vec<usize> = face_edges
            .iter()
            .map(|fe| {
                let l = fe.map(|e| self.len(edges[e as usize]));
                let mut k = 0;
                for j in 1..3 {
                    if l[j] > l[k] {
                        k = j;
                    }
                }
                k
            })
            .collect();
        loop {
            let mut changed = false;
            for (f, fe) in face_edges.iter().enumerate() {
                let l = fe[longest[f]] as usize;
                if !marked[l] && fe.iter().any(|&e| marked[e as usize]) {
                    marked[l] = true;
                    changed = true;
                }
            }
            if !changed {
                break;
            }
        }
        Some(Plan { edges, face_edges, marked, longest })
    }

    /// The Phong-tessellation point of edge (a, b), its normal and its plane. An edge out of a
    /// flat vertex ([`State::plane`]) lies in that vertex's plane, and so do its midpoint and
    /// the faces around it: a CAD export's flat face meshed as a fan of slivers meets its
    /// fillet at vertices whose normals lean towards the fillet, and the tangent planes of
    /// those would lift the face's new vertices off it (a bump the shading shows along every
    /// split sliver).
    fn midpoint(&self, a: usize, b: usize) -> (Vector3<f64>, Vector3<f64>, Option<Vector3<f64>>) {
        let (pa, pb, na, nb) = (self.pos[a], self.pos[b], self.nrm[a], self.nrm[b]);
        let m = (pa + pb) * 0.5;
        let flat = match (self.plane[a], self.plane[b]) {
            (Some(p), _) => Some((p, pa)),
            (None, Some(p)) => Some((p, pb)),
            (None, None) => None,
        };
        if let Some((plane, on)) = flat {
            // On the plane itself (the other end may be a rim vertex a little off it), with
            // the plane's normal, pointing the way the vertices' do.
            let n = if plane.dot(&(na + nb)) < 0.0 { -plane } else { plane };
            return (m - plane * (m - on).dot(&plane), n, Some(plane));
        }
        let n = (na + nb).try_normalize(1e-300).unwrap_or(na);
        let p = if na.dot(&nb) < CREASE_COS {
            m
        } else {
            let proj = |p: &Vector3<f64>, q: &Vector3<f64>| m - q * (m - p).dot(q);
            let star = (proj(&pa, &na) + proj(&pb, &nb)) * 0.5;
            m + (star - m) * PHONG_ALPHA
        };
        (p, n, None)
    }

    /// The plane an edge along a flat region's rim keeps its new vertex on: both ends on the
    /// rim of one plane ([`State::rim`]).
    fn rim_of(&self, a: usize, b: usize) -> Option<(Vector3<f64>, Vector3<f64>)> {
        match (self.rim[a], self.rim[b]) {
            (Some((n, on)), Some((q, _))) if n.dot(&q) >= FLAT_COS => Some((n, on)),
            _ => None,
        }
    }

    /// Per edge of `plan`, the plane of the CAD face both its faces lie in, if they do
    /// ([`face_planes`]); `None` on a boundary edge.
    fn edge_planes(&self, plan: &Plan) -> Vec<Option<Vector3<f64>>> {
        let mut first: Vec<Option<Option<Vector3<f64>>>> = vec![None; plan.edges.len()];
        let mut out = vec![None; plan.edges.len()];
        for (f, fe) in plan.face_edges.iter().enumerate() {
            let q = self.face_plane[self.origin[f] as usize];
            for &e in fe {
                match first[e as usize] {
                    None => first[e as usize] = Some(q),
                    Some(p) => {
                        out[e as usize] = match (p, q) {
                            (Some(p), Some(q)) if p.dot(&q) >= FLAT_COS => Some(p),
                            _ => None,
                        }
                    }
                }
            }
        }
        out
    }

    fn split(&mut self, plan: &Plan, retarget: Retarget<'_>) {
        let mut mid = vec![u32::MAX; plan.edges.len()];
        let edge_plane = self.edge_planes(plan);
        for (e, &[a, b]) in plan.edges.iter().enumerate() {
            if !plan.marked[e] {
                continue;
            }
            let (mut p, n, plane) = match edge_plane[e] {
                // Inside a CAD face: on the segment, which lies in its plane.
                Some(q) => {
                    let (na, nb) = (self.nrm[a as usize], self.nrm[b as usize]);
                    let n = if q.dot(&(na + nb)) < 0.0 { -q } else { q };
                    ((self.pos[a as usize] + self.pos[b as usize]) * 0.5, n, Some(q))
                }
                None => self.midpoint(a as usize, b as usize),
            };
            // Along a flat region's rim the Phong point follows the rim's curve in the plane
            // but not the rim's normals out of it (they lean towards the curved side).
            let rim = if plane.is_none() { self.rim_of(a as usize, b as usize) } else { None };
            if let Some((rn, on)) = rim {
                p -= rn * (p - on).dot(&rn);
            }
            mid[e] = self.pos.len() as u32;
            self.pos.push(p);
            self.nrm.push(n);
            self.plane.push(plane);
            self.rim.push(rim);
            self.parents.push([a, b]);
        }
        let mut uv = self.uv.take().map(Corners::new);
        let mut normals = self.normals.take().map(Corners::new);
        let mut faces = Vec::with_capacity(self.faces.len() * 2);
        let mut origin = Vec::with_capacity(faces.capacity());
        let mut target = Vec::with_capacity(faces.capacity());
        for (f, face) in self.faces.iter().enumerate() {
            let fe = plan.face_edges[f];
            let m = fe.map(|e| plan.marked[e as usize]);
            // Children as (corner slots): 0..3 the face's corners, 3..6 the midpoints of its
            // edges 0, 1, 2.
            let children = children(m, plan.longest[f]);
            let slot_vertex = |s: usize| if s < 3 { face[s] } else { mid[fe[s - 3] as usize] };
            let uv_slots = uv.as_mut().map(|c| c.slots(f, |x, y| (x + y) * 0.5));
            let n_slots = normals
                .as_mut()
                .map(|c| c.slots(f, |x, y| (x + y).try_normalize(1e-300).unwrap_or(*x)));
            let split = children.len() > 1;
            for ch in children {
                let face = ch.map(slot_vertex);
                faces.push(face);
                origin.push(self.origin[f]);
                target.push(if split {
                    let corners = face.map(|v| self.pos[v as usize]);
                    retarget(&corners, &face.map(|v| self.nrm[v as usize]), self.target[f])
                } else {
                    self.target[f]
                });
                if let (Some(c), Some(s)) = (uv.as_mut(), uv_slots.as_ref()) {
                    c.push(ch.map(|k| s[k]));
                }
                if let (Some(c), Some(s)) = (normals.as_mut(), n_slots.as_ref()) {
                    c.push(ch.map(|k| s[k]));
                }
            }
        }
        self.faces = faces;
        self.origin = origin;
        self.target = target;
        self.uv = uv.map(Corners::finish);
        self.normals = normals.map(Corners::finish);
    }
}

/// A corner attribute being split: midpoint values are shared by the corners that split the
/// same pair of values (so a seam keeps one value per side, and the rest stays shared).
struct Corners<T> {
    old: CornerAttribute<T>,
    values: Vec<T>,
    corners: Vec<[u32; 3]>,
    cache: HashMap<[u32; 2], u32>,
}

impl<T: Copy> Corners<T> {
    fn new(old: CornerAttribute<T>) -> Self {
        let values = old.values.clone();
        Corners { old, values, corners: Vec::new(), cache: HashMap::new() }
    }

    /// The value indices of face `f`'s six slots (corners, then edge midpoints).
    fn slots(&mut self, f: usize, mid: impl Fn(&T, &T) -> T) -> [u32; 6] {
        let c = self.old.corners[f];
        let mut s = [c[0], c[1], c[2], 0, 0, 0];
        for k in 0..3 {
            let (a, b) = (c[k], c[(k + 1) % 3]);
            let key = [a.min(b), a.max(b)];
            let values = &mut self.values;
            s[3 + k] = *self.cache.entry(key).or_insert_with(|| {
                let v = mid(&values[a as usize], &values[b as usize]);
                values.push(v);
                (values.len() - 1) as u32
            });
        }
        s
    }

    fn push(&mut self, c: [u32; 3]) {
        self.corners.push(c);
    }

    fn finish(self) -> CornerAttribute<T> {
        CornerAttribute { values: self.values, corners: self.corners }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn square() -> Mesh {
        Mesh::from_triangles(
            vec![
                Vector3::new(0.0, 0.0, 0.0),
                Vector3::new(1.0, 0.0, 0.0),
                Vector3::new(1.0, 1.0, 0.0),
                Vector3::new(0.0, 1.0, 0.0),
            ],
            vec![[0, 1, 2], [0, 2, 3]],
        )
    }

    fn area(m: &Mesh) -> f64 {
        m.faces
            .iter()
            .map(|f| {
                let p = f.map(|v| m.positions[v as usize]);
                0.5 * (p[1] - p[0]).cross(&(p[2] - p[0])).z
            })
            .sum()
    }

    #[test]
    fn a_flat_square_is_split_until_every_edge_is_short_and_stays_conforming() {
        let m = square();
        let r = refine(&m, &[0.3, 0.3], &RefineOptions::default()).unwrap();
        let out = &r.mesh;
        // Every edge at most 0.3, the area and the orientation kept (all signed areas > 0).
        for f in &out.faces {
            let p = f.map(|v| out.positions[v as usize]);
            for k in 0..3 {
                assert!((p[(k + 1) % 3] - p[k]).norm() <= 0.3 + 1e-12);
            }
            assert!((p[1] - p[0]).cross(&(p[2] - p[0])).z > 0.0);
        }
        assert!((area(out) - 1.0).abs() < 1e-12);
        // Conforming: every interior edge has exactly two faces, the boundary is the square's
        // perimeter (length 4).
        let mut count: HashMap<[u32; 2], usize> = HashMap::new();
        for f in &out.faces {
            for k in 0..3 {
                let (a, b) = (f[k], f[(k + 1) % 3]);
                *count.entry([a.min(b), a.max(b)]).or_default() += 1;
            }
        }
        let perimeter: f64 = count
            .iter()
            .filter(|(_, c)| **c == 1)
            .map(|(e, _)| (out.positions[e[1] as usize] - out.positions[e[0] as usize]).norm())
            .sum();
        assert!(count.values().all(|c| *c <= 2));
        assert!((perimeter - 4.0).abs() < 1e-12, "perimeter {perimeter}");
        // The input's vertices keep their indices.
        assert_eq!(&out.positions[..4], &m.positions[..]);
        assert_eq!(r.added(), out.num_vertices() - 4);
    }

    #[test]
    fn only_the_asked_region_is_refined_and_the_budget_is_enforced() {
        let m = square();
        // Ten unit squares along x: only the first square's faces ask for 0.3.
        let mut pos = Vec::new();
        for i in 0..=10 {
            pos.push(Vector3::new(i as f64, 0.0, 0.0));
            pos.push(Vector3::new(i as f64, 1.0, 0.0));
        }
        let faces: Vec<[u32; 3]> = (0..10u32)
            .flat_map(|i| [[2 * i, 2 * i + 2, 2 * i + 3], [2 * i, 2 * i + 3, 2 * i + 1]])
            .collect();
        let strip = Mesh::from_triangles(pos, faces);
        let mut target = vec![f64::INFINITY; 20];
        target[0] = 0.3;
        target[1] = 0.3;
        let part = refine(&strip, &target, &RefineOptions::default()).unwrap();
        assert!((area(&part.mesh) - 10.0).abs() < 1e-12);
        // The closure spreads a little beyond the first square, not along the strip: the last
        // five squares are untouched (their ten faces are still there, as they were).
        for f in &strip.faces[10..] {
            assert!(part.mesh.faces.contains(f), "{f:?} was split");
        }
        assert!(part.faces_split >= 2 && part.faces_split < 10, "{}", part.faces_split);
        let opts = RefineOptions { max_new_vertices: 3, ..RefineOptions::default() };
        let e = refine(&m, &[0.01, 0.01], &opts).unwrap_err().to_string();
        assert!(e.contains("mesh.refine"), "{e}");
    }

    #[test]
    fn midpoints_follow_the_tangent_planes_of_a_sphere() {
        // Two points of the unit circle at ±10°, normals radial.
        let t = 10f64.to_radians();
        let (pa, pb) = (Vector3::new(t.cos(), t.sin(), 0.0), Vector3::new(t.cos(), -t.sin(), 0.0));
        let st = State {
            pos: vec![pa, pb],
            nrm: vec![pa, pb],
            plane: vec![None, None],
            rim: vec![None, None],
            faces: vec![],
            face_plane: vec![],
            origin: vec![],
            target: vec![],
            uv: None,
            normals: None,
            parents: Vec::new(),
        };
        let (p, n, _) = st.midpoint(0, 1);
        // Hand-derived: m = (cos t, 0, 0); (m − pa)·na = cos²t − 1 = −sin²t, so each tangent
        // plane projection is m + sin²t·nᵢ, their mean m + sin²t (cos t, 0, 0), and
        // m + ½(p* − m) = (cos t (1 + ½ sin²t), 0, 0) = (1 − 3t⁴/8 + …, 0, 0): moved out from
        // the chord (cos t, 1.5 % inside) to within 0.04 % of the circle.
        let want = t.cos() * (1.0 + 0.5 * t.sin().powi(2));
        assert!((p - Vector3::new(want, 0.0, 0.0)).norm() < 1e-12, "{p}");
        assert!((n - Vector3::x()).norm() < 1e-12);
        assert!((p.norm() - 1.0).abs() < 4e-4 && (t.cos() - 1.0).abs() > 0.01);
    }

    #[test]
    fn every_pattern_of_marks_tiles_the_triangle_with_its_orientation() {
        // A scalene triangle whose longest edge is edge 2 (corners 2 → 0).
        let p =
            [Vector3::new(0.0, 0.0, 0.0), Vector3::new(1.0, 0.2, 0.0), Vector3::new(0.3, 1.5, 0.0)];
        let slot = |s: usize| if s < 3 { p[s] } else { (p[s - 3] + p[(s - 2) % 3]) * 0.5 };
        for m in
            [[false, false, true], [true, false, true], [false, true, true], [true, true, true]]
        {
            let ch = children(m, 2);
            let mut total = 0.0f64;
            for c in &ch {
                let q = c.map(slot);
                let a = 0.5 * (q[1] - q[0]).cross(&(q[2] - q[0])).z;
                assert!(a > 0.0, "{m:?}: child {c:?} flipped");
                total += a;
            }
            let whole = 0.5 * (p[1] - p[0]).cross(&(p[2] - p[0])).z;
            assert!((total - whole).abs() < 1e-12, "{m:?}");
            // Each marked edge's midpoint is used, no unmarked one is.
            for k in 0..3 {
                assert_eq!(ch.iter().any(|c| c.contains(&(3 + k))), m[k], "{m:?}");
            }
        }
    }

    #[test]
    fn uvs_are_split_per_corner_and_interpolated() {
        let mut m = square();
        m.uv = Some(CornerAttribute {
            values: m.positions.iter().map(|p| nalgebra::Vector2::new(p.x, p.y)).collect(),
            corners: m.faces.clone(),
        });
        let r = refine(&m, &[0.6, 0.6], &RefineOptions::default()).unwrap();
        let uv = r.mesh.uv.as_ref().unwrap();
        // The UV of every corner equals the (flat) position's xy.
        for (f, face) in r.mesh.faces.iter().enumerate() {
            for (&v, t) in face.iter().zip(uv.face(f)) {
                let p = r.mesh.positions[v as usize];
                assert!((p.x - t.x).abs() < 1e-12 && (p.y - t.y).abs() < 1e-12);
            }
        }
    }
}
