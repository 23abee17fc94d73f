//! Where the edits need a finer mesh (docs/math.md §12), before any field exists.
//!
//! The grain lives on vertices and the highlight a designer sees is the zero set of its linear
//! interpolant per triangle, so a warp or a drawn curve that bends within one triangle cannot
//! be followed, whatever the solver does. Each bend and expand asks for edges no longer than
//! `edge` × its radius × the warp's largest compression ([`finest_scale`]: the target carries
//! the field's detail that much closer together) on the faces that reach into its ball; each
//! curve asks for
//! `edge` × 3/8 × min(radius, width) on the faces that reach into its tube (its designed grain
//! turns across half the tube: `CURVE_EDGE`). Stencils and the light tools set
//! directions, not positions, and ask for nothing.
//!
//! **The half vector's turn.** The grain a bend, an expand or a curve designs is an angle from
//! h̄, the tangent part of the key light's half vector: φ* = θ(h̄ᵢ) + ψ*, ψ* the grain's angle
//! from h̄ where the target comes from (docs/math.md §9). Where the part folds at the scale of
//! its triangles — a sculpt's skin folds, a scan's ridges — θ(h̄) turns by tens of degrees
//! along one edge, ψ* as much again, and a grain that turns by more than a right angle along an
//! edge is no longer a grain but a singular triangle. So inside a region every face along
//! which h̄ turns by more than `max_turn` (`mesh.refine.turn`, default 20°) asks for its
//! longest edge × max_turn / turn, and the faces a split makes are asked again with their own
//! normals (the ones the Phong points were placed with), down to [`MIN_TURN_SCALE`] × the
//! region's edge. A smooth part turns h̄ by a few degrees per edge and asks for nothing more.
//!
//! The regions are Euclidean balls and tubes: they contain the geodesic supports the tools
//! use later, so a face of a support is never left coarse.
//!
//! A region that holds none of the part's vertices falls between them: either the part's
//! triangles are larger than the brush (a CAD export whose flat and cylindrical faces are a
//! few long slivers, a developable strip) or the radius is a slip of units. The two are told
//! apart by the part's size: a region whose reach is at least [`MIN_REACH_SHARE`] of the
//! bounding-box diagonal asks for its edge on the faces it touches (their exact distance to
//! the region, not a bound), so the tool then finds vertices inside it; a smaller one asks for
//! nothing and its tool refuses it, naming the radius, as before.

use std::path::Path;

use nalgebra::Vector3;

use super::curve::read_svg_polylines;
use super::support::Centre;
use super::warp::{finest_scale, WarpKind};
use super::{at_edit, Edit};
use crate::geometry::cells::SegmentCells;
use crate::highlight::lighting::half_vector;
use crate::highlight::Lighting;
use crate::mesh::Mesh;
use crate::Result;

/// The smallest reach, as a share of the part's bounding-box diagonal, for which a region that
/// holds no vertex is refined (module docs): 1 mm on a 200 mm part.
pub const MIN_REACH_SHARE: f64 = 0.005;

/// The finest edge the half vector's turn may ask for, as a share of its region's edge (at most
/// three levels of splitting past the region's request: bounded work near a critical point,
/// where h̄ turns a half-turn at any size).
pub const MIN_TURN_SCALE: f64 = 0.125;

/// The default of `mesh.refine.turn`: the largest turn of h̄ along an edge inside a region,
/// degrees (module docs, "the half vector's turn").
pub const DEFAULT_MAX_TURN_DEG: f64 = 20.0;

/// |h̄| below which a corner counts as a critical point.
const MIN_TANGENT_H: f64 = 1e-6;

/// Most points a curve is sampled at when its tube holds no vertex (the work of marking the
/// faces is at most this many closest-point queries per face near the curve).
const MAX_SAMPLES: usize = 100_000;

/// A curve's edge relative to a brush's: the grain the curve tool designs turns back to the
/// field before the edit across the outer half of its tube (up to a half-turn for a line field,
/// more where the lift needs it), and a turn of more than a right angle along one edge is no
/// longer a grain but a singular triangle. With the default `edge` of 1/3 this gives r/8:
/// about four edges across the ring (docs/math.md §9, docs/benchmarks.md session 12).
const CURVE_EDGE: f64 = 3.0 / 8.0;

/// One region of an edit: a polyline (one point for a brush) and its reach, and the edge
/// length wanted inside it.
#[derive(Clone, Debug, PartialEq)]
struct Region {
    lines: Vec<Vec<Vector3<f64>>>,
    reach: f64,
    edge: f64,
}

impl Region {
    /// The area of the region's trace on a surface, at most: 2 × reach × its polylines'
    /// length + π reach² for each (a ball's πr² for a lone point).
    fn area(&self) -> f64 {
        let r = self.reach;
        let finite = |w: &[Vector3<f64>]| w.iter().all(|p| p.iter().all(|c| c.is_finite()));
        self.lines
            .iter()
            .map(|l| {
                let length: f64 =
                    l.windows(2).filter(|w| finite(w)).map(|w| (w[1] - w[0]).norm()).sum();
                2.0 * r * length + std::f64::consts::PI * r * r
            })
            .sum()
    }
}

