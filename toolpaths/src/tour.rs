//! The model both the orderer (`order.rs`) and its local search (`improve.rs`) work on: the
//! strokes' fixed [`Ends`], a [`Tour`] of their current entries and exits, XY distance and
//! the bucket size for endpoint searches.

use crate::geom::{norm, sub, Vec2};

/// A stroke as the orderer sees it: entry and exit in machine XY, or for a closed loop the
/// vertices where it may be entered.
#[derive(Clone, Debug, PartialEq)]
pub struct Ends {
    /// First point.
    pub start: Vec2,
    /// Last point.
    pub end: Vec2,
    /// For closed loops: candidate entry points (empty for open strokes).
    pub ring: Vec<Vec2>,
}

impl Ends {
    /// An open stroke from `start` to `end`.
    pub fn open(start: Vec2, end: Vec2) -> Ends {
        Ends { start, end, ring: Vec::new() }
    }

    /// A closed loop that may be entered at any of `ring` (non-empty).
    pub fn ring(ring: Vec<Vec2>) -> Ends {
        Ends { start: ring[0], end: ring[0], ring }
    }
}

/// XY distance.
pub(crate) fn d(a: Vec2, b: Vec2) -> f64 {
    norm(sub(a, b))
}

/// Current entry/exit of every stroke.
pub(crate) struct Tour<'a> {
    pub(crate) e: &'a [Ends],
    pub(crate) ent: Vec<Vec2>,
    pub(crate) ext: Vec<Vec2>,
    pub(crate) flipped: Vec<bool>,
    pub(crate) vertex: Vec<Option<usize>>,
}

impl<'a> Tour<'a> {
    pub(crate) fn new(e: &'a [Ends]) -> Tour<'a> {
        Tour {
            e,
            ent: e.iter().map(|x| x.start).collect(),
            ext: e.iter().map(|x| x.end).collect(),
            flipped: vec![false; e.len()],
            vertex: e.iter().map(|x| (!x.ring.is_empty()).then_some(0)).collect(),
        }
    }

    pub(crate) fn is_ring(&self, s: usize) -> bool {
        !self.e[s].ring.is_empty()
    }

    pub(crate) fn set_flip(&mut self, s: usize, f: bool) {
        if self.is_ring(s) {
            return;
        }
        self.flipped[s] = f;
        let (a, b) = (self.e[s].start, self.e[s].end);
        (self.ent[s], self.ext[s]) = if f { (b, a) } else { (a, b) };
    }

    pub(crate) fn set_vertex(&mut self, s: usize, k: usize) {
        self.vertex[s] = Some(k);
        self.ent[s] = self.e[s].ring[k];
        self.ext[s] = self.e[s].ring[k];
    }

    /// Travel from `home` through the strokes in `order`.
    pub(crate) fn length(&self, order: &[usize], home: Vec2) -> f64 {
        let mut pos = home;
        let mut t = 0.0;
        for &s in order {
            t += d(pos, self.ent[s]);
            pos = self.ext[s];
        }
        t
    }
}

/// Bucket size for `items` points spread over their bounding box: about `per` items a cell.
pub(crate) fn cell_size(pts: &[Vec2], items: usize) -> f64 {
    let mut b = [[f64::INFINITY; 2], [f64::NEG_INFINITY; 2]];
    for p in pts {
        for k in 0..2 {
            b[0][k] = b[0][k].min(p[k]);
            b[1][k] = b[1][k].max(p[k]);
        }
    }
    let (w, h) = ((b[1][0] - b[0][0]).max(0.0), (b[1][1] - b[0][1]).max(0.0));
    // A thin or collinear set (strokes all starting on one edge) has almost no area: size the
    // cells as if the points were spread over a band of width len/items, so that a cell holds
    // about two points rather than the grid degenerating to thousands of empty cells.
    let len = w.max(h);
    let items = items.max(1) as f64;
    let area = (w * h).max(len * len / items).max(1e-12);
    (2.0 * area / items).sqrt().max(1e-9)
}

#[cfg(test)]
mod tests {
    use super::cell_size;

    /// Stroke ends on one line (a sheet brushed edge to edge starts every stroke on the same
    /// edge): the cells must hold a couple of points each, not shrink to the 4096-cells-per-side
    /// floor of an arealess box (the bundled kettle's plan phase took 2.3 s instead of 5 ms).
    #[test]
    fn collinear_points_get_cells_of_their_spacing() {
        let pts: Vec<[f64; 2]> = (0..100).map(|i| [0.0, i as f64]).collect();
        let cell = cell_size(&pts, pts.len());
        let spacing = 99.0 / 99.0;
        assert!(cell >= spacing && cell <= 4.0 * spacing, "cell {cell}");
        // A filled square keeps the old size: √(2·area/items).
        let grid: Vec<[f64; 2]> =
            (0..100).map(|i| [(i % 10) as f64 * 10.0, (i / 10) as f64 * 10.0]).collect();
        let c = cell_size(&grid, grid.len());
        assert!((c - (2.0f64 * 90.0 * 90.0 / 100.0).sqrt()).abs() < 1e-9, "cell {c}");
    }
}
