//! Untangling a designed grain where the part is sculpted finer than the brush (docs/math.md
//! §10, "Untangling").
//!
//! A warp or a drawn curve designs the grain vertex by vertex ([`super::warp`],
//! [`super::curve`]): φ* = θ(h̄) + ψ*, the angle ψ* from h̄ pulled back from where the highlight
//! came from. On skin folds h̄ has critical points every few millimetres, and ψ* brings along the
//! winding it had around the ones it came from while θ keeps winding around the ones that stay:
//! the design meets every position row but turns the grain by more than a right angle within a
//! triangle, in pairs of singular faces no highlight asks for.
//!
//! The design's singular faces are grown into *parts* ([`PASS_RINGS`] rings of the support
//! around them, in connected components). In each part the rotation the edits ask for,
//! Δ = φ* − φ_before (a number per vertex, mod 2π/k: it has no winding of its own), is replaced
//! by its harmonic fill from the part's rim, holding
//!
//! - the key highlight as the design draws it: the vertices at an edge where ĝ changes sign,
//!   with |ĝ*| ≤ [`HOLD`] and h̄ resolved (|h̄| ≥ [`MIN_RESOLVED_H`]), keep their design — except
//!   within [`RELEASE_RINGS`] rings of a critical point of h̄, through which every smooth grain
//!   puts a highlight (§10), so the highlight may pass it there;
//! - the dark: a filled vertex whose ĝ falls below [`BAND`] on the side of h̄ the design gave it
//!   (near a critical point, on either side) is held at the band's edge and the fill repeated
//!   (at most [`BAND_ROUNDS`] times), so that the fill adds no glow and, away from the critical
//!   points, no highlight.
//!
//! A part's fill is kept when its faces hold fewer singular ones than the design's; its ĝ
//! becomes the position target there (the solve then starts from it and keeps it). The parts
//! still singular are grown further in the next pass.
//!
//! Work: per pass one scan of the support's faces and one sparse solve per part and band round;
//! [`PASS_RINGS`] and [`BAND_ROUNDS`] bound the passes and rounds.

use std::collections::HashSet;

use super::{g_hat, Context, State};
use crate::geometry::connection::wrap_angle;
use crate::solve::fill::rotation_fill;
use crate::solve::singularities::face_index;

/// The rings of the support grown around the design's singular faces, one pass each.
pub const PASS_RINGS: [usize; 3] = [4, 8, 16];

/// |ĝ*| up to which a vertex at a key-highlight crossing keeps its design.
pub const HOLD: f64 = 0.3;

/// |ĝ| a filled vertex keeps: no glow where the edit asked for dark.
pub const BAND: f64 = 0.5;

/// Rounds of holding the filled vertices that left the band.
pub const BAND_ROUNDS: usize = 6;

/// Rings around a critical point of h̄ within which the highlight may move.
pub const RELEASE_RINGS: usize = 3;

/// |h̄| (of a unit h) below which the mesh does not resolve θ at a vertex: its crossing is not
/// held and its band not kept (within 3° of h ∥ n).
pub const MIN_RESOLVED_H: f64 = 0.05;

/// What untangling did, summed over its passes.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct Untangled {
    /// Singular faces the design added inside the support.
    pub singular_designed: usize,
    /// Of them, or new ones, those left after the fills.
    pub singular_left: usize,
    /// Parts whose fill was kept.
    pub parts_filled: usize,
    /// Vertices those fills turned.
    pub vertices_turned: usize,
}

/// Untangles the designed grain of `st` inside the edits' support (see the module docs).
pub(crate) fn untangle(ctx: &Context, st: &mut State) -> Untangled {
    let before: Vec<f64> = st.phi.iter().zip(&st.designed).map(|(p, d)| d.unwrap_or(*p)).collect();
    let mut left = designed_singular(ctx, st, &before);
    let mut out = Untangled { singular_designed: left.len(), ..Default::default() };
    if left.is_empty() {
        return out;
    }
    let weights = vec![1.0; ctx.geom.adjacency.num_slots()];
    for rings in PASS_RINGS {
        for part in parts(ctx, st, &left, rings) {
            if let Some(n) = fill_part(ctx, st, &before, &part, &weights) {
                out.parts_filled += 1;
                out.vertices_turned += n;
            }
        }
        left = designed_singular(ctx, st, &before);
        if left.is_empty() {
            break;
        }
    }
    out.singular_left = left.len();
    out
}

