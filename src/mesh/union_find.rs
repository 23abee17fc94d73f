//! Disjoint sets whose representative is always the smallest element, so labels follow file
//! order and never depend on the order of the unions.

/// Union-find over `0..n` with path halving; the root of a set is its smallest element.
pub(crate) struct UnionFind {
    parent: Vec<u32>,
}

impl UnionFind {
    pub(crate) fn new(n: usize) -> Self {
        UnionFind { parent: (0..n as u32).collect() }
    }

    pub(crate) fn find(&mut self, mut x: u32) -> u32 {
        while self.parent[x as usize] != x {
            let p = self.parent[x as usize];
            self.parent[x as usize] = self.parent[p as usize];
            x = p;
        }
        x
    }

    pub(crate) fn union(&mut self, a: u32, b: u32) {
        let (ra, rb) = (self.find(a), self.find(b));
        if ra != rb {
            let (lo, hi) = if ra < rb { (ra, rb) } else { (rb, ra) };
            self.parent[hi as usize] = lo;
        }
    }

    /// Dense labels `0..k` numbered by each set's smallest element, and `k`.
    pub(crate) fn labels(mut self) -> (Vec<u32>, usize) {
        let n = self.parent.len();
        let mut label = vec![u32::MAX; n];
        let mut k = 0u32;
        for x in 0..n as u32 {
            let r = self.find(x);
            if r == x {
                label[x as usize] = k;
                k += 1;
            } else {
                label[x as usize] = label[r as usize];
            }
        }
        (label, k as usize)
    }
}
