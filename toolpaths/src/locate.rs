//! Point location: barycentric coordinates, a uniform grid over triangle bounding boxes for
//! cold starts, and a straight walk across triangle adjacency for the hot path (every
//! Runge–Kutta stage starts from the triangle of the previous point).
//!
//! The straight walk follows the segment `q → p` and leaves each triangle through the edge
//! the segment crosses first (Devillers, Pion & Teillaud, *Walking in a triangulation*,
//! 2002, §2.1). Unlike the "most negative coordinate" visibility walk it also reports *where*
//! the segment leaves the domain, which the tracer uses to end strokes exactly on the chart
//! boundary.

pub(crate) use crate::geom::barycentric;
use crate::geom::{cross, sub, Vec2};
use crate::grid::FaceGrid;
use crate::mesh::{Domain, NONE};

/// Barycentric tolerance: a point this far outside a triangle still counts as inside.
const INSIDE_EPS: f64 = 1e-12;

/// Outcome of a straight walk from a located point `q` towards `p`.
#[derive(Clone, Copy, Debug, PartialEq)]
pub(crate) enum Walk {
    /// `p` lies in `face` with barycentric coordinates `bary`.
    Inside { face: u32, bary: [f64; 3] },
    /// The segment leaves the domain through boundary edge `edge` (opposite that corner) of
    /// `face`, at parameter `t ∈ [0, 1]` along `q → p`.
    Exit { face: u32, edge: u8, t: f64 },
}

/// Walk from `q` (inside `face`) to `p` across adjacency.
pub(crate) fn walk(dom: &Domain, mut face: u32, q: Vec2, p: Vec2) -> Walk {
    let cap = 64 + dom.tris.len().min(1 << 20);
    for _ in 0..cap {
        let corners = dom.corners(face);
        let lp = barycentric(corners, p);
        if lp.iter().all(|&l| l >= -INSIDE_EPS) {
            return Walk::Inside { face, bary: lp };
        }
        let lq = barycentric(corners, q);
        let mut best: Option<(f64, usize)> = None;
        for i in 0..3 {
            if lp[i] < -INSIDE_EPS && lq[i] > lp[i] {
                let t = lq[i] / (lq[i] - lp[i]);
                if best.is_none_or(|(bt, _)| t < bt) {
                    best = Some((t, i));
                }
            }
        }
        let (t, edge) = best.unwrap_or_else(|| {
            let i = (0..3).min_by(|&a, &b| lp[a].total_cmp(&lp[b])).unwrap_or(0);
            (0.0, i)
        });
        let next = dom.neighbors[face as usize][edge];
        if next == NONE {
            return Walk::Exit { face, edge: edge as u8, t: t.clamp(0.0, 1.0) };
        }
        face = next;
    }
    // Degenerate cycling (should not happen on a valid mesh): fall back to the grid.
    match dom.grid.locate(dom, p) {
        Some((face, bary)) => Walk::Inside { face, bary },
        None => Walk::Exit { face, edge: 0, t: 0.0 },
    }
}

impl FaceGrid {
    /// The face containing `p` (the lowest face index wins on shared edges), or `None`
    /// when `p` is outside the domain.
    pub(crate) fn locate(&self, dom: &Domain, p: Vec2) -> Option<(u32, [f64; 3])> {
        self.locate_in(dom, p, None)
    }

    /// As [`FaceGrid::locate`], among the faces of chart `chart` only (when given): where
    /// charts overlap in UV, each is located separately.
    pub(crate) fn locate_in(
        &self,
        dom: &Domain,
        p: Vec2,
        chart: Option<u32>,
    ) -> Option<(u32, [f64; 3])> {
        let fx = (p[0] - self.origin[0]) * self.inv_cell;
        let fy = (p[1] - self.origin[1]) * self.inv_cell;
        if !(fx >= -1e-9
            && fy >= -1e-9
            && fx <= self.nx as f64 + 1e-9
            && fy <= self.ny as f64 + 1e-9)
        {
            return None;
        }
        let x = (fx as usize).min(self.nx - 1);
        let y = (fy as usize).min(self.ny - 1);
        let c = y * self.nx + x;
        let mut best: Option<(u32, [f64; 3], f64)> = None;
        for &f in &self.faces[self.start[c] as usize..self.start[c + 1] as usize] {
            if chart.is_some_and(|k| dom.chart[f as usize] != k) {
                continue;
            }
            let b = barycentric(dom.corners(f), p);
            let m = b[0].min(b[1]).min(b[2]);
            if m >= -INSIDE_EPS && best.is_none_or(|(_, _, bm)| m > bm + 1e-15) {
                best = Some((f, b, m));
                if m > 1e-9 {
                    break;
                }
            }
        }
        best.map(|(f, b, _)| (f, b))
    }
}

