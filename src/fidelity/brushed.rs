//! The fidelity of an edit as brushed (issue 47; docs/math.md §10, "As brushed"): the same
//! measure as the designed grain's ([`super::edit_fidelity`]), on the grain rebuilt from the
//! strokes (`uvfield::as_brushed`), next to the designed one.
//!
//! Both are measured against the same target (W(C0) of the field before the edit, or the drawn
//! curve: it does not depend on the grain measured), so their samples are the same, one for
//! one. Per sample k, with d_d and d_b its distances to the designed and to the as-brushed key
//! highlight (units of r, capped at [`super::MAX_DISTANCE`]), the **departure** is
//!
//! ```text
//! Δ_k = d_b,k − d_d,k
//! ```
//!
//! and the report gives the sample of largest |Δ_k| (the first in sample order on a tie): its
//! point on the part (scene units), its face and Δ (positive: the strokes put the highlight
//! farther from the target than the design). The singular triangles the strokes add are the
//! as-brushed field's singular triangles in the support less the designed field's,
//! `singular_after(brushed) − singular_after(designed)` (negative when the strokes remove some).

use nalgebra::Vector3;
use serde::Serialize;

use super::EditShape;
use super::{measure, support_faces, EditFidelity, FidelityOptions, Fields, Target};
use crate::edit::EditReport;
use crate::geometry::Geometry;
use crate::highlight::Symmetry;
use crate::mesh::Mesh;
use crate::Result;

/// Where the key highlight as brushed departs most from the designed one, measured on the
/// edit's target.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct Departure {
    /// The target sample, on the part (scene units).
    pub point: [f64; 3],
    /// The face it lies on (of the mesh the field lives on: FIELD.json's `faces`).
    pub face: usize,
    /// Its distance to the designed key highlight, units of r.
    pub designed: f64,
    /// Its distance to the as-brushed key highlight, units of r.
    pub as_brushed: f64,
    /// as_brushed − designed, units of r (positive: the strokes moved the highlight away from
    /// the target).
    pub value: f64,
}

/// One edit measured on the designed grain and on the grain rebuilt from the strokes.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct BrushedEditFidelity {
    /// Position of the edit in the `edits` list.
    pub index: usize,
    /// The tool's name.
    pub tool: String,
    /// The measure on the designed grain (the grain the strokes were traced from).
    pub designed: EditFidelity,
    /// The same measure on the grain rebuilt from the strokes.
    pub as_brushed: EditFidelity,
    /// Singular triangles in the support the strokes add: as-brushed `singular_after` minus
    /// designed `singular_after` (negative when they remove some).
    pub singular_added: i64,
    /// Vertices with a corner in the support that no stroke gave a direction (their grain is
    /// zero in the as-brushed field).
    pub unbrushed_vertices: usize,
    /// Vertices of the support's faces farther than half the brush's width from the stroke
    /// whose direction they take (on the part): gaps the brush never passed over, which the
    /// rebuilt grain fills with the nearest stroke's direction (filled in by the run from the
    /// strokes, [`beyond_reach_in_support`]; 0 otherwise).
    pub beyond_reach_vertices: usize,
    /// Where the two highlights differ most on the target; absent when nothing was compared.
    pub departure: Option<Departure>,
}

/// The fidelity of one edit on the designed grain `u_designed` and on the as-brushed grain
/// `u_brushed` (world-space unit vectors per vertex; the zero vector where no stroke gave one),
/// both against the target of the field before the edit `u_before`.
///
/// Errors: as [`super::edit_fidelity`].
#[allow(clippy::too_many_arguments)]
pub fn brushed_fidelity(
    mesh: &Mesh,
    geometry: &Geometry,
    h: &[Vector3<f64>],
    symmetry: Symmetry,
    u_before: &[Vector3<f64>],
    u_designed: &[Vector3<f64>],
    u_brushed: &[Vector3<f64>],
    index: usize,
    tool: &str,
    shape: &EditShape,
    options: &FidelityOptions,
) -> Result<BrushedEditFidelity> {
    let fields = |u_after| Fields { mesh, geometry, h, symmetry, u_before, u_after };
    let (designed, t_designed) = measure(&fields(u_designed), index, tool, shape, options)?;
    let (as_brushed, t_brushed) = measure(&fields(u_brushed), index, tool, shape, options)?;
    let singular_added = as_brushed.singular_after as i64 - designed.singular_after as i64;
    let departure = match (&t_designed, &t_brushed) {
        (Some(d), Some(b)) => largest_departure(mesh, shape, d, b),
        _ => None,
    };
    let unbrushed_vertices = support_vertices(mesh, shape)
        .iter()
        .filter(|&&v| u_brushed.get(v).is_none_or(|u| !(u.norm_squared() > 0.0)))
        .count();
    Ok(BrushedEditFidelity {
        index,
        tool: tool.to_string(),
        designed,
        as_brushed,
        singular_added,
        unbrushed_vertices,
        beyond_reach_vertices: 0,
        departure,
    })
}

