//! Fabrication figures measured on the traced strokes themselves (issue 17): the turning
//! radius along each stroke, the spread rate between neighbouring strokes, and the deviation
//! of the strokes that cross a locked region from the lock's direction.
//!
//! Everything here is measured on the strokes as the machine runs them, on the part's surface
//! (the 3D lift of the UV polylines, with the lift's interpolated normals; without a lift, in
//! UV as millimetres on a flat sheet), and never looks at the field the strokes were traced
//! from. It is an independent check of the solver's field-level constraint figures.
//!
//! **Samples.** Along each stroke (its 3D polyline, arc length `s`) sample centres are placed
//! every `step / 2` from one `trim` (default: the brush width) after its start to one `trim`
//! before its end; a closed loop is sampled all the way round with no trim. Each centre is
//! snapped to the nearest polyline vertex `b`, and the vertices `a` and `c` nearest to
//! `s_b − step` and `s_b + step` are its neighbours (the polyline's own vertices lie on the
//! traced curve, so no chord is interpolated). A sample stands for `step / 2` of length.
//!
//! **Turning radius.** With `n` the surface normal at `b` and `P = I − nnᵀ`, the points are
//! projected into the tangent plane, `x = P(a − b)`, `y = P(c − b)`: the curvature of a
//! surface curve's projection into its tangent plane at a point is its geodesic curvature
//! there (do Carmo §4-4), so the circumradius
//!
//! ```text
//! ρ = |x| |y| |x − y| / (2 |x × y|)                                     (S1)
//! ```
//!
//! is the stroke's turning radius along the surface, free of the part's own bending (a
//! stroke round a cylinder has ρ = ∞). For points on a circle of radius ρ, (S1) is exactly ρ.
//!
//! **Spread rate.** At each sample the nearest point of every *other* stroke on the left and
//! on the right (in the tangent plane, `w = n × t`) within `neighbour_radius` is found (a
//! segment's foot; a foot at a neighbour's end, or an offset more than 45° off `w`, does not
//! count, nor does one within `trim` of the neighbour's open ends). Where two consecutive samples see the same neighbour on one side at distances
//! `δ₀`, `δ₁`, arc lengths `s₀`, `s₁` apart,
//!
//! ```text
//! σ = (ln δ₁ − ln δ₀) / (s₁ − s₀)                                       (S2)
//! ```
//!
//! is d ln δ/ds, the quantity the splay bound limits (math.md §7: d ln δ/ds = div u); for rays
//! from a point (δ = r sin Δθ) it is 1/r exactly.
//!
//! **Locks.** A [`LockProbe`] lists field-mesh vertices with the lock's direction at each. A
//! sample lies in the locked region when all three corners of its face are locked by the
//! probe; its target is the barycentric blend of the corners' directions (sign-aligned), and
//! its deviation is the angle, modulo 180°, between the stroke's tangent (the chord between the
//! vertices next to `b`, projected) and the target projected into the tangent plane.

use std::collections::HashMap;

use serde::{Deserialize, Serialize};

use crate::error::{positive, Result, ToolpathError};
use crate::geom::{cross3, dot3, norm3, segment_foot3, sub3, Vec2, Vec3};
use crate::locate::barycentric;
use crate::mesh::Domain;
use crate::place::Placement;

/// A locked region: field-mesh vertices and the lock's direction at each.
#[derive(Clone, Debug, Default, PartialEq, Serialize, Deserialize)]
pub struct LockProbe {
    /// A name for the report (e.g. the scene key `constraints.locks[0]`).
    pub name: String,
    /// Field-mesh (UV) vertex indices.
    pub vertices: Vec<u32>,
    /// The lock's direction at each vertex: a 3D tangent vector with a lift, else a UV vector.
    pub directions: Vec<Vec3>,
}

/// What to measure, and the measuring step.
#[derive(Clone, Debug, Default, PartialEq, Serialize, Deserialize)]
pub struct StrokeCheckOptions {
    /// Arc step between the three points of a turning-radius sample, mm on the part (> 0;
    /// default: half the brush width). Samples are `step / 2` apart.
    pub step: Option<f64>,
    /// Length left out at each end of an open stroke, mm (≥ 0; default: the brush width).
    pub trim: Option<f64>,
    /// The tool's minimum turning radius R, mm (> 0): report the share of samples below R,
    /// 0.95 R and 0.8 R. `None`: the turning radius is not measured.
    pub turning_radius: Option<f64>,
    /// The splay bound s_max on |d ln δ/ds|, per mm (> 0). `None`: not measured.
    pub splay: Option<f64>,
    /// Locked regions to measure.
    pub locks: Vec<LockProbe>,
    /// How far to look for a neighbouring stroke, mm (> 0; default 2.5 d_sep).
    pub neighbour_radius: Option<f64>,
    /// Keep every sample in [`StrokeChecks::samples`] (for tests and plots; default false).
    pub keep_samples: bool,
}

