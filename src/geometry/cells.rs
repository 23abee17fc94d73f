//! Segments in space listed under the cells of a sparse uniform grid: the one grid of the edit
//! tools' resolution (`edit::resolution`) and the fidelity measure (`fidelity::grid`), which
//! differ only in how they size the cells, list a segment and search.

use std::collections::HashMap;

use nalgebra::Vector3;

/// Segment indices under cubic cells of side `cell`, counted from `origin`; only the cells that
/// hold a segment are stored.
#[derive(Clone, Debug)]
pub(crate) struct SegmentCells {
    origin: Vector3<f64>,
    cell: f64,
    cells: HashMap<[i64; 3], Vec<u32>>,
}

impl SegmentCells {
    /// An empty grid of cells of side `cell` (finite and positive) counted from `origin`.
    pub(crate) fn new(origin: Vector3<f64>, cell: f64) -> Self {
        SegmentCells { origin, cell, cells: HashMap::new() }
    }

    /// The cells' side.
    pub(crate) fn cell(&self) -> f64 {
        self.cell
    }

    /// The key of the cell holding `p`: ⌊(p − origin) / cell⌋ per axis, within ±10¹⁵ (0 for a
    /// coordinate that is not finite).
    pub(crate) fn key(&self, p: &Vector3<f64>) -> [i64; 3] {
        ((p - self.origin) / self.cell)
            .map(|q| {
                let c = q.floor();
                if c.is_finite() {
                    c.clamp(-1e15, 1e15) as i64
                } else {
                    0
                }
            })
            .into()
    }

    /// Lists segment `k` from `a` to `b` under every cell of the box of its ends' cells.
    pub(crate) fn insert_box(&mut self, k: u32, a: &Vector3<f64>, b: &Vector3<f64>) {
        let (lo, hi) = (self.key(&a.inf(b)), self.key(&a.sup(b)));
        for i in lo[0]..=hi[0] {
            for j in lo[1]..=hi[1] {
                for l in lo[2]..=hi[2] {
                    self.cells.entry([i, j, l]).or_default().push(k);
                }
            }
        }
    }

    /// Lists segment `k` from `a` to `b` under the cells of its samples every half cell (its
    /// ends among them): a point within `d` of the segment is within `d` + ¼ cell of a sample.
    pub(crate) fn insert_along(&mut self, k: u32, a: &Vector3<f64>, b: &Vector3<f64>) {
        let n = ((b - a).norm() / (0.5 * self.cell)).ceil().max(1.0) as usize;
        for j in 0..=n {
            let key = self.key(&(a + (b - a) * (j as f64 / n as f64)));
            let bucket = self.cells.entry(key).or_default();
            if bucket.last() != Some(&k) {
                bucket.push(k);
            }
        }
    }

    /// The segments listed under the cell `key`.
    pub(crate) fn get(&self, key: &[i64; 3]) -> &[u32] {
        self.cells.get(key).map_or(&[], Vec::as_slice)
    }

    /// The smallest and largest keys of the cells holding a segment, per axis (`i64::MAX` and
    /// `i64::MIN` when there is none).
    pub(crate) fn occupied(&self) -> [[i64; 3]; 2] {
        let mut bounds = [[i64::MAX; 3], [i64::MIN; 3]];
        for k in self.cells.keys() {
            for i in 0..3 {
                bounds[0][i] = bounds[0][i].min(k[i]);
                bounds[1][i] = bounds[1][i].max(k[i]);
            }
        }
        bounds
    }
}
