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
//! [`coherent_start`] chooses one branch per vertex so that neighbours agree. Vertices without a
//! position row (fixed, or free without a target), and those whose angle meets their row already
//! (the grain a tool designed, untangled where it tangled: `edit::untangle`; on the deep-folded
//! sculpt of docs/benchmarks.md re-choosing their branches added up to 12 singular triangles), keep
//! their angle and are *decided*. Every edge
//! says which relative choice of its two vertices agrees better — the agreement of two grains
//! being sᵢⱼ cos(φᵢ − φⱼ − ρᵢⱼ), ρ the transport, sᵢⱼ = ±1 the relative orientation of the two
//! grains at the start for a line field (the targets' signs are stated in those orientations;
//! 1 for a vector field) — and how clearly (the difference between the two relations); an edge
//! to a decided vertex says which branch, and so does a small preference for the branch nearer
//! the vertex's own start. The links are taken from the clearest down and kept when they join
//! two groups (Kruskal's algorithm on a 2-colouring): clear links — where both vertices' branches
//! are far apart, near the highlight the edit asks for — decide first, and the disagreements that
//! no consistent choice avoids fall on the links where the two branches nearly coincide
//! (|ĝ*| → 1, u ∥ h̄) and choosing either costs little. (It replaced a greedy growth from the
//! decided vertices inwards, which let the rim of a brush decide before the highlight the edit
//! asks for; on the corpus of docs/benchmarks.md the figures are the same but for one curve with
//! a singular triangle fewer.) Each chosen angle is the representative nearest the vertex's
//! start (mod 2π), so that a line field's orientation, in which ĝ*ᵢ is stated, is kept. The
//! result satisfies every position row exactly; the optimizer tries it first
//! ([`super::optimize()`]).

use super::highlight_term::HighlightTerm;
use super::position_term::TARGET_BOUND;

/// Weight of a vertex's preference for the branch nearer its own start, relative to one
/// decided neighbour.
const SELF_PREFERENCE: f64 = 0.25;

/// |ĝ − ĝ*| within which a vertex's angle meets its row: it keeps its angle (the design's).
const MET_ROW: f64 = 1e-9;

/// |h̄| below which a vertex keeps its angle (a critical point: every grain puts the highlight
/// through it).
const MIN_TANGENT_H: f64 = 1e-6;

/// A constraint between two labels (or a label and the ground): which relation it prefers and
/// how clearly.
#[derive(Clone, Copy, Debug)]
struct Link {
    confidence: f64,
    a: u32,
    /// `GROUND` for a constraint on `a` alone.
    b: u32,
    /// The preferred relation: labels equal (false) or different (true); against the ground,
    /// the preferred label of `a`.
    parity: bool,
}

/// The node standing for the decided vertices (label 0 by definition).
const GROUND: u32 = u32::MAX;

/// Disjoint sets with the parity of every element relative to its root (a 2-colouring kept
/// under union); the ground is element `n`.
struct ParitySets {
    parent: Vec<u32>,
    /// Parity of the element relative to its parent.
    parity: Vec<bool>,
}

impl ParitySets {
    fn new(n: usize) -> Self {
        ParitySets { parent: (0..=n as u32).collect(), parity: vec![false; n + 1] }
    }

    /// The root of `x` and the parity of `x` relative to it; every element on the way is
    /// pointed at the root (path compression).
    fn find(&mut self, x: u32) -> (u32, bool) {
        let (mut r, mut p) = (x, false);
        while self.parent[r as usize] != r {
            p ^= self.parity[r as usize];
            r = self.parent[r as usize];
        }
        let (mut y, mut py) = (x, p);
        while self.parent[y as usize] != y {
            let (next, next_p) = (self.parent[y as usize], py ^ self.parity[y as usize]);
            self.parent[y as usize] = r;
            self.parity[y as usize] = py;
            (y, py) = (next, next_p);
        }
        (r, p)
    }

    /// Joins the sets of `a` and `b` so that parity(a) ⊕ parity(b) = `rel`; false when they
    /// were one set already (the link is then left out). The ground stays a root.
    fn union(&mut self, a: u32, b: u32, rel: bool, ground: u32) -> bool {
        let (ra, pa) = self.find(a);
        let (rb, pb) = self.find(b);
        if ra == rb {
            return false;
        }
        let (child, root) =
            if rb == ground || (ra != ground && rb < ra) { (ra, rb) } else { (rb, ra) };
        self.parent[child as usize] = root;
        self.parity[child as usize] = pa ^ pb ^ rel;
        true
    }
}

