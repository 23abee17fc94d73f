//! Edit fidelity (issue 13; docs/math.md §10, "Edit fidelity"): did an edit put the key light's
//! highlight where it asked?
//!
//! The key light's ideal highlight is the zero set {g = 0} of g = hᵀu (math.md §2: ℓ is tangent
//! to the level sets of g, and on {g = 0} it is the highlight's tangent). Per triangle, g is
//! interpolated linearly between its corners, so the zero set is one straight segment per
//! triangle whose corners do not all have the same sign ([`highlight_segments`]). For line
//! fields (k = 2) u has no sign: the corners of a triangle are first given the sign that
//! agrees with the first corner (u_b ← −u_b where u_bᵀu_a < 0), which leaves the zero set
//! unchanged by the sign of any vertex.
//!
//! For an edit of brush radius r, C0 is that highlight of the field before the edit (the
//! optimizer's input) and C1 of the field after the solve, both restricted to the faces with a
//! corner in the edit's support:
//!
//! - **bend / expand**: the target is W(C0): C0's segments in the brush chart (geodesic polar
//!   coordinates in units of r, src/edit/chart.rs; without a chart, the brush plane's
//!   (x, y) = [eₓ e_y]ᵀ(p − o)/r), every point mapped by the warp W, the image resampled every
//!   `sample_spacing` of arc length; only samples within `compare_radius` of the centre count.
//!   Distance: in the chart, to the nearest C1 segment that has an endpoint in the unit disk; in
//!   units of r. The chart follows the surface's own geodesic polar coordinates (a scan's noise
//!   does not stretch it), so a reader measuring in those from FIELD.json finds the same figures
//!   (docs/math.md §10, "Measured again from the outputs").
//! - **curve**: the target is the drawn curve (3D polylines; UV curves lifted through the mesh's
//!   UV map, [`lift_uv_polylines`]) resampled every `sample_spacing`·r of arc length, less one
//!   radius at each end of each polyline. Distance: in space, to the nearest C1 segment, divided
//!   by r.
//!
//! Faces whose corner normals face away from the brush plane (Σ nᵢ·n_plane ≤ 0: the far side of
//! a thin part caught by a Euclidean brush) are left out of the warps' C0 and C1. Distances are
//! capped at [`MAX_DISTANCE`] r (no C1 segment closer than that counts as that far), so every
//! figure is finite. The figures: the share of samples within `tolerance`·r (`within`), the
//! 95th percentile and the median of the distances (nearest rank), and the singular triangles
//! ([`crate::highlight::singularities()`]) among the faces with a corner in the support (a singular
//! pair straddling the support's edge is the edit's doing too), before and after. An edit has
//! *landed* when within ≥ [`GOAL_WITHIN`], p95 ≤ [`GOAL_P95`] and it added no singular
//! triangle beyond those its highlight forces ([`forced_singular`]: a critical point of the key
//! light that no highlight passes makes every grain turn around it).

// `!(x > 0.0)` is how the measure rejects NaN along with the out-of-range values.
#![allow(clippy::neg_cmp_op_on_partial_ord)]

use nalgebra::{Vector2, Vector3};
use serde::Serialize;

use crate::edit::{EditReport, WarpKind};
use crate::geometry::Geometry;
use crate::highlight::Symmetry;
use crate::mesh::Mesh;
use crate::{Error, Result};

mod brushed;
pub mod carry;
mod forced;
mod grid;
mod segments;

pub use crate::edit::shape::{warp_shape, EditShape};
pub use crate::edit::uv_lift::lift_uv_polylines;
pub use brushed::{
    beyond_reach_in_support, brushed_fidelity, brushed_fidelity_of_edits, BrushedEditFidelity,
    Departure,
};
pub use forced::{forced_singular, CriticalGroups, Forced, NEIGHBOURHOOD_RINGS};
use grid::{point_segment_distance, SegmentGrid, TriangleGrid};
pub use segments::{highlight_segments, highlight_segments_of_faces};
use segments::{indexed_segments, segments_with_normals};

/// The goal on [`EditFidelity::within`]: at least 90 % of the target within tolerance.
pub const GOAL_WITHIN: f64 = 0.9;
/// The goal on [`EditFidelity::p95`]: the 95th-percentile distance at most 0.10 r.
pub const GOAL_P95: f64 = 0.10;
/// Distances are capped at this many radii (a sample with no C1 segment closer counts as this
/// far).
pub const MAX_DISTANCE: f64 = 2.0;

/// Options of [`edit_fidelity`]; every length is in units of the brush radius r.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct FidelityOptions {
    /// A target sample is "within" when C1 is closer than this (default 0.05).
    pub tolerance: f64,
    /// Warps: only W(C0) samples closer than this to the centre count (default 0.85).
    pub compare_radius: f64,
    /// Arc length between target samples (default 0.01).
    pub sample_spacing: f64,
}

