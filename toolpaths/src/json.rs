//! Strokes JSON: the ordered, oriented strokes for other tools (serde).
//!
//! ```json
//! { "format": "grainline-strokes", "version": 1, "units": "mm",
//!   "width": 1.0, "d_sep": 0.9, "spacing": "surface",
//!   "strokes": [ { "index": 0, "stroke": 12, "reversed": false,
//!                  "uv": [[[u, v], ...]], "xyz": [[[x, y, z], ...]] | null,
//!                  "length_mm": 42.1, "start": "boundary", "end": "too_close",
//!                  "closed": false } ] }
//! ```
//! `uv`/`xyz` hold one polyline per piece (pieces are split at UV seam jumps), simplified
//! with the plan's tolerance. Numbers are rounded to 1e-6 mm.

use serde::{Deserialize, Serialize};

use crate::error::{Result, ToolpathError};
use crate::geom::{Vec2, Vec3};
use crate::place::Placement;
use crate::plan::Plan;
use crate::spacing::Spacing;
use crate::trace::StopReason;

/// One stroke in the JSON file.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct StrokeRecord {
    /// Position in cutting order.
    pub index: usize,
    /// Index of the traced stroke in the placement.
    pub stroke: usize,
    /// Whether it runs against its tracing order.
    pub reversed: bool,
    /// UV polylines (one per seam piece).
    pub uv: Vec<Vec<Vec2>>,
    /// 3D polylines when the input has a lift.
    pub xyz: Option<Vec<Vec<Vec3>>>,
    /// Surface length, mm.
    pub length_mm: f64,
    /// Why the first point stopped.
    pub start: StopReason,
    /// Why the last point stopped.
    pub end: StopReason,
    /// Closed loop.
    pub closed: bool,
    /// A gap-filling stroke ([`crate::Stroke::fill`]); written only when true.
    #[serde(default, skip_serializing_if = "std::ops::Not::not")]
    pub fill: bool,
}

/// The whole strokes file.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct StrokesFile {
    /// Always `grainline-strokes`.
    pub format: String,
    /// Format version (1).
    pub version: u32,
    /// Always `mm`.
    pub units: String,
    /// Brush width, mm.
    pub width: f64,
    /// Stroke spacing, mm.
    pub d_sep: f64,
    /// Where spacing was measured.
    pub spacing: Spacing,
    /// Strokes in cutting order.
    pub strokes: Vec<StrokeRecord>,
}

fn r6(x: f64) -> f64 {
    let y = (x * 1e6).round() / 1e6;
    if y == 0.0 {
        0.0
    } else {
        y
    }
}

/// Build the strokes file from a plan.
pub fn strokes_file(placement: &Placement, plan: &Plan) -> StrokesFile {
    let strokes = plan
        .passes
        .iter()
        .enumerate()
        .map(|(i, p)| StrokeRecord {
            index: i,
            stroke: p.stroke,
            reversed: p.reversed,
            uv: p.uv.iter().map(|l| l.iter().map(|q| q.map(r6)).collect()).collect(),
            xyz: p
                .xyz
                .as_ref()
                .map(|x| x.iter().map(|l| l.iter().map(|q| q.map(r6)).collect()).collect()),
            length_mm: r6(p.length),
            start: p.stops[0],
            end: p.stops[1],
            closed: p.stops[1] == StopReason::ClosedLoop,
            fill: placement.strokes.get(p.stroke).is_some_and(|s| s.fill),
        })
        .collect();
    StrokesFile {
        format: "grainline-strokes".into(),
        version: 1,
        units: "mm".into(),
        width: placement.width,
        d_sep: placement.d_sep,
        spacing: placement.spacing,
        strokes,
    }
}

/// The strokes file as pretty-printed JSON.
pub fn strokes_json(placement: &Placement, plan: &Plan) -> Result<String> {
    let file = strokes_file(placement, plan);
    let mut s =
        serde_json::to_string_pretty(&file).map_err(|e| ToolpathError::Serialize(e.to_string()))?;
    s.push('\n');
    Ok(s)
}
