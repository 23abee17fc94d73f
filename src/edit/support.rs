//! The brush support B of the paper's §5 and its planar parametrization.
//!
//! - **Centre**: a vertex, or a point projected to the closest point of the surface.
//! - **Distance**: `geodesic` (the default) or `euclidean` (straight-line distance to the centre
//!   point, every vertex of the mesh within the ball). The geodesic distance is a Dijkstra
//!   search with straight-line shortcuts (in the spirit of Theta*): every vertex keeps an
//!   *anchor* — the centre or an earlier vertex — and its distance is the anchor's plus the arc
//!   from the anchor, estimated from the chord c and the angle α between the two normals as
//!   c·(α/2)/sin(α/2) (exact for circular arcs: planes, spheres, a cylinder's circumference).
//!   The shortcut is taken while the normals of the anchor and the vertex are within 60° of each
//!   other; otherwise the anchor moves to the previous vertex of the path. The distance is
//!   exact on planes (every anchor is the centre), exact along great circles, and never takes a
//!   shortcut through the inside of a thin part (the normals disagree). A known limit: around a
//!   hole in a flat region the shortcut crosses the hole.
//! - **Plane**: a weighted PCA of the support's positions (weights Aᵢ(1 − dᵢ²/r²)), its normal
//!   the axis of least variance, oriented like the vertex normals (the mean normal when the
//!   support is too small or too round for PCA). Its origin is the centre point, its axes eₓ,
//!   e_y the brush's.
//! - **Chart**: the support unrolled onto that plane in geodesic polar coordinates (the
//!   discrete exponential map, [`super::chart`]), in units of r: on a plane it is the plane's
//!   own coordinates and the support is exactly the unit disk; on a curved part it does not
//!   fold where the orthogonal projection would (a fin, a rim).
//! - **Fall-off** w(x, y) = (1 − x² − y²)² (paper §5).
//! - **Point location** (the warps' ℓ_q): the faces with a corner in the support, in the chart
//!   and bucketed in a grid; a value at a planar point q is the barycentric
//!   interpolation of the corner values in the triangle containing q (the one nearest the query's
//!   vertex in space when the projection overlaps itself), or, for q beyond a boundary, at the
//!   closest point of the closest triangle.

use std::cmp::Ordering;
use std::collections::BinaryHeap;

use nalgebra::{Matrix3, Vector2, Vector3};
use serde::{Deserialize, Serialize};

use super::chart::{Base, Chart};
use super::Context;
use crate::geometry::Frame;
use crate::{Error, Result};

/// Where a brush is centred: `{"vertex": 12}` or `{"point": [x, y, z]}`.
#[derive(Clone, Debug, PartialEq, Serialize, schemars::JsonSchema)]
#[serde(rename_all = "snake_case", deny_unknown_fields)]
pub enum Centre {
    /// A vertex index.
    Vertex(u32),
    /// A point in scene units, projected to the closest point of the surface.
    Point([f64; 3]),
}

/// `centre` as written: read as a map so an unknown key is named (an enum read inside an edit
/// only said "expected map with a single key").
#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct CentreKeys {
    vertex: Option<u32>,
    point: Option<[f64; 3]>,
}

impl<'de> Deserialize<'de> for Centre {
    fn deserialize<D: serde::Deserializer<'de>>(d: D) -> std::result::Result<Self, D::Error> {
        Centre::try_from(CentreKeys::deserialize(d)?).map_err(serde::de::Error::custom)
    }
}

impl TryFrom<CentreKeys> for Centre {
    type Error = String;

    fn try_from(k: CentreKeys) -> std::result::Result<Self, String> {
        match (k.vertex, k.point) {
            (Some(v), None) => Ok(Centre::Vertex(v)),
            (None, Some(p)) => Ok(Centre::Point(p)),
            _ => {
                Err("centre: give exactly one of `vertex` (an index) or `point` ([x, y, z])".into())
            }
        }
    }
}

