//! Carrying the 3D grain field into the toolpaths crate's UV domain, and back.
//!
//! [`field_mesh`] turns a mesh with per-corner UVs and a per-vertex grain angle φ into a
//! [`FieldMesh`]:
//!
//! * **UV vertices** are the distinct (position, UV value) pairs of the face corners, numbered
//!   in order of first appearance (face by face, corner by corner), so a vertex on a UV seam
//!   becomes one UV vertex per side.
//! * **Directions.** For a triangle with UV edges `e₁, e₂` and 3D edges `E₁, E₂`, the lift's
//!   Jacobian is `J = [E₁ E₂]·[e₁ e₂]⁻¹` (3×2) and the first fundamental form is `M = JᵀJ`.
//!   A 3D grain direction `u` is carried into UV by the pseudo-inverse,
//!   `d = J⁺u = M⁻¹Jᵀu`: the UV vector whose lift `J d` is `u` projected onto the face plane.
//!   Each corner contributes its vertex's `u` mapped through its own triangle's `J⁺`,
//!   normalized in UV and weighted by the corner's 3D angle; the sum per UV vertex is the
//!   direction (for k = 2 the sum is taken of angle-doubled vectors, `|d|(cos 2θ, sin 2θ)`,
//!   and halved back, so the arbitrary sign of a line never cancels anything).
//! * **Orientation.** No angle is ever measured against the UV axes in a tangent frame:
//!   `J` contains the reflection of a mirrored or flipped UV triangle (its `det[e₁ e₂] < 0`),
//!   so `J d = u` holds whatever the handedness of the chart, and a stroke traced along `d`
//!   lifts to a curve running along `+u`. A chart mirrored in UV therefore gets mirrored UV
//!   directions, never a grain turned over.
//! * **Degenerate triangles** (UV area ≤ `degenerate_ratio` × UV bbox diagonal², or a lift
//!   whose first fundamental form is not positive definite) are left out of the field mesh
//!   and listed in the report; UV vertices used only by them are dropped.
//! * **Seams** — mesh edges whose two faces disagree on the UV of an end — become
//!   [`SeamPair`]s; the 3D lift (positions, the geometry's normals) and the per-triangle
//!   metric `M` are attached, so spacing is measured on the part, in scene units.
//!
//! [`as_brushed`] goes the other way: each mesh vertex takes the UV tangent of the nearest
//! placed stroke segment (found with a uniform grid), lifted to 3D through the Jacobian of
//! one of its triangles, and the result is compared with the designed field.

use std::collections::{BTreeMap, HashMap};

use grainline_toolpaths::{segment_distance, Directions, FieldMesh, Metric, Placement, SeamPair};
use nalgebra::{Matrix2, Vector2, Vector3};
use rayon::prelude::*;
use serde::{Deserialize, Serialize};

use crate::geometry::Geometry;
use crate::highlight::Symmetry;
use crate::mesh::{CornerAttribute, Mesh};
use crate::{Error, Result};

/// Options of [`field_mesh`].
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize, schemars::JsonSchema)]
#[serde(deny_unknown_fields, default)]
pub struct UvFieldOptions {
    /// A UV triangle whose |area| is at most this fraction of the squared UV bounding-box
    /// diagonal is degenerate (skipped and reported). In [0, 1e-3]. Default 1e-12.
    pub degenerate_ratio: f64,
    /// Pass the UV seams to the toolpaths crate (strokes may then cross them when
    /// `placement.trace.cross_seams` is on). Default true.
    pub seams: bool,
}

impl Default for UvFieldOptions {
    fn default() -> Self {
        UvFieldOptions { degenerate_ratio: 1e-12, seams: true }
    }
}

impl UvFieldOptions {
    /// Range-checks every number; keys are relative to this section.
    pub fn validate(&self) -> Result<()> {
        if !(self.degenerate_ratio.is_finite() && (0.0..=1e-3).contains(&self.degenerate_ratio)) {
            return Err(Error::setting(
                "degenerate_ratio",
                format!(
                    "must be in [0, 1e-3], got {}",
                    crate::error::fmt_num(self.degenerate_ratio)
                ),
            ));
        }
        Ok(())
    }
}

