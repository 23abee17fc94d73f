//! Local improvement of a stroke tour: 2-opt with neighbour lists and O(1) gains from
//! prefix sums, Or-opt moves of short runs, and re-choosing where closed loops are entered
//! (see [`crate::order`] for the model).

use crate::geom::Vec2;
use crate::grid::PointGrid;
use crate::order::{d, OrderOptions, Tour};

/// Re-choose each loop's entry vertex given its neighbours in the tour.
pub(crate) fn rotate_rings(tour: &mut Tour, order: &[usize], home: Vec2) {
    for k in 0..order.len() {
        let s = order[k];
        if !tour.is_ring(s) {
            continue;
        }
        let prev = if k == 0 { home } else { tour.ext[order[k - 1]] };
        let next = order.get(k + 1).map(|&t| tour.ent[t]);
        let cost = |p: Vec2| d(prev, p) + next.map_or(0.0, |q| d(p, q));
        let ring = &tour.e[s].ring;
        let mut best = (cost(ring[0]), 0);
        for (i, p) in ring.iter().enumerate().skip(1) {
            let c = cost(*p);
            if c < best.0 {
                best = (c, i);
            }
        }
        tour.set_vertex(s, best.1);
    }
}

/// Endpoint `id` of the neighbour lists: `2s` is the start (a loop's current vertex),
/// `2s + 1` the end of stroke `s`.
fn endpoint(tour: &Tour, id: usize) -> Vec2 {
    let s = id / 2;
    match (tour.is_ring(s), id % 2) {
        (true, _) => tour.ent[s],
        (false, 0) => tour.e[s].start,
        (false, _) => tour.e[s].end,
    }
}

/// The neighbour-list id of the point where stroke `s` currently exits.
fn exit_id(tour: &Tour, s: usize) -> usize {
    if tour.is_ring(s) || tour.flipped[s] {
        2 * s
    } else {
        2 * s + 1
    }
}

/// K nearest strokes (by either endpoint) of every stroke endpoint.
fn neighbour_lists(tour: &Tour, k: usize) -> Vec<Vec<u32>> {
    let n = tour.ent.len();
    let pts = |id: usize| endpoint(tour, id);
    let mut b = [pts(0), pts(0)];
    for id in 0..2 * n {
        let p = pts(id);
        for j in 0..2 {
            b[0][j] = b[0][j].min(p[j]);
            b[1][j] = b[1][j].max(p[j]);
        }
    }
    let area = ((b[1][0] - b[0][0]) * (b[1][1] - b[0][1])).max(1e-12);
    let cell = (area / n as f64).sqrt().max(1e-9);
    let mut grid = PointGrid::new(b, cell);
    for id in 0..2 * n {
        grid.insert(pts(id), id as u32);
    }
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

/// Prefix sums of forward (`exit_m → entry_{m+1}`) and backward (`exit_{m+1} → entry_m`)
/// travel, and positions, recomputed from index `from` on (earlier entries are unchanged).
fn prefix(
    tour: &Tour,
    order: &[usize],
    from: usize,
    pos: &mut [usize],
    fwd: &mut [f64],
    bwd: &mut [f64],
) {
    for (k, &s) in order.iter().enumerate().skip(from) {
        pos[s] = k;
    }
    for k in from.max(1)..order.len() {
        let (a, b) = (order[k - 1], order[k]);
        fwd[k] = fwd[k - 1] + d(tour.ext[a], tour.ent[b]);
        bwd[k] = bwd[k - 1] + d(tour.ext[b], tour.ent[a]);
    }
}

/// 2-opt on the open tour: reverse `order[i..=j]` when it shortens travel.
pub(crate) fn two_opt(tour: &mut Tour, order: &mut [usize], flip: bool, o: &OrderOptions) {
    let n = order.len();
    if n < 3 || o.two_opt_passes == 0 {
        return;
    }
    let nb = neighbour_lists(tour, o.neighbours.max(1));
    let mut pos = vec![0usize; n];
    let mut fwd = vec![0.0; n];
    let mut bwd = vec![0.0; n];
    prefix(tour, order, 0, &mut pos, &mut fwd, &mut bwd);
    for _ in 0..o.two_opt_passes {
        let mut improved = false;
        for i in 0..n {
            let prev_exit = if i == 0 { o.home } else { tour.ext[order[i - 1]] };
            let list: &[u32] =
                if i == 0 { &nb[2 * order[0]] } else { &nb[exit_id(tour, order[i - 1])] };
            let mut best: Option<(f64, usize)> = None;
            for &c in list {
                let j = pos[c as usize];
                if j <= i {
                    continue;
                }
                let (si, sj) = (order[i], order[j]);
                let after = order.get(j + 1).map(|&t| tour.ent[t]);
                let old_in = d(prev_exit, tour.ent[si]);
                let old_out = after.map_or(0.0, |q| d(tour.ext[sj], q));
                let (new_in, new_out, inner) = if flip {
                    // The run is reversed and every stroke in it flipped: inner travel is
                    // kept (loops exit where they enter, so they need no flip).
                    (d(prev_exit, tour.ext[sj]), after.map_or(0.0, |q| d(tour.ent[si], q)), 0.0)
                } else {
                    (
                        d(prev_exit, tour.ent[sj]),
                        after.map_or(0.0, |q| d(tour.ext[si], q)),
                        (bwd[j] - bwd[i]) - (fwd[j] - fwd[i]),
                    )
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
                        let f = !tour.flipped[s];
                        tour.set_flip(s, f);
                    }
                }
                prefix(tour, order, i, &mut pos, &mut fwd, &mut bwd);
                improved = true;
            }
        }
        if !improved {
            break;
        }
    }
}

