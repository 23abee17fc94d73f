//! A start for the position energy that takes the same branch on neighbouring vertices.
//!
//! A position row (math.md §9) asks ĝᵢ = h̄ᵢᵀūᵢ/|h̄ᵢ| = ĝ*ᵢ, which two grain angles satisfy,
//! mirror images about h̄ᵢ:
//!
//! ```text
//! φᵢ± = θᵢ ± arccos ĝ*ᵢ,      θᵢ = atan2(h̄ᵢ)
//! ```
//!
//! Both give the same g = hᵀu at the vertex, so the rows alone cannot choose. Where the field
//! before the edit has u ∥ h̄ (ĝ ≈ ±1, away from the highlight: the common case inside a brush)
//! the two are equally near the start, and Levenberg–Marquardt, whose position rows are
//! independent, sends neighbouring vertices down different branches. For a line field
//! (k = 2) that is worse than a kink: neighbours on mirrored branches have grains more than a
//! right angle apart, the corners of a triangle then align with the opposite orientation, their
//! g changes sign and the highlight lands where the branches meet instead of where ĝ* puts it
//! (on the corpus of docs/benchmarks.md a third to a half of a drawn curve got no highlight).
//!
//! [`coherent_start`] chooses one branch per vertex so that neighbours agree: vertices without a
//! position row (fixed, or free without a target) keep their angle and are *decided*; the
//! undecided vertex whose choice is clearest goes next — the one whose two branches differ most
//! in their agreement with its decided neighbours (Σⱼ sᵢⱼ cos(φ − φⱼ − ρᵢⱼ), ρ the transport,
//! sᵢⱼ = ±1 the relative orientation of the two grains at the start for a line field: the
//! targets' signs are stated in those orientations; 1 for a vector field),
//! plus a small preference for the branch nearer its own start — and the rest follow, region
//! growing from the outside of the brush inwards. Each chosen angle is the representative nearest
//! the vertex's start (mod 2π), so that a line field's orientation, in which ĝ*ᵢ is stated, is
//! kept. The result satisfies every position row exactly; the optimizer tries it first
//! ([`super::optimize()`]).

use std::cmp::Ordering;
use std::collections::BinaryHeap;

use super::highlight_term::HighlightTerm;
use super::position_term::TARGET_BOUND;

/// Weight of a vertex's preference for the branch nearer its own start, relative to one
/// decided neighbour.
const SELF_PREFERENCE: f64 = 0.25;

/// |h̄| below which a vertex keeps its angle (a critical point: every grain puts the highlight
/// through it).
const MIN_TANGENT_H: f64 = 1e-6;

/// One undecided vertex in the queue: its margin when it was pushed.
#[derive(Clone, Copy, Debug)]
struct Entry {
    margin: f64,
    vertex: u32,
    stamp: u32,
}

impl PartialEq for Entry {
    fn eq(&self, other: &Self) -> bool {
        self.cmp(other) == Ordering::Equal
    }
}
impl Eq for Entry {}
impl PartialOrd for Entry {
    fn partial_cmp(&self, other: &Self) -> Option<Ordering> {
        Some(self.cmp(other))
    }
}
impl Ord for Entry {
    /// Larger margin first; among equal margins the lower vertex (deterministic).
    fn cmp(&self, other: &Self) -> Ordering {
        self.margin.total_cmp(&other.margin).then_with(|| other.vertex.cmp(&self.vertex))
    }
}

/// The nearest representative of `a` (mod 2π) to `near`.
fn nearest_turn(a: f64, near: f64) -> f64 {
    let tau = std::f64::consts::TAU;
    let m = ((near - a) / tau).round();
    if m.is_finite() {
        a + m * tau
    } else {
        a
    }
}

/// The branch-coherent start for the position rows of `term` on the `free` vertices, from
/// `phi`; `None` when no free vertex has a position row.
pub fn coherent_start(term: &HighlightTerm, phi: &[f64], free: &[u32]) -> Option<Vec<f64>> {
    let g = term.geometry;
    let n = phi.len();
    let line = term.symmetry.k() == 2;
    // The two candidates of every free vertex with a position row.
    let mut cand: Vec<Option<[f64; 2]>> = vec![None; n];
    let mut any = false;
    for &v in free {
        let i = v as usize;
        let Some(t) = term.target_g[i] else { continue };
        if term.weight[i].is_nan() || term.weight[i] <= 0.0 {
            continue;
        }
        let hb = term.h_bar(i);
        if hb.norm().is_nan() || hb.norm() <= MIN_TANGENT_H || !t.is_finite() {
            continue;
        }
        let theta = hb.y.atan2(hb.x);
        let a = t.clamp(-TARGET_BOUND, TARGET_BOUND).acos();
        cand[i] = Some([nearest_turn(theta + a, phi[i]), nearest_turn(theta - a, phi[i])]);
        any = true;
    }
    if !any {
        return None;
    }
    let mut out = phi.to_vec();
    let mut decided: Vec<bool> = cand.iter().map(|c| c.is_none()).collect();
    // Agreement of each candidate of vertex i with its decided neighbours and its own start.
    let score = |i: usize, out: &[f64], decided: &[bool]| -> [f64; 2] {
        let c = cand[i].expect("undecided vertices have candidates");
        let mut s = [0.0; 2];
        for slot in g.adjacency.slots(i) {
            let j = g.adjacency.target(slot);
            if !decided[j] {
                continue;
            }
            // Agreement of the representatives, in the relative orientation the two had at the
            // start (line fields): the targets' signs were stated in those orientations.
            let pj = out[j] + g.transport[slot];
            // Weighted by how clear that orientation was: cos of the start angle between them
            // (near a right angle, the start says nothing about it).
            let rel = if line { (phi[i] - phi[j] - g.transport[slot]).cos() } else { 1.0 };
            for (b, sb) in s.iter_mut().enumerate() {
                *sb += rel * (c[b] - pj).cos();
            }
        }
        for (b, sb) in s.iter_mut().enumerate() {
            *sb += SELF_PREFERENCE * (c[b] - phi[i]).cos();
        }
        s
    };
    let mut stamp = vec![0u32; n];
    let mut heap = BinaryHeap::new();
    for i in 0..n {
        if !decided[i] {
            let s = score(i, &out, &decided);
            heap.push(Entry { margin: (s[0] - s[1]).abs(), vertex: i as u32, stamp: 0 });
        }
    }
    while let Some(e) = heap.pop() {
        let i = e.vertex as usize;
        if decided[i] || e.stamp != stamp[i] {
            continue;
        }
        let s = score(i, &out, &decided);
        let c = cand[i].expect("undecided vertices have candidates");
        out[i] = if s[1] > s[0] { c[1] } else { c[0] };
        decided[i] = true;
        for slot in g.adjacency.slots(i) {
            let j = g.adjacency.target(slot);
            if decided[j] {
                continue;
            }
            stamp[j] += 1;
            let sj = score(j, &out, &decided);
            heap.push(Entry { margin: (sj[0] - sj[1]).abs(), vertex: j as u32, stamp: stamp[j] });
        }
    }
    Some(out)
}