impl Default for FidelityOptions {
    fn default() -> Self {
        FidelityOptions { tolerance: 0.05, compare_radius: 0.85, sample_spacing: 0.01 }
    }
}

impl FidelityOptions {
    /// Range-checks the options: tolerance in (0, 2], compare radius in (0, 1], spacing in
    /// [10⁻⁴, 0.5].
    pub fn validate(&self) -> Result<()> {
        let check = |name: &str, x: f64, lo: f64, hi: f64, open_lo: bool| {
            let ok = x.is_finite() && x <= hi && if open_lo { x > lo } else { x >= lo };
            if ok {
                Ok(())
            } else {
                Err(Error::invalid_arg(
                    format!("fidelity.{name}"),
                    format!(
                        "must be within {}{lo}, {hi}], got {x}",
                        if open_lo { "(" } else { "[" }
                    ),
                ))
            }
        };
        check("tolerance", self.tolerance, 0.0, MAX_DISTANCE, true)?;
        check("compare_radius", self.compare_radius, 0.0, 1.0, true)?;
        check("sample_spacing", self.sample_spacing, 1e-4, 0.5, false)
    }
}

/// The figures of one edit; serialized into the optimize and run reports under `fidelity`.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct EditFidelity {
    /// Position of the edit in the `edits` list.
    pub index: usize,
    /// The tool's name.
    pub tool: String,
    /// The brush radius r, scene units.
    pub radius: f64,
    /// Target samples compared.
    pub samples: usize,
    /// Share of the target samples within tolerance·r of C1 (0 to 1).
    pub within: f64,
    /// 95th-percentile distance from the target to C1, in units of r.
    pub p95: f64,
    /// Median distance, in units of r.
    pub median: f64,
    /// Singular triangles inside the support, field before the edit.
    pub singular_before: usize,
    /// Singular triangles inside the support after the solve.
    pub singular_after: usize,
    /// Faces inside the support holding a critical point of the key light (a zero of h̄,
    /// h ∥ n): every smooth grain's highlight passes through each ([`forced_singular`]).
    pub critical_points: usize,
    /// Singular triangles the field before the edit must have, its highlight passing some of
    /// those critical points by ([`forced_singular`]).
    pub singular_forced_before: usize,
    /// The same for the solved field: singular triangles that no grain with the highlight it
    /// has avoids.
    pub singular_forced_after: usize,
    /// within ≥ 0.9, p95 ≤ 0.10, and no singular triangle added beyond those the highlight
    /// forces: singular_after − singular_before ≤ singular_forced_after −
    /// singular_forced_before.
    pub landed: bool,
    /// Target samples left out because they lie on none of the support's faces (bend and
    /// expand: W(C0) beyond the part's boundary, or where the surface turns away from the
    /// brush plane); not counted in `samples`.
    pub off_part: usize,
    /// Why the edit could not be measured, or what missed.
    pub note: Option<String>,
}

/// A face of a brush in its chart: the 3D corners and their chart coordinates.
struct ChartFace {
    positions: [Vector3<f64>; 3],
    corners: [Vector2<f64>; 3],
}

impl ChartFace {
    /// The chart point of a point of the face (barycentric in its 3D triangle).
    fn at(&self, p: &Vector3<f64>) -> Vector2<f64> {
        let [a, b, c] = self.positions;
        let (_, w) = crate::edit::support::closest_point_on_triangle(p, &a, &b, &c);
        self.corners[0] * w[0] + self.corners[1] * w[1] + self.corners[2] * w[2]
    }
}

/// The faces of `any` with their chart corners: from `chart` (vertex, coordinates) when it is
/// given, else those facing the plane (origin, ex, ey), projected to it and scaled by 1/radius.
fn brush_faces(
    mesh: &Mesh,
    geometry: &Geometry,
    any: &[usize],
    chart: &[(u32, [f64; 2])],
    (origin, ex, ey): (&Vector3<f64>, &Vector3<f64>, &Vector3<f64>),
    radius: f64,
) -> Vec<(usize, ChartFace)> {
    let coords = |v: u32| {
        let i = chart.binary_search_by_key(&v, |c| c.0).ok()?;
        Some(Vector2::new(chart[i].1[0], chart[i].1[1]))
    };
    let plane_n = ex.cross(ey);
    any.iter()
        .filter_map(|&f| {
            let face = mesh.faces.get(f)?;
            let positions = mesh.face_positions(f);
            let corners = if chart.is_empty() {
                let s: Vector3<f64> = face.iter().map(|&v| geometry.frames[v as usize].n).sum();
                if s.dot(&plane_n) <= 0.0 {
                    return None;
                }
                positions.map(|p| {
                    let w = p - origin;
                    Vector2::new(ex.dot(&w), ey.dot(&w)) / radius
                })
            } else {
                let [a, b, c] = face.map(coords);
                [a?, b?, c?]
            };
            Some((f, ChartFace { positions, corners }))
        })
        .collect()
}

