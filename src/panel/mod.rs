//! Flat sheet-metal panels: a closed outline (with holes) read from an SVG, meshed with a
//! refined constrained Delaunay triangulation, UV = XY in millimetres.
//!
//! * **SVG** is read by [`crate::svg_read`] (usvg): every shape (`path` with every command of
//!   SVG 1.1 §8.3 absolute and relative, `polygon`, `rect` with its `rx`/`ry` corners,
//!   `circle`, `ellipse`, and `line` or `polyline` when they close), `<use>` instances,
//!   transforms on the element, its groups and the root, CSS styles; elements with
//!   `display: none` and the content of `defs`, `clipPath`, `mask`, `marker` and `pattern`
//!   draw nothing and are left out. Negative sizes are refused.
//! * **Units.** The root's `width`/`height` (with `mm`, `cm`, `in`, `pt`, `pc`, `px` or no
//!   unit = px at 96 per inch) and `viewBox` give millimetres per user unit (the root's
//!   `preserveAspectRatio`, default `xMidYMid meet`, when the aspect ratios differ); without a
//!   `viewBox` one user unit is one px. A root with neither a `viewBox` nor both sizes is
//!   refused (its units are unknown). The panel's X is the SVG x, its Y points up:
//!   `Y = (bottom of the viewport) − y`, so the part is not mirrored and its faces are
//!   counter-clockwise seen from +Z.
//! * **Curves** are flattened to within `tolerance` mm: Béziers with Wang's bound on the
//!   number of chords (`n = ⌈√(d(d−1)/8 · max‖Δ²P‖ / tol)⌉`; Wang, Zheng & Sederberg,
//!   *Computer Graphics and Geometric Modeling*, 2nd ed., §10.5); arcs, circles, ellipses
//!   and rounded corners are cubic Béziers in usvg (within 2.7 × 10⁻⁴ of the radius).
//! * **Inside/outside** is the even-odd rule: a loop inside an outline is a hole, a loop inside
//!   a hole is an island. Loops may not touch or cross themselves or each other; open,
//!   self-intersecting and zero-area loops, and a file without any, are errors naming the file
//!   and the element.
//! * **Meshing.** Boundary segments are split to at most `max_edge`, inserted as constraint
//!   edges of spade's `ConstrainedDelaunayTriangulation`, and refined (Ruppert/Chew,
//!   `RefinementParameters` with the angle limit and an area bound of ½ · √3/4 · max_edge²,
//!   outer faces excluded). Interior edges still longer than `max_edge` get their midpoint
//!   inserted and the refinement is repeated, until none is left.

use std::collections::HashSet;
use std::path::Path;

use nalgebra::{Vector2, Vector3};
use serde::{Deserialize, Serialize};
use spade::handles::FixedVertexHandle;
use spade::{
    AngleLimit, ConstrainedDelaunayTriangulation, Point2, RefinementParameters, RefinementResult,
    Triangulation,
};

use crate::mesh::{CornerAttribute, Mesh, Units};
use crate::{Error, Result};

mod nesting;
mod svg;

pub use nesting::even_odd_area;
pub use svg::read_svg_loops;

/// Options of the panel mesher (a scene section when a scene names an outline).
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize, schemars::JsonSchema)]
#[serde(deny_unknown_fields, default)]
pub struct PanelOptions {
    /// Longest triangle edge, mm; `None` (the default) lets the angle criterion alone decide.
    pub max_edge: Option<f64>,
    /// Smallest triangle angle the refinement aims for, degrees, in [0, 34]. Default 25.
    /// Angles of the outline itself below this cannot be improved.
    pub min_angle_deg: f64,
    /// Curve flattening tolerance, mm (> 0). Default 0.01.
    pub tolerance: f64,
    /// Most vertices the refinement may add (a guard against runaway refinement).
    /// Default 2 000 000.
    pub max_added_vertices: usize,
}

impl Default for PanelOptions {
    fn default() -> Self {
        PanelOptions {
            max_edge: None,
            min_angle_deg: 25.0,
            tolerance: 0.01,
            max_added_vertices: 2_000_000,
        }
    }
}

