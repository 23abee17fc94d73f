//! Nearest-segment queries for the fidelity measure: segments bucketed in a sparse grid.

use std::collections::HashMap;

use nalgebra::Vector3;

/// Nearest-segment queries: segments bucketed in a sparse uniform grid.
pub(super) struct SegmentGrid {
    segs: Vec<[Vector3<f64>; 2]>,
    /// Per segment, the unit normal of the face it lies on (distances are then measured in
    /// that face's plane, leaving out the offset along the normal), or zero (in space).
    normals: Vec<Vector3<f64>>,
    cell: f64,
    cells: HashMap<[i64; 3], Vec<u32>>,
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
        let mut cells: HashMap<[i64; 3], Vec<u32>> = HashMap::new();
        for (k, s) in segs.iter().enumerate() {
            let (lo, hi) = (key(&s[0].inf(&s[1]), cell), key(&s[0].sup(&s[1]), cell));
            for i in lo[0]..=hi[0] {
                for j in lo[1]..=hi[1] {
                    for l in lo[2]..=hi[2] {
                        cells.entry([i, j, l]).or_default().push(k as u32);
                    }
                }
            }
        }
        let normals = vec![Vector3::zeros(); segs.len()];
        let mut bounds = [[i64::MAX; 3], [i64::MIN; 3]];
        for k in cells.keys() {
            for i in 0..3 {
                bounds[0][i] = bounds[0][i].min(k[i]);
                bounds[1][i] = bounds[1][i].max(k[i]);
            }
        }
        SegmentGrid { segs, normals, cell, cells, slack: 0.0, bounds }
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
        let c = key(p, self.cell);
        let mut best = cap;
        let rings = (cap / self.cell).ceil().max(1.0) as i64 + 1;
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
                        let Some(list) = self.cells.get(&[c[0] + i, c[1] + j, c[2] + l]) else {
                            continue;
                        };
                        for &k in list {
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
            if best <= (ring as f64 - self.slack) * self.cell {
                break;
            }
        }
        best
    }
}

fn key(p: &Vector3<f64>, cell: f64) -> [i64; 3] {
    p.map(|x| {
        let c = (x / cell).floor();
        if c.is_finite() {
            c.clamp(-1e15, 1e15) as i64
        } else {
            0
        }
    })
    .into()
}

pub(super) fn point_segment_distance(p: &Vector3<f64>, a: &Vector3<f64>, b: &Vector3<f64>) -> f64 {
    let e = b - a;
    let ee = e.norm_squared();
    let t = if ee > 0.0 { ((p - a).dot(&e) / ee).clamp(0.0, 1.0) } else { 0.0 };
    (a + e * t - p).norm()
}
