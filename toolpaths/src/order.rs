//! Stroke orientation and ordering to minimize travel.
//!
//! Ordering is an open asymmetric travelling-salesman problem over strokes with fixed entry
//! and exit points: greedy nearest neighbour from the home position, then 2-opt with
//! neighbour lists (Johnson & McGeoch, *The TSP: a case study in local optimization*, 1997,
//! §3). Reversing a run of strokes that may not be flipped changes the travel *inside* the
//! run, so the 2-opt gain uses prefix sums of forward (`exit_k → entry_{k+1}`) and backward
//! (`exit_{k+1} → entry_k`) travel, making every candidate move O(1). Only `alternate` lets
//! the orderer flip strokes. No randomness: the result depends only on the input order.

use serde::{Deserialize, Serialize};

use crate::geom::{norm, sub, Vec2};
use crate::grid::PointGrid;

/// Global stroke orientation (the brushing direction is a process choice).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "lowercase")]
pub enum Direction {
    /// Vector fields: along the arrows. Line fields: so that `(end − start) · reference ≥ 0`
    /// (closed loops: counter-clockwise in UV).
    #[default]
    Along,
    /// The opposite of `Along`.
    Against,
    /// Either way; the orderer picks the one that shortens travel.
    Alternate,
}

/// Ordering options.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(default)]
pub struct OrderOptions {
    /// Where the tool starts (machine XY, mm).
    pub home: Vec2,
    /// Most 2-opt sweeps over the tour. Default 50.
    pub two_opt_passes: usize,
    /// Candidate neighbours per endpoint for 2-opt. Default 10.
    pub neighbours: usize,
}

impl Default for OrderOptions {
    fn default() -> Self {
        OrderOptions { home: [0.0, 0.0], two_opt_passes: 50, neighbours: 10 }
    }
}

/// A stroke as the orderer sees it: entry and exit in machine XY.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Ends {
    /// First point.
    pub start: Vec2,
    /// Last point.
    pub end: Vec2,
}

/// Result of ordering.
#[derive(Clone, Debug, PartialEq)]
pub struct Ordering {
    /// Stroke indices in cutting order.
    pub order: Vec<usize>,
    /// Whether each stroke (by input index) is run end → start.
    pub flipped: Vec<bool>,
    /// Travel from home through all strokes, mm (XY).
    pub travel: f64,
    /// Travel between strokes only (excluding the first move from home), mm.
    pub travel_between: f64,
    /// Travel after the greedy phase, before 2-opt (from home), mm.
    pub travel_greedy: f64,
}

fn d(a: Vec2, b: Vec2) -> f64 {
    norm(sub(a, b))
}

/// Order strokes; `flip` allows running strokes backwards.
pub fn order_strokes(ends: &[Ends], flip: bool, opts: &OrderOptions) -> Ordering {
    let n = ends.len();
    if n == 0 {
        return Ordering {
            order: vec![],
            flipped: vec![],
            travel: 0.0,
            travel_between: 0.0,
            travel_greedy: 0.0,
        };
    }
    let (mut order, mut flipped) = greedy(ends, flip, opts.home);
    let travel_greedy = tour_length(ends, &order, &flipped, opts.home);
    two_opt(ends, &mut order, &mut flipped, flip, opts);
    let travel = tour_length(ends, &order, &flipped, opts.home);
    let first = entry(ends, order[0], &flipped);
    Ordering { travel_between: travel - d(opts.home, first), order, flipped, travel, travel_greedy }
}

fn entry(e: &[Ends], s: usize, flipped: &[bool]) -> Vec2 {
    if flipped[s] {
        e[s].end
    } else {
        e[s].start
    }
}

fn exit(e: &[Ends], s: usize, flipped: &[bool]) -> Vec2 {
    if flipped[s] {
        e[s].start
    } else {
        e[s].end
    }
}

