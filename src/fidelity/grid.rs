//! Spatial queries for the fidelity measure: nearest segments (a sparse grid of 3D cells) and
//! point-in-triangle tests for planar triangles (a dense grid of 2D cells).

use nalgebra::{Vector2, Vector3};

use crate::edit::support::barycentric;
use crate::geometry::cells::SegmentCells;

/// Nearest-segment queries: segments bucketed in a sparse uniform grid.
pub(super) struct SegmentGrid {
    segs: Vec<[Vector3<f64>; 2]>,
    /// Per segment, the unit normal of the face it lies on (distances are then measured in
    /// that face's plane, leaving out the offset along the normal), or zero (in space).
    normals: Vec<Vector3<f64>>,
    /// Each segment under every cell its box meets, counted from the origin.
    cells: SegmentCells,
    /// Rings of cells [`SegmentGrid::nearest`] visits past the one that settles the distance:
    /// one when distances are measured in the faces' planes (they can be a little shorter).
    slack: f64,
    /// The smallest and largest cell keys holding a segment, per axis (queries visit no cell
    /// beyond them: a flat set of segments is searched in its plane only).
    bounds: [[i64; 3]; 2],
}

impl SegmentGrid {
    /// `reach`: the largest distance queries care about (the cell is twice the mean segment's
    /// length but at least reach/32, so a query visits at most 65³ cells, and no more than
    /// the occupied cells' box holds: a noisy zero set of many short segments is not searched
    /// a few hundred segments per cell).
    pub(super) fn new(segs: Vec<[Vector3<f64>; 2]>, reach: f64) -> Self {
        let mean = if segs.is_empty() {
            0.0
        } else {
            segs.iter().map(|s| (s[1] - s[0]).norm()).sum::<f64>() / segs.len() as f64
        };
        let cell = (2.0 * mean).max(reach / 32.0).max(1e-12);
        let mut cells = SegmentCells::new(Vector3::zeros(), cell);
        for (k, s) in segs.iter().enumerate() {
            cells.insert_box(k as u32, &s[0], &s[1]);
        }
        let normals = vec![Vector3::zeros(); segs.len()];
        let bounds = cells.occupied();
        SegmentGrid { segs, normals, cells, slack: 0.0, bounds }
    }

    /// A grid whose distances are measured in the plane of each segment's face (`normals`, one
    /// unit normal per segment).
    pub(super) fn in_planes(
        segs: Vec<[Vector3<f64>; 2]>,
        normals: Vec<Vector3<f64>>,
        reach: f64,
    ) -> Self {
        let mut g = SegmentGrid::new(segs, reach);
        if normals.len() == g.segs.len() {
            g.slack = if normals.iter().any(|n| n.norm_squared() > 0.0) { 1.0 } else { 0.0 };
            g.normals = normals;
        }
        g
    }

    /// The distance from `p` to the nearest segment, or `cap` if none is closer.
    pub(super) fn nearest(&self, p: &Vector3<f64>, cap: f64) -> f64 {
        if self.segs.is_empty() {
            return cap;
        }
        let (c, cell) = (self.cells.key(p), self.cells.cell());
        let mut best = cap;
        let rings = (cap / cell).ceil().max(1.0) as i64 + 1;
        // The offsets from c along axis `a` that reach an occupied cell, within `ring`.
        let [lo, hi] = self.bounds;
        let range = |a: usize, ring: i64| {
            (-ring).max(lo[a].saturating_sub(c[a]))..=ring.min(hi[a].saturating_sub(c[a]))
        };
        for ring in 0..=rings {
            // Cells of Chebyshev distance `ring` from c.
            for i in range(0, ring) {
                for j in range(1, ring) {
                    for l in range(2, ring) {
                        if i.abs().max(j.abs()).max(l.abs()) != ring {
                            continue;
                        }
                        for &k in self.cells.get(&[c[0] + i, c[1] + j, c[2] + l]) {
                            let s = &self.segs[k as usize];
                            let n = &self.normals[k as usize];
                            let q = p - n * (p - s[0]).dot(n);
                            best = best.min(point_segment_distance(&q, &s[0], &s[1]));
                        }
                    }
                }
            }
            // Every cell of a later ring is at least ring·cell away from p (one ring more when
            // distances are measured in the faces' planes, which can be a little shorter).
            if best <= (ring as f64 - self.slack) * cell {
                break;
            }
        }
        best
    }
}

pub(super) fn point_segment_distance(p: &Vector3<f64>, a: &Vector3<f64>, b: &Vector3<f64>) -> f64 {
    let e = b - a;
    let ee = e.norm_squared();
    let t = if ee > 0.0 { ((p - a).dot(&e) / ee).clamp(0.0, 1.0) } else { 0.0 };
    (a + e * t - p).norm()
}

/// Point-in-triangle queries for planar triangles: each triangle listed under the cells of a
/// uniform grid over the chart that its box covers (cells about the mean triangle's size, at
/// most 256 per axis); a triangle covering more than [`TriangleGrid::WIDE`] cells (a sliver along
/// the brush) is kept apart and tried for every query.
pub(super) struct TriangleGrid<'a> {
    tris: &'a [[Vector2<f64>; 3]],
    lo: Vector2<f64>,
    cell: f64,
    n: [usize; 2],
    cells: Vec<Vec<u32>>,
    wide: Vec<u32>,
}

impl<'a> TriangleGrid<'a> {
    const WIDE: usize = 64;

