//! Untangling a flattening's small folds (math.md §11.5, "Small folds are untangled").
//!
//! A scan's noise folds its surface over itself in places: tiny triangles whose normals point
//! against their neighbours'. A map that keeps shapes (LSCM, ARAP, BFF) maps such a triangle
//! flipped, and a chart that is otherwise well flattened would be rejected, and cut, for a
//! handful of triangles a thousandth of its area.
//!
//! `untangle` moves the vertices of the flipped triangles (and of interior vertices whose UV
//! angles do not add up to 2π) to the Tutte embedding of their neighbourhood, the vertices
//! around them held where the map put them: each free vertex at the mean of its neighbours,
//!
//! ```text
//! deg(i) u_i − Σ_{j ∈ N(i), j free} u_j = Σ_{j ∈ N(i), j held} u_j        (Eq. U1)
//! ```
//!
//! (W. T. Tutte 1963, "How to draw a graph": inside a convex ring of held vertices the result
//! is an embedding). When a triangle around a free vertex is still flipped, the free set grows
//! by a ring and is solved again, at most [`MAX_RINGS`] times. The free set may cover at most
//! [`MAX_FOLD_SHARE`] of the chart's 3D area: a larger fold is no noise, and the chart is cut
//! as before. The caller checks the whole map again (`distortion::invalid`).

use nalgebra::{Vector2, Vector3};

use super::charts::ChartMesh;
use super::distortion::signed_area;
use super::linsys::Spd;

/// The largest share of a chart's 3D area that untangling may move.
pub const MAX_FOLD_SHARE: f64 = 0.05;

/// The smallest area a moved triangle may keep, relative to the chart's (UV area over 3D
/// area, against the chart's ratio): a Tutte map of a ring that is not convex can squash a
/// triangle to a sliver that is not flipped.
pub const MIN_AREA_RATIO: f64 = 1e-3;

/// Rings grown around the folds before giving up.
pub const MAX_RINGS: usize = 3;

/// The chart's vertex–triangle incidence (compressed rows).
struct Incidence {
    start: Vec<u32>,
    tris: Vec<u32>,
}

impl Incidence {
    fn new(chart: &ChartMesh) -> Self {
        let n = chart.num_vertices();
        let mut start = vec![0u32; n + 1];
        for t in &chart.tris {
            for &v in t {
                start[v as usize + 1] += 1;
            }
        }
        for i in 0..n {
            start[i + 1] += start[i];
        }
        let mut fill = start.clone();
        let mut tris = vec![0u32; 3 * chart.tris.len()];
        for (k, t) in chart.tris.iter().enumerate() {
            for &v in t {
                tris[fill[v as usize] as usize] = k as u32;
                fill[v as usize] += 1;
            }
        }
        Incidence { start, tris }
    }

    fn of(&self, v: usize) -> &[u32] {
        &self.tris[self.start[v] as usize..self.start[v + 1] as usize]
    }
}

/// The 3D area of a chart triangle.
fn area_3d(pos: &[Vector3<f64>], t: &[u32; 3]) -> f64 {
    let p = t.map(|v| pos[v as usize]);
    0.5 * (p[1] - p[0]).cross(&(p[2] - p[0])).norm()
}

/// Whether the map flips a triangle.
fn flipped(chart: &ChartMesh, uv: &[Vector2<f64>], t: usize) -> bool {
    let a = signed_area(chart.tris[t].map(|v| uv[v as usize]));
    a <= 0.0 || a.is_nan()
}

/// The seeds of the free set: the vertices of flipped triangles and the interior vertices
/// whose UV angles do not add up to 2π.
fn seeds(chart: &ChartMesh, uv: &[Vector2<f64>]) -> Vec<bool> {
    let n = chart.num_vertices();
    let mut free = vec![false; n];
    let mut angle_sum = vec![0.0f64; n];
    for (k, t) in chart.tris.iter().enumerate() {
        if flipped(chart, uv, k) {
            t.iter().for_each(|&v| free[v as usize] = true);
        }
        let u = t.map(|v| uv[v as usize]);
        for c in 0..3 {
            let (a, b) = (u[(c + 1) % 3] - u[c], u[(c + 2) % 3] - u[c]);
            angle_sum[t[c] as usize] += a.perp(&b).atan2(a.dot(&b));
        }
    }
    let mut on_boundary = vec![false; n];
    for e in &chart.boundary {
        on_boundary[e[0] as usize] = true;
        on_boundary[e[1] as usize] = true;
    }
    let two_pi = std::f64::consts::TAU;
    for v in 0..n {
        let off = (angle_sum[v] - two_pi).abs();
        if !on_boundary[v] && (off > 1e-6 * two_pi || off.is_nan()) {
            free[v] = true;
        }
    }
    free
}

