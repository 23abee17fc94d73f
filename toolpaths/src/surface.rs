//! Strokes on the surface the triangles approximate, not on their chords.
//!
//! A CAD export writes a fillet or a turned face as strips of flat triangles; the part's
//! metal is the curved surface they stand off by up to their sagitta. When the caller knows
//! that surface per triangle ([`crate::SurfaceLift`], e.g. the cylinders, cones, spheres and tori
//! grainline recognizes), every 3D point of a stroke is that surface's point nearest to the
//! chord's: `X = π_f(lift_chord(u, v))` for a UV point in triangle `f`, with the surface's
//! normal there (the strokes JSON, the passes' 3D points, G-code surface following and the
//! tilt checks all read it through [`crate::Domain`]'s lift).
//!
//! Inside such a triangle the field is the caller's ambient grain per corner `aᵢ` (3D vectors
//! off the surface whose blend, projected onto the surface's tangent plane, is the grain;
//! grainline extends its unit grain so that a world direction's projection is reproduced
//! exactly) blended at the point, projected onto the surface there and pulled back into UV
//! through the lift's Jacobian (`field.rs`), not the chords' blend of UV directions.
//!
//! A stroke's samples are then chords of a curve on the surface: [`densify`] inserts UV
//! midpoints until each lifted segment stands off the curve by at most a quarter of the plan
//! tolerance — `|π(mid) − ½(π(a) + π(b))| ≤ tol/4` — so the simplified 3D polylines (RDP at
//! the plan tolerance) stay within it of the surface.

use crate::geom::Vec2;
use crate::locate::barycentric;
use crate::mesh::Domain;
use crate::place::Placement;

/// Most halvings of one stroke segment ([`densify`]): 2¹⁰ pieces.
const MAX_DEPTH: u32 = 10;

/// Most points [`densify`] adds, as a multiple of the strokes' own: a tolerance far below the
/// surface's curvature cannot grow the strokes without bound (past it the remaining segments
/// keep their samples, which lie on the surface all the same).
const MAX_ADDED_PER_POINT: usize = 8;

/// Inserts UV points into the strokes of `placement` until every lifted segment stands off the
/// surface by at most `tol / 4` (module docs), adding at most [`MAX_ADDED_PER_POINT`] times the
/// strokes' points; a no-op without a [`crate::SurfaceLift`]. Seam jumps are kept as they are.
/// Returns the number of points inserted.
pub(crate) fn densify(dom: &Domain, placement: &mut Placement, tol: f64) -> usize {
    if dom.surface.is_none() || tol.is_nan() || tol <= 0.0 {
        return 0;
    }
    let total: usize = placement.strokes.iter().map(|s| s.uv.len()).sum();
    let mut budget = MAX_ADDED_PER_POINT * total;
    for s in &mut placement.strokes {
        let n = s.uv.len();
        let mut uv = Vec::with_capacity(n);
        let mut faces = Vec::with_capacity(n);
        let mut breaks = Vec::with_capacity(s.breaks.len());
        let mut next_break = s.breaks.iter().copied().peekable();
        for i in 0..n {
            if next_break.next_if_eq(&i).is_some() {
                breaks.push(uv.len());
            } else if i > 0 {
                let (a, b) = ((s.uv[i - 1], s.faces[i - 1]), (s.uv[i], s.faces[i]));
                let mut out = (&mut uv, &mut faces, &mut budget);
                split(dom, a, b, 0.25 * tol, MAX_DEPTH, &mut out);
            }
            uv.push(s.uv[i]);
            faces.push(s.faces[i]);
        }
        s.uv = uv;
        s.faces = faces;
        s.breaks = breaks;
    }
    MAX_ADDED_PER_POINT * total - budget
}

/// Where [`split`] puts its points: UV, faces, and the points it may still add.
type Out<'a> = (&'a mut Vec<Vec2>, &'a mut Vec<u32>, &'a mut usize);

/// The points strictly between `a` and `b` (pushed in order) that bring the lifted segment
/// within `tol` of the surface.
fn split(dom: &Domain, a: (Vec2, u32), b: (Vec2, u32), tol: f64, depth: u32, out: &mut Out) {
    if depth == 0 || *out.2 == 0 {
        return;
    }
    let m = [0.5 * (a.0[0] + b.0[0]), 0.5 * (a.0[1] + b.0[1])];
    let face = if a.1 == b.1 {
        Some(a.1)
    } else {
        dom.grid.locate_in(dom, m, Some(dom.chart[a.1 as usize])).map(|(f, _)| f)
    };
    let Some(face) = face else { return };
    let lift = |p: Vec2, f: u32| dom.lift(f, barycentric(dom.corners(f), p));
    let (Some(pa), Some(pb), Some(pm)) = (lift(a.0, a.1), lift(b.0, b.1), lift(m, face)) else {
        return;
    };
    let off = (0..3).map(|k| (pm[k] - 0.5 * (pa[k] + pb[k])).powi(2)).sum::<f64>().sqrt();
    if off.is_nan() || off <= tol {
        return;
    }
    split(dom, a, (m, face), tol, depth - 1, out);
    if *out.2 == 0 {
        return;
    }
    *out.2 -= 1;
    out.0.push(m);
    out.1.push(face);
    split(dom, (m, face), b, tol, depth - 1, out);
}