    pub(super) fn new(tris: &'a [[Vector2<f64>; 3]]) -> Self {
        let finite = |t: &&[Vector2<f64>; 3]| t.iter().all(|p| p.iter().all(|c| c.is_finite()));
        let (mut lo, mut hi) = (Vector2::repeat(f64::INFINITY), Vector2::repeat(-f64::INFINITY));
        let mut size = 0.0;
        for t in tris.iter().filter(finite) {
            for p in t {
                lo = lo.inf(p);
                hi = hi.sup(p);
            }
            size += (t[1] - t[0]).norm() + (t[2] - t[1]).norm() + (t[0] - t[2]).norm();
        }
        let count = tris.iter().filter(finite).count().max(1) as f64;
        let span = (hi - lo).max();
        let cell = (size / (3.0 * count)).max(span / 256.0);
        let mut grid =
            TriangleGrid { tris, lo, cell, n: [0, 0], cells: Vec::new(), wide: Vec::new() };
        if !(cell.is_finite() && cell > 0.0) {
            grid.wide = (0..tris.len() as u32).collect();
            return grid;
        }
        let n = |i: usize| ((hi[i] - lo[i]) / cell).floor() as usize + 1;
        grid.n = [n(0), n(1)];
        grid.cells = vec![Vec::new(); grid.n[0] * grid.n[1]];
        for (k, t) in tris.iter().enumerate() {
            if !finite(&t) {
                continue;
            }
            // The box grown by a little more than the barycentric tolerance allows outside.
            let (tlo, thi) = (t[0].inf(&t[1]).inf(&t[2]), t[0].sup(&t[1]).sup(&t[2]));
            let margin = Vector2::repeat(1e-5 * (thi - tlo).norm());
            let (a, b) = (grid.key(&(tlo - margin)), grid.key(&(thi + margin)));
            if (b[0] - a[0] + 1) * (b[1] - a[1] + 1) > Self::WIDE {
                grid.wide.push(k as u32);
                continue;
            }
            for i in a[0]..=b[0] {
                for j in a[1]..=b[1] {
                    grid.cells[i * grid.n[1] + j].push(k as u32);
                }
            }
        }
        grid
    }

    /// The cell of `p`, clamped to the grid.
    fn key(&self, p: &Vector2<f64>) -> [usize; 2] {
        let q = (p - self.lo) / self.cell;
        let at = |x: f64, n: usize| (x.floor().max(0.0) as usize).min(n.saturating_sub(1));
        [at(q.x, self.n[0]), at(q.y, self.n[1])]
    }

    /// Whether planar point `p` lies in one of the triangles (a small tolerance).
    #[cfg(test)]
    pub(super) fn contains(&self, p: &Vector2<f64>) -> bool {
        self.locate(p).is_some()
    }

    /// The first triangle (the wide ones, then the cell's, in order) that holds planar point
    /// `p` within a small tolerance, with `p`'s barycentric coordinates in it.
    pub(super) fn locate(&self, p: &Vector2<f64>) -> Option<(usize, [f64; 3])> {
        let inside = |k: &u32| {
            let b = barycentric(p, &self.tris[*k as usize])?;
            b.iter().all(|&x| x >= -1e-6).then_some((*k as usize, b))
        };
        if let Some(hit) = self.wide.iter().find_map(inside) {
            return Some(hit);
        }
        if self.cells.is_empty() || !p.iter().all(|c| c.is_finite()) {
            return None;
        }
        // A point just outside the grid's box may still be within the tolerance of a triangle
        // on its edge: the clamped cell holds those.
        self.cells[{
            let k = self.key(p);
            k[0] * self.n[1] + k[1]
        }]
        .iter()
        .find_map(inside)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The grid's answer is the brute-force scan's, for a fan of slivers across the chart (kept
    /// apart as wide), a mesh of small triangles, and points inside, outside and on edges.
    #[test]
    fn triangle_grid_agrees_with_brute_force() {
        let mut tris = Vec::new();
        for i in 0..20 {
            for j in 0..20 {
                let (x, y) = (-1.0 + 0.1 * i as f64, -1.0 + 0.1 * j as f64);
                let (a, b, c, d) = (
                    Vector2::new(x, y),
                    Vector2::new(x + 0.1, y),
                    Vector2::new(x + 0.1, y + 0.1),
                    Vector2::new(x, y + 0.1),
                );
                if (i + j) % 7 != 3 {
                    tris.push([a, b, c]);
                    tris.push([a, c, d]);
                }
            }
        }
        for k in 0..8 {
            let t = k as f64 * 0.05;
            tris.push([Vector2::new(1.2, -1.0), Vector2::new(3.0, t), Vector2::new(3.0, t + 0.01)]);
        }
        let grid = TriangleGrid::new(&tris);
        let brute = |p: &Vector2<f64>| {
            tris.iter().any(|t| barycentric(p, t).is_some_and(|b| b.iter().all(|&x| x >= -1e-6)))
        };
        let mut s = 5u64;
        let mut rnd = || {
            s = s.wrapping_mul(6364136223846793005).wrapping_add(1442695040888963407);
            (s >> 11) as f64 / (1u64 << 53) as f64 * 4.0 - 1.5
        };
        let mut inside = 0;
        for k in 0..20000 {
            let p = if k % 5 == 0 {
                // On a grid line: on an edge shared by two triangles, or on the part's border.
                Vector2::new(-1.0 + 0.1 * ((k / 5) % 21) as f64, rnd())
            } else {
                Vector2::new(rnd(), rnd())
            };
            let want = brute(&p);
            assert_eq!(grid.contains(&p), want, "{p:?}");
            inside += want as usize;
        }
        assert!(inside > 3000, "{inside}");
    }
}
