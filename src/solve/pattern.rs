//! The direct linear solve of [`super::lm`]: the damped normal equations
//! (JᵀJ + λD) δ = −Jᵀr (math.md §4, the paper's §4.3) in a sparsity pattern fixed for a whole
//! solve, and shared by later solves whose Jacobian has the same structure (the continuation
//! stages and the second start of [`super::optimize()`]).
//!
//! The pattern is built straight from the Jacobian's row structure (each row block's free
//! columns, [`JacobianRows`]): column c of JᵀJ's lower triangle holds every column that shares a
//! row block with c — the 2-ring of the Eq. 10 stencils — gathered with a marker array, no sparse
//! product and no triplet sort. The unknowns are renumbered once in a fill-reducing order
//! (approximate minimum degree) and the pattern is stored in that order, so the Cholesky
//! factorization of every damping try reads the matrix in place (no per-try permutation), and
//! every JᵀJ product of the assembly has a precomputed value slot.

use faer::dyn_stack::{MemBuffer, MemStack};
use faer::linalg::cholesky::llt::factor::LltRegularization;
use faer::prelude::*;
use faer::sparse::linalg::amd;
use faer::sparse::linalg::cholesky::{
    factorize_symbolic_cholesky, CholeskySymbolicParams, SymbolicCholesky, SymmetricOrdering,
};
use faer::sparse::linalg::SupernodalThreshold;
use faer::sparse::{SparseColMatRef, SymbolicSparseColMatRef};
use faer::{Conj, Par, Side};

use super::cg::JacobianRows;

/// Up to this many unknowns the direct path orders them by reverse Cuthill–McKee, above by
/// approximate minimum degree. Measured (bench_solver, ms): at 656 free vertices of a brush
/// RCM gives nnz(L) 43.4k against AMD's 36.6k with the same factorization time (0.4–0.6 ms),
/// and the set-up drops from ~1.4 to ~0.9 ms; on a whole torus of 3k vertices (periodic, so
/// a wide band) RCM's factor is 25 % larger and slower, so AMD takes over early.
const RCM_MAX_UNKNOWNS: usize = 1024;

/// What [`super::lm::solve_cached`] keeps between solves: the direct path's pattern, ordering
/// and symbolic Cholesky analysis, reused when the next solve's Jacobian has the same row
/// structure (same free set, same residual blocks), rebuilt otherwise. Holding one across
/// solves never changes their results, only their set-up time.
#[derive(Default)]
pub struct SolveCache {
    pub(crate) direct: Option<DirectSystem>,
}

impl std::fmt::Debug for SolveCache {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("SolveCache").field("unknowns", &self.direct.as_ref().map(|d| d.n)).finish()
    }
}

/// The lower triangle of P(JᵀJ)Pᵀ (P the fill-reducing renumbering) with its symbolic Cholesky
/// analysis, the factor's values and the factorization's workspace, all allocated once. Each
/// iteration refills the values from the Jacobian's rows ([`DirectSystem::fill`]); each damping
/// try refactorizes in place, sequentially (so the result does not depend on the thread count).
pub(crate) struct DirectSystem {
    n: usize,
    /// The row structure the pattern was built from (`JacobianRows::ptr`, `col`).
    key_ptr: Vec<u32>,
    key_col: Vec<u32>,
    /// `new_of[c]`: the position of unknown c in the elimination order.
    new_of: Vec<usize>,
    col_ptr: Vec<usize>,
    row_idx: Vec<usize>,
    /// Value slot of every JᵀJ product, in the order [`DirectSystem::fill`] computes them.
    slot: Vec<u32>,
    /// JᵀJ (undamped) of the last fill, and the damped matrix handed to the factorization.
    base: Vec<f64>,
    vals: Vec<f64>,
    symbolic: SymbolicCholesky<usize>,
    l_values: Vec<f64>,
    workspace: MemBuffer,
    rhs: Vec<f64>,
}