impl StrokeCheckOptions {
    /// Rejects NaN and out-of-range values.
    pub fn validate(&self) -> Result<()> {
        if let Some(s) = self.step {
            positive("checks.step", s)?;
        }
        if let Some(t) = self.trim {
            crate::error::non_negative("checks.trim", t)?;
        }
        if let Some(r) = self.turning_radius {
            positive("checks.turning_radius", r)?;
        }
        if let Some(s) = self.splay {
            positive("checks.splay", s)?;
        }
        if let Some(r) = self.neighbour_radius {
            positive("checks.neighbour_radius", r)?;
        }
        for l in &self.locks {
            if l.vertices.len() != l.directions.len() {
                return Err(ToolpathError::InvalidMesh(format!(
                    "lock probe {}: {} vertices and {} directions",
                    l.name,
                    l.vertices.len(),
                    l.directions.len()
                )));
            }
            if let Some(i) = l.directions.iter().position(|d| !d.iter().all(|x| x.is_finite())) {
                return Err(ToolpathError::NonFinite { what: "lock probe directions", index: i });
            }
        }
        Ok(())
    }
}

/// Where on the strokes a figure was found.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct StrokePlace {
    /// Index of the stroke in the placement.
    pub stroke: usize,
    /// Arc length from the stroke's first point, mm.
    pub arc_mm: f64,
    /// UV position.
    pub uv: Vec2,
    /// Position on the part (UV and 0 without a lift).
    pub xyz: Vec3,
}

/// A share of the measured samples (and of their length).
#[derive(Clone, Copy, Debug, Default, PartialEq, Serialize, Deserialize)]
pub struct Share {
    /// Samples counted.
    pub samples: usize,
    /// Their fraction of the samples measured.
    pub sample_fraction: f64,
    /// Their fraction of the stroke length measured.
    pub length_fraction: f64,
}

/// The turning radius along the strokes.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct TurningFigures {
    /// The limit R, mm.
    pub radius: f64,
    /// Samples measured.
    pub samples: usize,
    /// Stroke length they stand for, mm.
    pub length_mm: f64,
    /// Samples turning tighter than R.
    pub below_radius: Share,
    /// Samples tighter than 0.95 R.
    pub below_95: Share,
    /// Samples tighter than 0.8 R.
    pub below_80: Share,
    /// The tightest turn, mm (null when nothing was measured or every sample is straight).
    pub min_radius_mm: Option<f64>,
    /// R / (tightest turn): > 1 where the constraint is broken.
    pub max_ratio: f64,
    /// Where the tightest turn is.
    pub tightest: Option<StrokePlace>,
}

/// The spread rate between neighbouring strokes.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct SplayFigures {
    /// The bound s_max, per mm.
    pub bound: f64,
    /// (sample, side) pairs where a rate was measured.
    pub samples: usize,
    /// Largest |d ln δ/ds|, per mm.
    pub max_rate: f64,
    /// max_rate / bound.
    pub max_ratio: f64,
    /// Measurements above the bound.
    pub above_bound: Share,
    /// Measurements above 1.1 × the bound.
    pub above_110: Share,
    /// Where the largest rate is.
    pub worst: Option<StrokePlace>,
}

/// The strokes crossing one locked region.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct LockFigures {
    /// The probe's name.
    pub name: String,
    /// Samples inside the region (faces with all corners locked).
    pub samples: usize,
    /// Strokes with at least one such sample.
    pub strokes: usize,
    /// Largest deviation from the lock's direction, degrees (0 without samples).
    pub max_deviation_deg: f64,
    /// Mean deviation, degrees.
    pub mean_deviation_deg: f64,
    /// Where the largest deviation is.
    pub worst: Option<StrokePlace>,
}

/// One measured sample (kept with [`StrokeCheckOptions::keep_samples`]).
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct CheckSample {
    /// Where it is.
    pub at: StrokePlace,
    /// Turning radius (S1), mm; null on a straight piece.
    pub turning_radius: Option<f64>,
    /// Spread rate (S2) towards the left and right neighbour, per mm.
    pub spread: [Option<f64>; 2],
    /// Deviation from a lock, degrees, with the probe's index.
    pub lock_deviation: Option<(usize, f64)>,
}

