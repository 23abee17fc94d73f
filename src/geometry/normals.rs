//! Per-vertex normals.
//!
//! The default is the angle-weighted normal (Thürmer & Wüthrich 1998): the sum of the incident
//! face normals weighted by the corner angle at the vertex. It is independent of how the
//! one-ring is triangulated, unlike the area-weighted one. The jet fit ([`super::curvature`])
//! refines it further.

use nalgebra::Vector3;
use rayon::prelude::*;

use crate::mesh::planar::{planar_regions, TANGENT_COS};
use crate::mesh::refine::{FLAT_COS, MIN_FLAT_FACES};
use crate::mesh::Mesh;
pub use crate::mesh::VertexFaces;

/// How the initial vertex normals are computed.
#[derive(
    Clone,
    Copy,
    Debug,
    Default,
    PartialEq,
    Eq,
    serde::Serialize,
    serde::Deserialize,
    schemars::JsonSchema,
)]
#[serde(rename_all = "kebab-case")]
pub enum NormalSource {
    /// Face normals weighted by the corner angle (the default).
    #[default]
    AngleWeighted,
    /// Face normals weighted by the face area.
    AreaWeighted,
    /// The file's normals (`vn`), averaged over the corners of each vertex; falls back to
    /// angle-weighted where the file has none.
    File,
}

/// The direction used where a vertex has no usable normal (an isolated vertex, or a vertex
/// whose faces all have zero area): +Z. Such vertices are counted by [`vertex_normals`].
pub const FALLBACK_NORMAL: Vector3<f64> = Vector3::new(0.0, 0.0, 1.0);

/// Unit face normals (zero vector for a zero-area face): the normals of [`face_data`].
pub fn face_normals(mesh: &Mesh) -> Vec<Vector3<f64>> {
    face_data(mesh).into_iter().map(|f| f.normal).collect()
}

/// A face's unit normal (zero for a zero-area face) and its interior angles at its three
/// corners, in the face's vertex order.
#[derive(Clone, Copy, Debug)]
pub struct FaceData {
    /// Unit normal, or zero.
    pub normal: Vector3<f64>,
    /// Interior angles (they add up to π).
    pub angles: [f64; 3],
}

/// [`FaceData`] of every face. The corner angles share the face's cross product:
/// αₐ = atan2(|e_ab × e_ac|, e_ab·e_ac), likewise at b, and α_c = π − αₐ − α_b (an absolute error
/// of a few ulps of π, which is what a normal weight needs; one atan2 and no cross product
/// fewer per corner than [`corner_angle`] at each corner).
pub fn face_data(mesh: &Mesh) -> Vec<FaceData> {
    (0..mesh.num_faces())
        .into_par_iter()
        .map(|f| {
            let [a, b, c] = mesh.face_positions(f);
            let (ab, ac, bc) = (b - a, c - a, c - b);
            let n = ab.cross(&ac);
            let len = n.norm();
            let normal = if len > 0.0 && len.is_finite() { n / len } else { Vector3::zeros() };
            let alpha = len.atan2(ab.dot(&ac));
            let beta = len.atan2(-ab.dot(&bc));
            let gamma = (std::f64::consts::PI - alpha - beta).max(0.0);
            FaceData { normal, angles: [alpha, beta, gamma] }
        })
        .collect()
}

/// Interior angle of a triangle at `a` (between `b − a` and `c − a`), robust for tiny angles.
#[inline]
pub fn corner_angle(a: &Vector3<f64>, b: &Vector3<f64>, c: &Vector3<f64>) -> f64 {
    let (u, v) = (b - a, c - a);
    u.cross(&v).norm().atan2(u.dot(&v))
}

/// Per-vertex unit normals and the number of vertices that took [`FALLBACK_NORMAL`].
///
/// Accumulates per face and reduces per vertex through `vertex_faces` so the sum order, and
/// hence every bit of the result, is independent of the thread count.
pub fn vertex_normals(
    mesh: &Mesh,
    vertex_faces: &VertexFaces,
    source: NormalSource,
) -> (Vec<Vector3<f64>>, usize) {
    vertex_normals_from_faces(mesh, vertex_faces, &face_data(mesh), source)
}