/// Walks pieces of a chain and emits a sample every `spacing` of arc length (the first at
/// spacing/2), carrying the phase from piece to piece.
struct Resampler {
    spacing: f64,
    next: f64,
    out: Vec<Vector3<f64>>,
}

impl Resampler {
    fn new(spacing: f64) -> Self {
        Resampler { spacing, next: 0.5 * spacing, out: Vec::new() }
    }

    fn piece(&mut self, p: &Vector3<f64>, q: &Vector3<f64>) {
        let len = (q - p).norm();
        if !(len > 0.0) {
            return;
        }
        while self.next <= len {
            self.out.push(p + (q - p) * (self.next / len));
            self.next += self.spacing;
        }
        self.next -= len;
    }
}

/// The faces with a corner in the support, ascending.
fn support_faces(mesh: &Mesh, support: &[u32]) -> Vec<usize> {
    let mut inside = vec![false; mesh.num_vertices()];
    for &v in support {
        if let Some(x) = inside.get_mut(v as usize) {
            *x = true;
        }
    }
    (0..mesh.num_faces())
        .filter(|&f| {
            mesh.faces[f].iter().any(|&v| inside.get(v as usize).copied().unwrap_or(false))
        })
        .collect()
}

/// W(C0) sampled every `spacing` (planar units), kept within `compare` of the centre.
fn warp_samples(
    c0: &[[Vector2<f64>; 2]],
    kind: WarpKind,
    strength: f64,
    spacing: f64,
    compare: f64,
) -> Vec<Vector2<f64>> {
    let w = |p: Vector2<f64>| crate::edit::warp::warp(kind, strength, &p);
    let lift = |p: Vector2<f64>| Vector3::new(p.x, p.y, 0.0);
    let mut rs = Resampler::new(spacing);
    for s in c0 {
        let (a, b) = (s[0], s[1]);
        // A segment clear of the unit disk is not moved, and lies beyond the compare disk.
        if point_segment_distance(&Vector3::zeros(), &lift(a), &lift(b)) > 1.0 {
            continue;
        }
        let n = ((b - a).norm() / spacing).ceil().clamp(1.0, 1e6) as usize;
        let at = |t: f64| a + (b - a) * t;
        let mut prev = w(a);
        for k in 1..=n {
            let (t0, t1) = ((k - 1) as f64 / n as f64, k as f64 / n as f64);
            let next = w(at(t1));
            // Refine where the warp stretches a piece beyond the spacing.
            let m = ((next - prev).norm() / spacing).ceil().clamp(1.0, 1e4) as usize;
            let mut q = prev;
            for j in 1..=m {
                let r = if j == m { next } else { w(at(t0 + (t1 - t0) * j as f64 / m as f64)) };
                rs.piece(&lift(q), &lift(r));
                q = r;
            }
            prev = next;
        }
    }
    rs.out.into_iter().map(|p| Vector2::new(p.x, p.y)).filter(|p| p.norm() < compare).collect()
}

/// Curve samples every `spacing` (scene units), more than `trim` of arc length from either end
/// of each polyline: at arc lengths (k + ½)·spacing within [trim, length − trim].
fn curve_samples(polylines: &[Vec<Vector3<f64>>], spacing: f64, trim: f64) -> Vec<Vector3<f64>> {
    let mut out = Vec::new();
    for line in polylines {
        let total: f64 = line.windows(2).map(|s| (s[1] - s[0]).norm()).sum();
        if !(total.is_finite() && total > 2.0 * trim) {
            continue;
        }
        let (mut next, mut s0) = (0.5 * spacing, 0.0);
        for seg in line.windows(2) {
            let (a, b) = (seg[0], seg[1]);
            let len = (b - a).norm();
            if !(len > 0.0) {
                continue;
            }
            while next <= s0 + len {
                if next >= trim && next <= total - trim {
                    out.push(a + (b - a) * ((next - s0) / len));
                }
                next += spacing;
            }
            s0 += len;
        }
    }
    out
}

/// The nearest-rank percentile of sorted values (q in (0, 1]).
fn percentile(sorted: &[f64], q: f64) -> f64 {
    if sorted.is_empty() {
        return 0.0;
    }
    let rank = (q * sorted.len() as f64).ceil() as usize;
    sorted[rank.clamp(1, sorted.len()) - 1]
}

