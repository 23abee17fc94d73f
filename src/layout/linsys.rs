//! Sparse symmetric positive definite systems for the flattening methods: assembled from
//! (row, column, value) entries and solved with the project's solver, faer's sparse Cholesky
//! factorization (`factor`, as `highlight::smoothest` and `edit::stencil` use, its size
//! bounded before it is allocated), factored once and reused for every right-hand side (ARAP
//! solves the same matrix at each iteration).

use faer::prelude::*;
use faer::sparse::{SparseColMat, Triplet};

use crate::factor::Factor;
use crate::{Error, Result};

/// A factored SPD matrix of size `n`.
pub(crate) struct Spd {
    llt: Factor<f64>,
    n: usize,
}

impl Spd {
    /// Factors the symmetric matrix given by `entries` (duplicates are summed; both triangles
    /// may be given, only the lower one is read). `stage` names the method in errors.
    pub(crate) fn factor(
        n: usize,
        mut entries: Vec<(usize, usize, f64)>,
        stage: &'static str,
    ) -> Result<Spd> {
        entries.retain(|&(r, c, _)| r >= c);
        entries.sort_unstable_by_key(|&(r, c, _)| (c, r));
        let mut merged: Vec<Triplet<usize, usize, f64>> = Vec::with_capacity(entries.len());
        for (r, c, v) in entries {
            match merged.last_mut() {
                Some(t) if t.row == r && t.col == c => t.val += v,
                _ => merged.push(Triplet::new(r, c, v)),
            }
        }
        if let Some(t) = merged.iter().find(|t| !t.val.is_finite()) {
            return Err(Error::Numerical {
                stage,
                message: format!("matrix entry ({}, {}) is not finite", t.row, t.col),
            });
        }
        let a = SparseColMat::<usize, f64>::try_new_from_triplets(n, n, &merged).map_err(|e| {
            Error::Numerical {
                stage,
                message: format!("matrix assembly: {}", crate::error::describe_creation(&e)),
            }
        })?;
        // The factor's size is bounded before it is allocated (limits::MAX_FACTOR_BYTES).
        let llt = Factor::new(a.as_ref(), stage)?;
        Ok(Spd { llt, n })
    }

    /// Solves `A x = b` for each column of `rhs` (each of length `n`), in place.
    pub(crate) fn solve(&self, rhs: &mut [Vec<f64>]) {
        let mut m = Mat::<f64>::from_fn(self.n, rhs.len(), |i, j| rhs[j][i]);
        self.llt.solve_in_place(m.as_mut());
        for (j, col) in rhs.iter_mut().enumerate() {
            for (i, x) in col.iter_mut().enumerate() {
                *x = m[(i, j)];
            }
        }
    }
}