/// The stroke-level figures.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct StrokeChecks {
    /// Arc step used, mm.
    pub step_mm: f64,
    /// Length left out at each open end, mm.
    pub trim_mm: f64,
    /// Whether measured on the 3D lift (else in UV).
    pub on_surface: bool,
    /// Turning radius, when asked.
    pub turning: Option<TurningFigures>,
    /// Spread rate, when asked.
    pub splay: Option<SplayFigures>,
    /// One entry per lock probe.
    pub locks: Vec<LockFigures>,
    /// Every sample, when asked (left out of JSON when empty).
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    pub samples: Vec<CheckSample>,
}

impl StrokeChecks {
    /// The figures that break a constraint, as warning sentences: a turn tighter than 0.95 R,
    /// a spread above 1.1 × the bound, a stroke more than 1° off a lock.
    pub fn warnings(&self) -> Vec<String> {
        let mut out = Vec::new();
        if let Some(t) = &self.turning {
            if let (Some(m), Some(p)) = (t.min_radius_mm, &t.tightest) {
                if t.below_95.samples > 0 {
                    out.push(format!(
                        "strokes turn tighter than the turning radius {:.4}: {:.2} % of the \
                         samples below 0.95 R, {:.2} % below 0.8 R, tightest {:.4} (ratio \
                         {:.2}) on stroke {} at [{:.3}, {:.3}, {:.3}]",
                        t.radius,
                        100.0 * t.below_95.sample_fraction,
                        100.0 * t.below_80.sample_fraction,
                        m,
                        t.max_ratio,
                        p.stroke,
                        p.xyz[0],
                        p.xyz[1],
                        p.xyz[2]
                    ));
                }
            }
        }
        if let Some(s) = &self.splay {
            if let (true, Some(p)) = (s.above_110.samples > 0, &s.worst) {
                out.push(format!(
                    "neighbouring strokes spread faster than the splay bound {:.4}: {:.2} % of \
                     the measurements above 1.1 × the bound, largest {:.4} (ratio {:.2}) on \
                     stroke {} at [{:.3}, {:.3}, {:.3}]",
                    s.bound,
                    100.0 * s.above_110.sample_fraction,
                    s.max_rate,
                    s.max_ratio,
                    p.stroke,
                    p.xyz[0],
                    p.xyz[1],
                    p.xyz[2]
                ));
            }
        }
        for l in &self.locks {
            if let (true, Some(p)) = (l.max_deviation_deg > 1.0, &l.worst) {
                out.push(format!(
                    "strokes through the lock {} deviate from it by up to {:.2}° (mean {:.2}°) \
                     on stroke {} at [{:.3}, {:.3}, {:.3}]",
                    l.name,
                    l.max_deviation_deg,
                    l.mean_deviation_deg,
                    p.stroke,
                    p.xyz[0],
                    p.xyz[1],
                    p.xyz[2]
                ));
            }
        }
        out
    }
}

/// One stroke on the part: points, normals, faces, barycentric coordinates, arc lengths.
struct Lifted {
    uv: Vec<Vec2>,
    x: Vec<Vec3>,
    n: Vec<Vec3>,
    face: Vec<u32>,
    bary: Vec<[f64; 3]>,
    s: Vec<f64>,
    closed: bool,
}

fn lift_stroke(dom: &Domain, uv: &[Vec2], faces: &[u32], closed: bool) -> Lifted {
    let mut l = Lifted {
        uv: Vec::with_capacity(uv.len()),
        x: Vec::with_capacity(uv.len()),
        n: Vec::with_capacity(uv.len()),
        face: Vec::with_capacity(uv.len()),
        bary: Vec::with_capacity(uv.len()),
        s: Vec::with_capacity(uv.len()),
        closed,
    };
    for (p, &f) in uv.iter().zip(faces) {
        let b = barycentric(dom.corners(f), *p);
        let x = dom.lift(f, b).unwrap_or([p[0], p[1], 0.0]);
        let n = if dom.has_lift() { dom.normal(f, b) } else { Some([0.0, 0.0, 1.0]) };
        let Some(n) = n else { continue };
        if !(x.iter().all(|v| v.is_finite()) && n.iter().all(|v| v.is_finite())) {
            continue;
        }
        let s = match l.x.last() {
            Some(&q) => l.s.last().copied().unwrap_or(0.0) + norm3(sub3(x, q)),
            None => 0.0,
        };
        l.uv.push(*p);
        l.x.push(x);
        l.n.push(n);
        l.face.push(f);
        l.bary.push(b);
        l.s.push(s);
    }
    l
}