/// The figures of one edit: `u_before`/`u_after` are world-space unit grain vectors per vertex,
/// `h` the key light's half vectors per vertex.
///
/// Errors: `h`, `u_before`, `u_after` or the geometry not of the mesh's vertex count, options out
/// of range. A case that cannot be measured (no highlight before a warp, a curve shorter than two
/// radii, no highlight after) is not an error: it gives `within = 0`, `landed = false` and a
/// `note`.
#[allow(clippy::too_many_arguments)]
pub fn edit_fidelity(
    mesh: &Mesh,
    geometry: &Geometry,
    h: &[Vector3<f64>],
    symmetry: Symmetry,
    u_before: &[Vector3<f64>],
    u_after: &[Vector3<f64>],
    index: usize,
    tool: &str,
    shape: &EditShape,
    options: &FidelityOptions,
) -> Result<EditFidelity> {
    let fields = Fields { mesh, geometry, h, symmetry, u_before, u_after };
    Ok(measure(&fields, index, tool, shape, options)?.0)
}

/// [`edit_fidelity`] of `fields`, with the target's samples and their distances when there
/// were any to score.
fn measure(
    fields: &Fields,
    index: usize,
    tool: &str,
    shape: &EditShape,
    options: &FidelityOptions,
) -> Result<(EditFidelity, Option<Target>)> {
    options.validate()?;
    fields.check_vertex_counts()?;
    let Fields { mesh, geometry, h, symmetry, u_before, u_after } = *fields;
    let radius = shape.radius();
    let mut fid = EditFidelity {
        index,
        tool: tool.to_string(),
        radius,
        samples: 0,
        within: 0.0,
        p95: 0.0,
        median: 0.0,
        singular_before: 0,
        singular_after: 0,
        critical_points: 0,
        singular_forced_before: 0,
        singular_forced_after: 0,
        landed: false,
        off_part: 0,
        note: None,
    };
    if !(radius.is_finite() && radius > 0.0) {
        fid.note = Some(format!("the brush radius {radius} is not a positive number"));
        return Ok((fid, None));
    }
    let any = support_faces(mesh, shape.support());
    // Singular triangles inside the support.
    fid.singular_before = fields.singular_in(&any, u_before);
    fid.singular_after = fields.singular_in(&any, u_after);
    let critical = CriticalGroups::new(mesh, geometry, h, &any);
    let before = critical.forced(geometry, h, u_before, symmetry);
    fid.critical_points = before.critical_points;
    fid.singular_forced_before = before.singular;
    fid.singular_forced_after = critical.forced(geometry, h, u_after, symmetry).singular;

    // Distances of the target samples, in units of r.
    let target = target_distances(fields, &any, shape, options);
    fid.off_part = target.off_part;
    let off_note = off_part_note(fid.off_part, target.distances.len());
    if target.empty && fid.off_part > 0 {
        fid.note = off_note;
        return Ok((fid, None));
    }
    if target.empty {
        fid.note = Some(empty_target_note(shape, options));
        return Ok((fid, None));
    }
    score(&mut fid, &target, off_note, options);
    Ok((fid, Some(target)))
}

/// The mesh and the fields an edit is measured on: `u_before`/`u_after` world-space unit grain
/// vectors per vertex, `h` the key light's half vectors per vertex.
struct Fields<'a> {
    mesh: &'a Mesh,
    geometry: &'a Geometry,
    h: &'a [Vector3<f64>],
    symmetry: Symmetry,
    u_before: &'a [Vector3<f64>],
    u_after: &'a [Vector3<f64>],
}

impl Fields<'_> {
    /// Errors unless `h`, `u_before`, `u_after` and the geometry have the mesh's vertex count.
    fn check_vertex_counts(&self) -> Result<()> {
        let Fields { mesh, geometry, h, u_before, u_after, .. } = *self;
        let n = mesh.num_vertices();
        if h.len() != n || u_before.len() != n || u_after.len() != n || geometry.num_vertices() != n
        {
            return Err(Error::invalid_arg(
                "fidelity",
                format!(
                    "the mesh has {n} vertices, but h {}, u_before {}, u_after {}, geometry {}",
                    h.len(),
                    u_before.len(),
                    u_after.len(),
                    geometry.num_vertices()
                ),
            ));
        }
        Ok(())
    }

    /// The singular triangles of the field `u` among the faces `any` (ascending).
    fn singular_in(&self, any: &[usize], u: &[Vector3<f64>]) -> usize {
        let k = self.symmetry.k();
        let phi = self.geometry.angles_of(u);
        let sing = crate::highlight::singularities(self.mesh, self.geometry, &phi, k);
        // A face with an unbrushed corner (zero grain) has no index to count.
        let brushed = |f: usize| {
            self.mesh.faces[f]
                .iter()
                .all(|&v| u.get(v as usize).is_some_and(|x| x.norm_squared() > 0.0))
        };
        sing.iter()
            .filter(|s| any.binary_search(&(s.face as usize)).is_ok() && brushed(s.face as usize))
            .count()
    }
}

