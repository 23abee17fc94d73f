//! The matrix-free inexact step of [`super::lm`] for large systems (math.md §7): the stacked
//! Jacobian stored by rows and by columns, the product (JᵀJ + diag(shift))x in two parallel
//! passes, and Jacobi-preconditioned conjugate gradients.

use rayon::prelude::*;

/// From this many unknowns, [`super::LinearSolver::Auto`] uses conjugate gradients: the Cholesky
/// factor of the 2-ring pattern fills in superlinearly (×21 at 100k), CG stays linear per
/// iteration.
pub const CG_THRESHOLD: usize = 20_000;

/// Largest relative residual ‖b − Ax‖/‖b‖ at which the conjugate gradients stop (the forcing
/// term of the inexact step; it tightens to ‖g‖/‖g₀‖ as the gradient falls, so the final
/// iterations are as exact as the direct ones).
pub const CG_FORCING: f64 = 0.3;

/// Cap on conjugate-gradient iterations per damped system.
pub const CG_MAX_ITERATIONS: usize = 60;

/// Jacobi-preconditioned conjugate gradients for (JᵀJ + diag(shift)) x = b, from x = 0,
/// stopping at ‖b − Ax‖ ≤ tol ‖b‖ or [`CG_MAX_ITERATIONS`]. Returns x and the iterations used.
/// The products run in parallel chunks whose sums have a fixed order, and the dot products are
/// sequential, so the result is the same at any thread count.
pub(crate) fn conjugate_gradient(
    j: &JacobianProduct,
    shift: &[f64],
    precond: &[f64],
    b: &[f64],
    tol: f64,
) -> (Vec<f64>, usize) {
    let n = b.len();
    let dot = |a: &[f64], c: &[f64]| a.iter().zip(c).map(|(x, y)| x * y).sum::<f64>();
    let inv: Vec<f64> = precond.iter().map(|&p| if p > 0.0 { 1.0 / p } else { 0.0 }).collect();
    let mut x = vec![0.0; n];
    let mut r = b.to_vec();
    let mut z: Vec<f64> = r.iter().zip(&inv).map(|(a, m)| a * m).collect();
    let mut p = z.clone();
    let mut ap = vec![0.0; n];
    let mut t = Vec::new();
    let mut rz = dot(&r, &z);
    let target = tol * dot(b, b).sqrt();
    let mut used = 0;
    for _ in 0..CG_MAX_ITERATIONS {
        if dot(&r, &r).sqrt() <= target || rz <= 0.0 {
            break;
        }
        j.apply(&p, shift, &mut t, &mut ap);
        let pap = dot(&p, &ap);
        if pap <= 0.0 || !pap.is_finite() {
            break;
        }
        used += 1;
        let alpha = rz / pap;
        for c in 0..n {
            x[c] += alpha * p[c];
            r[c] -= alpha * ap[c];
            z[c] = r[c] * inv[c];
        }
        let rz_new = dot(&r, &z);
        let beta = rz_new / rz;
        rz = rz_new;
        for c in 0..n {
            p[c] = z[c] + beta * p[c];
        }
    }
    (x, used)
}

/// The stacked Jacobian J by row blocks (one block per residual of up to two components): the
/// free columns and their two derivatives, for the matrix-free (conjugate gradient) solve.
#[derive(Default)]
pub(crate) struct JacobianRows {
    /// Block b's entries are `ptr[b]..ptr[b + 1]`.
    pub(crate) ptr: Vec<u32>,
    pub(crate) col: Vec<u32>,
    pub(crate) d: Vec<[f64; 2]>,
}

