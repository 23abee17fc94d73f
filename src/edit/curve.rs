//! The curve tool (beyond the paper): highlight curves drawn by the designer.
//!
//! The curves are polylines either in UV space — given inline (`uv`) or as the paths of an SVG
//! file (`svg`) drawn over the UV square — or in space (`points`, 3D points near the surface).
//! Each vertex closer than the radius r to a curve gets the curve's tangent at the closest point
//! as its target ℓ*, with weight w·(1 − d²/r²)²; the other vertices keep their current ℓ.
//!
//! **UV curves.** A vertex has one UV position per chart around it (a seam vertex has several);
//! each chart has a Jacobian Jᵢ = ∂p/∂(u, v) (3×2), the corner-angle-weighted mean of the
//! per-face Jacobians [e₁ e₂][d₁ d₂]⁻¹ (e the 3D edges, d the UV edges). Distances are measured
//! in the metric G = JᵀJ (the first fundamental form: |J Δuv| is the distance in scene units to
//! first order), so the closest point of a segment is the G-orthogonal projection; the UV tangent
//! τ becomes J τ, projected onto the tangent plane. The chart giving the smallest distance wins.
//!
//! **SVG.** Every shape of the file (read by [`crate::svg_read`], usvg: paths with every
//! command, arcs included, rects, circles, ellipses, lines, polylines, polygons, `<use>`,
//! transforms, styles; `display: none` left out) is flattened to chords within `tolerance`
//! (UV units). The viewBox (or, without one, `0 0 width height`) maps to the UV square:
//! u = (x − x₀)/w, v = 1 − (y − y₀)/h (SVG's y points down, v up), stretched to it whatever
//! the root's `preserveAspectRatio`. A closed subpath ends with its first point again.
//!
//! **Magnitude.** ℓ* has the length max(|ℓᵢ|, median |ℓ|): a curve asks for a clear highlight
//! direction even where the current ℓ is nearly zero.
//!
//! **Position** (docs/math.md §9). The tangent targets only make the highlights *parallel* to
//! the curve; the position target puts the key light's highlight *on* it. With d the signed
//! distance of vertex i from the closest curve (positive to the left of the curve's direction,
//! seen from the normal; behind an end the offset along the tangent does not count, so d → 0
//! continuously), ĝ*ᵢ = (1 − β) ĝᵢ + β σ oᵢ tanh(d/width): β = 1 up to half the radius and
//! falls smoothly to 0 at the radius (so the zero of ĝ* is on the curve exactly and the target
//! joins the current field at the tube's edge); σ = ±1, one per polyline, is the side that
//! agrees best with the current ĝ (the smaller change); oᵢ = ±1 orients a line field
//! consistently over the tube (1 for k = 1).

use std::path::Path;

use nalgebra::{Matrix2, Vector2, Vector3};
use serde::{Deserialize, Serialize};

use super::{check_radius, check_weight, Context, EditReport, State};
use crate::{Error, Result};

/// A curve edit: `{"tool": "curve", "svg": "highlights.svg", "radius": 2}` (or `"uv"` or
/// `"points"` instead of `"svg"`).
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize, schemars::JsonSchema)]
#[serde(deny_unknown_fields)]
pub struct CurveEdit {
    /// An SVG file of paths over the UV square (already resolved by the caller).
    #[serde(default)]
    pub svg: Option<String>,
    /// Polylines in UV coordinates.
    #[serde(default)]
    pub uv: Option<Vec<Vec<[f64; 2]>>>,
    /// Polylines of 3D points near the surface, scene units.
    #[serde(default)]
    pub points: Option<Vec<Vec<[f64; 3]>>>,
    /// Vertices closer than this to a curve (scene units) get its tangent as target.
    pub radius: f64,
    /// Weight of the targets on the curve (default 1), falling off as (1 − d²/r²)².
    #[serde(default = "super::one")]
    pub weight: f64,
    /// Flattening tolerance of SVG Bézier curves, UV units (default 0.001).
    #[serde(default = "default_tolerance")]
    pub tolerance: f64,
    /// The sharpness of the highlight put on the curve, scene units (default: the radius): the
    /// position target is ĝ* = tanh(d/width) at signed distance d from the curve, so the grain
    /// turns from across h (on the curve) by 50° at d = width. A rendered highlight is about
    /// α·width/|h̄| wide for a BRDF of roughness α along the grain: smaller is sharper (and
    /// turns the grain faster; mind a turning-radius constraint).
    #[serde(default)]
    pub width: Option<f64>,
}

