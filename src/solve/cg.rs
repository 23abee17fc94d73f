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
    let mut t = ProductScratch::default();
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
    /// The blocks from this one on have a single residual component (their second derivative
    /// is zero); [`JacobianProduct`] stores them without it.
    pub(crate) split: usize,
}

/// J by rows and by columns, for y = (JᵀJ + diag(shift)) x in two parallel passes: t = Jx by
/// row blocks, then y = Jᵀt by columns (each column's terms in row order).
///
/// The entries are stored in f32 (mixed precision: the vectors, sums, gradient, diagonal and
/// energies stay f64). The products only steer the inexact CG step, whose quality the gain ratio
/// checks against the true energy. It halves the memory J holds during a whole-mesh iteration
/// (640 → 320 MB at 1M vertices); the wall time did not change measurably (docs/benchmarks.md).
///
/// The row blocks from `split` on have one residual component (smoothness, hinges, locks: the
/// blocks after the highlight rows), and are stored without the zero second component: a
/// third less memory streamed per product on a whole mesh.
pub(crate) struct JacobianProduct {
    split: usize,
    ptr: Vec<u32>,
    col: Vec<u32>,
    /// Derivatives of the two-component blocks' entries (entries before `ptr[split]`).
    d2: Vec<[f32; 2]>,
    /// Derivatives of the one-component blocks' entries (entries from `ptr[split]`).
    d1: Vec<f32>,
    /// Column c's two-component entries are `col_ptr2[c]..col_ptr2[c + 1]` of `t_block2`
    /// (their row block) and `t_d2` (their derivatives), its one-component ones likewise (row
    /// blocks counted from `split`): J's entries copied in column order, so that the Jᵀ pass
    /// streams through memory instead of gathering.
    col_ptr2: Vec<u32>,
    t_block2: Vec<u32>,
    t_d2: Vec<[f32; 2]>,
    col_ptr1: Vec<u32>,
    t_block1: Vec<u32>,
    t_d1: Vec<f32>,
}

/// The scratch of [`JacobianProduct::apply`]: t = Jx for the two- and one-component blocks.
#[derive(Default)]
pub(crate) struct ProductScratch {
    t2: Vec<[f64; 2]>,
    t1: Vec<f64>,
}

/// The column-ordered copy of the entries `range` of `rows` (blocks counted from `first`).
fn by_column<T: Copy + Default>(
    rows: &JacobianRows,
    n: usize,
    blocks: std::ops::Range<usize>,
    value: impl Fn(usize) -> T,
) -> (Vec<u32>, Vec<u32>, Vec<T>) {
    let (first, entries) =
        (blocks.start, rows.ptr[blocks.start] as usize..rows.ptr[blocks.end] as usize);
    let mut col_ptr = vec![0u32; n + 1];
    for &c in &rows.col[entries.clone()] {
        col_ptr[c as usize + 1] += 1;
    }
    for c in 0..n {
        col_ptr[c + 1] += col_ptr[c];
    }
    let mut next = col_ptr.clone();
    let mut t_block = vec![0u32; entries.len()];
    let mut t_d = vec![T::default(); entries.len()];
    for b in blocks {
        for e in rows.ptr[b] as usize..rows.ptr[b + 1] as usize {
            let slot = &mut next[rows.col[e] as usize];
            t_block[*slot as usize] = (b - first) as u32;
            t_d[*slot as usize] = value(e);
            *slot += 1;
        }
    }
    (col_ptr, t_block, t_d)
}

impl JacobianProduct {
    pub(crate) fn new(rows: JacobianRows, n: usize) -> Self {
        let blocks = rows.ptr.len().saturating_sub(1);
        let split = rows.split.min(blocks);
        let e_split = rows.ptr[split] as usize;
        let d2: Vec<[f32; 2]> =
            rows.d[..e_split].iter().map(|v| [v[0] as f32, v[1] as f32]).collect();
        let d1: Vec<f32> = rows.d[e_split..].iter().map(|v| v[0] as f32).collect();
        let (col_ptr2, t_block2, t_d2) = by_column(&rows, n, 0..split, |e| d2[e]);
        let (col_ptr1, t_block1, t_d1) = by_column(&rows, n, split..blocks, |e| d1[e - e_split]);
        JacobianProduct {
            split,
            ptr: rows.ptr,
            col: rows.col,
            d2,
            d1,
            col_ptr2,
            t_block2,
            t_d2,
            col_ptr1,
            t_block1,
            t_d1,
        }
    }