/// What [`field_mesh`] did.
#[derive(Clone, Debug, Default, PartialEq, Serialize)]
pub struct UvFieldReport {
    /// UV vertices in the field mesh.
    pub uv_vertices: usize,
    /// Triangles in the field mesh.
    pub triangles: usize,
    /// Mesh faces left out because their UV triangle (or lift) is degenerate.
    pub degenerate_faces: Vec<u32>,
    /// Triangles with negative signed UV area (mirrored or flipped), kept.
    pub flipped_faces: usize,
    /// Seam pairs passed on.
    pub seam_pairs: usize,
    /// UV vertices whose averaged direction vanished (the corners disagree: a singularity).
    pub vanishing_directions: usize,
    /// The factor applied to the UV layout so one UV unit is about one scene unit on the
    /// part (area-preserving on average): flat SVG and G-code coordinates are UV × this.
    pub uv_scale: f64,
    /// For each UV vertex, the mesh vertex it lifts to.
    pub uv_to_vertex: Vec<u32>,
}

/// Lift Jacobian `J = [E₁ E₂]·[e₁ e₂]⁻¹` of a triangle (columns x_u, x_v), or `None` when the
/// UV triangle is degenerate.
fn jacobian(uv: [Vector2<f64>; 3], p: [Vector3<f64>; 3]) -> Option<[Vector3<f64>; 2]> {
    let (e1, e2) = (uv[1] - uv[0], uv[2] - uv[0]);
    let det = e1.perp(&e2);
    if det == 0.0 || !det.is_finite() {
        return None;
    }
    let (p1, p2) = (p[1] - p[0], p[2] - p[0]);
    // [e1 e2]⁻¹ = 1/det [[e2y, −e2x], [−e1y, e1x]]
    let xu = (p1 * e2.y - p2 * e1.y) / det;
    let xv = (-p1 * e2.x + p2 * e1.x) / det;
    Some([xu, xv])
}

/// `J⁺u = (JᵀJ)⁻¹ Jᵀ u`, or `None` when `JᵀJ` is singular.
fn pseudo_inverse(j: &[Vector3<f64>; 2], u: &Vector3<f64>) -> Option<Vector2<f64>> {
    let m = Matrix2::new(j[0].dot(&j[0]), j[0].dot(&j[1]), j[1].dot(&j[0]), j[1].dot(&j[1]));
    let d = m.try_inverse()? * Vector2::new(j[0].dot(u), j[1].dot(u));
    d.iter().all(|x| x.is_finite()).then_some(d)
}

fn toolpath_symmetry(s: Symmetry) -> grainline_toolpaths::Symmetry {
    match s {
        Symmetry::Oriented => grainline_toolpaths::Symmetry::Vector,
        Symmetry::Line => grainline_toolpaths::Symmetry::Line,
    }
}

fn corner_angle(p: [Vector3<f64>; 3], c: usize) -> f64 {
    let a = p[(c + 1) % 3] - p[c];
    let b = p[(c + 2) % 3] - p[c];
    let ang = a.cross(&b).norm().atan2(a.dot(&b));
    if ang.is_finite() {
        ang
    } else {
        0.0
    }
}

/// The mesh's UV layout, once `opts` are range-checked and the grain angles `phi` checked
/// against `mesh` and `geometry` (one finite angle and one frame per vertex).
fn checked_uv<'m>(
    mesh: &'m Mesh,
    geometry: &Geometry,
    phi: &[f64],
    opts: &UvFieldOptions,
) -> Result<&'m CornerAttribute<Vector2<f64>>> {
    opts.validate()?;
    let uv = mesh.uv.as_ref().ok_or_else(|| {
        Error::setting(
            "toolpaths",
            "the mesh has no UV coordinates (OBJ `vt`); toolpaths need a UV layout \
             (`layout::flatten` or `grainline flatten` makes one)",
        )
    })?;
    let nv = mesh.num_vertices();
    if phi.len() != nv || geometry.num_vertices() != nv {
        return Err(Error::invalid_arg(
            "phi",
            format!(
                "{} angles and {} frames for {nv} vertices",
                phi.len(),
                geometry.num_vertices()
            ),
        ));
    }
    if let Some(i) = phi.iter().position(|p| !p.is_finite()) {
        return Err(Error::Numerical {
            stage: "uv field",
            message: format!("grain angle of vertex {i} is not finite"),
        });
    }
    Ok(uv)
}

/// The degeneracy threshold on a UV triangle's area: `degenerate_ratio` × the squared diagonal
/// of the UV bounding box.
fn degenerate_area(values: &[Vector2<f64>], degenerate_ratio: f64) -> f64 {
    // UV bounding box diagonal for the degeneracy threshold.
    let (mut lo, mut hi) = (Vector2::repeat(f64::INFINITY), Vector2::repeat(f64::NEG_INFINITY));
    for t in values {
        lo = lo.inf(t);
        hi = hi.sup(t);
    }
    let diag2 = (hi - lo).norm_squared();
    degenerate_ratio * diag2
}