/// A target sample on the part (scene units) and its face, when known.
type Located = (Vector3<f64>, Option<usize>);

/// The distances of an edit's target samples to C1, in units of r.
struct Target {
    distances: Vec<f64>,
    /// Where each sample lies: on the part (scene units), with its face when known (warps:
    /// the support face the sample lies on in the brush chart; curves: none, the drawn curve
    /// is given in space).
    points: Vec<Located>,
    /// No target sample to compare.
    empty: bool,
    /// No C1 segment.
    empty_c1: bool,
    /// Samples left out as beyond the part (warps).
    off_part: usize,
}

/// A bend or expand brush: the warp, the brush plane (origin, ex, ey), the brush chart and the
/// radius.
struct WarpBrush<'a> {
    kind: WarpKind,
    strength: f64,
    plane: (&'a Vector3<f64>, &'a Vector3<f64>, &'a Vector3<f64>),
    chart: &'a [(u32, [f64; 2])],
    radius: f64,
}

/// The target of `shape` and its distances to C1 (the field after the solve) on the faces
/// `any`.
fn target_distances(
    fields: &Fields,
    any: &[usize],
    shape: &EditShape,
    options: &FidelityOptions,
) -> Target {
    let radius = shape.radius();
    match shape {
        EditShape::Warp { kind, strength, origin, ex, ey, chart, .. } => {
            let brush = WarpBrush {
                kind: *kind,
                strength: *strength,
                plane: (origin, ex, ey),
                chart,
                radius,
            };
            warp_distances(fields, any, &brush, options)
        }
        EditShape::Curve { polylines, .. } => {
            curve_distances(fields, any, polylines, radius, options)
        }
    }
}

/// bend / expand: the samples of W(C0) to the nearest C1 segment, in the brush chart.
fn warp_distances(
    fields: &Fields,
    any: &[usize],
    brush: &WarpBrush,
    options: &FidelityOptions,
) -> Target {
    let Fields { mesh, geometry, h, symmetry, u_before, u_after } = *fields;
    // The support's faces in the brush chart (or, without one, those facing the
    // plane, projected to it); C0 and C1 are cut from them there.
    let chart_faces = brush_faces(mesh, geometry, any, brush.chart, brush.plane, brush.radius);
    let faces: Vec<usize> = chart_faces.iter().map(|x| x.0).collect();
    let in_chart = |segs: Vec<(usize, [Vector3<f64>; 2])>| -> Vec<[Vector2<f64>; 2]> {
        segs.iter().map(|&(k, s)| s.map(|p| chart_faces[k].1.at(&p))).collect()
    };
    let c0 = in_chart(indexed_segments(mesh, h, u_before, symmetry, &faces));
    let all_samples = warp_samples(
        &c0,
        brush.kind,
        brush.strength,
        options.sample_spacing,
        options.compare_radius,
    );
    // Samples of W(C0) on none of the support's faces (in the brush chart) lie beyond
    // the part's boundary: no grain the edit may change puts a highlight there. They
    // are counted and left out.
    let tris: Vec<[Vector2<f64>; 3]> = chart_faces.iter().map(|x| x.1.corners).collect();
    let on_faces = TriangleGrid::new(&tris);
    // Each sample kept with its point on the part: barycentric in the chart face it lies on.
    let (samples, points): (Vec<Vector2<f64>>, Vec<Located>) = all_samples
        .iter()
        .filter_map(|p| {
            let (k, w) = on_faces.locate(p)?;
            let (f, face) = &chart_faces[k];
            let [a, b, c] = face.positions;
            Some((*p, (a * w[0] + b * w[1] + c * w[2], Some(*f))))
        })
        .unzip();
    let off_part = all_samples.len() - samples.len();
    let c1: Vec<[Vector3<f64>; 2]> = in_chart(indexed_segments(mesh, h, u_after, symmetry, &faces))
        .into_iter()
        .filter(|s| s[0].norm() <= 1.0 || s[1].norm() <= 1.0)
        .map(|s| s.map(|p| Vector3::new(p.x, p.y, 0.0)))
        .collect();
    let empty_c1 = c1.is_empty();
    let grid = SegmentGrid::new(c1, MAX_DISTANCE);
    let d: Vec<f64> =
        samples.iter().map(|p| grid.nearest(&Vector3::new(p.x, p.y, 0.0), MAX_DISTANCE)).collect();
    Target { distances: d, points, empty: samples.is_empty(), empty_c1, off_part }
}