impl PanelOptions {
    /// Range-checks every number; keys are relative to this section.
    pub fn validate(&self) -> Result<()> {
        if let Some(m) = self.max_edge {
            if !(m.is_finite() && m > 0.0) {
                return Err(Error::setting(
                    "max_edge",
                    format!("must be > 0, got {}", crate::error::fmt_num(m)),
                ));
            }
        }
        let a = self.min_angle_deg;
        if !(a.is_finite() && (0.0..=34.0).contains(&a)) {
            return Err(Error::setting(
                "min_angle_deg",
                format!(
                    "must be in [0, 34] degrees (refinement may not terminate above), got {}",
                    crate::error::fmt_num(a)
                ),
            ));
        }
        if !(self.tolerance.is_finite() && self.tolerance > 0.0) {
            return Err(Error::setting(
                "tolerance",
                format!("must be > 0, got {}", crate::error::fmt_num(self.tolerance)),
            ));
        }
        if self.max_added_vertices == 0 {
            return Err(Error::setting("max_added_vertices", "must be > 0, got 0"));
        }
        Ok(())
    }
}

/// The meshed panel.
#[derive(Clone, Debug)]
pub struct PanelResult {
    /// The mesh: z = 0, UV = XY, units mm, faces counter-clockwise seen from +Z.
    pub mesh: Mesh,
    /// Closed loops read (outlines and holes).
    pub loops: usize,
    /// Area enclosed by the flattened loops (even-odd), mm².
    pub outline_area: f64,
    /// Smallest triangle angle, degrees.
    pub min_angle_deg: f64,
    /// Longest triangle edge, mm.
    pub max_edge: f64,
    /// False when spade ran out of `max_added_vertices` (the angle goal may be missed).
    pub refinement_complete: bool,
}

/// One closed, flattened loop in mm, and the element it came from (for messages).
#[derive(Clone, Debug)]
pub struct Loop {
    /// Points in mm (not repeated at the end).
    pub points: Vec<[f64; 2]>,
    /// `path element on line 7 (id "hole")`, or `subpath 2 of path element on line 7` when
    /// the element has several.
    pub element: String,
    /// 1-based line of the element in the file (0 when not from a file).
    pub line: usize,
}

fn signed_area(p: &[[f64; 2]]) -> f64 {
    let n = p.len();
    0.5 * (0..n).map(|i| p[i][0] * p[(i + 1) % n][1] - p[(i + 1) % n][0] * p[i][1]).sum::<f64>()
}

/// The sign of the orientation of (a, b, c): positive counter-clockwise, zero exactly when
/// the three points are collinear. Exact (Shewchuk's adaptive predicate, `robust`): the naive
/// product differences misjudge the nearly collinear neighbours of a finely sampled curve.
fn orient(a: [f64; 2], b: [f64; 2], c: [f64; 2]) -> f64 {
    let p = |q: [f64; 2]| robust::Coord { x: q[0], y: q[1] };
    robust::orient2d(p(a), p(b), p(c))
}

fn on_segment(a: [f64; 2], b: [f64; 2], p: [f64; 2]) -> bool {
    p[0] >= a[0].min(b[0])
        && p[0] <= a[0].max(b[0])
        && p[1] >= a[1].min(b[1])
        && p[1] <= a[1].max(b[1])
}

/// Whether closed segments ab and cd share a point.
fn segments_touch(a: [f64; 2], b: [f64; 2], c: [f64; 2], d: [f64; 2]) -> bool {
    let (d1, d2) = (orient(c, d, a), orient(c, d, b));
    let (d3, d4) = (orient(a, b, c), orient(a, b, d));
    if ((d1 > 0.0 && d2 < 0.0) || (d1 < 0.0 && d2 > 0.0))
        && ((d3 > 0.0 && d4 < 0.0) || (d3 < 0.0 && d4 > 0.0))
    {
        return true;
    }
    (d1 == 0.0 && on_segment(c, d, a))
        || (d2 == 0.0 && on_segment(c, d, b))
        || (d3 == 0.0 && on_segment(a, b, c))
        || (d4 == 0.0 && on_segment(a, b, d))
}