impl Centre {
    /// Checks the point is finite (the vertex index is checked against the mesh later).
    pub fn validate(&self) -> Result<()> {
        if let Centre::Point(p) = self {
            if !p.iter().all(|c| c.is_finite()) {
                return Err(Error::setting("centre.point", "coordinates must be finite"));
            }
        }
        Ok(())
    }
}

/// How distances to the centre are measured.
#[derive(
    Clone, Copy, Debug, Default, PartialEq, Eq, Serialize, Deserialize, schemars::JsonSchema,
)]
#[serde(rename_all = "snake_case")]
pub enum Metric {
    /// Along the surface (see the module documentation); the default.
    #[default]
    Geodesic,
    /// Straight-line distance in space.
    Euclidean,
}

/// The centre resolved on the surface.
#[derive(Clone, Debug)]
pub struct SurfacePoint {
    /// Position on the surface.
    pub position: Vector3<f64>,
    /// Unit normal there (interpolated vertex normals).
    pub normal: Vector3<f64>,
    /// Vertices with their straight-line distance, to seed the geodesic search.
    pub seeds: Vec<(usize, f64)>,
    /// The vertex closest to the point.
    pub nearest_vertex: usize,
}

/// Resolves a [`Centre`]; errors name `centre.vertex` or `centre.point`.
pub(crate) fn resolve_centre(ctx: &Context, centre: &Centre) -> Result<SurfacePoint> {
    let mesh = ctx.mesh;
    match centre {
        Centre::Vertex(v) => {
            let i = *v as usize;
            if i >= mesh.num_vertices() {
                return Err(Error::setting(
                    "centre.vertex",
                    format!("vertex {i} does not exist (the mesh has {})", mesh.num_vertices()),
                ));
            }
            Ok(SurfacePoint {
                position: mesh.positions[i],
                normal: ctx.normals[i],
                seeds: vec![(i, 0.0)],
                nearest_vertex: i,
            })
        }
        Centre::Point(p) => {
            let key = p.map(f64::to_bits);
            // The same bits give the same point: the search is a function of them.
            if let Some(hit) = ctx.centres.find(&key) {
                return Ok(hit);
            }
            let point = closest_surface_point(ctx, p)?;
            ctx.centres.keep(key, &point);
            Ok(point)
        }
    }
}

/// The centres resolved so far, by the bits of their points: a drag keeps its brush centre
/// from step to step, and finding the closest point visits every face.
#[derive(Default)]
pub(crate) struct CentreMemo(std::sync::Mutex<Vec<([u64; 3], SurfacePoint)>>);

/// Centres kept by a [`CentreMemo`].
const CENTRES_KEPT: usize = 8;

impl CentreMemo {
    fn find(&self, key: &[u64; 3]) -> Option<SurfacePoint> {
        let kept = self.0.lock().unwrap_or_else(|e| e.into_inner());
        kept.iter().find(|(k, _)| k == key).map(|(_, p)| p.clone())
    }

    fn keep(&self, key: [u64; 3], point: &SurfacePoint) {
        let mut kept = self.0.lock().unwrap_or_else(|e| e.into_inner());
        kept.push((key, point.clone()));
        if kept.len() > CENTRES_KEPT {
            kept.remove(0);
        }
    }
}

