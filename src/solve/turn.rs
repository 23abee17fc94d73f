//! Bounded turns: rotating a regular field towards a target without adding a singularity
//! (docs/math.md §10, "Untangling").
//!
//! A rotation field Δ (the angle by which each vertex's grain turns; a number, not a direction,
//! so no transport between vertices) applied to a field φ gives φ + Δ. Read mod 2π/k, as a
//! target rotation is, Δ may wind around a face and add a singularity there. A *real* Δ cannot:
//! with dᵢⱼ = wrap_k(φⱼ + ρᵢⱼ − φᵢ) the turn of φ along the edge ij, the index of a face
//! (k · Σ wrap_k(dᵢⱼ + Δⱼ − Δᵢ) over its edges, less the holonomy, over 2π) equals φ's whenever
//! no edge wraps, |dᵢⱼ + Δⱼ − Δᵢ| < π/k, because Σ (Δⱼ − Δᵢ) around a face is 0. So
//!
//! ```text
//! min Σ_free wᵢ (Δᵢ − Tᵢ)² + Σ_edges λᵢⱼ (Δⱼ − Δᵢ + dᵢⱼ)²   with   |Δⱼ − Δᵢ + dᵢⱼ| ≤ β < π/k,
//! ```
//!
//! over the free vertices (the others keep their lifted target), has every face of the region
//! as singular as φ was. Tᵢ is the target rotation's representative (mod 2π/k) nearest the
//! current Δᵢ; the bound is met by reweighting: each round solves the sparse positive definite
//! system of the quadratic and multiplies λ on the edges over the bound by [`GROWTH`], until
//! none is (at most [`ROUNDS`] rounds). The work is in proportion to the free vertices and
//! their rim, whatever the mesh's size.
//!
//! The target is first lifted to real numbers: breadth first from a vertex of the rim (the
//! fixed vertices), along the rim's own edges before any other, each vertex taking the
//! representative nearest its parent's; the rim's lift must close (a rim around a net winding
//! of the target is refused).

use std::collections::HashMap;

use faer::prelude::*;
use faer::sparse::{SparseColMat, Triplet};

use crate::geometry::connection::wrap_angle;
use crate::geometry::Geometry;

/// Rounds of reweighting at most.
pub const ROUNDS: usize = 30;

/// Rounds whose targets are chosen again (the representative nearest the current rotation).
pub const RELIFT_ROUNDS: usize = 4;

/// Factor by which λ grows on an edge over the bound, per round.
pub const GROWTH: f64 = 4.0;

/// λ an edge over the bound gets at least (against targets of weight about 1).
pub const MIN_LAMBDA: f64 = 1e-3;

/// What a bounded turn needs beyond the geometry.
pub struct TurnInput<'a> {
    /// The field turned (angles in the vertices' frames, one per vertex), regular on the region.
    pub phi: &'a [f64],
    /// The rotation wanted, one per vertex, read mod 2π/k.
    pub target: &'a [f64],
    /// The vertices solved for (unique); their neighbours not among them, the *rim*, are held
    /// at their lifted target.
    pub free: &'a [u32],
    /// The weight (≥ 0) of each free vertex's target, in the order of `free`.
    pub weight: &'a [f64],
    /// The field's symmetry (1: vectors, 2: lines).
    pub k: u32,
}

/// How a bounded turn is computed.
#[derive(Clone, Copy, Debug)]
pub struct TurnOptions {
    /// β / (π/k): the largest turn of the result along an edge, as a share of a wrap (< 1).
    pub bound: f64,
    /// λ at the start, on every edge: how much the result's smoothness counts against the
    /// targets (0 leaves it to the bound).
    pub smoothness: f64,
}

/// The free vertices and their rim, numbered locally (free first), with the edges that touch a
/// free vertex: work in proportion to the region, not the mesh.
struct Region {
    /// Global vertex of each local one: the free vertices (in the input's order), then the rim.
    verts: Vec<usize>,
    /// Local number of each global vertex of the region.
    local: HashMap<usize, usize>,
    /// Free vertices.
    n: usize,
    /// Each edge with a free end once: (free end, other end, the field's turn d from the first
    /// to the second).
    edges: Vec<(usize, usize, f64)>,
}

impl Region {
    fn new(geometry: &Geometry, input: &TurnInput) -> Region {
        let adj = &geometry.adjacency;
        let kf = input.k as f64;
        let n = input.free.len();
        let mut verts: Vec<usize> = input.free.iter().map(|&v| v as usize).collect();
        let mut local: HashMap<usize, usize> = HashMap::with_capacity(2 * n);
        for (c, &v) in verts.iter().enumerate() {
            local.insert(v, c);
        }
        let mut edges = Vec::with_capacity(4 * n);
        for c in 0..n {
            let i = verts[c];
            for s in adj.slots(i) {
                let j = adj.target(s);
                let b = *local.entry(j).or_insert_with(|| {
                    verts.push(j);
                    verts.len() - 1
                });
                if b >= n || c < b {
                    let turn = input.phi[j] + geometry.transport[s] - input.phi[i];
                    edges.push((c, b, wrap_angle(kf * turn) / kf));
                }
            }
        }
        Region { verts, local, n, edges }
    }
}

