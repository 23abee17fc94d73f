//! Automatic UV layouts for parts that arrive without one.
//!
//! [`flatten`] cuts a mesh into charts and flattens each one (math.md, "Flattening"):
//!
//! 1. Every edge-connected piece of the mesh is tried as one chart. A chart must be a disk,
//!    or planar (a disk with holes) with its normals within about a hemisphere ([`charts`]);
//!    it is flattened by LSCM ([`lscm`], conformal) and, with
//!    [`Method::Arap`], refined by ARAP ([`arap`], local/global, started from LSCM); with
//!    [`Method::Bff`] a disk chart is flattened by boundary first flattening instead ([`bff`],
//!    conformal, boundary lengths kept), other charts and invalid BFF maps by LSCM. It is
//!    kept when the flattening is valid (no flipped triangle, no boundary crossing,
//!    [`distortion`]; a few flipped triangles of a scan's small folds are first untangled,
//!    [`untangle`]) and the stretch max(σ₁, 1/σ₂) of 95 % of its area is at most
//!    [`LayoutOptions::max_stretch`]. With ARAP, a chart whose LSCM map already passes is kept
//!    with it and ARAP runs once on the final charts (step 4). A developable or nearly
//!    developable sheet therefore stays one chart, flattened with little distortion.
//! 2. A piece that is not kept is cut: along its sharp creases first, then by region growing
//!    on normal cones, then by bisection ([`charts`]); each piece is tried again. Single
//!    triangles flatten exactly, so every mesh gets a layout. On a noisy part (a scan whose
//!    sharp edges enclose many single faces, [`charts::NOISE_FRACTION`]) the tiny crease pieces
//!    join their neighbours and cuts keep whole the fans that would wrap on a chart's boundary
//!    ([`charts::WRAP_ANGLE`]).
//! 3. Small charts (at most [`MERGE_FRACTION`] of the faces) are merged into neighbours
//!    while the union still flattens within the same bounds, smallest first, so a closed
//!    scan ends up with a handful of charts.
//! 4. ARAP runs on the final charts kept with their LSCM map. The charts are scaled to their
//!    surface area, packed into [0, 1]² at one common scale
//!    ([`pack`]) and reported: charts, seams, area and angle distortion, edge-length error.
//!
//! The result is deterministic: no step depends on the thread count.

pub mod arap;
pub mod bff;
pub mod charts;
pub mod distortion;
mod linsys;
pub mod lscm;
pub mod pack;
pub mod untangle;

use std::collections::VecDeque;
use std::time::Instant;

use nalgebra::{Vector2, Vector3};
use serde::{Deserialize, Serialize};

use crate::error::fmt_num;
use crate::mesh::halfedge::HalfEdges;
use crate::mesh::{CornerAttribute, Mesh};
use crate::{Error, Result};
use charts::ChartMesh;
use distortion::{area_scale, invalid, FaceMeasures, Stat};

/// How each chart is flattened.
#[derive(
    Clone, Copy, Debug, Default, PartialEq, Eq, Serialize, Deserialize, schemars::JsonSchema,
)]
#[serde(rename_all = "lowercase")]
pub enum Method {
    /// Least-squares conformal maps (angles kept; areas may vary across a curved chart).
    Lscm,
    /// As-rigid-as-possible, started from LSCM (lengths kept as well as the surface allows).
    #[default]
    Arap,
    /// Boundary first flattening with minimal area distortion (conformal; boundary lengths
    /// kept). Charts that are not disks, or whose BFF map is not valid, get LSCM's.
    Bff,
}

impl Method {
    /// The method's name as written in scenes and on the command line.
    pub fn as_str(self) -> &'static str {
        match self {
            Method::Lscm => "lscm",
            Method::Arap => "arap",
            Method::Bff => "bff",
        }
    }
}

impl std::str::FromStr for Method {
    type Err = Error;
    fn from_str(s: &str) -> Result<Self> {
        match s {
            "lscm" => Ok(Method::Lscm),
            "arap" => Ok(Method::Arap),
            "bff" => Ok(Method::Bff),
            _ => Err(Error::invalid_arg(
                "method",
                format!("unknown method {s:?}; expected lscm, arap or bff"),
            )),
        }
    }
}