/// The point of the surface closest to `p` (the first such face in face order), its
/// interpolated normal and the face's corners as seeds.
fn closest_surface_point(ctx: &Context, p: &[f64; 3]) -> Result<SurfacePoint> {
    let mesh = ctx.mesh;
    let p = Vector3::new(p[0], p[1], p[2]);
    let mut best: Option<(f64, usize, Vector3<f64>, [f64; 3])> = None;
    for f in 0..mesh.num_faces() {
        let [a, b, c] = mesh.face_positions(f);
        let (x, bary) = closest_point_on_triangle(&p, &a, &b, &c);
        let d2 = (x - p).norm_squared();
        if best.as_ref().is_none_or(|b| d2 < b.0) {
            best = Some((d2, f, x, bary));
        }
    }
    let Some((_, f, x, bary)) = best else {
        return Err(Error::setting("centre.point", "the mesh has no faces"));
    };
    let tri = mesh.faces[f].map(|v| v as usize);
    let mut normal = Vector3::zeros();
    for k in 0..3 {
        normal += ctx.normals[tri[k]] * bary[k];
    }
    let [a, b, c] = mesh.face_positions(f);
    let face_n = (b - a).cross(&(c - a));
    let normal = if normal.norm() > 1e-9 {
        normal.normalize()
    } else if face_n.norm() > 0.0 {
        face_n.normalize()
    } else {
        ctx.normals[tri[0]]
    };
    let seeds: Vec<(usize, f64)> =
        tri.iter().map(|&v| (v, (mesh.positions[v] - x).norm())).collect();
    let nearest_vertex =
        seeds.iter().min_by(|a, b| a.1.total_cmp(&b.1).then(a.0.cmp(&b.0))).map_or(tri[0], |s| s.0);
    Ok(SurfacePoint { position: x, normal, seeds, nearest_vertex })
}

/// The closest point of triangle abc to p, with its barycentric coordinates (Ericson,
/// "Real-Time Collision Detection", §5.1.5).
pub fn closest_point_on_triangle(
    p: &Vector3<f64>,
    a: &Vector3<f64>,
    b: &Vector3<f64>,
    c: &Vector3<f64>,
) -> (Vector3<f64>, [f64; 3]) {
    let (ab, ac, ap) = (b - a, c - a, p - a);
    let (d1, d2) = (ab.dot(&ap), ac.dot(&ap));
    if d1 <= 0.0 && d2 <= 0.0 {
        return (*a, [1.0, 0.0, 0.0]);
    }
    let bp = p - b;
    let (d3, d4) = (ab.dot(&bp), ac.dot(&bp));
    if d3 >= 0.0 && d4 <= d3 {
        return (*b, [0.0, 1.0, 0.0]);
    }
    let vc = d1 * d4 - d3 * d2;
    if vc <= 0.0 && d1 >= 0.0 && d3 <= 0.0 {
        let v = d1 / (d1 - d3);
        return (a + ab * v, [1.0 - v, v, 0.0]);
    }
    let cp = p - c;
    let (d5, d6) = (ab.dot(&cp), ac.dot(&cp));
    if d6 >= 0.0 && d5 <= d6 {
        return (*c, [0.0, 0.0, 1.0]);
    }
    let vb = d5 * d2 - d1 * d6;
    if vb <= 0.0 && d2 >= 0.0 && d6 <= 0.0 {
        let w = d2 / (d2 - d6);
        return (a + ac * w, [1.0 - w, 0.0, w]);
    }
    let va = d3 * d6 - d5 * d4;
    if va <= 0.0 && (d4 - d3) >= 0.0 && (d5 - d6) >= 0.0 {
        let w = (d4 - d3) / ((d4 - d3) + (d5 - d6));
        return (b + (c - b) * w, [0.0, 1.0 - w, w]);
    }
    let denom = va + vb + vc;
    if !(denom.abs() > 0.0) {
        // Degenerate (zero-area) triangle: the nearest corner.
        let d = [(p - a).norm(), (p - b).norm(), (p - c).norm()];
        let k = (0..3).min_by(|&i, &j| d[i].total_cmp(&d[j])).unwrap_or(0);
        let mut bary = [0.0; 3];
        bary[k] = 1.0;
        return ([*a, *b, *c][k], bary);
    }
    let (v, w) = (vb / denom, vc / denom);
    (a + ab * v + ac * w, [1.0 - v - w, v, w])
}

/// The arc length between two surface points estimated from the chord and the normals:
/// c·(α/2)/sin(α/2), exact for a circular arc whose normals turn by α.
fn arc_length(pa: &Vector3<f64>, pb: &Vector3<f64>, na: &Vector3<f64>, nb: &Vector3<f64>) -> f64 {
    let chord = (pb - pa).norm();
    let alpha = na.cross(nb).norm().atan2(na.dot(nb));
    let half = 0.5 * alpha;
    if half < 1e-4 {
        chord * (1.0 + half * half / 6.0)
    } else {
        chord * half / half.sin()
    }
}

