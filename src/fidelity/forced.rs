//! Singular triangles the highlight forces (docs/math.md §10, "Forced singularities").
//!
//! h̄, the tangent part of the key light's half vector, is a direction field whose zeros are the
//! critical points c (h ∥ n); its angle θ winds around each by its index (+1 where the surface
//! curves the same way in every direction, −1 at a saddle of the normal map). Write the grain's
//! angle as φ = θ + ψ. On a loop around c that the highlight (g = hᵀu = 0, ψ ≡ π/2 mod π) does
//! not cross, ψ stays within a half turn, so it cannot wind, and φ winds as θ does: the grain has
//! singularities of total index ind(c) inside the loop. So every smooth grain puts its
//! highlight through every critical point, and a field whose highlight passes a critical point
//! by has singular triangles there — whatever the solver does. For a line field (k = 2) that is
//! |ind| · k triangles of index ±½ as a generic field has them.
//!
//! Discretely: θᵢ is the angle of h̄ in vertex i's frame, and a face where the field θ has a
//! non-zero index (the connection's index, [`crate::highlight::singularities()`] with k = 1) holds a
//! zero of h̄ — counted only where |h̄| ≥ 10⁻⁶ at every corner (a flat region facing the light,
//! h̄ ≡ 0, holds no isolated zero, and its round-off angles no index). Each zero's
//! *neighbourhood* is the vertices within [`NEIGHBOURHOOD_RINGS`] edges of its corners; zeros
//! whose neighbourhoods share a vertex form a group. A group whose
//! neighbourhood's rim (its vertices with a neighbour outside) has no edge where g changes sign
//! (a line field's second vertex aligned to the first) forces |Σ ind| · k singular triangles,
//! Σ over the faces with every corner in the neighbourhood: the rim is the loop of the argument
//! above, so the count never includes one the field could avoid with the highlight it has.

use nalgebra::Vector3;

use crate::geometry::Geometry;
use crate::highlight::singularities::face_index;
use crate::highlight::Symmetry;
use crate::mesh::{Mesh, VertexFaces};

/// The rings of vertices around a zero's face: the neighbourhood whose rim the highlight must
/// not cross for the zero to force a singularity.
pub const NEIGHBOURHOOD_RINGS: usize = 2;

/// What the critical points inside a support force on a field.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct Forced {
    /// Faces holding a zero of h̄ (a critical point of the key light) among the faces given.
    pub critical_points: usize,
    /// Of them, those in groups that no highlight passes (and whose indices do not cancel).
    pub passed_by: usize,
    /// The singular triangles they force: Σ |Σ ind| · k over those groups.
    pub singular: usize,
}

/// The critical points among `faces` (ascending) and the singular triangles they force on the
/// field `u` (world-space unit grain vectors) under the half vectors `h`.
pub fn forced_singular(
    mesh: &Mesh,
    geometry: &Geometry,
    h: &[Vector3<f64>],
    u: &[Vector3<f64>],
    symmetry: Symmetry,
    faces: &[usize],
) -> Forced {
    CriticalGroups::new(mesh, geometry, h, faces).forced(geometry, h, u, symmetry)
}

/// The critical points of h̄ among some faces, grouped, with what does not depend on the grain:
/// each group's neighbourhood and the sum of the indices inside it.
pub struct CriticalGroups {
    /// Faces holding a zero of h̄.
    critical_points: usize,
    /// Per group: its members, its neighbourhood's vertices (ascending) and Σ ind inside.
    groups: Vec<(usize, Vec<usize>, i64)>,
}

impl CriticalGroups {
    /// The zeros of h̄ (half vectors `h`) among `faces` (ascending), grouped.
    pub fn new(
        mesh: &Mesh,
        geometry: &Geometry,
        h: &[Vector3<f64>],
        faces: &[usize],
    ) -> CriticalGroups {
        let (theta, defined) = h_angles(geometry, h);
        // θ's index only where h̄ has a direction at every corner: a flat region facing the
        // light (h̄ ≡ 0) holds no isolated zero, and its round-off angles no index.
        let index = |f: usize| {
            if mesh.faces[f].iter().all(|&v| defined[v as usize]) {
                face_index(mesh, geometry, &theta, f, 1) as i64
            } else {
                0
            }
        };
        let zeros: Vec<usize> = faces.iter().copied().filter(|&f| index(f) != 0).collect();
        if zeros.is_empty() {
            return CriticalGroups { critical_points: 0, groups: Vec::new() };
        }
        let vf = VertexFaces::new(mesh);
        let hoods: Vec<Vec<usize>> =
            zeros.iter().map(|&f| within_rings(mesh, geometry, f)).collect();
        let groups = groups(&hoods)
            .into_iter()
            .map(|members| {
                let mut inside: Vec<usize> =
                    members.iter().flat_map(|&z| hoods[z].iter().copied()).collect();
                inside.sort_unstable();
                inside.dedup();
                let is_in = |v: u32| inside.binary_search(&(v as usize)).is_ok();
                // Σ ind over the faces with every corner inside (zeros beyond the support too).
                let mut around: Vec<usize> = inside
                    .iter()
                    .flat_map(|&v| vf.of(v).iter().map(|&(f, _)| f as usize))
                    .collect();
                around.sort_unstable();
                around.dedup();
                let sum: i64 = around
                    .iter()
                    .filter(|&&f| mesh.faces[f].iter().all(|&v| is_in(v)))
                    .map(|&f| index(f))
                    .sum();
                (members.len(), inside, sum)
            })
            .collect();
        CriticalGroups { critical_points: zeros.len(), groups }
    }