/// When the pipeline makes a layout (used by `grainline run` / `trace`; [`flatten`] ignores
/// it).
#[derive(
    Clone, Copy, Debug, Default, PartialEq, Eq, Serialize, Deserialize, schemars::JsonSchema,
)]
#[serde(rename_all = "lowercase")]
pub enum LayoutMode {
    /// Make a layout when the part has no UVs and toolpaths need them (the default).
    #[default]
    Auto,
    /// Always make one, replacing the part's own UVs for the toolpaths.
    Always,
    /// Never: a part without UVs is refused (before any long stage runs).
    Never,
}

/// Options of [`flatten`].
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize, schemars::JsonSchema)]
#[serde(deny_unknown_fields, default)]
pub struct LayoutOptions {
    /// When the pipeline makes a layout (`auto`, `always`, `never`). Default `auto`.
    pub mode: LayoutMode,
    /// `arap` (default), `lscm` or `bff`.
    pub method: Method,
    /// Edges whose dihedral angle exceeds this (degrees) are the first seams tried. In
    /// (0, 180]. Default 40.
    pub crease_angle_deg: f64,
    /// Half-angle (degrees) of the normal cones grown into charts. In (0, 90]. Default 60.
    pub cone_angle_deg: f64,
    /// A chart is kept when the stretch max(σ₁, 1/σ₂) of 95 % of its area is at most this.
    /// At least 1. Default 2.
    pub max_stretch: f64,
    /// Largest number of ARAP local/global iterations per chart. At most 1000. Default 20.
    pub arap_iterations: usize,
    /// Gap between packed charts, as a fraction of the square root of the layout's area. In
    /// [0, 0.5]. Default 0.01.
    pub gap: f64,
}

impl Default for LayoutOptions {
    fn default() -> Self {
        LayoutOptions {
            mode: LayoutMode::Auto,
            method: Method::Arap,
            crease_angle_deg: 40.0,
            cone_angle_deg: 60.0,
            max_stretch: 2.0,
            arap_iterations: 20,
            gap: 0.01,
        }
    }
}

impl LayoutOptions {
    /// Range-checks every setting; keys are relative to this section.
    pub fn validate(&self) -> Result<()> {
        let range = |key: &str, v: f64, ok: bool, what: &str| {
            if v.is_finite() && ok {
                Ok(())
            } else {
                Err(Error::setting(key, format!("must be {what}, got {}", fmt_num(v))))
            }
        };
        let c = self.crease_angle_deg;
        range("crease_angle_deg", c, c > 0.0 && c <= 180.0, "in (0, 180]")?;
        let k = self.cone_angle_deg;
        range("cone_angle_deg", k, k > 0.0 && k <= 90.0, "in (0, 90]")?;
        range("max_stretch", self.max_stretch, self.max_stretch >= 1.0, "at least 1")?;
        range("gap", self.gap, (0.0..=0.5).contains(&self.gap), "in [0, 0.5]")?;
        if self.arap_iterations > 1000 {
            return Err(Error::setting(
                "arap_iterations",
                format!("must be at most 1000, got {}", self.arap_iterations),
            ));
        }
        Ok(())
    }
}

/// How many pieces each kind of cut made.
#[derive(Clone, Copy, Debug, Default, PartialEq, Serialize, schemars::JsonSchema)]
pub struct Cuts {
    /// Regions cut along sharp creases.
    pub creases: usize,
    /// Regions cut by normal-cone growing.
    pub cones: usize,
    /// Regions bisected.
    pub bisections: usize,
    /// Charts merged into a neighbour afterwards (their union flattened within the bounds).
    pub merges: usize,
}

