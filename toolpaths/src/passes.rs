//! Building one pass from an oriented, ordered stroke: lead-in ramp, overtravel past the
//! part edge, the simplified (or arc-fitted) stroke, lead-out ramp; plus the simplified UV
//! and 3D polylines for SVG and JSON. See [`crate::plan`] for the geometry.
//!
//! **Overtravel (run-outs) continue the machine path along its tangent** (R1): at an end `p`
//! that stopped on the part's edge, with `t` the unit tangent of the machine polyline there
//! (in `X Y Z`, or in the developed `x, r_ref·A, Z` of a rotary fixture, Z included), the
//! brush runs on to `p ± L t`, `L` the larger of `plan.overtravel` and the stroke's run-out
//! ([`crate::Stroke::overtravel`]). The path has no corner at the edge (the controller does
//! not slow down there), and the run-out lies on the part's surface continued by its tangent
//! plane past the edge: in flat mode at the cutting Z, on a rotary fixture on the cone that
//! continues the body of revolution (`ρ = ρ_edge + (dρ/dx)·Δx`), when surface following
//! above a convex part by at most `√(R² + L²) − R` for a normal curvature radius `R`.

use serde::{Deserialize, Serialize};

use crate::geom::{Vec2, Vec3};
use crate::locate::barycentric;
use crate::mesh::Domain;
use crate::plan_options::PlanOptions;
use crate::simplify::{fit_moves, Segment};
use crate::trace::StopReason;

/// Which part of a pass a move belongs to.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum MoveKind {
    /// Ramp down onto the stroke.
    LeadIn,
    /// Extension past the part edge.
    Overtravel,
    /// The stroke itself.
    Cut,
    /// Ramp up off the stroke.
    LeadOut,
}

/// One pass of the tool: plunge at `start`, then `moves`, then retract.
#[derive(Clone, Debug, PartialEq)]
pub struct Pass {
    /// Index of the stroke in [`Placement::strokes`](crate::Placement::strokes).
    pub stroke: usize,
    /// Whether the stroke runs end → start relative to its traced order.
    pub reversed: bool,
    /// First point (machine coordinates): where the tool plunges to.
    pub start: Vec3,
    /// Moves in order, with their kind.
    pub moves: Vec<(MoveKind, Segment)>,
    /// UV polyline pieces in cutting order (split at seam jumps), simplified.
    pub uv: Vec<Vec<Vec2>>,
    /// 3D lift of the oriented stroke points (when the input has positions), simplified
    /// like `uv` (one list per piece).
    pub xyz: Option<Vec<Vec<Vec3>>>,
    /// Stop reason at the first / last point of the pass (after orientation).
    pub stops: [StopReason; 2],
    /// Surface length of the stroke, mm.
    pub length: f64,
    /// Sheet of the pass (flat mode: charts that overlap in UV go on separate sheets,
    /// numbered from 0; always 0 when surface following or when no charts overlap).
    pub sheet: usize,
}

/// An oriented stroke in machine space before ordering.
#[derive(Clone)]
pub(crate) struct Item {
    pub(crate) stroke: usize,
    pub(crate) reversed: bool,
    pub(crate) uv: Vec<Vec<Vec2>>,
    pub(crate) faces: Vec<Vec<u32>>,
    pub(crate) machine: Vec<Vec3>,
    pub(crate) stops: [StopReason; 2],
    /// The stroke's run-outs past chart edges ([`crate::Stroke::overtravel`]), mm.
    pub(crate) overtravel: [f64; 2],
    pub(crate) length: f64,
}

fn tangent_xy(a: Vec3, b: Vec3) -> Vec2 {
    let t = [b[0] - a[0], b[1] - a[1]];
    let l = (t[0] * t[0] + t[1] * t[1]).sqrt();
    if l > 0.0 {
        [t[0] / l, t[1] / l]
    } else {
        [1.0, 0.0]
    }
}

/// First point at least `eps` away from `pts[0]` in XY, for a stable tangent.
fn far_point(pts: &[Vec3], eps: f64) -> Vec3 {
    for p in &pts[1..] {
        if ((p[0] - pts[0][0]).powi(2) + (p[1] - pts[0][1]).powi(2)).sqrt() > eps {
            return *p;
        }
    }
    pts[pts.len() - 1]
}

/// Unit tangent of the machine polyline at its first point pointing inwards (`from_end`:
/// at its last point pointing outwards), in machine space (`Z` included; `[x, r_ref·A, Z]` on a
/// rotary fixture), towards the first point at least `eps` away in 3D.
fn tangent_3d(pts: &[Vec3], eps: f64, from_end: bool) -> Vec3 {
    let n = pts.len();
    let at = |i: usize| if from_end { pts[n - 1 - i] } else { pts[i] };
    let a = at(0);
    let away = |p: Vec3| [p[0] - a[0], p[1] - a[1], p[2] - a[2]];
    let q = (1..n).map(at).find(|&p| crate::geom::norm3(away(p)) > eps).unwrap_or(at(n - 1));
    let v = away(q);
    let l = crate::geom::norm3(v);
    if l.is_nan() || l <= 0.0 {
        return [1.0, 0.0, 0.0];
    }
    // Inwards at the first point; outwards (from the interior to the end) at the last.
    let sign = if from_end { -1.0 } else { 1.0 };
    v.map(|x| sign * x / l)
}

