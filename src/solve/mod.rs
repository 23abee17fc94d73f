//! Inverting the highlight model: residuals and analytic Jacobians of the energies of the
//! optimizer (the paper's §4.3, math.md §3–4). The Levenberg–Marquardt driver builds on these.

pub mod highlight_term;

pub use highlight_term::{HighlightTerm, VertexJacobian};