/// What [`flatten`] made, and its distortion.
#[derive(Clone, Debug, PartialEq, Serialize, schemars::JsonSchema)]
pub struct LayoutReport {
    /// The method asked for.
    pub method: Method,
    /// Charts in the layout.
    pub charts: usize,
    /// Faces of the largest chart.
    pub largest_chart_faces: usize,
    /// Seam edges (mesh edges between two charts).
    pub seam_edges: usize,
    /// Total length of the seams on the part, scene units.
    pub seam_length: f64,
    /// max(σ₁σ₂, 1/(σ₁σ₂)) per face, area-weighted (1: areas kept).
    pub area_distortion: Stat,
    /// σ₁/σ₂ per face, area-weighted (1: angles kept).
    pub angle_distortion: Stat,
    /// Mean |UV angle − 3D angle| of each face's corners, degrees, area-weighted.
    pub angle_error_deg: Stat,
    /// |s·ℓ_uv − ℓ| / ℓ over every edge of every face, length-weighted (s = `uv_scale`).
    pub edge_length_error: Stat,
    /// UV triangles with signed area ≤ 0 (always 0: such charts are cut).
    pub flipped_faces: usize,
    /// Charts whose ARAP result was not valid (or, for a final chart kept with its LSCM map,
    /// not within the stretch bound), so their LSCM flattening was kept.
    pub arap_fallbacks: usize,
    /// Charts (tried, merges included) that BFF could not flatten, so LSCM's map was used:
    /// not a disk, or BFF's map not valid (added after 0.2.0).
    pub bff_fallbacks: usize,
    /// Of `bff_fallbacks`, the charts that were not disks (planar charts with holes).
    pub bff_not_disk: usize,
    /// Charts (tried) whose conformal BFF map was not valid and got the harmonic one.
    pub bff_harmonic: usize,
    /// ARAP local/global iterations over the charts whose ARAP map was kept.
    pub arap_iterations: usize,
    /// Cuts made.
    pub cuts: Cuts,
    /// UV × this ≈ scene units on the part (the layout's one scale).
    pub uv_scale: f64,
    /// Wall seconds.
    pub seconds: f64,
}

/// A layout: per-corner UVs in [0, 1]², the chart of each face and the report.
#[derive(Clone, Debug)]
pub struct Layout {
    /// The UVs (one value per chart vertex).
    pub uv: CornerAttribute<Vector2<f64>>,
    /// The chart of each face.
    pub face_chart: Vec<u32>,
    /// Charts, seams and distortion.
    pub report: LayoutReport,
}

/// One region waiting to be flattened, with the next cut to try on it.
struct Region {
    faces: Vec<u32>,
    next_cut: u8,
}

/// What the per-chart flattenings did, over every chart tried (merges included).
#[derive(Default)]
struct Counters {
    arap_fallbacks: usize,
    arap_iterations: usize,
    bff_fallbacks: usize,
    bff_not_disk: usize,
    bff_harmonic: usize,
}

/// The chart's BFF map (math.md §11.6), or `None` (counted) when the chart is not a disk or the
/// map is not valid.
fn flatten_bff(
    chart: &ChartMesh,
    pos: &[Vector3<f64>],
    counters: &mut Counters,
) -> Option<Vec<Vector2<f64>>> {
    if !chart.is_disk() {
        counters.bff_fallbacks += 1;
        counters.bff_not_disk += 1;
        return None;
    }
    // The conformal extension first; the harmonic one (boundary exactly the closed polygon)
    // when the conformal map is not valid.
    for extension in [bff::Extension::Conformal, bff::Extension::Harmonic] {
        if let Ok(mut uv) = bff::bff(chart, pos, extension) {
            if valid_untangled(chart, pos, &mut uv) {
                counters.bff_harmonic += (extension == bff::Extension::Harmonic) as usize;
                return Some(uv);
            }
        }
    }
    counters.bff_fallbacks += 1;
    None
}

/// A chart kept, with its flattening.
struct Flat {
    chart: ChartMesh,
    uv: Vec<Vector2<f64>>,
    /// The map is LSCM's, valid and within the stretch bound; ARAP refines it once the charts
    /// are final ([`finish_arap`]).
    arap_pending: bool,
}

/// A flattening found by [`flatten_chart`].
struct Found {
    uv: Vec<Vector2<f64>>,
    arap_pending: bool,
}

