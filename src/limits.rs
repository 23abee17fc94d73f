//! Budgets: every bound grainline puts on its input's size or magnitude, in one place
//! (documented in docs/scene.md, "Limits", and docs/formats.md).

/// Largest accepted |coordinate| of an OBJ `v` after `scale` (1e75, in the mesh's units).
///
/// Geometry multiplies up to four coordinates: with every |c| ≤ B an edge vector's components
/// are ≤ 2B, a face's cross product `(b − a) × (c − a)` (twice its area) has components ≤ 8B²
/// and squared norm ≤ 192·B⁴. That stays below `f64::MAX` ≈ 1.8e308 for B ≤ 9.8e76; 1e75 keeps
/// a margin of 10⁶ for sums over faces and unit conversions. Larger coordinates are refused
/// (naming the line and vertex) instead of turning areas into infinity or NaN and faces into
/// false zero-area ones.
pub const MAX_COORDINATE: f64 = 1e75;

/// `--threads` is capped at this many worker threads per available core.
pub const THREADS_PER_CORE: usize = 4;

/// The number of worker threads used for a `--threads` request: at least 1, at most
/// [`THREADS_PER_CORE`] × the available cores (results never depend on the count; more threads
/// than that only cost memory and scheduling). Returns the count and whether it was capped.
pub fn worker_threads(requested: usize, available_cores: usize) -> (usize, bool) {
    let cap = THREADS_PER_CORE * available_cores.max(1);
    (requested.clamp(1, cap), requested > cap)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn item12_threads_are_capped_at_four_per_core() {
        assert_eq!(worker_threads(100_000, 2), (8, true));
        assert_eq!(worker_threads(8, 2), (8, false));
        assert_eq!(worker_threads(0, 2), (1, false));
        assert_eq!(worker_threads(3, 0), (3, false));
    }

    #[test]
    fn coordinate_bound_keeps_the_cross_product_finite() {
        // The worst case of the bound's derivation: 192·B⁴ is finite, and so at 10·B it is not.
        let b = MAX_COORDINATE;
        assert!((192.0 * b * b * b * b).is_finite());
        let b10 = 10.0 * b;
        assert!(!(192.0 * b10 * b10 * b10 * b10 * 1e6).is_finite());
    }
}