impl Lifted {
    fn len(&self) -> f64 {
        self.s.last().copied().unwrap_or(0.0)
    }

    /// The vertex whose arc length is nearest `t` (periodic for a closed stroke: returns the
    /// vertex index in 0..n−1, the last point being the first).
    fn nearest(&self, t: f64) -> usize {
        let n = self.s.len();
        let (t, m) = if self.closed && n > 2 {
            (t.rem_euclid(self.len().max(f64::MIN_POSITIVE)), n - 1)
        } else {
            (t, n)
        };
        let i = self.s[..m].partition_point(|&x| x < t);
        let best = if i == 0 {
            0
        } else if i >= m {
            m - 1
        } else if (self.s[i] - t) < (t - self.s[i - 1]) {
            i
        } else {
            i - 1
        };
        if self.closed && n > 2 && best == m - 1 && (self.len() - t) < (t - self.s[m - 1]) {
            0
        } else {
            best
        }
    }

    /// Arc length from vertex `i` forward to vertex `j` (periodic when closed).
    fn arc_between(&self, i: usize, j: usize) -> f64 {
        let d = self.s[j] - self.s[i];
        if self.closed && d < 0.0 {
            d + self.len()
        } else {
            d
        }
    }
}

fn proj(n: Vec3, v: Vec3) -> Vec3 {
    let d = dot3(n, v);
    [v[0] - d * n[0], v[1] - d * n[1], v[2] - d * n[2]]
}

/// (S1): circumradius of `b, b + x, b + y` after projection into the tangent plane of `n`.
fn turning_radius(n: Vec3, a: Vec3, b: Vec3, c: Vec3) -> Option<f64> {
    let x = proj(n, sub3(a, b));
    let y = proj(n, sub3(c, b));
    let area2 = norm3(cross3(x, y));
    let prod = norm3(x) * norm3(y) * norm3(sub3(x, y));
    if prod.is_nan() || prod <= 0.0 {
        return None;
    }
    if area2 <= 1e-14 * prod / (norm3(x) + norm3(y)) {
        return None;
    }
    let r = prod / (2.0 * area2);
    r.is_finite().then_some(r)
}

/// One centre: the vertex and its two neighbours a step back and forward.
#[derive(Clone, Copy)]
struct Centre {
    stroke: usize,
    a: usize,
    b: usize,
    c: usize,
}

fn centres(l: &Lifted, stroke: usize, step: f64, trim: f64, out: &mut Vec<Centre>) {
    let n = l.x.len();
    if n < 3 {
        return;
    }
    let len = l.len();
    let h = 0.5 * step;
    let (from, to) = if l.closed { (0.0, len - 0.5 * h) } else { (trim, len - trim) };
    if to.is_nan() || from.is_nan() || to < from {
        return;
    }
    let count = ((to - from) / h).floor() as usize + 1;
    let last = if l.closed { n - 2 } else { n - 1 };
    for j in 0..count.min(1 << 24) {
        let t = from + j as f64 * h;
        let b = l.nearest(t);
        let mut a = l.nearest(l.s[b] - step);
        let mut c = l.nearest(l.s[b] + step);
        if l.closed {
            if a == b {
                a = if b == 0 { last } else { b - 1 };
            }
            if c == b {
                c = if b == last { 0 } else { b + 1 };
            }
        } else {
            if a == b {
                if b == 0 {
                    continue;
                }
                a = b - 1;
            }
            if c == b {
                if b >= last {
                    continue;
                }
                c = b + 1;
            }
        }
        out.push(Centre { stroke, a, b, c });
    }
}

/// Segments of every stroke in a hashed 3D grid, for the neighbour search.
struct SegmentGrid {
    cell: f64,
    map: HashMap<[i64; 3], Vec<(u32, u32)>>,
}

impl SegmentGrid {
    fn key(&self, p: Vec3) -> [i64; 3] {
        p.map(|x| (x / self.cell).floor() as i64)
    }

    fn new(strokes: &[Lifted], cell: f64) -> SegmentGrid {
        let mut g = SegmentGrid { cell, map: HashMap::new() };
        for (si, l) in strokes.iter().enumerate() {
            for i in 0..l.x.len().saturating_sub(1) {
                let (p, q) = (l.x[i], l.x[i + 1]);
                let lo = g.key([0, 1, 2].map(|k| p[k].min(q[k])));
                let hi = g.key([0, 1, 2].map(|k| p[k].max(q[k])));
                // A segment longer than a few cells (a seam jump without a lift) is skipped.
                if (0..3).any(|k| hi[k] - lo[k] > 4) {
                    continue;
                }
                for x in lo[0]..=hi[0] {
                    for y in lo[1]..=hi[1] {
                        for z in lo[2]..=hi[2] {
                            g.map.entry([x, y, z]).or_default().push((si as u32, i as u32));
                        }
                    }
                }
            }
        }
        g
    }
}

