//! The smoothness energy E_s: the connection Dirichlet energy, one residual per edge (math.md §4).
//!
//! ```text
//! r_ij = √(λ_s w_ij) · (2/k) · sin(kΔ_ij / 2),      Δ_ij = φ_j + ρ_ij − φ_i
//! ∂r_ij/∂φ_j = −∂r_ij/∂φ_i = √(λ_s w_ij) · cos(kΔ_ij / 2)
//! ```
//!
//! |r_ij|² = λ_s w_ij |e^{ikφ_j}e^{ikρ_ij} − e^{ikφ_i}|²/k², so the energy is periodic in φ with
//! period 2π/k and never compares raw angles. w_ij are the clamped cotangent weights.

/// Residual and the two Jacobian entries (∂/∂φ_i, ∂/∂φ_j) of one edge.
#[inline]
pub fn edge_residual(phi_i: f64, phi_j: f64, rho_ij: f64, weight: f64, k: u32) -> (f64, f64, f64) {
    edge_residual_scaled(phi_i, phi_j, rho_ij, edge_scale(weight), k)
}

/// The scale √(λ_s w_ij) of an edge's residual (0 for a negative weight).
#[inline]
pub fn edge_scale(weight: f64) -> f64 {
    weight.max(0.0).sqrt()
}

/// [`edge_residual`] with the scale `s` = [`edge_scale`]`(weight)` computed once (the same
/// bits).
#[inline]
pub fn edge_residual_scaled(
    phi_i: f64,
    phi_j: f64,
    rho_ij: f64,
    s: f64,
    k: u32,
) -> (f64, f64, f64) {
    let kf = k as f64;
    let half = 0.5 * kf * (phi_j + rho_ij - phi_i);
    let d = s * half.cos();
    (s * (2.0 / kf) * half.sin(), -d, d)
}
