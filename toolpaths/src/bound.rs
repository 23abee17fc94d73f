//! Lower bounds on the travel of any order of strokes whose orientation is fixed (what vpype
//! calls `linesort --no-flip`), to judge how far an order is from the best possible.
//!
//! **Model.** A tour visits strokes `s_1 … s_n`; its travel between strokes is
//! `Σ_{k<n} c(s_k, s_{k+1})` with `c(a, b)` the distance from the exit of `a` to the entry
//! of `b` (for a closed loop, the nearest pair of its vertices: a loop exits where it
//! enters, so the true cost of a tour can only be larger). With a home position `h` the
//! travel also has the leg `d(h, entry(s_1))`.
//!
//! **Assignment bound (proof).** Add a row `H` (home) and a column `Z` (end of the path).
//! Map the tour to the assignment `H → s_1`, `s_k → s_{k+1}`, `s_n → Z`: every row and every
//! column is used exactly once (a path is an assignment minus one edge, closed through
//! `H`/`Z`). With costs `c(H, b) = d(h, entry(b))` (0 without a home), `c(a, Z) = 0`,
//! `c(a, a)` and `c(H, Z)` forbidden, the assignment costs at most the tour's travel. So
//! the minimum-cost assignment is ≤ the travel of *every* tour. By weak LP duality any
//! `u, v` with `u_r + v_c ≤ c(r, c)` for all allowed pairs has `Σu + Σv ≤` that minimum, so
//! `Σu + Σv` is a valid bound however `u, v` were found. We find them with shortest
//! augmenting paths (Dijkstra with potentials) on k-nearest candidate lists, then make the
//! dual feasible for *all* pairs: `u_r ← min_c (c(r, c) − v_c)` over every column, using a
//! radius search that cannot miss a smaller value (columns are only ever lowered, so
//! `v ≤ 0` and a column can beat the current `u_r` only if `c(r, c) < u_r`).
//!
//! **Nearest bound.** The weaker `Σ_a min_{b≠a} c(a, b) − max_a min_{b≠a} c(a, b)`
//! (+ `min_b c(H, b)`): every stroke but the last is followed by some other stroke. It is the
//! dual solution `u_a = min_b c(a, b)`, `v_Z = −max`, so the exact assignment bound (complete
//! lists) is never lower.

use std::cmp::Reverse;
use std::collections::BinaryHeap;

use crate::buckets::Buckets;
use crate::geom::Vec2;
use crate::tour::{cell_size, d, Ends};

/// Lower bounds on travel for strokes in fixed orientation (see the module docs).
#[derive(Clone, Debug, PartialEq)]
pub struct TravelBound {
    /// `Σ` of each stroke's nearest-other-entry distance minus the largest one (plus the
    /// nearest entry to home when a home is given), mm.
    pub nearest: f64,
    /// The assignment bound `Σu + Σv`, mm; `None` when the candidate lists admit no perfect
    /// assignment (then only `nearest` is available).
    pub assignment: Option<f64>,
    /// Cost of the assignment found on the candidate lists (an upper bound on the exact
    /// minimum assignment; equal to it when no pair outside the lists is cheaper), mm.
    pub assignment_primal: Option<f64>,
}

/// Options of [`travel_bound`].
#[derive(Clone, Debug, PartialEq)]
pub struct BoundOptions {
    /// Include the leg from this home to the first stroke; `None` bounds the travel between
    /// strokes only (vpype's pen-up length). Default `None`.
    pub home: Option<Vec2>,
    /// Candidate columns per row for the augmenting-path search (the bound stays valid for
    /// any value; more candidates make it tighter). Default 12.
    pub neighbours: usize,
}

impl Default for BoundOptions {
    fn default() -> Self {
        BoundOptions { home: None, neighbours: 12 }
    }
}

/// Exit candidates of a stroke (a loop's vertices, else its end).
fn exits(e: &Ends) -> &[Vec2] {
    if e.ring.is_empty() {
        std::slice::from_ref(&e.end)
    } else {
        &e.ring
    }
}

/// Entry candidates of a stroke (a loop's vertices, else its start).
fn entries(e: &Ends) -> &[Vec2] {
    if e.ring.is_empty() {
        std::slice::from_ref(&e.start)
    } else {
        &e.ring
    }
}

