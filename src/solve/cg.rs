//! The inexact step of [`super::lm`] for large systems (math.md §7): the stacked Jacobian's row
//! blocks, JᵀJ assembled into a pattern fixed for the solve, the product (JᵀJ + diag(shift))x in
//! one parallel pass over its rows, and Jacobi-preconditioned conjugate gradients.

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

/// Jacobi-preconditioned conjugate gradients for (A + diag(shift)) x = b, A = JᵀJ, from x = 0,
/// stopping at ‖b − Ax‖ ≤ tol ‖b‖ or [`CG_MAX_ITERATIONS`]. Returns x and the iterations used.
/// The products and vector updates run in parallel chunks, and the dot products add fixed chunks
/// in order, so the result is the same at any thread count.
pub(crate) fn conjugate_gradient(
    a: &NormalMatrix,
    shift: &[f64],
    precond: &[f64],
    b: &[f64],
    tol: f64,
) -> (Vec<f64>, usize) {
    let n = b.len();
    let inv: Vec<f64> = precond.iter().map(|&p| if p > 0.0 { 1.0 / p } else { 0.0 }).collect();
    let mut x = vec![0.0; n];
    let mut r = b.to_vec();
    let mut z: Vec<f64> = r.iter().zip(&inv).map(|(a, m)| a * m).collect();
    let mut p = z.clone();
    let mut ap = vec![0.0; n];
    let mut rz = dot(&r, &z);
    let mut rr = dot(&r, &r);
    let target = tol * dot(b, b).sqrt();
    let mut used = 0;
    for _ in 0..CG_MAX_ITERATIONS {
        if rr.sqrt() <= target || rz <= 0.0 {
            break;
        }
        a.apply(&p, Some(shift), &mut ap);
        let pap = dot(&p, &ap);
        if pap <= 0.0 || !pap.is_finite() {
            break;
        }
        used += 1;
        let alpha = rz / pap;
        // x += αp, r −= αAp, z = M⁻¹r, with the chunk sums of rᵀz and rᵀr.
        let parts: Vec<(f64, f64)> = x
            .par_chunks_mut(VECTOR_CHUNK)
            .zip(r.par_chunks_mut(VECTOR_CHUNK))
            .zip(z.par_chunks_mut(VECTOR_CHUNK))
            .zip(p.par_chunks(VECTOR_CHUNK).zip(ap.par_chunks(VECTOR_CHUNK)))
            .zip(inv.par_chunks(VECTOR_CHUNK))
            .map(|((((xs, rs), zs), (ps, aps)), invs)| {
                let (mut sz, mut sr) = (0.0, 0.0);
                for i in 0..xs.len() {
                    xs[i] += alpha * ps[i];
                    rs[i] -= alpha * aps[i];
                    zs[i] = rs[i] * invs[i];
                    sz += rs[i] * zs[i];
                    sr += rs[i] * rs[i];
                }
                (sz, sr)
            })
            .collect();
        let rz_new: f64 = parts.iter().map(|q| q.0).sum();
        rr = parts.iter().map(|q| q.1).sum();
        let beta = rz_new / rz;
        rz = rz_new;
        p.par_chunks_mut(VECTOR_CHUNK).zip(z.par_chunks(VECTOR_CHUNK)).for_each(|(ps, zs)| {
            for (pi, zi) in ps.iter_mut().zip(zs) {
                *pi = zi + beta * *pi;
            }
        });
    }
    (x, used)
}

/// The stacked Jacobian J by row blocks (one block per residual of up to two components): the
/// free columns and their two derivatives (the second is zero in one-component blocks), from
/// which the direct path and [`NormalMatrix`] fill JᵀJ.
#[derive(Default)]
pub(crate) struct JacobianRows {
    /// Block b's entries are `ptr[b]..ptr[b + 1]`.
    pub(crate) ptr: Vec<u32>,
    pub(crate) col: Vec<u32>,
    pub(crate) d: Vec<[f64; 2]>,
}

/// Rows of the normal matrix per parallel chunk (fill and product). Chunks are fixed by the row
/// order alone and each row's sum has a fixed order, so results do not depend on the thread
/// count.
const ROWS_PER_CHUNK: usize = 2048;

/// Σ aᵢbᵢ in fixed chunks added in order: parallel, and the same bits at any thread count.
fn dot(a: &[f64], b: &[f64]) -> f64 {
    let parts: Vec<f64> = a
        .par_chunks(VECTOR_CHUNK)
        .zip(b.par_chunks(VECTOR_CHUNK))
        .map(|(x, y)| x.iter().zip(y).map(|(p, q)| p * q).sum::<f64>())
        .collect();
    parts.iter().sum()
}