fn default_tolerance() -> f64 {
    1e-3
}

impl CurveEdit {
    /// Range-checks every number; exactly one of `svg`, `uv`, `points`.
    pub fn validate(&self) -> Result<()> {
        let given = [self.svg.is_some(), self.uv.is_some(), self.points.is_some()];
        if given.iter().filter(|g| **g).count() != 1 {
            return Err(Error::setting("svg", "give exactly one of `svg`, `uv` or `points`"));
        }
        check_radius("radius", self.radius)?;
        check_weight("weight", self.weight)?;
        if !(self.tolerance.is_finite() && self.tolerance > 0.0 && self.tolerance <= 0.1) {
            return Err(Error::setting(
                "tolerance",
                format!("must be within (0, 0.1], got {}", crate::error::fmt_num(self.tolerance)),
            ));
        }
        if let Some(w) = self.width {
            check_radius("width", w)?;
        }
        if let Some(lines) = &self.uv {
            check_polylines("uv", lines)?;
        }
        if let Some(lines) = &self.points {
            check_polylines("points", lines)?;
        }
        Ok(())
    }
}

fn check_polylines<const N: usize>(key: &str, lines: &[Vec<[f64; N]>]) -> Result<()> {
    if lines.is_empty() {
        return Err(Error::setting(key, "holds no polyline"));
    }
    check_point_count(key, lines.iter().map(Vec::len).sum())?;
    for (k, l) in lines.iter().enumerate() {
        if l.len() < 2 {
            return Err(Error::setting(format!("{key}[{k}]"), "needs at least two points"));
        }
        if let Some(j) = l.iter().position(|p| !p.iter().all(|c| c.is_finite())) {
            return Err(Error::setting(format!("{key}[{k}][{j}]"), "coordinates must be finite"));
        }
    }
    Ok(())
}

/// Refuses a curve of more than [`crate::limits::MAX_CURVE_POINTS`] points, naming `key`.
fn check_point_count(key: &str, n: usize) -> Result<()> {
    let max = crate::limits::MAX_CURVE_POINTS;
    if n > max {
        return Err(Error::setting(
            key,
            format!("holds {n} points, more than the {max} a curve edit may have"),
        ));
    }
    Ok(())
}

/// Reads the paths of an SVG file as UV polylines (module documentation).
pub fn read_svg_polylines(path: &Path, tolerance: f64) -> Result<Vec<Vec<Vector2<f64>>>> {
    let text = crate::output::read_bounded_text(path, crate::limits::MAX_SVG_BYTES, "an SVG file")?;
    svg_polylines(&text, path, tolerance)
}

/// Parses SVG text into UV polylines; the error is a message (the caller adds the file).
pub fn parse_svg_polylines(
    text: &str,
    tolerance: f64,
) -> std::result::Result<Vec<Vec<Vector2<f64>>>, String> {
    svg_polylines(text, Path::new("svg"), tolerance).map_err(|e| match e {
        Error::Parse { line: 0, message, .. } => message,
        Error::Parse { line, message, .. } => format!("line {line}: {message}"),
        e => e.to_string(),
    })
}