/// curve: the samples of the drawn curves to the nearest C1 segment, in space, over r.
fn curve_distances(
    fields: &Fields,
    any: &[usize],
    polylines: &[Vec<Vector3<f64>>],
    radius: f64,
    options: &FidelityOptions,
) -> Target {
    let Fields { mesh, h, symmetry, u_after, .. } = *fields;
    // At most MAX_FIDELITY_SAMPLES samples: a longer curve is sampled more sparsely (each
    // sample's search costs up to the cells within the cap, so a zigzag of 2,000 points took
    // most of its run here).
    let total: f64 =
        polylines.iter().flat_map(|l| l.windows(2)).map(|s| (s[1] - s[0]).norm()).sum();
    let sparsest = total / crate::limits::MAX_FIDELITY_SAMPLES as f64;
    let spacing =
        (options.sample_spacing * radius).max(if sparsest.is_finite() { sparsest } else { 0.0 });
    let samples = curve_samples(polylines, spacing, radius);
    // Distances along the surface: in the plane of the face C1 crosses, leaving out
    // an offset along its normal (the drawn curve lies on the part as it was drawn on,
    // a refined mesh's new vertices a little off its facets; the tool itself measures
    // the offset across the curve's tangent in the tangent plane).
    let (c1, normals) = segments_with_normals(mesh, h, u_after, symmetry, any);
    let empty_c1 = c1.is_empty();
    let cap = MAX_DISTANCE * radius;
    let grid = SegmentGrid::in_planes(c1, normals, cap);
    let d: Vec<f64> = samples.iter().map(|p| grid.nearest(p, cap) / radius).collect();
    let points = samples.iter().map(|p| (*p, None)).collect();
    Target { distances: d, points, empty: samples.is_empty(), empty_c1, off_part: 0 }
}

/// The note on the `off_part` samples left out of `kept` + `off_part`, if any.
fn off_part_note(off_part: usize, kept: usize) -> Option<String> {
    (off_part > 0).then(|| {
        let all = off_part + kept;
        format!(
            "{} of {all} samples of the warped highlight ({:.0} %) lie beyond the part or out of \
             the brush's reach (on none of its faces in the brush chart) and are left out: no \
             grain can put a highlight there",
            off_part,
            100.0 * off_part as f64 / all as f64
        )
    })
}

/// The note of an edit with no target sample.
fn empty_target_note(shape: &EditShape, options: &FidelityOptions) -> String {
    match shape {
        EditShape::Warp { .. } => format!(
            "nothing to compare: the field before the edit has no key highlight within \
             {} r of the brush centre",
            options.compare_radius
        ),
        EditShape::Curve { .. } => "nothing to compare: no curve is longer than two radii \
                                    (UV curves: on the mesh's UV layout)"
            .to_string(),
    }
}

/// The figures of the target's distances, whether the edit landed, and the notes.
fn score(
    fid: &mut EditFidelity,
    target: &Target,
    off_note: Option<String>,
    options: &FidelityOptions,
) {
    let mut sorted: Vec<f64> =
        target.distances.iter().map(|d| d.clamp(0.0, MAX_DISTANCE)).collect();
    sorted.sort_unstable_by(f64::total_cmp);
    fid.samples = sorted.len();
    fid.within =
        sorted.iter().filter(|&&d| d <= options.tolerance).count() as f64 / sorted.len() as f64;
    fid.p95 = percentile(&sorted, 0.95);
    fid.median = percentile(&sorted, 0.5);
    let missed = missed_goals(fid, target.empty_c1, options);
    fid.landed = missed.is_empty();
    let forced = (fid.landed && fid.singular_after > fid.singular_before).then(|| {
        format!(
            "singular triangles {} → {}, all forced: the highlight passes critical points of the \
             key light (h ∥ n) by, and a grain turns around each",
            fid.singular_before, fid.singular_after
        )
    });
    let notes: Vec<String> = off_note
        .into_iter()
        .chain(forced)
        .chain((!fid.landed).then(|| missed.join("; ")))
        .collect();
    if !notes.is_empty() {
        fid.note = Some(notes.join("; "));
    }
}