/// Solves Eq. U1 for the free vertices in place; false when the system cannot be solved.
fn tutte(chart: &ChartMesh, inc: &Incidence, free: &[bool], uv: &mut [Vector2<f64>]) -> bool {
    let ids: Vec<usize> = (0..free.len()).filter(|&v| free[v]).collect();
    let mut index = vec![usize::MAX; free.len()];
    ids.iter().enumerate().for_each(|(k, &v)| index[v] = k);
    let mut entries = Vec::new();
    let mut rhs = vec![vec![0.0; ids.len()], vec![0.0; ids.len()]];
    for (k, &v) in ids.iter().enumerate() {
        // Each neighbour once: the other corners of the incident triangles, deduplicated.
        let mut nbrs: Vec<u32> = inc
            .of(v)
            .iter()
            .flat_map(|&t| chart.tris[t as usize])
            .filter(|&w| w as usize != v)
            .collect();
        nbrs.sort_unstable();
        nbrs.dedup();
        entries.push((k, k, nbrs.len() as f64));
        for &w in &nbrs {
            match index[w as usize] {
                usize::MAX => {
                    rhs[0][k] += uv[w as usize].x;
                    rhs[1][k] += uv[w as usize].y;
                }
                j => entries.push((k, j, -1.0)),
            }
        }
    }
    let Ok(spd) = Spd::factor(ids.len(), entries, "layout (untangle)") else {
        return false;
    };
    spd.solve(&mut rhs);
    for (k, &v) in ids.iter().enumerate() {
        let p = Vector2::new(rhs[0][k], rhs[1][k]);
        if !(p.x.is_finite() && p.y.is_finite()) {
            return false;
        }
        uv[v] = p;
    }
    true
}

/// Whether one of the triangles `tris` keeps less than [`MIN_AREA_RATIO`] of its area in the
/// map, relative to the chart's UV area over its 3D area.
pub(crate) fn squashed(
    chart: &ChartMesh,
    pos: &[Vector3<f64>],
    uv: &[Vector2<f64>],
    tris: impl Iterator<Item = usize>,
) -> bool {
    let area3 = |t: &[u32; 3]| area_3d(pos, t);
    let (mut a3, mut a2) = (0.0, 0.0);
    for t in &chart.tris {
        a3 += area3(t);
        a2 += signed_area(t.map(|v| uv[v as usize])).abs();
    }
    let ratio = a2 / a3;
    let mut tris = tris;
    tris.any(|k| {
        let t = &chart.tris[k];
        let a = signed_area(t.map(|v| uv[v as usize]));
        a < MIN_AREA_RATIO * ratio * area3(t) || a.is_nan()
    })
}