/// The shapes of an SVG ([`crate::svg_read`]) as UV polylines: the canvas (the viewBox, or
/// `0 0 width height`) maps to the UV square, u = x / W, v = 1 − y / H.
fn svg_polylines(text: &str, name: &Path, tolerance: f64) -> Result<Vec<Vec<Vector2<f64>>>> {
    // The viewBox maps onto the whole UV square, whatever the aspect ratio of the root's
    // width and height (as this reader always did); tolerance in UV units.
    let options = crate::svg_read::ReadOptions {
        tolerance: crate::svg_read::Tolerance::OfCanvas(tolerance),
        stretch: true,
    };
    let drawing = crate::svg_read::read_with(text, name, &options)?;
    let (w, h) = (drawing.width_px, drawing.height_px);
    let mut out = Vec::new();
    for shape in drawing.shapes {
        for sub in shape.subpaths {
            let mut line: Vec<Vector2<f64>> =
                sub.points.iter().map(|p| Vector2::new(p[0] / w, 1.0 - p[1] / h)).collect();
            if sub.closed {
                // A closed subpath ends where it starts.
                line.push(line[0]);
            }
            if line.len() >= 2 {
                out.push(line);
            }
        }
    }
    if out.is_empty() {
        return Err(Error::Parse {
            path: name.to_path_buf(),
            line: 0,
            message: "no path with at least two points".into(),
        });
    }
    Ok(out)
}

/// The closest point of segment ab to p in the metric G: (parameter t, squared G-distance).
fn closest_on_segment(
    p: &Vector2<f64>,
    a: &Vector2<f64>,
    b: &Vector2<f64>,
    g: &Matrix2<f64>,
) -> (f64, f64) {
    let e = b - a;
    let ee = e.dot(&(g * e));
    let t = if ee > 0.0 { ((p - a).dot(&(g * e)) / ee).clamp(0.0, 1.0) } else { 0.0 };
    let d = a + e * t - p;
    (t, d.dot(&(g * d)))
}

/// Applies a curve edit.
pub(crate) fn apply(
    ctx: &Context,
    st: &mut State,
    e: &CurveEdit,
    report: &mut EditReport,
) -> Result<()> {
    let mut norms: Vec<f64> = st.ell.iter().map(|l| l.norm()).collect();
    let median = if norms.is_empty() {
        0.0
    } else {
        let mid = norms.len() / 2;
        *norms.select_nth_unstable_by(mid, |a, b| a.total_cmp(b)).1
    };
    // The position targets need the triangles the curve crosses to have their corners inside
    // the tube (β = 1 up to half of it): on a mesh coarser than the radius, they reach two
    // median edge lengths from the curve.
    let edge = median_edge_length(ctx.mesh);
    let reach = e.radius.max(2.0 * edge);
    if reach > e.radius {
        report.notes.push(format!(
            "the radius {} is less than two median edge lengths ({:.3}): the position targets \
             reach {reach:.3} from the curve so that the mesh can carry the highlight",
            e.radius, edge
        ));
    }
    let (found, polylines) = if let Some(points) = &e.points {
        let lines: Vec<Vec<Vector3<f64>>> = points
            .iter()
            .map(|l| l.iter().map(|p| Vector3::new(p[0], p[1], p[2])).collect())
            .collect();
        report.polylines = Some(lines.len());
        report.segments = Some(lines.iter().map(|l| l.len() - 1).sum());
        (space_targets(ctx, &lines, reach), lines)
    } else {
        let lines: Vec<Vec<Vector2<f64>>> = match (&e.svg, &e.uv) {
            (Some(path), _) => {
                let lines = read_svg_polylines(Path::new(path), e.tolerance)?;
                check_point_count("svg", lines.iter().map(Vec::len).sum())?;
                lines
            }
            (None, Some(uv)) => {
                uv.iter().map(|l| l.iter().map(|p| Vector2::new(p[0], p[1])).collect()).collect()
            }
            (None, None) => Vec::new(),
        };
        report.polylines = Some(lines.len());
        report.segments = Some(lines.iter().map(|l| l.len().saturating_sub(1)).sum());
        let key = if e.svg.is_some() { "svg" } else { "uv" };
        let found = uv_targets(ctx, &lines, reach).ok_or_else(|| {
            Error::setting(key, "the mesh has no UV coordinates; give 3D `points` instead")
        })?;
        (found, super::uv_lift::lift_uv_polylines(ctx.mesh, &lines))
    };
    let support = (0..found.len())
        .filter(|&i| found[i].is_some_and(|h| h.distance < e.radius))
        .map(|i| i as u32)
        .collect();
    report.shape = Some(super::shape::EditShape::Curve { radius: e.radius, polylines, support });
    let mut count = 0;
    let mut critical = 0;
    let width = e.width.unwrap_or(e.radius);
    let (profile, design) = position_profile(ctx, st, &found, reach, width);
    for (i, hit) in found.iter().enumerate() {
        let Some(hit) = hit else { continue };
        st.set_support(i);
        if st.critical[i] {
            critical += 1;
            continue;
        }
        // The optimizer starts from the designed grain, which meets its position row; the rows
        // keep the full weight over the tube, as the grain itself turns back into the current
        // field at the tube's edge.
        let g = match design[i] {
            Some(phi) => st.design(ctx, i, phi),
            None => profile[i],
        };
        st.set_target_g(i, g, e.weight);
        if hit.distance >= e.radius {
            continue;
        }
        let n = ctx.normals[i];
        let t = hit.tangent - n * n.dot(&hit.tangent);
        let w = e.weight * (1.0 - (hit.distance / e.radius).powi(2)).powi(2);
        if !(t.norm() > 1e-9 * hit.tangent.norm()) || !(w > 0.0) {
            continue;
        }
        let len = st.ell[i].norm().max(median);
        let len = if len > 0.0 { len } else { 1.0 };
        st.set_target(i, t.normalize() * len, w);
        count += 1;
    }
    report.vertices = count;
    report.critical_vertices = critical;
    if critical > 0 {
        report.notes.push(format!(
            "the curve passes within its radius of {critical} critical points (h ∥ n): every \
             highlight goes through them whatever the grain, so the highlight cannot follow the \
             curve there"
        ));
    }
    if count == 0 && critical == 0 {
        return Err(Error::setting(
            "radius",
            format!(
                "the curves come within {} of no vertex: check that they lie on the part \
                 (UV curves: in the mesh's UV range) or increase the radius",
                e.radius
            ),
        ));
    }
    Ok(())
}

