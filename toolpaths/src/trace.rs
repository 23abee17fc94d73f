//! Streamline tracing with the Dormand–Prince 5(4) embedded Runge–Kutta pair, with step and
//! error measured in surface length.
//!
//! The ODE is `dp/ds = d(p)`, where `s` is arc length **on the part** and `d` is the field
//! normalized so that `I(d, d) = 1` (see [`crate::field`]). A step of size `h` therefore
//! advances `h` mm on the surface, and the local error estimate `ε = ‖h Σ eᵢ kᵢ‖_I` (the
//! difference between the 5th- and 4th-order solutions, measured with the first fundamental
//! form) is in mm too. Steps with `ε > tol` are rejected; the next step is
//! `h · clamp(0.9 (tol/ε)^{1/5}, 0.2, 5)` (Hairer, Nørsett & Wanner, *Solving ODEs I*, §II.4,
//! eq. 4.13; coefficients from Dormand & Prince 1980, table 2). The scheme is FSAL: the last
//! stage of an accepted step is the first stage of the next.
//!
//! Departure from a plain ODE solver: a step is also rejected when the sagitta of its chord
//! (estimated from the turn between the first and last stage) exceeds the tolerance, so the
//! *polyline* we output — not only its vertices — stays within tolerance of the streamline.

use serde::{Deserialize, Serialize};

use crate::error::{non_negative, positive, Result, ToolpathError};
use crate::field::{sample, Singularity};
use crate::geom::{add, cross, dot, scale, sub, Vec2};
use crate::grid::PointGrid;
use crate::locate::{barycentric, walk, Walk};
use crate::mesh::{Domain, Symmetry};
use crate::stroke::{join, Half};
pub use crate::stroke::{StopReason, Stroke};

/// The share of [`TraceOptions::tolerance`] a step keeps to on a recognized curved surface
/// (`Tracer::tolerance_at`).
pub const CURVED_TOLERANCE_FACTOR: f64 = 0.1;

/// Options of the streamline integrator. Lengths are surface millimetres.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(default)]
#[serde(deny_unknown_fields)]
#[cfg_attr(feature = "schemars", derive(schemars::JsonSchema))]
pub struct TraceOptions {
    /// Local error tolerance per step, mm on the surface: both the Dormand–Prince error
    /// estimate and the sagitta of each chord (distance between the polyline and the
    /// integrated curve) are kept below it. Default 1e-3.
    pub tolerance: f64,
    /// Largest step, mm. Placement caps it at `d_test / 2` so spacing tests see every
    /// approach. Default 1.
    pub max_step: f64,
    /// Smallest step, mm; below it a failing step ends the stroke. Default 1e-6.
    pub min_step: f64,
    /// Maximum stroke length, mm. Default 10 000.
    pub max_length: f64,
    /// Radius around each singularity that strokes may not enter, mm. Default 1.
    pub exclusion_radius: f64,
    /// Continue across UV seams listed in [`crate::FieldMesh::seams`]. Default false.
    pub cross_seams: bool,
    /// Cap on integration steps per half stroke (a guard, reported as `max_length`).
    pub max_steps: usize,
}

impl Default for TraceOptions {
    fn default() -> Self {
        TraceOptions {
            tolerance: 1e-3,
            max_step: 1.0,
            min_step: 1e-6,
            max_length: 1e4,
            exclusion_radius: 1.0,
            cross_seams: false,
            max_steps: 2_000_000,
        }
    }
}

impl TraceOptions {
    /// Reject NaN, infinite or non-positive values.
    pub fn validate(&self) -> Result<()> {
        positive("placement.trace.tolerance", self.tolerance)?;
        positive("placement.trace.max_step", self.max_step)?;
        positive("placement.trace.min_step", self.min_step)?;
        positive("placement.trace.max_length", self.max_length)?;
        non_negative("placement.trace.exclusion_radius", self.exclusion_radius)?;
        if self.max_steps == 0 {
            return Err(ToolpathError::InvalidOption {
                name: "placement.trace.max_steps",
                value: 0.0,
                reason: "must be at least 1 (0 traces no stroke)",
            });
        }
        if self.min_step > self.max_step {
            // Blame the one that was moved: min_step when it is not its default.
            return Err(if self.min_step != Self::default().min_step {
                ToolpathError::InvalidOption {
                    name: "placement.trace.min_step",
                    value: self.min_step,
                    reason: "must not exceed max_step",
                }
            } else {
                ToolpathError::InvalidOption {
                    name: "placement.trace.max_step",
                    value: self.max_step,
                    reason: "must be at least min_step (default 1e-6)",
                }
            });
        }
        Ok(())
    }
}

