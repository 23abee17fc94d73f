//! The report of `grainline inspect`: counts, extent, topology, UV charts and problems of a
//! loaded mesh. Serialized as the stable JSON object documented in `docs/formats.md`
//! ("inspect --json").

use std::path::Path;

use nalgebra::Vector2;
use serde::Serialize;

use super::load::LoadedMesh;
use super::topology::{Component, Topology};
use super::uv_charts::UvCharts;
use super::VertexId;

/// Version of the JSON layout; bumped when a field changes meaning or is removed.
pub const INSPECT_FORMAT_VERSION: u32 = 1;

/// Axis-aligned bounding box.
#[derive(Clone, Debug, Serialize)]
pub struct BoundingBox {
    /// Smallest coordinates.
    pub min: [f64; 3],
    /// Largest coordinates.
    pub max: [f64; 3],
    /// `max − min`.
    pub size: [f64; 3],
}

/// One boundary loop.
#[derive(Clone, Debug, Serialize)]
pub struct BoundaryLoop {
    /// Number of edges (= vertices) of the loop.
    pub edges: usize,
    /// Length along the loop, in the mesh unit.
    pub length: f64,
    /// 1-based file `v` number of the loop's first vertex.
    pub first_vertex: u32,
}

/// UV layout summary.
#[derive(Clone, Debug, Serialize)]
pub struct UvReport {
    /// Number of charts.
    pub charts: usize,
    /// Seam edges.
    pub seam_edges: usize,
    /// Faces with negative signed UV area.
    pub flipped_faces: usize,
    /// Faces with zero UV area.
    pub degenerate_faces: usize,
    /// Faces whose orientation disagrees with their chart's majority.
    pub faces_against_chart: usize,
    /// Charts whose majority of faces is flipped.
    pub mirrored_charts: Vec<MirroredChart>,
    /// Number of mirrored charts (= `mirrored_charts.len()`; added after 0.2.0).
    pub mirrored_chart_count: usize,
    /// Charts with at least one flipped face (mirrored or not; added after 0.2.0).
    pub charts_with_flipped_faces: usize,
    /// Pairs of charts `[a, b]`, `a < b`, whose UV triangles share interior points, ascending
    /// (at most [`MAX_LISTED_OVERLAPS`] listed; added after 0.2.0).
    pub overlapping_charts: Vec<[usize; 2]>,
    /// Number of overlapping chart pairs (all of them, also beyond the listed ones).
    pub overlapping_chart_pairs: usize,
}

/// At most this many overlapping chart pairs are listed in [`UvReport::overlapping_charts`].
pub const MAX_LISTED_OVERLAPS: usize = 100;

/// Do the open UV triangles `a` and `b` share points? The separating-axis test on the six edge
/// normals: disjoint iff some axis separates the projections; projections that only touch
/// (overlap ≤ `eps`) count as separated, so charts packed edge to edge do not overlap.
fn triangles_overlap(a: &[Vector2<f64>; 3], b: &[Vector2<f64>; 3], eps: f64) -> bool {
    for (t, o) in [(a, b), (b, a)] {
        for i in 0..3 {
            let e = t[(i + 1) % 3] - t[i];
            let n = Vector2::new(-e.y, e.x);
            let len = n.norm();
            if len == 0.0 {
                continue;
            }
            let n = n / len;
            let (mut lo1, mut hi1, mut lo2, mut hi2) =
                (f64::INFINITY, f64::NEG_INFINITY, f64::INFINITY, f64::NEG_INFINITY);
            for k in 0..3 {
                let p = n.dot(&t[k]);
                let q = n.dot(&o[k]);
                (lo1, hi1, lo2, hi2) = (lo1.min(p), hi1.max(p), lo2.min(q), hi2.max(q));
            }
            if hi1.min(hi2) - lo1.max(lo2) <= eps {
                return false;
            }
        }
    }
    true
}