/// A region with the edge it asks for, and its segments bucketed for distance queries.
#[derive(Clone, Debug)]
struct Marked {
    region: Region,
    want: f64,
    grid: SegmentGrid,
    /// The edit that asked (its index in the scene's `edits`).
    edit: usize,
    /// The area to be refined: the faces it reaches that are coarser than `want`, at most the
    /// region's own area ([`Region::area`]).
    area: f64,
}

/// What the edits ask of the refinement: the edge each face of the part needs, and the
/// regions that asked, so that the faces a split makes can be asked again
/// ([`Resolution::child_target`]), with the turn of the key highlight's half vector they allow
/// ([`Resolution::turn`]). Two requests are equal when their faces' edges, their regions and
/// their turns are: they refine the part the same way.
#[derive(Clone, Debug)]
pub struct Resolution {
    /// The edge length each face of the part needs (`f64::INFINITY` where none asks), from the
    /// regions alone: the turn's request needs the part's normals
    /// ([`Resolution::turned_faces`]).
    pub faces: Vec<f64>,
    marked: Vec<Marked>,
    /// How far the key highlight's half vector may turn along an edge inside a region
    /// (`None`: no limit).
    pub turn: Option<HalfVectorTurn>,
}

/// Inside the edits' regions, how far the tangent part h̄ of the key light's half vector may
/// turn along one edge (module docs, "the half vector's turn").
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct HalfVectorTurn {
    /// The key light and the view the edits see.
    pub lighting: Lighting,
    /// The largest turn along an edge, radians.
    pub max_turn: f64,
}

impl HalfVectorTurn {
    /// The largest turn of h̄ along the edges of a triangle with corners `p` and unit normals
    /// `n`: h̄ at one end transported to the other's tangent plane by the rotation that takes
    /// one normal to the other, and measured there (radians, in [0, π]). π where h̄ (nearly)
    /// vanishes at a corner (a critical point, h ∥ n: every direction is its direction).
    pub fn turn(&self, p: &[Vector3<f64>; 3], n: &[Vector3<f64>; 3]) -> f64 {
        let l = &self.lighting;
        let hb = |k: usize| {
            let h = half_vector(&l.omega_in(&p[k]), &l.omega_out(&p[k]), &n[k]);
            h - n[k] * n[k].dot(&h)
        };
        let hb = [hb(0), hb(1), hb(2)];
        if hb.iter().any(|h| !(h.norm() > MIN_TANGENT_H)) {
            return std::f64::consts::PI;
        }
        (0..3)
            .map(|k| {
                let (a, b) = (k, (k + 1) % 3);
                let w = transport(&hb[b], &n[b], &n[a]);
                n[a].dot(&hb[a].cross(&w)).atan2(hb[a].dot(&w)).abs()
            })
            .fold(0.0, |m: f64, t| if t.is_nan() { std::f64::consts::PI } else { m.max(t) })
    }

    /// The edge a triangle (corners `p`, unit normals `n`) of a region asking for `edge` needs
    /// so that h̄ turns by at most [`HalfVectorTurn::max_turn`] along it: its longest edge ×
    /// max_turn / turn, no shorter than [`MIN_TURN_SCALE`] × `edge`; `f64::INFINITY` when it
    /// turns less.
    pub fn want(&self, p: &[Vector3<f64>; 3], n: &[Vector3<f64>; 3], edge: f64) -> f64 {
        let turn = self.turn(p, n);
        if !(turn > self.max_turn) {
            return f64::INFINITY;
        }
        let longest = (0..3).map(|k| (p[(k + 1) % 3] - p[k]).norm()).fold(0.0, f64::max);
        (longest * self.max_turn / turn).max(MIN_TURN_SCALE * edge)
    }
}

/// `w`, tangent at unit normal `from`, turned by the smallest rotation that takes `from` to
/// `to` (Rodrigues with axis `from` × `to`); unchanged when the normals are opposed.
fn transport(w: &Vector3<f64>, from: &Vector3<f64>, to: &Vector3<f64>) -> Vector3<f64> {
    let c = from.dot(to);
    if !(c > -1.0 + 1e-9) {
        return *w;
    }
    let a = from.cross(to);
    w + a.cross(w) + a.cross(&a.cross(w)) / (1.0 + c)
}

/// About how many vertices refining for one edit adds ([`Resolution::estimates`]).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct RefineEstimate {
    /// The edit's index in the scene's `edits`.
    pub edit: usize,
    /// The area to be refined (scene units²).
    pub area: f64,
    /// The edge asked there (scene units).
    pub edge: f64,
    /// [`VERTICES_PER_EDGE_SQUARE`] × area / edge².
    pub vertices: f64,
}

/// Vertices that longest-edge bisection adds per edge² of area refined to an edge `e`: it
/// stops when the longest edge is at most `e` and its children's is then at least `e/√2`, so
/// the triangles it leaves have areas between about e²/8 and e²/4 (right isosceles ones,
/// e²/6 on average), and a surface has about half as many vertices as triangles: 3/e².
/// On the kettle, a curve whose tube covers 1.4 × 10⁴ mm² at e = 0.25 mm added 6.4 × 10⁵.
pub const VERTICES_PER_EDGE_SQUARE: f64 = 3.0;

