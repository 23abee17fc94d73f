//! The scene's `solver` section: [`SolverSettings`].

use schemars::JsonSchema;
use serde::{Deserialize, Serialize};

use super::locks::LockSpec;
use crate::error::fmt_num;
use crate::{Error, Result};

/// The tool's minimum turning radius: |ūᵀ∇φ| ≤ 1/radius (math.md §4).
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize, JsonSchema)]
#[serde(deny_unknown_fields)]
pub struct TurningRadius {
    /// Minimum radius of curvature of the strokes along the surface (> 0, scene units).
    pub radius: f64,
    /// Hinge weight λ_κ (> 0, dimensionless; default 10: a vertex whose streamline curvature
    /// is twice the bound costs ten 45° highlight errors).
    #[serde(default = "default_constraint_weight")]
    pub weight: f64,
}

/// Bounded splay of neighbouring strokes: |v̄ᵀ∇φ| = |div u| ≤ max (math.md §4).
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize, JsonSchema)]
#[serde(deny_unknown_fields)]
pub struct Splay {
    /// Bound s_max on |d ln(spacing)/ds| (> 0, per scene unit); ln(δ_max/δ_min)/L_stroke.
    pub max: f64,
    /// Hinge weight λ_σ (> 0, dimensionless; default 10).
    #[serde(default = "default_constraint_weight")]
    pub weight: f64,
}

/// A hinge inside the triangles (`solve::face_hinge`, issue 17), for `turning_in_triangles`
/// and `splay_in_triangles`: bounds the curvature (or the divergence) of the streamlines of
/// the field as the stroke tracer interpolates it, at four quadrature points per triangle, by
/// R/(1 − margin) (or s_max·(1 − margin)). Needs `turning_radius` (or `splay`); the vertex
/// hinge stays. On by default with its constraint.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize, JsonSchema)]
#[serde(deny_unknown_fields)]
pub struct TriangleTerm {
    /// Whether the triangle term runs (default true; `false` keeps the vertex hinge alone, as
    /// before issue 17).
    #[serde(default = "default_true")]
    pub enabled: bool,
    /// Fraction in [0, 0.5) by which the triangles are held tighter than the constraint
    /// (default 0.05: the interpolated field is bounded by R/0.95 or 0.95 s_max, so that strokes
    /// traced from it keep within the constraint with the tracer's and the sampling's errors).
    #[serde(default = "default_margin")]
    pub margin: f64,
    /// Hinge weight (> 0, dimensionless; default: the constraint's own weight).
    #[serde(default)]
    pub weight: Option<f64>,
}

fn default_margin() -> f64 {
    0.05
}

fn default_true() -> bool {
    true
}

impl Default for TriangleTerm {
    fn default() -> Self {
        TriangleTerm { enabled: true, margin: default_margin(), weight: None }
    }
}

fn default_constraint_weight() -> f64 {
    10.0
}

/// Fabrication constraints of the `solver` section.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize, JsonSchema)]
#[serde(deny_unknown_fields, default)]
pub struct Constraints {
    /// Minimum tool turning radius (default: none).
    pub turning_radius: Option<TurningRadius>,
    /// The turning radius also inside the triangles, as the tracer interpolates the field
    /// (default: on with margin 0.05 whenever `turning_radius` is given; `{"enabled": false}`
    /// keeps the vertex hinge alone). Only with `turning_radius`.
    pub turning_in_triangles: Option<TriangleTerm>,
    /// Bounded splay (default: none).
    pub splay: Option<Splay>,
    /// The splay bound also inside the triangles, on the divergence of the field as the tracer
    /// interpolates it (default: on with margin 0.05 whenever `splay` is given;
    /// `{"enabled": false}` keeps the vertex hinge alone). Only with `splay`.
    pub splay_in_triangles: Option<TriangleTerm>,
    /// Locked directions (default: none).
    pub locks: Vec<LockSpec>,
    /// Two locks on one vertex conflict when they differ by more than this (radians, modulo
    /// 2π/k; default 0.01). Conflicts are reported and resolved by their circular mean.
    pub conflict_tolerance: f64,
}

impl Default for Constraints {
    fn default() -> Self {
        Constraints {
            turning_radius: None,
            turning_in_triangles: None,
            splay: None,
            splay_in_triangles: None,
            locks: Vec::new(),
            conflict_tolerance: 0.01,
        }
    }
}