/// The closest curve of a vertex within the radius.
#[derive(Clone, Copy, Debug)]
struct Hit {
    /// Distance to the curve (scene units).
    distance: f64,
    /// The curve's 3D tangent at the closest point (not normalized).
    tangent: Vector3<f64>,
    /// The vertex minus the closest point (3D, scene units, to first order for UV curves).
    offset: Vector3<f64>,
    /// Which polyline.
    line: usize,
}

/// The median length of the mesh's edges (each interior edge counted twice; 0 without faces).
fn median_edge_length(mesh: &crate::mesh::Mesh) -> f64 {
    let mut lengths: Vec<f64> = (0..mesh.num_faces())
        .flat_map(|f| {
            let [a, b, c] = mesh.face_positions(f);
            [(b - a).norm(), (c - b).norm(), (a - c).norm()]
        })
        .filter(|l| l.is_finite())
        .collect();
    if lengths.is_empty() {
        return 0.0;
    }
    let mid = lengths.len() / 2;
    *lengths.select_nth_unstable_by(mid, |a, b| a.total_cmp(b)).1
}

/// β of the position profile: 1 up to half the radius, then a smoothstep down to 0 at it.
fn blend(d: f64, radius: f64) -> f64 {
    let x = ((d / radius - 0.5) / 0.5).clamp(0.0, 1.0);
    1.0 - x * x * (3.0 - 2.0 * x)
}

/// A finite f64 ordered totally (the spanning tree's priority).
#[derive(Clone, Copy, Debug, PartialEq)]
struct Clarity(f64);
impl Eq for Clarity {}
impl PartialOrd for Clarity {
    fn partial_cmp(&self, other: &Self) -> Option<std::cmp::Ordering> {
        Some(self.cmp(other))
    }
}
impl Ord for Clarity {
    fn cmp(&self, other: &Self) -> std::cmp::Ordering {
        self.0.total_cmp(&other.0)
    }
}