/// What [`scan_faces`] gathers from the mesh's faces, in face order.
struct FaceScan {
    /// Position of each UV vertex.
    uv_pos: Vec<[f64; 2]>,
    /// For each UV vertex, the mesh vertex it lifts to.
    uv_to_vertex: Vec<u32>,
    /// The kept triangles, in UV vertex ids.
    tris: Vec<[u32; 3]>,
    /// First fundamental form of each kept triangle.
    metrics: Vec<Metric>,
    /// Per face: its UV vertex ids (None when skipped), for the seams.
    face_uv: Vec<Option<[u32; 3]>>,
    /// Per UV vertex: the sum of its corners' weighted UV directions (angle-doubled for k = 2).
    acc: Vec<Vector2<f64>>,
    /// 3D area of the kept triangles.
    surface_area: f64,
    /// UV area of the kept triangles.
    uv_area: f64,
    /// Faces skipped as degenerate.
    degenerate_faces: Vec<u32>,
    /// Kept triangles with negative signed UV area.
    flipped_faces: usize,
}

/// The contribution of corner `c` of a triangle (3D positions `p`, lift Jacobian `j`) to its UV
/// vertex's direction sum: the vertex's grain `u` carried into UV, normalized and weighted by
/// the corner's 3D angle (angle-doubled when `k2`); `None` when it has no UV direction.
fn corner_direction(
    j: &[Vector3<f64>; 2],
    u: &Vector3<f64>,
    p: [Vector3<f64>; 3],
    c: usize,
    k2: bool,
) -> Option<Vector2<f64>> {
    // u carried into UV through this triangle: d = J⁺u.
    let d = pseudo_inverse(j, u)?;
    let n = d.norm();
    if n > 0.0 {
        let d = d / n;
        let wgt = corner_angle(p, c);
        let contrib = if k2 { Vector2::new(d.x * d.x - d.y * d.y, 2.0 * d.x * d.y) } else { d };
        Some(contrib * wgt)
    } else {
        None
    }
}

/// Scans the faces in order: skips (and lists) the degenerate ones, numbers the UV vertices
/// of the others in order of first appearance and sums their corners' grain directions `u3`
/// carried into UV.
fn scan_faces(
    mesh: &Mesh,
    uv: &CornerAttribute<Vector2<f64>>,
    u3: &[Vector3<f64>],
    k2: bool,
    min_area: f64,
) -> FaceScan {
    let mut s = FaceScan {
        uv_pos: Vec::new(),
        uv_to_vertex: Vec::new(),
        tris: Vec::new(),
        metrics: Vec::new(),
        face_uv: vec![None; mesh.num_faces()],
        acc: Vec::new(),
        surface_area: 0.0,
        uv_area: 0.0,
        degenerate_faces: Vec::new(),
        flipped_faces: 0,
    };
    let mut ids: HashMap<(u32, u64, u64), u32> = HashMap::new();
    let mut jacobians: Vec<[Vector3<f64>; 2]> = Vec::new();

    #[allow(clippy::needless_range_loop)] // f indexes the mesh, its UVs and face_uv
    for f in 0..mesh.num_faces() {
        let w = uv.face(f);
        let p = mesh.face_positions(f);
        let area2 = (w[1] - w[0]).perp(&(w[2] - w[0]));
        let j = jacobian(w, p);
        let metric = j.and_then(|j| {
            let m = Metric { e: j[0].dot(&j[0]), f: j[0].dot(&j[1]), g: j[1].dot(&j[1]) };
            m.is_valid().then_some(m)
        });
        let (Some(j), Some(metric)) = (j, metric) else {
            s.degenerate_faces.push(f as u32);
            continue;
        };
        if 0.5 * area2.abs() <= min_area {
            s.degenerate_faces.push(f as u32);
            continue;
        }
        s.flipped_faces += (area2 < 0.0) as usize;
        let mut t = [0u32; 3];
        for c in 0..3 {
            let v = mesh.faces[f][c];
            let key = (v, w[c].x.to_bits(), w[c].y.to_bits());
            let id = *ids.entry(key).or_insert_with(|| {
                s.uv_pos.push([w[c].x, w[c].y]);
                s.uv_to_vertex.push(v);
                s.acc.push(Vector2::zeros());
                (s.uv_pos.len() - 1) as u32
            });
            t[c] = id;
            if let Some(contrib) = corner_direction(&j, &u3[v as usize], p, c, k2) {
                s.acc[id as usize] += contrib;
            }
        }
        s.face_uv[f] = Some(t);
        s.surface_area += 0.5 * (p[1] - p[0]).cross(&(p[2] - p[0])).norm();
        s.uv_area += 0.5 * area2.abs();
        s.tris.push(t);
        s.metrics.push(metric);
        jacobians.push(j);
    }
    s
}