/// Where a march along the surface ends.
#[derive(Clone, Copy, Debug, PartialEq)]
pub(crate) enum March {
    /// The full distance fits: the end point and its face.
    Inside { p: Vec2, face: u32 },
    /// The path leaves the domain after `travelled` surface mm, at `p` on a boundary edge
    /// of `face`.
    Exit { p: Vec2, face: u32, travelled: f64 },
}

/// March `dist` surface mm from `p` (in face `f`) along the straightest path on the
/// piecewise-linear surface with initial UV direction `dir`, each triangle measured with its
/// own metric `metric(face)`.
///
/// Inside a triangle the path is a UV straight line (the lift is affine there). Crossing an
/// interior edge with UV vector `e`, the path keeps its angle to the edge on the surface
/// (unfolding the two triangles: the discrete straightest geodesic of Polthier & Schmies,
/// *Straightest geodesics on polyhedral surfaces*, 1998): with `cos θ = I_f(d, e) /
/// (|d|_f |e|_f)`, the new direction is `cos θ ê + sin θ m`, where `ê = e / |e|_g` and `m`
/// is the `I_g`-unit normal of `e` on the side the path enters (eq. M1).
pub(crate) fn march(
    dom: &Domain,
    metric: impl Fn(u32) -> crate::geom::Metric,
    mut f: u32,
    mut p: Vec2,
    dir: Vec2,
    dist: f64,
) -> March {
    use crate::geom::{add, scale};
    let mut left = dist;
    let l0 = metric(f).length(dir);
    if !(l0 > 0.0 && dist >= 0.0) {
        return March::Inside { p, face: f };
    }
    let mut n = scale(dir, 1.0 / l0);
    for _ in 0..4096 + dom.tris.len().min(1 << 16) {
        let c = dom.corners(f);
        let lp = barycentric(c, p);
        let lq = barycentric(c, add(p, n));
        let mut best = (f64::INFINITY, 3usize);
        let dls = [0, 1, 2].map(|i| lq[i] - lp[i]);
        // A path running along an edge (a chart border) does not cross it.
        let tiny = 1e-12 * (dls[0].abs() + dls[1].abs() + dls[2].abs());
        for i in 0..3 {
            let dl = dls[i];
            if dl < -tiny {
                let t = lp[i].max(0.0) / -dl;
                if t < best.0 {
                    best = (t, i);
                }
            }
        }
        let mf = metric(f);
        let ln = mf.length(n);
        if ln.is_nan() || ln <= 0.0 || best.1 == 3 {
            break;
        }
        let t_end = left / ln;
        if t_end <= best.0 {
            return March::Inside { p: add(p, scale(n, t_end)), face: f };
        }
        let (t, e) = best;
        p = add(p, scale(n, t));
        left -= t * ln;
        let g = dom.neighbors[f as usize][e];
        if g == NONE {
            return March::Exit { p, face: f, travelled: dist - left.max(0.0) };
        }
        let tv = dom.tris[f as usize];
        let ev = sub(dom.uv[tv[(e + 2) % 3] as usize], dom.uv[tv[(e + 1) % 3] as usize]);
        let mg = metric(g);
        let (le_f, le_g) = (mf.length(ev), mg.length(ev));
        if !(le_f > 0.0 && le_g > 0.0) {
            break;
        }
        // Eq. M1.
        let cos = (mf.inner(n, ev) / (ln * le_f)).clamp(-1.0, 1.0);
        let sin = (1.0 - cos * cos).max(0.0).sqrt();
        let eh = scale(ev, 1.0 / le_g);
        let mut m = mg.unit_normal(eh);
        if cross(ev, m) * cross(ev, n) < 0.0 {
            m = [-m[0], -m[1]];
        }
        n = add(scale(eh, cos), scale(m, sin));
        f = g;
    }
    March::Exit { p, face: f, travelled: dist - left.max(0.0) }
}