/// The `solver` section of a scene: how the grain field is optimized (the paper's §4.3).
///
/// Every field has a default; `{}` is a valid section.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize, JsonSchema)]
#[serde(deny_unknown_fields, default)]
pub struct SolverSettings {
    /// Smoothness weight λ_s (≥ 0; default 0, which turns the interleaved smoothing pass on:
    /// on spot this recovered 16 of 22 perturbed brushes exactly with the harmonic-fill start,
    /// against 1 of 10 with 1e-6 and 0 of 22 with 1e-4; docs/benchmarks.md). **Relative**: the connection Dirichlet energy
    /// Σ wᵢⱼ|…|² (scale-free) is multiplied by λ_s × the surface area, so that it scales like
    /// the highlight energy Σ Aᵢ‖Lᵢ − Lᵢ*‖² and λ_s means the same on a part in mm or in m.
    pub smoothness: f64,
    /// Iteration cap (1 to 1,000, `limits::MAX_SOLVER_ITERATIONS`; default 50).
    pub max_iterations: usize,
    /// Stop when an accepted step lowers the total energy by less than this fraction (≥ 0;
    /// default 1e-10).
    pub relative_decrease: f64,
    /// Stop when ‖Jᵀr‖∞ falls below this (≥ 0; default 1e-12).
    pub gradient_tolerance: f64,
    /// Initial Levenberg–Marquardt damping λ, relative to diag(JᵀJ) (> 0; default 1e-4).
    pub initial_damping: f64,
    /// Interleave the paper's Laplacian smoothing pass with the iterations (default: on when
    /// `smoothness` is 0, off otherwise). A pass is kept only if it does not raise the energy.
    pub interleaved_smoothing: Option<bool>,
    /// Continuation on the smoothness weight: solve first with 1000, 100 and 10 × λ_s (at most
    /// 5 iterations each), then with λ_s, each stage starting from the last (default false).
    /// Strong smoothing first keeps the solve out of the local minima of the data term where
    /// hᵀv ≈ 0 (math.md §3). Ignored when λ_s = 0.
    pub continuation: bool,
    /// Free every vertex instead of the edits' support (default false).
    pub whole_mesh: bool,
    /// Also consider the connection-harmonic fill of the free region from its fixed
    /// neighbours as a start, and start from it when its energy is lower than the given
    /// field's (default true; `solve::fill`). It keeps the solve out of the other minima of
    /// the data term (math.md §3).
    pub harmonic_start: bool,
    /// The free set is the edits' support dilated by this many rings of neighbours (default 2).
    pub margin_rings: u32,
    /// Weight of the "keep the current ℓ" targets of vertices outside every edit (≥ 0, default
    /// 1.0; used by the edit module when it builds the targets).
    pub outside_weight: f64,
    /// Untangle the grain an edit designs where it turns by more than a right angle within a
    /// triangle (skin folds finer than the brush; docs/math.md §10, "Untangling"; default
    /// true; used by the edit module).
    pub untangle: bool,
    /// Which highlight energy the edits' targets drive (default `position`).
    pub highlight_energy: HighlightEnergy,
    /// Fabrication constraints.
    pub constraints: Constraints,
}

/// The data term of the solve: what an edit's target says about the highlight.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Serialize, Deserialize, JsonSchema)]
#[serde(rename_all = "snake_case")]
pub enum HighlightEnergy {
    /// Target the scalar g = hᵀu itself (docs/math.md §9): its zero set is the key light's
    /// highlight and its level sets are the potential highlights, so a warp's target
    /// g*(p) = g(W⁻¹(p)) puts the highlight *where* the edit asks, and a curve's target makes
    /// the highlight lie *on* the curve. One row per vertex, smooth in φ, no |ℓ| → 0
    /// singularity, no curvature in the residual.
    #[default]
    Position,
    /// The paper's Eq. 5/8 (repaired, docs/math.md §4): the direction of the highlight tangent ℓ
    /// (Eq. 7) only, through the tensor L = ℓℓᵀ/|ℓ|².
    Tensor,
}