/// The real rotation Δ of each free vertex (in the order of `input.free`), or `None` when the
/// rim's lift does not close, a system fails or the bound is not met.
pub fn bounded_turn(
    geometry: &Geometry,
    input: &TurnInput,
    options: &TurnOptions,
) -> Option<Vec<f64>> {
    if input.free.is_empty() {
        return Some(Vec::new());
    }
    let period = std::f64::consts::TAU / input.k as f64;
    let beta = options.bound * period / 2.0;
    let region = Region::new(geometry, input);
    let n = region.n;
    let target = |l: usize| input.target[region.verts[l]];
    let mut delta = lift(geometry, &region, &target, period)?;
    let mut lambda = vec![options.smoothness; region.edges.len()];
    let mut t: Vec<f64> = Vec::new();
    for round in 0..ROUNDS {
        // The first rounds' targets: the representative nearest the current rotation; then
        // they stay, so that the reweighting converges.
        if round < RELIFT_ROUNDS {
            t = (0..n).map(|c| nearest(target(c), delta[c], period)).collect();
        }
        let solved = solve_round(&region, input.weight, &delta, &t, &lambda)?;
        delta[..n].copy_from_slice(&solved);
        let mut over = false;
        for (e, &(a, b, d)) in region.edges.iter().enumerate() {
            if (delta[b] - delta[a] + d).abs() > beta {
                over = true;
                lambda[e] = (lambda[e] * GROWTH).max(MIN_LAMBDA);
            }
        }
        if !over {
            delta.truncate(n);
            return delta.iter().all(|d| d.is_finite()).then_some(delta);
        }
    }
    None
}

/// The representative of `a` (mod `period`) nearest `to`.
fn nearest(a: f64, to: f64, period: f64) -> f64 {
    a + period * ((to - a) / period).round()
}

/// The target lifted to real numbers over the region, by local vertex (see the module docs);
/// `None` when the rim's lift does not close.
fn lift(
    geometry: &Geometry,
    region: &Region,
    target: &impl Fn(usize) -> f64,
    period: f64,
) -> Option<Vec<f64>> {
    let adj = &geometry.adjacency;
    let (n, all) = (region.n, region.verts.len());
    let neighbours = |l: usize| {
        adj.neighbors(region.verts[l])
            .iter()
            .filter_map(|&w| region.local.get(&(w as usize)).copied())
    };
    let mut delta: Vec<f64> = (0..all).map(|l| nearest(target(l), 0.0, period)).collect();
    let mut seen = vec![false; all];
    // Breadth first from the first rim vertex, along the rim's own edges before any other (a
    // rim met from inside, as a hole's, is then lifted along itself too).
    let mut queue = std::collections::VecDeque::with_capacity(all);
    for start in n..all {
        if seen[start] {
            continue;
        }
        seen[start] = true;
        queue.push_back(start);
        while let Some(v) = queue.pop_front() {
            for w in neighbours(v) {
                if !seen[w] {
                    seen[w] = true;
                    delta[w] = nearest(target(w), delta[v], period);
                    if v >= n && w >= n {
                        queue.push_front(w);
                    } else {
                        queue.push_back(w);
                    }
                }
            }
        }
    }
    // The rim's lift closes: no rim edge jumps by half a period or more.
    let closes = (n..all)
        .all(|v| neighbours(v).all(|w| w < n || (delta[w] - delta[v]).abs() < period / 2.0));
    (closes && seen.iter().all(|&s| s)).then_some(delta)
}

/// One round's quadratic, solved for the free vertices: rows wᵢ (Δᵢ − tᵢ) and
/// λₑ (Δ_b − Δ_a + dₑ), the rim's Δ held.
fn solve_round(
    region: &Region,
    weight: &[f64],
    delta: &[f64],
    t: &[f64],
    lambda: &[f64],
) -> Option<Vec<f64>> {
    let n = region.n;
    let mut diag: Vec<f64> = (0..n).map(|c| weight[c].max(0.0)).collect();
    let mut rhs = Mat::<f64>::zeros(n, 1);
    for c in 0..n {
        rhs[(c, 0)] = diag[c] * t[c];
    }
    let mut triplets = Vec::with_capacity(2 * region.edges.len() + n);
    for (&(a, b, d), &l) in region.edges.iter().zip(lambda) {
        if l.is_nan() || l <= 0.0 {
            continue;
        }
        diag[a] += l;
        rhs[(a, 0)] += l * d;
        if b < n {
            diag[b] += l;
            rhs[(b, 0)] -= l * d;
            triplets.push(Triplet::new(a, b, -l));
            triplets.push(Triplet::new(b, a, -l));
        } else {
            rhs[(a, 0)] += l * delta[b];
        }
    }
    for (c, d) in diag.iter().enumerate() {
        triplets.push(Triplet::new(c, c, d.max(1e-12)));
    }
    let a = SparseColMat::<usize, f64>::try_new_from_triplets(n, n, &triplets).ok()?;
    let llt = crate::factor::Factor::new(a.as_ref(), "bounded turn").ok()?;
    llt.solve_in_place(rhs.as_mut());
    let out: Vec<f64> = (0..n).map(|c| rhs[(c, 0)]).collect();
    out.iter().all(|x| x.is_finite()).then_some(out)
}