/// Normals within 60° of each other: the straight-line shortcut is allowed.
const SHORTCUT_COS: f64 = 0.5;

#[derive(PartialEq)]
struct Item(f64, u32);
impl Eq for Item {}
impl PartialOrd for Item {
    fn partial_cmp(&self, other: &Self) -> Option<Ordering> {
        Some(self.cmp(other))
    }
}
impl Ord for Item {
    fn cmp(&self, other: &Self) -> Ordering {
        // A min-heap on distance, ties by vertex index.
        other.0.total_cmp(&self.0).then(other.1.cmp(&self.1))
    }
}

/// Vertices within `radius` of the centre with their distance, sorted by vertex index.
pub(crate) fn distances(
    ctx: &Context,
    src: &SurfacePoint,
    radius: f64,
    metric: Metric,
) -> Vec<(usize, f64)> {
    let pos = &ctx.mesh.positions;
    if metric == Metric::Euclidean {
        return pos
            .iter()
            .enumerate()
            .map(|(i, p)| (i, (p - src.position).norm()))
            .filter(|&(_, d)| d <= radius)
            .collect();
    }
    const SOURCE: u32 = u32::MAX;
    let n = pos.len();
    let mut dist = vec![f64::INFINITY; n];
    let mut anchor = vec![SOURCE; n];
    let mut done = vec![false; n];
    let mut heap = BinaryHeap::new();
    for &(v, d) in &src.seeds {
        if d < dist[v] {
            dist[v] = d;
            heap.push(Item(d, v as u32));
        }
    }
    let mut out = Vec::new();
    while let Some(Item(d, u)) = heap.pop() {
        let u = u as usize;
        if done[u] || d > dist[u] {
            continue;
        }
        if d > radius {
            break;
        }
        done[u] = true;
        out.push((u, d));
        let (pa, na, da) = match anchor[u] {
            SOURCE => (src.position, src.normal, 0.0),
            a => (pos[a as usize], ctx.normals[a as usize], dist[a as usize]),
        };
        for &v in ctx.geom.adjacency.neighbors(u) {
            let v = v as usize;
            if done[v] {
                continue;
            }
            let nv = ctx.normals[v];
            let mut best = dist[u] + arc_length(&pos[u], &pos[v], &ctx.normals[u], &nv);
            let mut best_anchor = u as u32;
            if na.dot(&nv) >= SHORTCUT_COS {
                let c = da + arc_length(&pa, &pos[v], &na, &nv);
                if c <= best {
                    best = c;
                    best_anchor = anchor[u];
                }
            }
            if best < dist[v] {
                dist[v] = best;
                anchor[v] = best_anchor;
                heap.push(Item(best, v as u32));
            }
        }
    }
    out.sort_unstable_by_key(|x| x.0);
    out
}

/// A brush support with its plane parametrization.
#[derive(Clone, Debug)]
pub struct Support {
    /// Support vertices, ascending.
    pub vertices: Vec<usize>,
    /// Distance of each support vertex to the centre.
    pub distance: Vec<f64>,
    /// Chart coordinates of each support vertex (units of r; about the geodesic distance from
    /// the centre, so inside the unit disk up to the chart's error).
    pub xy: Vec<Vector2<f64>>,
    /// The brush radius r.
    pub radius: f64,
    /// The centre on the surface.
    pub centre: SurfacePoint,
    /// Origin of the plane and the chart (the centre point).
    pub origin: Vector3<f64>,
    /// Plane x axis.
    pub ex: Vector3<f64>,
    /// Plane y axis (the brush's +y direction).
    pub ey: Vector3<f64>,
    /// Plane normal, ex × ey.
    pub normal: Vector3<f64>,
    /// The geodesic polar chart of the support and the faces around it ([`super::chart`]);
    /// [`Support::xy`] are its coordinates.
    pub chart: Chart,
}

