//! Stroke orientation and ordering to minimize travel.
//!
//! Ordering is an open asymmetric travelling-salesman problem over strokes with fixed entry
//! and exit points (only `alternate` lets the orderer flip strokes): greedy nearest neighbour
//! from the home position, then a queue-driven local search with neighbour lists — 2-opt,
//! segment swaps (asymmetric 3-opt / Or-opt) and re-choosing loop entries — see
//! `improve.rs` (Johnson & McGeoch, *The TSP: a case study in local optimization*,
//! 1997, §3; Or, 1976). No randomness: the result depends only on the input.
//!
//! Closed loops may be entered at any of their vertices (they exit where they entered):
//! greedy picks the nearest of up to 16 of them and the local search moves the entry to the
//! vertex that minimizes `d(previous exit, x) + d(x, next entry)`. This is a rotation, not a
//! flip.

use serde::{Deserialize, Serialize};

use crate::buckets::Buckets;
use crate::geom::Vec2;
use crate::improve::Search;
pub use crate::tour::Ends;
use crate::tour::{cell_size, d, Tour};

/// Global stroke orientation (the brushing direction is a process choice).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "lowercase")]
#[cfg_attr(feature = "schemars", derive(schemars::JsonSchema))]
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
#[serde(deny_unknown_fields)]
#[cfg_attr(feature = "schemars", derive(schemars::JsonSchema))]
pub struct OrderOptions {
    /// Where the tool starts (machine XY, mm). Default [0, 0].
    pub home: Vec2,
    /// Local-search effort: at most this many improving moves per stroke (0: greedy only).
    /// Default 50 (never reached in practice: the search stops at a local optimum).
    pub two_opt_passes: usize,
    /// Candidate neighbours per endpoint: the nearest entries to an exit (and exits to an
    /// entry), plus as many of the same kind; with flips, twice this many endpoints of either
    /// kind. Default 10.
    pub neighbours: usize,
}

impl Default for OrderOptions {
    fn default() -> Self {
        OrderOptions { home: [0.0, 0.0], two_opt_passes: 50, neighbours: 10 }
    }
}

/// Result of ordering.
#[derive(Clone, Debug, PartialEq)]
pub struct Ordering {
    /// Stroke indices in cutting order.
    pub order: Vec<usize>,
    /// Whether each stroke (by input index) is run end → start.
    pub flipped: Vec<bool>,
    /// For closed loops: the ring vertex where each is entered (by input index).
    pub entry: Vec<Option<usize>>,
    /// Travel from home through all strokes, mm (XY).
    pub travel: f64,
    /// Travel between strokes only (excluding the first move from home), mm.
    pub travel_between: f64,
    /// Travel after the greedy phase, before the local search (from home), mm.
    pub travel_greedy: f64,
}

/// Order strokes; `flip` allows running open strokes backwards.
pub fn order_strokes(ends: &[Ends], flip: bool, opts: &OrderOptions) -> Ordering {
    let n = ends.len();
    if n == 0 {
        return Ordering {
            order: vec![],
            flipped: vec![],
            entry: vec![],
            travel: 0.0,
            travel_between: 0.0,
            travel_greedy: 0.0,
        };
    }
    let mut tour = Tour::new(ends);
    let mut order = greedy(&mut tour, flip, opts.home);
    let travel_greedy = tour.length(&order, opts.home);
    if opts.two_opt_passes > 0 && n >= 2 {
        let max_moves = opts.two_opt_passes.saturating_mul(n);
        let mut search = Search::new(&mut tour, &order, flip, opts.home, opts.neighbours);
        search.run(max_moves);
        order = search.order();
    }
    let travel = tour.length(&order, opts.home);
    let first = tour.ent[order[0]];
    Ordering {
        travel_between: travel - d(opts.home, first),
        order,
        flipped: tour.flipped,
        entry: tour.vertex,
        travel,
        travel_greedy,
    }
}

/// Travel of a tour of open strokes from `home` (rings entered at their first vertex).
pub fn tour_length(e: &[Ends], order: &[usize], flipped: &[bool], home: Vec2) -> f64 {
    let mut tour = Tour::new(e);
    for (s, &f) in flipped.iter().enumerate() {
        tour.set_flip(s, f);
    }
    tour.length(order, home)
}

/// Most entry vertices of a loop offered to the greedy phase.
const GREEDY_RING_POINTS: usize = 16;

const START: u32 = u32::MAX;
const END: u32 = u32::MAX - 1;

/// Greedy nearest neighbour from `home`: always go to the nearest entry point of an unused
/// stroke (ties: lowest candidate id). Used strokes' candidates leave the buckets, so each
/// step costs about one ring search.
fn greedy(tour: &mut Tour, flip: bool, home: Vec2) -> Vec<usize> {
    let e = tour.e;
    let n = e.len();
    // Entry candidates: (stroke, START | END | ring vertex); `first[s]..first[s + 1]` are
    // stroke s's.
    let mut cand: Vec<(u32, u32)> = Vec::new();
    let mut pts: Vec<Vec2> = Vec::new();
    let mut first = Vec::with_capacity(n + 1);
    for (s, x) in e.iter().enumerate() {
        first.push(cand.len());
        if x.ring.is_empty() {
            cand.push((s as u32, START));
            pts.push(x.start);
            if flip {
                cand.push((s as u32, END));
                pts.push(x.end);
            }
        } else {
            // A loop offers a few evenly spaced vertices; the local search re-chooses among
            // all of them.
            let step = x.ring.len().div_ceil(GREEDY_RING_POINTS).max(1);
            for (k, p) in x.ring.iter().enumerate().step_by(step) {
                cand.push((s as u32, k as u32));
                pts.push(*p);
            }
        }
    }
    first.push(cand.len());
    let cell = cell_size(&pts, n);
    let mut grid = Buckets::new(pts, cell);
    let mut order = Vec::with_capacity(n);
    let mut pos = home;
    for _ in 0..n {
        let Some((_, id)) = grid.nearest(pos, |_| true) else { break };
        let (s, code) = cand[id as usize];
        let s = s as usize;
        for c in first[s]..first[s + 1] {
            grid.remove(c as u32);
        }
        match code {
            START => tour.set_flip(s, false),
            END => tour.set_flip(s, true),
            k => tour.set_vertex(s, k as usize),
        }
        order.push(s);
        pos = tour.ext[s];
    }
    order
}
