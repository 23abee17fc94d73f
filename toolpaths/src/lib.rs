//! # grainline-toolpaths
//!
//! Evenly spaced brush strokes from a direction field on a triangulated UV domain, exported
//! as SVG, G-code and JSON. A pure 2D library: it knows nothing of the solver that produced
//! the field.
//!
//! Pipeline: [`FieldMesh`] → [`Domain::new`] → [`place_strokes`] (Jobard–Lefer placement of
//! streamlines traced with Dormand–Prince 5(4)) → [`plan_toolpath`] (simplify, orient,
//! order, leads) → [`write_svg`], [`write_gcode`], [`strokes_json`]. [`generate`] runs all of
//! it and fills a [`Report`].

mod error;
pub mod field;
mod geom;
mod grid;
mod locate;
mod mesh;
pub mod trace;

pub use error::{Result, ToolpathError};
pub use field::{singularities, Singularity};
pub use geom::{Metric, Vec2, Vec3};
pub use mesh::{Directions, Domain, FaceId, FieldMesh, SeamPair, Symmetry, VertexId};
pub use trace::{trace_streamline, StopReason, Stroke, TraceOptions};
pub mod place;
mod spacing;
pub use place::{place_strokes, Placement, PlacementOptions};
pub use spacing::Spacing;