/// Lower bounds on the travel of any ordering of `ends` in their given orientation.
pub fn travel_bound(ends: &[Ends], opts: &BoundOptions) -> TravelBound {
    let n = ends.len();
    if n == 0 || (n < 2 && opts.home.is_none()) {
        return TravelBound { nearest: 0.0, assignment: Some(0.0), assignment_primal: Some(0.0) };
    }
    // Entry points of all strokes, item → stroke.
    let mut owner = Vec::new();
    let mut pts = Vec::new();
    for (s, e) in ends.iter().enumerate() {
        for p in entries(e) {
            owner.push(s as u32);
            pts.push(*p);
        }
    }
    let cell = cell_size(&pts, n);
    let grid = Buckets::new(pts, cell);
    let home_cost = |c: usize| opts.home.map_or(0.0, |h| dist_to(h, entries(&ends[c])));
    // Candidate lists grow (×4) while no perfect assignment exists on them or the dual
    // lost more than 1 % to pairs outside them; at k ≥ n − 1 they are complete.
    let mut k = opts.neighbours.max(1);
    loop {
        let (rows, nearest) = candidates(ends, &grid, &owner, k, &home_cost, opts.home.is_some());
        let complete = k + 1 >= n;
        let Some((v, col_of_row)) = assign(&rows, n + 1) else {
            if complete {
                return TravelBound { nearest, assignment: None, assignment_primal: None };
            }
            k = (4 * k).min(n);
            continue;
        };
        let primal: f64 = (0..=n)
            .map(|r| rows[r].iter().find(|e| e.0 == col_of_row[r]).map_or(0.0, |e| e.1))
            .sum();
        let dual = repaired_dual(ends, &grid, &owner, &rows, &v, &col_of_row, &home_cost);
        if complete || primal - dual <= 1e-2 * primal {
            return TravelBound {
                nearest,
                assignment: Some(dual),
                assignment_primal: Some(primal),
            };
        }
        k = (4 * k).min(n);
    }
}

/// `Σu + Σv` with `u_r = min_c (c(r, c) − v_c)` over *every* allowed column (module docs).
fn repaired_dual(
    ends: &[Ends],
    grid: &Buckets,
    owner: &[u32],
    rows: &[Vec<(usize, f64)>],
    v: &[f64],
    col_of_row: &[usize],
    home_cost: &dyn Fn(usize) -> f64,
) -> f64 {
    let n = ends.len();
    let z = n; // column Z and row H share index n
    let vmax = v[..n].iter().cloned().fold(f64::NEG_INFINITY, f64::max);
    let mut u_sum = 0.0;
    for (r, e) in ends.iter().enumerate() {
        let matched = rows[r].iter().find(|x| x.0 == col_of_row[r]).map_or(0.0, |x| x.1);
        let mut u = (matched - v[col_of_row[r]]).min(0.0 - v[z]);
        let radius = u + vmax;
        for &x in exits(e) {
            grid.within(x, radius, |id, dd| {
                let c = owner[id as usize] as usize;
                if c != r {
                    u = u.min(dd - v[c]);
                }
            });
        }
        u_sum += u;
    }
    // Row H: every column but Z.
    u_sum += (0..n).map(|c| home_cost(c) - v[c]).fold(f64::INFINITY, f64::min);
    u_sum + v.iter().sum::<f64>()
}

/// Rows of candidate (column, cost) pairs: each stroke's `k` nearest other strokes by
/// exit-to-entry distance plus column Z, and row H with every stroke; and the nearest bound.
fn candidates(
    ends: &[Ends],
    grid: &Buckets,
    owner: &[u32],
    k: usize,
    home_cost: &dyn Fn(usize) -> f64,
    with_home: bool,
) -> (Vec<Vec<(usize, f64)>>, f64) {
    let n = ends.len();
    let z = n;
    let mut rows: Vec<Vec<(usize, f64)>> = Vec::with_capacity(n + 1);
    let mut nearest_terms = Vec::with_capacity(n);
    for (s, e) in ends.iter().enumerate() {
        let mut best: Vec<(f64, u32)> = Vec::new();
        for &x in exits(e) {
            let key = |id: u32| (owner[id as usize] as usize != s).then_some(owner[id as usize]);
            for (dd, c) in grid.k_nearest(x, k, key) {
                match best.iter_mut().find(|b| b.1 == c) {
                    Some(b) => b.0 = b.0.min(dd),
                    None => best.push((dd, c)),
                }
            }
        }
        best.sort_by(|a, b| a.0.total_cmp(&b.0).then(a.1.cmp(&b.1)));
        best.truncate(k);
        nearest_terms.push(best.first().map_or(0.0, |b| b.0));
        let mut row: Vec<(usize, f64)> = best.iter().map(|&(dd, c)| (c as usize, dd)).collect();
        row.push((z, 0.0));
        rows.push(row);
    }
    rows.push((0..n).map(|c| (c, home_cost(c))).collect());
    let largest = nearest_terms.iter().cloned().fold(0.0, f64::max);
    let mut nearest = nearest_terms.iter().sum::<f64>() - largest;
    if with_home {
        nearest += (0..n).map(home_cost).fold(f64::INFINITY, f64::min);
    }
    (rows, nearest)
}

