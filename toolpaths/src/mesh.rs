//! The validated form [`Domain`] of the input ([`FieldMesh`], in `input.rs`), with
//! adjacency, per-triangle metric and the point-location grid.

use std::collections::BTreeMap;
use std::sync::OnceLock;

use serde::{Deserialize, Serialize};

use crate::error::{Result, ToolpathError};
use crate::geom::{barycentric, cross, segment_distance, sub, Metric, Vec2, Vec3};
use crate::grid::FaceGrid;
use crate::input::SurfaceHook;
pub use crate::input::{Directions, FaceId, FieldMesh, SeamPair, Symmetry, VertexId};
use crate::topology::{build_adjacency, build_metric, build_seams};
pub(crate) use crate::topology::{SeamLink, NONE};

/// Connected components of the face adjacency, numbered by lowest face, and their UV boxes.
fn build_charts(uv: &[Vec2], tris: &[[u32; 3]], nb: &[[u32; 3]]) -> (Vec<u32>, Vec<[Vec2; 2]>) {
    let mut chart = vec![NONE; tris.len()];
    let mut boxes = Vec::new();
    let mut stack = Vec::new();
    for f0 in 0..tris.len() {
        if chart[f0] != NONE {
            continue;
        }
        let c = boxes.len() as u32;
        let mut bb = [[f64::INFINITY; 2], [f64::NEG_INFINITY; 2]];
        chart[f0] = c;
        stack.push(f0 as u32);
        while let Some(f) = stack.pop() {
            for &v in &tris[f as usize] {
                let p = uv[v as usize];
                for k in 0..2 {
                    bb[0][k] = bb[0][k].min(p[k]);
                    bb[1][k] = bb[1][k].max(p[k]);
                }
            }
            for &g in &nb[f as usize] {
                if g != NONE && chart[g as usize] == NONE {
                    chart[g as usize] = c;
                    stack.push(g);
                }
            }
        }
        boxes.push(bb);
    }
    (chart, boxes)
}

/// Unit vertex normals: the given ones, else the sum of the incident faces' area vectors.
fn vertex_normals(p: &[Vec3], tris: &[[u32; 3]], given: Option<&[Vec3]>) -> Vec<Vec3> {
    use crate::geom::{cross3, norm3, sub3};
    let mut n = match given {
        Some(g) => g.to_vec(),
        None => {
            let mut n = vec![[0.0; 3]; p.len()];
            for t in tris {
                let [a, b, c] = t.map(|v| p[v as usize]);
                let w = cross3(sub3(b, a), sub3(c, a));
                for &v in t {
                    for k in 0..3 {
                        n[v as usize][k] += w[k];
                    }
                }
            }
            n
        }
    };
    for x in &mut n {
        let l = norm3(*x);
        *x = if l > 0.0 && l.is_finite() { x.map(|c| c / l) } else { [0.0; 3] };
    }
    n
}

/// A singular point of the field.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
pub struct Singularity {
    /// UV position (where the blended field vanishes, else the triangle centroid).
    pub uv: Vec2,
    /// Face that holds it.
    pub face: u32,
    /// Poincaré index: +1 vortex/source, −1 saddle, ±½ for line fields (−½ trisector).
    pub index: f64,
}

/// A validated [`FieldMesh`] with triangle adjacency, metrics and a point-location grid.
#[derive(Debug)]
pub struct Domain {
    pub(crate) uv: Vec<Vec2>,
    pub(crate) tris: Vec<[u32; 3]>,
    pub(crate) dirs: Vec<Vec2>,
    pub(crate) symmetry: Symmetry,
    pub(crate) positions: Option<Vec<Vec3>>,
    pub(crate) normals: Option<Vec<Vec3>>,
    pub(crate) metric: Vec<Metric>,
    /// `sqrt(λ_min)` of each face's metric: the least surface length per UV unit.
    pub(crate) min_stretch: Vec<f64>,
    /// Neighbour across the edge opposite corner i, or [`NONE`].
    pub(crate) neighbors: Vec<[u32; 3]>,
    /// Seam continuation of boundary edges, keyed by (face, local edge).
    pub(crate) seams: BTreeMap<(u32, u8), SeamLink>,
    pub(crate) grid: FaceGrid,
    pub(crate) bbox: [Vec2; 2],
    /// Chart (connected component of the UV adjacency, seams not followed) of each face.
    /// Charts are numbered in order of their lowest face.
    pub(crate) chart: Vec<u32>,
    /// UV bounding box of each chart.
    pub(crate) chart_bbox: Vec<[Vec2; 2]>,
    /// Unit vertex normals used by the 3D spacing measure (the given normals, else area-
    /// weighted face normals); present with the lift.
    pub(crate) spacing_normals: Option<Vec<Vec3>>,
    /// Singularities, found on first use (`field.rs`).
    pub(crate) sing: OnceLock<Vec<Singularity>>,
    /// The surface each triangle approximates, when known (`surface.rs`).
    pub(crate) surface: Option<SurfaceHook>,
    /// Per face on a known surface, its corners' grain extended off it (`surface.rs`); empty
    /// without a surface.
    pub(crate) ambient: Vec<Option<[Vec3; 3]>>,
}