/// Vector entries per parallel chunk of the conjugate gradients' updates and dot products.
const VECTOR_CHUNK: usize = 16_384;

/// JᵀJ assembled into a sparsity pattern fixed for a whole solve, both triangles stored by rows
/// (CSR), for y = (JᵀJ + diag(shift)) x in one parallel pass over the rows.
///
/// The pattern comes from the Jacobian's row structure ([`JacobianRows`]: the structure does not
/// change between iterations): row c holds every column that shares a row block with c, the
/// 2-ring of the Eq. 10 stencils (about 19 entries a row on a closed mesh). Each
/// [`NormalMatrix::fill`] recomputes the values row by row: row c gathers the products d_c·d_a of
/// every row block that holds c (a per-thread column → slot map, no atomics, a fixed summation
/// order).
///
/// One product streams the matrix once (about 8 bytes an entry), where the matrix-free
/// Jᵀ(Jx) it replaces streamed J twice (by rows and by columns, about 3× the bytes); the
/// values are stored in f32 (mixed precision: the vectors, sums, gradient, diagonal and
/// energies stay f64). The products only steer the inexact CG step, whose quality the gain ratio
/// checks against the true energy.
pub(crate) struct NormalMatrix {
    n: usize,
    /// Row c's entries are `row_ptr[c]..row_ptr[c + 1]` (columns ascending).
    row_ptr: Vec<u32>,
    col: Vec<u32>,
    val: Vec<f32>,
    /// diag(JᵀJ) in f64, from the last fill.
    diag: Vec<f64>,
    /// Column c's row blocks are `cb[cb_ptr[c]..cb_ptr[c + 1]]` (blocks ascending).
    cb_ptr: Vec<u32>,
    cb: Vec<u32>,
    /// The row structure the pattern was built from (its block count and entry count).
    key: (usize, usize),
}

impl NormalMatrix {
    /// The pattern of JᵀJ for `n` unknowns from the Jacobian's row structure.
    pub(crate) fn new(rows: &JacobianRows, n: usize) -> Self {
        let (ptr, col) = (&rows.ptr, &rows.col);
        let blocks = ptr.len().saturating_sub(1);
        let (cb_ptr, cb) = rows.blocks_by_column(n);
        // Row c's columns: every column of every block holding c, gathered with a marker (one
        // per chunk of rows; a row's marks are its own index, so the marker is never reset).
        let parts: Vec<(Vec<u32>, Vec<u32>)> = (0..n.div_ceil(ROWS_PER_CHUNK))
            .into_par_iter()
            .map_init(
                || vec![u32::MAX; n],
                |mark, k| {
                    let rows_k = k * ROWS_PER_CHUNK..((k + 1) * ROWS_PER_CHUNK).min(n);
                    let mut len = Vec::with_capacity(rows_k.len());
                    let mut cols = Vec::with_capacity(20 * rows_k.len());
                    for c in rows_k {
                        let start = cols.len();
                        mark[c] = c as u32;
                        cols.push(c as u32);
                        for &b in &cb[cb_ptr[c] as usize..cb_ptr[c + 1] as usize] {
                            for &a in &col[ptr[b as usize] as usize..ptr[b as usize + 1] as usize] {
                                if mark[a as usize] != c as u32 {
                                    mark[a as usize] = c as u32;
                                    cols.push(a);
                                }
                            }
                        }
                        cols[start..].sort_unstable();
                        len.push((cols.len() - start) as u32);
                    }
                    (len, cols)
                },
            )
            .collect();
        let nnz: usize = parts.iter().map(|p| p.1.len()).sum();
        let mut row_ptr = Vec::with_capacity(n + 1);
        row_ptr.push(0u32);
        let mut all = Vec::with_capacity(nnz);
        for (len, cols) in parts {
            for l in len {
                row_ptr.push(row_ptr.last().copied().unwrap_or(0) + l);
            }
            all.extend_from_slice(&cols);
        }
        NormalMatrix {
            n,
            row_ptr,
            col: all,
            val: vec![0.0; nnz],
            diag: vec![0.0; n],
            cb_ptr,
            cb,
            key: (blocks, rows.col.len()),
        }
    }

    /// Whether `rows` has the block and entry counts the pattern was built from (the row
    /// structure itself depends only on the mesh and the free set, [`super::lm`]).
    pub(crate) fn matches(&self, rows: &JacobianRows, n: usize) -> bool {
        self.n == n && self.key == (rows.ptr.len().saturating_sub(1), rows.col.len())
    }