/// The paper's fall-off w(x, y) = (1 − x² − y²)², 0 outside the unit disk.
#[inline]
pub fn falloff(p: &Vector2<f64>) -> f64 {
    let s = 1.0 - p.norm_squared();
    if s > 0.0 {
        s * s
    } else {
        0.0
    }
}

impl Support {
    /// Gathers the support of a brush, fits its plane and sets its axes.
    ///
    /// `direction`: a world vector whose projection onto the plane is the +y axis. Without one,
    /// the x axis follows the dominant direction of `ell` over the support (weighted by the
    /// fall-off; a tensor average, so signs do not matter) and y = n × x, so that a warp moves
    /// the highlights across themselves. Errors with key `radius` if no vertex is inside.
    pub(crate) fn new(
        ctx: &Context,
        centre: &Centre,
        radius: f64,
        metric: Metric,
        direction: Option<&[f64; 3]>,
        ell: &[Vector3<f64>],
    ) -> Result<Self> {
        let src = resolve_centre(ctx, centre)?;
        let found = distances(ctx, &src, radius, metric);
        if found.is_empty() {
            return Err(Error::setting(
                "radius",
                format!(
                    "the support holds no vertex: no vertex is within {} of the centre \
                     ({} distance); increase the radius or move the centre",
                    crate::error::fmt_num(radius),
                    match metric {
                        Metric::Geodesic => "geodesic",
                        Metric::Euclidean => "euclidean",
                    }
                ),
            ));
        }
        let (vertices, distance): (Vec<usize>, Vec<f64>) = found.into_iter().unzip();
        let normal = fit_normal(ctx, &vertices, &distance, radius, &src);
        let origin = src.position;
        let to_plane = |w: &Vector3<f64>| w - normal * normal.dot(w);
        let ey = direction
            .map(|d| to_plane(&Vector3::new(d[0], d[1], d[2])))
            .filter(|d| d.norm() > 1e-9)
            .map(|d| d.normalize());
        let (ex, ey) = match ey {
            Some(ey) => (ey.cross(&normal), ey),
            None => {
                let frame = Frame::from_normal(normal);
                let mut acc = Vector2::zeros();
                for (&v, &d) in vertices.iter().zip(&distance) {
                    let l = frame.to_local(&ell[v]);
                    let w = falloff(&Vector2::new(d / radius, 0.0));
                    acc += Vector2::new(l.x * l.x - l.y * l.y, 2.0 * l.x * l.y) * w;
                }
                let ex = if acc.norm() > 0.0 {
                    frame.direction(0.5 * acc.y.atan2(acc.x))
                } else {
                    frame.t
                };
                (ex, normal.cross(&ex))
            }
        };
        let chart = brush_chart(ctx, &src, radius, (origin, ex, ey, normal), &vertices, &distance);
        // Every support vertex is in the chart (it is placed from an earlier neighbour or the
        // centre); the fallback to the plane only guards against a non-finite estimate.
        let xy = vertices
            .iter()
            .map(|&v| {
                chart.coords(v).unwrap_or_else(|| {
                    let w = ctx.mesh.positions[v] - origin;
                    Vector2::new(ex.dot(&w), ey.dot(&w)) / radius
                })
            })
            .collect();
        Ok(Support { vertices, distance, xy, radius, centre: src, origin, ex, ey, normal, chart })
    }

    /// Chart components of the tangent vector `w` at vertex `v` ([`Chart::vector_to_chart`]).
    pub(crate) fn vector_to_chart(
        &self,
        ctx: &Context,
        v: usize,
        w: &Vector3<f64>,
    ) -> Vector2<f64> {
        self.chart.vector_to_chart(v, &ctx.geom.frames[v], w)
    }

    /// The tangent vector at vertex `v` whose chart components are `c`.
    pub(crate) fn vector_from_chart(
        &self,
        ctx: &Context,
        v: usize,
        c: &Vector2<f64>,
    ) -> Vector3<f64> {
        self.chart.vector_from_chart(v, &ctx.geom.frames[v], c)
    }
}