/// Dormand–Prince 5(4) tableau.
const C: [f64; 7] = [0.0, 0.2, 0.3, 0.8, 8.0 / 9.0, 1.0, 1.0];
const A: [[f64; 6]; 7] = [
    [0.0; 6],
    [0.2, 0.0, 0.0, 0.0, 0.0, 0.0],
    [3.0 / 40.0, 9.0 / 40.0, 0.0, 0.0, 0.0, 0.0],
    [44.0 / 45.0, -56.0 / 15.0, 32.0 / 9.0, 0.0, 0.0, 0.0],
    [19372.0 / 6561.0, -25360.0 / 2187.0, 64448.0 / 6561.0, -212.0 / 729.0, 0.0, 0.0],
    [9017.0 / 3168.0, -355.0 / 33.0, 46732.0 / 5247.0, 49.0 / 176.0, -5103.0 / 18656.0, 0.0],
    [35.0 / 384.0, 0.0, 500.0 / 1113.0, 125.0 / 192.0, -2187.0 / 6784.0, 11.0 / 84.0],
];
/// `b − b*` (5th minus 4th order weights).
const E: [f64; 7] = [
    71.0 / 57600.0,
    0.0,
    -71.0 / 16695.0,
    71.0 / 1920.0,
    -17253.0 / 339200.0,
    22.0 / 525.0,
    -1.0 / 40.0,
];

/// The tracer: a domain, its singularities and options.
pub(crate) struct Tracer<'a> {
    pub dom: &'a Domain,
    pub opts: &'a TraceOptions,
    sing: &'a [Singularity],
    sing_grid: PointGrid,
    /// Largest UV radius that can hold a surface distance of `exclusion_radius`.
    closure: f64,
    /// Counts of field evaluations (for the report).
    pub evals: u64,
    /// +1 on the forward half, −1 on the backward half.
    sign: f64,
}

/// Where the integration of a half-stroke stands.
struct Cursor {
    /// The current point and its face.
    p: Vec2,
    f: u32,
    /// The field at `p` (the first stage of the next step).
    k0: Vec2,
    /// The next step size, surface mm.
    h: f64,
    /// Arc length integrated so far, surface mm.
    arc: f64,
    /// UV seams crossed so far.
    seam_jumps: usize,
}

enum StepFail {
    Exit,
    Field,
}