fn check_finite2(what: &'static str, v: &[Vec2]) -> Result<()> {
    match v.iter().position(|p| !(p[0].is_finite() && p[1].is_finite())) {
        Some(index) => Err(ToolpathError::NonFinite { what, index }),
        None => Ok(()),
    }
}

fn check_finite3(what: &'static str, v: &[Vec3]) -> Result<()> {
    match v.iter().position(|p| !p.iter().all(|x| x.is_finite())) {
        Some(index) => Err(ToolpathError::NonFinite { what, index }),
        None => Ok(()),
    }
}

/// The corners' ambient grain ([`FieldMesh::ambient`]): one entry per triangle, finite.
fn check_ambient(a: Option<Vec<Option<[Vec3; 3]>>>, nf: usize) -> Result<Vec<Option<[Vec3; 3]>>> {
    let Some(a) = a else { return Ok(Vec::new()) };
    if a.len() != nf {
        return Err(ToolpathError::InvalidMesh(format!(
            "{} ambient triangles for {nf} triangles",
            a.len()
        )));
    }
    match a.iter().position(|c| c.is_some_and(|c| !c.iter().flatten().all(|x| x.is_finite()))) {
        Some(index) => Err(ToolpathError::NonFinite { what: "ambient", index }),
        None => Ok(a),
    }
}

impl Domain {
    /// Validate `mesh` and build adjacency, metrics and the location grid.
    ///
    /// Errors on: out-of-range indices, non-finite numbers, array lengths that do not match,
    /// degenerate UV triangles, non-manifold edges, invalid metrics or seams.
    pub fn new(mesh: FieldMesh) -> Result<Domain> {
        let nv = mesh.uv.len();
        let nf = mesh.triangles.len();
        if nf == 0 {
            return Err(ToolpathError::InvalidMesh("no triangles".into()));
        }
        if nf >= NONE as usize || nv >= NONE as usize {
            return Err(ToolpathError::InvalidMesh("too many elements".into()));
        }
        check_finite2("uv", &mesh.uv)?;
        for (f, t) in mesh.triangles.iter().enumerate() {
            if t.iter().any(|&v| v as usize >= nv) {
                return Err(ToolpathError::InvalidMesh(format!(
                    "triangle {f} references a vertex beyond {nv}"
                )));
            }
        }
        let dirs = match mesh.directions {
            Directions::Vectors(v) => {
                check_finite2("directions", &v)?;
                v
            }
            Directions::Angles(a) => {
                if let Some(index) = a.iter().position(|x| !x.is_finite()) {
                    return Err(ToolpathError::NonFinite { what: "directions", index });
                }
                a.iter().map(|t| [t.cos(), t.sin()]).collect()
            }
        };
        if dirs.len() != nv {
            return Err(ToolpathError::InvalidMesh(format!(
                "{} directions for {nv} vertices",
                dirs.len()
            )));
        }
        for (what, arr) in [("positions", &mesh.positions), ("normals", &mesh.normals)] {
            if let Some(a) = arr {
                if a.len() != nv {
                    return Err(ToolpathError::InvalidMesh(format!(
                        "{} {what} for {nv} vertices",
                        a.len()
                    )));
                }
                check_finite3(what, a)?;
            }
        }
        let mesh_has_lift = mesh.positions.is_some();
        let uv = mesh.uv;
        let tris = mesh.triangles;
        let mut bbox = [[f64::INFINITY; 2], [f64::NEG_INFINITY; 2]];
        for p in &uv {
            for k in 0..2 {
                bbox[0][k] = bbox[0][k].min(p[k]);
                bbox[1][k] = bbox[1][k].max(p[k]);
            }
        }
        let diag = ((bbox[1][0] - bbox[0][0]).powi(2) + (bbox[1][1] - bbox[0][1]).powi(2)).sqrt();
        for (face, t) in tris.iter().enumerate() {
            let [a, b, c] = t.map(|v| uv[v as usize]);
            let area = 0.5 * cross(sub(b, a), sub(c, a));
            if area.is_nan() || area.abs() <= 1e-14 * diag * diag {
                return Err(ToolpathError::DegenerateTriangle { face, area });
            }
        }
        let metric = build_metric(&uv, &tris, mesh.metric, mesh.positions.as_deref())?;
        let min_stretch = metric.iter().map(|m| m.eigen_range().0.sqrt()).collect();
        let neighbors = build_adjacency(&tris)?;
        let seams = build_seams(&uv, &tris, &neighbors, &mesh.seams)?;
        let grid = FaceGrid::new(&uv, &tris, bbox);
        let (chart, chart_bbox) = build_charts(&uv, &tris, &neighbors);
        let spacing_normals =
            mesh.positions.as_ref().map(|p| vertex_normals(p, &tris, mesh.normals.as_deref()));
        let ambient = check_ambient(mesh.ambient, nf)?;
        let dom = Domain {
            uv,
            tris,
            dirs,
            symmetry: mesh.symmetry,
            positions: mesh.positions,
            normals: mesh.normals,
            metric,
            min_stretch,
            neighbors,
            seams,
            grid,
            bbox,
            chart,
            chart_bbox,
            spacing_normals,
            sing: OnceLock::new(),
            surface: mesh.surface.filter(|_| mesh_has_lift),
            ambient,
        };
        Ok(dom)
    }