/// J by rows and by columns, for y = (JᵀJ + diag(shift)) x in two parallel passes: t = Jx by
/// row blocks, then y = Jᵀt by columns (each column's terms in row order).
///
/// The entries are stored in f32 (mixed precision: the vectors, sums, gradient, diagonal and
/// energies stay f64). The products only steer the inexact CG step, whose quality the gain ratio
/// checks against the true energy. It halves the memory J holds during a whole-mesh iteration
/// (640 → 320 MB at 1M vertices); the wall time did not change measurably (docs/benchmarks.md).
pub(crate) struct JacobianProduct {
    ptr: Vec<u32>,
    col: Vec<u32>,
    d: Vec<[f32; 2]>,
    /// Column c's entries are `col_ptr[c]..col_ptr[c + 1]` of `t_block` (their row block) and
    /// `t_d` (their derivatives): J's entries copied in column order, so that the Jᵀ pass
    /// streams through memory instead of gathering.
    col_ptr: Vec<u32>,
    t_block: Vec<u32>,
    t_d: Vec<[f32; 2]>,
}

impl JacobianProduct {
    pub(crate) fn new(rows: JacobianRows, n: usize) -> Self {
        let blocks = rows.ptr.len().saturating_sub(1);
        let mut col_ptr = vec![0u32; n + 1];
        for &c in &rows.col {
            col_ptr[c as usize + 1] += 1;
        }
        for c in 0..n {
            col_ptr[c + 1] += col_ptr[c];
        }
        let mut next = col_ptr.clone();
        let mut t_block = vec![0u32; rows.col.len()];
        let mut t_d = vec![[0.0f32; 2]; rows.col.len()];
        let d: Vec<[f32; 2]> = rows.d.iter().map(|v| [v[0] as f32, v[1] as f32]).collect();
        for b in 0..blocks {
            for e in rows.ptr[b] as usize..rows.ptr[b + 1] as usize {
                let slot = &mut next[rows.col[e] as usize];
                t_block[*slot as usize] = b as u32;
                t_d[*slot as usize] = d[e];
                *slot += 1;
            }
        }
        JacobianProduct { ptr: rows.ptr, col: rows.col, d, col_ptr, t_block, t_d }
    }

    /// y = (JᵀJ + diag(shift)) x.
    pub(crate) fn apply(&self, x: &[f64], shift: &[f64], t: &mut Vec<[f64; 2]>, y: &mut [f64]) {
        let r = self;
        let blocks = r.ptr.len().saturating_sub(1);
        t.resize(blocks, [0.0; 2]);
        t.par_chunks_mut(4096).enumerate().for_each(|(k, chunk)| {
            for (i, tb) in chunk.iter_mut().enumerate() {
                let b = k * 4096 + i;
                let (mut t0, mut t1) = (0.0, 0.0);
                for e in r.ptr[b] as usize..r.ptr[b + 1] as usize {
                    let xc = x[r.col[e] as usize];
                    t0 += r.d[e][0] as f64 * xc;
                    t1 += r.d[e][1] as f64 * xc;
                }
                *tb = [t0, t1];
            }
        });
        let t = &*t;
        y.par_chunks_mut(4096).enumerate().for_each(|(k, chunk)| {
            for (i, yc) in chunk.iter_mut().enumerate() {
                let c = k * 4096 + i;
                let mut acc = shift[c] * x[c];
                for e in self.col_ptr[c] as usize..self.col_ptr[c + 1] as usize {
                    let tb = t[self.t_block[e] as usize];
                    acc += self.t_d[e][0] as f64 * tb[0] + self.t_d[e][1] as f64 * tb[1];
                }
                *yc = acc;
            }
        });
    }
}

impl JacobianRows {
    pub(crate) fn append(&mut self, other: &JacobianRows) {
        let base = self.col.len() as u32;
        if self.ptr.is_empty() {
            self.ptr.push(0);
        }
        self.ptr.extend(other.ptr.iter().skip(1).map(|&p| p + base));
        self.col.extend_from_slice(&other.col);
        self.d.extend_from_slice(&other.d);
    }

    /// diag(JᵀJ).
    pub(crate) fn diagonal(&self, n: usize) -> Vec<f64> {
        let mut out = vec![0.0; n];
        for (c, d) in self.col.iter().zip(&self.d) {
            out[*c as usize] += d[0] * d[0] + d[1] * d[1];
        }
        out
    }
}