/// Travel of a tour from `home`.
pub fn tour_length(e: &[Ends], order: &[usize], flipped: &[bool], home: Vec2) -> f64 {
    let mut pos = home;
    let mut t = 0.0;
    for &s in order {
        t += d(pos, entry(e, s, flipped));
        pos = exit(e, s, flipped);
    }
    t
}

fn bbox(e: &[Ends], home: Vec2) -> [Vec2; 2] {
    let mut b = [home, home];
    for x in e {
        for p in [x.start, x.end] {
            for k in 0..2 {
                b[0][k] = b[0][k].min(p[k]);
                b[1][k] = b[1][k].max(p[k]);
            }
        }
    }
    b
}

/// Greedy nearest neighbour with a grid of unvisited entry points (ties: lowest id).
fn greedy(e: &[Ends], flip: bool, home: Vec2) -> (Vec<usize>, Vec<bool>) {
    let n = e.len();
    let b = bbox(e, home);
    let area = ((b[1][0] - b[0][0]) * (b[1][1] - b[0][1])).max(1e-12);
    let cell = (area / n as f64).sqrt().max(1e-9);
    let mut grid = PointGrid::new(b, cell);
    let pts = |id: usize| if id.is_multiple_of(2) { e[id / 2].start } else { e[id / 2].end };
    for (s, x) in e.iter().enumerate() {
        grid.insert(x.start, (2 * s) as u32);
        if flip {
            grid.insert(x.end, (2 * s + 1) as u32);
        }
    }
    let mut used = vec![false; n];
    let mut order = Vec::with_capacity(n);
    let mut flipped = vec![false; n];
    let mut pos = home;
    let span = (b[1][0] - b[0][0]).max(b[1][1] - b[0][1]) + 2.0 * cell;
    for _ in 0..n {
        let mut r = cell;
        let mut best: Option<(f64, u32)> = None;
        loop {
            grid.visit(pos, r, |id| {
                if !used[id as usize / 2] {
                    let dd = d(pos, pts(id as usize));
                    if dd <= r && best.is_none_or(|(bd, bid)| dd < bd || (dd == bd && id < bid)) {
                        best = Some((dd, id));
                    }
                }
                true
            });
            if best.is_some() || r > 2.0 * span {
                break;
            }
            r *= 2.0;
        }
        let (_, id) = best.unwrap_or_else(|| {
            // Unreachable in practice: fall back to a scan.
            let s = (0..n).find(|&s| !used[s]).unwrap_or(0);
            (0.0, 2 * s as u32)
        });
        let s = id as usize / 2;
        used[s] = true;
        flipped[s] = id % 2 == 1;
        order.push(s);
        pos = exit(e, s, &flipped);
    }
    (order, flipped)
}

/// K nearest stroke endpoints (by stroke id) of every endpoint, via the grid.
fn neighbour_lists(e: &[Ends], k: usize) -> Vec<Vec<u32>> {
    let n = e.len();
    let b = bbox(e, e[0].start);
    let area = ((b[1][0] - b[0][0]) * (b[1][1] - b[0][1])).max(1e-12);
    let cell = (area / n as f64).sqrt().max(1e-9);
    let mut grid = PointGrid::new(b, cell);
    for (s, x) in e.iter().enumerate() {
        grid.insert(x.start, (2 * s) as u32);
        grid.insert(x.end, (2 * s + 1) as u32);
    }
    let pts = |id: usize| if id.is_multiple_of(2) { e[id / 2].start } else { e[id / 2].end };
    let mut out = Vec::with_capacity(2 * n);
    for id in 0..2 * n {
        let p = pts(id);
        let mut r = cell;
        let mut found: Vec<(f64, u32)> = Vec::new();
        for _ in 0..40 {
            found.clear();
            grid.visit(p, r, |o| {
                if o as usize / 2 != id / 2 {
                    let dd = d(p, pts(o as usize));
                    if dd <= r {
                        found.push((dd, o / 2));
                    }
                }
                true
            });
            if found.len() >= 2 * k || found.len() >= 2 * (n - 1) {
                break;
            }
            r *= 2.0;
        }
        found.sort_by(|a, b| a.0.total_cmp(&b.0).then(a.1.cmp(&b.1)));
        let mut list: Vec<u32> = Vec::with_capacity(k);
        for (_, s) in found {
            if !list.contains(&s) {
                list.push(s);
                if list.len() == k {
                    break;
                }
            }
        }
        out.push(list);
    }
    out
}