/// The chart of a support ([`super::chart`]): its vertices nearest first, then the other
/// corners of the faces that touch it (the point location's triangles need every corner).
fn brush_chart(
    ctx: &Context,
    src: &SurfacePoint,
    radius: f64,
    (origin, ex, ey, normal): (Vector3<f64>, Vector3<f64>, Vector3<f64>, Vector3<f64>),
    vertices: &[usize],
    distance: &[f64],
) -> Chart {
    let mut order: Vec<(f64, usize)> =
        vertices.iter().zip(distance).map(|(&v, &d)| (d, v)).collect();
    order.sort_unstable_by(|a, b| a.0.total_cmp(&b.0).then(a.1.cmp(&b.1)));
    let mut ring: Vec<(f64, usize)> = vertices
        .iter()
        .flat_map(|&v| ctx.vf.of(v).iter().map(|&(f, _)| f as usize))
        .flat_map(|f| ctx.mesh.faces[f].map(|c| c as usize))
        .filter(|c| vertices.binary_search(c).is_err())
        .map(|c| ((ctx.mesh.positions[c] - origin).norm(), c))
        .collect();
    ring.sort_unstable_by(|a, b| a.0.total_cmp(&b.0).then(a.1.cmp(&b.1)));
    ring.dedup_by_key(|x| x.1);
    let order: Vec<usize> = order.iter().chain(&ring).map(|x| x.1).collect();
    let base = Base { origin, ex, ey, normal, seeds: &src.seeds, radius };
    let neighbours =
        |v: usize| ctx.geom.adjacency.neighbors(v).iter().map(|&u| u as usize).collect();
    Chart::new(&ctx.mesh.positions, &ctx.geom.frames, neighbours, &base, &order)
}

/// The plane normal of a weighted PCA of the support, oriented like the vertex normals.
fn fit_normal(
    ctx: &Context,
    vertices: &[usize],
    distance: &[f64],
    radius: f64,
    src: &SurfacePoint,
) -> Vector3<f64> {
    let pos = &ctx.mesh.positions;
    let weights: Vec<f64> = vertices
        .iter()
        .zip(distance)
        .map(|(&v, &d)| ctx.geom.areas[v].max(0.0) * (1.0 - (d / radius).powi(2)).max(0.0))
        .collect();
    let total: f64 = weights.iter().sum();
    let weights: Vec<f64> = if total > 0.0 && total.is_finite() {
        weights.iter().map(|w| w / total).collect()
    } else {
        vec![1.0 / vertices.len() as f64; vertices.len()]
    };
    let mut mean_n = Vector3::zeros();
    let mut centroid = Vector3::zeros();
    for (&v, &w) in vertices.iter().zip(&weights) {
        mean_n += ctx.normals[v] * w;
        centroid += pos[v] * w;
    }
    let reference = if mean_n.norm() > 1e-6 { mean_n.normalize() } else { src.normal };
    if vertices.len() < 3 {
        return reference;
    }
    let mut cov = Matrix3::zeros();
    for (&v, &w) in vertices.iter().zip(&weights) {
        let d = pos[v] - centroid;
        cov += d * d.transpose() * w;
    }
    let eig = nalgebra::SymmetricEigen::new(cov);
    let mut order = [0usize, 1, 2];
    order.sort_by(|&a, &b| eig.eigenvalues[a].total_cmp(&eig.eigenvalues[b]));
    let (l0, l1) = (eig.eigenvalues[order[0]], eig.eigenvalues[order[1]]);
    if !(l1 > 0.0 && l0 <= 0.5 * l1) {
        return reference;
    }
    let n: Vector3<f64> = eig.eigenvectors.column(order[0]).into();
    let n = if n.dot(&reference) < 0.0 { -n } else { n };
    if n.norm() > 0.5 && n.iter().all(|c| c.is_finite()) {
        n.normalize()
    } else {
        reference
    }
}