fn dist_to(p: Vec2, set: &[Vec2]) -> f64 {
    set.iter().map(|q| d(p, *q)).fold(f64::INFINITY, f64::min)
}

/// Min-cost perfect assignment of `m` rows to `m` columns on the sparse `rows` (shortest
/// augmenting paths, Dijkstra on reduced costs). Returns the column potentials `v` (row
/// potentials are `c(r, col(r)) − v_col(r)`) and each row's column; `None` when some row
/// cannot be augmented within the lists.
fn assign(rows: &[Vec<(usize, f64)>], m: usize) -> Option<(Vec<f64>, Vec<usize>)> {
    const FREE: usize = usize::MAX;
    let mut v = vec![0.0; m];
    let mut row_of_col = vec![FREE; m];
    let mut col_of_row = vec![FREE; m];
    let mut dist = vec![f64::INFINITY; m];
    let mut pred = vec![FREE; m];
    let mut done = vec![false; m];
    let mut scanned: Vec<usize> = Vec::new();
    let mut touched: Vec<usize> = Vec::new();
    let u_of = |r: usize, col_of_row: &[usize], v: &[f64]| {
        let c = col_of_row[r];
        rows[r].iter().find(|e| e.0 == c).map_or(0.0, |e| e.1) - v[c]
    };
    for r0 in 0..m {
        let mut heap: BinaryHeap<Reverse<(Key, usize)>> = BinaryHeap::new();
        for &(c, w) in &rows[r0] {
            let nd = w - v[c];
            if nd < dist[c] {
                dist[c] = nd;
                pred[c] = r0;
                touched.push(c);
                heap.push(Reverse((Key(nd), c)));
            }
        }
        let mut sink = FREE;
        while let Some(Reverse((Key(dc), c))) = heap.pop() {
            if done[c] || dc > dist[c] {
                continue;
            }
            done[c] = true;
            scanned.push(c);
            let i = row_of_col[c];
            if i == FREE {
                sink = c;
                break;
            }
            let ui = u_of(i, &col_of_row, &v);
            for &(c2, w) in &rows[i] {
                if done[c2] {
                    continue;
                }
                let nd = dc + (w - v[c2] - ui);
                if nd < dist[c2] {
                    dist[c2] = nd;
                    pred[c2] = i;
                    touched.push(c2);
                    heap.push(Reverse((Key(nd), c2)));
                }
            }
        }
        if sink == FREE {
            return None;
        }
        let ds = dist[sink];
        for &c in &scanned {
            v[c] += dist[c] - ds;
        }
        let mut c = sink;
        loop {
            let i = pred[c];
            let next = col_of_row[i];
            row_of_col[c] = i;
            col_of_row[i] = c;
            if i == r0 {
                break;
            }
            c = next;
        }
        for &c in &touched {
            dist[c] = f64::INFINITY;
            pred[c] = FREE;
            done[c] = false;
        }
        scanned.clear();
        touched.clear();
    }
    Some((v, col_of_row))
}

/// A total order on finite distances for the heap.
#[derive(Clone, Copy, PartialEq)]
struct Key(f64);
impl Eq for Key {}
impl PartialOrd for Key {
    fn partial_cmp(&self, o: &Self) -> Option<std::cmp::Ordering> {
        Some(self.cmp(o))
    }
}
impl Ord for Key {
    fn cmp(&self, o: &Self) -> std::cmp::Ordering {
        self.0.total_cmp(&o.0)
    }
}