impl PartialEq for Resolution {
    fn eq(&self, other: &Self) -> bool {
        self.faces == other.faces
            && self.turn == other.turn
            && self.marked.len() == other.marked.len()
            && self
                .marked
                .iter()
                .zip(&other.marked)
                .all(|(a, b)| a.region == b.region && a.want == b.want)
    }
}

impl Resolution {
    /// About how many vertices the refinement adds for each edit that asks for any, before
    /// any is added: [`VERTICES_PER_EDGE_SQUARE`] × A / e², A the area of the part's faces
    /// within the edit's reach and coarser than its edge e, at most the area of its region
    /// (a ball's πr², a tube's 2r × its length + πr²: the faces a split makes are asked again,
    /// so a long face touched by a brush is refined near it only). Linear in a curve's length
    /// whatever its points; the half vector's turn (at most [`MIN_TURN_SCALE`] of the edge,
    /// near critical points and folds) is not counted.
    pub fn estimates(&self) -> Vec<RefineEstimate> {
        self.marked
            .iter()
            .filter(|m| m.area > 0.0)
            .map(|m| RefineEstimate {
                edit: m.edit,
                area: m.area,
                edge: m.want,
                vertices: VERTICES_PER_EDGE_SQUARE * m.area / (m.want * m.want),
            })
            .collect()
    }

    /// The finest edge asked anywhere (`f64::INFINITY` when no face asks).
    pub fn finest(&self) -> f64 {
        self.faces.iter().copied().fold(f64::INFINITY, f64::min)
    }

    /// The edge a face made by a split needs, from its corners `p`: the smallest `want` of the
    /// regions it may reach (its centroid within reach + its radius about the centroid of
    /// their lines, the test the part's own faces were marked by), `f64::INFINITY` when it
    /// reaches none. A split face's children are asked again, so that a long sliver touched by
    /// a brush is refined near the brush only, not along its whole length (docs/math.md §12).
    pub fn child_target(&self, p: &[Vector3<f64>; 3]) -> f64 {
        let c = (p[0] + p[1] + p[2]) / 3.0;
        let rho = p.iter().map(|q| (q - c).norm()).fold(0.0, f64::max);
        let mut t = f64::INFINITY;
        for m in &self.marked {
            if m.want < t && m.grid.within(&c, m.region.reach + rho) {
                t = m.want;
            }
        }
        t
    }

    /// [`Resolution::child_target`] with the turn's request: the smaller of the regions' edge
    /// and the one the half vector's turn across the face asks for ([`HalfVectorTurn::want`]
    /// with the face's corners `p` and their unit normals `n`), inside a region only.
    pub fn face_target(&self, p: &[Vector3<f64>; 3], n: &[Vector3<f64>; 3]) -> f64 {
        let edge = self.child_target(p);
        match &self.turn {
            Some(turn) if edge.is_finite() => edge.min(turn.want(p, n, edge)),
            _ => edge,
        }
    }

    /// The edge each face of `mesh` needs ([`Resolution::faces`] with the turn's request on the
    /// faces a region reaches), with `normals` the unit normals of its vertices.
    pub fn turned_faces(&self, mesh: &Mesh, normals: &[Vector3<f64>]) -> Vec<f64> {
        let Some(turn) = &self.turn else { return self.faces.clone() };
        (self.faces.iter().zip(&mesh.faces))
            .map(|(&edge, face)| {
                let at = |v: &u32| normals.get(*v as usize).copied();
                match (
                    face.map(|v| mesh.positions.get(v as usize).copied()),
                    face.each_ref().map(at),
                ) {
                    ([Some(a), Some(b), Some(c)], [Some(na), Some(nb), Some(nc)])
                        if edge.is_finite() =>
                    {
                        edge.min(turn.want(&[a, b, c], &[na, nb, nc], edge))
                    }
                    _ => edge,
                }
            })
            .collect()
    }
}

/// The edge length each face of `mesh` needs for `edits` (`f64::INFINITY` where none asks),
/// with `edge` the fraction of a brush radius (or a curve's width) an edge may span.
pub fn edit_resolution(mesh: &Mesh, edits: &[Edit], edge: f64) -> Result<Resolution> {
    let mut target = vec![f64::INFINITY; mesh.num_faces()];
    let mut marked = Vec::new();
    for (k, e) in edits.iter().enumerate() {
        let Some(region) = region_of(mesh, e).map_err(|err| at_edit(k, e.tool(), err))? else {
            continue;
        };
        let want = edge * region.edge;
        if !(want.is_finite() && want > 0.0) {
            continue;
        }
        let grid = SegmentGrid::new(&region.lines, region.reach);
        if let Some(area) = mark(mesh, &region, &grid, want, &mut target) {
            let area = area.min(region.area());
            marked.push(Marked { region, want, grid, edit: k, area });
        }
    }
    Ok(Resolution { faces: target, marked, turn: None })
}