/// The faces inside the support, with a corner the edits designed, whose index differs from
/// the field's before the edits and is not 0; ascending.
fn designed_singular(ctx: &Context, st: &State, before: &[f64]) -> Vec<usize> {
    let (mesh, k) = (ctx.mesh, ctx.symmetry.k());
    (0..mesh.num_faces())
        .filter(|&f| {
            let c = mesh.faces[f];
            c.iter().all(|&v| st.support[v as usize])
                && c.iter().any(|&v| st.designed[v as usize].is_some())
        })
        .filter(|&f| {
            let after = face_index(mesh, ctx.geom, &st.phi, f, k);
            after != 0 && after != face_index(mesh, ctx.geom, before, f, k)
        })
        .collect()
}

/// The support's vertices within `rings` rings of the `faces`, in connected parts (each
/// ascending, the parts by their first vertex).
fn parts(ctx: &Context, st: &State, faces: &[usize], rings: usize) -> Vec<Vec<u32>> {
    let adj = &ctx.geom.adjacency;
    let n = ctx.mesh.num_vertices();
    let mut mark = vec![false; n];
    let seeds = faces.iter().flat_map(|&f| ctx.mesh.faces[f]);
    grow(adj, seeds, rings, |w| st.support[w] && !std::mem::replace(&mut mark[w], true));
    let mut seen = vec![false; n];
    let mut out = Vec::new();
    for v in 0..n {
        if !mark[v] || seen[v] {
            continue;
        }
        seen[v] = true;
        let mut part = vec![v as u32];
        let mut i = 0;
        while i < part.len() {
            for &w in adj.neighbors(part[i] as usize) {
                if mark[w as usize] && !seen[w as usize] {
                    seen[w as usize] = true;
                    part.push(w);
                }
            }
            i += 1;
        }
        part.sort_unstable();
        out.push(part);
    }
    out
}

/// Visits the `seeds` and `rings` rings around them: `take(v)` says whether v is new and
/// inside (then it is grown from).
fn grow(
    adj: &crate::mesh::Adjacency,
    seeds: impl Iterator<Item = u32>,
    rings: usize,
    mut take: impl FnMut(usize) -> bool,
) {
    let mut front: Vec<u32> = seeds.filter(|&v| take(v as usize)).collect();
    for _ in 0..rings {
        let mut next = Vec::new();
        for &v in &front {
            for &w in adj.neighbors(v as usize) {
                if take(w as usize) {
                    next.push(w);
                }
            }
        }
        front = next;
    }
}