/// Flattens one disk (or planar) chart; `None` when the result is not valid or too stretched.
fn flatten_chart(
    chart: &ChartMesh,
    pos: &[Vector3<f64>],
    options: &LayoutOptions,
    counters: &mut Counters,
) -> Option<Found> {
    let single = chart.tris.len() == 1;
    let bff_uv = (options.method == Method::Bff && !single)
        .then(|| flatten_bff(chart, pos, counters))
        .flatten();
    let uv = match bff_uv {
        Some(uv) => uv,
        None => {
            let mut uv = lscm::lscm(chart, pos).ok()?;
            let s = area_scale(chart, pos, &uv);
            uv.iter_mut().for_each(|p| *p *= s);
            if single {
                return Some(Found { uv, arap_pending: false });
            }
            let lscm_valid = valid_untangled(chart, pos, &mut uv);
            // With ARAP, a valid LSCM map within the bound decides: ARAP runs once the charts
            // are final (every merge tried), on the final charts only.
            if options.method == Method::Arap
                && lscm_valid
                && within_bound(chart, pos, &uv, options)
            {
                return Some(Found { uv, arap_pending: true });
            }
            match options.method {
                Method::Lscm | Method::Bff => lscm_valid.then_some(uv)?,
                Method::Arap => match arap::arap(chart, pos, &uv, options.arap_iterations)
                    .ok()
                    .and_then(|mut run| valid_untangled(chart, pos, &mut run.uv).then_some(run))
                {
                    Some(run) => {
                        counters.arap_iterations += run.iterations;
                        run.uv
                    }
                    None => {
                        lscm_valid.then_some(())?;
                        counters.arap_fallbacks += 1;
                        uv
                    }
                },
            }
        }
    };
    within_bound(chart, pos, &uv, options).then_some(Found { uv, arap_pending: false })
}

/// Whether the stretch max(σ₁, 1/σ₂) of 95 % of the chart's area is within the bound.
fn within_bound(
    chart: &ChartMesh,
    pos: &[Vector3<f64>],
    uv: &[Vector2<f64>],
    options: &LayoutOptions,
) -> bool {
    let s = area_scale(chart, pos, uv);
    let m = FaceMeasures::new(chart, pos, uv, s);
    let stretch = Stat::of(&m.stretch(), &m.area, 1e12);
    stretch.p95 <= options.max_stretch
}

/// ARAP (math.md §11.4) on the charts kept with LSCM's map: its map where it is valid and
/// within the stretch bound, LSCM's otherwise (counted as a fallback).
fn finish_arap(flats: &mut [Flat], mesh: &Mesh, options: &LayoutOptions, counters: &mut Counters) {
    for flat in flats.iter_mut().filter(|f| f.arap_pending) {
        let (chart, pos) = (&flat.chart, flat.chart.positions(mesh));
        match arap::arap(chart, &pos, &flat.uv, options.arap_iterations) {
            Ok(mut run) => {
                if valid_untangled(chart, &pos, &mut run.uv)
                    && within_bound(chart, &pos, &run.uv, options)
                {
                    counters.arap_iterations += run.iterations;
                    flat.uv = run.uv;
                } else {
                    counters.arap_fallbacks += 1;
                }
            }
            Err(_) => counters.arap_fallbacks += 1,
        }
        flat.arap_pending = false;
    }
}

/// Whether the map is valid, after untangling its small folds ([`untangle`]) when it is not
/// valid as it is.
fn valid_untangled(chart: &ChartMesh, pos: &[Vector3<f64>], uv: &mut [Vector2<f64>]) -> bool {
    invalid(chart, uv).is_none()
        || (untangle::untangle(chart, pos, uv) && invalid(chart, uv).is_none())
}

/// Area-weighted mean of the face normals, as a length in [0, 1]: 1 for a flat chart, about
/// 0.5 for a hemisphere, near 0 for a closed surface.
fn normal_spread(faces: &[u32], mesh: &Mesh) -> f64 {
    let (mut sum, mut area) = (Vector3::zeros(), 0.0);
    for &f in faces {
        let [a, b, c] = mesh.face_positions(f as usize);
        let w = (b - a).cross(&(c - a));
        if w.iter().all(|x| x.is_finite()) {
            sum += w;
            area += w.norm();
        }
    }
    if area > 0.0 {
        sum.norm() / area
    } else {
        0.0
    }
}

