//! # grainline
//!
//! Design how a brushed-metal part should *shine*, and get the brushing toolpaths that make it
//! shine that way.
//!
//! The library follows Raymond et al. 2014, "Optimizing BRDF Orientations for the Manipulation
//! of Anisotropic Highlights": the tangent ℓ of the highlight curves produced by a grain field u
//! (Eq. 4/7), and its inversion.
//!
//! ## Layers
//!
//! The modules stand on each other in one direction. Bottom to top, a module uses only modules
//! of lower layers: modules of one layer do not use each other, and no modules use each other
//! in a cycle (`tests/structure.rs` reads this list and the sources, and fails on a use within
//! a layer or upward, or a cycle):
//!
//! 1. `error`, `limits`, `output`, `allocator`, `resident` — the error type, the budgets, the
//!    outputs written atomically, the allocator, the process's resident memory.
//! 2. `factor`, `cancel` — the bounded sparse Cholesky factor; long work cancelled from
//!    outside at its check points.
//! 3. `mesh` — loading (OBJ, STL, PLY), validation, topology, UV charts, refinement.
//! 4. `svg_read`, `generate` — SVG drawings read as polylines; analytic test parts.
//! 5. `geometry`, `texmap` — normals, frames, areas, connection, curvature, ∇φ, face angles;
//!    the grain as a texture in UV space (MikkTSpace frames, baking, maps read back).
//! 6. `highlight`, `layout`, `panel`, `appearance` — ℓ, the initial fields and the field's
//!    singularities; UV layouts; panels from outlines; materials, lights and BRDFs.
//! 7. `solve`, `field`, `uvfield` — the solver; FIELD.json; the grain carried into the UV
//!    layout.
//! 8. `edit` — the edit tools (they start the solver's designed grain).
//! 9. `fidelity`, `render`, `export` — did an edit land; the CPU preview; glTF.
//! 10. `scene` — the scene file.
//! 11. `pipeline` — the staged run: a plan, one file per stage, a short sequencer.
//! 12. `editor` — `grainline edit`'s server and session.
//!
//! The binary's `cli` (src/cli) sits on top and uses the library by its public paths.
//!
//! ```
//! use grainline::field::{compute_field, FieldOptions};
//! use grainline::generate;
//! use grainline::highlight::{InitialField, Lighting, View};
//! use nalgebra::Vector3;
//!
//! // A cylinder brushed around its axis, lit from above, seen from the side.
//! let mesh = generate::cylinder(30.0, 80.0, 32, 8);
//! let lighting = Lighting::new(Vector3::new(0.3, -0.5, 1.0), View::Direction(-Vector3::y()))?;
//! let mut options = FieldOptions::new(lighting);
//! options.init = InitialField::CurvatureMax;
//! let field = compute_field(&mesh, &options)?;
//! // Eq. 7: with the grain around the axis, the highlight tangents run along it (away from
//! // the rims, where the jet fit is one-sided).
//! let interior: Vec<f64> = (0..mesh.num_vertices())
//!     .filter(|&i| mesh.positions[i].z.abs() < 25.0 && field.highlight.ell[i].norm() > 1e-9)
//!     .map(|i| field.highlight.ell[i].normalize().z.abs())
//!     .collect();
//! assert!(!interior.is_empty() && interior.iter().all(|&c| c > 0.99));
//! # Ok::<(), grainline::Error>(())
//! ```

#![warn(missing_docs)]

pub mod allocator;
pub mod appearance;
pub mod cancel;
pub mod edit;
pub mod editor;
pub mod error;
pub mod export;
pub(crate) mod factor;
pub mod fidelity;
pub mod field;
pub mod generate;
pub mod geometry;
pub mod highlight;
pub mod layout;
pub mod limits;
pub mod mesh;
pub mod output;
pub mod panel;
pub mod pipeline;
pub mod render;
pub mod resident;
pub mod scene;
pub mod solve;
pub mod svg_read;
pub mod texmap;
pub mod uvfield;

pub use error::{Error, Result};