/// One part's fill (see the module docs): the number of vertices turned, or `None` when the
/// fill is not kept.
fn fill_part(
    ctx: &Context,
    st: &mut State,
    before: &[f64],
    part: &[u32],
    weights: &[f64],
) -> Option<usize> {
    let (mesh, adj, k) = (ctx.mesh, &ctx.geom.adjacency, ctx.symmetry.k());
    let kf = k as f64;
    let in_part = |v: u32| part.binary_search(&v).is_ok();
    let mut faces: Vec<usize> =
        part.iter().flat_map(|&v| ctx.vf.of(v as usize).iter().map(|&(f, _)| f as usize)).collect();
    faces.sort_unstable();
    faces.dedup();
    let singular =
        |phi: &[f64]| faces.iter().filter(|&&f| face_index(mesh, ctx.geom, phi, f, k) != 0).count();
    let interior: Vec<u32> = part
        .iter()
        .copied()
        .filter(|&v| adj.neighbors(v as usize).iter().all(|&w| in_part(w)))
        .collect();
    let released = near_critical_points(ctx, st, &faces);
    let resolved = |i: usize| ctx.geom.frames[i].to_local(&st.h[i]).norm() >= MIN_RESOLVED_H;
    // The rotation the edits ask for, mod 2π/k.
    let mut delta: Vec<f64> =
        st.phi.iter().zip(before).map(|(p, b)| wrap_angle(kf * (p - b)) / kf).collect();
    let mut free: Vec<u32> = interior
        .iter()
        .copied()
        .filter(|&v| {
            let i = v as usize;
            let held = st.h_angle(ctx, i).is_some()
                && resolved(i)
                && !released.contains(&v)
                && st.target_g[i].abs() <= HOLD
                && on_crossing(ctx, st, i);
            !held
        })
        .collect();
    let mut filled = rotation_fill(ctx.geom, weights, &delta, &free, k)?;
    for _ in 0..BAND_ROUNDS {
        let before_len = free.len();
        free.retain(|&v| {
            let i = v as usize;
            let Some(theta) = st.h_angle(ctx, i).filter(|_| resolved(i)) else { return true };
            let psi = wrap_angle(before[i] + filled[i] - theta);
            // The design's side of h̄ (near a critical point, the fill's own).
            let side_of = |a: f64| if a.cos() < 0.0 { -1.0 } else { 1.0 };
            let side = if released.contains(&v) {
                side_of(psi)
            } else {
                side_of(before[i] + delta[i] - theta)
            };
            if side * psi.cos() >= BAND {
                return true;
            }
            let edge = (side * BAND).acos().copysign(psi);
            delta[i] = filled[i] + wrap_angle(theta + edge - (before[i] + filled[i]));
            false
        });
        if free.len() == before_len {
            break;
        }
        filled = rotation_fill(ctx.geom, weights, &delta, &free, k)?;
    }
    let mut phi = st.phi.clone();
    for &v in &interior {
        let i = v as usize;
        let d = if free.binary_search(&v).is_ok() { filled[i] } else { delta[i] };
        phi[i] = st.phi[i] + wrap_angle(kf * (before[i] + d - st.phi[i])) / kf;
    }
    if singular(&phi) >= singular(&st.phi) {
        return None;
    }
    let mut turned = 0;
    for &v in &interior {
        let i = v as usize;
        if phi[i] == st.phi[i] {
            continue;
        }
        turned += 1;
        let g = st.design(ctx, i, phi[i]);
        if st.edit_weight_g[i].is_some() {
            st.target_g[i] = g;
        }
    }
    Some(turned)
}

/// The vertices within [`RELEASE_RINGS`] rings of a face among `faces` around which θ, the
/// angle of h̄, winds (a critical point of h̄; only where h̄ has a direction at every corner).
fn near_critical_points(ctx: &Context, st: &State, faces: &[usize]) -> HashSet<u32> {
    let mesh = ctx.mesh;
    let mut theta = vec![f64::NAN; mesh.num_vertices()];
    for &f in faces {
        for &v in &mesh.faces[f] {
            theta[v as usize] = st.h_angle(ctx, v as usize).unwrap_or(f64::NAN);
        }
    }
    let critical = faces.iter().copied().filter(|&f| {
        mesh.faces[f].iter().all(|&v| theta[v as usize].is_finite())
            && face_index(mesh, ctx.geom, &theta, f, 1) != 0
    });
    let mut out = HashSet::new();
    let seeds = critical.flat_map(|f| mesh.faces[f]).collect::<Vec<_>>();
    grow(&ctx.geom.adjacency, seeds.into_iter(), RELEASE_RINGS, |w| out.insert(w as u32));
    out
}

/// Whether vertex `i` ends an edge the key highlight crosses: ĝ changes sign along it (a line
/// field's neighbour aligned to `i`'s grain).
fn on_crossing(ctx: &Context, st: &State, i: usize) -> bool {
    let adj = &ctx.geom.adjacency;
    let line = ctx.symmetry.k() == 2;
    let gi = g_hat(&ctx.geom.frames[i], st.phi[i], &st.h[i]);
    adj.slots(i).any(|s| {
        let j = adj.target(s);
        let turn = st.phi[j] + ctx.geom.transport[s] - st.phi[i];
        let flip = if line && turn.cos() < 0.0 { std::f64::consts::PI } else { 0.0 };
        gi * g_hat(&ctx.geom.frames[j], st.phi[j] + flip, &st.h[j]) < 0.0
    })
}
