//! # grainline-toolpaths
//!
//! Evenly spaced brush strokes from a direction field on a triangulated UV domain, exported
//! as SVG, G-code and JSON. A pure 2D library: it knows nothing of the solver that produced
//! the field.
//!
//! Pipeline: [`FieldMesh`] → [`Domain::new`] → [`place_strokes`] (Jobard–Lefer placement of
//! streamlines traced with Dormand–Prince 5(4) in surface arc length) → [`coverage()`] →
//! [`plan_toolpath`] (orient, simplify/arcs, order, leads, Z) → [`write_svg`],
//! [`write_gcode`], [`strokes_json`]. [`generate`] runs all of it and fills a [`Report`].
//!
//! Layers of the source files, bottom to top (a file uses only files of lower layers):
//!
//! 1. `error`, `geom`: errors; vectors, metrics, barycentric coordinates.
//! 2. `input`, `grid`, `buckets`, `simplify`, `snippet`, `stroke`, `tour`: the input mesh
//!    (and the surface its triangles approximate, [`SurfaceLift`]);
//!    uniform grids; point buckets; polyline simplification; spindle snippets; strokes; the
//!    stroke tour model.
//! 3. `topology`, `improve`, `bound`: adjacency, metrics and seams; tour local search;
//!    travel bounds.
//! 4. `mesh`, `order`: the validated [`Domain`]; stroke ordering.
//! 5. `field`, `locate`, `rotary`: field sampling and singularities; point location; rotary
//!    fixtures (the axis of a turned part, found or given).
//! 6. `trace`: streamline tracing.
//! 7. `spacing`: stroke-to-stroke distances.
//! 8. `place`: stroke placement.
//! 9. `budget`, `coverage`, `stroke_checks`, `surface`: work budgets; coverage; stroke
//!    checks; strokes sampled on the surface the triangles approximate.
//! 10. `plan_options`: planner options.
//! 11. `passes`: one pass from one stroke.
//! 12. `plan`: the ordered passes.
//! 13. `gcode`, `json`, `report`: G-code; JSON strokes; the report.
//! 14. `svg_out`: SVG.
//! 15. `job`: the whole pipeline ([`generate`]).
//!
//! ```
//! use grainline_toolpaths::*;
//! // A 4 × 2 mm sheet of two triangles with a constant field along +V.
//! let uv = vec![[0.0, 0.0], [4.0, 0.0], [4.0, 2.0], [0.0, 2.0]];
//! let tris = vec![[0, 1, 2], [0, 2, 3]];
//! let mesh = FieldMesh::new(uv, tris, Directions::Angles(vec![1.5708; 4]), Symmetry::Line);
//! let opts = JobOptions {
//!     placement: PlacementOptions::new(1.0, 0.0),
//!     gcode: Some(GcodeOptions::default()),
//!     ..Default::default()
//! };
//! let out = generate(mesh, &opts).unwrap();
//! // Strokes at u = 0, 1, 2, 3, 4 (the first seed is the centre of the sheet).
//! assert_eq!(out.report.stroke_count, 5);
//! assert!(out.gcode.unwrap().contains("G21 G90 G17"));
//! ```

#![warn(missing_docs)]

mod bound;
mod buckets;
pub mod budget;
mod coverage;
mod error;
mod field;
mod gcode;
mod geom;
mod grid;
mod improve;
mod input;
mod job;
mod json;
mod locate;
mod mesh;
mod order;
mod passes;
mod place;
mod plan;
mod plan_options;
mod report;
pub mod rotary;
mod simplify;
mod snippet;
mod spacing;
mod stroke;
mod stroke_checks;
mod surface;
mod svg_out;
mod topology;
mod tour;
mod trace;

pub use bound::{travel_bound, BoundOptions, TravelBound};
pub use budget::{PlacementEstimate, MAX_NEIGHBOURS, MAX_STROKE_SAMPLES};
pub use coverage::{coverage, Coverage, CoverageOptions, GapMap};
pub use error::{Result, ToolpathError};
pub use field::{singularities, Singularity};
pub use gcode::{
    check_safety, cycle_time, write_gcode, CycleTime, Dialect, Envelope, GcodeOptions, LengthUnit,
    Spindle, DEFAULT_RAPID_MM_MIN,
};
pub use geom::{segment_distance, Metric, Vec2, Vec3};
pub use input::{SurfaceHook, SurfaceLift};
pub use job::{generate, JobOptions, JobOutput, LENGTH_DEFAULTS_MM};
pub use json::{strokes_file, strokes_json, StrokeRecord, StrokesFile};
pub use mesh::{Directions, Domain, FaceId, FieldMesh, SeamPair, Symmetry, VertexId};
pub use order::{order_strokes, tour_length, Direction, Ends, OrderOptions, Ordering};
pub use place::{place_strokes, Placement, PlacementOptions};
pub use plan::{
    ordering_ends, plan_toolpath, MoveKind, Pass, Plan, PlanOptions, Sheets, TiltPolicy, ZMode,
};
pub use report::{PhaseTime, Report};
pub use rotary::{fit_axis, rotary_move_length, AxisFit, AxisSpec, Fixture, RotaryAxis};
pub use simplify::{fit_moves, rdp_indices, Segment};
pub use spacing::Spacing;
pub use stroke_checks::{
    check_strokes, cut_tight_ends, CheckSample, LockFigures, LockProbe, Share, SplayFigures,
    StrokeCheckOptions, StrokeChecks, StrokePlace, TightEndCuts, TurningFigures,
};
pub use svg_out::{write_svg, SvgOptions};
pub use trace::{trace_streamline, StopReason, Stroke, TraceOptions};
