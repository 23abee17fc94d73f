//! Inverting the highlight model: residuals and analytic Jacobians of the energies of the
//! optimizer (the paper's §4.3, math.md §3–4), the sparse Levenberg–Marquardt driver, the
//! fabrication constraints, and the entry point [`optimize()`].

pub mod branch;
mod cg;
pub mod fabrication;
pub mod face_hinge;
pub mod fill;
pub mod highlight_term;
pub mod lm;
pub mod locks;
pub mod optimize;
mod pattern;
pub mod position_term;
pub mod settings;
pub mod smoothness;
pub mod turn;

pub use fabrication::{GradientHinge, HingeKind};
pub use highlight_term::{HighlightTerm, VertexJacobian};
pub use lm::{
    solve, solve_cached, Energies, HingeOptions, Iteration, LinearSolver, LmOptions, LmResult,
    SolveCache, StopReason,
};
pub use locks::{BoundaryRelation, LockConflict, LockRegion, LockSpec, ResolvedLocks};
pub use optimize::{
    optimize, optimize_with, ConstraintViolations, OptimizeReport, OptimizeResult, OptimizeReuse,
    StartChoice,
};
pub use settings::{
    Constraints, HighlightEnergy, SolverSettings, Splay, TriangleTerm, TurningRadius,
};
// Field analysis lives with the highlight model (`crate::highlight::singularities`); the
// solver's report carries it, and its paths here stay for the library's users.
pub use crate::highlight::singularities::{self, singularities, Singularity};