/// Per vertex, the designed grain φ* ([`designed_grain`]), or where there is none (no hit, or
/// h̄ vanishes) the position target ĝ* (module docs, "Position"; the current target without a
/// hit). A designed vertex's ĝ entry is unused (its current target): its target is the ĝ of
/// φ* ([`State::design`]).
fn position_profile(
    ctx: &Context,
    st: &State,
    found: &[Option<Hit>],
    radius: f64,
    width: f64,
) -> (Vec<f64>, Vec<Option<f64>>) {
    let n = found.len();
    // oᵢ: an orientation of a line field over the tube (k = 1: all +1), grown along a maximum
    // spanning tree of |uᵢ·uⱼ| from the lowest vertex of each connected piece, so that it
    // follows the edges where the start says clearly how two grains are oriented and leaves
    // the disagreements of a rough start to edges where they turn by nearly a right angle.
    let mut orient = vec![0.0f64; n];
    let line_field = ctx.symmetry == crate::highlight::Symmetry::Line;
    for seed in 0..n {
        if found[seed].is_none() || orient[seed] != 0.0 {
            continue;
        }
        orient[seed] = 1.0;
        // (clarity, Reverse(vertex), sign) — the clearest edge first, ties by the lower vertex.
        let mut heap = std::collections::BinaryHeap::new();
        let push = |heap: &mut std::collections::BinaryHeap<_>, i: usize, orient: &[f64]| {
            let ui = ctx.grain(&st.phi, i) * orient[i];
            for &j in ctx.geom.adjacency.neighbors(i) {
                let j = j as usize;
                if found[j].is_none() || orient[j] != 0.0 {
                    continue;
                }
                let d = if line_field { ctx.grain(&st.phi, j).dot(&ui) } else { 1.0 };
                let d = if d.is_finite() { d } else { 0.0 };
                let sign: i8 = if d >= 0.0 { 1 } else { -1 };
                heap.push((Clarity(d.abs()), std::cmp::Reverse(j), sign));
            }
        };
        push(&mut heap, seed, &orient);
        while let Some((_, std::cmp::Reverse(j), sign)) = heap.pop() {
            if orient[j] != 0.0 {
                continue;
            }
            orient[j] = f64::from(sign);
            push(&mut heap, j, &orient);
        }
    }
    // The signed distance: the offset's component across the tangent, seen from the normal.
    let signed: Vec<f64> = found
        .iter()
        .enumerate()
        .map(|(i, h)| {
            h.map_or(0.0, |h| {
                let t = h.tangent.normalize();
                ctx.normals[i].dot(&t.cross(&h.offset))
            })
        })
        .collect();
    // σ per polyline: the side whose profile agrees best with the current ĝ.
    let lines = found.iter().flatten().map(|h| h.line + 1).max().unwrap_or(0);
    let mut agree = vec![0.0f64; lines];
    for (i, h) in found.iter().enumerate() {
        if let Some(h) = h {
            let b = blend(h.distance, radius) * ctx.geom.areas[i].max(0.0);
            agree[h.line] += b * orient[i] * st.target_g[i] * (signed[i] / width).tanh();
        }
    }
    let sigma: Vec<f64> = agree.iter().map(|&a| if a < 0.0 { -1.0 } else { 1.0 }).collect();
    let tube = Tube { found, orient: &orient, signed: &signed, sigma: &sigma, radius, width };
    // The core's side of h̄ with the smaller turn over the ring.
    let designs = [designed_grain(ctx, st, &tube, 1.0), designed_grain(ctx, st, &tube, -1.0)];
    let design = if designs[1].1 < designs[0].1 { &designs[1].0 } else { &designs[0].0 };
    (0..n)
        .map(|i| match (&found[i], design[i]) {
            (Some(_), Some(phi)) => (st.target_g[i], Some(phi)),
            (Some(h), None) => {
                let b = blend(h.distance, radius);
                let wanted = sigma[h.line] * orient[i] * (signed[i] / width).tanh();
                let g = (1.0 - b) * st.target_g[i] + b * wanted;
                (if g.is_finite() { g } else { st.target_g[i] }, None)
            }
            (None, _) => (st.target_g[i], None),
        })
        .unzip()
}

