//! The smoothest direction field (Knöppel, Crane, Pinkall & Schröder 2013, "Globally optimal
//! direction fields"), in power form.
//!
//! With zᵢ = e^{ikφᵢ} (k = 1 or 2) the connection Dirichlet energy
//!
//! ```text
//! E(z) = Σ_edges wᵢⱼ |zⱼ e^{ikρᵢⱼ} − zᵢ|²,     wᵢⱼ the clamped cotangent weights,
//! ```
//!
//! is the Hermitian form zᴴAz with Aᵢᵢ = Σⱼ wᵢⱼ and Aᵢⱼ = −wᵢⱼ e^{ikρᵢⱼ}. The smoothest field is
//! the eigenvector of the smallest eigenvalue of A z = λ M z (M the diagonal of vertex areas),
//! found by inverse iteration on one sparse Cholesky factorization of A + σM (σ a tiny shift that
//! keeps the factorization defined when the surface has no holonomy, e.g. a plane).
//! φᵢ = arg(zᵢ)/k. The field is unique up to a global rotation; the start vector is fixed, so
//! the result is deterministic.

use faer::c64;
use faer::prelude::*;
use faer::sparse::{SparseColMat, Triplet};

use super::Symmetry;
use crate::geometry::laplacian::cotan_weights;
use crate::geometry::Geometry;
use crate::mesh::Mesh;
use crate::{Error, Result};

/// Options of [`smoothest_field`].
#[derive(Clone, Copy, Debug)]
pub struct SmoothestOptions {
    /// Maximum number of inverse iterations.
    pub max_iterations: usize,
    /// Stop when the Rayleigh quotient changes by less than this, relatively.
    pub tolerance: f64,
}

impl Default for SmoothestOptions {
    fn default() -> Self {
        SmoothestOptions { max_iterations: 50, tolerance: 1e-10 }
    }
}

/// The smoothest field and how it was found.
#[derive(Clone, Debug)]
pub struct SmoothestResult {
    /// φ per vertex.
    pub phi: Vec<f64>,
    /// The smallest eigenvalue λ (the field's energy per unit area).
    pub eigenvalue: f64,
    /// Inverse iterations done.
    pub iterations: usize,
}

/// Computes the smoothest field of symmetry `symmetry` on `mesh`.
pub fn smoothest_field(
    mesh: &Mesh,
    geom: &Geometry,
    symmetry: Symmetry,
    options: &SmoothestOptions,
) -> Result<SmoothestResult> {
    let n = geom.num_vertices();
    if n == 0 {
        return Ok(SmoothestResult { phi: Vec::new(), eigenvalue: 0.0, iterations: 0 });
    }
    let k = symmetry.k() as f64;
    let adj = &geom.adjacency;
    let w = cotan_weights(mesh, adj);
    let mass: Vec<f64> = geom.areas.iter().map(|&a| if a > 0.0 { a } else { 0.0 }).collect();
    let total_mass: f64 = mass.iter().sum();
    let mean_mass = (total_mass / n as f64).max(f64::MIN_POSITIVE);
    // A vertex without area (isolated) still needs a positive mass for M to be definite.
    let mass: Vec<f64> = mass.iter().map(|&m| m.max(1e-12 * mean_mass)).collect();
    let trace_a: f64 = w.iter().sum();
    let sigma = 1e-8 * (trace_a / total_mass.max(f64::MIN_POSITIVE)).max(1e-300);

    let mut triplets = Vec::with_capacity(adj.num_slots() + n);
    for (i, &m) in mass.iter().enumerate() {
        let mut diag = sigma * m;
        for s in adj.slots(i) {
            let j = adj.target(s);
            diag += w[s];
            if w[s] != 0.0 {
                let a = k * geom.transport[s];
                triplets.push(Triplet::new(i, j, c64::new(-w[s] * a.cos(), -w[s] * a.sin())));
            }
        }
        triplets.push(Triplet::new(i, i, c64::new(diag, 0.0)));
    }
    let a = SparseColMat::<usize, c64>::try_new_from_triplets(n, n, &triplets).map_err(|e| {
        Error::Numerical {
            stage: "smoothest field",
            message: format!("matrix assembly: {}", crate::error::describe_creation(&e)),
        }
    })?;
    let llt = crate::factor::Factor::new(a.as_ref(), "smoothest field")?;

    // Deterministic start: golden-angle phases.
    let mut z: Vec<c64> = (0..n)
        .map(|i| c64::new((i as f64 * 2.399_963).cos(), (i as f64 * 2.399_963).sin()))
        .collect();
    normalize(&mut z, &mass);
    let mut lambda = f64::INFINITY;
    let mut iterations = 0;
    for it in 0..options.max_iterations {
        iterations = it + 1;
        let mut rhs = Mat::<c64>::from_fn(n, 1, |i, _| z[i] * mass[i]);
        llt.solve_in_place(rhs.as_mut());
        let mut x: Vec<c64> = (0..n).map(|i| rhs[(i, 0)]).collect();
        normalize(&mut x, &mass);
        // Rayleigh quotient xᴴAx / xᴴMx (xᴴMx = 1 after normalization).
        let mut rq = 0.0;
        for i in 0..n {
            for s in adj.slots(i) {
                let j = adj.target(s);
                if i < j {
                    let a = c64::new((k * geom.transport[s]).cos(), (k * geom.transport[s]).sin());
                    rq += w[s] * (x[j] * a - x[i]).norm_sqr();
                }
            }
        }
        z = x;
        let done = (lambda - rq).abs() <= options.tolerance * rq.abs().max(1e-300);
        lambda = rq;
        if done {
            break;
        }
    }
    let phi = z.iter().map(|c| c.im.atan2(c.re) / k).collect();
    Ok(SmoothestResult { phi, eigenvalue: lambda, iterations })
}

fn normalize(z: &mut [c64], mass: &[f64]) {
    let norm: f64 = z.iter().zip(mass).map(|(c, m)| c.norm_sqr() * m).sum::<f64>().sqrt();
    if norm > 0.0 && norm.is_finite() {
        for c in z.iter_mut() {
            *c /= norm;
        }
    }
}
