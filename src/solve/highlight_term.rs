//! The highlight energy E_ℓ (the paper's Eq. 5/8, repaired as in docs/math.md §4) per vertex:
//! its two-row residual and the analytic Jacobian row block.
//!
//! With ℓ̄ᵢ = R mᵢ the highlight tangent in frame coordinates (Eq. 7) and
//! q(ℓ) = (ℓ₁² − ℓ₂², 2ℓ₁ℓ₂)/(|ℓ|² + ε²) the traceless part of the regularized tensor,
//!
//! ```text
//! rᵢ = √(wᵢAᵢ/2) · [q(ℓ̄ᵢ) − qᵢ*]          so that Σ|rᵢ|² = Σ wᵢAᵢ‖L_ε(ℓᵢ) − L*ᵢ‖²_F.
//! ```
//!
//! Jacobian (cᵢⱼ = cos kΔᵢⱼ for the sine form of Eq. 10, 1 for the angle form):
//!
//! ```text
//! ∂∇φᵢ/∂φⱼ = Pᵢ⁺[:, j] cᵢⱼ,           ∂∇φᵢ/∂φᵢ = −Σⱼ Pᵢ⁺[:, j] cᵢⱼ
//! ∂mᵢ/∂φᵢ = −(ūᵢᵀh̄ᵢ)∇φᵢ + (v̄ᵢᵀh̄ᵢ) ∂∇φᵢ/∂φᵢ + (nᵢᵀh) Wᵢ v̄ᵢ
//! ∂mᵢ/∂φⱼ = (v̄ᵢᵀh̄ᵢ) ∂∇φᵢ/∂φⱼ
//! ∂rᵢ/∂φ  = √(wᵢAᵢ/2) (∂q/∂ℓ) R (∂mᵢ/∂φ),  D = |ℓ|² + ε²,
//! ∂q₁/∂ℓ = 2[(ℓ₁, −ℓ₂) − q₁ℓ]/D,          ∂q₂/∂ℓ = 2[(ℓ₂, ℓ₁) − q₂ℓ]/D
//! ```
//!
//! Row i is non-zero only in column i and the columns of its Eq. 10 stencil, so the Jacobian has
//! the Laplacian's pattern (the paper's §4.3 remark).

use nalgebra::{Matrix2, Vector2, Vector3};

use crate::geometry::{Geometry, GradientForm};
use crate::highlight::ell::m_vector;
use crate::highlight::tensor::{default_epsilon, q};
use crate::highlight::Symmetry;

/// The data of the highlight energy: geometry, half vectors, targets and weights.
#[derive(Clone, Debug)]
pub struct HighlightTerm<'a> {
    /// The surface.
    pub geometry: &'a Geometry,
    /// Half vector per vertex.
    pub h: &'a [Vector3<f64>],
    /// k = 1 or 2.
    pub symmetry: Symmetry,
    /// Eq. 10 form.
    pub form: GradientForm,
    /// Regularization ε of the tensor (docs/math.md §4).
    pub epsilon: f64,
    /// Target q(ℓ̄*) per vertex in frame coordinates (`None`: no target, zero residual).
    pub target_q: Vec<Option<Vector2<f64>>>,
    /// Weight wᵢ per vertex (multiplies the area).
    pub weight: Vec<f64>,
    /// Target ĝ*ᵢ of the position energy per vertex (`None`: no position row;
    /// [`super::position_term`]). A vertex may have a tensor target, a position target, both or
    /// neither; the pipeline gives each vertex the one `solver.highlight_energy` selects.
    pub target_g: Vec<Option<f64>>,
}

/// The residual of one vertex and its Jacobian entries.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct VertexJacobian {
    /// The two residual components.
    pub residual: [f64; 2],
    /// `(column vertex, ∂r/∂φ_column)`; the vertex itself comes first.
    pub entries: Vec<(u32, [f64; 2])>,
}

const QUARTER_TURN: Matrix2<f64> = Matrix2::new(0.0, -1.0, 1.0, 0.0);

impl<'a> HighlightTerm<'a> {
    /// The term whose targets are the highlights of `phi` itself at every vertex (weight 1,
    /// ε from [`default_epsilon`] of those highlights), so `phi` has zero highlight energy:
    /// the "keep the current ℓ" target, and the set-up of recovery tests and benchmarks.
    pub fn own_targets(
        geometry: &'a Geometry,
        h: &'a [Vector3<f64>],
        symmetry: Symmetry,
        form: GradientForm,
        phi: &[f64],
    ) -> Self {
        let n = phi.len();
        let mut term = HighlightTerm {
            geometry,
            h,
            symmetry,
            form,
            epsilon: 0.0,
            target_q: vec![None; n],
            weight: vec![1.0; n],
            target_g: vec![None; n],
        };
        let ell: Vec<Vector2<f64>> = (0..n).map(|i| term.ell_bar(phi, i)).collect();
        let norms: Vec<f64> = ell.iter().map(|l| l.norm()).collect();
        term.epsilon = default_epsilon(&norms);
        term.target_q = ell.iter().map(|l| Some(q(l, term.epsilon))).collect();
        term
    }
}

