//! A uniform bucket grid over UV for fixed-radius neighbour queries (the "grid for the
//! distance tests" of Jobard & Lefer 1997, §3). Cells are sized near `d_sep`, so a query
//! of radius `d_sep` touches about nine cells. Also the grid over triangle bounding boxes
//! that point location starts from ([`FaceGrid`]).

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

/// A uniform grid over the UV bounding box; each cell lists the faces whose bounding box
/// overlaps it (CSR layout, ascending face order so lookups are deterministic). Point
/// location in it ([`FaceGrid::locate`]) is in `locate.rs`.
#[derive(Debug)]
pub(crate) struct FaceGrid {
    pub(crate) origin: Vec2,
    pub(crate) inv_cell: f64,
    pub(crate) nx: usize,
    pub(crate) ny: usize,
    pub(crate) start: Vec<u32>,
    pub(crate) faces: Vec<u32>,
}

impl FaceGrid {
    pub(crate) fn new(uv: &[Vec2], tris: &[[u32; 3]], bbox: [Vec2; 2]) -> FaceGrid {
        let w = (bbox[1][0] - bbox[0][0]).max(1e-300);
        let h = (bbox[1][1] - bbox[0][1]).max(1e-300);
        let target = (tris.len() as f64).clamp(1.0, 4e6);
        let cell = (w * h / target).sqrt().max(w.max(h) / 4096.0);
        let nx = ((w / cell).ceil() as usize).max(1);
        let ny = ((h / cell).ceil() as usize).max(1);
        let inv_cell = 1.0 / cell;
        let range = |t: &[u32; 3]| {
            let ps = t.map(|v| uv[v as usize]);
            let lo = [0, 1].map(|k| ps.iter().map(|p| p[k]).fold(f64::INFINITY, f64::min));
            let hi = [0, 1].map(|k| ps.iter().map(|p| p[k]).fold(f64::NEG_INFINITY, f64::max));
            let cx = |x: f64, o: f64, n: usize| (((x - o) * inv_cell) as usize).min(n - 1);
            (
                cx(lo[0], bbox[0][0], nx),
                cx(hi[0], bbox[0][0], nx),
                cx(lo[1], bbox[0][1], ny),
                cx(hi[1], bbox[0][1], ny),
            )
        };
        let mut count = vec![0u32; nx * ny + 1];
        for t in tris {
            let (x0, x1, y0, y1) = range(t);
            for y in y0..=y1 {
                for x in x0..=x1 {
                    count[y * nx + x + 1] += 1;
                }
            }
        }
        for i in 1..count.len() {
            count[i] += count[i - 1];
        }
        let mut fill = count.clone();
        let mut faces = vec![0u32; count[nx * ny] as usize];
        for (f, t) in tris.iter().enumerate() {
            let (x0, x1, y0, y1) = range(t);
            for y in y0..=y1 {
                for x in x0..=x1 {
                    let c = y * nx + x;
                    faces[fill[c] as usize] = f as u32;
                    fill[c] += 1;
                }
            }
        }
        FaceGrid { origin: bbox[0], inv_cell, nx, ny, start: count, faces }
    }

    /// Faces whose bounding box overlaps the grid cell of `p` (empty outside the grid).
    pub(crate) fn faces_near(&self, p: Vec2) -> &[u32] {
        let fx = (p[0] - self.origin[0]) * self.inv_cell;
        let fy = (p[1] - self.origin[1]) * self.inv_cell;
        if !(fx >= 0.0 && fy >= 0.0) {
            return &[];
        }
        let x = (fx as usize).min(self.nx - 1);
        let y = (fy as usize).min(self.ny - 1);
        let c = y * self.nx + x;
        &self.faces[self.start[c] as usize..self.start[c + 1] as usize]
    }
}
