//! Locked grain directions: which vertices, which angle, hard or soft (math.md §4).
//!
//! A [`LockSpec`] names a vertex set — an explicit list, the vertices within a Euclidean radius
//! of a point, or a boundary loop — and a direction: a world vector projected into each tangent
//! plane, or the boundary's own tangent (parallel) or its inward normal in the surface
//! (perpendicular, n × tangent, since a loop runs with its faces on the left).
//!
//! Hard locks (the default) take the vertex out of the unknowns and set its angle exactly. Soft
//! locks add the residual of [`super::fabrication::lock_residual`] with their weight.
//!
//! Angles are periodic (2π/k): two locks on one vertex conflict when their angles differ by
//! more than a tolerance modulo 2π/k; a conflict is reported and resolved by the circular mean
//! of e^{ikφ} (angle-doubled for k = 2). When the mean is undefined (the unit vectors cancel,
//! e.g. two opposite directions for k = 1) the first lock's angle is kept, so no NaN arises.

use nalgebra::Vector3;
use schemars::JsonSchema;
use serde::{Deserialize, Serialize};

use crate::geometry::connection::wrap_angle;
use crate::geometry::Geometry;
use crate::mesh::topology::Topology;
use crate::mesh::Mesh;
use crate::{Error, Result};

/// A ball: the vertices whose distance to `center` is at most `radius`.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize, JsonSchema)]
#[serde(deny_unknown_fields)]
pub struct LockRegion {
    /// Centre of the ball (scene units); `centre` is accepted too, as in the edits.
    #[serde(alias = "centre")]
    pub center: [f64; 3],
    /// Radius (> 0, scene units).
    pub radius: f64,
}

/// A direction derived from a boundary loop.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize, JsonSchema)]
#[serde(rename_all = "snake_case")]
pub enum BoundaryRelation {
    /// Along the boundary, in the loop's direction (faces on the left).
    Parallel,
    /// Across the boundary, pointing into the surface.
    Perpendicular,
}

/// One lock of the `constraints.locks` list. Exactly one vertex set (`vertices`, `region` or
/// `boundary_loop`) and exactly one direction (`direction` or `boundary`, the latter only with
/// `boundary_loop`).
#[derive(Clone, Debug, Default, PartialEq, Serialize, Deserialize, JsonSchema)]
#[serde(deny_unknown_fields)]
pub struct LockSpec {
    /// Explicit vertex indices (0-based).
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    pub vertices: Vec<u32>,
    /// The vertices within a ball.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub region: Option<LockRegion>,
    /// The vertices of boundary loop number `boundary_loop` (as `grainline inspect` lists them).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub boundary_loop: Option<usize>,
    /// A world direction, projected into each tangent plane.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub direction: Option<[f64; 3]>,
    /// Parallel or perpendicular to the boundary (with `boundary_loop` only).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub boundary: Option<BoundaryRelation>,
    /// Soft-lock weight λ_L > 0 (dimensionless: 1 makes a 45° deviation cost about as much as
    /// a 45° highlight error). Absent: a hard lock, held exactly.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub weight: Option<f64>,
}

