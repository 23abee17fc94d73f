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

    /// Empty the cell that holds `p` (the inverse of every `insert` at points of that cell).
    pub(crate) fn clear_at(&mut self, p: Vec2) {
        let (x, y) = self.cell_of(p);
        let x = x.clamp(0, self.nx as isize - 1) as usize;
        let y = y.clamp(0, self.ny as isize - 1) as usize;
        self.cells[y * self.nx + x].clear();
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