impl HighlightTerm<'_> {
    /// ℓ̄ᵢ (frame coordinates) of the field φ.
    pub fn ell_bar(&self, phi: &[f64], i: usize) -> Vector2<f64> {
        let g = self.geometry;
        let grad = g.stencil.gradient_at(phi, self.symmetry.k(), self.form, i);
        QUARTER_TURN * m_vector(&g.frames[i], &g.weingarten[i], &grad, phi[i], &self.h[i])
    }

    /// The residual of vertex `i` alone.
    pub fn residual(&self, phi: &[f64], i: usize) -> [f64; 2] {
        let Some(tq) = self.target_q[i] else { return [0.0; 2] };
        let s = (0.5 * self.weight[i] * self.geometry.areas[i]).max(0.0).sqrt();
        let d = (q(&self.ell_bar(phi, i), self.epsilon) - tq) * s;
        [d.x, d.y]
    }

    /// Residual and analytic Jacobian entries of vertex `i`.
    pub fn jacobian(&self, phi: &[f64], i: usize) -> VertexJacobian {
        let mut entries = Vec::new();
        let residual = self.jacobian_into(phi, i, &mut entries);
        VertexJacobian { residual, entries }
    }

    /// [`HighlightTerm::jacobian`] into a caller's buffer (cleared first; no allocation once it
    /// has grown): returns the residual, writes the entries.
    pub fn jacobian_into(
        &self,
        phi: &[f64],
        i: usize,
        entries: &mut Vec<(u32, [f64; 2])>,
    ) -> [f64; 2] {
        entries.clear();
        let Some(tq) = self.target_q[i] else { return [0.0; 2] };
        let g = self.geometry;
        let (frame, w) = (&g.frames[i], &g.weingarten[i]);
        let k = self.symmetry.k() as f64;
        let grad = g.stencil.gradient_at(phi, self.symmetry.k(), self.form, i);
        let (sn, cs) = phi[i].sin_cos();
        let (u, v) = (Vector2::new(cs, sn), Vector2::new(-sn, cs));
        let hb = frame.to_local(&self.h[i]);
        let (uh, vh, nh) = (u.dot(&hb), v.dot(&hb), frame.n.dot(&self.h[i]));
        let m = grad * vh + w * u * nh;
        let ell = QUARTER_TURN * m;
        let dsq = ell.norm_squared() + self.epsilon * self.epsilon;
        let qv = q(&ell, self.epsilon);
        let s = (0.5 * self.weight[i] * g.areas[i]).max(0.0).sqrt();
        let residual = (qv - tq) * s;
        if dsq <= 0.0 {
            entries.push((i as u32, [0.0; 2]));
            return [residual.x, residual.y];
        }
        // ∂q/∂ℓ̄ as a 2×2 matrix (rows q₁, q₂), then composed with the quarter turn.
        let dq = Matrix2::new(
            2.0 * (ell.x - qv.x * ell.x) / dsq,
            2.0 * (-ell.y - qv.x * ell.y) / dsq,
            2.0 * (ell.y - qv.y * ell.x) / dsq,
            2.0 * (ell.x - qv.y * ell.y) / dsq,
        ) * QUARTER_TURN
            * s;
        let mut dgrad_self = Vector2::zeros();
        entries.push((i as u32, [0.0; 2]));
        for e in g.stencil.range(i) {
            let j = g.stencil.neighbor[e];
            let c = match self.form {
                GradientForm::Sine => (k * (phi[j as usize] + g.stencil.rho[e] - phi[i])).cos(),
                // The wrapped difference has derivative 1 away from ±π/k.
                GradientForm::Angle => 1.0,
            };
            let col = Vector2::new(g.stencil.pinv[e][0], g.stencil.pinv[e][1]) * c;
            dgrad_self -= col;
            let dr = dq * (col * vh);
            entries.push((j, [dr.x, dr.y]));
        }
        let dm_self = -grad * uh + dgrad_self * vh + w * v * nh;
        let dr = dq * dm_self;
        entries[0].1 = [dr.x, dr.y];
        [residual.x, residual.y]
    }
}
