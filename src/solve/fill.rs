//! The connection-harmonic fill of the free region: a second start for the optimizer.
//!
//! With zᵢ = e^{ikφᵢ} (k = 1 or 2), the fill minimizes the connection Dirichlet energy of
//! [`super::smoothness`] over the free vertices with the fixed ones held:
//!
//! ```text
//! min Σ_edges wᵢⱼ |zⱼ e^{ikρᵢⱼ} − zᵢ|²   over zᵢ, i free   ⇔   A_ff z_f = b,
//! A_ii = Σⱼ wᵢⱼ,  A_ij = −wᵢⱼ e^{ikρᵢⱼ} (i, j free),  bᵢ = Σ_{j fixed} wᵢⱼ e^{ikρᵢⱼ} zⱼ,
//! ```
//!
//! a sparse Hermitian positive definite system when every connected part of the free set touches
//! a fixed vertex (a tiny diagonal shift keeps it definite otherwise). φᵢ = arg(zᵢ)/k.
//!
//! Why: the data term alone fixes the field only up to one constant per highlight curve where
//! it enters the free region (math.md §3), so Levenberg–Marquardt started far from the answer
//! can settle in another minimum. The fill is what the paper's Laplacian smoothing pass converges
//! to, computed in one solve; [`super::optimize()`] starts from it when its energy is lower than
//! the given start's.

use faer::c64;
use faer::prelude::*;
use faer::sparse::{SparseColMat, Triplet};

use crate::geometry::Geometry;

/// The harmonic fill of `phi` on the `free` vertices (sorted, unique). Returns `None` when the
/// system cannot be factorized. Vertices where the fill vanishes (|zᵢ| below 1e-9 of the
/// boundary's: a singularity of the filled field) keep their angle from `phi`. Each filled angle
/// is the representative (mod 2π/k) nearest the vertex's angle in `phi`.
pub fn harmonic_fill(
    geometry: &Geometry,
    weights: &[f64],
    phi: &[f64],
    free: &[u32],
    k: u32,
) -> Option<Vec<f64>> {
    let nv = geometry.num_vertices();
    let adj = &geometry.adjacency;
    let kf = k as f64;
    let mut col = vec![u32::MAX; nv];
    for (c, &v) in free.iter().enumerate() {
        col[v as usize] = c as u32;
    }
    let n = free.len();
    if n == 0 {
        return Some(phi.to_vec());
    }
    let mut triplets = Vec::with_capacity(8 * n);
    let mut rhs = Mat::<c64>::zeros(n, 1);
    let mut diag = vec![0.0; n];
    let mut touches_fixed = false;
    for (c, &v) in free.iter().enumerate() {
        let i = v as usize;
        for s in adj.slots(i) {
            let w = weights[s];
            if w <= 0.0 || !w.is_finite() {
                continue;
            }
            let j = adj.target(s);
            let a = kf * geometry.transport[s];
            let e = c64::new(a.cos(), a.sin());
            diag[c] += w;
            if col[j] != u32::MAX {
                triplets.push(Triplet::new(c, col[j] as usize, e * (-w)));
            } else {
                let zj = c64::new((kf * phi[j]).cos(), (kf * phi[j]).sin());
                rhs[(c, 0)] += e * zj * w;
                touches_fixed = true;
            }
        }
    }
    if !touches_fixed {
        return None;
    }
    let mean = diag.iter().sum::<f64>() / n as f64;
    for (c, d) in diag.iter().enumerate() {
        // A free vertex with no weighted edge still needs a positive pivot.
        triplets.push(Triplet::new(c, c, c64::new(d + 1e-10 * mean.max(1e-300), 0.0)));
    }
    let a = SparseColMat::<usize, c64>::try_new_from_triplets(n, n, &triplets).ok()?;
    let llt = crate::factor::Factor::new(a.as_ref(), "harmonic fill").ok()?;
    llt.solve_in_place(rhs.as_mut());
    let scale = rhs.col(0).iter().map(|z| z.norm()).fold(0.0f64, f64::max);
    let mut out = phi.to_vec();
    for (c, &v) in free.iter().enumerate() {
        let z = rhs[(c, 0)];
        if z.re.is_finite() && z.im.is_finite() && z.norm() > 1e-9 * scale {
            // arg(z)/k is one of the k representatives of the filled direction; keep the one
            // nearest the given angle, so that a line field's orientation at each vertex (in
            // which the position targets state ĝ*, math.md §9) survives the fill.
            let a = z.im.atan2(z.re) / kf;
            let period = std::f64::consts::TAU / kf;
            let old = phi[v as usize];
            let m = ((old - a) / period).round();
            out[v as usize] = if m.is_finite() { a + m * period } else { a };
        }
    }
    Some(out)
}
