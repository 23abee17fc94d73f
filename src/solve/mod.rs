//! Inverting the highlight model: residuals and analytic Jacobians of the energies of the
//! optimizer (the paper's §4.3, math.md §3–4), and the sparse Levenberg–Marquardt driver.

pub mod highlight_term;
pub mod lm;
pub mod smoothness;

pub use highlight_term::{HighlightTerm, VertexJacobian};
pub use lm::{solve, LmOptions, LmResult, StopReason};