impl DirectSystem {
    /// Builds the pattern, the ordering and the symbolic analysis for `n` unknowns from the
    /// Jacobian's row structure.
    pub(crate) fn new(rows: &JacobianRows, n: usize) -> Result<Self, String> {
        let (ptr, col) = (&rows.ptr, &rows.col);
        let (lp, li) = lower_pattern(rows, n);
        let new_of = fill_reducing_order(n, &lp, &li)?;
        let (col_ptr, row_idx) = renumbered(n, &lp, &li, &new_of);
        let slot = product_slots(rows, n, &new_of, &col_ptr, &row_idx);
        let symbolic = symbolic_analysis(n, &col_ptr, &row_idx)?;
        // The factor's size is known here, before it is allocated (issue 15, item 12).
        crate::factor::check_factor_size("solve", symbolic.len_val(), 8)
            .map_err(|e| e.to_string())?;
        let l_values = vec![0.0; symbolic.len_val()];
        let workspace = MemBuffer::try_new(
            symbolic
                .factorize_numeric_llt_scratch::<f64>(Par::Seq, Default::default())
                .or(symbolic.solve_in_place_scratch::<f64>(1, Par::Seq)),
        )
        .map_err(|_| "out of memory for the factorization workspace".to_string())?;
        let nnz = row_idx.len();
        Ok(DirectSystem {
            n,
            key_ptr: ptr.clone(),
            key_col: col.clone(),
            new_of,
            col_ptr,
            row_idx,
            slot,
            base: vec![0.0; nnz],
            vals: vec![0.0; nnz],
            symbolic,
            l_values,
            workspace,
            rhs: vec![0.0; n],
        })
    }

    /// Whether this pattern was built from the same row structure.
    pub(crate) fn matches(&self, rows: &JacobianRows, n: usize) -> bool {
        self.n == n && self.key_ptr == rows.ptr && self.key_col == rows.col
    }

    /// Refills JᵀJ from the Jacobian's rows: every product J[row, a]·J[row, b] (a ≥ b) of every
    /// row block added to its slot, sequentially in a fixed order (deterministic).
    pub(crate) fn fill(&mut self, rows: &JacobianRows) {
        debug_assert!(self.key_ptr == rows.ptr && self.key_col == rows.col);
        self.base.iter_mut().for_each(|v| *v = 0.0);
        let (base, slot) = (&mut self.base, &self.slot);
        let mut p = 0;
        for w in rows.ptr.windows(2) {
            let (s, e) = (w[0] as usize, w[1] as usize);
            let (cols, ds) = (&rows.col[s..e], &rows.d[s..e]);
            for (&a, da) in cols.iter().zip(ds) {
                for (&c, dc) in cols.iter().zip(ds) {
                    if a >= c {
                        base[slot[p] as usize] += da[0] * dc[0] + da[1] * dc[1];
                        p += 1;
                    }
                }
            }
        }
        debug_assert_eq!(p, slot.len());
    }

    /// diag(JᵀJ) of the last fill, in the unknowns' order.
    pub(crate) fn diagonal(&self) -> Vec<f64> {
        self.new_of.iter().map(|&k| self.base[self.col_ptr[k]]).collect()
    }

    /// Solves (JᵀJ + λ diag(scale)) x = rhs in place (`scale` and `rhs` in the unknowns'
    /// order): refills the damped matrix and its Cholesky factor (symbolic analysis reused).
    pub(crate) fn solve_damped(
        &mut self,
        lambda: f64,
        scale: &[f64],
        rhs: &mut [f64],
    ) -> Result<(), String> {
        self.vals.copy_from_slice(&self.base);
        for (c, &k) in self.new_of.iter().enumerate() {
            // The diagonal is the first entry of its column (rows ≥ column, sorted).
            self.vals[self.col_ptr[k]] += lambda * scale[c];
            self.rhs[k] = rhs[c];
        }
        let a = SparseColMatRef::new(
            SymbolicSparseColMatRef::new_checked(
                self.n,
                self.n,
                &self.col_ptr,
                None,
                &self.row_idx,
            ),
            &self.vals,
        );
        let llt = self
            .symbolic
            .factorize_numeric_llt(
                &mut self.l_values,
                a,
                Side::Lower,
                LltRegularization::default(),
                Par::Seq,
                MemStack::new(&mut self.workspace),
                Default::default(),
            )
            .map_err(|e| crate::error::describe_pivot(&e))?;
        let x = MatMut::from_column_major_slice_mut(&mut self.rhs, self.n, 1);
        llt.solve_in_place_with_conj(Conj::No, x, Par::Seq, MemStack::new(&mut self.workspace));
        for (c, &k) in self.new_of.iter().enumerate() {
            rhs[c] = self.rhs[k];
        }
        Ok(())
    }
}