/// The vertices of the faces with a corner in the edit's support whose distance to their
/// stroke (`stroke_distance`, scene units per vertex) exceeds `reach` (half the brush's width).
pub fn beyond_reach_in_support(
    mesh: &Mesh,
    shape: &EditShape,
    stroke_distance: &[Option<f64>],
    reach: f64,
) -> usize {
    support_vertices(mesh, shape)
        .iter()
        .filter(|&&v| stroke_distance.get(v).copied().flatten().is_some_and(|d| d > reach))
        .count()
}

/// The vertices of the faces with a corner in the edit's support, ascending.
fn support_vertices(mesh: &Mesh, shape: &EditShape) -> Vec<usize> {
    let mut v: Vec<usize> = support_faces(mesh, shape.support())
        .iter()
        .flat_map(|&f| mesh.faces[f].map(|x| x as usize))
        .collect();
    v.sort_unstable();
    v.dedup();
    v
}

/// The sample of largest |d_b − d_d| (the first on a tie), with its face: the warps' from the
/// chart, a curve sample's the nearest face of the support.
fn largest_departure(
    mesh: &Mesh,
    shape: &EditShape,
    designed: &Target,
    brushed: &Target,
) -> Option<Departure> {
    if designed.distances.len() != brushed.distances.len() {
        return None;
    }
    let cap = |d: f64| d.clamp(0.0, super::MAX_DISTANCE);
    let mut best: Option<(usize, f64)> = None;
    for (k, (d, b)) in designed.distances.iter().zip(&brushed.distances).enumerate() {
        let delta = cap(*b) - cap(*d);
        if best.is_none_or(|(_, x)| delta.abs() > x.abs()) {
            best = Some((k, delta));
        }
    }
    let (k, value) = best?;
    let (point, face) = *designed.points.get(k)?;
    let face = face.or_else(|| nearest_face(mesh, support_faces(mesh, shape.support()), &point))?;
    Some(Departure {
        point: [point.x, point.y, point.z],
        face,
        designed: cap(designed.distances[k]),
        as_brushed: cap(brushed.distances[k]),
        value,
    })
}

/// The face of `faces` nearest to `p` (the first on a tie).
fn nearest_face(mesh: &Mesh, faces: Vec<usize>, p: &Vector3<f64>) -> Option<usize> {
    let mut best: Option<(usize, f64)> = None;
    for f in faces {
        let [a, b, c] = mesh.face_positions(f);
        let (q, _) = crate::edit::support::closest_point_on_triangle(p, &a, &b, &c);
        let d = (q - p).norm_squared();
        if best.is_none_or(|(_, x)| d < x) {
            best = Some((f, d));
        }
    }
    best.map(|b| b.0)
}

/// [`brushed_fidelity`] of every edit with a shape (`reports[k].shape`): the field before
/// `phi_before` (the optimizer's input), the designed field `phi_designed` (angles in the
/// geometry's frames) and the as-brushed grain `u_brushed`.
#[allow(clippy::too_many_arguments)]
pub fn brushed_fidelity_of_edits(
    mesh: &Mesh,
    geometry: &Geometry,
    h: &[Vector3<f64>],
    symmetry: Symmetry,
    phi_before: &[f64],
    phi_designed: &[f64],
    u_brushed: &[Vector3<f64>],
    reports: &[EditReport],
    options: &FidelityOptions,
) -> Result<Vec<BrushedEditFidelity>> {
    if !reports.iter().any(|r| r.shape.is_some()) {
        return Ok(Vec::new());
    }
    let u_before = geometry.directions_of(phi_before);
    let u_designed = geometry.directions_of(phi_designed);
    reports
        .iter()
        .filter_map(|r| r.shape.as_ref().map(|s| (r, s)))
        .map(|(r, s)| {
            crate::cancel::checkpoint("fidelity")?;
            brushed_fidelity(
                mesh,
                geometry,
                h,
                symmetry,
                &u_before,
                &u_designed,
                u_brushed,
                r.index,
                &r.tool,
                s,
                options,
            )
        })
        .collect()
}