/// Refuses loops that cross or touch themselves or each other: a sweep over x (segments sorted
/// by their left end; each compared with the segments whose x-range it overlaps), with exact
/// predicates. The work is O(n log n + K), K the pairs of segments whose x-ranges overlap:
/// a few per segment on an outline (a 200,000-point circle is checked in well under a second).
fn check_simple(loops: &[Loop], name: &Path) -> Result<()> {
    struct Seg {
        a: [f64; 2],
        b: [f64; 2],
        lp: usize,
        i: usize,
    }
    let mut segs: Vec<Seg> = Vec::new();
    for (lp, l) in loops.iter().enumerate() {
        let n = l.points.len();
        for i in 0..n {
            segs.push(Seg { a: l.points[i], b: l.points[(i + 1) % n], lp, i });
        }
    }
    segs.sort_by(|s, t| s.a[0].min(s.b[0]).total_cmp(&t.a[0].min(t.b[0])));
    let mut active: Vec<usize> = Vec::new();
    for k in 0..segs.len() {
        let s = &segs[k];
        let x0 = s.a[0].min(s.b[0]);
        active.retain(|&j| segs[j].a[0].max(segs[j].b[0]) >= x0);
        for &j in &active {
            let t = &segs[j];
            if s.lp == t.lp {
                let n = loops[s.lp].points.len();
                let adjacent = (s.i + 1) % n == t.i || (t.i + 1) % n == s.i;
                if adjacent {
                    // Neighbours share one end; they may not overlap beyond it (a spike).
                    let (p, q, r) =
                        if (s.i + 1) % n == t.i { (s.a, s.b, t.b) } else { (t.a, t.b, s.b) };
                    let back = orient(p, q, r) == 0.0
                        && (r[0] - q[0]) * (p[0] - q[0]) + (r[1] - q[1]) * (p[1] - q[1]) > 0.0;
                    if !back || n < 3 {
                        continue;
                    }
                } else if !segments_touch(s.a, s.b, t.a, t.b) {
                    continue;
                }
            } else if !segments_touch(s.a, s.b, t.a, t.b) {
                continue;
            }
            let at = s.a;
            let (what, line) = if s.lp == t.lp {
                (format!("{} crosses or touches itself", loops[s.lp].element), loops[s.lp].line)
            } else {
                let (x, y) = (s.lp.min(t.lp), s.lp.max(t.lp));
                (
                    format!("{} crosses or touches {}", loops[x].element, loops[y].element),
                    loops[x].line,
                )
            };
            return Err(Error::Parse {
                path: name.to_path_buf(),
                line,
                message: format!("{what} near ({:.3}, {:.3}) mm", at[0], at[1]),
            });
        }
        active.push(k);
    }
    Ok(())
}

/// Meshes closed loops (in mm; even-odd inside) into a flat panel.
pub fn mesh_loops(loops: &[Loop], name: &Path, opts: &PanelOptions) -> Result<PanelResult> {
    check_loops(loops, name, opts)?;
    let mut cdt: Cdt = ConstrainedDelaunayTriangulation::new();
    let max_edge = opts.max_edge.unwrap_or(f64::INFINITY);
    insert_boundaries(&mut cdt, loops, max_edge)?;
    let (result, complete) = refine_to_max_edge(&mut cdt, opts, max_edge)?;
    let PanelTriangles { positions, uvs, faces, min_angle, longest } =
        panel_triangles(&cdt, &result);
    if faces.is_empty() {
        return Err(numerical("the outline produced no triangles".into()));
    }
    let mut mesh = Mesh::from_triangles(positions, faces.clone());
    mesh.uv = Some(CornerAttribute { values: uvs, corners: faces });
    mesh.units = Units::Mm;
    Ok(PanelResult {
        mesh,
        loops: loops.len(),
        outline_area: even_odd_area(loops),
        min_angle_deg: min_angle,
        max_edge: longest,
        refinement_complete: complete,
    })
}

/// The triangulation of a panel.
type Cdt = ConstrainedDelaunayTriangulation<Point2<f64>>;

/// An error of the triangulation.
fn numerical(m: String) -> Error {
    Error::Numerical { stage: "panel triangulation", message: m }
}

/// Checks the options and the loops before anything is triangulated: at least one loop, within
/// the budget, none crossing, each enclosing an area.
fn check_loops(loops: &[Loop], name: &Path, opts: &PanelOptions) -> Result<()> {
    opts.validate()?;
    if loops.is_empty() {
        return Err(Error::Parse {
            path: name.to_path_buf(),
            line: 0,
            message: "no closed outline".into(),
        });
    }
    let max = crate::limits::MAX_PANEL_COORDINATE_MM;
    for l in loops {
        if let Some(p) = l.points.iter().find(|p| !(p[0].abs() <= max && p[1].abs() <= max)) {
            return Err(Error::Parse {
                path: name.to_path_buf(),
                line: l.line,
                message: format!(
                    "{}: the point ({}, {}) mm is beyond ±{} mm (limits::MAX_PANEL_COORDINATE_MM, \
                     1 km): check the drawing's units and viewBox",
                    l.element,
                    crate::error::fmt_num(p[0]),
                    crate::error::fmt_num(p[1]),
                    crate::error::fmt_num(max)
                ),
            });
        }
    }
    check_budget(loops, opts)?;
    check_simple(loops, name)?;
    if let Some(l) = loops.iter().find(|l| signed_area(&l.points).abs() <= 1e-12) {
        return Err(Error::Parse {
            path: name.to_path_buf(),
            line: l.line,
            message: format!("{}: a subpath encloses no area", l.element),
        });
    }
    Ok(())
}

