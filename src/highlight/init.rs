//! Initial grain fields: from the UV layout, a world direction, principal curvature directions,
//! the smoothest field, or per-vertex directions given by the user.
//!
//! Every result is an angle φ per vertex in the vertex frames ([`crate::geometry::Frame`]),
//! finite everywhere; vertices where the chosen construction has no direction take a documented
//! fallback and are listed in the result.

use nalgebra::Vector3;

use super::smoothest::{smoothest_field, SmoothestOptions};
use super::Symmetry;
use crate::geometry::normals::corner_angle;
use crate::geometry::Geometry;
use crate::mesh::Mesh;
use crate::{Error, Result};

/// How to build the initial field.
#[derive(Clone, Debug, PartialEq)]
pub enum InitialField {
    /// ∂p/∂u of the UV layout, per vertex from the chart that covers most of its corner angle.
    Uv,
    /// The smoothest field (Knöppel et al. 2013) for the chosen symmetry.
    Smooth,
    /// The direction of minimum principal curvature (k2).
    CurvatureMin,
    /// The direction of maximum principal curvature (k1).
    CurvatureMax,
    /// A world direction projected onto each tangent plane.
    World(Vector3<f64>),
    /// One world direction per vertex, projected onto the tangent planes.
    Directions(Vec<Vector3<f64>>),
    /// A grain map in UV space (direction or angle, docs/formats.md "Grain maps"), read at
    /// every face corner in its MikkTSpace frame ([`crate::texmap::corner_grain`]) and summed
    /// per vertex (needs UVs).
    Map(crate::texmap::GrainMap),
}

impl std::str::FromStr for InitialField {
    type Err = Error;
    /// Parses `uv`, `smooth`, `curvature-min`, `curvature-max` or `world:X,Y,Z`.
    fn from_str(s: &str) -> Result<Self> {
        Ok(match s {
            "uv" => InitialField::Uv,
            "smooth" => InitialField::Smooth,
            "curvature-min" => InitialField::CurvatureMin,
            "curvature-max" => InitialField::CurvatureMax,
            _ => match s.strip_prefix("world:") {
                Some(v) => InitialField::World(super::parse_vec3("init", v)?),
                None => {
                    return Err(Error::invalid_arg(
                        "init",
                        format!(
                        "{s:?}: expected uv, smooth, curvature-min, curvature-max or world:X,Y,Z"
                    ),
                    ))
                }
            },
        })
    }
}

/// An initial field and where it needed a fallback.
#[derive(Clone, Debug, Default)]
pub struct InitialFieldResult {
    /// φ per vertex.
    pub phi: Vec<f64>,
    /// Vertices where the construction had no direction and a fallback was used.
    pub fallback_vertices: Vec<u32>,
}

/// Relative length under which a projected direction counts as vanishing.
const VANISHING: f64 = 1e-6;

/// Builds the initial field.
///
/// Fallbacks: for `World`, a vertex where the direction is (within 2°, [`NEARLY_NORMAL`])
/// normal to the surface takes
/// [`second_direction`] projected instead. For `World` and `Uv`, a vertex whose direction
/// still vanishes takes the sum of its
/// neighbours' (non-fallback) directions projected onto its tangent plane, or, if that vanishes
/// too, its frame's t axis. `Directions` errors instead, naming the vertex.
pub fn initial_field(
    mesh: &Mesh,
    geom: &Geometry,
    init: &InitialField,
    symmetry: Symmetry,
) -> Result<InitialFieldResult> {
    let n = geom.num_vertices();
    let dirs: Vec<Option<Vector3<f64>>> = match init {
        InitialField::Smooth => {
            let phi = smoothest_field(mesh, geom, symmetry, &SmoothestOptions::default())?.phi;
            return Ok(InitialFieldResult { phi, fallback_vertices: Vec::new() });
        }
        InitialField::CurvatureMin | InitialField::CurvatureMax => {
            let phi = geom
                .principal
                .iter()
                .map(|p| {
                    let d = if *init == InitialField::CurvatureMax { p.d1 } else { p.d2() };
                    d[1].atan2(d[0])
                })
                .collect();
            return Ok(InitialFieldResult { phi, fallback_vertices: Vec::new() });
        }
        InitialField::World(w) => {
            let second = second_direction(w);
            (0..n)
                .map(|i| match project_at_least(geom, i, w, NEARLY_NORMAL) {
                    Some(u) => Some(u),
                    None => project(geom, i, &second).or_else(|| project(geom, i, w)),
                })
                .collect()
        }
        InitialField::Directions(d) => {
            if d.len() != n {
                return Err(Error::invalid_arg(
                    "directions",
                    format!("{} directions for {} vertices", d.len(), n),
                ));
            }
            return d
                .iter()
                .enumerate()
                .map(|(i, w)| {
                    project(geom, i, w).map(|u| geom.frames[i].angle_of(&u)).ok_or_else(|| {
                        Error::invalid_arg(
                            "directions",
                            format!(
                                "vertex {i}: direction ({}, {}, {}) vanishes in the tangent plane",
                                w.x, w.y, w.z
                            ),
                        )
                    })
                })
                .collect::<Result<Vec<f64>>>()
                .map(|phi| InitialFieldResult { phi, fallback_vertices: Vec::new() });
        }
        InitialField::Uv => uv_directions(mesh, geom, symmetry)?,
        InitialField::Map(map) => map_directions(mesh, geom, map, symmetry)?,
    };
    Ok(with_fallbacks(geom, dirs, symmetry))
}

