//! The grain at a face's corners extended off the surface, so that blending it inside the face
//! and projecting the blend onto the surface reproduces a world direction's projection
//! exactly (docs/math.md §3, "Recognized surfaces"): what the strokes
//! (`grainline_toolpaths`' surface field) and the glb's texture read inside a curved face.
//!
//! On a 30° strip of a fillet the projected grain can turn by tens of degrees between two
//! rulings; a blend of the corners' unit tangents follows the chord, not the surface. The
//! corners' grain `uᵢ` (unit tangents at unit normals `nᵢ`) is extended to ambient vectors
//! `aᵢ = sᵢ uᵢ + tᵢ nᵢ` that agree as well as they can:
//!
//! `argmin Σ_{i<j} |aᵢ − aⱼ|² + ε Σ ((sᵢ − 1)² + tᵢ²)` subject to `Σ sᵢ = 3`.
//!
//! A grain that is one direction `w` projected and normalised gives `aᵢ = c w` at every corner
//! (to ε), whose blend projected onto the tangent plane anywhere on the face is `w`'s
//! projection there. Any other grain gets its smoothest ambient extension. With
//! `Σ_{i<j} |aᵢ − aⱼ|² = 3 Σ |aᵢ|² − |Σ aᵢ|²` and `Bᵢ = [uᵢ nᵢ]`, the Hessian's blocks are
//! `4 BᵢᵀBᵢ` and `−2 BᵢᵀBⱼ`; the constraint's multiplier makes a 7 × 7 system.

use nalgebra::{SMatrix, SVector, Vector3};

type V3 = Vector3<f64>;

/// Regularisation towards `aᵢ = uᵢ`: fixes what the corners leave free (on a flat face, any
/// `tᵢ` along the common normal).
const EPS: f64 = 1e-9;

/// The corners' ambient grain (module docs); `None` when the system is singular or a number
/// is not finite.
pub fn extend(u: [V3; 3], n: [V3; 3]) -> Option<[V3; 3]> {
    let mut m = SMatrix::<f64, 7, 7>::zeros();
    let mut rhs = SVector::<f64, 7>::zeros();
    let b = |i: usize| [u[i], n[i]];
    for i in 0..3 {
        for j in 0..3 {
            let w = if i == j { 4.0 } else { -2.0 };
            for (p, bp) in b(i).iter().enumerate() {
                for (q, bq) in b(j).iter().enumerate() {
                    m[(2 * i + p, 2 * j + q)] = w * bp.dot(bq);
                }
            }
        }
        m[(2 * i, 2 * i)] += 2.0 * EPS;
        m[(2 * i + 1, 2 * i + 1)] += 2.0 * EPS;
        rhs[2 * i] = 2.0 * EPS;
        m[(2 * i, 6)] = 1.0;
        m[(6, 2 * i)] = 1.0;
    }
    rhs[6] = 3.0;
    let x = m.lu().solve(&rhs)?;
    let out = [0, 1, 2].map(|i| u[i] * x[2 * i] + n[i] * x[2 * i + 1]);
    out.iter().all(|a| a.iter().all(|c| c.is_finite())).then_some(out)
}

#[cfg(test)]
mod tests {
    use super::*;

    fn grain(n: V3, w: V3) -> V3 {
        (w - n * n.dot(&w)).normalize()
    }

    /// On a cylinder's 30° strip and on a sphere's patch, a projected world direction extends
    /// to that direction at every corner; on a flat face the grain is kept.
    #[test]
    fn a_projected_world_direction_extends_to_itself() {
        let w = V3::new(0.2, 1.0, 0.3);
        let cyl = |a: f64| V3::new(a.cos(), a.sin(), 0.0);
        let sph = |a: f64, b: f64| V3::new(a.cos() * b.cos(), a.sin() * b.cos(), b.sin());
        let a = 30f64.to_radians();
        for n in [[cyl(0.0), cyl(a), cyl(a)], [sph(0.1, 0.2), sph(0.4, 0.25), sph(0.2, 0.6)]] {
            let u = n.map(|n| grain(n, w));
            let ext = extend(u, n).unwrap();
            for e in ext {
                assert!(e.normalize().cross(&w.normalize()).norm() < 1e-7, "{e:?}");
            }
        }
        let n = [V3::z(); 3];
        let u = [V3::x(), V3::new(1.0, 0.2, 0.0).normalize(), V3::y()];
        let ext = extend(u, n).unwrap();
        for (e, u) in ext.iter().zip(u) {
            assert!(e.normalize().dot(&u) > 0.99, "{e:?} vs {u:?}");
        }
    }
}