/// Inserts every loop's boundary, its segments split to at most `max_edge`, as constraint
/// edges.
fn insert_boundaries(cdt: &mut Cdt, loops: &[Loop], max_edge: f64) -> Result<()> {
    for l in loops {
        let n = l.points.len();
        let mut handles: Vec<FixedVertexHandle> = Vec::new();
        for i in 0..n {
            let (a, b) = (l.points[i], l.points[(i + 1) % n]);
            let len = (b[0] - a[0]).hypot(b[1] - a[1]);
            let k =
                if max_edge.is_finite() { (len / max_edge).ceil().max(1.0) as usize } else { 1 };
            for j in 0..k {
                let t = j as f64 / k as f64;
                let p = Point2::new(a[0] + t * (b[0] - a[0]), a[1] + t * (b[1] - a[1]));
                handles.push(
                    cdt.insert(p)
                        .map_err(|e| numerical(format!("{}: {}", l.element, insertion(&e))))?,
                );
            }
        }
        let m = handles.len();
        for i in 0..m {
            let (a, b) = (handles[i], handles[(i + 1) % m]);
            if a != b && !cdt.can_add_constraint(a, b) {
                return Err(numerical(format!("{}: a boundary edge could not be kept", l.element)));
            }
            cdt.add_constraint(a, b);
        }
    }
    Ok(())
}

/// The refinement's parameters: outer faces excluded, the angle limit, the vertex budget, and
/// with a `max_edge` an area bound of ½ · √3/4 · max_edge².
fn refinement_params(opts: &PanelOptions, max_edge: f64) -> RefinementParameters<f64> {
    let mut p = RefinementParameters::<f64>::new()
        .exclude_outer_faces(true)
        .with_angle_limit(AngleLimit::from_deg(opts.min_angle_deg))
        .with_max_additional_vertices(opts.max_added_vertices);
    if max_edge.is_finite() {
        p = p.with_max_allowed_area(0.5 * 3f64.sqrt() / 4.0 * max_edge * max_edge);
    }
    p
}

/// Refines the triangulation; with a `max_edge`, inserts the midpoints of the interior edges
/// still longer and refines again (at most 50 rounds). Returns the last refinement's result and
/// whether every refinement completed.
fn refine_to_max_edge(
    cdt: &mut Cdt,
    opts: &PanelOptions,
    max_edge: f64,
) -> Result<(RefinementResult, bool)> {
    let mut result = cdt.refine(refinement_params(opts, max_edge));
    let mut complete = result.refinement_complete;
    for _ in 0..50 {
        if !max_edge.is_finite() {
            break;
        }
        let outer: HashSet<_> = result.excluded_faces.iter().copied().collect();
        let mut mids: Vec<Point2<f64>> = Vec::new();
        for f in cdt.inner_faces() {
            if outer.contains(&f.fix()) {
                continue;
            }
            let v = f.vertices().map(|v| v.position());
            for i in 0..3 {
                let (a, b) = (v[i], v[(i + 1) % 3]);
                if (b.x - a.x).hypot(b.y - a.y) > max_edge {
                    mids.push(Point2::new(0.5 * (a.x + b.x), 0.5 * (a.y + b.y)));
                }
            }
        }
        if mids.is_empty() {
            break;
        }
        for p in mids {
            cdt.insert(p).map_err(|e| numerical(insertion(&e)))?;
        }
        result = cdt.refine(refinement_params(opts, max_edge));
        complete &= result.refinement_complete;
    }
    Ok((result, complete))
}

/// The panel's triangles, counter-clockwise, with their vertices (UV = XY) and figures.
struct PanelTriangles {
    positions: Vec<Vector3<f64>>,
    uvs: Vec<Vector2<f64>>,
    faces: Vec<[u32; 3]>,
    /// Smallest angle, degrees.
    min_angle: f64,
    /// Longest edge, mm.
    longest: f64,
}

