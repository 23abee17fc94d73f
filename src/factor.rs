//! A sparse Cholesky factorization whose size is known, and bounded, before it is computed
//! (issue 15, item 12): the symbolic analysis (approximate minimum degree ordering and the
//! elimination tree, linear in the matrix) gives the number of values of L, and the numeric
//! factorization is refused when they would exceed [`crate::limits::MAX_FACTOR_BYTES`].
//!
//! The same computation as faer's `sp_cholesky` (the same ordering, parameters and
//! parallelism), so results are unchanged.

use faer::dyn_stack::{MemBuffer, MemStack};
use faer::linalg::cholesky::llt::factor::LltRegularization;
use faer::sparse::linalg::cholesky::{factorize_symbolic_cholesky, LltRef, SymbolicCholesky};
use faer::sparse::SparseColMatRef;
use faer::traits::ComplexField;
use faer::{Conj, MatMut, Side};

use crate::{Error, Result};

/// L of A = LLᴴ (lower triangle of A read).
pub(crate) struct Factor<T> {
    symbolic: SymbolicCholesky<usize>,
    values: Vec<T>,
}

/// Refuses a factor of `values` entries of `bytes` each past the budget, naming `stage`.
pub(crate) fn check_factor_size(stage: &'static str, values: usize, bytes: usize) -> Result<()> {
    let total = (values as u128) * (bytes as u128);
    let budget = crate::limits::MAX_FACTOR_BYTES;
    if total > u128::from(budget) {
        return Err(Error::Numerical {
            stage,
            message: format!(
                "the Cholesky factor would hold {values} values ({:.2} GiB), beyond the budget \
                 of {:.0} GiB (grainline::limits::MAX_FACTOR_BYTES); use a coarser mesh or a \
                 smaller edit region (solver.margin_rings, the edits' radius)",
                total as f64 / f64::from(1u32 << 30),
                budget as f64 / f64::from(1u32 << 30)
            ),
        });
    }
    Ok(())
}

impl<T: ComplexField> Factor<T> {
    /// Factors `a` (square, Hermitian positive definite; its lower triangle is read).
    pub(crate) fn new(a: SparseColMatRef<'_, usize, T>, stage: &'static str) -> Result<Self> {
        let numerical = |message: String| Error::Numerical { stage, message };
        let symbolic = factorize_symbolic_cholesky(
            a.symbolic(),
            Side::Lower,
            Default::default(),
            Default::default(),
        )
        .map_err(|e| numerical(format!("Cholesky: {}", crate::error::describe_faer(&e))))?;
        let len = symbolic.len_val();
        check_factor_size(stage, len, std::mem::size_of::<T>())?;
        let mut values = Vec::new();
        values
            .try_reserve_exact(len)
            .map_err(|_| numerical("out of memory for the Cholesky factor".into()))?;
        values.resize(len, T::zero_impl());
        let par = faer::get_global_parallelism();
        let scratch = symbolic.factorize_numeric_llt_scratch::<T>(par, Default::default());
        let mut work = MemBuffer::try_new(scratch)
            .map_err(|_| numerical("out of memory for the Cholesky workspace".into()))?;
        symbolic
            .factorize_numeric_llt::<T>(
                &mut values,
                a,
                Side::Lower,
                LltRegularization::default(),
                par,
                MemStack::new(&mut work),
                Default::default(),
            )
            .map_err(|e| numerical(format!("Cholesky: {}", crate::error::describe_pivot(&e))))?;
        Ok(Factor { symbolic, values })
    }

    /// Solves A x = b in place (b's columns are the right-hand sides).
    pub(crate) fn solve_in_place(&self, rhs: MatMut<'_, T>) {
        let par = faer::get_global_parallelism();
        let scratch = self.symbolic.solve_in_place_scratch::<T>(rhs.ncols(), par);
        LltRef::<'_, usize, T>::new(&self.symbolic, &self.values).solve_in_place_with_conj(
            Conj::No,
            rhs,
            par,
            MemStack::new(&mut MemBuffer::new(scratch)),
        );
    }
}

#[cfg(test)]
mod tests {
    use faer::c64;
    use faer::sparse::{SparseColMat, Triplet};
    use faer::Mat;

    use super::*;

    #[test]
    fn factors_and_solves_a_small_hermitian_system() {
        // A = [[4, 1 − i], [1 + i, 3]] (lower triangle given); x = [1, i] gives
        // b = [4 + (1 − i)i, (1 + i) + 3i] = [5 + i, 1 + 4i].
        let t = [
            Triplet::new(0, 0, c64::new(4.0, 0.0)),
            Triplet::new(1, 0, c64::new(1.0, 1.0)),
            Triplet::new(1, 1, c64::new(3.0, 0.0)),
        ];
        let a = SparseColMat::<usize, c64>::try_new_from_triplets(2, 2, &t).unwrap();
        let f = Factor::new(a.as_ref(), "test").unwrap();
        let mut b = Mat::<c64>::from_fn(2, 1, |i, _| [c64::new(5.0, 1.0), c64::new(1.0, 4.0)][i]);
        f.solve_in_place(b.as_mut());
        assert!((b[(0, 0)] - c64::new(1.0, 0.0)).norm() < 1e-12, "{:?}", b[(0, 0)]);
        assert!((b[(1, 0)] - c64::new(0.0, 1.0)).norm() < 1e-12, "{:?}", b[(1, 0)]);
    }

    #[test]
    fn item12_a_factor_past_the_budget_is_refused_before_it_is_allocated() {
        let values = (crate::limits::MAX_FACTOR_BYTES / 16 + 1) as usize;
        let e = check_factor_size("smoothest field", values, 16).unwrap_err().to_string();
        assert!(e.contains("smoothest field") && e.contains("beyond the budget of 8 GiB"), "{e}");
        assert!(check_factor_size("x", values - 1, 16).is_ok());
    }
}