/// The goals the scored edit missed, each as a phrase for the note.
fn missed_goals(fid: &EditFidelity, empty_c1: bool, options: &FidelityOptions) -> Vec<String> {
    let mut missed = Vec::new();
    if empty_c1 {
        missed.push("the solved field has no key highlight in the support".to_string());
    }
    if fid.within < GOAL_WITHIN {
        missed.push(format!(
            "{:.0} % of the target within {} r (goal {:.0} %)",
            100.0 * fid.within,
            options.tolerance,
            100.0 * GOAL_WITHIN
        ));
    }
    if fid.p95 > GOAL_P95 {
        missed.push(format!("p95 {:.3} r (goal ≤ {GOAL_P95} r)", fid.p95));
    }
    let forced_added = fid.singular_forced_after.saturating_sub(fid.singular_forced_before);
    if fid.singular_after > fid.singular_before + forced_added {
        let forced = if forced_added > 0 {
            format!(
                " ({forced_added} of them forced: the highlight passes critical points of the key \
                 light by, and a grain turns around each)"
            )
        } else {
            String::new()
        };
        missed.push(format!(
            "singular triangles {} → {}{forced}",
            fid.singular_before, fid.singular_after
        ));
    }
    let all = fid.off_part + fid.samples;
    if fid.off_part as f64 > (1.0 - GOAL_WITHIN) * all as f64 {
        missed.push(format!(
            "{:.0} % of the target is out of reach (goal ≤ {:.0} %)",
            100.0 * fid.off_part as f64 / all as f64,
            100.0 * (1.0 - GOAL_WITHIN)
        ));
    }
    missed
}

/// The fidelity of every edit with a shape (`reports[k].shape`), for the fields `phi_before`
/// (the optimizer's input) and `phi_after` (the solved field), angles in the geometry's frames.
#[allow(clippy::too_many_arguments)]
pub fn fidelity_of_edits(
    mesh: &Mesh,
    geometry: &Geometry,
    h: &[Vector3<f64>],
    symmetry: Symmetry,
    phi_before: &[f64],
    phi_after: &[f64],
    reports: &[EditReport],
    options: &FidelityOptions,
) -> Result<Vec<EditFidelity>> {
    if !reports.iter().any(|r| r.shape.is_some()) {
        return Ok(Vec::new());
    }
    let u_before = geometry.directions_of(phi_before);
    let u_after = geometry.directions_of(phi_after);
    reports
        .iter()
        .filter_map(|r| r.shape.as_ref().map(|s| (r, s)))
        .map(|(r, s)| {
            crate::cancel::checkpoint("fidelity")?;
            edit_fidelity(
                mesh, geometry, h, symmetry, &u_before, &u_after, r.index, &r.tool, s, options,
            )
        })
        .collect()
}

#[cfg(test)]
mod tests {
    use super::segments::{corner_g, zero_segment};
    use super::*;

    #[test]
    fn zero_segment_of_a_hand_triangle() {
        // g = x − 0.25 on the triangle (0,0), (1,0), (0,1): the zero set is x = 0.25 from
        // (0.25, 0) to (0.25, 0.75).
        let p = [Vector3::zeros(), Vector3::x(), Vector3::y()];
        let g = [-0.25, 0.75, -0.25];
        let [a, b] = zero_segment(&p, &g).unwrap();
        let (lo, hi) = if a.y < b.y { (a, b) } else { (b, a) };
        assert!((lo - Vector3::new(0.25, 0.0, 0.0)).norm() < 1e-15, "{lo:?}");
        assert!((hi - Vector3::new(0.25, 0.75, 0.0)).norm() < 1e-15, "{hi:?}");
        assert!(zero_segment(&p, &[1.0, 2.0, 0.5]).is_none());
        assert!(zero_segment(&p, &[-1.0, -2.0, -0.5]).is_none());
        assert!(zero_segment(&p, &[f64::NAN, -2.0, 0.5]).is_none());
    }

    #[test]
    fn line_alignment_follows_the_first_corner() {
        let face = [0u32, 1, 2];
        let h = vec![Vector3::x(); 3];
        let u = vec![Vector3::x(), -Vector3::x(), Vector3::new(-0.5, 0.8, 0.0)];
        let g = corner_g(&face, &h, &u, Symmetry::Line).unwrap();
        assert_eq!(g, [1.0, 1.0, 0.5]);
        let g = corner_g(&face, &h, &u, Symmetry::Oriented).unwrap();
        assert_eq!(g, [1.0, -1.0, -0.5]);
    }