impl Default for SolverSettings {
    fn default() -> Self {
        SolverSettings {
            smoothness: 0.0,
            max_iterations: 50,
            relative_decrease: 1e-10,
            gradient_tolerance: 1e-12,
            initial_damping: 1e-4,
            interleaved_smoothing: None,
            continuation: false,
            whole_mesh: false,
            harmonic_start: true,
            margin_rings: 2,
            outside_weight: 1.0,
            untangle: true,
            highlight_energy: HighlightEnergy::Position,
            constraints: Constraints::default(),
        }
    }
}

fn check(key: &str, value: f64, ok: bool, what: &str) -> Result<()> {
    if value.is_finite() && ok {
        Ok(())
    } else {
        let got = crate::error::fmt_num(value);
        Err(Error::setting(key, format!("must be a finite number {what}, got {got}")))
    }
}

impl SolverSettings {
    /// Range-checks every number; errors name the key relative to the section.
    pub fn validate(&self) -> Result<()> {
        let max_s = crate::limits::MAX_SMOOTHNESS;
        let in_range = (0.0..=max_s).contains(&self.smoothness);
        check("smoothness", self.smoothness, in_range, &format!("in [0, {}]", fmt_num(max_s)))?;
        let max_it = crate::limits::MAX_SOLVER_ITERATIONS;
        if self.max_iterations == 0 || self.max_iterations > max_it {
            return Err(Error::setting(
                "max_iterations",
                format!("must be in [1, {max_it}], got {}", self.max_iterations),
            ));
        }
        check("relative_decrease", self.relative_decrease, self.relative_decrease >= 0.0, "≥ 0")?;
        check(
            "gradient_tolerance",
            self.gradient_tolerance,
            self.gradient_tolerance >= 0.0,
            "≥ 0",
        )?;
        check("initial_damping", self.initial_damping, self.initial_damping > 0.0, "> 0")?;
        check("outside_weight", self.outside_weight, self.outside_weight >= 0.0, "≥ 0")?;
        if self.margin_rings > 64 {
            return Err(Error::setting(
                "margin_rings",
                format!("must be ≤ 64, got {}", self.margin_rings),
            ));
        }
        let c = &self.constraints;
        if let Some(t) = &c.turning_radius {
            let max_r = crate::limits::MAX_TURNING_RADIUS;
            check(
                "constraints.turning_radius.radius",
                t.radius,
                t.radius > 0.0 && t.radius <= max_r,
                &format!("> 0 and ≤ {}", fmt_num(max_r)),
            )?;
            check("constraints.turning_radius.weight", t.weight, t.weight > 0.0, "> 0")?;
        }
        if let Some(t) = &c.turning_in_triangles {
            let key = "constraints.turning_in_triangles";
            if c.turning_radius.is_none() {
                return Err(Error::setting(key, "needs constraints.turning_radius"));
            }
            check(
                &format!("{key}.margin"),
                t.margin,
                (0.0..0.5).contains(&t.margin),
                "in [0, 0.5)",
            )?;
            if let Some(w) = t.weight {
                check(&format!("{key}.weight"), w, w > 0.0, "> 0")?;
            }
        }
        if let Some(t) = &c.splay_in_triangles {
            let key = "constraints.splay_in_triangles";
            if c.splay.is_none() {
                return Err(Error::setting(key, "needs constraints.splay"));
            }
            check(
                &format!("{key}.margin"),
                t.margin,
                (0.0..0.5).contains(&t.margin),
                "in [0, 0.5)",
            )?;
            if let Some(w) = t.weight {
                check(&format!("{key}.weight"), w, w > 0.0, "> 0")?;
            }
        }
        if let Some(s) = &c.splay {
            check("constraints.splay.max", s.max, s.max > 0.0, "> 0")?;
            check("constraints.splay.weight", s.weight, s.weight > 0.0, "> 0")?;
        }
        check(
            "constraints.conflict_tolerance",
            c.conflict_tolerance,
            c.conflict_tolerance >= 0.0,
            "≥ 0",
        )?;
        for (i, l) in c.locks.iter().enumerate() {
            l.validate_at(&format!("constraints.locks[{i}]"))?;
        }
        Ok(())
    }

    /// Whether the interleaved smoothing pass runs (explicit setting, else `smoothness == 0`).
    pub fn smoothing_pass(&self) -> bool {
        self.interleaved_smoothing.unwrap_or(self.smoothness == 0.0)
    }
}