/// Point location among the projected triangles of a support, to interpolate vertex values at
/// planar points (the warps' ℓ_q).
///
/// The triangles are the faces with a corner in the support, projected to the brush plane. ℓ_q
/// is the barycentric interpolation of the corner values in the triangle that contains q (the
/// one nearest the query's vertex in space when the projection overlaps itself), or — for q
/// outside every triangle, beyond a boundary — at the closest point of the closest triangle.
pub(crate) struct PlaneLocator {
    tris: Vec<(usize, [Vector2<f64>; 3])>,
    lo: Vector2<f64>,
    cell: f64,
    dim: usize,
    cells: Vec<Vec<u32>>,
}

impl PlaneLocator {
    pub fn new(ctx: &Context, support: &Support) -> Self {
        let mut faces: Vec<usize> = support
            .vertices
            .iter()
            .flat_map(|&v| ctx.vf.of(v).iter().map(|&(f, _)| f as usize))
            .collect();
        faces.sort_unstable();
        faces.dedup();
        let tris: Vec<(usize, [Vector2<f64>; 3])> = faces
            .iter()
            .filter_map(|&f| {
                let [a, b, c] = ctx.mesh.faces[f].map(|v| support.chart.coords(v as usize));
                Some((f, [a?, b?, c?]))
            })
            .collect();
        let mut lo = Vector2::repeat(f64::INFINITY);
        let mut hi = Vector2::repeat(f64::NEG_INFINITY);
        for (_, t) in &tris {
            for p in t {
                lo = lo.inf(p);
                hi = hi.sup(p);
            }
        }
        let dim = ((tris.len() as f64).sqrt().ceil() as usize).clamp(1, 512);
        let extent = (hi - lo).max().max(1e-12);
        let cell = extent / dim as f64;
        let mut cells = vec![Vec::new(); dim * dim];
        for (k, (_, t)) in tris.iter().enumerate() {
            let (a, b) = (t[0].inf(&t[1]).inf(&t[2]), t[0].sup(&t[1]).sup(&t[2]));
            let (i0, j0) = cell_of(&a, &lo, cell, dim);
            let (i1, j1) = cell_of(&b, &lo, cell, dim);
            for j in j0..=j1 {
                for i in i0..=i1 {
                    cells[j * dim + i].push(k as u32);
                }
            }
        }
        PlaneLocator { tris, lo, cell, dim, cells }
    }

    /// The face and barycentric coordinates of planar point `q`; `near` is a world point that
    /// breaks ties between overlapping triangles.
    pub fn locate(
        &self,
        ctx: &Context,
        q: &Vector2<f64>,
        near: &Vector3<f64>,
    ) -> (usize, [f64; 3]) {
        self.locate_or_nearest(ctx, q, near).0
    }

    /// [`PlaneLocator::locate`], and whether `q` lies in a triangle (false: beyond a boundary,
    /// the closest point of the closest triangle was used).
    pub fn locate_or_nearest(
        &self,
        ctx: &Context,
        q: &Vector2<f64>,
        near: &Vector3<f64>,
    ) -> ((usize, [f64; 3]), bool) {
        let (ci, cj) = cell_of(q, &self.lo, self.cell, self.dim);
        let mut best: Option<(f64, usize, [f64; 3])> = None;
        for j in cj.saturating_sub(1)..=(cj + 1).min(self.dim - 1) {
            for i in ci.saturating_sub(1)..=(ci + 1).min(self.dim - 1) {
                for &k in &self.cells[j * self.dim + i] {
                    let (f, t) = &self.tris[k as usize];
                    let Some(b) = barycentric(q, t) else { continue };
                    if b.iter().all(|&x| x >= -1e-9) {
                        let [p0, p1, p2] = ctx.mesh.face_positions(*f);
                        let d = ((p0 + p1 + p2) / 3.0 - near).norm_squared();
                        if best.as_ref().is_none_or(|x| (d, *f) < (x.0, x.1)) {
                            best = Some((d, *f, b));
                        }
                    }
                }
            }
        }
        if let Some((_, f, b)) = best {
            return ((f, b), true);
        }
        // Outside every triangle (beyond a boundary): the closest point of the closest one.
        let q3 = Vector3::new(q.x, q.y, 0.0);
        let mut best: Option<(f64, usize, [f64; 3])> = None;
        for (f, t) in &self.tris {
            let [a, b, c] = t.map(|p| Vector3::new(p.x, p.y, 0.0));
            let (x, bary) = closest_point_on_triangle(&q3, &a, &b, &c);
            let d = (x - q3).norm_squared();
            if best.as_ref().is_none_or(|x| (d, *f) < (x.0, x.1)) {
                best = Some((d, *f, bary));
            }
        }
        (best.map_or((0, [1.0, 0.0, 0.0]), |(_, f, b)| (f, b)), false)
    }

