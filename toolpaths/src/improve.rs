//! Local search on a stroke tour (see [`crate::order`] for the model): 2-opt, segment swaps
//! ("or-3opt", which contain Or-opt) and re-choosing where closed loops are entered, driven
//! by a queue of strokes with don't-look bits over neighbour lists built once.
//!
//! The tour is `seq[0] = home, seq[1..=n]` = strokes; `X(k)` is the exit point at position
//! `k` (home for `k = 0`) and `N(k)` the entry point (none past the end: the path is open,
//! the last move costs nothing). Moves (Johnson & McGeoch 1997, §3; Or 1976):
//!
//! * **2-opt** reverses `seq[i..=j]`. With fixed orientations (no flips) the strokes inside
//!   keep their direction, so the travel *inside* the run changes: from `Σ f` (forward edges
//!   `X(k−1) → N(k)`) to `Σ r` (`X(k) → N(k−1)`), read from prefix sums in O(1). With
//!   flips allowed every stroke of the run is flipped and inner travel is unchanged.
//! * **Segment swap** `a | S1 | S2 | c'` → `a | S2 | S1 | c'`: removes `a→S1`, `S1→S2`,
//!   `S2→c'`, adds `a→S2`, `S2→S1`, `S1→c'`. No stroke changes direction, so it is exact for
//!   fixed orientations (the asymmetric 3-opt move; Or-opt is the case of a short `S1` or
//!   `S2`). Candidates: one new edge from a neighbour list with positive partial gain, the
//!   second from another list (three variants, one per new edge that is looked up first).
//! * **Loop entry**: a closed loop exits where it enters; its entry vertex is re-chosen to
//!   minimize `d(X(k−1), x) + d(x, N(k+1))` (a rotation, not a flip).
//!
//! Each popped stroke tries the moves that remove an edge at its entry or exit, applies the
//! best, and queues the strokes at every changed edge; the search stops when the queue is
//! empty (a local optimum for all three moves with these lists) or after `max_moves`.
//! Everything runs in a fixed order: same input, same tour.

use std::collections::VecDeque;

use crate::buckets::Buckets;
use crate::geom::Vec2;
use crate::tour::{cell_size, d, Tour};

/// Least gain (mm) for a move to count; far above the rounding of the prefix sums.
const EPS: f64 = 1e-9;

/// Edges per block of the prefix sums.
const BLOCK: usize = 128;

/// A candidate move and its gain.
#[derive(Clone, Copy, Debug)]
enum Move {
    /// Reverse `seq[i..=j]`.
    Reverse(usize, usize),
    /// Swap `seq[a+1..=b]` and `seq[b+1..=c]`.
    Swap(usize, usize, usize),
    /// Enter the loop at position `k` at ring vertex `v`.
    Ring(usize, usize),
}

pub(crate) struct Search<'t, 'e> {
    tour: &'t mut Tour<'e>,
    flip: bool,
    home: Vec2,
    n: usize,
    seq: Vec<usize>,
    pos: Vec<usize>,
    /// Neighbour lists, `k` slots per endpoint id (`u32::MAX` = empty): `2s` start, `2s + 1`
    /// end of stroke `s`, `2n` home. Without flips an end lists the nearest starts of other
    /// strokes and a start the nearest ends; with flips, the nearest endpoints of either kind.
    nb: Vec<u32>,
    k: usize,
    stride: usize,
    /// No flips: per-edge forward / reverse travel (see the module docs) and their prefix
    /// sums in blocks of `BLOCK` edges: within the block (`pf`, `pr`) and of whole blocks
    /// before it (`bf`, `br`), so an update costs O(changed + BLOCK + n / BLOCK).
    f: Vec<f64>,
    r: Vec<f64>,
    pf: Vec<f64>,
    pr: Vec<f64>,
    bf: Vec<f64>,
    br: Vec<f64>,
    queue: VecDeque<usize>,
    queued: Vec<bool>,
}