/// [`vertex_normals`] from the mesh's face normals and corner angles (as [`face_data`] gives
/// them).
pub fn vertex_normals_from_faces(
    mesh: &Mesh,
    vertex_faces: &VertexFaces,
    faces: &[FaceData],
    source: NormalSource,
) -> (Vec<Vector3<f64>>, usize) {
    let file_avg = match (source, &mesh.normals) {
        (NormalSource::File, Some(_)) => Some(file_vertex_normals(mesh, vertex_faces)),
        _ => None,
    };
    let normals: Vec<Vector3<f64>> = (0..mesh.num_vertices())
        .into_par_iter()
        .map(|v| {
            if let Some(n) = file_avg.as_ref().and_then(|f| f[v]) {
                return n;
            }
            let mut sum = Vector3::zeros();
            for &(f, c) in vertex_faces.of(v) {
                let face = &faces[f as usize];
                let w = match source {
                    NormalSource::AreaWeighted => {
                        let fv = mesh.faces[f as usize];
                        let p = |k: usize| mesh.positions[fv[(c as usize + k) % 3] as usize];
                        0.5 * (p(1) - p(0)).cross(&(p(2) - p(0))).norm()
                    }
                    _ => face.angles[c as usize],
                };
                sum += w * face.normal;
            }
            normalize_or(sum, FALLBACK_NORMAL)
        })
        .collect();
    let fallback = (0..mesh.num_vertices())
        .into_par_iter()
        .filter(|&v| {
            vertex_faces.of(v).iter().all(|&(f, _)| faces[f as usize].normal == Vector3::zeros())
        })
        .count();
    (normals, fallback)
}

fn file_vertex_normals(mesh: &Mesh, vf: &VertexFaces) -> Vec<Option<Vector3<f64>>> {
    let attr = mesh.normals.as_ref().expect("checked by caller");
    (0..mesh.num_vertices())
        .into_par_iter()
        .map(|v| {
            let sum: Vector3<f64> = vf
                .of(v)
                .iter()
                .map(|&(f, c)| attr.values[attr.corners[f as usize][c as usize] as usize])
                .sum();
            let n = sum.norm();
            (n > 1e-12 && n.is_finite()).then(|| sum / n)
        })
        .collect()
}

/// `v / |v|`, or `fallback` when `v` is zero or not finite.
#[inline]
pub fn normalize_or(v: Vector3<f64>, fallback: Vector3<f64>) -> Vector3<f64> {
    let n = v.norm();
    if n > 1e-300 && n.is_finite() {
        v / n
    } else {
        fallback
    }
}

/// The default crease angle (degrees): edges whose faces' normals differ by more than this are
/// sharp (the scene key `mesh.crease_angle`).
pub const DEFAULT_CREASE_ANGLE_DEG: f64 = 40.0;

/// Shading normals per face corner that do not average across sharp edges, and what was split.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct CornerNormals {
    /// For each face, the unit normal at each of its three corners.
    pub corners: Vec<[Vector3<f64>; 3]>,
    /// Edges whose dihedral angle exceeds the crease angle (each counted once).
    pub crease_edges: usize,
    /// Vertices whose faces form two or more smooth sectors (their corners differ).
    pub split_vertices: usize,
}

/// Whether the edge between faces with unit normals `a` and `b` is sharp at crease angle θ:
/// the angle between the normals exceeds θ, i.e. aᵀb < cos θ (math.md §3, "Creases"). A face
/// of zero area (zero normal) is sharp against every neighbour, so it joins no sector.
#[inline]
pub fn is_crease(a: &Vector3<f64>, b: &Vector3<f64>, cos_theta: f64) -> bool {
    a == &Vector3::zeros() || b == &Vector3::zeros() || a.dot(b) < cos_theta
}