/// Lower triangle of JᵀJ in the original numbering (diagonal always present), column
/// pointers and row indices: the columns sharing a row block, gathered with a marker.
fn lower_pattern(rows: &JacobianRows, n: usize) -> (Vec<usize>, Vec<usize>) {
    let (ptr, col) = (&rows.ptr, &rows.col);
    let range = |b: usize| ptr[b] as usize..ptr[b + 1] as usize;
    // Column → the row blocks that hold it (counting sort, blocks ascending).
    let (cb_ptr, cb) = rows.blocks_by_column(n);
    let mut mark = vec![usize::MAX; n];
    let mut lp = Vec::with_capacity(n + 1);
    let mut li: Vec<usize> = Vec::with_capacity(8 * n + col.len());
    lp.push(0usize);
    for c in 0..n {
        let start = li.len();
        mark[c] = c;
        li.push(c);
        for &b in &cb[cb_ptr[c] as usize..cb_ptr[c + 1] as usize] {
            for &a in &col[range(b as usize)] {
                let a = a as usize;
                if a > c && mark[a] != c {
                    mark[a] = c;
                    li.push(a);
                }
            }
        }
        li[start..].sort_unstable();
        lp.push(li.len());
    }
    (lp, li)
}

/// `new_of[c]`, the position of unknown c in the elimination order of the pattern `lp`, `li`.
fn fill_reducing_order(n: usize, lp: &[usize], li: &[usize]) -> Result<Vec<usize>, String> {
    // Fill-reducing order: reverse Cuthill–McKee for small systems (an edit's brush: a
    // few µs instead of AMD's ~0.5 ms, and a band the supernodal factorization handles as
    // fast as AMD's order despite ~20 % more fill), approximate minimum degree above.
    let mut fwd = vec![0usize; n];
    let mut new_of = vec![0usize; n];
    if n <= RCM_MAX_UNKNOWNS {
        let order = rcm(n, lp, li);
        for (k, &c) in order.iter().enumerate() {
            new_of[c] = k;
        }
    } else {
        let a = SymbolicSparseColMatRef::new_checked(n, n, lp, None, li);
        let mut mem = MemBuffer::try_new(amd::order_scratch::<usize>(n, li.len()))
            .map_err(|_| "out of memory for the factorization workspace".to_string())?;
        amd::order(&mut fwd, &mut new_of, a, amd::Control::default(), MemStack::new(&mut mem))
            .map_err(|e| crate::error::describe_faer(&e))?;
    }
    Ok(new_of)
}

/// The same lower triangle in the new numbering: column pointers and (sorted) row indices.
fn renumbered(n: usize, lp: &[usize], li: &[usize], new_of: &[usize]) -> (Vec<usize>, Vec<usize>) {
    let mut col_ptr = vec![0usize; n + 1];
    for c in 0..n {
        for &a in &li[lp[c]..lp[c + 1]] {
            col_ptr[new_of[a].min(new_of[c]) + 1] += 1;
        }
    }
    for c in 0..n {
        col_ptr[c + 1] += col_ptr[c];
    }
    let mut next = col_ptr.clone();
    let mut row_idx = vec![0usize; li.len()];
    for c in 0..n {
        for &a in &li[lp[c]..lp[c + 1]] {
            let (r, k) = (new_of[a].max(new_of[c]), new_of[a].min(new_of[c]));
            row_idx[next[k]] = r;
            next[k] += 1;
        }
    }
    for k in 0..n {
        row_idx[col_ptr[k]..col_ptr[k + 1]].sort_unstable();
    }
    (col_ptr, row_idx)
}