    /// Interpolates the vertex vectors `values` at `q`, in chart components (each corner's
    /// vector taken into the chart through its own frame, [`Support::vector_to_chart`]). For
    /// line fields (`align`), the corner values are first given the sign of the longest one
    /// (ℓ of a line field has no sign).
    pub fn interpolate(
        &self,
        ctx: &Context,
        support: &Support,
        q: &Vector2<f64>,
        near: &Vector3<f64>,
        values: &[Vector3<f64>],
        align: bool,
    ) -> Vector2<f64> {
        let (f, b) = self.locate(ctx, q, near);
        let corners = ctx.mesh.faces[f]
            .map(|v| support.vector_to_chart(ctx, v as usize, &values[v as usize]));
        let reference = *corners
            .iter()
            .max_by(|a, b| a.norm_squared().total_cmp(&b.norm_squared()))
            .unwrap_or(&corners[0]);
        let mut out = Vector2::zeros();
        for k in 0..3 {
            let c =
                if align && corners[k].dot(&reference) < 0.0 { -corners[k] } else { corners[k] };
            out += c * b[k];
        }
        out
    }
}

impl PlaneLocator {
    /// Interpolates the vertex scalars `values` at `q` (barycentric in the located triangle);
    /// each corner value is multiplied by `sign(corner)` first (±1: line fields state ĝ in one
    /// orientation of the grain). The flag is false where `q` lies beyond the part's boundary.
    pub fn interpolate_scalar(
        &self,
        ctx: &Context,
        q: &Vector2<f64>,
        near: &Vector3<f64>,
        values: &[f64],
        sign: impl Fn(usize) -> f64,
    ) -> (f64, bool) {
        let ((f, b), inside) = self.locate_or_nearest(ctx, q, near);
        let corners = ctx.mesh.faces[f];
        let v =
            (0..3).map(|k| values[corners[k] as usize] * sign(corners[k] as usize) * b[k]).sum();
        (v, inside)
    }
}

fn cell_of(p: &Vector2<f64>, lo: &Vector2<f64>, cell: f64, dim: usize) -> (usize, usize) {
    let f = |x: f64| {
        let c = (x / cell).floor();
        if c.is_finite() && c > 0.0 {
            (c as usize).min(dim - 1)
        } else {
            0
        }
    };
    (f(p.x - lo.x), f(p.y - lo.y))
}

/// Barycentric coordinates of q in triangle t (None for a degenerate triangle).
pub(crate) fn barycentric(q: &Vector2<f64>, t: &[Vector2<f64>; 3]) -> Option<[f64; 3]> {
    let (e1, e2, d) = (t[1] - t[0], t[2] - t[0], q - t[0]);
    let det = e1.x * e2.y - e1.y * e2.x;
    let scale = e1.norm_squared() + e2.norm_squared();
    if !(det.abs() > 1e-14 * scale) {
        return None;
    }
    let v = (d.x * e2.y - d.y * e2.x) / det;
    let w = (e1.x * d.y - e1.y * d.x) / det;
    Some([1.0 - v - w, v, w])
}