    /// y = (JᵀJ + diag(shift)) x.
    pub(crate) fn apply(&self, x: &[f64], shift: &[f64], t: &mut ProductScratch, y: &mut [f64]) {
        let r = self;
        let blocks = r.ptr.len().saturating_sub(1);
        let e_split = r.ptr[r.split] as usize;
        t.t2.resize(r.split, [0.0; 2]);
        t.t1.resize(blocks - r.split, 0.0);
        t.t2.par_chunks_mut(4096).enumerate().for_each(|(k, chunk)| {
            for (i, tb) in chunk.iter_mut().enumerate() {
                let b = k * 4096 + i;
                let (mut t0, mut t1) = (0.0, 0.0);
                for e in r.ptr[b] as usize..r.ptr[b + 1] as usize {
                    let xc = x[r.col[e] as usize];
                    t0 += r.d2[e][0] as f64 * xc;
                    t1 += r.d2[e][1] as f64 * xc;
                }
                *tb = [t0, t1];
            }
        });
        t.t1.par_chunks_mut(4096).enumerate().for_each(|(k, chunk)| {
            for (i, tb) in chunk.iter_mut().enumerate() {
                let b = r.split + k * 4096 + i;
                let mut t0 = 0.0;
                for e in r.ptr[b] as usize..r.ptr[b + 1] as usize {
                    t0 += r.d1[e - e_split] as f64 * x[r.col[e] as usize];
                }
                *tb = t0;
            }
        });
        let (t2, t1) = (&t.t2, &t.t1);
        y.par_chunks_mut(4096).enumerate().for_each(|(k, chunk)| {
            for (i, yc) in chunk.iter_mut().enumerate() {
                let c = k * 4096 + i;
                let mut acc = shift[c] * x[c];
                for e in r.col_ptr2[c] as usize..r.col_ptr2[c + 1] as usize {
                    let tb = t2[r.t_block2[e] as usize];
                    acc += r.t_d2[e][0] as f64 * tb[0] + r.t_d2[e][1] as f64 * tb[1];
                }
                for e in r.col_ptr1[c] as usize..r.col_ptr1[c + 1] as usize {
                    acc += r.t_d1[e] as f64 * t1[r.t_block1[e] as usize];
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

#[cfg(test)]
mod tests {
    use super::*;
    use nalgebra::{DMatrix, DVector};

    /// (JᵀJ + diag(shift)) x through the stored product against nalgebra's dense product, with
    /// two-component blocks first and one-component blocks (second derivative zero) after.
    #[test]
    fn product_matches_a_dense_one() {
        let (n, blocks, split) = (50usize, 120usize, 70usize);
        let mut x = 7u64;
        let mut rnd = || {
            x = x.wrapping_mul(6364136223846793005).wrapping_add(1442695040888963407);
            // Values exact in f32, so the f32 storage is not the difference tested.
            ((x >> 40) % 64) as f64 / 16.0 - 2.0
        };
        let mut rows = JacobianRows { ptr: vec![0], split, ..Default::default() };
        let mut j = DMatrix::<f64>::zeros(2 * blocks, n);
        for b in 0..blocks {
            for k in 0..1 + b % 5 {
                let c = (b * 13 + k * 7) % n;
                let d = [rnd(), if b < split { rnd() } else { 0.0 }];
                rows.col.push(c as u32);
                rows.d.push(d);
                j[(2 * b, c)] += d[0];
                j[(2 * b + 1, c)] += d[1];
            }
            rows.ptr.push(rows.col.len() as u32);
        }
        let diag = rows.diagonal(n);
        let jtj = j.transpose() * &j;
        for c in 0..n {
            assert_eq!(diag[c], jtj[(c, c)]);
        }
        let product = JacobianProduct::new(rows, n);
        let xs: Vec<f64> = (0..n).map(|c| (c % 7) as f64 - 3.0).collect();
        let shift: Vec<f64> = (0..n).map(|c| (c % 3) as f64).collect();
        let mut y = vec![0.0; n];
        product.apply(&xs, &shift, &mut ProductScratch::default(), &mut y);
        let want = &jtj * DVector::from_vec(xs.clone());
        for c in 0..n {
            let w = want[c] + shift[c] * xs[c];
            assert!((y[c] - w).abs() <= 1e-12 * w.abs().max(1.0), "{c}: {} against {w}", y[c]);
        }
    }
}
