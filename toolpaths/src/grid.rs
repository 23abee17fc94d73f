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

/// A hashed uniform grid over 3D points (or UV points embedded at z = 0) for fixed-radius
/// neighbour queries when distances are measured on the part's 3D lift. Only the occupied
/// cells are stored, so a large part with small cells costs memory in proportion to its
/// points. Lookups never iterate the hash map, so results do not depend on the hasher.
#[derive(Debug, Clone)]
pub(crate) struct HashGrid3 {
    inv_cell: f64,
    cells: std::collections::HashMap<[i64; 3], Vec<u32>, std::hash::BuildHasherDefault<Mix>>,
}

/// A small multiplicative hasher for cell keys (FxHash's constant).
#[derive(Default, Clone, Copy, Debug)]
pub(crate) struct Mix(u64);

impl std::hash::Hasher for Mix {
    fn finish(&self) -> u64 {
        self.0
    }
    fn write(&mut self, bytes: &[u8]) {
        for &b in bytes {
            self.write_u64(b as u64);
        }
    }
    fn write_i64(&mut self, x: i64) {
        self.write_u64(x as u64);
    }
    fn write_u64(&mut self, x: u64) {
        self.0 = (self.0.rotate_left(5) ^ x).wrapping_mul(0x51_7c_c1_b7_27_22_0a_95);
    }
    fn write_usize(&mut self, x: usize) {
        self.write_u64(x as u64);
    }
}

impl HashGrid3 {
    /// A grid with cubic cells of edge `cell` (clamped to a tiny positive value).
    pub(crate) fn new(cell: f64) -> HashGrid3 {
        let cell = if cell.is_finite() && cell > 1e-12 { cell } else { 1e-12 };
        HashGrid3 { inv_cell: 1.0 / cell, cells: Default::default() }
    }

    fn key(&self, p: [f64; 3]) -> [i64; 3] {
        // Saturating float-to-int casts keep far-away or non-finite points in border cells.
        p.map(|x| (x * self.inv_cell).floor() as i64)
    }

    /// Insert item `id` at `p`.
    pub(crate) fn insert(&mut self, p: [f64; 3], id: u32) {
        let k = self.key(p);
        self.cells.entry(k).or_default().push(id);
    }

    /// Empty the cell that holds `p`.
    pub(crate) fn clear_at(&mut self, p: [f64; 3]) {
        let k = self.key(p);
        if let Some(c) = self.cells.get_mut(&k) {
            c.clear();
        }
    }

    /// Call `f(id)` for every item in cells within distance `r` of `p` (per axis; a superset
    /// of the items within `r`), in a fixed order. Stops early when `f` returns `false`.
    pub(crate) fn visit(&self, p: [f64; 3], r: f64, mut f: impl FnMut(u32) -> bool) {
        if !(r >= 0.0) {
            return;
        }
        let lo = self.key([p[0] - r, p[1] - r, p[2] - r]);
        let hi = self.key([p[0] + r, p[1] + r, p[2] + r]);
        for z in lo[2]..=hi[2] {
            for y in lo[1]..=hi[1] {
                for x in lo[0]..=hi[0] {
                    if let Some(c) = self.cells.get(&[x, y, z]) {
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
}
