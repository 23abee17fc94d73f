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
//! The rotation the edits ask for, Δ = φ* − φ_before, is a number per vertex read mod 2π/k, and
//! those faces are where it winds. Around them it is replaced by a *real* rotation
//! ([`crate::solve::turn`]), which cannot add a singular face: the nearest to the design whose
//! every edge turns the grain by less than a wrap, the design weighted by 1 at the vertices
//! that hold the key highlight as it draws it (an edge where ĝ changes sign, |ĝ*| ≤ [`HOLD`],
//! h̄ resolved, not within [`RELEASE_RINGS`] rings of a critical point of h̄, through which every
//! smooth grain puts a highlight), by [`DARK_WEIGHT`] elsewhere. The parts are grown
//! [`TURN_RINGS`] rings around the singular faces, then as wide around the paths that pair them
//! ([`pairs`]: a rim around a net winding has no real rotation), within the support and
//! [`REACH_RINGS`] rings beyond it (the solve's free region). Where a pair was, the grain turns by a half turn across a band, and the highlight
//! takes the detour through the critical points the design passed by. A part's turn is kept
//! when its faces hold fewer singular ones; its ĝ becomes the position target there (the solve
//! then starts from it and keeps it).
//!
//! Before that, a vertex to which a tool gave a position row but no design, among designed
//! neighbours, is designed at the root of its row nearest its angle (`meet_rows`).
//!
//! Work: per pass one scan of the reach's faces and one bounded turn per part (at most
//! [`crate::solve::turn::ROUNDS`] sparse solves); [`TURN_RINGS`] bounds the passes and
//! [`pairs::MAX_VISITS`] the pairing.

use std::collections::HashSet;

pub mod pairs;

use super::{g_hat, Context, State};
use crate::geometry::connection::wrap_angle;
use crate::highlight::singularities::{face_index, face_index_of};
use crate::solve::turn::{bounded_turn, TurnInput, TurnOptions};

/// |ĝ*| up to which a vertex at a key-highlight crossing holds it.
pub const HOLD: f64 = 0.3;

/// Rings around a critical point of h̄ within which the highlight may move.
pub const RELEASE_RINGS: usize = 3;

/// |h̄| (of a unit h) below which the mesh does not resolve θ at a vertex: its crossing is not
/// held (within 3° of h ∥ n).
pub const MIN_RESOLVED_H: f64 = 0.05;

/// The rings grown around the design's singular faces (then around the paths pairing them),
/// one pass each.
pub const TURN_RINGS: [usize; 3] = [2, 4, 8];

/// The weight of the design at a vertex that holds no crossing (1 at one that does).
pub const DARK_WEIGHT: f64 = 0.1;

/// The rings beyond the support in which bounded turns may turn the grain: the solve's free
/// region with its default margin (`solver.margin_rings`).
pub const REACH_RINGS: usize = 2;

/// The largest turn of a bounded turn's result along an edge, as a share of a wrap.
pub const TURN_BOUND: f64 = 0.8;

/// What untangling did, summed over its passes.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct Untangled {
    /// Singular faces the design added inside the support (and [`REACH_RINGS`] beyond).
    pub singular_designed: usize,
    /// Of them, those left.
    pub singular_left: usize,
    /// Parts whose turn was kept.
    pub parts_turned: usize,
    /// Vertices those turns turned.
    pub vertices_turned: usize,
}

/// Untangles the designed grain of `st` inside the edits' support (see the module docs).
pub(crate) fn untangle(ctx: &Context, st: &mut State) -> Untangled {
    // The grain before the edits, φ where no edit designed it: a design keeps the angle it
    // replaced, so this is the same before and after meet_rows and the turns.
    meet_rows(ctx, st);
    let mut reach = vec![false; st.support.len()];
    let mut reached = Vec::new();
    grow(
        &ctx.geom.adjacency,
        (0..reach.len() as u32).filter(|&v| st.support[v as usize]),
        REACH_RINGS,
        |w| {
            let new = !std::mem::replace(&mut reach[w], true);
            if new {
                reached.push(w as u32);
            }
            new
        },
    );
    let region = Region { inside: &reach, faces: faces_of(ctx, &reached) };
    let mut out = Untangled {
        singular_designed: designed_singular(ctx, st, &region).len(),
        ..Default::default()
    };
    if out.singular_designed == 0 {
        return out;
    }
    let before: Vec<f64> = st.phi.iter().zip(&st.designed).map(|(p, d)| d.unwrap_or(*p)).collect();
    out.singular_left = turn_passes(ctx, st, &before, &region, &mut out);
    out
}

/// Where untangling acts: the support and [`REACH_RINGS`] rings beyond (`inside`, per vertex)
/// and the faces with a corner there (ascending).
struct Region<'a> {
    inside: &'a [bool],
    faces: Vec<usize>,
}