/// Or-opt: move a run `order[i..i+len]` (len 1..=3, not reversed) to just after another
/// stroke `c` from the run's entry neighbour list, when that shortens travel.
pub(crate) fn or_opt(tour: &mut Tour, order: &mut Vec<usize>, o: &OrderOptions) {
    let n = order.len();
    if n < 4 || o.two_opt_passes == 0 {
        return;
    }
    let nb = neighbour_lists(tour, o.neighbours.max(1));
    let mut pos = vec![0usize; n];
    let reindex = |order: &[usize], pos: &mut [usize], a: usize, b: usize| {
        for (k, &s) in order.iter().enumerate().take(b + 1).skip(a) {
            pos[s] = k;
        }
    };
    reindex(order, &mut pos, 0, n - 1);
    let x = |tour: &Tour, order: &[usize], k: usize| {
        if k == usize::MAX {
            o.home
        } else {
            tour.ext[order[k]]
        }
    };
    for _ in 0..o.two_opt_passes {
        let mut improved = false;
        for len in 1..=3usize {
            let mut i = 0;
            while i + len <= n {
                let last = i + len - 1;
                let before = if i == 0 { usize::MAX } else { i - 1 };
                let after = order.get(last + 1).map(|&t| tour.ent[t]);
                let (ei, xl) = (tour.ent[order[i]], tour.ext[order[last]]);
                let xb = x(tour, order, before);
                let removed =
                    d(xb, ei) + after.map_or(0.0, |a| d(xl, a)) - after.map_or(0.0, |a| d(xb, a));
                let mut best: Option<(f64, usize)> = None;
                let entry_id = if tour.is_ring(order[i]) || !tour.flipped[order[i]] {
                    2 * order[i]
                } else {
                    2 * order[i] + 1
                };
                for &c in &nb[entry_id] {
                    let j = pos[c as usize];
                    if (i..=last).contains(&j) || j + 1 == i {
                        continue;
                    }
                    let xj = tour.ext[order[j]];
                    let nj = order.get(j + 1).map(|&t| tour.ent[t]);
                    let added =
                        d(xj, ei) + nj.map_or(0.0, |q| d(xl, q)) - nj.map_or(0.0, |q| d(xj, q));
                    let gain = removed - added;
                    if gain > 1e-9 && best.is_none_or(|(g, _)| gain > g) {
                        best = Some((gain, j));
                    }
                }
                if let Some((_, j)) = best {
                    let run: Vec<usize> = order.drain(i..=last).collect();
                    let at = if j > last { j - len + 1 } else { j + 1 };
                    order.splice(at..at, run);
                    reindex(order, &mut pos, i.min(at), (last).max(at + len - 1));
                    improved = true;
                }
                i += 1;
            }
        }
        if !improved {
            break;
        }
    }
}