/// A direction and its weight.
type Weighted = (Vector3<f64>, f64);

/// Sums directions at vertex `i` as `symmetry` reads them: as vectors for an oriented field;
/// for a line field by their doubled angle in the vertex's tangent frame (u and −u add up
/// instead of cancelling: a mirrored chart's ∂p/∂u on either side of its fold, or neighbours
/// whose directions point opposite ways along one line). `None` when the sum vanishes.
fn sum_directions(
    geom: &Geometry,
    i: usize,
    dirs: impl Iterator<Item = Weighted>,
    symmetry: Symmetry,
) -> Option<Vector3<f64>> {
    match symmetry {
        Symmetry::Oriented => {
            let sum: Vector3<f64> = dirs.map(|(d, w)| d * w).sum();
            project(geom, i, &sum)
        }
        Symmetry::Line => {
            let f = &geom.frames[i];
            let (mut c, mut s, mut total) = (0.0, 0.0, 0.0);
            for (d, w) in dirs {
                let local = f.to_local(&d);
                let len2 = local.norm_squared();
                // A direction along the normal has no line in the tangent plane (`project`).
                if !(len2 > (VANISHING * VANISHING) * d.norm_squared() && len2.is_finite()) {
                    continue;
                }
                // (cos 2α, sin 2α) from (cos α, sin α) without an angle.
                c += w * (local.x * local.x - local.y * local.y) / len2;
                s += w * 2.0 * local.x * local.y / len2;
                total += w;
            }
            let len = c.hypot(s);
            (len > VANISHING * total && len.is_finite()).then(|| f.direction(0.5 * s.atan2(c)))
        }
    }
}

/// `w` projected onto the tangent plane of vertex `i` and normalized, unless it vanishes there.
/// The grain where a world direction `w` is normal to the surface (a flat face that faces
/// it, where its projection vanishes): the world axis least aligned with `w` (the first of a
/// tie: x, then y, then z), made perpendicular to `w`. On such a face every vertex takes the
/// same direction, so the grain stays straight across it.
pub fn second_direction(w: &Vector3<f64>) -> Vector3<f64> {
    let mut k = 0;
    for j in 1..3 {
        if w[j].abs() < w[k].abs() {
            k = j;
        }
    }
    let a = Vector3::ith(k, 1.0);
    let w2 = w.norm_squared();
    if w2 > 0.0 && w2.is_finite() {
        a - w * (w.dot(&a) / w2)
    } else {
        a
    }
}

/// The sine of the angle between a world direction and the surface normal under which the
/// direction counts as normal to the surface (2°): its projection there is mostly the
/// normal's error (a CAD export's coordinates are `f32`, and a flat face's slivers tilt their
/// normals by up to about 10⁻³), so [`second_direction`] is used instead.
pub const NEARLY_NORMAL: f64 = 0.035;

/// `w` projected onto vertex `i`'s tangent plane and normalized, if at least `min` × |w| long.
fn project_at_least(geom: &Geometry, i: usize, w: &Vector3<f64>, min: f64) -> Option<Vector3<f64>> {
    let n = geom.frames[i].n;
    let p = w - n * n.dot(w);
    let len = p.norm();
    (len > min * w.norm() && len.is_finite()).then(|| p / len)
}

fn project(geom: &Geometry, i: usize, w: &Vector3<f64>) -> Option<Vector3<f64>> {
    let n = geom.frames[i].n;
    let p = w - n * n.dot(w);
    let len = p.norm();
    (len > VANISHING * w.norm() && len.is_finite()).then(|| p / len)
}

fn with_fallbacks(
    geom: &Geometry,
    dirs: Vec<Option<Vector3<f64>>>,
    symmetry: Symmetry,
) -> InitialFieldResult {
    let mut fallback_vertices = Vec::new();
    let phi = (0..dirs.len())
        .map(|i| {
            let f = &geom.frames[i];
            if let Some(u) = dirs[i] {
                return f.angle_of(&u);
            }
            fallback_vertices.push(i as u32);
            let near = geom.adjacency.neighbors(i).iter().filter_map(|&j| dirs[j as usize]);
            sum_directions(geom, i, near.map(|d| (d, 1.0)), symmetry)
                .map_or(0.0, |u| f.angle_of(&u))
        })
        .collect();
    InitialFieldResult { phi, fallback_vertices }
}

