//! # grainline
//!
//! Design how a brushed-metal part should *shine*, and get the brushing toolpaths that make it
//! shine that way.
//!
//! The library follows Raymond et al. 2014, "Optimizing BRDF Orientations for the Manipulation
//! of Anisotropic Highlights": the tangent ℓ of the highlight curves produced by a grain field u
//! (Eq. 4/7), and its inversion. The layers depend on each other in one direction:
//! `mesh` ← `geometry` ← `highlight`.

pub mod error;
pub mod generate;
pub mod geometry;
pub mod mesh;

pub use error::{Error, Result};