/// Chart pairs whose UV triangles overlap (share interior points), ascending, found through a
/// uniform grid over the UV bounding box (about one face per cell). Zero-area and non-finite
/// UV faces are skipped.
pub fn overlapping_chart_pairs(
    uv: &super::CornerAttribute<Vector2<f64>>,
    charts: &UvCharts,
) -> Vec<[usize; 2]> {
    use std::collections::BTreeSet;
    let nf = uv.corners.len();
    if charts.charts().len() < 2 || nf == 0 {
        return Vec::new();
    }
    let faces: Vec<usize> = (0..nf)
        .filter(|&f| {
            let t = uv.face(f);
            t.iter().all(|p| p.x.is_finite() && p.y.is_finite())
                && charts.signed_area(super::FaceId(f as u32)) != 0.0
        })
        .collect();
    let (mut lo, mut hi) = (Vector2::repeat(f64::INFINITY), Vector2::repeat(f64::NEG_INFINITY));
    for &f in &faces {
        for p in uv.face(f) {
            lo = lo.inf(&p);
            hi = hi.sup(&p);
        }
    }
    if faces.is_empty() {
        return Vec::new();
    }
    let size = hi - lo;
    let eps = 1e-9 * size.norm();
    // About one face per cell, at most 2048 cells a side.
    let n = ((faces.len() as f64).sqrt().ceil() as usize).clamp(1, 2048);
    let cell = |x: f64, lo: f64, w: f64| -> usize {
        if w <= 0.0 {
            0
        } else {
            (((x - lo) / w * n as f64) as usize).min(n - 1)
        }
    };
    let range = |t: &[Vector2<f64>; 3]| {
        let (a, b) = (t[0].inf(&t[1]).inf(&t[2]), t[0].sup(&t[1]).sup(&t[2]));
        (
            cell(a.x, lo.x, size.x)..=cell(b.x, lo.x, size.x),
            cell(a.y, lo.y, size.y)..=cell(b.y, lo.y, size.y),
        )
    };
    let mut bins: Vec<Vec<u32>> = vec![Vec::new(); n * n];
    for &f in &faces {
        let (xs, ys) = range(&uv.face(f));
        for y in ys {
            for x in xs.clone() {
                bins[y * n + x].push(f as u32);
            }
        }
    }
    let mut pairs = BTreeSet::new();
    for bin in &bins {
        for (i, &f) in bin.iter().enumerate() {
            let cf = charts.chart_of(super::FaceId(f));
            let tf = uv.face(f as usize);
            for &g in &bin[i + 1..] {
                let cg = charts.chart_of(super::FaceId(g));
                let key = [cf.min(cg), cf.max(cg)];
                if cf == cg || pairs.contains(&key) {
                    continue;
                }
                if triangles_overlap(&tf, &uv.face(g as usize), eps) {
                    pairs.insert(key);
                }
            }
        }
    }
    pairs.into_iter().collect()
}

/// A mirrored chart.
#[derive(Clone, Debug, Serialize)]
pub struct MirroredChart {
    /// Chart index (charts are numbered by their first face).
    pub chart: usize,
    /// Faces in the chart.
    pub faces: usize,
    /// Of which flipped.
    pub flipped: usize,
}

/// The angle below which a triangle counts as a sliver in [`QualityReport`] (degrees).
pub const SLIVER_ANGLE_DEG: f64 = 5.0;

/// Triangle shape and sharp edges.
#[derive(Clone, Debug, Serialize)]
pub struct QualityReport {
    /// The smallest interior angle of any triangle, degrees.
    pub min_angle_deg: f64,
    /// The triangle with the smallest angle, as the file names it (`line 12`, `triangle 7`,
    /// `face element 3`).
    pub min_angle_face: String,
    /// The sliver threshold ([`SLIVER_ANGLE_DEG`]).
    pub sliver_angle_deg: f64,
    /// Triangles with an angle below the threshold.
    pub slivers: usize,
    /// The crease angle the sharp edges are counted at (the default of `mesh.crease_angle`).
    pub crease_angle_deg: f64,
    /// Edges whose faces' normals differ by more than the crease angle (the preview does not
    /// smooth across them).
    pub crease_edges: usize,
    /// Vertices where the preview's normal is split.
    pub split_vertices: usize,
    /// Smooth patches: faces joined across every edge that is not sharp (docs/math.md §3,
    /// "Patches"). Each is brushed as its own sheet.
    pub patches: usize,
    /// Copies of vertices made when the part is split into its patches (`mesh.patches`).
    pub patch_copies: usize,
}

/// The name of mesh face `f` in the file's own terms.
pub fn face_name(r: &super::load::LoadReport, f: usize) -> String {
    use super::load::MeshFormat;
    use super::validate::Naming;
    let line = r.face_line.get(f).copied().unwrap_or(0);
    let index = r.face_index.get(f).copied().unwrap_or(f as u32);
    match r.format {
        MeshFormat::Obj if line > 0 => format!("line {line}"),
        MeshFormat::Obj => format!("face {f}"),
        MeshFormat::Stl => Naming::Stl.face(line, index),
        MeshFormat::Ply => Naming::Ply.face(line, index),
    }
}

/// Problems found (and tolerated) while loading.
#[derive(Clone, Debug, Serialize)]
pub struct Problems {
    /// Zero-area faces dropped.
    pub degenerate_faces: usize,
    /// Edges with three or more faces.
    pub nonmanifold_edges: usize,
    /// Vertices whose faces form several fans.
    pub nonmanifold_vertices: usize,
    /// Edges whose two faces are oriented inconsistently.
    pub inconsistent_orientation_edges: usize,
    /// File vertices used by no face.
    pub unreferenced_vertices: usize,
    /// File vertices welded into an earlier one.
    pub welded_vertices: usize,
}