/// The direction of each UV vertex from its corners' sum `acc` (for k = 2 the doubled angle
/// halved back); the magnitude is kept as the coherence. A vanishing sum gives the zero
/// vector and is counted in `vanishing`.
fn uv_directions(acc: &[Vector2<f64>], k2: bool, vanishing: &mut usize) -> Vec<[f64; 2]> {
    acc.iter()
        .map(|a| {
            let n = a.norm();
            if n.is_nan() || n <= 1e-9 {
                *vanishing += 1;
                return [0.0, 0.0];
            }
            if k2 {
                // Halve the doubled angle, keep the magnitude as the coherence.
                let th = 0.5 * a.y.atan2(a.x);
                [n * th.cos(), n * th.sin()]
            } else {
                [a.x, a.y]
            }
        })
        .collect()
}

/// The UV seams: manifold mesh edges between kept faces (`face_uv`) that disagree on the UV
/// vertex of an end.
fn seam_pairs(mesh: &Mesh, face_uv: &[Option<[u32; 3]>]) -> Vec<SeamPair> {
    let mut seams = Vec::new();
    let mut edges: BTreeMap<(u32, u32), Vec<(usize, usize)>> = BTreeMap::new();
    for (f, t) in mesh.faces.iter().enumerate() {
        if face_uv[f].is_none() {
            continue;
        }
        for c in 0..3 {
            let (a, b) = (t[c], t[(c + 1) % 3]);
            edges.entry((a.min(b), a.max(b))).or_default().push((f, c));
        }
    }
    for ((a, _), list) in &edges {
        if list.len() != 2 {
            continue;
        }
        let side = |(f, c): (usize, usize)| {
            let t = mesh.faces[f];
            let u = face_uv[f].expect("kept face");
            let (i, j) = (c, (c + 1) % 3);
            // UV ids of the edge, ordered so that [0] lifts to mesh vertex `a`.
            if t[i] == *a {
                [u[i], u[j]]
            } else {
                [u[j], u[i]]
            }
        };
        let (s0, s1) = (side(list[0]), side(list[1]));
        if s0 != s1 {
            seams.push(SeamPair { a: s0, b: s1 });
        }
    }
    seams
}

/// Scales the UV layout (`uv_pos`, and the `metrics` with it) so one UV unit is about one
/// scene unit on the part; returns the factor.
fn normalize_uv_scale(
    surface_area: f64,
    uv_area: f64,
    uv_pos: &mut [[f64; 2]],
    metrics: &mut [Metric],
) -> f64 {
    // One UV unit ≈ one scene unit on the part: a [0, 1]² layout would otherwise give a flat
    // SVG / G-code of about a millimetre. The area-preserving scale keeps the metric exact
    // (M' = M / s²), so spacing on the part is unchanged; UV = XY panels keep s = 1.
    let mut scale = (surface_area / uv_area).sqrt();
    if !(scale.is_finite() && scale > 0.0) || (scale - 1.0).abs() < 1e-6 {
        scale = 1.0;
    }
    if scale != 1.0 {
        for q in uv_pos.iter_mut() {
            q[0] *= scale;
            q[1] *= scale;
        }
        let s2 = scale * scale;
        for m in metrics.iter_mut() {
            m.e /= s2;
            m.f /= s2;
            m.g /= s2;
        }
    }
    scale
}