impl<'t, 'e> Search<'t, 'e> {
    /// Set up the search on `order` (a permutation of the strokes), with `k` neighbours per
    /// endpoint taken at the strokes' current entry/exit points.
    pub(crate) fn new(
        tour: &'t mut Tour<'e>,
        order: &[usize],
        flip: bool,
        home: Vec2,
        k: usize,
    ) -> Search<'t, 'e> {
        let n = order.len();
        let mut seq = Vec::with_capacity(n + 1);
        seq.push(n);
        seq.extend_from_slice(order);
        let mut pos = vec![0; n + 1];
        for (p, &s) in seq.iter().enumerate() {
            pos[s] = p;
        }
        // More candidates than strokes list nothing more (the lists are already complete).
        let k = k.clamp(1, n.max(1));
        let mut s = Search {
            tour,
            flip,
            home,
            n,
            seq,
            pos,
            nb: Vec::new(),
            k,
            stride: k,
            f: Vec::new(),
            r: Vec::new(),
            pf: Vec::new(),
            pr: Vec::new(),
            bf: Vec::new(),
            br: Vec::new(),
            queue: (0..n).map(|p| order[p]).collect(),
            queued: vec![true; n + 1],
        };
        s.queued[n] = false;
        s.build_lists();
        if !flip {
            s.f = vec![0.0; n + 1];
            s.r = vec![0.0; n + 1];
            s.pf = vec![0.0; n + 1];
            s.pr = vec![0.0; n + 1];
            s.bf = vec![0.0; n / BLOCK + 2];
            s.br = vec![0.0; n / BLOCK + 2];
            s.refresh(1, n);
        }
        s
    }

    /// The order found (strokes only).
    pub(crate) fn order(&self) -> Vec<usize> {
        self.seq[1..].to_vec()
    }

    fn build_lists(&mut self) {
        let n = self.n;
        let k = self.k;
        // As many again of the other kind: without flips an end also lists the strokes that
        // end near it (their successors are candidates for the same return move).
        let extra = k;
        let stride = k + extra;
        let t = &*self.tour;
        let mut nb = vec![u32::MAX; (2 * n + 1) * stride];
        let mut put = |id: usize, list: Vec<(f64, u32)>, more: Vec<(f64, u32)>| {
            let slots = &mut nb[id * stride..(id + 1) * stride];
            let mut m = 0;
            for (_, s) in list.into_iter().chain(more) {
                if m < stride && !slots[..m].contains(&s) {
                    slots[m] = s;
                    m += 1;
                }
            }
        };
        if self.flip {
            let pts: Vec<Vec2> = (0..2 * n).map(|id| endpoint(t, id)).collect();
            let cell = cell_size(&pts, 2 * n);
            let g = Buckets::new(pts, cell);
            for id in 0..2 * n {
                let own = (id / 2) as u32;
                let key = |o: u32| (o / 2 != own).then_some(o / 2);
                put(id, g.k_nearest(endpoint(t, id), stride, key), vec![]);
            }
            put(2 * n, g.k_nearest(self.home, stride, |o| Some(o / 2)), vec![]);
        } else {
            let starts = Buckets::new(t.ent.clone(), cell_size(&t.ent, n));
            let ends = Buckets::new(t.ext.clone(), cell_size(&t.ext, n));
            for s in 0..n {
                let other = |o: u32| (o as usize != s).then_some(o);
                let (x, y) = (t.ext[s], t.ent[s]);
                put(2 * s + 1, starts.k_nearest(x, k, other), ends.k_nearest(x, extra, other));
                put(2 * s, ends.k_nearest(y, k, other), starts.k_nearest(y, extra, other));
            }
            put(2 * n, starts.k_nearest(self.home, stride, Some), vec![]);
        }
        self.nb = nb;
        self.stride = stride;
    }