/// Whether a chart is worth flattening as it is: a disk, a single triangle, or a planar
/// chart with holes whose normals stay within about a hemisphere (a closed part with a few
/// holes is not tried: it cannot flatten within the stretch bound).
fn worth_flattening(chart: &ChartMesh, mesh: &Mesh) -> bool {
    chart.is_disk()
        || chart.tris.len() == 1
        || (chart.is_planar() && normal_spread(&chart.faces, mesh) >= PLANAR_MIN_SPREAD)
}

/// [`normal_spread`] a chart with holes needs before it is flattened as it is.
const PLANAR_MIN_SPREAD: f64 = 0.5;

/// Merges charts into neighbours while the union still flattens (valid, within the stretch
/// bound): smallest charts first (those of at most `cap` faces), each tried against its
/// neighbours in order of shared edges, passes repeated until none merges.
#[allow(clippy::too_many_arguments)]
fn merge_charts(
    accepted: &mut Vec<Flat>,
    mesh: &Mesh,
    he: &HalfEdges,
    ctx: &mut MergeContext<'_>,
    options: &LayoutOptions,
    counters: &mut Counters,
    cap: usize,
) -> usize {
    let mut merges = 0;
    let nf = mesh.num_faces();
    let mut owner = vec![usize::MAX; nf];
    for (k, Flat { chart: c, .. }) in accepted.iter().enumerate() {
        for &f in &c.faces {
            owner[f as usize] = k;
        }
    }
    let mut alive = vec![true; accepted.len()];
    let mut tried: std::collections::HashSet<(usize, usize, usize, usize)> = Default::default();
    for _pass in 0..8 {
        let mut merged_any = false;
        let mut order: Vec<usize> = (0..accepted.len()).filter(|&k| alive[k]).collect();
        order.sort_by_key(|&k| (accepted[k].chart.faces.len(), k));
        for a in order {
            if !alive[a] || accepted[a].chart.faces.len() > cap {
                continue;
            }
            let mut shared: std::collections::BTreeMap<usize, usize> = Default::default();
            for &f in &accepted[a].chart.faces {
                for c in 0..3 {
                    if let Some(t) = he.twin(3 * f + c) {
                        let b = owner[(t / 3) as usize];
                        if b != a && b != usize::MAX {
                            *shared.entry(b).or_default() += 1;
                        }
                    }
                }
            }
            let mut nb: Vec<(usize, usize)> = shared.into_iter().collect();
            nb.sort_by(|x, y| y.1.cmp(&x.1).then(x.0.cmp(&y.0)));
            for &(b, _) in nb.iter().take(3) {
                let key = (a, accepted[a].chart.faces.len(), b, accepted[b].chart.faces.len());
                if !tried.insert(key) {
                    continue;
                }
                let mut faces = accepted[b].chart.faces.clone();
                faces.extend_from_slice(&accepted[a].chart.faces);
                let id = *ctx.next_id;
                *ctx.next_id += 1;
                for (i, &f) in faces.iter().enumerate() {
                    ctx.tag[f as usize] = id;
                    ctx.pos_in[f as usize] = i as u32;
                }
                let chart = ChartMesh::new(&faces, he, mesh, ctx.tag, ctx.pos_in, id);
                if !worth_flattening(&chart, mesh) {
                    continue;
                }
                let pos = chart.positions(mesh);
                if let Some(found) = flatten_chart(&chart, &pos, options, counters) {
                    for &f in &accepted[a].chart.faces {
                        owner[f as usize] = b;
                    }
                    let arap_pending = found.arap_pending;
                    accepted[b] = Flat { chart, uv: found.uv, arap_pending };
                    alive[a] = false;
                    merged_any = true;
                    merges += 1;
                    break;
                }
            }
        }
        if !merged_any {
            break;
        }
    }
    let mut k = 0;
    accepted.retain(|_| {
        k += 1;
        alive[k - 1]
    });
    merges
}

/// The region bookkeeping of [`flatten`] that [`merge_charts`] shares.
struct MergeContext<'a> {
    tag: &'a mut Vec<u32>,
    pos_in: &'a mut Vec<u32>,
    next_id: &'a mut u32,
}

/// Charts of at most this fraction of the mesh's faces are merged into neighbours (the
/// larger ones only receive).
pub const MERGE_FRACTION: f64 = 0.05;