/// The nearest neighbour of one side: (stroke, distance).
type Side = Option<(u32, f64)>;

#[allow(clippy::too_many_arguments)]
fn neighbours(
    grid: &SegmentGrid,
    strokes: &[Lifted],
    me: usize,
    p: Vec3,
    n: Vec3,
    t: Vec3,
    radius: f64,
    trim: f64,
) -> [Side; 2] {
    let w = cross3(n, t);
    let k = grid.key(p);
    let mut best: [Option<(f64, u32, u32, bool)>; 2] = [None, None];
    for dx in -1..=1 {
        for dy in -1..=1 {
            for dz in -1..=1 {
                let Some(list) = grid.map.get(&[k[0] + dx, k[1] + dy, k[2] + dz]) else {
                    continue;
                };
                for &(si, i) in list {
                    if si as usize == me {
                        continue;
                    }
                    let l = &strokes[si as usize];
                    let (a, b) = (l.x[i as usize], l.x[i as usize + 1]);
                    let (tt, foot) = segment_foot3(p, a, b);
                    let off = sub3(foot, p);
                    let d = norm3(off);
                    if !(d > 0.0 && d <= radius) {
                        continue;
                    }
                    let nf = l.n[i as usize];
                    if dot3(nf, n) < 0.5 {
                        continue;
                    }
                    let side_dot = dot3(off, w);
                    // Within 45° of the stroke's normal in the surface.
                    if side_dot.abs() < std::f64::consts::FRAC_1_SQRT_2 * d {
                        continue;
                    }
                    // A foot within `trim` of the neighbour's open ends does not count (the
                    // ends are left out of the neighbour's own figures too).
                    let s_foot = l.s[i as usize] + tt * norm3(sub3(b, a));
                    let at_end = !l.closed && (s_foot <= trim || s_foot >= l.len() - trim);
                    let side = usize::from(side_dot < 0.0);
                    let cand = (d, si, i, at_end);
                    let better = match best[side] {
                        None => true,
                        Some(b) => (d, si, i) < (b.0, b.1, b.2),
                    };
                    if better {
                        best[side] = Some(cand);
                    }
                }
            }
        }
    }
    best.map(|b| b.and_then(|(d, si, _, at_end)| (!at_end).then_some((si, d))))
}

fn unit(v: Vec3) -> Option<Vec3> {
    let l = norm3(v);
    (l > 0.0 && l.is_finite()).then(|| v.map(|x| x / l))
}

fn share(count: usize, length: f64, samples: usize, total_length: f64) -> Share {
    Share {
        samples: count,
        sample_fraction: if samples > 0 { count as f64 / samples as f64 } else { 0.0 },
        length_fraction: if total_length > 0.0 { length / total_length } else { 0.0 },
    }
}

/// The lifted stroke pieces of a placement, and which placement stroke each belongs to.
fn lift_placement(dom: &Domain, placement: &Placement) -> (Vec<Lifted>, Vec<usize>) {
    let mut strokes = Vec::new();
    for s in &placement.strokes {
        if dom.has_lift() {
            strokes.push(lift_stroke(dom, &s.uv, &s.faces, s.is_closed()));
        } else {
            // Without a lift a seam jump is a gap: measure each piece on its own.
            let pieces = s.pieces();
            for r in pieces.iter() {
                let closed = s.is_closed() && pieces.len() == 1;
                strokes.push(lift_stroke(dom, &s.uv[r.clone()], &s.faces[r.clone()], closed));
            }
        }
    }
    // Which placement stroke each lifted piece belongs to.
    let mut owner = Vec::with_capacity(strokes.len());
    for (i, s) in placement.strokes.iter().enumerate() {
        let k = if dom.has_lift() { 1 } else { s.pieces().len() };
        owner.extend(std::iter::repeat_n(i, k));
    }
    (strokes, owner)
}

/// The samples every figure is measured on: the lifted stroke pieces and their centres.
struct Sampling<'a> {
    /// Lifted stroke pieces.
    strokes: &'a [Lifted],
    /// Which placement stroke each lifted piece belongs to.
    owner: &'a [usize],
    /// The sample centres, piece by piece.
    cs: &'a [Centre],
    /// Arc step between the three points of a sample, mm.
    step: f64,
    /// Length left out at each end of an open stroke, mm.
    trim: f64,
    /// Arc length per sample (`step / 2`), mm.
    h: f64,
}