/// Per vertex, ∂p/∂u averaged (by corner angle) over the faces of the UV chart that holds most
/// of the vertex's corner angle. Faces are grouped by the UV index at the vertex's corner, so
/// faces across a seam (other charts, unrelated UV orientation) never cancel each other. ∂p/∂u
/// is the direction of increasing u on the surface whatever the chart's handedness; where a
/// mirrored chart folds (u = |x|: the faces on either side share the fold's UVs but their ∂p/∂u
/// point opposite ways), a line field sums them as lines ([`sum_directions`]) and gets the
/// fold's common line, which a sum of vectors cancelled. Faces with a degenerate UV triangle
/// are skipped.
/// The grain a map gives each vertex: its corners' readings ([`crate::texmap::corner_grain`],
/// in the geometry's normals' frames) summed with their corner angles as weights.
fn map_directions(
    mesh: &Mesh,
    geom: &Geometry,
    map: &crate::texmap::GrainMap,
    symmetry: Symmetry,
) -> Result<Vec<Option<Vector3<f64>>>> {
    let uv = mesh.uv.as_ref().ok_or_else(|| {
        Error::invalid_arg("init", "a grain map needs the part's UV coordinates, and it has none")
    })?;
    let normals: Vec<Vector3<f64>> = geom.frames.iter().map(|f| f.n).collect();
    let oriented = symmetry == Symmetry::Oriented;
    let corners =
        crate::texmap::corner_grain(&mesh.positions, &mesh.faces, &normals, uv, map, oriented);
    let vf = crate::geometry::VertexFaces::new(mesh);
    Ok((0..mesh.num_vertices())
        .map(|v| {
            let dirs = vf.of(v).iter().filter_map(|&(f, c)| {
                let (f, c) = (f as usize, c as usize);
                let tri = mesh.face_positions(f);
                let angle = corner_angle(&tri[c], &tri[(c + 1) % 3], &tri[(c + 2) % 3]);
                corners[f][c].map(|d| (d, angle))
            });
            sum_directions(geom, v, dirs, symmetry)
        })
        .collect())
}

fn uv_directions(
    mesh: &Mesh,
    geom: &Geometry,
    symmetry: Symmetry,
) -> Result<Vec<Option<Vector3<f64>>>> {
    let uv = mesh.uv.as_ref().ok_or_else(|| {
        Error::invalid_arg("init", "the mesh has no UV coordinates (vt); use another --init")
    })?;
    let dpdu: Vec<Option<Vector3<f64>>> = (0..mesh.num_faces())
        .map(|f| {
            let [p0, p1, p2] = mesh.face_positions(f);
            let [t0, t1, t2] = uv.face(f);
            let (e1, e2) = (p1 - p0, p2 - p0);
            let (d1, d2) = (t1 - t0, t2 - t0);
            let det = d1.x * d2.y - d2.x * d1.y;
            let scale = d1.norm() * d2.norm();
            if !(det.abs() > 1e-12 * scale && scale > 0.0) {
                return None;
            }
            let g = (e1 * d2.y - e2 * d1.y) / det;
            g.iter().all(|c| c.is_finite()).then_some(g)
        })
        .collect();
    let vf = crate::geometry::VertexFaces::new(mesh);
    Ok((0..mesh.num_vertices())
        .map(|v| {
            // (uv index, total corner angle, (unit direction, corner angle) of its faces) per
            // chart around v.
            let mut groups: Vec<(u32, f64, Vec<Weighted>)> = Vec::new();
            for &(f, c) in vf.of(v) {
                let (f, c) = (f as usize, c as usize);
                let tri = mesh.face_positions(f);
                let angle = corner_angle(&tri[c], &tri[(c + 1) % 3], &tri[(c + 2) % 3]);
                let key = uv.corners[f][c];
                let idx = match groups.iter().position(|g| g.0 == key) {
                    Some(k) => k,
                    None => {
                        groups.push((key, 0.0, Vec::new()));
                        groups.len() - 1
                    }
                };
                groups[idx].1 += angle;
                if let Some(d) = dpdu[f] {
                    groups[idx].2.push((d.normalize(), angle));
                }
            }
            groups.sort_by(|a, b| b.1.total_cmp(&a.1).then(a.0.cmp(&b.0)));
            groups.iter().find_map(|g| sum_directions(geom, v, g.2.iter().copied(), symmetry))
        })
        .collect())
}