/// The value slot of every product, in fill order: each product's (row, column) in the
/// new numbering, bucketed by column, then looked up through a row → slot marker of
/// that column.
fn product_slots(
    rows: &JacobianRows,
    n: usize,
    new_of: &[usize],
    col_ptr: &[usize],
    row_idx: &[usize],
) -> Vec<u32> {
    let (ptr, col) = (&rows.ptr, &rows.col);
    let blocks = ptr.len().saturating_sub(1);
    let range = |b: usize| ptr[b] as usize..ptr[b + 1] as usize;
    let mut prod: Vec<(u32, u32)> = Vec::with_capacity(3 * row_idx.len());
    for b in 0..blocks {
        let cols = &col[range(b)];
        for &a in cols {
            for &c in cols {
                if a >= c {
                    let (na, nc) = (new_of[a as usize], new_of[c as usize]);
                    prod.push((na.max(nc) as u32, na.min(nc) as u32));
                }
            }
        }
    }
    let mut bucket_ptr = vec![0usize; n + 1];
    for &(_, k) in &prod {
        bucket_ptr[k as usize + 1] += 1;
    }
    for k in 0..n {
        bucket_ptr[k + 1] += bucket_ptr[k];
    }
    let mut next = bucket_ptr.clone();
    // Each bucket entry carries its product's row, so the lookups below read the buckets in
    // order (no gather from `prod`).
    let mut bucket = vec![(0u32, 0u32); prod.len()];
    for (p, &(r, k)) in prod.iter().enumerate() {
        bucket[next[k as usize]] = (r, p as u32);
        next[k as usize] += 1;
    }
    let mut at = vec![u32::MAX; n];
    let mut slot = vec![0u32; prod.len()];
    for k in 0..n {
        for e in col_ptr[k]..col_ptr[k + 1] {
            at[row_idx[e]] = e as u32;
        }
        for &(r, p) in &bucket[bucket_ptr[k]..bucket_ptr[k + 1]] {
            let e = at[r as usize];
            debug_assert!(
                e != u32::MAX && row_idx[e as usize] == r as usize,
                "a product outside the pattern"
            );
            slot[p as usize] = e;
        }
        for e in col_ptr[k]..col_ptr[k + 1] {
            at[row_idx[e]] = u32::MAX;
        }
    }
    slot
}

/// The symbolic Cholesky analysis of the renumbered lower triangle `col_ptr`, `row_idx`.
fn symbolic_analysis(
    n: usize,
    col_ptr: &[usize],
    row_idx: &[usize],
) -> Result<SymbolicCholesky<usize>, String> {
    // faer's symbolic analysis without a permutation reads the upper triangle as given:
    // hand it the transpose of the pattern (the numeric factorization reads the lower one).
    let mut up_ptr = vec![0usize; n + 1];
    for &r in row_idx {
        up_ptr[r + 1] += 1;
    }
    for c in 0..n {
        up_ptr[c + 1] += up_ptr[c];
    }
    let mut next = up_ptr.clone();
    let mut up_idx = vec![0usize; row_idx.len()];
    for k in 0..n {
        for &r in &row_idx[col_ptr[k]..col_ptr[k + 1]] {
            up_idx[next[r]] = k;
            next[r] += 1;
        }
    }
    factorize_symbolic_cholesky(
        SymbolicSparseColMatRef::new_checked(n, n, &up_ptr, None, &up_idx),
        Side::Upper,
        SymmetricOrdering::Identity,
        // Supernodal even where faer's flop-ratio heuristic picks the simplicial
        // (up-looking) factorization: on the 2-ring pattern of a brush of 200–700 vertices
        // it took the numeric factorization from ~1.0 to ~0.6 ms (bench_solver, Fig. 12a).
        CholeskySymbolicParams {
            supernodal_flop_ratio_threshold: SupernodalThreshold::FORCE_SUPERNODAL,
            ..Default::default()
        },
    )
    .map_err(|e| crate::error::describe_faer(&e))
}

/// Reverse Cuthill–McKee order of the symmetric pattern given by its lower triangle.
fn rcm(n: usize, lp: &[usize], li: &[usize]) -> Vec<usize> {
    // Full adjacency (both triangles, no diagonal).
    let mut deg = vec![0usize; n + 1];
    for c in 0..n {
        for &a in &li[lp[c]..lp[c + 1]] {
            if a != c {
                deg[a + 1] += 1;
                deg[c + 1] += 1;
            }
        }
    }
    for c in 0..n {
        deg[c + 1] += deg[c];
    }
    let ap = deg.clone();
    let mut next = deg;
    let mut adj = vec![0usize; ap[n]];
    for c in 0..n {
        for &a in &li[lp[c]..lp[c + 1]] {
            if a != c {
                adj[next[a]] = c;
                next[a] += 1;
                adj[next[c]] = a;
                next[c] += 1;
            }
        }
    }
    let degree = |v: usize| ap[v + 1] - ap[v];
    let mut order = Vec::with_capacity(n);
    let mut seen = vec![false; n];
    let bfs = |start: usize, seen: &mut [bool], out: &mut Vec<usize>| {
        let base = out.len();
        seen[start] = true;
        out.push(start);
        let mut head = base;
        while head < out.len() {
            let v = out[head];
            head += 1;
            let from = out.len();
            for &u in &adj[ap[v]..ap[v + 1]] {
                if !seen[u] {
                    seen[u] = true;
                    out.push(u);
                }
            }
            out[from..].sort_by_key(|&u| (degree(u), u));
        }
    };
    // Pseudo-peripheral start of each component: the last vertex reached by a breadth-first
    // search from its first vertex, twice (the searches' marks are undone through their lists).
    let mut scratch = Vec::new();
    for s0 in 0..n {
        if seen[s0] {
            continue;
        }
        let mut start = s0;
        for _ in 0..2 {
            scratch.clear();
            bfs(start, &mut seen, &mut scratch);
            start = *scratch.last().expect("non-empty");
            for &v in &scratch {
                seen[v] = false;
            }
        }
        bfs(start, &mut seen, &mut order);
    }
    order.reverse();
    order
}