impl<'a> Tracer<'a> {
    pub fn new(dom: &'a Domain, sing: &'a [Singularity], opts: &'a TraceOptions) -> Tracer<'a> {
        let mut sing_grid = PointGrid::new(dom.bbox, opts.exclusion_radius.max(1e-9) * 2.0);
        for (i, s) in sing.iter().enumerate() {
            sing_grid.insert(s.uv, i as u32);
        }
        Tracer { dom, opts, sing, sing_grid, closure: closure_radius(opts), evals: 0, sign: 1.0 }
    }

    /// Distance from `p` (in face `f`) to the nearest singularity if below the exclusion
    /// radius, with that singularity's position.
    pub fn near_singularity(&self, p: Vec2, f: u32) -> Option<Vec2> {
        self.near_singularity_within(p, f, self.opts.exclusion_radius)
    }

    /// The nearest singularity within surface distance `r` of `p` (in face `f`), if any.
    pub fn near_singularity_within(&self, p: Vec2, f: u32, r: f64) -> Option<Vec2> {
        if r <= 0.0 || self.sing.is_empty() {
            return None;
        }
        let m = &self.dom.metric[f as usize];
        let r_uv = r / self.dom.min_stretch[f as usize];
        let mut hit = None;
        self.sing_grid.visit(p, r_uv, |i| {
            let s = self.sing[i as usize].uv;
            if m.length(sub(s, p)) < r {
                hit = Some(s);
                false
            } else {
                true
            }
        });
        hit
    }

    /// Vector fields are integrated backwards on the backward half (`sign = −1`); line
    /// fields follow the heading instead, so the sign is not needed there.
    fn oriented(&self, d: Option<Vec2>) -> Option<Vec2> {
        match (self.dom.symmetry, d) {
            (Symmetry::Vector, Some(v)) if self.sign < 0.0 => Some([-v[0], -v[1]]),
            _ => d,
        }
    }

    fn eval(&mut self, f: u32, bary: [f64; 3], heading: Vec2) -> Option<Vec2> {
        self.evals += 1;
        self.oriented(sample(self.dom, f, bary, Some(heading)))
    }

    /// The local tolerance of a step from face `f`: [`TraceOptions::tolerance`], a
    /// [`CURVED_TOLERANCE_FACTOR`] of it on a face of a recognized curved surface. There each
    /// chord pulls the surface's grain back into UV through its own Jacobian, so the UV field
    /// kinks at every chord edge, which the embedded error estimate under-reads: at 1e-3 mm a
    /// stroke across a 2 mm round leaned by 1–3° over 0.2–0.5 mm on 1–2 % of its length.
    fn tolerance_at(&self, f: u32) -> f64 {
        let curved = self.dom.ambient.get(f as usize).is_some_and(Option::is_some);
        self.opts.tolerance * if curved { CURVED_TOLERANCE_FACTOR } else { 1.0 }
    }

    /// One Dormand–Prince step of size `h` from `p` in face `f` with first stage `k0`.
    /// Returns the new point, its face, the last stage and the error estimate (mm).
    fn step(
        &mut self,
        p: Vec2,
        f: u32,
        k0: Vec2,
        h: f64,
    ) -> std::result::Result<(Vec2, u32, Vec2, f64), StepFail> {
        let mut k = [[0.0; 2]; 7];
        k[0] = k0;
        let mut last = (p, f);
        for s in 1..7 {
            let mut q = p;
            for j in 0..s {
                q = add(q, scale(k[j], h * A[s][j]));
            }
            debug_assert!(C[s] > 0.0);
            match walk(self.dom, f, p, q) {
                Walk::Inside { face, bary } => {
                    k[s] = self.eval(face, bary, k0).ok_or(StepFail::Field)?;
                    last = (q, face);
                }
                Walk::Exit { .. } => return Err(StepFail::Exit),
            }
        }
        let mut e = [0.0, 0.0];
        for j in 0..7 {
            e = add(e, scale(k[j], h * E[j]));
        }
        let err = self.dom.metric[f as usize].length(e);
        Ok((last.0, last.1, k[6], err))
    }

    /// Distance along the ray `p + t·dir` (surface mm) to the domain boundary, if within
    /// `reach`; with the face and edge where it leaves.
    fn boundary_along(&self, p: Vec2, f: u32, dir: Vec2, reach: f64) -> Option<(f64, u32, u8)> {
        match walk(self.dom, f, p, add(p, scale(dir, reach))) {
            Walk::Exit { face, edge, t } => Some((t * reach, face, edge)),
            Walk::Inside { .. } => None,
        }
    }

    /// Trace from `p0` (in face `f0`) with initial heading `h0` until a stop.
    /// `blocked(p, f, s, vertex)` is the spacing test (true when `p` is too close to other
    /// strokes or to this stroke's own points far away along it); `s` is the signed arc
    /// length from the seed (`sign` is −1 on the backward half); `vertex` is false for the
    /// extra test at the middle of each step.
    pub fn trace_half(
        &mut self,
        p0: Vec2,
        f0: u32,
        h0: Vec2,
        sign: f64,
        mut blocked: impl FnMut(Vec2, u32, f64, bool) -> bool,
    ) -> Half {
        let o = self.opts;
        let mut half = Half {
            uv: vec![p0],
            faces: vec![f0],
            breaks: Vec::new(),
            stop: StopReason::MaxLength,
            length: 0.0,
        };
        let (p, f) = (p0, f0);
        self.sign = sign;
        let Some(k0) =
            self.oriented(sample(self.dom, f, barycentric(self.dom.corners(f), p), Some(h0)))
        else {
            half.stop = StopReason::Singularity;
            return half;
        };
        let mut c = Cursor { p, f, k0, h: 0.25 * o.max_step, arc: 0.0, seam_jumps: 0 };
        for _ in 0..o.max_steps {
            let remaining = o.max_length - c.arc;
            if remaining <= o.min_step {
                half.stop = StopReason::MaxLength;
                return half;
            }
            let hs = c.h.min(remaining);
            let (p, k0) = (c.p, c.k0);
            let tol = self.tolerance_at(c.f);
            match self.step(p, c.f, k0, hs) {
                Ok((q, fq, k6, err)) => {
                    if err > tol && hs > o.min_step {
                        c.h = (hs * (0.9 * (tol / err).powf(0.2)).max(0.2)).max(o.min_step);
                        continue;
                    }
                    // The chord p → q must also stay within tolerance of the curve: for a
                    // turn θ over arc length h the sagitta is (h/θ)(1 − cos θ/2) ≈ hθ/8.
                    let turn = cross(k0, k6).atan2(dot(k0, k6)).abs();
                    let sag =
                        if turn > 1e-12 { hs / turn * (1.0 - (0.5 * turn).cos()) } else { 0.0 };
                    if sag > tol && hs > o.min_step {
                        c.h = (hs * 0.9 * (tol / sag).sqrt()).max(o.min_step);
                        continue;
                    }
                    // Accepted step.
                    if let Some(s) = self.near_singularity(q, fq) {
                        let m = &self.dom.metric[fq as usize];
                        let end = circle_exit(m, p, q, s, o.exclusion_radius);
                        half.length += m.length(sub(end, p));
                        half.uv.push(end);
                        half.faces.push(fq);
                        half.stop = StopReason::Singularity;
                        return half;
                    }
                    let m = &self.dom.metric[fq as usize];
                    let chord = m.length(sub(q, p));
                    if c.arc > 4.0 * self.closure
                        && half.breaks.is_empty()
                        && passes_by(m, p0, p, q, self.closure)
                        && dot(k6, h0) > 0.0
                    {
                        half.length += m.length(sub(p0, p));
                        half.uv.push(p0);
                        half.faces.push(f0);
                        half.stop = StopReason::ClosedLoop;
                        return half;
                    }
                    let mid = scale(add(p, q), 0.5);
                    if blocked(mid, fq, sign * (c.arc + 0.5 * hs), false)
                        || blocked(q, fq, sign * (c.arc + hs), true)
                    {
                        half.stop = StopReason::TooClose;
                        return half;
                    }
                    half.length += chord;
                    c.arc += hs;
                    half.uv.push(q);
                    half.faces.push(fq);
                    c.p = q;
                    c.f = fq;
                    c.k0 = k6;
                    let mut grow = if err > 0.0 { 0.9 * (tol / err).powf(0.2) } else { 5.0 };
                    // Sagitta grows with h²: do not grow into a step that will be rejected.
                    if sag > 0.0 {
                        grow = grow.min(0.9 * (tol / sag).sqrt());
                    }
                    c.h = (hs * grow.clamp(0.2, 5.0)).clamp(o.min_step, o.max_step);
                }
                Err(StepFail::Field) => {
                    if hs <= o.min_step {
                        half.stop = StopReason::Singularity;
                        return half;
                    }
                    c.h = (hs * 0.25).max(o.min_step);
                }
                Err(StepFail::Exit) => {
                    if let Some(stop) = self.at_boundary(&mut half, &mut c, hs) {
                        half.stop = stop;
                        return half;
                    }
                }
            }
        }
        half.stop = StopReason::MaxLength;
        half
    }

    /// A step of size `hs` from the cursor left the domain: retry with a shorter step, or
    /// end the half on the boundary (appending the point where it leaves), or continue
    /// across a UV seam. `Some(stop)` when the half ends.
    fn at_boundary(&self, half: &mut Half, c: &mut Cursor, hs: f64) -> Option<StopReason> {
        let o = self.opts;
        let (p, f, k0) = (c.p, c.f, c.k0);
        let hit = self.boundary_along(p, f, k0, hs);
        let finish = match hit {
            Some((d, _, _)) => d < 1e-3 * o.max_step || hs <= o.min_step,
            None => hs <= o.min_step,
        };
        if !finish {
            c.h = match hit {
                Some((d, _, _)) if d < hs => d.max(o.min_step),
                _ => (hs * 0.5).max(o.min_step),
            };
            return None;
        }
        let Some((d, bf, be)) = hit.or_else(|| self.boundary_along(p, f, k0, o.max_step)) else {
            return Some(StopReason::Boundary);
        };
        let end = add(p, scale(k0, d));
        half.length += self.dom.metric[f as usize].length(sub(end, p));
        half.uv.push(end);
        half.faces.push(bf);
        let link = self.dom.seams.get(&(bf, be)).copied();
        match link {
            Some(link) if o.cross_seams && c.seam_jumps < 1000 => {
                c.seam_jumps += 1;
                let (q, hq) = cross_seam(self.dom, bf, &link, end, k0);
                let fq = link.face;
                let bq = barycentric(self.dom.corners(fq), q);
                let Some(kq) = self.oriented(sample(self.dom, fq, bq, Some(hq))) else {
                    return Some(StopReason::Singularity);
                };
                half.breaks.push(half.uv.len());
                half.uv.push(q);
                half.faces.push(fq);
                c.p = q;
                c.f = fq;
                c.k0 = kq;
                None
            }
            _ => Some(StopReason::Boundary),
        }
    }

    /// Trace both ways from a located seed and join the halves. `None` when the seed is in
    /// an exclusion zone or the field vanishes there.
    pub fn trace_both(
        &mut self,
        seed: Vec2,
        face: u32,
        mut blocked: impl FnMut(Vec2, u32, f64, bool) -> bool,
    ) -> Option<Stroke> {
        if self.near_singularity(seed, face).is_some() {
            return None;
        }
        let bary = barycentric(self.dom.corners(face), seed);
        let d = sample(self.dom, face, bary, None)?;
        // Let the spacing test record the seed itself (it was already found clear).
        let _ = blocked(seed, face, 0.0, true);
        let fwd = self.trace_half(seed, face, d, 1.0, &mut blocked);
        if fwd.stop == StopReason::ClosedLoop {
            return Some(Stroke {
                uv: fwd.uv,
                faces: fwd.faces,
                breaks: fwd.breaks,
                start: StopReason::ClosedLoop,
                end: StopReason::ClosedLoop,
                length: fwd.length,
                fill: false,
                run_out: [None; 2],
                overtravel: [0.0; 2],
            });
        }
        let back = self.trace_half(seed, face, [-d[0], -d[1]], -1.0, &mut blocked);
        Some(join(back, fwd))
    }
}

/// Radius within which a stroke passing its start is closed into a loop: half the
/// largest step.
pub(crate) fn closure_radius(opts: &TraceOptions) -> f64 {
    0.5 * opts.max_step
}

/// Whether the segment `p → q` passes `s` (its foot lies within the segment) at a distance
/// below `r`, under metric `m`.
fn passes_by(m: &crate::geom::Metric, s: Vec2, p: Vec2, q: Vec2, r: f64) -> bool {
    let d = sub(q, p);
    let l2 = m.inner(d, d);
    if l2 <= 0.0 {
        return false;
    }
    let t = m.inner(sub(s, p), d) / l2;
    (0.0..=1.0).contains(&t) && m.length(sub(sub(s, p), scale(d, t))) < r
}

/// Where the chord `p → q` (p outside, q inside) enters the circle of surface radius `r`
/// about `s`, under metric `m`.
fn circle_exit(m: &crate::geom::Metric, p: Vec2, q: Vec2, s: Vec2, r: f64) -> Vec2 {
    let d = sub(q, p);
    let w = sub(p, s);
    let a = m.inner(d, d);
    let b = 2.0 * m.inner(w, d);
    let c = m.inner(w, w) - r * r;
    let disc = b * b - 4.0 * a * c;
    if a <= 0.0 || disc < 0.0 || c < 0.0 {
        return p;
    }
    let t = ((-b - disc.sqrt()) / (2.0 * a)).clamp(0.0, 1.0);
    add(p, scale(d, t))
}

/// Map a point on a seam edge and a heading to the other side: the glued edge's similarity
/// (a reflection too when the two charts have opposite UV orientation).
fn cross_seam(
    dom: &Domain,
    face: u32,
    link: &crate::mesh::SeamLink,
    p: Vec2,
    heading: Vec2,
) -> (Vec2, Vec2) {
    let a = sub(link.from[1], link.from[0]);
    let b = sub(link.to[1], link.to[0]);
    let t = (dot(sub(p, link.from[0]), a) / dot(a, a)).clamp(0.0, 1.0);
    let q = add(link.to[0], scale(b, t));
    let orient = |f: u32| {
        let c = dom.corners(f);
        cross(sub(c[1], c[0]), sub(c[2], c[0])).signum()
    };
    let mirrored = orient(face) != orient(link.face);
    // Complex arithmetic: z = b / a (or b / conj(a)), applied to h (or conj(h)).
    let (ar, ai) = if mirrored { (a[0], -a[1]) } else { (a[0], a[1]) };
    let den = ar * ar + ai * ai;
    let z = [(b[0] * ar + b[1] * ai) / den, (b[1] * ar - b[0] * ai) / den];
    let h = if mirrored { [heading[0], -heading[1]] } else { heading };
    let mapped = [z[0] * h[0] - z[1] * h[1], z[0] * h[1] + z[1] * h[0]];
    (q, mapped)
}

/// Trace one streamline through `seed` (UV) in both directions, without spacing tests.
/// Returns `Ok(None)` when the seed is outside the domain, inside a singularity's exclusion
/// radius, or where the field vanishes.
pub fn trace_streamline(dom: &Domain, seed: Vec2, opts: &TraceOptions) -> Result<Option<Stroke>> {
    opts.validate()?;
    if !(seed[0].is_finite() && seed[1].is_finite()) {
        return Err(ToolpathError::NonFinite { what: "seed", index: 0 });
    }
    let mut tracer = Tracer::new(dom, dom.singularities(), opts);
    let Some((face, _)) = dom.grid.locate(dom, seed) else {
        return Ok(None);
    };
    Ok(tracer.trace_both(seed, face, |_, _, _, _| false))
}
