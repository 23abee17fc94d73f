//! Coverage of the surface by the strokes: the fraction of the surface within `d_sep / 2`
//! of a stroke, the largest gap, and a raster gap map for previews.
//!
//! The UV bounding box is sampled at pixel centres (pitch `resolution` mm on the surface,
//! converted to UV with the median stretch); each pixel inside the domain gets its distance
//! to the nearest stroke (same metric as the spacing), capped at `4 d_sep`. Coverage is the
//! area-weighted fraction (weight = UV pixel area × `√(EG − F²)`) of pixels with distance ≤
//! `d_sep / 2`; the largest gap is twice the largest distance (the diameter of the largest
//! stroke-free disc centred on a pixel), and `largest_gap_capped` says when that distance
//! reached the cap (the true gap is then at least the value given).
//!
//! Each chart is rasterized on its own (pixels of the common raster inside the chart's UV
//! box, located in that chart only), so charts that overlap in UV are each measured; the gap
//! map keeps the larger distance where charts overlap.

use serde::{Deserialize, Serialize};

use crate::error::{positive, Result};
use crate::geom::Vec2;
use crate::locate::{walk, Walk};
use crate::mesh::Domain;
use crate::place::{Placement, RunOuts};
use crate::spacing::{typical_stretch, StrokeIndex};

/// Most pixels a gap map may have; the pitch grows past this.
const MAX_PIXELS: f64 = 4.0e6;

/// Coverage options.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(default)]
#[serde(deny_unknown_fields)]
#[cfg_attr(feature = "schemars", derive(schemars::JsonSchema))]
pub struct CoverageOptions {
    /// Pixel pitch, mm; `None` means `d_sep / 4`.
    pub resolution: Option<f64>,
    /// Keep the raster in the result. Default true.
    pub keep_map: bool,
}

impl CoverageOptions {
    /// Reject a non-positive or non-finite `resolution`.
    pub fn validate(&self) -> Result<()> {
        if let Some(r) = self.resolution {
            positive("coverage.resolution", r)?;
        }
        Ok(())
    }
}

impl Default for CoverageOptions {
    fn default() -> Self {
        CoverageOptions { resolution: None, keep_map: true }
    }
}

/// A raster over the UV bounding box: distance (mm) from each pixel centre to the nearest
/// stroke, row-major from the `origin` corner (min U, min V), `-1` outside the domain.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct GapMap {
    /// UV of the corner of pixel (0, 0).
    pub origin: Vec2,
    /// Pixel size in UV units.
    pub pixel: f64,
    /// Columns.
    pub width: usize,
    /// Rows.
    pub height: usize,
    /// Distances, mm (capped at `4 d_sep`); `-1` outside.
    pub distance: Vec<f32>,
}

/// Coverage figures.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct Coverage {
    /// Area fraction of the surface within `d_sep / 2` of a stroke, in [0, 1].
    pub fraction: f64,
    /// Diameter of the largest stroke-free disc, mm (capped at `8 d_sep`).
    pub largest_gap: f64,
    /// UV centre of that disc.
    pub largest_gap_at: Vec2,
    /// Whether `largest_gap` is the capped value (the stroke-free disc is at least that
    /// wide; there may be no stroke at all nearby).
    #[serde(default)]
    pub largest_gap_capped: bool,
    /// The raster, if kept.
    pub map: Option<GapMap>,
}

/// Measure coverage of the domain by the placed strokes.
pub fn coverage(dom: &Domain, placement: &Placement, o: &CoverageOptions) -> Result<Coverage> {
    let d_sep = placement.d_sep;
    let res = positive("coverage.resolution", o.resolution.unwrap_or(d_sep / 4.0))?;
    let mut index = StrokeIndex::new(dom, d_sep, placement.spacing);
    for s in &placement.strokes {
        index.insert(dom, s);
    }
    // The brush's band along the run-outs past chart edges counts where it lies inside the
    // domain (only pixels inside are measured).
    let metric = |f: u32| index.metric(dom, f);
    let run_outs = RunOuts::of(dom, &placement.strokes, d_sep, placement.spacing, metric);
    let b = dom.bbox();
    let (w, h) = (b[1][0] - b[0][0], b[1][1] - b[0][1]);
    let mut pixel = res / typical_stretch(dom, placement.spacing);
    pixel = pixel.max((w * h / MAX_PIXELS).sqrt());
    let nx = ((w / pixel).ceil() as usize).max(1);
    let ny = ((h / pixel).ceil() as usize).max(1);
    let cap = 4.0 * d_sep;
    let mut dist = vec![-1f32; nx * ny];
    let (mut covered, mut total) = (0.0, 0.0);
    let mut worst = (0.0, [0.0, 0.0]);
    for (chart, cb) in dom.chart_bbox.iter().enumerate() {
        let chart = Some(chart as u32);
        let span = |lo: f64, hi: f64, o: f64, n: usize| {
            let a = (((lo - o) / pixel).floor().max(0.0) as usize).min(n - 1);
            let b = (((hi - o) / pixel).ceil().max(0.0) as usize).min(n);
            (a, b.max(a + 1))
        };
        let (i0, i1) = span(cb[0][0], cb[1][0], b[0][0], nx);
        let (j0, j1) = span(cb[0][1], cb[1][1], b[0][1], ny);
        let mut hint: Option<(u32, Vec2)> = None;
        for j in j0..j1 {
            for i in i0..i1 {
                let p = [b[0][0] + (i as f64 + 0.5) * pixel, b[0][1] + (j as f64 + 0.5) * pixel];
                let face = match hint {
                    Some((f, q)) => match walk(dom, f, q, p) {
                        Walk::Inside { face, .. } => Some(face),
                        Walk::Exit { .. } => dom.grid.locate_in(dom, p, chart).map(|x| x.0),
                    },
                    None => dom.grid.locate_in(dom, p, chart).map(|x| x.0),
                };
                let Some(f) = face else { continue };
                hint = Some((f, p));
                // Expanding search: most pixels have a stroke within d_sep / 2.
                let mut r = 0.5 * d_sep;
                let d = loop {
                    let d = index
                        .nearest(dom, p, f, r)
                        .min(run_outs.distance(dom.chart[f as usize], p));
                    if d < r || r >= cap {
                        break d;
                    }
                    r = (2.0 * r).min(cap);
                };
                let px = &mut dist[j * nx + i];
                *px = px.max(d as f32);
                let wgt = dom.metric[f as usize].area_factor();
                total += wgt;
                if d <= 0.5 * d_sep {
                    covered += wgt;
                }
                if d > worst.0 {
                    worst = (d, p);
                }
            }
        }
    }
    Ok(Coverage {
        fraction: if total > 0.0 { covered / total } else { 0.0 },
        largest_gap: 2.0 * worst.0,
        largest_gap_at: worst.1,
        largest_gap_capped: worst.0 >= cap,
        map: o.keep_map.then_some(GapMap {
            origin: b[0],
            pixel,
            width: nx,
            height: ny,
            distance: dist,
        }),
    })
}