/// A curve's tube: the closest curve of every vertex, the orientation of a line field over it,
/// the signed distances and the side σ of each polyline's profile.
struct Tube<'a> {
    found: &'a [Option<Hit>],
    orient: &'a [f64],
    signed: &'a [f64],
    sigma: &'a [f64],
    radius: f64,
    width: f64,
}

/// The grain the curve asks for over its tube, designed as angles (docs/math.md §9, "curve"):
/// per vertex φ* (`None` where h̄ vanishes: a critical point), and the squared turn
/// Σ A (φ* − φ)² it costs.
///
/// In the core the grain is the profile's: ψ_c = s arccos(σ o tanh(d/width)) from h̄ on the
/// core's side `s`. Out to the tube's edge it turns back to the field before the edit by a
/// fraction β of D = ψ_c − ψ₀, the turn between the two, *lifted continuously* over the tube
/// (modulo a half-turn for a line field, whose two orientations are one grain): φ* = φ + β D.
/// D is continuous wherever the field before the edit and the profile are, so φ* has no
/// singularity the two do not have. (A blend of ĝ instead cannot leave the side of h̄ it
/// starts on — ĝ would have to reach ±1 — so where the field before the edit crossed its own
/// highlight near the curve, no grain realised it without singular triangles.) The lift is
/// grown from the smallest steps first and shifted by whole periods for the smallest turn.
fn designed_grain(ctx: &Context, st: &State, tube: &Tube, side: f64) -> (Vec<Option<f64>>, f64) {
    use crate::geometry::connection::wrap_angle;
    use std::f64::consts::{PI, TAU};
    let Tube { found, orient, signed, sigma, radius, width } = *tube;
    let n = found.len();
    let line_field = ctx.symmetry == crate::highlight::Symmetry::Line;
    let period = if line_field { PI } else { TAU };
    // Wrapped to (−period/2, period/2].
    let k = TAU / period;
    let wrap = |x: f64| wrap_angle(k * x) / k;
    // D, the turn from the field before the edit to the profile (NaN where h̄ vanishes).
    let mut turn = vec![f64::NAN; n];
    for i in 0..n {
        let (Some(h), Some(theta)) = (&found[i], st.h_angle(ctx, i)) else { continue };
        let psi0 = st.phi[i] + if orient[i] < 0.0 { PI } else { 0.0 } - theta;
        let profile = (sigma[h.line] * (signed[i] / width).tanh()).clamp(-1.0, 1.0);
        let d = wrap_angle(side * profile.acos() - psi0);
        turn[i] = if d.is_finite() { d } else { f64::NAN };
    }
    // Lift D over each connected piece of the tube: Prim's order on the smallest steps.
    let mut lift = vec![f64::NAN; n];
    let mut cost = 0.0;
    for seed in 0..n {
        if turn[seed].is_nan() || !lift[seed].is_nan() {
            continue;
        }
        lift[seed] = wrap(turn[seed]);
        let mut piece = vec![seed];
        // (−|step|, Reverse(vertex), value): the smallest step first, ties by the lower vertex.
        let mut heap = std::collections::BinaryHeap::new();
        let push = |heap: &mut std::collections::BinaryHeap<_>, i: usize, lift: &[f64]| {
            for &j in ctx.geom.adjacency.neighbors(i) {
                let j = j as usize;
                if turn[j].is_nan() || !lift[j].is_nan() {
                    continue;
                }
                let step = wrap(turn[j] - turn[i]);
                heap.push((Clarity(-step.abs()), std::cmp::Reverse(j), Clarity(lift[i] + step)));
            }
        };
        push(&mut heap, seed, &lift);
        while let Some((_, std::cmp::Reverse(j), Clarity(v))) = heap.pop() {
            if lift[j].is_nan() {
                lift[j] = v;
                piece.push(j);
                push(&mut heap, j, &lift);
            }
        }
        // The whole number of periods that makes the weighted turn smallest.
        let (mut num, mut den) = (0.0, 0.0);
        for &i in &piece {
            let b = found[i].map_or(0.0, |h| blend(h.distance, radius));
            let w = b * b * ctx.geom.areas[i].max(0.0);
            num += w * lift[i];
            den += w;
        }
        let shift = if den > 0.0 { period * (num / den / period).round() } else { 0.0 };
        for &i in &piece {
            lift[i] -= shift;
            let b = found[i].map_or(0.0, |h| blend(h.distance, radius));
            cost += ctx.geom.areas[i].max(0.0) * (b * lift[i]).powi(2);
        }
    }
    let design = (0..n)
        .map(|i| {
            let h = found[i]?;
            if !lift[i].is_finite() {
                return None;
            }
            let phi = st.phi[i] + blend(h.distance, radius) * lift[i];
            phi.is_finite().then_some(phi)
        })
        .collect();
    (design, cost)
}

