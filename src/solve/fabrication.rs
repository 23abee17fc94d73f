//! Fabrication energies (math.md §4): soft hinges on the geodesic curvature of the streamlines
//! (the brushing tool's minimum turning radius) and on their divergence (splay, i.e. how fast
//! neighbouring strokes spread), and soft direction locks.
//!
//! Both hinges are functions of the Eq. 10 gradient ∇φᵢ at a vertex:
//!
//! ```text
//! turning:  xᵢ = ūᵢᵀ∇φᵢ  (curl u, the streamline's geodesic curvature),  bound b = 1/R
//! splay:    xᵢ = v̄ᵢᵀ∇φᵢ  (div u),                                        bound b = s_max
//! rᵢ = √(λ Aᵢ) · max(0, |xᵢ|/b − 1)
//! ```
//!
//! so λ = 1 makes a vertex whose |x| is twice its bound cost as much as a 45° highlight error
//! there (docs/math.md §3: a 45° error costs Aᵢ). With ∂∇φᵢ/∂φⱼ = Pᵢ⁺[:, j] cᵢⱼ,
//! ∂∇φᵢ/∂φᵢ = −Σⱼ Pᵢ⁺[:, j] cᵢⱼ (cᵢⱼ = cos kΔᵢⱼ for the sine form, 1 for the angle form) and
//! ∂ū/∂φᵢ = v̄, ∂v̄/∂φᵢ = −ū:
//!
//! ```text
//! turning:  ∂x/∂φᵢ = v̄ᵀ∇φ + ūᵀ∂∇φ/∂φᵢ,    ∂x/∂φⱼ = ūᵀPᵢ⁺[:, j] cᵢⱼ
//! splay:    ∂x/∂φᵢ = −ūᵀ∇φ + v̄ᵀ∂∇φ/∂φᵢ,   ∂x/∂φⱼ = v̄ᵀPᵢ⁺[:, j] cᵢⱼ
//! ∂r/∂φ = √(λ Aᵢ) sign(xᵢ)/b · ∂x/∂φ   where the hinge is active, 0 elsewhere.
//! ```
//!
//! For k = 2, u → −u flips ū and keeps ∇φ, so |x| is periodic in π as it must be.
//!
//! A soft lock of vertex i to angle φ̂ is `rᵢ = √(λ Aᵢ)·(2/k)·sin(k(φᵢ − φ̂)/2)` (periodic in
//! 2π/k; ∂r/∂φᵢ = √(λ Aᵢ)·cos(k(φᵢ − φ̂)/2)).

use nalgebra::Vector2;

use crate::geometry::{Geometry, GradientForm};
use crate::highlight::Symmetry;

/// Which quantity a [`GradientHinge`] bounds.
#[derive(Clone, Copy, Debug, PartialEq, Eq, serde::Serialize)]
#[serde(rename_all = "snake_case")]
pub enum HingeKind {
    /// The streamline's geodesic curvature ūᵀ∇φ, bounded by 1/R.
    Turning,
    /// The divergence v̄ᵀ∇φ, bounded by s_max.
    Splay,
}

/// A soft hinge `√(λAᵢ)·max(0, |xᵢ|/b − 1)` on the curl or the divergence of the field.
#[derive(Clone, Copy, Debug)]
pub struct GradientHinge<'a> {
    /// The surface.
    pub geometry: &'a Geometry,
    /// k = 1 or 2.
    pub symmetry: Symmetry,
    /// Eq. 10 form.
    pub form: GradientForm,
    /// What is bounded.
    pub kind: HingeKind,
    /// The bound b > 0 on |x| (1/R for the turning radius R, s_max for splay).
    pub bound: f64,
    /// The weight λ ≥ 0.
    pub weight: f64,
}

impl GradientHinge<'_> {
    /// The bounded quantity xᵢ (curl or divergence of u) at vertex `i`.
    pub fn value(&self, phi: &[f64], i: usize) -> f64 {
        let grad = self.geometry.stencil.gradient_at(phi, self.symmetry.k(), self.form, i);
        self.project(phi[i], &grad).0
    }

    /// (x, ∂x/∂ū-part for the own angle) for a given gradient: returns (x, the direction d such
    /// that x = dᵀ∇φ, and ∂d/∂φᵢ).
    #[inline]
    fn project(&self, phi_i: f64, grad: &Vector2<f64>) -> (f64, Vector2<f64>, Vector2<f64>) {
        let (s, c) = phi_i.sin_cos();
        let (u, v) = (Vector2::new(c, s), Vector2::new(-s, c));
        match self.kind {
            HingeKind::Turning => (u.dot(grad), u, v),
            HingeKind::Splay => (v.dot(grad), v, -u),
        }
    }

    #[inline]
    fn scale(&self, i: usize) -> f64 {
        (self.weight * self.geometry.areas[i]).max(0.0).sqrt()
    }

    /// The residual of vertex `i`.
    pub fn residual(&self, phi: &[f64], i: usize) -> f64 {
        let x = self.value(phi, i);
        self.scale(i) * (x.abs() / self.bound - 1.0).max(0.0)
    }

    /// The residual of vertex `i` and its Jacobian entries `(column vertex, ∂r/∂φ)`, written to
    /// `entries` (cleared first; the vertex itself comes first, then its Eq. 10 stencil in
    /// order). The entries are written even where the hinge is inactive (as zeros), so the
    /// sparsity pattern does not depend on φ.
    pub fn jacobian(&self, phi: &[f64], i: usize, entries: &mut Vec<(u32, f64)>) -> f64 {
        let g = self.geometry;
        let k = self.symmetry.k() as f64;
        let grad = g.stencil.gradient_at(phi, self.symmetry.k(), self.form, i);
        let (x, d, dd) = self.project(phi[i], &grad);
        let s = self.scale(i);
        let excess = x.abs() / self.bound - 1.0;
        let active = excess > 0.0;
        let f = if active { s * x.signum() / self.bound } else { 0.0 };
        entries.clear();
        entries.push((i as u32, 0.0));
        let mut self_entry = dd.dot(&grad);
        for e in g.stencil.range(i) {
            let j = g.stencil.neighbor[e];
            let c = match self.form {
                GradientForm::Sine => (k * (phi[j as usize] + g.stencil.rho[e] - phi[i])).cos(),
                GradientForm::Angle => 1.0,
            };
            let col = d.dot(&Vector2::new(g.stencil.pinv[e][0], g.stencil.pinv[e][1])) * c;
            self_entry -= col;
            entries.push((j, f * col));
        }
        entries[0].1 = f * self_entry;
        if active {
            s * excess
        } else {
            0.0
        }
    }
}

/// The soft-lock residual of one vertex and its derivative: `(r, ∂r/∂φᵢ)` for
/// `r = √(λA)·(2/k)·sin(k(φ − φ̂)/2)`; `scale` is √(λA).
#[inline]
pub fn lock_residual(phi: f64, target: f64, scale: f64, k: u32) -> (f64, f64) {
    let kf = k as f64;
    let half = 0.5 * kf * (phi - target);
    (scale * (2.0 / kf) * half.sin(), scale * half.cos())
}
