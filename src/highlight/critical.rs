//! Critical points of the highlight field: where hᵀn exceeds a threshold (the paper's Fig. 5d-e).
//!
//! There h ≈ n, hᵀu = 0 for every tangent u, so a highlight passes through the point whatever
//! the grain: ℓ no longer depends on ∇φ, and editing cannot move it.

use nalgebra::Vector3;

/// The paper's threshold on hᵀn.
pub const DEFAULT_CRITICAL_THRESHOLD: f64 = 0.9995;

/// `hᵢᵀnᵢ > threshold` for every vertex.
pub fn critical_points(
    h: &[Vector3<f64>],
    normals: impl Iterator<Item = Vector3<f64>>,
    threshold: f64,
) -> Vec<bool> {
    h.iter().zip(normals).map(|(h, n)| h.dot(&n) > threshold).collect()
}