impl LockSpec {
    /// Checks the numbers and the choice of set and direction; `key` is this lock's key path
    /// (e.g. `constraints.locks[2]`).
    pub fn validate_at(&self, key: &str) -> Result<()> {
        let sets = usize::from(!self.vertices.is_empty())
            + usize::from(self.region.is_some())
            + usize::from(self.boundary_loop.is_some());
        if sets != 1 {
            return Err(Error::setting(
                key,
                format!("give exactly one of vertices, region, boundary_loop (got {sets})"),
            ));
        }
        if let Some(r) = &self.region {
            if !r.center.iter().all(|c| c.is_finite()) {
                return Err(Error::setting(format!("{key}.region.center"), "must be finite"));
            }
            if !(r.radius.is_finite() && r.radius > 0.0) {
                return Err(Error::setting(
                    format!("{key}.region.radius"),
                    format!("must be a finite number > 0, got {}", crate::error::fmt_num(r.radius)),
                ));
            }
        }
        match (&self.direction, &self.boundary) {
            (Some(d), None) => {
                if !d.iter().all(|c| c.is_finite()) || d.iter().all(|&c| c == 0.0) {
                    return Err(Error::setting(
                        format!("{key}.direction"),
                        format!("must be a finite non-zero vector, got {d:?}"),
                    ));
                }
            }
            (None, Some(_)) => {
                if self.boundary_loop.is_none() {
                    return Err(Error::setting(
                        format!("{key}.boundary"),
                        "needs boundary_loop (the direction is derived from that loop)",
                    ));
                }
            }
            _ => {
                return Err(Error::setting(key, "give exactly one of direction, boundary"));
            }
        }
        if let Some(w) = self.weight {
            if !(w.is_finite() && w > 0.0) {
                return Err(Error::setting(
                    format!("{key}.weight"),
                    format!("must be a finite number > 0, got {}", crate::error::fmt_num(w)),
                ));
            }
        }
        Ok(())
    }
}

/// Two or more locks on one vertex that disagree by more than the tolerance (mod 2π/k).
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct LockConflict {
    /// The vertex.
    pub vertex: u32,
    /// The angles asked for (rad, in the vertex frame), in the order of the lock list.
    pub angles: Vec<f64>,
    /// The angle used (their circular mean).
    pub resolved: f64,
}

/// The locks applied to the vertices.
#[derive(Clone, Debug, Default, PartialEq, Serialize)]
pub struct ResolvedLocks {
    /// Hard locks: (vertex, angle), by increasing vertex.
    pub hard: Vec<(u32, f64)>,
    /// Soft locks: (vertex, angle, weight), by increasing vertex (none on a hard vertex).
    pub soft: Vec<(u32, f64, f64)>,
    /// Conflicts found.
    pub conflicts: Vec<LockConflict>,
    /// Vertices skipped because the lock's direction has no tangential part there (a world
    /// direction along the normal, or a degenerate boundary tangent).
    pub degenerate: Vec<u32>,
}

/// The circular mean of angles for symmetry k, weighted: arg Σ wⱼ e^{ikφⱼ} / k. Falls back to
/// the first angle when the sum vanishes (relative to the weights) or the input is empty (0).
pub fn circular_mean(angles: &[(f64, f64)], k: u32) -> f64 {
    let kf = k as f64;
    let (mut c, mut s, mut wsum) = (0.0, 0.0, 0.0);
    for &(a, w) in angles {
        c += w * (kf * a).cos();
        s += w * (kf * a).sin();
        wsum += w.abs();
    }
    let norm = c.hypot(s);
    if norm.is_nan() || norm <= 1e-9 * wsum {
        return angles.first().map_or(0.0, |a| a.0);
    }
    s.atan2(c) / kf
}

/// The difference a − b wrapped to (−π/k, π/k].
#[inline]
pub fn angle_difference(a: f64, b: f64, k: u32) -> f64 {
    let kf = k as f64;
    wrap_angle(kf * (a - b)) / kf
}