/// One branch per vertex with candidates (0 or 1), the links between neighbours taken from the
/// clearest down (Kruskal with parities): a link joins two groups of vertices whose relative
/// choices are made, or a group to the decided vertices, which fixes the group's choice. Clear
/// links (the two branches of both vertices far apart) are kept, and the disagreements that no
/// consistent choice avoids fall on the unclear ones, where the two branches nearly coincide
/// and choosing either costs little.
fn choose_branches(
    term: &HighlightTerm,
    phi: &[f64],
    cand: &[(u32, [f64; 2])],
    line: bool,
) -> Vec<bool> {
    let g = term.geometry;
    // The candidates of vertex j, if it has some (`cand` is by increasing vertex).
    let of = |j: usize| cand.binary_search_by_key(&(j as u32), |c| c.0).ok();
    let mut links = Vec::new();
    for &(i, ref ci) in cand {
        let i = i as usize;
        // A small preference for the branch nearer the vertex's own start.
        let own =
            [SELF_PREFERENCE * (ci[0] - phi[i]).cos(), SELF_PREFERENCE * (ci[1] - phi[i]).cos()];
        links.push(Link {
            confidence: (own[0] - own[1]).abs(),
            a: i as u32,
            b: GROUND,
            parity: own[1] > own[0],
        });
        for slot in g.adjacency.slots(i) {
            let j = g.adjacency.target(slot);
            let rho = g.transport[slot];
            // The targets' signs were stated in the orientations of the start: weighted by how
            // clear the relative orientation of the two grains was there (line fields).
            let rel = if line { (phi[i] - phi[j] - rho).cos() } else { 1.0 };
            match of(j).map(|k| &cand[k].1) {
                None => {
                    let pj = phi[j] + rho;
                    let s = [rel * (ci[0] - pj).cos(), rel * (ci[1] - pj).cos()];
                    links.push(Link {
                        confidence: (s[0] - s[1]).abs(),
                        a: i as u32,
                        b: GROUND,
                        parity: s[1] > s[0],
                    });
                }
                Some(cj) if j > i => {
                    let agree = |a: usize, b: usize| rel * (ci[a] - cj[b] - rho).cos();
                    let same = 0.5 * (agree(0, 0) + agree(1, 1));
                    let differ = 0.5 * (agree(0, 1) + agree(1, 0));
                    links.push(Link {
                        confidence: (same - differ).abs(),
                        a: i as u32,
                        b: j as u32,
                        parity: differ > same,
                    });
                }
                Some(_) => {}
            }
        }
    }
    // Clearest first; ties by the vertices (deterministic). A link that says nothing (or NaN,
    // from a degenerate vertex) is left out.
    links.retain(|l| l.confidence > 0.0);
    links.sort_by(|x, y| {
        y.confidence.total_cmp(&x.confidence).then(x.a.cmp(&y.a)).then(x.b.cmp(&y.b))
    });
    // The sets hold the candidates' vertices, numbered in their order (the union's choice of
    // root compares numbers, and this numbering keeps their order), and the ground last.
    let m = cand.len();
    let ground = m as u32;
    let local = |v: u32| of(v as usize).expect("a link joins candidates") as u32;
    let mut sets = ParitySets::new(m);
    for l in &links {
        let b = if l.b == GROUND { ground } else { local(l.b) };
        sets.union(local(l.a), b, l.parity, ground);
    }
    (0..m as u32)
        // A group never linked to the decided vertices gives its root branch 0.
        .map(|i| sets.find(i).1)
        .collect()
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
    let line = term.symmetry.k() == 2;
    // The two candidates of every free vertex with a position row, by increasing vertex.
    let mut cand: Vec<(u32, [f64; 2])> = Vec::new();
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
        // A vertex whose angle meets its row already (a tool designed it, untangled where it
        // tangled: edit::untangle) is decided: its branch is the design's.
        let (sn, cs) = phi[i].sin_cos();
        let g = (cs * hb.x + sn * hb.y) / hb.norm();
        if (g - t.clamp(-TARGET_BOUND, TARGET_BOUND)).abs() <= MET_ROW {
            continue;
        }
        let a = t.clamp(-TARGET_BOUND, TARGET_BOUND).acos();
        cand.push((v, [nearest_turn(theta + a, phi[i]), nearest_turn(theta - a, phi[i])]));
    }
    if cand.is_empty() {
        return None;
    }
    cand.sort_by_key(|c| c.0);
    cand.dedup_by_key(|c| c.0);
    let mut out = phi.to_vec();
    let choice = choose_branches(term, phi, &cand, line);
    for (&(i, c), choose) in cand.iter().zip(choice) {
        out[i as usize] = c[usize::from(choose)];
    }
    Some(out)
}

#[cfg(test)]
mod tests {
    use super::ParitySets;

    /// Unions with parities keep a consistent 2-colouring; a link inside one set is refused;
    /// the ground (element n) stays a root.
    #[test]
    fn parity_sets_keep_a_two_colouring() {
        let n = 5;
        let ground = n as u32;
        let mut s = ParitySets::new(n);
        assert!(s.union(0, 1, true, ground));
        assert!(s.union(1, 2, true, ground));
        assert!(s.union(3, 4, false, ground));
        assert!(!s.union(0, 2, true, ground), "0 and 2 are one set already");
        assert!(s.union(4, ground, true, ground));
        assert!(s.union(2, 3, false, ground));
        let label = |s: &mut ParitySets, x: u32| s.find(x);
        for x in 0..n as u32 {
            assert_eq!(label(&mut s, x).0, ground, "{x} reaches the ground");
        }
        let l: Vec<bool> = (0..n as u32).map(|x| label(&mut s, x).1).collect();
        // 4 is 1 (against the ground), 3 = 4, 2 = 3, 1 ≠ 2, 0 ≠ 1.
        assert_eq!(l, vec![true, false, true, true, true]);
    }
}
