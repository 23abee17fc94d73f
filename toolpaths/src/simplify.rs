//! Polyline simplification (Ramer–Douglas–Peucker) and arc fitting for G2/G3.
//!
//! * RDP (Ramer 1972; Douglas & Peucker 1973) keeps the fewest vertices such that every
//!   dropped vertex lies within `tolerance` (mm, in machine space) of the kept polyline.
//! * Arc fitting: a run of at least [`MIN_ARC_POINTS`] consecutive points becomes one arc when
//!   every point lies within `tolerance` of the circle through the run's first, middle and
//!   last points, the points turn monotonically about its centre, the sweep is at most π, and
//!   Z stays within `tolerance` of the first point (arcs are planar, G17). The longest such
//!   run from each start is found by doubling then bisection.

use crate::geom::{cross, sub, Vec2, Vec3};

/// Fewest points an arc replaces.
pub const MIN_ARC_POINTS: usize = 5;
/// Arcs with a larger radius than this (mm) are left as lines.
const MAX_ARC_RADIUS: f64 = 5000.0;

/// One machine move from the previous point.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Segment {
    /// Straight move to `to`.
    Line {
        /// End point.
        to: Vec3,
    },
    /// Circular arc in the XY plane to `to` about `center` (Z moves linearly).
    Arc {
        /// End point.
        to: Vec3,
        /// Centre (XY).
        center: Vec2,
        /// Counter-clockwise (G3) or clockwise (G2).
        ccw: bool,
    },
}

impl Segment {
    /// End point of the move.
    pub fn end(&self) -> Vec3 {
        match *self {
            Segment::Line { to } | Segment::Arc { to, .. } => to,
        }
    }
}

fn seg_dist3(p: Vec3, a: Vec3, b: Vec3) -> f64 {
    let ab = crate::geom::sub3(b, a);
    let ap = crate::geom::sub3(p, a);
    let l2 = crate::geom::dot3(ab, ab);
    let t = if l2 > 0.0 { (crate::geom::dot3(ap, ab) / l2).clamp(0.0, 1.0) } else { 0.0 };
    crate::geom::norm3([ap[0] - t * ab[0], ap[1] - t * ab[1], ap[2] - t * ab[2]])
}

/// Indices kept by Ramer–Douglas–Peucker with tolerance `tol` (first and last always kept).
pub fn rdp_indices(pts: &[Vec3], tol: f64) -> Vec<usize> {
    let n = pts.len();
    if n <= 2 {
        return (0..n).collect();
    }
    let mut keep = vec![false; n];
    keep[0] = true;
    keep[n - 1] = true;
    let mut stack = vec![(0usize, n - 1)];
    while let Some((a, b)) = stack.pop() {
        let mut best = (0.0, 0usize);
        for k in a + 1..b {
            let d = seg_dist3(pts[k], pts[a], pts[b]);
            if d > best.0 {
                best = (d, k);
            }
        }
        if best.0 > tol {
            keep[best.1] = true;
            stack.push((a, best.1));
            stack.push((best.1, b));
        }
    }
    (0..n).filter(|&i| keep[i]).collect()
}

fn xy(p: Vec3) -> Vec2 {
    [p[0], p[1]]
}

/// Circle through three XY points: (centre, radius).
fn circle3(a: Vec2, b: Vec2, c: Vec2) -> Option<(Vec2, f64)> {
    let ab = sub(b, a);
    let ac = sub(c, a);
    let d = 2.0 * cross(ab, ac);
    if d.abs() < 1e-12 {
        return None;
    }
    let (l1, l2) = (ab[0] * ab[0] + ab[1] * ab[1], ac[0] * ac[0] + ac[1] * ac[1]);
    let ux = (ac[1] * l1 - ab[1] * l2) / d;
    let uy = (ab[0] * l2 - ac[0] * l1) / d;
    let r = (ux * ux + uy * uy).sqrt();
    (r.is_finite() && r < MAX_ARC_RADIUS).then_some(([a[0] + ux, a[1] + uy], r))
}

/// The arc through `pts[i..=j]`, if they form one within `tol`.
fn arc_fit(pts: &[Vec3], i: usize, j: usize, tol: f64) -> Option<(Vec2, bool)> {
    let m = (i + j) / 2;
    let (c, r) = circle3(xy(pts[i]), xy(pts[m]), xy(pts[j]))?;
    let ccw = cross(sub(xy(pts[m]), xy(pts[i])), sub(xy(pts[j]), xy(pts[m]))) > 0.0;
    let mut sweep = 0.0;
    for k in i..=j {
        let v = sub(xy(pts[k]), c);
        if ((v[0] * v[0] + v[1] * v[1]).sqrt() - r).abs() > tol
            || (pts[k][2] - pts[i][2]).abs() > tol
        {
            return None;
        }
        if k > i {
            let u = sub(xy(pts[k - 1]), c);
            let turn = cross(u, v).atan2(crate::geom::dot(u, v));
            if (turn > 0.0) != ccw || turn == 0.0 {
                return None;
            }
            sweep += turn.abs();
            // Each chord must stay within tol of the arc (sagitta r(1 − cos(θ/2))).
            if r * (1.0 - (0.5 * turn).cos()) > tol {
                return None;
            }
        }
    }
    (sweep <= std::f64::consts::PI).then_some((c, ccw))
}

/// Turn a dense machine-space polyline into moves: arcs where they fit (when `arcs`), RDP-
/// simplified lines elsewhere. The first point is the start and produces no move.
pub fn fit_moves(pts: &[Vec3], tol: f64, arcs: bool) -> Vec<Segment> {
    let n = pts.len();
    let mut out = Vec::new();
    let mut run_start = 0;
    let mut i = 0;
    let flush = |out: &mut Vec<Segment>, a: usize, b: usize| {
        if b > a {
            let run = &pts[a..=b];
            for k in rdp_indices(run, tol).into_iter().skip(1) {
                out.push(Segment::Line { to: run[k] });
            }
        }
    };
    while arcs && i + MIN_ARC_POINTS <= n {
        let mut good = None;
        let mut len = MIN_ARC_POINTS - 1;
        while i + len < n {
            match arc_fit(pts, i, i + len, tol) {
                Some(a) => good = Some((i + len, a)),
                None => break,
            }
            len *= 2;
        }
        let Some((mut j, mut fit)) = good else {
            i += 1;
            continue;
        };
        // Bisect between the last good and first bad length.
        let (mut lo, mut hi) = (j, (i + len).min(n - 1));
        while hi > lo + 1 {
            let mid = (lo + hi) / 2;
            match arc_fit(pts, i, mid, tol) {
                Some(a) => {
                    lo = mid;
                    j = mid;
                    fit = a;
                }
                None => hi = mid,
            }
        }
        if hi == n - 1 && hi > j {
            if let Some(a) = arc_fit(pts, i, hi, tol) {
                j = hi;
                fit = a;
            }
        }
        flush(&mut out, run_start, i);
        out.push(Segment::Arc { to: pts[j], center: fit.0, ccw: fit.1 });
        i = j;
        run_start = j;
    }
    flush(&mut out, run_start, n.saturating_sub(1));
    out
}