    /// Recomputes JᵀJ's values (and its diagonal) from the Jacobian's rows.
    pub(crate) fn fill(&mut self, rows: &JacobianRows) {
        let n = self.n;
        let (ptr, col, d) = (&rows.ptr, &rows.col, &rows.d);
        let (row_ptr, cols, cb_ptr, cb) = (&self.row_ptr, &self.col, &self.cb_ptr, &self.cb);
        let starts: Vec<usize> =
            (0..n.div_ceil(ROWS_PER_CHUNK)).map(|k| row_ptr[k * ROWS_PER_CHUNK] as usize).collect();
        let mut val_chunks: Vec<&mut [f32]> = Vec::with_capacity(starts.len());
        let mut rest: &mut [f32] = &mut self.val;
        for k in 0..starts.len() {
            let end = row_ptr[((k + 1) * ROWS_PER_CHUNK).min(n)] as usize;
            let (head, tail) = rest.split_at_mut(end - starts[k]);
            val_chunks.push(head);
            rest = tail;
        }
        let diag_chunks = self.diag.par_chunks_mut(ROWS_PER_CHUNK);
        val_chunks.into_par_iter().zip(diag_chunks).enumerate().for_each_init(
            || (vec![0u32; n], Vec::<f64>::new()),
            |(slot, acc), (k, (vals, diag))| {
                let base = starts[k];
                for (i, dc) in diag.iter_mut().enumerate() {
                    let c = k * ROWS_PER_CHUNK + i;
                    let entries = row_ptr[c] as usize..row_ptr[c + 1] as usize;
                    acc.clear();
                    acc.resize(entries.len(), 0.0);
                    for (s, &a) in cols[entries.clone()].iter().enumerate() {
                        slot[a as usize] = s as u32;
                    }
                    let mut last = u32::MAX;
                    for &b in &cb[cb_ptr[c] as usize..cb_ptr[c + 1] as usize] {
                        // A block listing c twice appears twice here; its terms count once.
                        if b == last {
                            continue;
                        }
                        last = b;
                        let block = ptr[b as usize] as usize..ptr[b as usize + 1] as usize;
                        // c's derivatives in this block (a block may list a column twice).
                        let mut dcb = [0.0f64; 2];
                        for e in block.clone() {
                            if col[e] as usize == c {
                                dcb[0] += d[e][0];
                                dcb[1] += d[e][1];
                            }
                        }
                        for e in block {
                            acc[slot[col[e] as usize] as usize] +=
                                dcb[0] * d[e][0] + dcb[1] * d[e][1];
                        }
                    }
                    for (s, v) in acc.iter().enumerate() {
                        vals[entries.start - base + s] = *v as f32;
                    }
                    *dc = acc[slot[c] as usize];
                }
            },
        );
    }

    /// diag(JᵀJ) of the last fill.
    pub(crate) fn diagonal(&self) -> &[f64] {
        &self.diag
    }

    /// y = (JᵀJ + diag(shift)) x, by rows in parallel chunks (each row's sum in column order).
    pub(crate) fn apply(&self, x: &[f64], shift: Option<&[f64]>, y: &mut [f64]) {
        let (row_ptr, col, val) = (&self.row_ptr, &self.col, &self.val);
        y.par_chunks_mut(ROWS_PER_CHUNK).enumerate().for_each(|(k, chunk)| {
            for (i, yc) in chunk.iter_mut().enumerate() {
                let c = k * ROWS_PER_CHUNK + i;
                let mut acc = shift.map_or(0.0, |s| s[c] * x[c]);
                for e in row_ptr[c] as usize..row_ptr[c + 1] as usize {
                    acc += val[e] as f64 * x[col[e] as usize];
                }
                *yc = acc;
            }
        });
    }
}

impl JacobianRows {
    /// For each of the `n` columns, the row blocks that hold it, ascending (a block that lists
    /// a column twice appears twice), by a counting sort: column c's blocks are
    /// `cb[cb_ptr[c]..cb_ptr[c + 1]]`. Returns `(cb_ptr, cb)`.
    pub(crate) fn blocks_by_column(&self, n: usize) -> (Vec<u32>, Vec<u32>) {
        let (ptr, col) = (&self.ptr, &self.col);
        let mut cb_ptr = vec![0u32; n + 1];
        for &c in col.iter() {
            cb_ptr[c as usize + 1] += 1;
        }
        for c in 0..n {
            cb_ptr[c + 1] += cb_ptr[c];
        }
        let mut next = cb_ptr.clone();
        let mut cb = vec![0u32; col.len()];
        for b in 0..ptr.len().saturating_sub(1) {
            for &c in &col[ptr[b] as usize..ptr[b + 1] as usize] {
                cb[next[c as usize] as usize] = b as u32;
                next[c as usize] += 1;
            }
        }
        (cb_ptr, cb)
    }