/// Resolves the lock specifications on a mesh into per-vertex angles (in the vertex frames).
/// `key` is the key path of the lock list (errors name `key[i]...`); `tolerance` is the
/// conflict tolerance in radians.
pub fn resolve_locks(
    mesh: &Mesh,
    geometry: &Geometry,
    specs: &[LockSpec],
    k: u32,
    tolerance: f64,
    key: &str,
) -> Result<ResolvedLocks> {
    let nv = mesh.num_vertices();
    // (vertex, angle, weight or None for hard), in lock order; grouped by vertex below (a
    // list of the locked vertices alone: no work per vertex of the part without locks).
    let mut asked: Vec<(u32, f64, Option<f64>)> = Vec::new();
    let mut degenerate = Vec::new();
    let mut topology: Option<Topology> = None;
    for (li, spec) in specs.iter().enumerate() {
        let lkey = format!("{key}[{li}]");
        spec.validate_at(&lkey)?;
        // (vertex, tangent direction before projection)
        let mut targets: Vec<(u32, Vector3<f64>)> = Vec::new();
        let world = spec.direction.map(|d| Vector3::new(d[0], d[1], d[2]));
        if !spec.vertices.is_empty() {
            for (vi, &v) in spec.vertices.iter().enumerate() {
                if v as usize >= nv {
                    return Err(Error::setting(
                        format!("{lkey}.vertices[{vi}]"),
                        format!("vertex {v} does not exist (the mesh has {nv} vertices)"),
                    ));
                }
                targets.push((v, world.unwrap_or_else(Vector3::zeros)));
            }
        } else if let Some(r) = &spec.region {
            let c = Vector3::new(r.center[0], r.center[1], r.center[2]);
            for (v, p) in mesh.positions.iter().enumerate() {
                if (p - c).norm() <= r.radius {
                    targets.push((v as u32, world.unwrap_or_else(Vector3::zeros)));
                }
            }
        } else if let Some(l) = spec.boundary_loop {
            if topology.is_none() {
                topology = Some(Topology::new(mesh)?);
            }
            let topo = topology.as_ref().expect("just built");
            let loops = topo.num_boundary_loops();
            if l >= loops {
                return Err(Error::setting(
                    format!("{lkey}.boundary_loop"),
                    format!("loop {l} does not exist (the mesh has {loops} boundary loops)"),
                ));
            }
            let lp = topo.boundary_loop(l);
            let m = lp.len();
            for (a, v) in lp.iter().enumerate() {
                let dir = match (world, spec.boundary) {
                    (Some(w), _) => w,
                    (None, rel) => {
                        let (prev, next) = (lp[(a + m - 1) % m], lp[(a + 1) % m]);
                        let tangent = mesh.positions[next.index()] - mesh.positions[prev.index()];
                        match rel {
                            Some(BoundaryRelation::Perpendicular) => {
                                geometry.normal(v.index()).cross(&tangent)
                            }
                            _ => tangent,
                        }
                    }
                };
                targets.push((v.0, dir));
            }
        }
        for (v, dir) in targets {
            let f = &geometry.frames[v as usize];
            let tangential = f.to_local(&dir);
            let len = tangential.norm();
            if len.is_nan() || len <= 1e-9 * dir.norm() {
                degenerate.push(v);
                continue;
            }
            asked.push((v, tangential.y.atan2(tangential.x), spec.weight));
        }
    }
    degenerate.sort_unstable();
    degenerate.dedup();
    let mut out = ResolvedLocks { degenerate, ..Default::default() };
    // A stable sort: each vertex's locks stay in lock order.
    asked.sort_by_key(|a| a.0);
    for group in asked.chunk_by(|a, b| a.0 == b.0) {
        let v = group[0].0;
        let list: Vec<(f64, Option<f64>)> = group.iter().map(|a| (a.1, a.2)).collect();
        let hard: Vec<(f64, f64)> =
            list.iter().filter(|a| a.1.is_none()).map(|a| (a.0, 1.0)).collect();
        let used: Vec<(f64, f64)> = if hard.is_empty() {
            list.iter().map(|a| (a.0, a.1.unwrap_or(1.0))).collect()
        } else {
            hard.clone()
        };
        let angle = circular_mean(&used, k);
        let first = list[0].0;
        let conflict = list.iter().any(|a| angle_difference(a.0, first, k).abs() > tolerance);
        if conflict {
            out.conflicts.push(LockConflict {
                vertex: v,
                angles: list.iter().map(|a| a.0).collect(),
                resolved: angle,
            });
        }
        if hard.is_empty() {
            let weight: f64 = used.iter().map(|a| a.1).sum();
            out.soft.push((v, angle, weight));
        } else {
            out.hard.push((v, angle));
        }
    }
    Ok(out)
}