/// Per vertex, the closest 3D polyline within `radius`.
fn space_targets(ctx: &Context, lines: &[Vec<Vector3<f64>>], radius: f64) -> Vec<Option<Hit>> {
    let mut lo = Vector3::repeat(f64::INFINITY);
    let mut hi = Vector3::repeat(f64::NEG_INFINITY);
    for p in lines.iter().flatten() {
        lo = lo.inf(p);
        hi = hi.sup(p);
    }
    let (lo, hi) = (lo.add_scalar(-radius), hi.add_scalar(radius));
    // The segments in order (line by line), and a grid of them: each vertex meets the
    // segments near it in that order (the same closest segment on ties).
    let segments: Vec<(usize, [Vector3<f64>; 2])> = lines
        .iter()
        .enumerate()
        .flat_map(|(line, l)| l.windows(2).map(move |s| (line, [s[0], s[1]])))
        .collect();
    let ends: Vec<([f64; 3], [f64; 3])> =
        segments.iter().map(|(_, s)| (s[0].into(), s[1].into())).collect();
    let grid = super::segment_grid::SegmentGrid::new(&ends, 2.0 * radius);
    let mut near = Vec::new();
    ctx.mesh
        .positions
        .iter()
        .map(|p| {
            if (0..3).any(|k| p[k] < lo[k] || p[k] > hi[k]) {
                return None;
            }
            let mut best: Option<Hit> = None;
            grid.near(&(*p).into(), radius, &mut near);
            for &k in &near {
                let (line, s) = segments[k as usize];
                {
                    let e = s[1] - s[0];
                    let ee = e.norm_squared();
                    if !(ee > 0.0) {
                        continue;
                    }
                    let t = ((p - s[0]).dot(&e) / ee).clamp(0.0, 1.0);
                    let offset = p - (s[0] + e * t);
                    let d = offset.norm();
                    if d < radius && best.is_none_or(|b| d < b.distance) {
                        best = Some(Hit { distance: d, tangent: e, offset, line });
                    }
                }
            }
            best
        })
        .collect()
}