/// The segments of a region's polylines (a lone point as a segment of length 0), bucketed in
/// a uniform grid of cells no smaller than the reach, each segment under the cells of its
/// samples every half cell: a point within `d` of a segment is within `d` + ¼ cell of one of
/// its samples. A query whose box spans more cells than there are segments scans them all.
#[derive(Clone, Debug)]
struct SegmentGrid {
    segments: Vec<[Vector3<f64>; 2]>,
    /// None below [`SegmentGrid::SCAN`] segments or when no cell size fits.
    cells: Option<SegmentCells>,
}

impl SegmentGrid {
    /// Below this many segments a query scans them all.
    const SCAN: usize = 16;
    /// Most cells per axis across the segments' box.
    const MAX_CELLS: f64 = 256.0;
    /// Most listings of segments in cells, besides two per segment.
    const MAX_SAMPLES: f64 = 4e6;

    fn new(lines: &[Vec<Vector3<f64>>], reach: f64) -> SegmentGrid {
        let finite = |p: &Vector3<f64>| p.iter().all(|c| c.is_finite());
        let mut segments = Vec::new();
        for l in lines {
            match l.as_slice() {
                [a] if finite(a) => segments.push([*a, *a]),
                _ => segments.extend(
                    l.windows(2).filter(|w| finite(&w[0]) && finite(&w[1])).map(|w| [w[0], w[1]]),
                ),
            }
        }
        let (lo, hi) = bounds(segments.iter().flatten());
        if segments.len() <= Self::SCAN || !(lo.x <= hi.x) {
            return SegmentGrid { segments, cells: None };
        }
        // Each segment is listed every half cell: at most MAX_SAMPLES + 2 per segment in all.
        let length: f64 = segments.iter().map(|[a, b]| (b - a).norm()).sum();
        let cell =
            reach.max((hi - lo).max() / Self::MAX_CELLS).max(2.0 * length / Self::MAX_SAMPLES);
        if !(cell.is_finite() && cell > 0.0) {
            return SegmentGrid { segments, cells: None };
        }
        let mut cells = SegmentCells::new(lo, cell);
        for (k, [a, b]) in segments.iter().enumerate() {
            cells.insert_along(k as u32, a, b);
        }
        SegmentGrid { segments, cells: Some(cells) }
    }

    /// Whether `p` is within `d` of a segment.
    fn within(&self, p: &Vector3<f64>, d: f64) -> bool {
        let near = |k: usize| segment_distance(p, &self.segments[k]) <= d;
        let Some(cells) = &self.cells else {
            return (0..self.segments.len()).any(near);
        };
        let slack = Vector3::repeat(d + 0.25 * cells.cell());
        let (lo, hi) = (cells.key(&(p - slack)), cells.key(&(p + slack)));
        let span: f64 = (0..3).map(|i| (hi[i] - lo[i] + 1) as f64).product();
        if !(span <= self.segments.len() as f64) {
            return (0..self.segments.len()).any(near);
        }
        for x in lo[0]..=hi[0] {
            for y in lo[1]..=hi[1] {
                for z in lo[2]..=hi[2] {
                    if cells.get(&[x, y, z]).iter().any(|&k| near(k as usize)) {
                        return true;
                    }
                }
            }
        }
        false
    }
}

/// The distance from `p` to the segment `s`.
fn segment_distance(p: &Vector3<f64>, s: &[Vector3<f64>; 2]) -> f64 {
    let ab = s[1] - s[0];
    let l2 = ab.norm_squared();
    let t = if l2 > 0.0 { ((p - s[0]).dot(&ab) / l2).clamp(0.0, 1.0) } else { 0.0 };
    (p - s[0] - ab * t).norm()
}

fn region_of(mesh: &Mesh, e: &Edit) -> Result<Option<Region>> {
    Ok(match e {
        Edit::Bend(w) | Edit::Expand(w) => {
            let kind = if matches!(e, Edit::Bend(_)) { WarpKind::Bend } else { WarpKind::Expand };
            let p = match &w.centre {
                Centre::Vertex(i) => match mesh.positions.get(*i as usize) {
                    Some(p) => *p,
                    None => return Ok(None), // the tool reports the bad index
                },
                Centre::Point(p) => Vector3::from(*p),
            };
            // The warp compresses the highlight pattern by up to `finest_scale`: its target
            // needs edges that much finer to be as well resolved as the field before it.
            let edge = w.radius * finest_scale(kind, w.strength);
            Some(Region { lines: vec![vec![p]], reach: w.radius, edge })
        }
        Edit::Curve(c) => {
            let lines: Vec<Vec<Vector3<f64>>> = if let Some(pts) = &c.points {
                pts.iter().map(|l| l.iter().map(|p| Vector3::from(*p)).collect()).collect()
            } else {
                let uv = match (&c.uv, &c.svg) {
                    (Some(uv), _) => uv
                        .iter()
                        .map(|l| l.iter().map(|p| nalgebra::Vector2::new(p[0], p[1])).collect())
                        .collect(),
                    (None, Some(svg)) => read_svg_polylines(Path::new(svg), c.tolerance)?,
                    (None, None) => return Ok(None),
                };
                super::uv_lift::lift_uv_polylines(mesh, &uv)
            };
            let width = c.width.unwrap_or(c.radius).min(c.radius);
            Some(Region { lines, reach: c.radius, edge: width * CURVE_EDGE })
        }
        Edit::Stencil(_) | Edit::Light(_) | Edit::MoveLight(_) => None,
    })
}