/// The faces with a corner among `vertices`, ascending.
fn faces_of(ctx: &Context, vertices: &[u32]) -> Vec<usize> {
    let mut faces: Vec<usize> =
        vertices.iter().flat_map(|&v| ctx.vf.of(v as usize)).map(|&(f, _)| f as usize).collect();
    faces.sort_unstable();
    faces.dedup();
    faces
}

/// The bounded turns, around the design's singular faces and then around the paths that pair
/// them (see the module docs), inside the `region`; the singular faces left.
fn turn_passes(
    ctx: &Context,
    st: &mut State,
    before: &[f64],
    region: &Region,
    out: &mut Untangled,
) -> usize {
    let reach = region.inside;
    let (mesh, k) = (ctx.mesh, ctx.symmetry.k());
    let theta: Vec<f64> =
        (0..mesh.num_vertices()).map(|i| st.h_angle(ctx, i).unwrap_or(f64::NAN)).collect();
    let mut left = designed_singular(ctx, st, region);
    for paired in [false, true] {
        for rings in TURN_RINGS {
            if left.is_empty() {
                return 0;
            }
            // The rotation the edits ask for (the parts of a pass are disjoint).
            let target: Vec<f64> = st.phi.iter().zip(before).map(|(p, b)| p - b).collect();
            let parts = if paired {
                let charge = |f: usize| {
                    face_index(mesh, ctx.geom, &st.phi, f, k)
                        - face_index(mesh, ctx.geom, before, f, k)
                };
                let paths = pairs::pair_paths(ctx, reach, &left, charge);
                parts_around(ctx, reach, paths.into_iter().flatten(), rings)
            } else {
                parts(ctx, reach, &left, rings)
            };
            for part in parts {
                if let Some(n) = turn_part(ctx, st, (before, &target, &theta), &part) {
                    out.parts_turned += 1;
                    out.vertices_turned += n;
                }
            }
            left = designed_singular(ctx, st, region);
        }
    }
    left.len()
}

/// Designs the vertices whose position row a tool set without designing their grain (its
/// source straddles a turn of ψ, or h̄ vanishes there), among designed neighbours (a stencil's
/// rows, with none, are the solve's to meet): the root of the row nearest the vertex's angle,
/// so that every row is met before the turns (the solve would otherwise pick their branches
/// alone, and a lone pick can turn the grain within a triangle).
fn meet_rows(ctx: &Context, st: &mut State) {
    let bound = crate::solve::position_term::TARGET_BOUND;
    for i in 0..ctx.mesh.num_vertices() {
        let adj = &ctx.geom.adjacency;
        if st.designed[i].is_some()
            || st.edit_weight_g[i].is_none()
            || !adj.neighbors(i).iter().any(|&j| st.designed[j as usize].is_some())
        {
            continue;
        }
        let Some(theta) = st.h_angle(ctx, i) else { continue };
        let t = st.target_g[i].clamp(-bound, bound);
        if (st.g[i] - t).abs() <= 1e-9 || !t.is_finite() {
            continue;
        }
        let a = t.acos();
        let near = |r: f64| st.phi[i] + wrap_angle(r - st.phi[i]);
        let (p, m) = (near(theta + a), near(theta - a));
        let phi = if (p - st.phi[i]).abs() <= (m - st.phi[i]).abs() { p } else { m };
        let g = st.design(ctx, i, phi);
        st.set_g_target(i, g);
    }
}

/// The faces with every corner in `region` and one the edits designed, whose index differs
/// from the field's before the edits and is not 0; ascending.
fn designed_singular(ctx: &Context, st: &State, region: &Region) -> Vec<usize> {
    let (mesh, k) = (ctx.mesh, ctx.symmetry.k());
    let before = |v: usize| st.designed[v].unwrap_or(st.phi[v]);
    // A face with every corner in the region has one there: among the region's faces.
    region
        .faces
        .iter()
        .copied()
        .filter(|&f| {
            let c = mesh.faces[f];
            c.iter().all(|&v| region.inside[v as usize])
                && c.iter().any(|&v| st.designed[v as usize].is_some())
        })
        .filter(|&f| {
            let after = face_index(mesh, ctx.geom, &st.phi, f, k);
            after != 0 && after != face_index_of(mesh, ctx.geom, before, f, k)
        })
        .collect()
}

/// The vertices of `region` within `rings` rings of the `faces`, in connected parts (each
/// ascending, the parts by their first vertex).
fn parts(ctx: &Context, region: &[bool], faces: &[usize], rings: usize) -> Vec<Vec<u32>> {
    parts_around(ctx, region, faces.iter().flat_map(|&f| ctx.mesh.faces[f]), rings)
}