/// 2-opt on the open tour: reverse `order[i..=j]` when it shortens travel.
fn two_opt(e: &[Ends], order: &mut [usize], flipped: &mut [bool], flip: bool, o: &OrderOptions) {
    let n = order.len();
    if n < 3 || o.two_opt_passes == 0 {
        return;
    }
    let nb = neighbour_lists(e, o.neighbours.max(1));
    let mut pos = vec![0usize; n];
    // fwd[k] = Σ_{m<k} d(exit_m, entry_{m+1}); bwd[k] = Σ_{m<k} d(exit_{m+1}, entry_m).
    let mut fwd = vec![0.0; n];
    let mut bwd = vec![0.0; n];
    let rebuild =
        |order: &[usize], flipped: &[bool], pos: &mut [usize], fwd: &mut [f64], bwd: &mut [f64]| {
            for (k, &s) in order.iter().enumerate() {
                pos[s] = k;
            }
            for k in 1..order.len() {
                let (a, b) = (order[k - 1], order[k]);
                fwd[k] = fwd[k - 1] + d(exit(e, a, flipped), entry(e, b, flipped));
                bwd[k] = bwd[k - 1] + d(exit(e, b, flipped), entry(e, a, flipped));
            }
        };
    rebuild(order, flipped, &mut pos, &mut fwd, &mut bwd);
    for _ in 0..o.two_opt_passes {
        let mut improved = false;
        for i in 0..n {
            let prev_exit = if i == 0 { o.home } else { exit(e, order[i - 1], flipped) };
            let key = if i == 0 { None } else { Some(order[i - 1]) };
            let lists: Vec<u32> = match key {
                Some(s) => {
                    let end_id = if flipped[s] { 2 * s } else { 2 * s + 1 };
                    nb[end_id].clone()
                }
                None => (0..n.min(o.neighbours.max(1)) as u32)
                    .map(|k| order[k as usize] as u32)
                    .collect(),
            };
            let mut best: Option<(f64, usize)> = None;
            for c in lists {
                let j = pos[c as usize];
                if j <= i {
                    continue;
                }
                let (si, sj) = (order[i], order[j]);
                let old_in = d(prev_exit, entry(e, si, flipped));
                let old_out = if j + 1 < n {
                    d(exit(e, sj, flipped), entry(e, order[j + 1], flipped))
                } else {
                    0.0
                };
                let (new_in, new_out, inner) = if flip {
                    // The run is reversed and every stroke in it flipped: inner travel is kept.
                    let ni = d(prev_exit, exit(e, sj, flipped));
                    let no = if j + 1 < n {
                        d(entry(e, si, flipped), entry(e, order[j + 1], flipped))
                    } else {
                        0.0
                    };
                    (ni, no, 0.0)
                } else {
                    let ni = d(prev_exit, entry(e, sj, flipped));
                    let no = if j + 1 < n {
                        d(exit(e, si, flipped), entry(e, order[j + 1], flipped))
                    } else {
                        0.0
                    };
                    (ni, no, (bwd[j] - bwd[i]) - (fwd[j] - fwd[i]))
                };
                let gain = old_in + old_out - new_in - new_out - inner;
                if gain > 1e-9 && best.is_none_or(|(g, _)| gain > g) {
                    best = Some((gain, j));
                }
            }
            if let Some((_, j)) = best {
                order[i..=j].reverse();
                if flip {
                    for &s in &order[i..=j] {
                        flipped[s] = !flipped[s];
                    }
                }
                rebuild(order, flipped, &mut pos, &mut fwd, &mut bwd);
                improved = true;
            }
        }
        if !improved {
            break;
        }
    }
}