/// Crease-aware corner normals (math.md §3, "Creases").
///
/// Around each vertex its faces are joined into *smooth sectors*: two faces that share an edge
/// at the vertex are in one sector unless that edge is sharp ([`is_crease`] with
/// `crease_angle_deg`). A vertex with a single sector keeps `vertex_normals[v]` at all its
/// corners (the normal the solver's frame uses), so a smooth mesh shades exactly as before. At
/// a vertex with several sectors each corner takes its sector's normal: the corner-angle
/// weighted sum of the sector's face normals, normalized (Eq. C1). On a flat sector that is the
/// plane's normal, so flat faces meeting at a bend shade flat up to the bend.
///
/// `crease_angle_deg` ≥ 180 splits nothing; 0 splits every edge that is not exactly flat.
/// The result is the same at any thread count (each vertex is computed on its own, in face
/// order).
pub fn corner_normals(
    mesh: &Mesh,
    vertex_faces: &VertexFaces,
    faces: &[FaceData],
    vertex_normals: &[Vector3<f64>],
    crease_angle_deg: f64,
) -> CornerNormals {
    let cos_theta =
        if crease_angle_deg >= 180.0 { -2.0 } else { crease_angle_deg.max(0.0).to_radians().cos() };
    // Per vertex: the normal of each incident corner (None if the vertex is smooth), and the
    // sharp edges from it to a vertex of larger index (so each edge is counted once).
    let per_vertex: Vec<(Option<Vec<Vector3<f64>>>, usize)> = (0..mesh.num_vertices())
        .into_par_iter()
        .map(|v| sector_normals(mesh, v, vertex_faces.of(v), faces, cos_theta))
        .collect();
    let mut corners: Vec<[Vector3<f64>; 3]> = (0..mesh.num_faces())
        .into_par_iter()
        .map(|f| mesh.faces[f].map(|v| vertex_normals[v as usize]))
        .collect();
    let (mut split_vertices, mut crease_edges) = (0, 0);
    for (v, (sectors, sharp)) in per_vertex.iter().enumerate() {
        crease_edges += sharp;
        if let Some(normals) = sectors {
            split_vertices += 1;
            for (&(f, c), n) in vertex_faces.of(v).iter().zip(normals) {
                corners[f as usize][c as usize] = *n;
            }
        }
    }
    CornerNormals { corners, crease_edges, split_vertices }
}

/// The sector normal of each corner of vertex `v`'s fan (in fan order), or `None` when the fan
/// is one smooth sector; and the number of sharp edges from `v` to vertices of larger index.
fn sector_normals(
    mesh: &Mesh,
    v: usize,
    fan: &[(u32, u8)],
    faces: &[FaceData],
    cos_theta: f64,
) -> (Option<Vec<Vector3<f64>>>, usize) {
    let k = fan.len();
    if k < 2 {
        return (None, 0);
    }
    // Union–find over the fan: faces sharing an edge (v, w) that is not sharp are joined. The
    // edges at the vertex are keyed by their other endpoint w and sorted to find the pairs.
    let mut parent: Vec<usize> = (0..k).collect();
    fn find(p: &mut [usize], mut i: usize) -> usize {
        while p[i] != i {
            p[i] = p[p[i]];
            i = p[i];
        }
        i
    }
    let mut spokes: Vec<(u32, usize)> = Vec::with_capacity(2 * k);
    for (i, &(f, c)) in fan.iter().enumerate() {
        let fv = mesh.faces[f as usize];
        spokes.push((fv[(c as usize + 1) % 3], i));
        spokes.push((fv[(c as usize + 2) % 3], i));
    }
    spokes.sort_unstable();
    let (mut j, mut sharp) = (0, 0);
    while j < spokes.len() {
        let mut e = j + 1;
        while e < spokes.len() && spokes[e].0 == spokes[j].0 {
            e += 1;
        }
        let mut sharp_edge = false;
        for a in j..e {
            for b in a + 1..e {
                let (fa, fb) = (spokes[a].1, spokes[b].1);
                let (na, nb) =
                    (&faces[fan[fa].0 as usize].normal, &faces[fan[fb].0 as usize].normal);
                if is_crease(na, nb, cos_theta) {
                    sharp_edge = true;
                } else {
                    let (ra, rb) = (find(&mut parent, fa), find(&mut parent, fb));
                    parent[ra.max(rb)] = ra.min(rb);
                }
            }
        }
        sharp += usize::from(sharp_edge && spokes[j].0 as usize > v);
        j = e;
    }
    let roots: Vec<usize> = (0..k).map(|i| find(&mut parent, i)).collect();
    if roots.iter().all(|&r| r == roots[0]) {
        return (None, sharp);
    }
    // Eq. C1: n_S = Σ_{f ∈ S} α_f n_f / |Σ α_f n_f|, summed in fan order.
    let mut sums = vec![Vector3::zeros(); k];
    for (i, &(f, c)) in fan.iter().enumerate() {
        let d = &faces[f as usize];
        sums[roots[i]] += d.angles[c as usize] * d.normal;
    }
    let normals = (0..k)
        .map(|i| {
            // A sector of zero-area faces only: the face's own (zero) normal; the renderer then
            // falls back to the geometric normal.
            normalize_or(sums[roots[i]], faces[fan[i].0 as usize].normal)
        })
        .collect();
    (Some(normals), sharp)
}

