//! The normalized highlight tensor L = ℓℓᵀ/|ℓ|² (the paper's Eq. 5) and its regularization.
//!
//! L is undefined at ℓ = 0 (the paper's Fig. 2b). grainline uses
//!
//! ```text
//! L_ε(ℓ) = (ℓℓᵀ + ½ε² I) / (|ℓ|² + ε²)
//! ```
//!
//! which has trace 1 for every ℓ, equals L when ε = 0, and tends smoothly to ½I (no preferred
//! direction) as |ℓ| → 0, so nothing divides by zero. Its traceless part is carried by
//! q(ℓ) = (ℓ₁² − ℓ₂², 2ℓ₁ℓ₂)/(|ℓ|² + ε²) (math.md §3): L_ε = ½(I + [[q₁, q₂], [q₂, −q₁]]).
//! The default ε is 0.02 × the median |m| over the mesh, so that ℓ → 0 costs about as much as a
//! 45° error.

use nalgebra::{Matrix2, Vector2};

/// The traceless components q(ℓ) of L_ε, for ℓ in frame coordinates.
#[inline]
pub fn q(ell: &Vector2<f64>, eps: f64) -> Vector2<f64> {
    let d = ell.norm_squared() + eps * eps;
    if d > 0.0 {
        Vector2::new(ell.x * ell.x - ell.y * ell.y, 2.0 * ell.x * ell.y) / d
    } else {
        Vector2::zeros()
    }
}

/// The regularized tensor L_ε(ℓ), for ℓ in frame coordinates.
#[inline]
pub fn tensor(ell: &Vector2<f64>, eps: f64) -> Matrix2<f64> {
    let q = q(ell, eps);
    Matrix2::new(1.0 + q.x, q.y, q.y, 1.0 - q.x) * 0.5
}

/// The default ε: 0.02 × the median of the given |m| (0 if all vanish).
pub fn default_epsilon(m_norms: &[f64]) -> f64 {
    let mut v: Vec<f64> = m_norms.iter().copied().filter(|x| x.is_finite()).collect();
    if v.is_empty() {
        return 0.0;
    }
    let mid = v.len() / 2;
    let (_, med, _) = v.select_nth_unstable_by(mid, |a, b| a.total_cmp(b));
    0.02 * *med
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn unit_trace_and_limits() {
        let l = Vector2::new(3.0, 4.0);
        let t = tensor(&l, 0.0);
        assert!((t - l * l.transpose() / 25.0).norm() < 1e-15);
        let t0 = tensor(&Vector2::zeros(), 0.1);
        assert!((t0 - Matrix2::identity() * 0.5).norm() < 1e-15);
        assert!((tensor(&Vector2::new(1e-9, 0.0), 0.1).trace() - 1.0).abs() < 1e-15);
        assert_eq!(tensor(&Vector2::zeros(), 0.0), Matrix2::identity() * 0.5);
    }
}