    /// What they force on the field `u` (world-space unit grain vectors; the same `h`).
    pub fn forced(
        &self,
        geometry: &Geometry,
        h: &[Vector3<f64>],
        u: &[Vector3<f64>],
        symmetry: Symmetry,
    ) -> Forced {
        let k = symmetry.k() as u64;
        let mut forced = Forced { critical_points: self.critical_points, ..Default::default() };
        for (members, inside, sum) in &self.groups {
            let is_in = |v: usize| inside.binary_search(&v).is_ok();
            if *sum != 0 && !rim_crossed(geometry, h, u, symmetry, inside, &is_in) {
                forced.passed_by += members;
                forced.singular += (sum.unsigned_abs() * k) as usize;
            }
        }
        forced
    }
}

/// |h̄| (of a unit h) below which h̄ has no direction.
const MIN_TANGENT_H: f64 = 1e-6;

/// θᵢ, the angle of h̄ in vertex i's frame, and whether |h̄ᵢ| ≥ [`MIN_TANGENT_H`] |hᵢ|.
fn h_angles(geometry: &Geometry, h: &[Vector3<f64>]) -> (Vec<f64>, Vec<bool>) {
    geometry
        .frames
        .iter()
        .zip(h)
        .map(|(f, h)| {
            let hb = f.to_local(h);
            (hb.y.atan2(hb.x), hb.norm() >= MIN_TANGENT_H * h.norm())
        })
        .unzip()
}

/// Whether the highlight crosses the rim of the vertex set `inside`: an edge between two of its
/// vertices that have a neighbour outside, where g = hᵀu changes sign (a line field's second
/// vertex aligned to the first).
fn rim_crossed(
    geometry: &Geometry,
    h: &[Vector3<f64>],
    u: &[Vector3<f64>],
    symmetry: Symmetry,
    inside: &[usize],
    is_in: &impl Fn(usize) -> bool,
) -> bool {
    let adj = &geometry.adjacency;
    let on_rim = |v: usize| adj.slots(v).any(|s| !is_in(adj.target(s)));
    inside.iter().copied().filter(|&a| on_rim(a)).any(|a| {
        adj.slots(a).any(|s| {
            let b = adj.target(s);
            if !(is_in(b) && on_rim(b)) {
                return false;
            }
            let ub = if symmetry == Symmetry::Line && u[b].dot(&u[a]) < 0.0 { -u[b] } else { u[b] };
            let (ga, gb) = (h[a].dot(&u[a]), h[b].dot(&ub));
            (ga >= 0.0) != (gb >= 0.0) || !(ga.is_finite() && gb.is_finite())
        })
    })
}

/// The vertices within [`NEIGHBOURHOOD_RINGS`] edges of face `f`'s corners, ascending.
fn within_rings(mesh: &Mesh, geometry: &Geometry, f: usize) -> Vec<usize> {
    let adj = &geometry.adjacency;
    let mut verts: Vec<usize> = mesh.faces[f].iter().map(|&v| v as usize).collect();
    let mut frontier = verts.clone();
    for _ in 0..NEIGHBOURHOOD_RINGS {
        let mut next = Vec::new();
        for &v in &frontier {
            for s in adj.slots(v) {
                let j = adj.target(s);
                if !verts.contains(&j) && !next.contains(&j) {
                    next.push(j);
                }
            }
        }
        verts.extend_from_slice(&next);
        frontier = next;
    }
    verts.sort_unstable();
    verts
}

/// The groups of zeros whose vertex sets share a vertex (union–find), each ascending, in the
/// order of their first member.
fn groups(sets: &[Vec<usize>]) -> Vec<Vec<usize>> {
    fn root(parent: &mut [usize], mut i: usize) -> usize {
        while parent[i] != i {
            parent[i] = parent[parent[i]];
            i = parent[i];
        }
        i
    }
    let mut parent: Vec<usize> = (0..sets.len()).collect();
    let mut owner = std::collections::HashMap::<usize, usize>::new();
    for (z, set) in sets.iter().enumerate() {
        for &v in set {
            if let Some(&other) = owner.get(&v) {
                let (a, b) = (root(&mut parent, z), root(&mut parent, other));
                if a != b {
                    parent[a.max(b)] = a.min(b);
                }
            } else {
                owner.insert(v, z);
            }
        }
    }
    let mut out: Vec<Vec<usize>> = Vec::new();
    let mut slot = vec![usize::MAX; sets.len()];
    for z in 0..sets.len() {
        let r = root(&mut parent, z);
        if slot[r] == usize::MAX {
            slot[r] = out.len();
            out.push(Vec::new());
        }
        out[slot[r]].push(z);
    }
    out
}