/// Everything `grainline inspect` reports.
#[derive(Clone, Debug, Serialize)]
pub struct InspectReport {
    /// Layout version ([`INSPECT_FORMAT_VERSION`]).
    pub format_version: u32,
    /// The mesh file.
    pub file: String,
    /// Its format: `obj`, `stl` or `ply`.
    pub format: &'static str,
    /// Unit of every length below.
    pub units: &'static str,
    /// Object and group names in the file.
    pub objects: Vec<String>,
    /// `v` entries in the file.
    pub file_vertices: usize,
    /// Vertices of the loaded mesh.
    pub vertices: usize,
    /// Undirected edges.
    pub edges: usize,
    /// Triangles of the loaded mesh.
    pub faces: usize,
    /// Polygons (more than three corners) split into triangles.
    pub polygons_split: usize,
    /// Bounding box.
    pub bounding_box: BoundingBox,
    /// Surface area (unit²).
    pub area: f64,
    /// χ = V − E + F.
    pub euler_characteristic: i64,
    /// Sum of the components' genera (`null` if a component has none).
    pub genus: Option<u32>,
    /// Connected components.
    pub components: Vec<Component>,
    /// Boundary loops, in the order found.
    pub boundary_loops: Vec<BoundaryLoop>,
    /// Connected components of the boundary edges (= loops unless loops touch at a vertex).
    pub boundary_components: usize,
    /// Boundary vertices.
    pub boundary_vertices: usize,
    /// UV layout (`null` without UVs).
    pub uv: Option<UvReport>,
    /// Whether the file has a normal for every corner.
    pub has_normals: bool,
    /// Slivers and sharp edges.
    pub quality: QualityReport,
    /// Problems found.
    pub problems: Problems,
}

impl InspectReport {
    /// Computes the report of a loaded mesh; `quality` is the mesh's angles and creases
    /// (`QualityReport::new`, computed with the face normals in [`crate::geometry`]).
    pub fn new(
        path: &Path,
        loaded: &LoadedMesh,
        topo: &Topology,
        uv: Option<&UvCharts>,
        quality: QualityReport,
    ) -> Self {
        let (mesh, r) = (&loaded.mesh, &loaded.report);
        let (lo, hi) = mesh.bounding_box().unwrap_or_default();
        let boundary_loops = (0..topo.num_boundary_loops())
            .map(|l| {
                let vs = topo.boundary_loop(l);
                let p = |v: VertexId| mesh.positions[v.index()];
                let length =
                    (0..vs.len()).map(|k| (p(vs[(k + 1) % vs.len()]) - p(vs[k])).norm()).sum();
                let first_vertex = r.source_vertex.get(vs[0].index()).copied().unwrap_or(0);
                BoundaryLoop { edges: vs.len(), length, first_vertex }
            })
            .collect();
        let overlaps = match (uv, mesh.uv.as_ref()) {
            (Some(c), Some(corners)) => overlapping_chart_pairs(corners, c),
            _ => Vec::new(),
        };
        let uv = uv.map(|c| UvReport {
            mirrored_chart_count: c.charts().iter().filter(|ch| ch.mirrored).count(),
            charts_with_flipped_faces: c.charts().iter().filter(|ch| ch.flipped > 0).count(),
            overlapping_chart_pairs: overlaps.len(),
            overlapping_charts: overlaps.iter().take(MAX_LISTED_OVERLAPS).copied().collect(),
            charts: c.charts().len(),
            seam_edges: c.num_seam_edges(),
            flipped_faces: c.num_flipped_faces(),
            degenerate_faces: c.num_degenerate_faces(),
            faces_against_chart: c.num_faces_against_chart(),
            mirrored_charts: c
                .charts()
                .iter()
                .enumerate()
                .filter(|(_, ch)| ch.mirrored)
                .map(|(chart, ch)| MirroredChart { chart, faces: ch.faces, flipped: ch.flipped })
                .collect(),
        });
        InspectReport {
            format_version: INSPECT_FORMAT_VERSION,
            file: path.display().to_string(),
            format: r.format.as_str(),
            units: mesh.units.as_str(),
            objects: r.objects.clone(),
            file_vertices: r.file_vertices,
            vertices: mesh.num_vertices(),
            edges: topo.num_edges(),
            faces: mesh.num_faces(),
            polygons_split: r.polygons_split,
            bounding_box: BoundingBox { min: lo.into(), max: hi.into(), size: (hi - lo).into() },
            area: mesh.area(),
            euler_characteristic: topo.euler_characteristic(),
            genus: topo.genus(),
            components: topo.components().to_vec(),
            boundary_loops,
            boundary_components: topo.num_boundary_components(),
            boundary_vertices: topo.boundary_vertices().len(),
            uv,
            has_normals: mesh.normals.is_some(),
            quality,
            problems: Problems {
                degenerate_faces: r.dropped_degenerate_faces,
                nonmanifold_edges: r.nonmanifold_edges,
                nonmanifold_vertices: r.nonmanifold_vertices,
                inconsistent_orientation_edges: r.inconsistent_orientation_edges,
                unreferenced_vertices: r.unreferenced_vertices,
                welded_vertices: r.welded_vertices,
            },
        }
    }
}
