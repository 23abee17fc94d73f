//! # grainline
//!
//! Design how a brushed-metal part should *shine*, and get the brushing toolpaths that make it
//! shine that way.
//!
//! The library follows Raymond et al. 2014, "Optimizing BRDF Orientations for the Manipulation
//! of Anisotropic Highlights": the tangent ℓ of the highlight curves produced by a grain field u
//! (Eq. 4/7), and its inversion. The layers depend on each other in one direction:
//! `mesh` ← `geometry` ← `highlight` ← `edit` / `solve` ← `pipeline`; `render` and `uvfield`
//! (into the `grainline-toolpaths` crate) consume a field, `scene` describes a whole job.
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
pub mod edit;
pub mod editor;
pub mod error;
pub mod export;
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
pub mod scene;
pub mod solve;
pub mod svg_read;
pub mod uvfield;

pub use error::{Error, Result};

/// Parses `X,Y,Z` (three finite numbers separated by commas) for the option `name`.
pub fn parse_vec3(name: &str, s: &str) -> Result<nalgebra::Vector3<f64>> {
    let parts: Vec<&str> = s.split(',').map(str::trim).collect();
    let bad = || Error::invalid_arg(name, format!("{s:?}: expected three numbers X,Y,Z"));
    if parts.len() != 3 {
        return Err(bad());
    }
    let mut v = [0.0; 3];
    for (k, p) in parts.iter().enumerate() {
        v[k] = p.parse::<f64>().map_err(|_| bad())?;
        if !v[k].is_finite() {
            return Err(Error::invalid_arg(name, format!("{s:?}: components must be finite")));
        }
    }
    Ok(nalgebra::Vector3::new(v[0], v[1], v[2]))
}