/// The vertices of `region` within `rings` rings of the `seeds`, in connected parts (as
/// [`parts`]).
fn parts_around(
    ctx: &Context,
    region: &[bool],
    seeds: impl Iterator<Item = u32>,
    rings: usize,
) -> Vec<Vec<u32>> {
    let adj = &ctx.geom.adjacency;
    let n = ctx.mesh.num_vertices();
    let mut mark = vec![false; n];
    grow(adj, seeds, rings, |w| region[w] && !std::mem::replace(&mut mark[w], true));
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

/// One part's bounded turn (see the module docs) towards the rotation `target` (one per
/// vertex, mod 2π/k), with θ the angle of h̄ (NaN where it has none): the number of vertices
/// turned, or `None` when it is not kept.
fn turn_part(
    ctx: &Context,
    st: &mut State,
    (before, target, theta): (&[f64], &[f64], &[f64]),
    part: &[u32],
) -> Option<usize> {
    let (mesh, adj, k) = (ctx.mesh, &ctx.geom.adjacency, ctx.symmetry.k());
    let kf = k as f64;
    let in_part = |v: u32| part.binary_search(&v).is_ok();
    let faces = part_faces(ctx, part);
    let singular =
        |phi: &[f64]| faces.iter().filter(|&&f| face_index(mesh, ctx.geom, phi, f, k) != 0).count();
    let interior: Vec<u32> = part
        .iter()
        .copied()
        .filter(|&v| adj.neighbors(v as usize).iter().all(|&w| in_part(w)))
        .collect();
    let released = near_critical_points(ctx, theta, &faces);
    let weight: Vec<f64> = interior
        .iter()
        .map(|&v| if holds_crossing(ctx, st, &released, v) { 1.0 } else { DARK_WEIGHT })
        .collect();
    let input = TurnInput { phi: before, target, free: &interior, weight: &weight, k };
    let options = TurnOptions { bound: TURN_BOUND, smoothness: 0.0 };
    let delta = bounded_turn(ctx.geom, &input, &options)?;
    // The turned angles, each the representative nearest the design's (ĝ's sign is stated in
    // its orientation); tried in place, then put back.
    let turned: Vec<(u32, f64)> = interior
        .iter()
        .zip(&delta)
        .map(|(&v, d)| {
            let i = v as usize;
            (v, st.phi[i] + wrap_angle(kf * (before[i] + d - st.phi[i])) / kf)
        })
        .collect();
    let was = singular(&st.phi);
    let old: Vec<f64> = interior.iter().map(|&v| st.phi[v as usize]).collect();
    for &(v, a) in &turned {
        st.set_phi(v as usize, a);
    }
    let now = singular(&st.phi);
    for (&v, a) in interior.iter().zip(old) {
        st.set_phi(v as usize, a);
    }
    (now < was).then(|| keep(ctx, st, &turned))
}

/// The faces with a corner in `part`, ascending.
fn part_faces(ctx: &Context, part: &[u32]) -> Vec<usize> {
    let mut faces: Vec<usize> =
        part.iter().flat_map(|&v| ctx.vf.of(v as usize).iter().map(|&(f, _)| f as usize)).collect();
    faces.sort_unstable();
    faces.dedup();
    faces
}

/// Whether h̄ is resolved at vertex `i` (|h̄| ≥ [`MIN_RESOLVED_H`]).
fn resolved(ctx: &Context, st: &State, i: usize) -> bool {
    ctx.geom.frames[i].to_local(&st.h[i]).norm() >= MIN_RESOLVED_H
}

/// Whether vertex `v` holds the key highlight as the design draws it (see the module docs).
fn holds_crossing(ctx: &Context, st: &State, released: &HashSet<u32>, v: u32) -> bool {
    let i = v as usize;
    st.h_angle(ctx, i).is_some()
        && resolved(ctx, st, i)
        && !released.contains(&v)
        && st.target_g[i].abs() <= HOLD
        && on_crossing(ctx, st, i)
}

/// Makes the `turned` angles the design (and their ĝ their position target): the number that
/// changed.
fn keep(ctx: &Context, st: &mut State, turned: &[(u32, f64)]) -> usize {
    let mut changed = 0;
    for &(v, a) in turned {
        let i = v as usize;
        if a == st.phi[i] {
            continue;
        }
        changed += 1;
        // The row follows (beyond the support too, where it kept the grain before the edits).
        let g = st.design(ctx, i, a);
        st.set_g_target(i, g);
    }
    changed
}

/// The vertices within [`RELEASE_RINGS`] rings of a face among `faces` around which `theta`, the
/// angle of h̄, winds (a critical point of h̄; only where h̄ has a direction at every corner).
fn near_critical_points(ctx: &Context, theta: &[f64], faces: &[usize]) -> HashSet<u32> {
    let mesh = ctx.mesh;
    let critical = faces.iter().copied().filter(|&f| {
        mesh.faces[f].iter().all(|&v| theta[v as usize].is_finite())
            && face_index(mesh, ctx.geom, theta, f, 1) != 0
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