/// Makes a UV layout for `mesh` (see the module documentation).
///
/// ```
/// use grainline::layout::{flatten, LayoutOptions};
/// // An open cylinder is an annulus, not a disk: it is cut into charts, and as it is
/// // developable, each chart is flattened without changing any length.
/// let mut tube = grainline::generate::cylinder(30.0, 80.0, 32, 8);
/// tube.uv = None;
/// let layout = flatten(&tube, &LayoutOptions::default())?;
/// assert!(layout.report.charts > 1);
/// assert!(layout.report.edge_length_error.max < 1e-9);
/// assert_eq!(layout.report.flipped_faces, 0);
/// # Ok::<(), grainline::Error>(())
/// ```
pub fn flatten(mesh: &Mesh, options: &LayoutOptions) -> Result<Layout> {
    let start = Instant::now();
    options.validate()?;
    let nf = mesh.num_faces();
    if nf == 0 {
        return Err(Error::EmptyMesh {
            path: "layout".into(),
            message: "no faces to flatten".into(),
        });
    }
    let he = HalfEdges::new(mesh.num_vertices(), &mesh.faces)?;
    let normals = charts::face_normals(mesh);
    let crease_cos = options.crease_angle_deg.to_radians().cos();
    let smooth = charts::smoothed_normals(mesh, &he, charts::NORMAL_SMOOTHING, crease_cos);
    let cone_cos = options.cone_angle_deg.to_radians().cos();
    let mut tag = vec![u32::MAX; nf];
    let mut pos_in = vec![0u32; nf];
    let mut next_id = 0u32;
    let mut cuts = Cuts::default();
    let mut counters = Counters::default();
    let charting = Charting {
        mesh,
        he: &he,
        options,
        normals: &normals,
        smooth: &smooth,
        crease_cos,
        cone_cos,
    };
    let mut ctx = MergeContext { tag: &mut tag, pos_in: &mut pos_in, next_id: &mut next_id };
    let mut accepted = charting.cut_into_charts(&mut ctx, &mut cuts, &mut counters)?;

    // Merge small charts into their neighbours while the unions flatten.
    let cap = (MERGE_FRACTION * nf as f64) as usize;
    cuts.merges = merge_charts(&mut accepted, mesh, &he, &mut ctx, options, &mut counters, cap);
    finish_arap(&mut accepted, mesh, options, &mut counters);
    // Pack at one scale, then measure.
    let mut uvs: Vec<Vec<Vector2<f64>>> = accepted.iter().map(|f| f.uv.clone()).collect();
    let factor = pack::pack(&mut uvs, options.gap);
    let uv_scale = 1.0 / factor;
    let m = measure(mesh, &accepted, &uvs, uv_scale);
    let (seam_edges, seam_length) = seams(mesh, &he, &m.face_chart);
    let cap = 1e12;
    let report = LayoutReport {
        method: options.method,
        charts: accepted.len(),
        largest_chart_faces: m.largest,
        seam_edges,
        seam_length,
        area_distortion: Stat::of(&m.area_d, &m.weights, cap),
        angle_distortion: Stat::of(&m.angle_d, &m.weights, cap),
        angle_error_deg: Stat::of(&m.angle_e, &m.weights, 180.0),
        edge_length_error: Stat::of(&m.edge_e, &m.edge_w, cap),
        flipped_faces: m.flipped,
        arap_fallbacks: counters.arap_fallbacks,
        bff_fallbacks: counters.bff_fallbacks,
        bff_not_disk: counters.bff_not_disk,
        bff_harmonic: counters.bff_harmonic,
        arap_iterations: counters.arap_iterations,
        cuts,
        uv_scale,
        seconds: start.elapsed().as_secs_f64(),
    };
    let Measures { values, corners, face_chart, .. } = m;
    Ok(Layout { uv: CornerAttribute { values, corners }, face_chart, report })
}

/// What the chart cutting of [`flatten`] reads: the mesh, its face normals (for creases) and
/// smoothed normals (for normal cones), and the two angles' cosines.
struct Charting<'a> {
    mesh: &'a Mesh,
    he: &'a HalfEdges,
    options: &'a LayoutOptions,
    normals: &'a [Vector3<f64>],
    smooth: &'a [Vector3<f64>],
    crease_cos: f64,
    cone_cos: f64,
}