    /// Number of charts (connected pieces of the UV layout; seams do not join them).
    pub fn chart_count(&self) -> usize {
        self.chart_bbox.len()
    }

    /// The chart of face `f` (charts are numbered in order of their lowest face).
    pub fn chart_of(&self, f: FaceId) -> usize {
        self.chart[f.0 as usize] as usize
    }

    /// Pairs of charts `(a, b)`, `a < b`, whose UV triangles overlap (share interior
    /// points): such charts are separate sheets. Ascending order.
    pub fn overlapping_charts(&self) -> Vec<(usize, usize)> {
        overlapping_charts(self)
    }

    /// Number of triangles.
    pub fn face_count(&self) -> usize {
        self.tris.len()
    }

    /// Axis-aligned UV bounding box `[min, max]`.
    pub fn bbox(&self) -> [Vec2; 2] {
        self.bbox
    }

    /// The field's symmetry.
    pub fn symmetry(&self) -> Symmetry {
        self.symmetry
    }

    /// Whether a 3D lift (positions) is available.
    pub fn has_lift(&self) -> bool {
        self.positions.is_some()
    }

    /// The metric of face `f`.
    pub fn metric(&self, f: FaceId) -> Metric {
        self.metric[f.0 as usize]
    }

    /// Surface area of the whole domain (mm²): `Σ area_uv · √(EG − F²)`.
    pub fn surface_area(&self) -> f64 {
        (0..self.tris.len()).map(|f| self.uv_area(f as u32) * self.metric[f].area_factor()).sum()
    }

    pub(crate) fn uv_area(&self, f: u32) -> f64 {
        let [a, b, c] = self.corners(f);
        0.5 * cross(sub(b, a), sub(c, a)).abs()
    }

    #[inline]
    pub(crate) fn corners(&self, f: u32) -> [Vec2; 3] {
        let t = self.tris[f as usize];
        [self.uv[t[0] as usize], self.uv[t[1] as usize], self.uv[t[2] as usize]]
    }

    /// Boundary edges (no neighbour, seams included) as UV segments, in face order.
    pub fn boundary_edges(&self) -> Vec<[Vec2; 2]> {
        let mut out = Vec::new();
        for (f, nb) in self.neighbors.iter().enumerate() {
            let c = self.corners(f as u32);
            for i in 0..3 {
                if nb[i] == NONE {
                    out.push([c[(i + 1) % 3], c[(i + 2) % 3]]);
                }
            }
        }
        out
    }