/// Builds the toolpaths crate's [`FieldMesh`] from a UV-mapped mesh and its grain field
/// (angles `phi` in the `geometry` frames). See the module documentation.
pub fn field_mesh(
    mesh: &Mesh,
    geometry: &Geometry,
    phi: &[f64],
    symmetry: Symmetry,
    opts: &UvFieldOptions,
) -> Result<(FieldMesh, UvFieldReport)> {
    let uv = checked_uv(mesh, geometry, phi, opts)?;
    let u3: Vec<Vector3<f64>> = geometry.directions_of(phi);
    let k2 = symmetry == Symmetry::Line;
    let min_area = degenerate_area(&uv.values, opts.degenerate_ratio);

    let FaceScan {
        mut uv_pos,
        uv_to_vertex,
        tris,
        mut metrics,
        face_uv,
        acc,
        surface_area,
        uv_area,
        degenerate_faces,
        flipped_faces,
    } = scan_faces(mesh, uv, &u3, k2, min_area);
    let mut report = UvFieldReport { degenerate_faces, flipped_faces, ..Default::default() };
    if tris.is_empty() {
        return Err(Error::InvalidMesh {
            path: "toolpaths".into(),
            message: format!(
                "every one of the {} faces is degenerate in UV; nothing to brush",
                mesh.num_faces()
            ),
        });
    }
    let dirs = uv_directions(&acc, k2, &mut report.vanishing_directions);

    // Seams: manifold mesh edges whose faces disagree on the UV vertex of an end.
    let seams = if opts.seams { seam_pairs(mesh, &face_uv) } else { Vec::new() };
    report.seam_pairs = seams.len();
    let scale = normalize_uv_scale(surface_area, uv_area, &mut uv_pos, &mut metrics);
    report.uv_scale = scale;
    report.uv_vertices = uv_pos.len();
    report.triangles = tris.len();

    let positions: Vec<[f64; 3]> =
        uv_to_vertex.iter().map(|&v| mesh.positions[v as usize].into()).collect();
    let normals: Vec<[f64; 3]> =
        uv_to_vertex.iter().map(|&v| geometry.normal(v as usize).into()).collect();
    report.uv_to_vertex = uv_to_vertex;
    let fm = FieldMesh::new(uv_pos, tris, Directions::Vectors(dirs), toolpath_symmetry(symmetry))
        .with_lift(positions, Some(normals))
        .with_metric(metrics)
        .with_seams(seams);
    Ok((fm, report))
}

/// The grain rebuilt from the placed strokes.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct AsBrushed {
    /// Unit 3D direction per mesh vertex (the zero vector where `brushed` is false).
    pub u: Vec<[f64; 3]>,
    /// Whether the vertex got a direction (it has a UV vertex within half the brush's width of
    /// a stroke).
    pub brushed: Vec<bool>,
    /// Angle between designed and as-brushed u per mesh vertex, degrees (mod 180° for k = 2;
    /// 0 where not brushed).
    pub angle_deg: Vec<f64>,
    /// Median of `angle_deg` over brushed vertices.
    pub median_deg: f64,
    /// 95th percentile (nearest rank) of `angle_deg` over brushed vertices.
    pub p95_deg: f64,
    /// Largest `angle_deg`.
    pub max_deg: f64,
    /// Number of brushed vertices.
    pub compared: usize,
    /// Per mesh vertex, its distance on the part to the stroke it took its direction from
    /// (scene units; `None` where it took none).
    pub stroke_distance: Vec<Option<f64>>,
    /// Vertices farther than half the brush's width from that stroke: the brush never passed
    /// over them (a gap the placement left); they have no grain (`brushed` false).
    pub beyond_reach: usize,
    /// The brush's width the strokes were placed for (scene units).
    pub width: f64,
}

/// `v / |v|`, or `None` for a zero or non-finite vector.
fn unit2(v: [f64; 2]) -> Option<[f64; 2]> {
    let l = (v[0] * v[0] + v[1] * v[1]).sqrt();
    (l > 0.0 && l.is_finite()).then(|| [v[0] / l, v[1] / l])
}

/// Relative slack on half the brush's width in the footprint test (rounding of the distance
/// taken through a triangle's Jacobian).
const FOOTPRINT_SLACK: f64 = 1e-6;

/// A uniform grid of stroke segments in UV for nearest-segment queries.
struct SegmentGrid {
    segs: Vec<([f64; 2], [f64; 2])>,
    /// The unit tangents of the stroke at each segment's two ends: the mean of the segment's
    /// direction and its neighbour's (the segment's own at a stroke's end or a break).
    tangents: Vec<([f64; 2], [f64; 2])>,
    origin: [f64; 2],
    cell: f64,
    nx: usize,
    ny: usize,
    cells: Vec<Vec<u32>>,
}

impl SegmentGrid {
    /// The strokes' segments with their run-outs (the brush runs on past the part's edge along
    /// the stroke's tangent and brushes the edge beside the stroke's end).
    fn new(placement: &Placement) -> SegmentGrid {
        let paths: Vec<(Vec<[f64; 2]>, Vec<usize>)> = placement
            .strokes
            .iter()
            .map(|s| {
                let lead = usize::from(s.run_out[0].is_some());
                let mut uv: Vec<[f64; 2]> = s.run_out[0].into_iter().collect();
                uv.extend_from_slice(&s.uv);
                uv.extend(s.run_out[1]);
                (uv, s.breaks.iter().map(|b| b + lead).collect())
            })
            .collect();
        SegmentGrid::of_paths(paths.iter().map(|(uv, b)| (&uv[..], &b[..])))
    }

