//! The position energy E_g (docs/math.md §9): the key light's highlight *where* the edit asks.
//!
//! The highlight of a grain u under the half vector h is the zero set of the scalar
//! g = hᵀu, and its potential highlights (paper §3.2) are the level sets of g; ℓ of Eq. 7 is
//! their tangent, n × ∇_S g. The paper's energy (Eq. 5) matches the *direction* of ℓ only, which
//! fixes one free constant per highlight curve (math.md §3): a curve may come out parallel to
//! the target, anywhere. Targeting g itself fixes that constant, and it needs neither ∇φ nor
//! the Weingarten map, so scan noise in the curvature never reaches it:
//!
//! ```text
//! ĝᵢ = h̄ᵢᵀūᵢ / |h̄ᵢ|                      (the cosine between u and the tangent part of h)
//! rᵢ = √(wᵢAᵢ) (h̄ᵢᵀūᵢ − |h̄ᵢ| ĝ*ᵢ)          = √(wᵢAᵢ) |h̄ᵢ| (ĝᵢ − ĝ*ᵢ)
//! ∂rᵢ/∂φᵢ = √(wᵢAᵢ) h̄ᵢᵀv̄ᵢ,                 ∂rᵢ/∂φⱼ = 0 (j ≠ i)
//! ```
//!
//! with h̄ᵢ = [tᵢ bᵢ]ᵀhᵢ and ū = (cos φ, sin φ), v̄ = (−sin φ, cos φ) (Eq. 6). The factor |h̄ᵢ|
//! fades the row out towards a critical point (h ∥ n, where hᵀu = 0 for every u and no edit
//! can move the highlight). Because h is taken per vertex, a near eye (and a point light)
//! enters exactly: g is the true hᵀu, not its distant-light approximation.
//!
//! For a line field (k = 2) g changes sign with u; ĝ*ᵢ is then stated in the orientation of
//! vertex i's start angle, and the residual, continuous in φᵢ, keeps that orientation.

use nalgebra::Vector2;

use super::highlight_term::HighlightTerm;

/// Targets are clamped to |ĝ*| ≤ this: at |ĝ*| = 1 the residual's derivative vanishes at the
/// solution (u ∥ h̄), which slows Gauss–Newton to a crawl without moving the highlight.
pub const TARGET_BOUND: f64 = 0.995;

impl HighlightTerm<'_> {
    /// h̄ᵢ = [tᵢ bᵢ]ᵀhᵢ, the tangent part of the half vector in vertex i's frame.
    #[inline]
    pub fn h_bar(&self, i: usize) -> Vector2<f64> {
        self.geometry.frames[i].to_local(&self.h[i])
    }

    /// The position residual of vertex `i` and its derivative with respect to φᵢ (0 and 0
    /// without a target).
    #[inline]
    pub fn position_row(&self, phi: &[f64], i: usize) -> (f64, f64) {
        let Some(target) = self.target_g[i] else { return (0.0, 0.0) };
        let hb = self.h_bar(i);
        let s = (self.weight[i] * self.geometry.areas[i]).max(0.0).sqrt();
        let (sn, cs) = phi[i].sin_cos();
        let target = target.clamp(-TARGET_BOUND, TARGET_BOUND);
        let r = s * (cs * hb.x + sn * hb.y - hb.norm() * target);
        let d = s * (cs * hb.y - sn * hb.x);
        (r, d)
    }
}