/// The inner faces the refinement did not exclude, their vertices numbered in order of first
/// use.
fn panel_triangles(cdt: &Cdt, result: &RefinementResult) -> PanelTriangles {
    let outer: HashSet<_> = result.excluded_faces.iter().copied().collect();
    let mut index = vec![u32::MAX; cdt.num_vertices()];
    let mut positions: Vec<Vector3<f64>> = Vec::new();
    let mut uvs: Vec<Vector2<f64>> = Vec::new();
    let mut faces: Vec<[u32; 3]> = Vec::new();
    let (mut min_angle, mut longest) = (f64::INFINITY, 0.0f64);
    for f in cdt.inner_faces() {
        if outer.contains(&f.fix()) {
            continue;
        }
        let vs = f.vertices();
        let mut t = [0u32; 3];
        let mut pts = [[0.0; 2]; 3];
        for (k, v) in vs.iter().enumerate() {
            let i = v.fix().index();
            let p = v.position();
            pts[k] = [p.x, p.y];
            if index[i] == u32::MAX {
                index[i] = positions.len() as u32;
                positions.push(Vector3::new(p.x, p.y, 0.0));
                uvs.push(Vector2::new(p.x, p.y));
            }
            t[k] = index[i];
        }
        if orient(pts[0], pts[1], pts[2]) < 0.0 {
            t.swap(1, 2);
            pts.swap(1, 2);
        }
        for k in 0..3 {
            let (a, b, c) = (pts[k], pts[(k + 1) % 3], pts[(k + 2) % 3]);
            let (u, w) = ([b[0] - a[0], b[1] - a[1]], [c[0] - a[0], c[1] - a[1]]);
            let ang = (u[0] * w[1] - u[1] * w[0]).abs().atan2(u[0] * w[0] + u[1] * w[1]);
            min_angle = min_angle.min(ang.to_degrees());
            longest = longest.max(u[0].hypot(u[1]));
        }
        faces.push(t);
    }
    PanelTriangles { positions, uvs, faces, min_angle, longest }
}

/// The panel's size, estimated from its loops before any triangle is built.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct PanelEstimate {
    /// Sum of the loops' areas, mm² (an upper bound of the even-odd area: holes count as
    /// area too; linear in the points, where the even-odd area is not).
    pub area: f64,
    /// Total length of the loops, mm.
    pub perimeter: f64,
    /// Triangles: `A / (½ · √3/4 · e²) + P / e` with a longest edge `e`, else twice the
    /// boundary points (the angle criterion alone adds few).
    pub triangles: f64,
}

/// Estimates the triangles of meshing `loops` with `max_edge` ([`crate::limits::MAX_PANEL_TRIANGLES`]).
pub fn estimate(loops: &[Loop], max_edge: Option<f64>) -> PanelEstimate {
    let area: f64 = loops.iter().map(|l| signed_area(&l.points).abs()).sum();
    let perimeter: f64 = loops
        .iter()
        .map(|l| {
            let n = l.points.len();
            (0..n)
                .map(|i| {
                    let (a, b) = (l.points[i], l.points[(i + 1) % n]);
                    (b[0] - a[0]).hypot(b[1] - a[1])
                })
                .sum::<f64>()
        })
        .sum();
    let points: usize = loops.iter().map(|l| l.points.len()).sum();
    let triangles = match max_edge {
        Some(e) => area / (0.5 * 3f64.sqrt() / 4.0 * e * e) + perimeter / e + points as f64,
        None => 2.0 * points as f64,
    };
    PanelEstimate { area, perimeter, triangles }
}

/// Refuses a panel whose estimated triangles exceed [`crate::limits::MAX_PANEL_TRIANGLES`],
/// naming `max_edge` (the scene's `outline.max_edge`, the CLI's `--max-edge`).
fn check_budget(loops: &[Loop], opts: &PanelOptions) -> Result<()> {
    let e = estimate(loops, opts.max_edge);
    let budget = crate::limits::MAX_PANEL_TRIANGLES;
    if e.triangles.is_finite() && e.triangles <= budget {
        return Ok(());
    }
    let fmt = crate::error::fmt_num;
    let area = format!("{:.0} mm²", e.area);
    let perimeter = format!("{:.0} mm", e.perimeter);
    match opts.max_edge {
        Some(m) => Err(Error::setting(
            "max_edge",
            format!(
                "{} mm on an outline of {area} and {perimeter} gives about {:.2e} triangles, \
                 beyond the budget of {budget:.0e}; use a longer edge (at least {} mm here)",
                fmt(m),
                e.triangles,
                round_up_2((4.7 * e.area / budget).sqrt().max(2.0 * e.perimeter / budget))
            ),
        )),
        None => Err(Error::setting(
            "tolerance",
            format!(
                "the flattened outline has {:.0} points, about {:.2e} triangles, beyond the \
                 budget of {budget:.0e}; use a coarser tolerance",
                e.triangles / 2.0,
                e.triangles
            ),
        )),
    }
}