    /// The grid of polylines in UV, each with the indices of its points that start a new
    /// piece (a break: no segment into them).
    fn of_paths<'a>(paths: impl Iterator<Item = (&'a [[f64; 2]], &'a [usize])>) -> SegmentGrid {
        let mut segs = Vec::new();
        let mut tangents = Vec::new();
        for (uv, breaks) in paths {
            let first = segs.len();
            let mut prev: Option<usize> = None;
            for i in 1..uv.len() {
                if breaks.contains(&i) {
                    prev = None;
                    continue;
                }
                let (a, b) = (uv[i - 1], uv[i]);
                let Some(d) = unit2([b[0] - a[0], b[1] - a[1]]) else { continue };
                segs.push((a, b));
                tangents.push((d, d));
                let k = segs.len() - 1;
                // Two segments meeting at a point of the stroke share its tangent there.
                if let Some(j) = prev.filter(|&j| j >= first && segs[j].1 == a) {
                    if let Some(t) = unit2([tangents[j].1[0] + d[0], tangents[j].1[1] + d[1]]) {
                        tangents[j].1 = t;
                        tangents[k].0 = t;
                    }
                }
                prev = Some(k);
            }
        }
        let (mut lo, mut hi) = ([f64::INFINITY; 2], [f64::NEG_INFINITY; 2]);
        let mut total = 0.0;
        for (a, b) in &segs {
            for k in 0..2 {
                lo[k] = lo[k].min(a[k]).min(b[k]);
                hi[k] = hi[k].max(a[k]).max(b[k]);
            }
            total += ((b[0] - a[0]).powi(2) + (b[1] - a[1]).powi(2)).sqrt();
        }
        if segs.is_empty() {
            return SegmentGrid {
                segs,
                tangents,
                origin: [0.0; 2],
                cell: 1.0,
                nx: 0,
                ny: 0,
                cells: Vec::new(),
            };
        }
        let (w, h) = ((hi[0] - lo[0]).max(1e-12), (hi[1] - lo[1]).max(1e-12));
        // Cells of the mean segment's length (at most 1M cells): on the corpus a query then
        // reads about half the segments it read with cells twice as long, in half the time. The
        // search is exact whatever the cell (see `nearest`).
        let mean = total / segs.len() as f64;
        let cell = mean.max((w * h / 1.0e6).sqrt()).max(1e-12);
        let nx = (w / cell).ceil() as usize + 1;
        let ny = (h / cell).ceil() as usize + 1;
        let mut g = SegmentGrid {
            segs,
            tangents,
            origin: lo,
            cell,
            nx,
            ny,
            cells: vec![Vec::new(); nx * ny],
        };
        for (i, (a, b)) in g.segs.iter().enumerate() {
            let (ia, ja) = g.cell_of(*a);
            let (ib, jb) = g.cell_of(*b);
            for j in ja.min(jb)..=ja.max(jb) {
                for i2 in ia.min(ib)..=ia.max(ib) {
                    g.cells[j * nx + i2].push(i as u32);
                }
            }
        }
        g
    }

    fn cell_of(&self, p: [f64; 2]) -> (usize, usize) {
        let c =
            |x: f64, o: f64, n: usize| (((x - o) / self.cell).floor().max(0.0) as usize).min(n - 1);
        (c(p[0], self.origin[0], self.nx), c(p[1], self.origin[1], self.ny))
    }

    /// Nearest segment to `p`: (index, distance).
    /// The parameter t ∈ [0, 1] of the foot of `p` on segment `s` (0 for a degenerate one).
    fn foot(&self, s: usize, p: [f64; 2]) -> f64 {
        let (a, b) = self.segs[s];
        let d = [b[0] - a[0], b[1] - a[1]];
        let l2 = d[0] * d[0] + d[1] * d[1];
        let t = (((p[0] - a[0]) * d[0] + (p[1] - a[1]) * d[1]) / l2).clamp(0.0, 1.0);
        if t.is_finite() {
            t
        } else {
            0.0
        }
    }

    /// `p` less its foot on segment `s` (UV).
    fn offset_to(&self, s: usize, p: [f64; 2]) -> [f64; 2] {
        let (a, b) = self.segs[s];
        let t = self.foot(s, p);
        [p[0] - a[0] - t * (b[0] - a[0]), p[1] - a[1] - t * (b[1] - a[1])]
    }

    /// The stroke's unit tangent at the foot of `p` on segment `s`: the tangents at the
    /// segment's ends blended linearly — the direction of the smooth path the stroke's points
    /// sample (the machine blends its moves; the brush does not follow the polyline's kinks).
    fn tangent_at(&self, s: usize, p: [f64; 2]) -> [f64; 2] {
        let (a, b) = self.segs[s];
        let (ta, tb) = self.tangents[s];
        let t = self.foot(s, p);
        let chord = [b[0] - a[0], b[1] - a[1]];
        unit2([ta[0] + t * (tb[0] - ta[0]), ta[1] + t * (tb[1] - ta[1])]).unwrap_or(chord)
    }

    fn nearest(&self, p: [f64; 2]) -> Option<(usize, f64)> {
        if self.segs.is_empty() {
            return None;
        }
        let (ci, cj) = self.cell_of(p);
        // Distance from p to the grid box (p may lie outside it).
        let out = |x: f64, o: f64, n: usize| {
            let hi = o + n as f64 * self.cell;
            (o - x).max(x - hi).max(0.0)
        };
        let outside = out(p[0], self.origin[0], self.nx).hypot(out(p[1], self.origin[1], self.ny));
        let mut best: Option<(usize, f64)> = None;
        let rmax = self.nx.max(self.ny);
        for r in 0..=rmax {
            let (i0, i1) = (ci as isize - r as isize, ci as isize + r as isize);
            let (j0, j1) = (cj as isize - r as isize, cj as isize + r as isize);
            for j in j0..=j1 {
                for i in i0..=i1 {
                    if i != i0 && i != i1 && j != j0 && j != j1 {
                        continue;
                    }
                    if i < 0 || j < 0 || i as usize >= self.nx || j as usize >= self.ny {
                        continue;
                    }
                    for &s in &self.cells[j as usize * self.nx + i as usize] {
                        let (a, b) = self.segs[s as usize];
                        let d = segment_distance(p, a, b);
                        // Ties go to the lower index, so the result is deterministic.
                        if best.is_none_or(|(bs, bd)| d < bd || (d == bd && (s as usize) < bs)) {
                            best = Some((s as usize, d));
                        }
                    }
                }
            }
            if let Some((_, d)) = best {
                // Every unvisited cell is at least r·cell (plus the outside gap) away.
                if d <= r as f64 * self.cell + outside {
                    break;
                }
            }
        }
        best
    }
}