impl Sampling<'_> {
    /// Where a sample centre lies on the placement.
    fn place(&self, c: &Centre) -> StrokePlace {
        let l = &self.strokes[c.stroke];
        StrokePlace { stroke: self.owner[c.stroke], arc_mm: l.s[c.b], uv: l.uv[c.b], xyz: l.x[c.b] }
    }
}

/// Turning radius: the share of samples below `r_lim`, 0.95 and 0.8 of it, and the tightest.
fn turning_figures(sm: &Sampling, r_lim: f64, samples: &mut [CheckSample]) -> TurningFigures {
    let (cs, h) = (sm.cs, sm.h);
    let total_len = cs.len() as f64 * h;
    let (mut n80, mut n95, mut n100) = (0usize, 0usize, 0usize);
    let mut min: Option<(f64, usize)> = None;
    for (j, c) in cs.iter().enumerate() {
        let l = &sm.strokes[c.stroke];
        let r = turning_radius(l.n[c.b], l.x[c.a], l.x[c.b], l.x[c.c]);
        if let Some(r) = r {
            n100 += usize::from(r < r_lim);
            n95 += usize::from(r < 0.95 * r_lim);
            n80 += usize::from(r < 0.8 * r_lim);
            if min.is_none_or(|(m, _)| r < m) {
                min = Some((r, j));
            }
        }
        if let Some(s) = samples.get_mut(j) {
            s.turning_radius = r;
        }
    }
    let n = cs.len();
    TurningFigures {
        radius: r_lim,
        samples: n,
        length_mm: total_len,
        below_radius: share(n100, n100 as f64 * h, n, total_len),
        below_95: share(n95, n95 as f64 * h, n, total_len),
        below_80: share(n80, n80 as f64 * h, n, total_len),
        min_radius_mm: min.map(|m| m.0),
        max_ratio: min.map_or(0.0, |m| r_lim / m.0),
        tightest: min.map(|(_, j)| sm.place(&cs[j])),
    }
}

/// Spread rate: `|d ln δ/ds|` to the nearest neighbour on each side (within `radius`),
/// against `bound`.
fn splay_figures(
    sm: &Sampling,
    bound: f64,
    radius: f64,
    samples: &mut [CheckSample],
) -> SplayFigures {
    let (strokes, cs, h) = (sm.strokes, sm.cs, sm.h);
    let grid = SegmentGrid::new(strokes, radius);
    let sides: Vec<[Side; 2]> = cs
        .iter()
        .map(|c| {
            let l = &strokes[c.stroke];
            let n = l.n[c.b];
            match unit(proj(n, sub3(l.x[c.c], l.x[c.a]))) {
                Some(t) => neighbours(&grid, strokes, c.stroke, l.x[c.b], n, t, radius, sm.trim),
                None => [None, None],
            }
        })
        .collect();
    let (mut count, mut above, mut above110) = (0usize, 0usize, 0usize);
    let mut worst: Option<(f64, usize)> = None;
    for j in 1..cs.len().saturating_sub(1) {
        let (p, q) = (&cs[j - 1], &cs[j + 1]);
        if p.stroke != cs[j].stroke || q.stroke != cs[j].stroke {
            continue;
        }
        let l = &strokes[cs[j].stroke];
        let ds = l.arc_between(p.b, q.b);
        if ds.is_nan() || ds <= 0.0 || ds > 3.0 * sm.step {
            continue;
        }
        for (side, (before, after)) in sides[j - 1].iter().zip(&sides[j + 1]).enumerate() {
            let (Some((s0, d0)), Some((s1, d1))) = (*before, *after) else {
                continue;
            };
            if s0 != s1 {
                continue;
            }
            let rate = (d1.ln() - d0.ln()) / ds;
            if !rate.is_finite() {
                continue;
            }
            count += 1;
            above += usize::from(rate.abs() > bound);
            above110 += usize::from(rate.abs() > 1.1 * bound);
            if worst.is_none_or(|(w, _)| rate.abs() > w) {
                worst = Some((rate.abs(), j));
            }
            if let Some(s) = samples.get_mut(j) {
                s.spread[side] = Some(rate);
            }
        }
    }
    let max_rate = worst.map_or(0.0, |w| w.0);
    let tl = count as f64 * h;
    SplayFigures {
        bound,
        samples: count,
        max_rate,
        max_ratio: max_rate / bound,
        above_bound: share(above, above as f64 * h, count, tl),
        above_110: share(above110, above110 as f64 * h, count, tl),
        worst: worst.map(|(_, j)| sm.place(&cs[j])),
    }
}