/// Per vertex, the closest UV polyline within `radius`, measured through the UV Jacobian of
/// each of the vertex's charts. `None` if the mesh has no UVs.
fn uv_targets(ctx: &Context, lines: &[Vec<Vector2<f64>>], radius: f64) -> Option<Vec<Option<Hit>>> {
    let mesh = ctx.mesh;
    let uv = mesh.uv.as_ref()?;
    let face_jacobian: Vec<Option<[Vector3<f64>; 2]>> = (0..mesh.num_faces())
        .map(|f| {
            let [p0, p1, p2] = mesh.face_positions(f);
            let [t0, t1, t2] = uv.face(f);
            let (e1, e2, d1, d2) = (p1 - p0, p2 - p0, t1 - t0, t2 - t0);
            let det = d1.x * d2.y - d2.x * d1.y;
            let scale = d1.norm() * d2.norm();
            if !(det.abs() > 1e-12 * scale && scale > 0.0) {
                return None;
            }
            let ju = (e1 * d2.y - e2 * d1.y) / det;
            let jv = (e2 * d1.x - e1 * d2.x) / det;
            (ju.iter().chain(jv.iter()).all(|c| c.is_finite())).then_some([ju, jv])
        })
        .collect();
    let mut lo = Vector2::repeat(f64::INFINITY);
    let mut hi = Vector2::repeat(f64::NEG_INFINITY);
    for p in lines.iter().flatten() {
        lo = lo.inf(p);
        hi = hi.sup(p);
    }
    let r2 = radius * radius;
    // The segments in order (line by line), and a grid of them in UV, its cell twice the
    // radius at the mesh's mean UV scale (the cell only sets the speed, not the result).
    let segments: Vec<(usize, [Vector2<f64>; 2])> = lines
        .iter()
        .enumerate()
        .flat_map(|(line, l)| l.windows(2).map(move |s| (line, [s[0], s[1]])))
        .collect();
    let ends: Vec<([f64; 2], [f64; 2])> =
        segments.iter().map(|(_, s)| (s[0].into(), s[1].into())).collect();
    let area_uv = (0..mesh.num_faces()).fold(0.0, |u, f| {
        let [t0, t1, t2] = uv.face(f);
        let d = 0.5 * (t1 - t0).perp(&(t2 - t0)).abs();
        u + if d.is_finite() { d } else { 0.0 }
    });
    let scale = (area_uv / mesh.area()).sqrt();
    let grid = super::segment_grid::SegmentGrid::new(&ends, 2.0 * radius * scale);
    let mut near = Vec::new();
    Some(
        (0..mesh.num_vertices())
            .map(|v| {
                // (uv index, angle sum, Σ angle·J) per chart around v.
                let mut charts: Vec<(u32, f64, [Vector3<f64>; 2])> = Vec::new();
                for &(f, c) in ctx.vf.of(v) {
                    let (f, c) = (f as usize, c as usize);
                    let Some(j) = face_jacobian[f] else { continue };
                    let tri = mesh.face_positions(f);
                    let angle = crate::geometry::normals::corner_angle(
                        &tri[c],
                        &tri[(c + 1) % 3],
                        &tri[(c + 2) % 3],
                    );
                    let key = uv.corners[f][c];
                    let k = match charts.iter().position(|x| x.0 == key) {
                        Some(k) => k,
                        None => {
                            charts.push((key, 0.0, [Vector3::zeros(); 2]));
                            charts.len() - 1
                        }
                    };
                    charts[k].1 += angle;
                    charts[k].2[0] += j[0] * angle;
                    charts[k].2[1] += j[1] * angle;
                }
                let mut best: Option<Hit> = None;
                for (key, total, js) in charts {
                    if !(total > 0.0) {
                        continue;
                    }
                    let (ju, jv) = (js[0] / total, js[1] / total);
                    let g = Matrix2::new(ju.dot(&ju), ju.dot(&jv), jv.dot(&ju), jv.dot(&jv));
                    let smallest = 0.5
                        * (g.trace()
                            - ((g[(0, 0)] - g[(1, 1)]).powi(2) + 4.0 * g[(0, 1)].powi(2)).sqrt());
                    if !(smallest > 0.0) {
                        continue;
                    }
                    let p = uv.values[key as usize];
                    let r_uv = radius / smallest.sqrt();
                    if p.x < lo.x - r_uv
                        || p.x > hi.x + r_uv
                        || p.y < lo.y - r_uv
                        || p.y > hi.y + r_uv
                    {
                        continue;
                    }
                    grid.near(&p.into(), r_uv, &mut near);
                    for &k in &near {
                        let (line, s) = segments[k as usize];
                        {
                            let (t, d2) = closest_on_segment(&p, &s[0], &s[1], &g);
                            if d2 < r2 && best.is_none_or(|b| d2 < b.distance * b.distance) {
                                let e = s[1] - s[0];
                                let o = p - (s[0] + e * t);
                                best = Some(Hit {
                                    distance: d2.sqrt(),
                                    tangent: ju * e.x + jv * e.y,
                                    offset: ju * o.x + jv * o.y,
                                    line,
                                });
                            }
                        }
                    }
                }
                best
            })
            .collect(),
    )
}