#[cfg(test)]
mod tests {
    use super::*;
    use nalgebra::{DMatrix, DVector};

    /// A Jacobian on a path of `n` unknowns with blocks of up to 5 consecutive columns (some
    /// two-component, some one-component), values from a fixed linear congruential sequence.
    fn rows(n: usize, seed: u64) -> JacobianRows {
        let mut x = seed;
        let mut rnd = || {
            x = x.wrapping_mul(6364136223846793005).wrapping_add(1442695040888963407);
            ((x >> 11) as f64 / (1u64 << 53) as f64) * 2.0 - 1.0
        };
        let mut r = JacobianRows { ptr: vec![0], ..Default::default() };
        for i in 0..n {
            for width in [5usize, 2] {
                for c in i.saturating_sub(width / 2)..(i + width / 2 + 1).min(n) {
                    // Scramble the column numbers so the order matters.
                    r.col.push(((c * 7919) % n) as u32);
                    r.d.push([rnd(), if width == 5 { rnd() } else { 0.0 }]);
                }
                r.ptr.push(r.col.len() as u32);
            }
        }
        r
    }

    /// The damped solve against a dense JᵀJ + λD formed and factorized by nalgebra.
    fn check(n: usize) {
        let r = rows(n, n as u64);
        let mut j = DMatrix::<f64>::zeros(2 * (r.ptr.len() - 1), n);
        for b in 0..r.ptr.len() - 1 {
            for e in r.ptr[b] as usize..r.ptr[b + 1] as usize {
                j[(2 * b, r.col[e] as usize)] += r.d[e][0];
                j[(2 * b + 1, r.col[e] as usize)] += r.d[e][1];
            }
        }
        let jtj = j.transpose() * &j;
        let mut sys = DirectSystem::new(&r, n).unwrap();
        assert!(sys.matches(&r, n));
        sys.fill(&r);
        let diag = sys.diagonal();
        for c in 0..n {
            assert!((diag[c] - jtj[(c, c)]).abs() <= 1e-12 * jtj[(c, c)].abs().max(1.0));
        }
        let scale: Vec<f64> = diag.iter().map(|d| d.max(1e-3)).collect();
        let lambda = 0.1;
        let b: Vec<f64> = (0..n).map(|c| ((c * 31) % 17) as f64 - 8.0).collect();
        let mut x = b.clone();
        sys.solve_damped(lambda, &scale, &mut x).unwrap();
        let a = &jtj
            + DMatrix::from_diagonal(&DVector::from_iterator(n, scale.iter().map(|s| lambda * s)));
        let want = a.cholesky().unwrap().solve(&DVector::from_vec(b));
        let err = (0..n).map(|c| (x[c] - want[c]).abs()).fold(0.0, f64::max);
        let size = want.amax();
        assert!(err <= 1e-9 * size, "n {n}: error {err} against {size}");
    }

    #[test]
    fn matches_a_dense_solve_with_either_ordering() {
        check(40); // reverse Cuthill–McKee
        check(RCM_MAX_UNKNOWNS + 60); // approximate minimum degree
    }

    #[test]
    fn another_structure_does_not_match() {
        let r = rows(30, 1);
        let sys = DirectSystem::new(&r, 30).unwrap();
        let mut other = rows(30, 2);
        assert!(sys.matches(&other, 30), "same structure, other values");
        other.col.swap(0, 1);
        assert!(!sys.matches(&other, 30));
        assert!(!sys.matches(&r, 31));
    }
}