    pub(crate) fn append(&mut self, other: &JacobianRows) {
        let base = self.col.len() as u32;
        if self.ptr.is_empty() {
            self.ptr.push(0);
        }
        self.ptr.extend(other.ptr.iter().skip(1).map(|&p| p + base));
        self.col.extend_from_slice(&other.col);
        self.d.extend_from_slice(&other.d);
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use nalgebra::{DMatrix, DVector};

    /// Random row blocks of one or two components over `n` columns; every 11th block lists a
    /// column twice. Values are multiples of 1/16 in [−2, 2), so JᵀJ's entries are exact in f32
    /// and the f32 storage is not the difference tested.
    fn random_rows(n: usize, blocks: usize, seed: u64) -> JacobianRows {
        let mut x = seed;
        let mut rnd = || {
            x = x.wrapping_mul(6364136223846793005).wrapping_add(1442695040888963407);
            ((x >> 40) % 64) as f64 / 16.0 - 2.0
        };
        let mut rows = JacobianRows { ptr: vec![0], ..Default::default() };
        for b in 0..blocks {
            let two = b < blocks / 2;
            for k in 0..1 + b % 5 {
                rows.col.push(((b * 13 + k * 7) % n) as u32);
                rows.d.push([rnd(), if two { rnd() } else { 0.0 }]);
            }
            if b % 11 == 0 {
                rows.col.push(((b * 13) % n) as u32);
                rows.d.push([rnd(), if two { rnd() } else { 0.0 }]);
            }
            rows.ptr.push(rows.col.len() as u32);
        }
        rows
    }

    /// (JᵀJ + diag(shift)) x and diag(JᵀJ) from the assembled matrix against nalgebra's dense
    /// J built from the same blocks.
    #[test]
    fn normal_matrix_matches_a_dense_product() {
        let (n, blocks) = (50usize, 120usize);
        let rows = random_rows(n, blocks, 7);
        let mut j = DMatrix::<f64>::zeros(2 * blocks, n);
        for b in 0..blocks {
            for e in rows.ptr[b] as usize..rows.ptr[b + 1] as usize {
                j[(2 * b, rows.col[e] as usize)] += rows.d[e][0];
                j[(2 * b + 1, rows.col[e] as usize)] += rows.d[e][1];
            }
        }
        let jtj = j.transpose() * &j;
        let mut a = NormalMatrix::new(&rows, n);
        assert!(a.matches(&rows, n));
        a.fill(&rows);
        for c in 0..n {
            assert_eq!(a.diagonal()[c], jtj[(c, c)], "diagonal {c}");
        }
        let xs: Vec<f64> = (0..n).map(|c| (c % 7) as f64 - 3.0).collect();
        let shift: Vec<f64> = (0..n).map(|c| (c % 3) as f64).collect();
        let mut y = vec![0.0; n];
        a.apply(&xs, Some(&shift), &mut y);
        let want = &jtj * DVector::from_vec(xs.clone());
        for c in 0..n {
            let w = want[c] + shift[c] * xs[c];
            assert!((y[c] - w).abs() <= 1e-12 * w.abs().max(1.0), "{c}: {} against {w}", y[c]);
        }
    }

    /// Over several parallel chunks of rows: the product against Jᵀ(Jx) computed block by
    /// block, and a refill with other values of the same structure.
    #[test]
    fn normal_matrix_over_several_chunks() {
        let n = 3 * ROWS_PER_CHUNK + 17;
        let mut a = NormalMatrix::new(&random_rows(n, 4 * n, 3), n);
        for seed in [3, 11] {
            let rows = random_rows(n, 4 * n, seed);
            assert!(a.matches(&rows, n));
            a.fill(&rows);
            let xs: Vec<f64> = (0..n).map(|c| ((c * 37) % 19) as f64 / 4.0 - 2.0).collect();
            let mut want = vec![0.0; n];
            for b in 0..rows.ptr.len() - 1 {
                let block = rows.ptr[b] as usize..rows.ptr[b + 1] as usize;
                let mut t = [0.0; 2];
                for e in block.clone() {
                    t[0] += rows.d[e][0] * xs[rows.col[e] as usize];
                    t[1] += rows.d[e][1] * xs[rows.col[e] as usize];
                }
                for e in block {
                    want[rows.col[e] as usize] += rows.d[e][0] * t[0] + rows.d[e][1] * t[1];
                }
            }
            let mut y = vec![0.0; n];
            a.apply(&xs, None, &mut y);
            for c in 0..n {
                let w = want[c];
                assert!((y[c] - w).abs() <= 1e-9 * w.abs().max(1.0), "{c}: {} against {w}", y[c]);
            }
        }
    }
}