/// Moves the vertices around the map's small folds to the Tutte embedding of their
/// neighbourhood (see the module documentation). True when no triangle around them is
/// flipped any more; `uv` is left unchanged otherwise.
pub(crate) fn untangle(chart: &ChartMesh, pos: &[Vector3<f64>], uv: &mut [Vector2<f64>]) -> bool {
    let mut free = seeds(chart, uv);
    if !free.iter().any(|&f| f) {
        return true;
    }
    let inc = Incidence::new(chart);
    let area = |t: &[u32; 3]| area_3d(pos, t);
    let total: f64 = chart.tris.iter().map(area).sum();
    let n = chart.num_vertices();
    for _ in 0..=MAX_RINGS {
        // The 3D area the free vertices' triangles cover.
        let mut touched = vec![false; chart.tris.len()];
        (0..n).filter(|&v| free[v]).for_each(|v| {
            inc.of(v).iter().for_each(|&t| touched[t as usize] = true);
        });
        let moved: f64 =
            chart.tris.iter().zip(&touched).filter(|(_, &t)| t).map(|(t, _)| area(t)).sum();
        if moved > MAX_FOLD_SHARE * total || moved.is_nan() || free.iter().all(|&f| f) {
            return false;
        }
        let mut trial = uv.to_vec();
        if !tutte(chart, &inc, &free, &mut trial) {
            return false;
        }
        let bad = (0..chart.tris.len()).any(|t| touched[t] && flipped(chart, &trial, t));
        if !bad && !squashed(chart, pos, &trial, (0..chart.tris.len()).filter(|&t| touched[t])) {
            uv.copy_from_slice(&trial);
            return true;
        }
        // Grow the free set by a ring around the free vertices.
        let grow: Vec<u32> = (0..n)
            .filter(|&v| free[v])
            .flat_map(|v| inc.of(v).iter().flat_map(|&t| chart.tris[t as usize]))
            .collect();
        grow.into_iter().for_each(|w| free[w as usize] = true);
    }
    false
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::generate::{plane, Grid};
    use crate::layout::distortion::invalid;
    use crate::mesh::halfedge::HalfEdges;

    /// A flat 20 × 20 grid as one chart, its positions, and the identity map (u, v) = (x, y).
    fn sheet() -> (ChartMesh, Vec<Vector3<f64>>, Vec<Vector2<f64>>) {
        let mesh = plane(10.0, Grid::new(20, 20));
        let he = HalfEdges::new(mesh.num_vertices(), &mesh.faces).unwrap();
        let ids: Vec<u32> = (0..mesh.num_faces() as u32).collect();
        let tag = vec![0u32; ids.len()];
        let chart = ChartMesh::new(&ids, &he, &mesh, &tag, &ids, 0);
        let pos = chart.positions(&mesh);
        let uv = pos.iter().map(|p| Vector2::new(p.x, p.y)).collect();
        (chart, pos, uv)
    }

    /// The chart vertex nearest `(x, y)`.
    fn nearest(pos: &[Vector3<f64>], x: f64, y: f64) -> usize {
        let d = |v: usize| (pos[v].x - x).powi(2) + (pos[v].y - y).powi(2);
        (0..pos.len()).min_by(|&a, &b| d(a).total_cmp(&d(b))).unwrap()
    }

    #[test]
    fn a_small_fold_is_untangled_and_the_rest_of_the_map_kept() {
        let (chart, pos, mut uv) = sheet();
        assert!(invalid(&chart, &uv).is_none());
        // Push one interior vertex 1.5 cells across its neighbours: its fan folds over.
        let v = nearest(&pos, 0.0, 0.0);
        uv[v] += Vector2::new(1.5, 0.4);
        assert!(invalid(&chart, &uv).is_some(), "the fold makes the map invalid");
        let before = uv.clone();
        assert!(untangle(&chart, &pos, &mut uv));
        assert_eq!(invalid(&chart, &uv), None);
        // Vertices more than four cells away (past the rings the free set may grow by) keep
        // their place exactly; the moved vertex went back inside its ring.
        for (w, p) in pos.iter().enumerate() {
            if (p.x.powi(2) + p.y.powi(2)).sqrt() > 4.5 {
                assert_eq!(uv[w], before[w], "vertex {w} at {p:?} moved");
            }
        }
        assert!(uv[v].norm() < 1.0, "{:?}", uv[v]);
    }

    #[test]
    fn a_fold_over_much_of_the_chart_is_left_for_the_cutting() {
        let (chart, pos, mut uv) = sheet();
        // Mirror a third of the sheet: a fold far beyond MAX_FOLD_SHARE of its area.
        for (w, p) in pos.iter().enumerate() {
            if p.x > 3.0 {
                uv[w].x = 6.0 - p.x;
            }
        }
        assert!(invalid(&chart, &uv).is_some());
        let before = uv.clone();
        assert!(!untangle(&chart, &pos, &mut uv));
        assert_eq!(uv, before, "a map that cannot be untangled is left as it was");
    }
}