/// `x` rounded up to two significant digits, as text (`0.0766…` → `0.077`).
fn round_up_2(x: f64) -> String {
    if !(x.is_finite() && x > 0.0) {
        return crate::error::fmt_num(x);
    }
    let e = x.log10().floor() as i32 - 1;
    let v = (x / 10f64.powi(e)).ceil();
    if e >= 0 {
        format!("{}", v * 10f64.powi(e))
    } else {
        format!("{:.*}", (-e) as usize, v * 10f64.powi(e))
    }
}

/// Reads an outline SVG and meshes it (see the module documentation).
pub fn panel_from_svg(path: &Path, opts: &PanelOptions) -> Result<PanelResult> {
    opts.validate()?;
    let text = crate::output::read_bounded_text(path, crate::limits::MAX_SVG_BYTES, "an SVG file")?;
    let loops = read_svg_loops(&text, path, opts.tolerance)?;
    mesh_loops(&loops, path, opts)
}

/// The triangulator's refusal of a point in words (spade's text is its `Debug` form).
fn insertion(e: &spade::InsertionError) -> String {
    match e {
        spade::InsertionError::TooLarge => format!(
            "a coordinate is beyond the triangulator's range (|x| ≤ {})",
            crate::error::fmt_num(spade::MAX_ALLOWED_VALUE)
        ),
        spade::InsertionError::TooSmall => format!(
            "a coordinate is too close to zero for the triangulator (|x| ≥ {} or 0)",
            crate::error::fmt_num(spade::MIN_ALLOWED_VALUE)
        ),
        spade::InsertionError::NAN => "a coordinate is not a number".into(),
    }
}

#[cfg(test)]
mod tests {
    #[test]
    fn item15_triangulator_refusals_are_in_words() {
        for e in [
            spade::InsertionError::TooLarge,
            spade::InsertionError::TooSmall,
            spade::InsertionError::NAN,
        ] {
            let m = super::insertion(&e);
            assert!(
                !m.contains("TooLarge") && !m.contains("TooSmall") && !m.contains("NAN"),
                "{m}"
            );
            assert!(m.contains("coordinate"), "{m}");
        }
    }

    fn circle(n: usize, r: f64, decimals: i32) -> super::Loop {
        let q = 10f64.powi(decimals);
        let points = (0..n)
            .map(|i| {
                let t = std::f64::consts::TAU * i as f64 / n as f64;
                [((50.0 + r * t.cos()) * q).round() / q, ((50.0 + r * t.sin()) * q).round() / q]
            })
            .collect();
        super::Loop { points, element: "circle".into(), line: 1 }
    }

    // Issue 30, item 11: a 200,000-point circle at 6 decimals is one simple loop, checked with
    // exact predicates in near-linear time; a loop that does cross is still refused.
    #[test]
    fn item_11_crossing_test_is_exact_and_near_linear() {
        let name = std::path::Path::new("c.svg");
        for r in [0.05, 1.0, 40.0] {
            let mut l = circle(200_000, r, 6);
            l.points.dedup();
            let t = std::time::Instant::now();
            super::check_simple(&[l], name).unwrap();
            assert!(t.elapsed().as_secs_f64() < 2.0, "r = {r}: {:?}", t.elapsed());
        }
        let eight = super::Loop {
            points: vec![[0.0, 0.0], [1.0, 1.0], [1.0, 0.0], [0.0, 1.0]],
            element: "eight".into(),
            line: 3,
        };
        let e = super::check_simple(&[eight], name).unwrap_err().to_string();
        assert!(e.contains("c.svg:3: eight crosses or touches itself"), "{e}");
        // Exactly collinear neighbours that turn back (a spike of 0.1 + 0.2 units) are caught.
        let spike = super::Loop {
            points: vec![[0.0, 0.0], [0.3, 0.3], [0.1, 0.1], [0.0, 1.0]],
            element: "spike".into(),
            line: 4,
        };
        assert!(super::check_simple(&[spike], name).is_err());
    }
}