    fn list(&self, id: usize) -> impl Iterator<Item = usize> + '_ {
        self.nb[id * self.stride..(id + 1) * self.stride]
            .iter()
            .take_while(|&&s| s != u32::MAX)
            .map(|&s| s as usize)
    }

    /// Endpoint id whose list holds strokes entered near `s`'s exit (home: `2n`).
    fn exit_list(&self, s: usize) -> usize {
        if s == self.n {
            2 * self.n
        } else if self.flip && self.tour.flipped[s] {
            2 * s
        } else {
            2 * s + 1
        }
    }

    /// Endpoint id whose list holds strokes that exit near `s`'s entry.
    fn entry_list(&self, s: usize) -> usize {
        self.exit_list(s) ^ 1
    }

    fn x(&self, k: usize) -> Vec2 {
        let s = self.seq[k];
        if s == self.n {
            self.home
        } else {
            self.tour.ext[s]
        }
    }

    fn en(&self, k: usize) -> Vec2 {
        self.tour.ent[self.seq[k]]
    }

    /// `d(p, N(k))`, 0 past the end of the path.
    fn dn(&self, p: Vec2, k: usize) -> f64 {
        if k > self.n {
            0.0
        } else {
            d(p, self.en(k))
        }
    }

    fn is_ring(&self, k: usize) -> bool {
        self.tour.is_ring(self.seq[k])
    }

    /// Recompute edges `lo..=hi` and the prefix sums that depend on them (no flips only).
    fn refresh(&mut self, lo: usize, hi: usize) {
        if self.flip {
            return;
        }
        let (lo, hi) = (lo.max(1), hi.min(self.n));
        for k in lo..=hi {
            self.f[k] = d(self.x(k - 1), self.en(k));
            self.r[k] = if k >= 2 { d(self.x(k), self.en(k - 1)) } else { 0.0 };
        }
        let (b0, b1) = (lo / BLOCK, hi / BLOCK);
        for b in b0..=b1 {
            let (s, e) = ((b * BLOCK).max(1), ((b + 1) * BLOCK).min(self.n + 1));
            let (mut af, mut ar) = (0.0, 0.0);
            for k in s..e {
                af += self.f[k];
                ar += self.r[k];
                self.pf[k] = af;
                self.pr[k] = ar;
            }
        }
        for b in b0 + 1..self.bf.len() {
            let last = (b * BLOCK - 1).min(self.n);
            let (tf, tr) = if last + 1 > (b - 1) * BLOCK {
                (self.pf[last], self.pr[last])
            } else {
                (0.0, 0.0)
            };
            self.bf[b] = self.bf[b - 1] + tf;
            self.br[b] = self.br[b - 1] + tr;
        }
    }

    /// `Σ_{m ≤ k} f[m]` and `Σ_{m ≤ k} r[m]`.
    fn prefix(&self, k: usize) -> (f64, f64) {
        (self.bf[k / BLOCK] + self.pf[k], self.br[k / BLOCK] + self.pr[k])
    }

    fn push(&mut self, k: usize) {
        if k <= self.n {
            let s = self.seq[k];
            if s != self.n && !self.queued[s] {
                self.queued[s] = true;
                self.queue.push_back(s);
            }
        }
    }

    /// Gain of reversing `seq[i..=j]` (`1 ≤ i ≤ j ≤ n`).
    fn reverse_gain(&self, i: usize, j: usize) -> f64 {
        let xi = self.x(i - 1);
        let old = d(xi, self.en(i)) + self.dn(self.x(j), j + 1);
        let new = if self.flip {
            d(xi, self.x(j)) + self.dn(self.en(i), j + 1)
        } else {
            let ((fi, ri), (fj, rj)) = (self.prefix(i), self.prefix(j));
            let inner = (rj - ri) - (fj - fi);
            d(xi, self.en(j)) + self.dn(self.x(i), j + 1) + inner
        };
        old - new
    }

    fn consider(best: &mut Option<(f64, Move)>, gain: f64, m: Move) {
        if gain > EPS && best.is_none_or(|(g, _)| gain > g) {
            *best = Some((gain, m));
        }
    }

    /// Best move removing the exit edge of the stroke at position `p` (and loop entries).
    fn best_move(&self, p: usize) -> Option<(f64, Move)> {
        let mut best = None;
        // Moves are found from the tail of a removed edge: every changed edge queues its tail,
        // so a stroke only looks at its own exit (the first stroke also at home's).
        for i1 in if p == 1 { 0..=1 } else { p..=p } {
            let t1 = self.seq[i1];
            let x1 = self.x(i1);
            for t3 in self.list(self.exit_list(t1)) {
                let q = self.pos[t3];
                if q > i1 {
                    // 2-opt, new edge X(i1) → (new entry of) seq[q].
                    let ok = i1 + 1 < q || (self.flip && !self.is_ring(q));
                    if ok {
                        Self::consider(
                            &mut best,
                            self.reverse_gain(i1 + 1, q),
                            Move::Reverse(i1 + 1, q),
                        );
                    }
                    // 2-opt, new edge X(i1) → N(q): seq[i1] keeps its direction.
                    if !self.flip && i1 >= 1 && i1 + 1 < q {
                        Self::consider(
                            &mut best,
                            self.reverse_gain(i1, q - 1),
                            Move::Reverse(i1, q - 1),
                        );
                    }
                    if q >= i1 + 2 {
                        // Swap, new edge a → b' with a = i1, b' = q.
                        let (a, b) = (i1, q - 1);
                        let g1 =
                            d(x1, self.en(a + 1)) + d(self.x(b), self.en(q)) - d(x1, self.en(q));
                        if g1 > EPS {
                            for c in self.list(self.entry_list(self.seq[a + 1])) {
                                let kc = self.pos[c];
                                if kc < q {
                                    continue;
                                }
                                let xc = self.x(kc);
                                let gain = g1 + self.dn(xc, kc + 1)
                                    - d(xc, self.en(a + 1))
                                    - self.dn(self.x(b), kc + 1);
                                Self::consider(&mut best, gain, Move::Swap(a, b, kc));
                            }
                        }
                        // Swap, new edge b → c' with b = i1, c' = q.
                        if i1 >= 1 {
                            let (b, c) = (i1, q - 1);
                            let g1 = d(x1, self.en(b + 1)) + d(self.x(c), self.en(q))
                                - d(x1, self.en(q));
                            if g1 > EPS {
                                let entry = self.seq[b + 1];
                                let mut try_a = |ka: usize| {
                                    if ka < b {
                                        let xa = self.x(ka);
                                        let gain = g1 + d(xa, self.en(ka + 1))
                                            - d(xa, self.en(b + 1))
                                            - d(self.x(c), self.en(ka + 1));
                                        Self::consider(&mut best, gain, Move::Swap(ka, b, c));
                                    }
                                };
                                try_a(0);
                                for a in self.list(self.entry_list(entry)) {
                                    try_a(self.pos[a]);
                                }
                            }
                        }
                    }
                } else if q >= 1 && q < i1 {
                    // Swap, new edge c → a' with c = i1, a' = q.
                    let (a, c) = (q - 1, i1);
                    let xa = self.x(a);
                    let g1 = d(xa, self.en(q)) + self.dn(x1, c + 1) - d(x1, self.en(q));
                    if g1 > EPS {
                        for bp in self.list(self.exit_list(self.seq[a])) {
                            let kb = self.pos[bp];
                            if kb <= q || kb > c {
                                continue;
                            }
                            let xb = self.x(kb - 1);
                            let gain =
                                g1 + d(xb, self.en(kb)) - d(xa, self.en(kb)) - self.dn(xb, c + 1);
                            Self::consider(&mut best, gain, Move::Swap(a, kb - 1, c));
                        }
                    }
                }
            }
            // With flips: 2-opt whose new edge leaves seq[i1] flipped, from its old entry.
            if self.flip && i1 >= 1 {
                for t3 in self.list(self.entry_list(t1)) {
                    let q = self.pos[t3];
                    if q > i1 && (i1 + 1 < q || !self.is_ring(i1)) {
                        Self::consider(
                            &mut best,
                            self.reverse_gain(i1, q - 1),
                            Move::Reverse(i1, q - 1),
                        );
                    }
                }
            }
        }
        if self.is_ring(p) {
            let s = self.seq[p];
            let prev = self.x(p - 1);
            let cost = |v: Vec2| d(prev, v) + self.dn(v, p + 1);
            let now = cost(self.tour.ent[s]);
            for (v, &pt) in self.tour.e[s].ring.iter().enumerate() {
                Self::consider(&mut best, now - cost(pt), Move::Ring(p, v));
            }
        }
        best
    }

    fn apply(&mut self, m: Move) {
        match m {
            Move::Reverse(i, j) => {
                self.seq[i..=j].reverse();
                if self.flip {
                    for k in i..=j {
                        let s = self.seq[k];
                        let f = !self.tour.flipped[s];
                        self.tour.set_flip(s, f);
                    }
                }
                for k in i..=j {
                    self.pos[self.seq[k]] = k;
                }
                self.refresh(i, j + 1);
                for k in [i - 1, i, j, j + 1] {
                    self.push(k);
                }
            }
            Move::Swap(a, b, c) => {
                self.seq[a + 1..=c].rotate_left(b - a);
                for k in a + 1..=c {
                    self.pos[self.seq[k]] = k;
                }
                self.refresh(a + 1, c + 1);
                let mid = a + (c - b);
                for k in [a, a + 1, mid, mid + 1, c, c + 1] {
                    self.push(k);
                }
            }
            Move::Ring(k, v) => {
                self.tour.set_vertex(self.seq[k], v);
                self.refresh(k, k + 1);
                for q in [k - 1, k + 1] {
                    self.push(q);
                }
            }
        }
    }

    /// Run until no queued stroke has an improving move, or `max_moves` moves.
    pub(crate) fn run(&mut self, max_moves: usize) {
        let mut done = 0;
        while let Some(s) = self.queue.pop_front() {
            self.queued[s] = false;
            if done >= max_moves {
                break;
            }
            if let Some((_, m)) = self.best_move(self.pos[s]) {
                self.apply(m);
                self.push(self.pos[s]);
                done += 1;
            }
        }
        self.queue.clear();
        self.queued.iter_mut().for_each(|q| *q = false);
    }
}

/// Endpoint `id` (`2s` start, `2s + 1` end; a loop's current vertex for both).
fn endpoint(tour: &Tour, id: usize) -> Vec2 {
    let s = id / 2;
    match (tour.is_ring(s), id % 2) {
        (true, _) => tour.ent[s],
        (false, 0) => tour.e[s].start,
        (false, _) => tour.e[s].end,
    }
}