/// Deviation of the strokes through lock `pi` (`probe`) from the lock's direction.
fn lock_figures(
    dom: &Domain,
    sm: &Sampling,
    pi: usize,
    probe: &LockProbe,
    samples: &mut [CheckSample],
) -> LockFigures {
    let nv = dom.uv.len();
    let mut dir: Vec<Option<Vec3>> = vec![None; nv];
    for (&v, d) in probe.vertices.iter().zip(&probe.directions) {
        if let Some(slot) = dir.get_mut(v as usize) {
            *slot = Some(*d);
        }
    }
    let (mut count, mut sum) = (0usize, 0.0);
    let mut worst: Option<(f64, usize)> = None;
    let mut touched = std::collections::BTreeSet::new();
    for (j, c) in sm.cs.iter().enumerate() {
        let l = &sm.strokes[c.stroke];
        let f = l.face[c.b];
        let t = dom.tris[f as usize];
        let Some(ds) = t.iter().map(|&v| dir[v as usize]).collect::<Option<Vec<Vec3>>>() else {
            continue;
        };
        let n = l.n[c.b];
        // The local tangent: the chord between the sample's adjacent vertices (the step's
        // chord would reach outside the region).
        let last = l.x.len() - 1;
        let (prev, next) = if l.closed {
            (if c.b == 0 { last - 1 } else { c.b - 1 }, c.b + 1)
        } else {
            (c.b.saturating_sub(1), (c.b + 1).min(last))
        };
        let Some(tan) = unit(proj(n, sub3(l.x[next], l.x[prev]))) else { continue };
        let mut target = [0.0; 3];
        for (i, d) in ds.iter().enumerate() {
            let mut d = if dom.has_lift() { *d } else { [d[0], d[1], 0.0] };
            if dot3(d, ds[0]) < 0.0 {
                d = d.map(|x| -x);
            }
            for k in 0..3 {
                target[k] += l.bary[c.b][i].max(0.0) * d[k];
            }
        }
        let Some(target) = unit(proj(n, target)) else { continue };
        let cosang = dot3(tan, target).abs().min(1.0);
        let sinang = norm3(cross3(tan, target));
        let dev = sinang.atan2(cosang).to_degrees();
        count += 1;
        sum += dev;
        touched.insert(sm.owner[c.stroke]);
        if worst.is_none_or(|(w, _)| dev > w) {
            worst = Some((dev, j));
        }
        if let Some(s) = samples.get_mut(j) {
            s.lock_deviation = Some((pi, dev));
        }
    }
    LockFigures {
        name: probe.name.clone(),
        samples: count,
        strokes: touched.len(),
        max_deviation_deg: worst.map_or(0.0, |w| w.0),
        mean_deviation_deg: if count > 0 { sum / count as f64 } else { 0.0 },
        worst: worst.map(|(_, j)| sm.place(&sm.cs[j])),
    }
}

/// Measures the figures of `opts` on the placed strokes (module docs).
pub fn check_strokes(
    dom: &Domain,
    placement: &Placement,
    opts: &StrokeCheckOptions,
) -> Result<StrokeChecks> {
    opts.validate()?;
    let step = opts.step.unwrap_or(0.5 * placement.width);
    let trim = opts.trim.unwrap_or(placement.width);
    let radius = opts.neighbour_radius.unwrap_or(2.5 * placement.d_sep);
    let (strokes, owner) = lift_placement(dom, placement);
    let mut cs = Vec::new();
    for (i, l) in strokes.iter().enumerate() {
        centres(l, i, step, trim, &mut cs);
    }
    let sm = Sampling { strokes: &strokes, owner: &owner, cs: &cs, step, trim, h: 0.5 * step };
    let mut samples: Vec<CheckSample> = Vec::new();
    if opts.keep_samples {
        samples = cs
            .iter()
            .map(|c| CheckSample {
                at: sm.place(c),
                turning_radius: None,
                spread: [None, None],
                lock_deviation: None,
            })
            .collect();
    }
    // Turning radius.
    let turning = opts.turning_radius.map(|r_lim| turning_figures(&sm, r_lim, &mut samples));
    // Keep the turning radius even when only splay or locks were asked for the samples.
    if opts.keep_samples && opts.turning_radius.is_none() {
        for (j, c) in cs.iter().enumerate() {
            let l = &strokes[c.stroke];
            samples[j].turning_radius = turning_radius(l.n[c.b], l.x[c.a], l.x[c.b], l.x[c.c]);
        }
    }
    // Spread rate.
    let splay = opts.splay.map(|bound| splay_figures(&sm, bound, radius, &mut samples));
    // Locks.
    let mut locks = Vec::new();
    for (pi, probe) in opts.locks.iter().enumerate() {
        locks.push(lock_figures(dom, &sm, pi, probe, &mut samples));
    }
    Ok(StrokeChecks {
        step_mm: step,
        trim_mm: trim,
        on_surface: dom.has_lift(),
        turning,
        splay,
        locks,
        samples,
    })
}