    /// The grid's nearest distance against brute force over random segments and queries.
    #[test]
    fn segment_grid_agrees_with_brute_force() {
        let mut s = 12345u64;
        let mut rnd = || {
            s = s.wrapping_mul(6364136223846793005).wrapping_add(1442695040888963407);
            (s >> 11) as f64 / (1u64 << 53) as f64
        };
        let segs: Vec<[Vector3<f64>; 2]> = (0..300)
            .map(|_| {
                let a = Vector3::new(rnd(), rnd(), rnd()) * 10.0;
                let d = Vector3::new(rnd() - 0.5, rnd() - 0.5, rnd() - 0.5) * 0.6;
                [a, a + d]
            })
            .collect();
        let grid = SegmentGrid::new(segs.clone(), 4.0);
        for _ in 0..500 {
            let p = Vector3::new(rnd(), rnd(), rnd()) * 14.0 - Vector3::repeat(2.0);
            let brute = segs
                .iter()
                .map(|s| point_segment_distance(&p, &s[0], &s[1]))
                .fold(f64::INFINITY, f64::min)
                .min(4.0);
            assert_eq!(grid.nearest(&p, 4.0), brute, "{p:?}");
        }
        assert_eq!(SegmentGrid::new(Vec::new(), 1.0).nearest(&Vector3::zeros(), 1.0), 1.0);
    }

    #[test]
    fn in_plane_distances_leave_out_the_offset_along_the_face_normal() {
        // A segment on the plane z = 0 from (0, 0, 0) to (1, 0, 0); a point 0.3 across it
        // and 0.4 above the plane is 0.5 away in space and 0.3 in the plane.
        let segs = vec![[Vector3::zeros(), Vector3::x()]];
        let p = Vector3::new(0.5, 0.3, 0.4);
        let space = SegmentGrid::new(segs.clone(), 2.0).nearest(&p, 2.0);
        let plane = SegmentGrid::in_planes(segs, vec![Vector3::z()], 2.0).nearest(&p, 2.0);
        assert!((space - 0.5).abs() < 1e-12, "{space}");
        assert!((plane - 0.3).abs() < 1e-12, "{plane}");
    }

    #[test]
    fn nearest_rank_percentiles() {
        let v: Vec<f64> = (1..=20).map(f64::from).collect();
        assert_eq!(percentile(&v, 0.95), 19.0);
        assert_eq!(percentile(&v, 0.5), 10.0);
        assert_eq!(percentile(&[3.0], 0.95), 3.0);
        assert_eq!(percentile(&[], 0.5), 0.0);
    }

    /// A straight curve of length 10 sampled every 0.1 less 1 at each end: samples at arc
    /// lengths 1.05, 1.15, …, 8.95 (80 of them), evenly spaced.
    #[test]
    fn curve_samples_drop_one_radius_at_each_end() {
        let line = vec![
            Vector3::zeros(),
            Vector3::new(3.0, 0.0, 0.0),
            Vector3::new(3.0, 0.0, 0.0),
            Vector3::new(10.0, 0.0, 0.0),
        ];
        let s = curve_samples(&[line], 0.1, 1.0);
        assert_eq!(s.len(), 80, "{}", s.len());
        for (k, p) in s.iter().enumerate() {
            assert!((p.x - (1.05 + 0.1 * k as f64)).abs() < 1e-9, "{k}: {p:?}");
        }
        assert!(curve_samples(&[vec![Vector3::zeros(), Vector3::x()]], 0.1, 0.6).is_empty());
    }

    /// W of a horizontal line through the bend: samples lie on y = c + s·d(x, c) at the
    /// requested spacing.
    #[test]
    fn warp_samples_lie_on_the_warped_line() {
        let c = 0.1;
        let segs: Vec<[Vector2<f64>; 2]> = (0..40)
            .map(|k| {
                let x0 = -1.2 + 2.4 * k as f64 / 40.0;
                [Vector2::new(x0, c), Vector2::new(x0 + 0.06, c)]
            })
            .collect();
        let s = warp_samples(&segs, WarpKind::Bend, 0.8, 0.01, 0.85);
        assert!(!s.is_empty());
        for p in &s {
            let d = crate::edit::warp::displacement(WarpKind::Bend, &Vector2::new(p.x, c)).0;
            // On a chord of the warped curve (pieces ≤ 0.01: sagitta below 10⁻⁴).
            assert!((p.y - (c + 0.8 * d)).abs() < 2e-4, "{p:?}");
            assert!(p.norm() < 0.85);
        }
        // Arc length of the warped curve inside the 0.85 disk / spacing ≈ the sample count.
        let mut len = 0.0;
        let m = 20000;
        let mut prev: Option<Vector2<f64>> = None;
        for k in 0..=m {
            let x = -1.0 + 2.0 * k as f64 / m as f64;
            let q = crate::edit::warp::warp(WarpKind::Bend, 0.8, &Vector2::new(x, c));
            if let Some(p) = prev {
                if q.norm() < 0.85 && p.norm() < 0.85 {
                    len += (q - p).norm();
                }
            }
            prev = Some(q);
        }
        let expected = len / 0.01;
        assert!((s.len() as f64 - expected).abs() <= 2.0, "{} vs {expected}", s.len());
    }
}