impl Charting<'_> {
    /// Cuts the mesh's edge-connected pieces into charts until each flattens: the charts and
    /// their UVs, in the order accepted.
    fn cut_into_charts(
        &self,
        ctx: &mut MergeContext,
        cuts: &mut Cuts,
        counters: &mut Counters,
    ) -> Result<Vec<Flat>> {
        let (mesh, he, options) = (self.mesh, self.he, self.options);
        let nf = mesh.num_faces();
        // The mesh's edge-connected pieces.
        let all: Vec<u32> = (0..nf as u32).collect();
        ctx.tag.iter_mut().for_each(|t| *t = 0);
        *ctx.next_id += 1;
        let mut queue: VecDeque<Region> = charts::pieces(&all, he, ctx.tag, 0, |_| true)
            .into_iter()
            .map(|faces| Region { faces, next_cut: 0 })
            .collect();
        // Whether the part is noisy (charts::NOISE_FRACTION): its sharp creases' pieces.
        let crease_pieces = charts::pieces(&all, he, ctx.tag, 0, |h| self.joins_across(h));
        let noisy = charts::is_noisy(&crease_pieces, nf);
        let mut accepted: Vec<Flat> = Vec::new();
        while let Some(region) = queue.pop_front() {
            let id = *ctx.next_id;
            *ctx.next_id += 1;
            for (i, &f) in region.faces.iter().enumerate() {
                ctx.tag[f as usize] = id;
                ctx.pos_in[f as usize] = i as u32;
            }
            let chart = ChartMesh::new(&region.faces, he, mesh, ctx.tag, ctx.pos_in, id);
            if worth_flattening(&chart, mesh) {
                let pos = chart.positions(mesh);
                if let Some(found) = flatten_chart(&chart, &pos, options, counters) {
                    let arap_pending = found.arap_pending;
                    accepted.push(Flat { chart, uv: found.uv, arap_pending });
                    continue;
                }
            }
            if region.faces.len() == 1 {
                return Err(Error::Numerical {
                    stage: "layout",
                    message: format!("face {} cannot be flattened", region.faces[0]),
                });
            }
            let (pieces, cut) = self.cut_region(&region, ctx.tag, ctx.pos_in, id, noisy, cuts);
            let pieces = if noisy {
                charts::unwrap_fans(pieces, &region.faces, mesh, he, ctx.tag, ctx.pos_in, id)
            } else {
                pieces
            };
            queue.extend(pieces.into_iter().map(|faces| Region { faces, next_cut: cut }));
        }
        Ok(accepted)
    }

    /// Whether the faces on either side of half-edge `h` are on the same side of every sharp
    /// crease (their normals' angle is at most the crease angle).
    fn joins_across(&self, h: u32) -> bool {
        let (f, g) = (h / 3, self.he.twin(h).map_or(h / 3, |t| t / 3));
        self.normals[f as usize].dot(&self.normals[g as usize]) >= self.crease_cos
    }

    /// Cuts the region tagged `id`: creases, then normal cones, then bisection (each only
    /// when it splits), from the region's next cut on. The pieces and their next cut.
    fn cut_region(
        &self,
        region: &Region,
        tag: &[u32],
        pos_in: &[u32],
        id: u32,
        noisy: bool,
        cuts: &mut Cuts,
    ) -> (Vec<Vec<u32>>, u8) {
        let he = self.he;
        // Cut: creases, then normal cones, then bisection (each only when it splits).
        let mut cut = region.next_cut;
        let mut pieces = Vec::new();
        if cut == 0 {
            pieces = charts::pieces(&region.faces, he, tag, id, |h| self.joins_across(h));
            if noisy {
                pieces = charts::absorb_small(pieces, &region.faces, he, tag, pos_in, id);
            }
            cut = 1;
            if pieces.len() > 1 {
                cuts.creases += 1;
            }
        }
        if pieces.len() <= 1 && cut == 1 {
            pieces = charts::cone_pieces(&region.faces, he, self.smooth, tag, id, self.cone_cos);
            cut = 2;
            if pieces.len() > 1 {
                cuts.cones += 1;
            }
        }
        if pieces.len() <= 1 {
            pieces = charts::bisect(&region.faces, he, tag, id);
            cut = 2;
            cuts.bisections += 1;
        }
        (pieces, cut)
    }
}