/// Sets the normal of the vertices that flat faces fix, and says which (math.md §3, "Flat
/// regions"): an interior vertex with at least three faces, all coplanar (within 1e-4 rad), is
/// *flat*, and its normal is their plane's, which the jet fit does not tilt; a vertex on the
/// rim of flat faces — some of its faces are incident to a flat
/// vertex, all of those lie in one plane, and its other faces lean less than 30° from it (a
/// fillet or a gently curved face meeting the plane tangentially, as CAD parts are made) — gets
/// the plane's normal too. Weighted averages leaned such a rim towards the curved side by half
/// its first step, so the flat face shaded as if it curved up to its rim. A CAD export's flat
/// face has no vertex inside it: a vertex on several planar regions takes the plane of the
/// widest when that one dominates ([`crate::mesh::planar`]).
pub fn pin_flat_normals(
    mesh: &Mesh,
    vf: &VertexFaces,
    adjacency: &crate::mesh::Adjacency,
    faces: &[FaceData],
    normals: &mut [Vector3<f64>],
) -> Vec<bool> {
    let nv = normals.len();
    // The plane of each flat vertex.
    // Per vertex and independent (in parallel; the same result at any thread count).
    let plane: Vec<Option<Vector3<f64>>> = (0..nv)
        .into_par_iter()
        .map(|v| {
            // Two faces (one quad of a curved grid's corner) or a boundary vertex (the first
            // strip of a ruled surface, a cylinder meshed along its rulings, is planar) do not
            // make a flat region.
            if vf.of(v).len() < MIN_FLAT_FACES || adjacency.is_boundary_vertex(v) {
                return None;
            }
            let mut it = vf.of(v).iter().map(|&(f, _)| faces[f as usize].normal);
            let first = it.find(|n| n.norm_squared() > 0.0)?;
            it.all(|n| n.norm_squared() == 0.0 || n.dot(&first) >= FLAT_COS).then_some(first)
        })
        .collect();
    let regions = planar_regions(mesh);
    let region_plane = regions.vertex_planes(mesh, vf);
    normals
        .par_iter_mut()
        .enumerate()
        .map(|(v, n)| {
            // A flat vertex's normal is its plane's, and the jet fit must not tilt it: a ring
            // grown past the rim (a low-valence vertex's 2-ring) reaches the curved side.
            let target = match plane[v] {
                Some(p) => Some(p),
                None => rim_plane(mesh, vf, faces, &plane, v)
                    .or_else(|| region_plane[v].map(|r| regions.normal[r as usize])),
            };
            // The plane's normal, on the side the vertex's own normal is.
            target.map(|p| *n = if p.dot(n) < 0.0 { -p } else { p }).is_some()
        })
        .collect()
}

/// The plane of the flat faces at rim vertex `v` ([`pin_flat_normals`]), if there is one.
fn rim_plane(
    mesh: &Mesh,
    vf: &VertexFaces,
    faces: &[FaceData],
    plane: &[Option<Vector3<f64>>],
    v: usize,
) -> Option<Vector3<f64>> {
    // The planes of the flat vertices that share a face with v.
    let mut p: Option<Vector3<f64>> = None;
    for &(f, _) in vf.of(v) {
        for &w in &mesh.faces[f as usize] {
            let Some(n) = plane[w as usize] else { continue };
            match p {
                None => p = Some(n),
                Some(q) if q.dot(&n) >= FLAT_COS => {}
                Some(_) => return None, // two planes meet here
            }
        }
    }
    let p = p?;
    let tangent = vf
        .of(v)
        .iter()
        .map(|&(f, _)| faces[f as usize].normal)
        .all(|n| n.norm_squared() == 0.0 || n.dot(&p) >= TANGENT_COS);
    tangent.then_some(p)
}
