//! A uniform bucket grid over UV for fixed-radius neighbour queries (the "grid for the
//! distance tests" of Jobard & Lefer 1997, §3). Cells are sized near `d_sep`, so a query
//! of radius `d_sep` touches about nine cells.

use crate::geom::Vec2;

/// Most cells a grid may allocate; the cell size grows past this.
const MAX_CELLS: f64 = 4.0e6;

#[derive(Debug, Clone)]
pub(crate) struct PointGrid {
    origin: Vec2,
    inv_cell: f64,
    nx: usize,
    ny: usize,
    cells: Vec<Vec<u32>>,
}

impl PointGrid {
    /// A grid over `bbox` (padded by one cell) with cells of about `cell` UV units.
    pub(crate) fn new(bbox: [Vec2; 2], cell: f64) -> PointGrid {
        let w = (bbox[1][0] - bbox[0][0]).max(1e-12);
        let h = (bbox[1][1] - bbox[0][1]).max(1e-12);
        let min_cell = (w * h / MAX_CELLS).sqrt();
        let cell = cell.max(min_cell).max(1e-12);
        let origin = [bbox[0][0] - cell, bbox[0][1] - cell];
        let nx = (w / cell).ceil() as usize + 3;
        let ny = (h / cell).ceil() as usize + 3;
        PointGrid { origin, inv_cell: 1.0 / cell, nx, ny, cells: vec![Vec::new(); nx * ny] }
    }

    fn cell_of(&self, p: Vec2) -> (isize, isize) {
        (
            ((p[0] - self.origin[0]) * self.inv_cell).floor() as isize,
            ((p[1] - self.origin[1]) * self.inv_cell).floor() as isize,
        )
    }

    /// Insert item `id` at `p` (points outside the padded box go to the border cells).
    pub(crate) fn insert(&mut self, p: Vec2, id: u32) {
        let (x, y) = self.cell_of(p);
        let x = x.clamp(0, self.nx as isize - 1) as usize;
        let y = y.clamp(0, self.ny as isize - 1) as usize;
        self.cells[y * self.nx + x].push(id);
    }

    /// Call `f(id)` for every item in cells within UV distance `r` of `p` (a superset of the
    /// items within `r`), in a fixed order. Stops early when `f` returns `false`.
    pub(crate) fn visit(&self, p: Vec2, r: f64, mut f: impl FnMut(u32) -> bool) {
        let k = (r * self.inv_cell).ceil() as isize;
        let (cx, cy) = self.cell_of(p);
        let x0 = (cx - k).max(0);
        let x1 = (cx + k).min(self.nx as isize - 1);
        let y0 = (cy - k).max(0);
        let y1 = (cy + k).min(self.ny as isize - 1);
        for y in y0..=y1 {
            for x in x0..=x1 {
                for &id in &self.cells[y as usize * self.nx + x as usize] {
                    if !f(id) {
                        return;
                    }
                }
            }
        }
    }
}

/// A uniform grid over 3D points (or UV points embedded at z = 0) for fixed-radius
/// neighbour queries when distances are measured on the part's 3D lift: a dense array of
/// cells over the box `bbox` (padded by one cell), with the cell size grown until there are
/// at most `MAX_CELLS` cells. Points outside the box go to the border cells, so queries stay
/// supersets.
#[derive(Debug, Clone)]
pub(crate) struct Grid3 {
    origin: [f64; 3],
    inv_cell: f64,
    n: [usize; 3],
    cells: Vec<Vec<u32>>,
}

impl Grid3 {
    /// A grid over `bbox` (`[min, max]`) with cubic cells of about `cell`.
    pub(crate) fn new(bbox: [[f64; 3]; 2], cell: f64) -> Grid3 {
        let ext = [0, 1, 2].map(|k| (bbox[1][k] - bbox[0][k]).max(0.0));
        let mut cell = if cell.is_finite() && cell > 1e-12 { cell } else { 1e-12 };
        let count = |c: f64| ext.map(|e| (e / c).ceil() as usize + 3);
        // Grow the cells until the grid is small enough.
        loop {
            let n = count(cell);
            let total = (n[0] as f64) * (n[1] as f64) * (n[2] as f64);
            if total <= MAX_CELLS {
                break;
            }
            cell *= (total / MAX_CELLS).cbrt().max(1.01);
        }
        let n = count(cell);
        let origin = [0, 1, 2].map(|k| bbox[0][k] - cell);
        Grid3 { origin, inv_cell: 1.0 / cell, n, cells: vec![Vec::new(); n[0] * n[1] * n[2]] }
    }

    fn coord(&self, p: [f64; 3]) -> [isize; 3] {
        [0, 1, 2].map(|k| ((p[k] - self.origin[k]) * self.inv_cell).floor() as isize)
    }

    fn clamp(&self, c: [isize; 3]) -> [usize; 3] {
        [0, 1, 2].map(|k| c[k].clamp(0, self.n[k] as isize - 1) as usize)
    }

    fn index(&self, c: [usize; 3]) -> usize {
        (c[2] * self.n[1] + c[1]) * self.n[0] + c[0]
    }

    /// Insert item `id` at `p`.
    pub(crate) fn insert(&mut self, p: [f64; 3], id: u32) {
        let i = self.index(self.clamp(self.coord(p)));
        self.cells[i].push(id);
    }

    /// Empty the cell that holds `p`.
    pub(crate) fn clear_at(&mut self, p: [f64; 3]) {
        let i = self.index(self.clamp(self.coord(p)));
        self.cells[i].clear();
    }

    /// Call `f(id)` for every item in cells within distance `r` of `p` (per axis; a superset
    /// of the items within `r`), in a fixed order. Stops early when `f` returns `false`.
    pub(crate) fn visit(&self, p: [f64; 3], r: f64, mut f: impl FnMut(u32) -> bool) {
        if r.is_nan() || r < 0.0 {
            return;
        }
        let lo = self.clamp(self.coord([p[0] - r, p[1] - r, p[2] - r]));
        let hi = self.clamp(self.coord([p[0] + r, p[1] + r, p[2] + r]));
        for z in lo[2]..=hi[2] {
            for y in lo[1]..=hi[1] {
                let row = (z * self.n[1] + y) * self.n[0];
                for c in &self.cells[row + lo[0]..=row + hi[0]] {
                    for &id in c {
                        if !f(id) {
                            return;
                        }
                    }
                }
            }
        }
    }
}
