//! A uniform grid over a curve edit's segments, so that finding the segments near a vertex
//! costs about the segments near it rather than all of them: a curve's cost is linear in its
//! points (a zigzag of 2,000 points over the kettle took 24 s when every vertex was compared
//! with every segment).
//!
//! Each segment is sampled every quarter cell and listed in the cells of its samples; a point
//! within `reach` of a segment is within `reach` + ¼ cell of one of its samples, so the cells
//! within that distance of the point hold every segment that can be within `reach` of it. The
//! candidates come out in ascending segment order, so that a search over them meets the
//! segments in the same order as a search over all of them (and keeps the same one on ties).
//! The cell is at least the caller's `min_cell`, and large enough that the samples number at
//! most 4 × 10⁶ + 8 per segment.

use std::collections::HashMap;

/// Segments of one curve edit in a uniform grid (`D` = 2 for UV curves, 3 for 3D ones).
pub(super) struct SegmentGrid<const D: usize> {
    origin: [f64; D],
    cell: f64,
    cells: HashMap<[i64; D], Vec<u32>>,
}

fn distance<const D: usize>(a: &[f64; D], b: &[f64; D]) -> f64 {
    (0..D).map(|k| (b[k] - a[k]).powi(2)).sum::<f64>().sqrt()
}

impl<const D: usize> SegmentGrid<D> {
    /// The grid of `segments` (their index in this list is what [`Self::near`] returns).
    pub(super) fn new(segments: &[([f64; D], [f64; D])], min_cell: f64) -> Self {
        let total: f64 = segments.iter().map(|(a, b)| distance(a, b)).sum();
        let cap = 4e6 + 8.0 * segments.len() as f64;
        let mut cell = min_cell.max(4.0 * total / cap);
        if !(cell.is_finite() && cell > 0.0) {
            cell = total.max(1.0);
        }
        let mut origin = [f64::INFINITY; D];
        for (a, b) in segments {
            for k in 0..D {
                origin[k] = origin[k].min(a[k]).min(b[k]);
            }
        }
        let mut grid = SegmentGrid { origin, cell, cells: HashMap::new() };
        let step = cell / 4.0;
        for (i, (a, b)) in segments.iter().enumerate() {
            let n = (distance(a, b) / step).ceil().clamp(1.0, cap) as usize;
            for j in 0..=n {
                let t = j as f64 / n as f64;
                let p: [f64; D] = std::array::from_fn(|k| a[k] + t * (b[k] - a[k]));
                let list = grid.cells.entry(grid.key(&p)).or_default();
                if list.last() != Some(&(i as u32)) {
                    list.push(i as u32);
                }
            }
        }
        grid
    }

    fn key(&self, p: &[f64; D]) -> [i64; D] {
        std::array::from_fn(|k| ((p[k] - self.origin[k]) / self.cell).floor() as i64)
    }

    /// The segments that may be within `reach` of `p` (Euclidean), ascending, each once,
    /// into `out` (cleared first).
    pub(super) fn near(&self, p: &[f64; D], reach: f64, out: &mut Vec<u32>) {
        out.clear();
        let r = reach + 0.25 * self.cell;
        let lo = self.key(&std::array::from_fn(|k| p[k] - r));
        let hi = self.key(&std::array::from_fn(|k| p[k] + r));
        let boxed: f64 = (0..D).map(|k| (hi[k] - lo[k] + 1) as f64).product();
        if boxed > self.cells.len() as f64 {
            // A reach wider than the curve: the occupied cells are fewer than the box's.
            for (key, list) in &self.cells {
                if (0..D).all(|k| lo[k] <= key[k] && key[k] <= hi[k]) {
                    out.extend_from_slice(list);
                }
            }
        } else {
            let mut key = lo;
            loop {
                if let Some(list) = self.cells.get(&key) {
                    out.extend_from_slice(list);
                }
                // The next cell of the box, the first coordinate fastest.
                let mut k = 0;
                while k < D && key[k] == hi[k] {
                    key[k] = lo[k];
                    k += 1;
                }
                if k == D {
                    break;
                }
                key[k] += 1;
            }
        }
        out.sort_unstable();
        out.dedup();
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The grid's candidates hold every segment within the reach, against brute force.
    #[test]
    fn candidates_hold_every_segment_within_reach() {
        let mut seed = 7u64;
        let mut rnd = || {
            seed = seed.wrapping_mul(6364136223846793005).wrapping_add(1442695040888963407);
            (seed >> 11) as f64 / (1u64 << 53) as f64
        };
        let segs: Vec<([f64; 2], [f64; 2])> = (0..300)
            .map(|_| ([rnd() * 10.0, rnd() * 10.0], [rnd() * 10.0, rnd() * 10.0]))
            .collect();
        for min_cell in [0.05, 0.5, 5.0] {
            let grid = SegmentGrid::new(&segs, min_cell);
            let mut near = Vec::new();
            for _ in 0..200 {
                let p = [rnd() * 12.0 - 1.0, rnd() * 12.0 - 1.0];
                let reach = rnd() * 2.0;
                grid.near(&p, reach, &mut near);
                assert!(near.windows(2).all(|w| w[0] < w[1]));
                for (i, (a, b)) in segs.iter().enumerate() {
                    let e = [b[0] - a[0], b[1] - a[1]];
                    let ee = e[0] * e[0] + e[1] * e[1];
                    let t = (((p[0] - a[0]) * e[0] + (p[1] - a[1]) * e[1]) / ee).clamp(0.0, 1.0);
                    let q = [a[0] + t * e[0], a[1] + t * e[1]];
                    if distance(&p, &q) < reach {
                        assert!(near.contains(&(i as u32)), "segment {i} missed at {p:?}");
                    }
                }
            }
        }
    }
}
