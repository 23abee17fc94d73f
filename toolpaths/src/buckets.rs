//! A static bucket grid of points in compressed rows (one allocation for all cells), with
//! removal and nearest / k-nearest queries by square rings of cells. Used by the stroke
//! orderer, whose greedy phase removes points as strokes are used.
//!
//! Ring `m` holds the cells at Chebyshev index distance `m` from the query's cell; every point
//! in ring `m` or beyond lies at least `(m − 1) · cell` from the query point, so a search may
//! stop once its current answer is closer than that.

use crate::geom::{norm, sub, Vec2};

/// Most cells a grid may allocate; the cell size grows past this.
const MAX_CELLS: f64 = 4.0e6;

pub(crate) struct Buckets {
    origin: Vec2,
    cell: f64,
    nx: usize,
    ny: usize,
    /// Cell `c` holds `ids[start[c] .. start[c] + live[c]]` (removed ids are swapped past
    /// the live part).
    start: Vec<u32>,
    live: Vec<u32>,
    ids: Vec<u32>,
    pts: Vec<Vec2>,
}

impl Buckets {
    /// Buckets over `pts` (item `i` is `pts[i]`) with cells of about `cell`.
    pub(crate) fn new(pts: Vec<Vec2>, cell: f64) -> Buckets {
        let mut b = [[f64::INFINITY; 2], [f64::NEG_INFINITY; 2]];
        for p in &pts {
            for k in 0..2 {
                b[0][k] = b[0][k].min(p[k]);
                b[1][k] = b[1][k].max(p[k]);
            }
        }
        if pts.is_empty() {
            b = [[0.0; 2], [1.0; 2]];
        }
        let w = (b[1][0] - b[0][0]).max(1e-12);
        let h = (b[1][1] - b[0][1]).max(1e-12);
        let cell = cell.max((w * h / MAX_CELLS).sqrt()).max(w.max(h) / 4096.0).max(1e-12);
        let nx = (w / cell).floor() as usize + 1;
        let ny = (h / cell).floor() as usize + 1;
        let mut g = Buckets {
            origin: b[0],
            cell,
            nx,
            ny,
            start: vec![0; nx * ny + 1],
            live: vec![0; nx * ny],
            ids: vec![0; pts.len()],
            pts: Vec::new(),
        };
        let cells: Vec<usize> = pts.iter().map(|&p| g.index(g.cell_of(p))).collect();
        for &c in &cells {
            g.live[c] += 1;
        }
        for c in 0..nx * ny {
            g.start[c + 1] = g.start[c] + g.live[c];
        }
        let mut fill = g.start.clone();
        for (i, &c) in cells.iter().enumerate() {
            g.ids[fill[c] as usize] = i as u32;
            fill[c] += 1;
        }
        g.pts = pts;
        g
    }

    fn cell_of(&self, p: Vec2) -> (usize, usize) {
        let f = |x: f64, o: f64, n: usize| {
            let i = ((x - o) / self.cell).floor();
            if i.is_nan() || i < 0.0 {
                0
            } else {
                (i as usize).min(n - 1)
            }
        };
        (f(p[0], self.origin[0], self.nx), f(p[1], self.origin[1], self.ny))
    }

    fn index(&self, (x, y): (usize, usize)) -> usize {
        y * self.nx + x
    }

    fn cell_items(&self, c: usize) -> &[u32] {
        let s = self.start[c] as usize;
        &self.ids[s..s + self.live[c] as usize]
    }

    /// Remove item `id` (no-op when already removed).
    pub(crate) fn remove(&mut self, id: u32) {
        let c = self.index(self.cell_of(self.pts[id as usize]));
        let s = self.start[c] as usize;
        let n = self.live[c] as usize;
        if let Some(k) = self.ids[s..s + n].iter().position(|&x| x == id) {
            self.ids.swap(s + k, s + n - 1);
            self.live[c] -= 1;
        }
    }

    /// Visit rings of cells around `p`; before ring `m`, `lower(m)` — a lower bound on the
    /// distance from `p` to any point not yet visited — is passed to `done`, and the search
    /// stops when it returns true.
    fn rings(&self, p: Vec2, mut done: impl FnMut(f64) -> bool, mut f: impl FnMut(u32, f64)) {
        let (cx, cy) = self.cell_of(p);
        let reach = cx.max(self.nx - 1 - cx).max(cy).max(self.ny - 1 - cy);
        for m in 0..=reach {
            if done(m.saturating_sub(1) as f64 * self.cell) {
                return;
            }
            let (x0, x1) = (cx.saturating_sub(m), (cx + m).min(self.nx - 1));
            let (y0, y1) = (cy.saturating_sub(m), (cy + m).min(self.ny - 1));
            let mut visit = |x: usize, y: usize| {
                for &id in self.cell_items(y * self.nx + x) {
                    f(id, norm(sub(self.pts[id as usize], p)));
                }
            };
            for y in y0..=y1 {
                let edge_row = y + m == cy || y == cy + m;
                if edge_row {
                    for x in x0..=x1 {
                        visit(x, y);
                    }
                } else {
                    if x0 + m == cx {
                        visit(x0, y);
                    }
                    if x1 == cx + m && m > 0 {
                        visit(x1, y);
                    }
                }
            }
        }
    }