/// Lowers `target` to `want` on every face that reaches within `region.reach` of its lines
/// (`grid`, the lines' segments: each vertex and face is compared with the segments near it, so
/// the work is linear in the curve's points); the area of the faces it reaches that are coarser
/// than `want`, `None` when the region asks for nothing (it may not: see
/// [`mark_between_vertices`]).
fn mark(
    mesh: &Mesh,
    region: &Region,
    grid: &SegmentGrid,
    want: f64,
    target: &mut [f64],
) -> Option<f64> {
    let (lo, hi) = bounds(region.lines.iter().flatten());
    if !(lo.x <= hi.x) {
        return None;
    }
    let n = mesh.num_vertices();
    // A brush or tube that holds none of the part's vertices lies on triangles larger than
    // itself, or its radius is a slip of units (module docs): `mark_between_vertices` decides.
    let holds_a_vertex = mesh.positions.iter().any(|p| {
        let near = (0..3).all(|i| p[i] >= lo[i] - region.reach && p[i] <= hi[i] + region.reach);
        near && grid.within(p, region.reach)
    });
    if !holds_a_vertex {
        return mark_between_vertices(mesh, region, want, target);
    }
    let mut area = 0.0;
    for (f, face) in mesh.faces.iter().enumerate() {
        if face.iter().any(|&v| v as usize >= n) {
            continue;
        }
        let p = face.map(|v| mesh.positions[v as usize]);
        let c = (p[0] + p[1] + p[2]) / 3.0;
        let rho = p.iter().map(|q| (q - c).norm()).fold(0.0, f64::max);
        let reach = region.reach + rho;
        let outside = (0..3).any(|i| c[i] < lo[i] - reach || c[i] > hi[i] + reach);
        if outside || !(reach.is_finite()) {
            continue;
        }
        if grid.within(&c, reach) {
            target[f] = target[f].min(want);
            area += coarse_area(&p, want);
        }
    }
    Some(area)
}

/// The area of the triangle `p` when its longest edge is longer than `want` (it is split), else 0.
fn coarse_area(p: &[Vector3<f64>; 3], want: f64) -> f64 {
    let longest = (0..3).map(|k| (p[(k + 1) % 3] - p[k]).norm()).fold(0.0, f64::max);
    if longest > want {
        0.5 * (p[1] - p[0]).cross(&(p[2] - p[0])).norm()
    } else {
        0.0
    }
}

/// [`mark`] for a region that holds no vertex: nothing when the region is small against the
/// part (a slip of units, refused by its tool), else `want` on the faces within the reach.
fn mark_between_vertices(
    mesh: &Mesh,
    region: &Region,
    want: f64,
    target: &mut [f64],
) -> Option<f64> {
    let (lo, hi) = bounds(mesh.positions.iter());
    let diagonal = (hi - lo).norm();
    if !(diagonal.is_finite() && region.reach >= MIN_REACH_SHARE * diagonal) {
        return None;
    }
    let mut area = 0.0;
    // The region's points, its polylines sampled every half reach (coarser, at most
    // MAX_SAMPLES in all, for a polyline longer than MAX_SAMPLES half reaches): the distance
    // of a face to the samples exceeds its distance to the polyline by at most half a step.
    let segments = || {
        region
            .lines
            .iter()
            .flat_map(|l| l.windows(2))
            .filter(|w| w.iter().flatten().all(|c| c.is_finite()))
    };
    let length: f64 = segments().map(|w| (w[1] - w[0]).norm()).sum();
    let step = (0.5 * region.reach).max(length / MAX_SAMPLES as f64);
    let mut samples: Vec<Vector3<f64>> =
        region.lines.iter().filter(|l| l.len() == 1).map(|l| l[0]).collect();
    for w in segments() {
        let n = ((w[1] - w[0]).norm() / step).ceil().max(1.0) as usize;
        samples.extend((0..=n).map(|k| w[0] + (w[1] - w[0]) * (k as f64 / n as f64)));
    }
    samples.retain(|p| p.iter().all(|c| c.is_finite()));
    let slack = if segments().next().is_some() { 0.5 * step } else { 0.0 };
    // The samples' box grown by the reach: a face outside it is farther than the reach from
    // every sample, so the closest points are sought only for the faces that meet it.
    let (lo, hi) = bounds(samples.iter());
    let grow = Vector3::repeat(region.reach + slack);
    let (lo, hi) = (lo - grow, hi + grow);
    let n = mesh.num_vertices();
    for (f, face) in mesh.faces.iter().enumerate() {
        if face.iter().any(|&v| v as usize >= n) {
            continue;
        }
        let [a, b, c] = face.map(|v| mesh.positions[v as usize]);
        let (flo, fhi) = (a.inf(&b).inf(&c), a.sup(&b).sup(&c));
        if (0..3).any(|i| fhi[i] < lo[i] || flo[i] > hi[i]) {
            continue;
        }
        let near = samples.iter().any(|p| {
            let (q, _) = crate::edit::support::closest_point_on_triangle(p, &a, &b, &c);
            (q - p).norm() <= region.reach + slack
        });
        if near {
            target[f] = target[f].min(want);
            area += coarse_area(&[a, b, c], want);
        }
    }
    Some(area)
}