/// The corner UVs of the packed charts and the per-face measures of [`measure`].
struct Measures {
    values: Vec<Vector2<f64>>,
    corners: Vec<[u32; 3]>,
    face_chart: Vec<u32>,
    area_d: Vec<f64>,
    angle_d: Vec<f64>,
    angle_e: Vec<f64>,
    weights: Vec<f64>,
    edge_e: Vec<f64>,
    edge_w: Vec<f64>,
    flipped: usize,
    largest: usize,
}

/// The charts' UVs (`uvs`, scaled by `uv_scale`) gathered as corner values, and every face's
/// area and angle distortion, angle error and edges' length errors, chart by chart.
fn measure(mesh: &Mesh, accepted: &[Flat], uvs: &[Vec<Vector2<f64>>], uv_scale: f64) -> Measures {
    let nf = mesh.num_faces();
    let mut values = Vec::new();
    let mut corners = vec![[0u32; 3]; nf];
    let mut face_chart = vec![0u32; nf];
    let (mut area_d, mut angle_d, mut angle_e, mut weights) =
        (Vec::new(), Vec::new(), Vec::new(), Vec::new());
    let (mut edge_e, mut edge_w) = (Vec::new(), Vec::new());
    let mut flipped = 0;
    let mut largest = 0;
    for (k, (Flat { chart, .. }, uv)) in accepted.iter().zip(uvs).enumerate() {
        let offset = values.len() as u32;
        values.extend_from_slice(uv);
        largest = largest.max(chart.faces.len());
        let pos = chart.positions(mesh);
        let m = FaceMeasures::new(chart, &pos, uv, uv_scale);
        for (i, (&f, t)) in chart.faces.iter().zip(&chart.tris).enumerate() {
            corners[f as usize] = t.map(|v| v + offset);
            face_chart[f as usize] = k as u32;
            let (s1, s2, det) = m.sigma[i];
            flipped += (det <= 0.0 || det.is_nan()) as usize;
            let a = s1 * s2;
            area_d.push(a.max(1.0 / a));
            angle_d.push(s1 / s2);
            weights.push(m.area[i]);
            let p = t.map(|v| pos[v as usize]);
            let q = t.map(|v| uv[v as usize] * uv_scale);
            let mut err = 0.0;
            for c in 0..3 {
                let (a3, b3) = (p[(c + 1) % 3] - p[c], p[(c + 2) % 3] - p[c]);
                let (a2, b2) = (q[(c + 1) % 3] - q[c], q[(c + 2) % 3] - q[c]);
                let t3 = a3.cross(&b3).norm().atan2(a3.dot(&b3));
                let t2 = a2.perp(&b2).atan2(a2.dot(&b2));
                err += (t2 - t3).abs().to_degrees() / 3.0;
                let l3 = a3.norm();
                if l3 > 0.0 {
                    edge_e.push(((a2.norm() - l3) / l3).abs());
                    edge_w.push(l3);
                }
            }
            angle_e.push(err);
        }
    }
    Measures {
        values,
        corners,
        face_chart,
        area_d,
        angle_d,
        angle_e,
        weights,
        edge_e,
        edge_w,
        flipped,
        largest,
    }
}

/// The seams: the number of edges between two charts and their total length.
fn seams(mesh: &Mesh, he: &HalfEdges, face_chart: &[u32]) -> (usize, f64) {
    let nf = mesh.num_faces();
    let (mut seam_edges, mut seam_length) = (0, 0.0);
    for h in 0..(3 * nf) as u32 {
        if let Some(t) = he.twin(h) {
            if h < t && face_chart[(h / 3) as usize] != face_chart[(t / 3) as usize] {
                seam_edges += 1;
                seam_length += (mesh.positions[he.dest(h) as usize]
                    - mesh.positions[he.origin(h) as usize])
                    .norm();
            }
        }
    }
    (seam_edges, seam_length)
}