/// Rebuilds the grain from placed strokes and compares it with the designed field.
///
/// The strokes count with their run-outs (the brush runs on past the part's edge and brushes
/// the edge beside a stroke's end).
///
/// `field` and `report` are what [`field_mesh`] returned for the same `mesh`; `placement` the
/// strokes placed on it. Each UV vertex takes the unit UV tangent `t` of its nearest stroke
/// segment; its 3D direction is `J t` (normalized, projected onto the vertex's tangent plane)
/// for the Jacobian `J` of the first field-mesh triangle using that UV vertex, as long as the
/// brush reached it: a vertex farther than half the placement's width from that stroke on the
/// part (`|J (p − foot)|`) was never brushed and keeps the zero vector (`brushed` false). A mesh
/// vertex with several UV vertices (a seam) takes the one nearest to a stroke.
pub fn as_brushed(
    mesh: &Mesh,
    geometry: &Geometry,
    phi: &[f64],
    symmetry: Symmetry,
    field: &FieldMesh,
    report: &UvFieldReport,
    placement: &Placement,
) -> Result<AsBrushed> {
    let nv = mesh.num_vertices();
    if phi.len() != nv || report.uv_to_vertex.len() != field.uv.len() {
        return Err(Error::invalid_arg(
            "as_brushed",
            "the field mesh, its report and the grain angles do not belong to this mesh",
        ));
    }
    let designed = geometry.directions_of(phi);
    // First triangle of each UV vertex.
    let mut first_tri = vec![u32::MAX; field.uv.len()];
    for (t, tri) in field.triangles.iter().enumerate() {
        for &v in tri {
            if first_tri[v as usize] == u32::MAX {
                first_tri[v as usize] = t as u32;
            }
        }
    }
    let grid = SegmentGrid::new(placement);
    // Each UV vertex's nearest stroke direction on the part, found in parallel (each query is
    // independent), then kept per mesh vertex in UV vertex order: the same at any thread count.
    type Lifted = (usize, f64, Vector3<f64>, f64);
    let lifted: Vec<Option<Lifted>> = (0..field.uv.len())
        .into_par_iter()
        .map(|uvv| {
            let t = first_tri[uvv];
            if t == u32::MAX {
                return None;
            }
            let (s, d) = grid.nearest(field.uv[uvv])?;
            let tri = field.triangles[t as usize];
            let w = tri.map(|v| Vector2::from(field.uv[v as usize]));
            let x = tri.map(|v| mesh.positions[report.uv_to_vertex[v as usize] as usize]);
            let j = jacobian(w, x)?;
            let t = grid.tangent_at(s, field.uv[uvv]);
            let tangent = j[0] * t[0] + j[1] * t[1];
            let v = report.uv_to_vertex[uvv] as usize;
            let n = geometry.normal(v);
            let tangent = tangent - n * n.dot(&tangent);
            let len = tangent.norm();
            // The distance to the stroke on the part, through this triangle's Jacobian.
            let off = grid.offset_to(s, field.uv[uvv]);
            let reach = (j[0] * off[0] + j[1] * off[1]).norm();
            (len > 0.0 && len.is_finite()).then(|| (v, d, tangent / len, reach))
        })
        .collect();
    let mut best: Vec<Option<(f64, Vector3<f64>)>> = vec![None; nv];
    let mut stroke_distance = vec![f64::INFINITY; nv];
    for (v, d, t, reach) in lifted.into_iter().flatten() {
        if best[v].is_none_or(|(bd, _)| d < bd) {
            best[v] = Some((d, t));
            stroke_distance[v] = reach;
        }
    }
    // Half the brush's width, less nothing but rounding: with overlap 0 a vertex midway between
    // two strokes lies exactly there, brushed by both bands' edges.
    let half = 0.5 * placement.width * (1.0 + FOOTPRINT_SLACK);
    let beyond_reach = stroke_distance.iter().filter(|&&d| d.is_finite() && d > half).count();
    let mut u = vec![[0.0; 3]; nv];
    let mut brushed = vec![false; nv];
    let mut angle_deg = vec![0.0; nv];
    let mut angles = Vec::new();
    for v in 0..nv {
        let Some((_, t)) = best[v] else { continue };
        // Beyond the brush's footprint the metal was never brushed: no grain there.
        if stroke_distance[v] > half {
            continue;
        }
        let mut c = t.dot(&designed[v]).clamp(-1.0, 1.0);
        if symmetry == Symmetry::Line {
            c = c.abs();
        }
        let a = c.acos().to_degrees();
        u[v] = t.into();
        brushed[v] = true;
        angle_deg[v] = a;
        angles.push(a);
    }
    angles.sort_by(f64::total_cmp);
    let rank = |q: f64| {
        if angles.is_empty() {
            0.0
        } else {
            let i = ((q * angles.len() as f64).ceil() as usize).clamp(1, angles.len()) - 1;
            angles[i]
        }
    };
    Ok(AsBrushed {
        u,
        brushed,
        angle_deg,
        median_deg: rank(0.5),
        p95_deg: rank(0.95),
        max_deg: angles.last().copied().unwrap_or(0.0),
        compared: angles.len(),
        stroke_distance: stroke_distance.iter().map(|&d| d.is_finite().then_some(d)).collect(),
        beyond_reach,
        width: placement.width,
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A stroke sampled every 10° on a circle of radius 10: the direction at the foot of a point
    /// beside it is the circle's tangent there within 0.5° (the chord's is up to 5° off), away
    /// from the stroke's ends, where the end segment's own direction is kept.
    #[test]
    fn the_stroke_direction_at_a_foot_is_the_sampled_curve_s_tangent() {
        let pts: Vec<[f64; 2]> = (0..=18)
            .map(|k| {
                let a = (k as f64 * 10.0).to_radians();
                [10.0 * a.cos(), 10.0 * a.sin()]
            })
            .collect();
        let grid = SegmentGrid::of_paths(std::iter::once((&pts[..], &[][..])));
        for deg in [13.0f64, 25.0, 48.0, 95.0, 163.0] {
            let a = deg.to_radians();
            let p = [10.3 * a.cos(), 10.3 * a.sin()];
            let (s, _) = grid.nearest(p).unwrap();
            let t = grid.tangent_at(s, p);
            let want = [-a.sin(), a.cos()];
            let off = (t[0] * want[1] - t[1] * want[0]).asin().to_degrees().abs();
            assert!(off < 0.5, "{deg}°: {off}° off the tangent");
        }
        // A break starts a new piece: no blending across it.
        let g = SegmentGrid::of_paths(std::iter::once((&pts[..], &[9][..])));
        assert_eq!(g.segs.len(), 17);
        let s = g.nearest([10.0 * 82f64.to_radians().cos(), 10.0 * 82f64.to_radians().sin()]);
        let (a, b) = g.segs[s.unwrap().0];
        let chord = unit2([b[0] - a[0], b[1] - a[1]]).unwrap();
        assert_eq!(g.tangents[s.unwrap().0].1, chord);
    }
}