/// The box of the finite points (lo > hi when there is none).
fn bounds<'a>(points: impl Iterator<Item = &'a Vector3<f64>>) -> (Vector3<f64>, Vector3<f64>) {
    let (mut lo, mut hi) = (Vector3::repeat(f64::INFINITY), Vector3::repeat(f64::NEG_INFINITY));
    for p in points.filter(|p| p.iter().all(|c| c.is_finite())) {
        lo = lo.inf(p);
        hi = hi.sup(p);
    }
    (lo, hi)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::edit::curve::CurveEdit;
    use crate::edit::warp::WarpEdit;

    fn strip() -> Mesh {
        // Ten unit squares along x, two triangles each.
        let mut pos = Vec::new();
        for i in 0..=10 {
            pos.push(Vector3::new(i as f64, 0.0, 0.0));
            pos.push(Vector3::new(i as f64, 1.0, 0.0));
        }
        let mut faces = Vec::new();
        for i in 0..10u32 {
            let (a, b, c, d) = (2 * i, 2 * i + 2, 2 * i + 3, 2 * i + 1);
            faces.push([a, b, c]);
            faces.push([a, c, d]);
        }
        Mesh::from_triangles(pos, faces)
    }

    #[test]
    fn a_brush_asks_for_its_fraction_of_the_radius_on_the_faces_it_reaches() {
        let m = strip();
        let bend: Edit = Edit::Bend(WarpEdit {
            centre: Centre::Point([2.5, 0.5, 0.0]),
            radius: 1.0,
            metric: Default::default(),
            strength: 0.8,
            direction: None,
            weight: 1.0,
        });
        let t = edit_resolution(&m, &[bend], 1.0 / 3.0).unwrap().faces;
        // Faces of squares 1, 2, 3 (centroids within 1 + their reach of x = 2.5) ask for 1/3
        // of the radius times the bend's compression, 1 − 0.8 · 4/(3√3); squares 5 and beyond
        // ask for nothing.
        let want = (1.0 - 0.8 * 4.0 / (3.0 * 3f64.sqrt())) / 3.0;
        for (f, v) in t.iter().enumerate() {
            let square = f / 2;
            if (1..=3).contains(&square) {
                assert!((v - want).abs() < 0.01 * want, "face {f}: {v} vs {want}");
            }
            if square >= 5 {
                assert!(v.is_infinite(), "face {f}: {v}");
            }
        }
    }

    #[test]
    fn a_brush_between_the_vertices_asks_for_nothing() {
        let m = strip();
        let tiny: Edit = Edit::Expand(WarpEdit {
            centre: Centre::Point([2.5, 0.5, 0.0]),
            radius: 0.01,
            metric: Default::default(),
            strength: 0.8,
            direction: None,
            weight: 1.0,
        });
        let t = edit_resolution(&m, &[tiny], 1.0 / 3.0).unwrap().faces;
        assert!(t.iter().all(|v| v.is_infinite()));
    }

    /// A 100 × 1 strip of two long slivers, as a CAD export meshes a flat face.
    fn two_slivers() -> Mesh {
        let pos = vec![
            Vector3::new(0.0, 0.0, 0.0),
            Vector3::new(100.0, 0.0, 0.0),
            Vector3::new(100.0, 1.0, 0.0),
            Vector3::new(0.0, 1.0, 0.0),
        ];
        Mesh::from_triangles(pos, vec![[0, 1, 2], [0, 2, 3]])
    }

    /// Two long slivers (a 100 × 1 strip, as a CAD export meshes a flat face): a brush of 5 in
    /// its middle holds no vertex, but it is no slip of units (5 % of the diagonal), so the two
    /// faces it touches ask for its edge, and so do a curve's; a brush or curve off the strip
    /// asks for nothing.
    #[test]
    fn a_brush_on_triangles_larger_than_it_asks_for_its_edge() {
        let m = two_slivers();
        let brush = |p: [f64; 3]| {
            Edit::Bend(WarpEdit {
                centre: Centre::Point(p),
                radius: 5.0,
                metric: Default::default(),
                strength: 0.8,
                direction: None,
                weight: 1.0,
            })
        };
        let t = edit_resolution(&m, &[brush([50.0, 0.5, 0.0])], 1.0 / 3.0).unwrap().faces;
        let want = 5.0 / 3.0 * finest_scale(WarpKind::Bend, 0.8);
        assert!(t.iter().all(|v| (v - want).abs() < 1e-12), "{t:?}");
        let t = edit_resolution(&m, &[brush([50.0, 20.0, 0.0])], 1.0 / 3.0).unwrap().faces;
        assert!(t.iter().all(|v| v.is_infinite()), "{t:?}");
        // A curve across the strip's middle, between its vertices, and one 10 above it.
        let curve = |y: f64| {
            Edit::Curve(CurveEdit {
                svg: None,
                uv: None,
                points: Some(vec![vec![[40.0, y, 0.0], [60.0, y + 0.5, 0.0]]]),
                radius: 2.0,
                weight: 1.0,
                tolerance: 1e-3,
                width: None,
            })
        };
        let t = edit_resolution(&m, &[curve(0.25)], 0.5).unwrap().faces;
        assert!(t.iter().all(|v| (v - 2.0 * 0.5 * CURVE_EDGE).abs() < 1e-12), "{t:?}");
        let t = edit_resolution(&m, &[curve(10.0)], 0.5).unwrap().faces;
        assert!(t.iter().all(|v| v.is_infinite()), "{t:?}");
    }

    /// The 100 × 1 strip of two slivers with a brush of radius 5 in its middle: asked again
    /// after each split, the slivers' children far from the brush are left alone, so all but a
    /// few new vertices (the longest-edge closure's, down the slivers) lie within three radii of
    /// the centre; inheriting the target splits the strip along its whole length to the
    /// brush's edge.
    #[test]
    fn a_sliver_is_refined_near_the_brush_only() {
        use crate::mesh::refine::{refine, refine_with, RefineOptions};
        let m = two_slivers();
        let bend = Edit::Bend(WarpEdit {
            centre: Centre::Point([50.0, 0.5, 0.0]),
            radius: 5.0,
            metric: Default::default(),
            strength: 0.8,
            direction: None,
            weight: 1.0,
        });
        let request = edit_resolution(&m, &[bend], 1.0 / 3.0).unwrap();
        let want = request.finest();
        let options = RefineOptions { max_levels: 12, ..Default::default() };
        let retarget =
            |p: &[Vector3<f64>; 3], _: &[Vector3<f64>; 3], _: f64| request.child_target(p);
        let near = refine_with(&m, &request.faces, &options, &retarget, None).unwrap();
        let whole = refine(&m, &request.faces, &options).unwrap();
        // New vertices more than three radii from the centre (the longest-edge closure may
        // carry a few splits down a sliver; the strip's length is 10 radii each way).
        let far = |r: &crate::mesh::refine::Refined| {
            r.mesh.positions[4..].iter().filter(|p| (p.x - 50.0).abs() > 15.0).count()
        };
        eprintln!(
            "near: {} vertices, {} far; whole: {} vertices, {} far",
            near.added(),
            far(&near),
            whole.added(),
            far(&whole)
        );
        assert!(far(&near) * 20 <= near.added(), "{} of {} far", far(&near), near.added());
        assert!(far(&whole) * 2 > whole.added());
        assert!(near.added() * 5 < whole.added(), "{} vs {}", near.added(), whole.added());
        // Inside the ball the edges are as asked.
        for f in &near.mesh.faces {
            let p = f.map(|v| near.mesh.positions[v as usize]);
            let c = (p[0] + p[1] + p[2]) / 3.0;
            if (c - Vector3::new(50.0, 0.5, 0.0)).norm() < 4.0 {
                for k in 0..3 {
                    assert!((p[k] - p[(k + 1) % 3]).norm() <= want + 1e-9);
                }
            }
        }
    }

    /// min(radius, width) × edge × [`CURVE_EDGE`]: 0.3 × 0.5 × 3/8.
    #[test]
    fn a_curve_asks_for_the_smaller_of_radius_and_width_along_its_tube() {
        let m = strip();
        let curve: Edit = Edit::Curve(CurveEdit {
            svg: None,
            uv: None,
            points: Some(vec![vec![[0.0, 0.5, 0.0], [4.0, 0.5, 0.0]]]),
            radius: 0.6,
            weight: 1.0,
            tolerance: 1e-3,
            width: Some(0.3),
        });
        let t = edit_resolution(&m, &[curve], 0.5).unwrap().faces;
        assert!((t[0] - 0.05625).abs() < 1e-12, "{}", t[0]);
        assert!(t[19].is_infinite());
    }

    /// Issue 46: a curve's request and its estimate follow its length, not its points. The
    /// same line in 2 or 2,001 points marks the same faces with the same estimate, a zigzag of
    /// tiny steps inside its own tube asks no more than the strip holds, and each estimate is
    /// 3 × the coarse faces' area within the tube's area / e².
    #[test]
    fn a_curve_s_estimate_follows_its_length_not_its_points() {
        let m = strip();
        let curve = |points: Vec<[f64; 3]>| {
            Edit::Curve(CurveEdit {
                svg: None,
                uv: None,
                points: Some(vec![points]),
                radius: 0.6,
                weight: 1.0,
                tolerance: 1e-3,
                width: None,
            })
        };
        let fine: Vec<[f64; 3]> = (0..=2000).map(|k| [k as f64 * 0.002, 0.5, 0.0]).collect();
        let a = edit_resolution(&m, &[curve(vec![[0.0, 0.5, 0.0], [4.0, 0.5, 0.0]])], 0.5).unwrap();
        let b = edit_resolution(&m, &[curve(fine)], 0.5).unwrap();
        assert_eq!(a.faces, b.faces);
        let (ea, eb) = (a.estimates(), b.estimates());
        assert_eq!(ea.len(), 1);
        // Every face the tube reaches (area ½, edges ≥ 1) is coarser than its edge 0.1125.
        let reached = |t: &[f64]| 0.5 * t.iter().filter(|x| x.is_finite()).count() as f64;
        let e = ea[0];
        assert_eq!((e.edit, e.edge, e.area), (0, 0.6 * 0.5 * CURVE_EDGE, reached(&a.faces)));
        assert!((5.0..=6.0).contains(&e.area), "{e:?}");
        assert!((e.vertices - 3.0 * e.area / (e.edge * e.edge)).abs() < 1e-9 * e.vertices);
        assert!((eb[0].vertices - e.vertices).abs() < 1e-9 * e.vertices, "{eb:?}");
        // 10⁴ steps of ±0.05 across y = 0.5 over 4 units: 1000 units long, a tube of 1200
        // units², yet it asks for the faces it reaches (those of the line, ± the last square).
        let zigzag: Vec<[f64; 3]> = (0..=10_000)
            .map(|k| [k as f64 * 4e-4, if k % 2 == 0 { 0.45 } else { 0.55 }, 0.0])
            .collect();
        let z = edit_resolution(&m, &[curve(zigzag)], 0.5).unwrap();
        let ez = z.estimates()[0];
        assert_eq!(ez.area, reached(&z.faces));
        assert!((ez.area - e.area).abs() <= 1.0, "{ez:?} {e:?}");
        // A short curve's estimate is bounded by its tube, not by the faces it touches:
        // 2 × 0.6 × 0.01 + π 0.6².
        let dot = edit_resolution(&m, &[curve(vec![[2.5, 0.5, 0.0], [2.51, 0.5, 0.0]])], 0.5)
            .unwrap()
            .estimates();
        let tube = 2.0 * 0.6 * 0.01 + std::f64::consts::PI * 0.36;
        assert!((dot[0].area - tube).abs() < 1e-12, "{dot:?}");
    }

    /// A light and a view both along +z: h = z, and h̄ on the unit sphere points to the pole.
    fn overhead() -> HalfVectorTurn {
        let z = Vector3::z();
        let lighting = Lighting::new(z, crate::highlight::lighting::View::Direction(z)).unwrap();
        HalfVectorTurn { lighting, max_turn: 10f64.to_radians() }
    }

    fn on_sphere(theta: f64, phi: f64) -> Vector3<f64> {
        Vector3::new(theta.sin() * phi.cos(), theta.sin() * phi.sin(), theta.cos())
    }

    /// On the unit sphere the smallest rotation between two normals is the parallel transport
    /// along the great circle through them, so h̄'s turn along a chord of a latitude θ spanning
    /// Δφ is π − 2β, β the base angle of the isosceles spherical triangle the chord makes with
    /// the pole: tan β = cot(Δφ/2) / cos θ (Napier's rule on its halves).
    #[test]
    fn the_turn_along_a_latitude_is_the_sphere_s_holonomy() {
        let t = overhead();
        for (theta, dphi) in
            [(0.3f64, 0.2f64), (0.7, 0.5), (1.2, 1.0), (std::f64::consts::FRAC_PI_2, 0.4)]
        {
            let (a, b) = (on_sphere(theta, 0.1), on_sphere(theta, 0.1 + dphi));
            let beta = (1.0 / ((dphi / 2.0).tan() * theta.cos())).atan();
            let want = std::f64::consts::PI - 2.0 * beta;
            let got = t.turn(&[a, b, b], &[a, b, b]);
            assert!((got - want).abs() < 1e-9, "θ {theta} Δφ {dphi}: {got} vs {want}");
        }
    }

    #[test]
    fn a_face_asks_for_its_longest_edge_scaled_by_the_turn_it_allows() {
        let t = overhead();
        let (a, b) = (on_sphere(0.3, 0.0), on_sphere(0.3, 0.5));
        let turn = t.turn(&[a, b, b], &[a, b, b]);
        assert!(turn > t.max_turn);
        let chord = (b - a).norm();
        let want = t.want(&[a, b, b], &[a, b, b], 0.1);
        assert!((want - chord * t.max_turn / turn).abs() < 1e-12, "{want}");
        // Never finer than MIN_TURN_SCALE of the region's edge.
        assert_eq!(t.want(&[a, b, b], &[a, b, b], 100.0), MIN_TURN_SCALE * 100.0);
        // Along the equator h̄ = −z everywhere: no turn, no request.
        let eq = std::f64::consts::FRAC_PI_2;
        let (c, d) = (on_sphere(eq, 0.0), on_sphere(eq, 0.5));
        assert!(t.want(&[c, d, d], &[c, d, d], 1.0).is_infinite());
    }

    #[test]
    fn a_critical_corner_turns_half_a_turn() {
        let t = overhead();
        let (pole, a) = (Vector3::z(), on_sphere(0.01, 0.0));
        assert_eq!(t.turn(&[pole, a, a], &[pole, a, a]), std::f64::consts::PI);
        // A NaN normal is treated as critical, never as "no turn".
        let nan = Vector3::new(f64::NAN, 0.0, 1.0);
        assert_eq!(t.turn(&[a, a, a], &[a, nan, a]), std::f64::consts::PI);
    }
}