/// What [`cut_tight_ends`] did.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Serialize, Deserialize)]
pub struct TightEndCuts {
    /// Stroke ends cut back (a stroke cut at both ends counts twice).
    pub cuts: usize,
    /// Strokes dropped because less than one brush width was left.
    pub dropped: usize,
}

/// Planning that respects the tool (issue 17, item 4): every open stroke end that stopped at a
/// boundary (a chart edge or an uncrossed seam) or at a singularity's exclusion zone is cut
/// back, within two brush widths of that end, to just past its tightest-turning sample whose
/// turning radius (S1, step = half the brush width, on the part) is below `radius`, so the
/// stroke ends where the tool can still follow it. A stroke left shorter than one brush width is
/// dropped. Interior turns, closed loops and ends that stopped near another stroke are left as
/// they are (the run report's `stroke_constraints` measures them).
pub fn cut_tight_ends(dom: &Domain, placement: &mut Placement, radius: f64) -> TightEndCuts {
    use crate::trace::StopReason;
    let mut out = TightEndCuts::default();
    if !(radius.is_finite() && radius > 0.0) {
        return out;
    }
    let width = placement.width;
    let step = 0.5 * width;
    let zone = 2.0 * width;
    let cuttable = |r: StopReason| matches!(r, StopReason::Boundary | StopReason::Singularity);
    let mut kept = Vec::with_capacity(placement.strokes.len());
    for mut s in std::mem::take(&mut placement.strokes) {
        if s.is_closed() || s.uv.len() < 3 || !(cuttable(s.start) || cuttable(s.end)) {
            kept.push(s);
            continue;
        }
        let l = lift_stroke(dom, &s.uv, &s.faces, false);
        if l.x.len() != s.uv.len() {
            kept.push(s); // a point without a normal: leave the stroke alone
            continue;
        }
        let n = l.x.len();
        let len = l.len();
        let rho = |i: usize| -> Option<f64> {
            let mut a = l.nearest(l.s[i] - step);
            let mut c = l.nearest(l.s[i] + step);
            if a == i {
                a = i.checked_sub(1)?;
            }
            if c == i {
                c = i + 1;
                if c >= n {
                    return None;
                }
            }
            turning_radius(l.n[i], l.x[a], l.x[i], l.x[c])
        };
        let (mut first, mut last) = (0usize, n - 1);
        if cuttable(s.start) {
            if let Some(i) = (1..n - 1)
                .rev()
                .filter(|&i| l.s[i] <= zone)
                .find(|&i| rho(i).is_some_and(|r| r < radius))
            {
                first = i;
            }
        }
        if cuttable(s.end) {
            if let Some(i) = (1..n - 1)
                .filter(|&i| len - l.s[i] <= zone)
                .find(|&i| rho(i).is_some_and(|r| r < radius))
            {
                last = i;
            }
        }
        if first == 0 && last == n - 1 {
            kept.push(s);
            continue;
        }
        out.cuts += usize::from(first > 0) + usize::from(last < n - 1);
        if last <= first || l.s[last] - l.s[first] < width {
            out.dropped += 1;
            continue;
        }
        // The kept piece, its seam breaks and its length on the part (seam jumps excluded, as
        // the tracer measures).
        let breaks: Vec<usize> =
            s.breaks.iter().filter(|&&b| b > first && b <= last).map(|&b| b - first).collect();
        s.uv = s.uv[first..=last].to_vec();
        s.faces = s.faces[first..=last].to_vec();
        s.length = (1..s.uv.len())
            .filter(|j| !breaks.contains(j))
            .map(|j| dom.metric[s.faces[j] as usize].length(crate::geom::sub(s.uv[j], s.uv[j - 1])))
            .sum();
        s.breaks = breaks;
        kept.push(s);
    }
    placement.strokes = kept;
    out
}