/// One pass of an ordered item (flipped when `flip`). `period`: on a rotary fixture, the period
/// of the developed angle (the machine points' second coordinate), unwrapped again here since a
/// closed loop may have been rotated to a new entry.
pub(crate) fn make_pass(
    dom: &Domain,
    it: &Item,
    flip: bool,
    o: &PlanOptions,
    period: Option<f64>,
) -> Pass {
    let mut machine = it.machine.clone();
    let mut uv = it.uv.clone();
    let mut faces = it.faces.clone();
    let mut stops = it.stops;
    let mut run = it.overtravel;
    if flip {
        run.swap(0, 1);
        machine.reverse();
        uv.reverse();
        faces.reverse();
        for (p, f) in uv.iter_mut().zip(faces.iter_mut()) {
            p.reverse();
            f.reverse();
        }
        stops.swap(0, 1);
    }
    if let Some(period) = period {
        crate::rotary::unwrap_developed(&mut machine, period);
    }
    let eps = o.tolerance;
    let first = machine[0];
    let last = machine[machine.len() - 1];
    let t0 = tangent_xy(first, far_point(&machine, eps));
    let rev_m: Vec<Vec3> = machine.iter().rev().copied().collect();
    let t1 = tangent_xy(far_point(&rev_m, eps), last);
    // At an end on a chart edge the brush runs past it by the plan's overtravel or the
    // stroke's own run-out, whichever is longer, straight on along the machine path's
    // tangent (eq. R1 in the module docs).
    let over =
        |k: usize| if stops[k] == StopReason::Boundary { o.overtravel.max(run[k]) } else { 0.0 };
    let (over_start, over_end) = (over(0), over(1));
    let (u0, u1) = (tangent_3d(&machine, eps, false), tangent_3d(&machine, eps, true));
    // `s` mm on the part along `u` from `p`: on a rotary fixture a developed step `ds` turns
    // the contact point, at `ρ = Z + contact_depth` from the axis, by `ρ / r_ref · ds`.
    let run_to = |p: Vec3, u: Vec3, s: f64| {
        let stretch = period.map_or(1.0, |period| {
            let (rho, r_ref) = (p[2] + o.contact_depth, period / std::f64::consts::TAU);
            (u[0] * u[0] + (rho / r_ref * u[1]).powi(2) + u[2] * u[2]).sqrt()
        });
        let s = if stretch > 0.0 { s / stretch } else { s };
        [p[0] + u[0] * s, p[1] + u[1] * s, p[2] + u[2] * s]
    };
    let at = |p: Vec3, t: Vec2, s: f64, dz: f64| [p[0] + t[0] * s, p[1] + t[1] * s, p[2] + dz];
    let mut moves = Vec::new();
    let cut_begin = run_to(first, u0, -over_start);
    let start = if o.lead_in > 0.0 || o.ramp_height > 0.0 {
        let s = at(cut_begin, t0, -o.lead_in, o.ramp_height);
        moves.push((MoveKind::LeadIn, Segment::Line { to: cut_begin }));
        s
    } else {
        cut_begin
    };
    if over_start > 0.0 {
        moves.push((MoveKind::Overtravel, Segment::Line { to: first }));
    }
    for seg in fit_moves(&machine, o.tolerance, o.arcs) {
        moves.push((MoveKind::Cut, seg));
    }
    let cut_end = run_to(last, u1, over_end);
    if over_end > 0.0 {
        moves.push((MoveKind::Overtravel, Segment::Line { to: cut_end }));
    }
    if o.lead_out > 0.0 || o.ramp_height > 0.0 {
        moves.push((
            MoveKind::LeadOut,
            Segment::Line { to: at(cut_end, t1, o.lead_out, o.ramp_height) },
        ));
    }
    // Simplified UV / 3D for SVG and JSON (same RDP tolerance, in UV or 3D mm).
    let uv_s: Vec<Vec<Vec2>> = uv
        .iter()
        .map(|p| {
            let p3: Vec<Vec3> = p.iter().map(|q| [q[0], q[1], 0.0]).collect();
            crate::simplify::rdp_indices(&p3, o.tolerance).into_iter().map(|k| p[k]).collect()
        })
        .collect();
    let xyz = dom.has_lift().then(|| {
        uv.iter()
            .zip(&faces)
            .map(|(p, f)| {
                let p3: Vec<Vec3> = p
                    .iter()
                    .zip(f)
                    .map(|(q, &ff)| {
                        dom.lift(ff, barycentric(dom.corners(ff), *q)).unwrap_or([0.0; 3])
                    })
                    .collect();
                crate::simplify::rdp_indices(&p3, o.tolerance).into_iter().map(|k| p3[k]).collect()
            })
            .collect()
    });
    Pass {
        stroke: it.stroke,
        reversed: it.reversed != flip,
        start,
        moves,
        uv: uv_s,
        xyz,
        stops,
        length: it.length,
        sheet: 0,
    }
}