    /// Call `f(id, distance)` for every live item within distance `r` of `p` (and possibly a
    /// few beyond it).
    pub(crate) fn within(&self, p: Vec2, r: f64, mut f: impl FnMut(u32, f64)) {
        if r.is_nan() || r < 0.0 {
            return;
        }
        self.rings(
            p,
            |lb| lb > r,
            |id, dd| {
                if dd <= r {
                    f(id, dd)
                }
            },
        );
    }

    /// The nearest live item to `p` accepted by `keep` (ties: lowest id), with its distance.
    pub(crate) fn nearest(&self, p: Vec2, keep: impl Fn(u32) -> bool) -> Option<(f64, u32)> {
        let mut best: Option<(f64, u32)> = None;
        let best_cell = std::cell::Cell::new(f64::INFINITY);
        self.rings(
            p,
            |lb| best_cell.get() < lb,
            |id, dd| {
                if keep(id) && best.is_none_or(|(bd, bid)| dd < bd || (dd == bd && id < bid)) {
                    best = Some((dd, id));
                    best_cell.set(dd);
                }
            },
        );
        best
    }

    /// Up to `k` nearest live items to `p` by distance, keeping for each key
    /// `key(id)` (`None` = skip the item) only its nearest item; sorted by (distance, key).
    pub(crate) fn k_nearest(
        &self,
        p: Vec2,
        k: usize,
        key: impl Fn(u32) -> Option<u32>,
    ) -> Vec<(f64, u32)> {
        let mut top: Vec<(f64, u32)> = Vec::with_capacity(k + 1);
        let kth = std::cell::Cell::new(f64::INFINITY);
        self.rings(
            p,
            |lb| kth.get() < lb,
            |id, dd| {
                let Some(key) = key(id) else { return };
                if top.len() == k && dd > kth.get() {
                    return;
                }
                if let Some(at) = top.iter().position(|t| t.1 == key) {
                    if (dd, key) >= top[at] {
                        return;
                    }
                    top.remove(at);
                }
                let at = top.partition_point(|t| (t.0, t.1) < (dd, key));
                top.insert(at, (dd, key));
                top.truncate(k);
                if top.len() == k {
                    kth.set(top[k - 1].0);
                }
            },
        );
        top
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn brute(pts: &[Vec2], p: Vec2, k: usize) -> Vec<(f64, u32)> {
        let mut v: Vec<(f64, u32)> =
            pts.iter().enumerate().map(|(i, q)| (norm(sub(*q, p)), i as u32)).collect();
        v.sort_by(|a, b| a.0.total_cmp(&b.0).then(a.1.cmp(&b.1)));
        v.truncate(k);
        v
    }

    /// k-nearest and nearest agree with a brute-force scan on scattered points, also after
    /// removals and for query points outside the grid.
    #[test]
    fn queries_match_brute_force() {
        let mut pts = Vec::new();
        let mut s = 12345u64;
        let mut rnd = || {
            s = s.wrapping_mul(6364136223846793005).wrapping_add(1442695040888963407);
            (s >> 11) as f64 / (1u64 << 53) as f64
        };
        for _ in 0..500 {
            let (x, y) = (rnd(), rnd());
            pts.push([100.0 * x * x, 30.0 * y]);
        }
        let mut g = Buckets::new(pts.clone(), 2.0);
        for q in [[50.0, 15.0], [-20.0, 5.0], [0.0, 0.0], [130.0, 60.0], [99.0, 1.0]] {
            assert_eq!(g.k_nearest(q, 7, Some), brute(&pts, q, 7));
            assert_eq!(g.nearest(q, |_| true), brute(&pts, q, 1).first().copied());
        }
        let mut alive: Vec<Vec2> = Vec::new();
        for (i, p) in pts.iter().enumerate() {
            if i % 3 == 0 {
                g.remove(i as u32);
            } else {
                alive.push(*p);
            }
        }
        let q = [40.0, 10.0];
        let want = brute(&pts, q, 400).into_iter().filter(|t| t.1 % 3 != 0).take(5);
        assert_eq!(g.k_nearest(q, 5, Some), want.collect::<Vec<_>>());
        // Keyed: items 2i and 2i + 1 share a key; each key appears once, at its nearer item.
        let got = g.k_nearest(q, 4, |id| Some(id / 2));
        let mut keys: Vec<u32> = got.iter().map(|t| t.1).collect();
        keys.dedup();
        assert_eq!(keys.len(), 4);
    }
}