    /// Whether `p`, a stroke end on a boundary edge of face `f`, is on the part's real edge
    /// (the metal ends there) rather than on a UV seam (the surface goes on across it): the
    /// boundary edge of `f` nearest to `p` is not listed in the seams. `false` when `f` has no
    /// boundary edge.
    pub(crate) fn on_part_edge(&self, f: u32, p: Vec2) -> bool {
        let c = self.corners(f);
        let nb = self.neighbors[f as usize];
        let dist = |i: usize| segment_distance(p, c[(i + 1) % 3], c[(i + 2) % 3]);
        let edge = (0..3).filter(|&i| nb[i] == NONE).min_by(|&i, &j| dist(i).total_cmp(&dist(j)));
        edge.is_some_and(|i| !self.seams.contains_key(&(f, i as u8)))
    }

    /// 3D position of a UV point given its face and barycentric coordinates: on the face's
    /// chord, or on the surface it approximates when known (`surface.rs`).
    pub(crate) fn lift(&self, f: u32, bary: [f64; 3]) -> Option<Vec3> {
        let x = self.chord_lift(f, bary)?;
        Some(self.surface.as_ref().and_then(|s| s.project(f, x)).map_or(x, |(q, _)| q))
    }

    pub(crate) fn chord_lift(&self, f: u32, bary: [f64; 3]) -> Option<Vec3> {
        let p = self.positions.as_ref()?;
        let t = self.tris[f as usize];
        Some([0, 1, 2].map(|k| (0..3).map(|i| bary[i] * p[t[i] as usize][k]).sum()))
    }

    /// Unit normal at a UV point: the surface's when known (`surface.rs`), oriented as the
    /// interpolated vertex normals (else the face normal), which it is otherwise.
    pub(crate) fn normal(&self, f: u32, bary: [f64; 3]) -> Option<Vec3> {
        let n = self.chord_normal(f, bary)?;
        let on = self.surface.as_ref().and_then(|s| s.project(f, self.chord_lift(f, bary)?));
        let Some((_, m)) = on else { return Some(n) };
        let l = crate::geom::norm3(m);
        let s = if crate::geom::dot3(m, n) < 0.0 { -1.0 } else { 1.0 };
        Some(if l > 0.0 { m.map(|x| s * x / l) } else { n })
    }

    fn chord_normal(&self, f: u32, bary: [f64; 3]) -> Option<Vec3> {
        let t = self.tris[f as usize];
        let n = if let Some(ns) = &self.normals {
            [0, 1, 2].map(|k| (0..3).map(|i| bary[i] * ns[t[i] as usize][k]).sum::<f64>())
        } else {
            let p = self.positions.as_ref()?;
            let [a, b, c] = t.map(|v| p[v as usize]);
            crate::geom::cross3(crate::geom::sub3(b, a), crate::geom::sub3(c, a))
        };
        let l = crate::geom::norm3(n);
        (l > 0.0).then(|| n.map(|x| x / l))
    }
}

/// Chart pairs whose UV triangles overlap: some face's centroid lies inside a face of
/// another chart (tested through the location grid's cell of the centroid).
fn overlapping_charts(dom: &Domain) -> Vec<(usize, usize)> {
    let mut pairs = std::collections::BTreeSet::new();
    if dom.chart_count() < 2 {
        return Vec::new();
    }
    for f in 0..dom.tris.len() as u32 {
        let c = dom.corners(f);
        let p = [(c[0][0] + c[1][0] + c[2][0]) / 3.0, (c[0][1] + c[1][1] + c[2][1]) / 3.0];
        let cf = dom.chart[f as usize];
        for &g in dom.grid.faces_near(p) {
            let cg = dom.chart[g as usize];
            if cg == cf || pairs.contains(&(cf.min(cg), cf.max(cg))) {
                continue;
            }
            // A centroid inside or on the closed triangle: the open triangle of `f` meets
            // the chart of `g` in interior points either way.
            let b = barycentric(dom.corners(g), p);
            if b.iter().all(|&x| x >= -1e-12) {
                pairs.insert((cf.min(cg), cf.max(cg)));
            }
        }
    }
    pairs.into_iter().map(|(a, b)| (a as usize, b as usize)).collect()
}
