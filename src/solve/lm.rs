//! Sparse Levenberg–Marquardt over the grain angles φ (the paper's §4.3).
//!
//! The unknowns are the angles of a chosen set of *free* vertices; all others stay fixed
//! (math.md §3: the data term alone is ill-posed, so the free set is an edit's support plus a
//! margin, and a weak smoothness term picks one solution). Each iteration assembles the stacked
//! residual r = [r_ℓ; r_s] and its analytic Jacobian J, solves
//!
//! ```text
//! (JᵀJ + λ D) δ = −Jᵀr,        D = diag(JᵀJ) (Marquardt scaling, floored)
//! ```
//!
//! by a sparse Cholesky factorization whose symbolic analysis (ordering, elimination tree) is
//! computed once and reused, and updates λ by the gain ratio (Nielsen's rule). An accepted step
//! never increases the energy.

use std::time::Instant;

use faer::linalg::solvers::Solve;
use faer::prelude::*;
use faer::sparse::linalg::solvers::{Llt, SymbolicLlt};
use faer::sparse::{SparseColMat, Triplet};
use faer::Side;

use super::highlight_term::HighlightTerm;
use super::smoothness::edge_residual;
use crate::geometry::laplacian::cotan_weights;
use crate::mesh::Mesh;
use crate::{Error, Result};

/// Options of [`solve`].
#[derive(Clone, Debug)]
pub struct LmOptions {
    /// Weight λ_s of the smoothness energy.
    pub smoothness: f64,
    /// Iteration cap.
    pub max_iterations: usize,
    /// Stop when an accepted step lowers the energy by less than this fraction.
    pub relative_decrease: f64,
    /// Stop when ‖Jᵀr‖∞ falls below this.
    pub gradient_tolerance: f64,
    /// Initial damping λ, relative to max diag(JᵀJ).
    pub initial_damping: f64,
}

impl Default for LmOptions {
    fn default() -> Self {
        LmOptions {
            smoothness: 1e-3,
            max_iterations: 50,
            relative_decrease: 1e-12,
            gradient_tolerance: 1e-12,
            initial_damping: 1e-4,
        }
    }
}

/// Why the solver stopped.
#[derive(Clone, Copy, Debug, PartialEq, Eq, serde::Serialize)]
#[serde(rename_all = "kebab-case")]
pub enum StopReason {
    /// The energy decrease fell below the relative tolerance.
    RelativeDecrease,
    /// The gradient norm fell below its tolerance.
    Gradient,
    /// The iteration cap was reached.
    IterationCap,
    /// No step could lower the energy (λ grew past its bound).
    NoProgress,
    /// There are no free vertices.
    NothingToSolve,
}

/// One iteration's record.
#[derive(Clone, Debug, serde::Serialize)]
pub struct Iteration {
    /// Highlight energy after the iteration.
    pub highlight_energy: f64,
    /// Smoothness energy after the iteration.
    pub smoothness_energy: f64,
    /// Damping λ used for the accepted step.
    pub damping: f64,
    /// ‖δ‖∞ of the accepted step.
    pub step_norm: f64,
    /// Seconds spent assembling residuals, Jacobian and normal equations.
    pub assembly_seconds: f64,
    /// Seconds spent in the factorization and solve.
    pub solve_seconds: f64,
}

/// Result of [`solve`].
#[derive(Clone, Debug)]
pub struct LmResult {
    /// The optimized angles (all vertices; fixed ones unchanged).
    pub phi: Vec<f64>,
    /// Per-iteration record (accepted steps).
    pub iterations: Vec<Iteration>,
    /// Why it stopped.
    pub stop: StopReason,
    /// Energies (highlight, smoothness) before the first iteration.
    pub initial_energy: (f64, f64),
}

struct System<'a> {
    term: &'a HighlightTerm<'a>,
    col_of: Vec<Option<u32>>,
    free: Vec<u32>,
    rows: Vec<u32>,
    edges: Vec<(u32, u32, f64, f64)>, // (i, j, ρ_ij, λ_s w_ij), i < j, at least one free
    k: u32,
}

impl System<'_> {
    fn energy(&self, phi: &[f64]) -> (f64, f64) {
        let eh: f64 = self
            .rows
            .iter()
            .map(|&i| {
                let r = self.term.residual(phi, i as usize);
                r[0] * r[0] + r[1] * r[1]
            })
            .sum();
        let es: f64 = self
            .edges
            .iter()
            .map(|&(i, j, rho, w)| {
                let r = edge_residual(phi[i as usize], phi[j as usize], rho, w, self.k).0;
                r * r
            })
            .sum();
        (eh, es)
    }

    /// The lower triangle of JᵀJ as triplets (in an order that depends only on the mesh and the
    /// free set, so the pattern is fixed across iterations) and Jᵀr.
    fn normal_equations(&self, phi: &[f64]) -> (Vec<Triplet<usize, usize, f64>>, Vec<f64>) {
        let n = self.free.len();
        let mut g = vec![0.0; n];
        let mut trip = Vec::new();
        let mut block: Vec<(usize, [f64; 2])> = Vec::new();
        let push_block = |block: &[(usize, [f64; 2])],
                          r: [f64; 2],
                          g: &mut Vec<f64>,
                          trip: &mut Vec<Triplet<usize, usize, f64>>| {
            for &(a, da) in block {
                g[a] += da[0] * r[0] + da[1] * r[1];
                for &(b, db) in block {
                    if a >= b {
                        trip.push(Triplet::new(a, b, da[0] * db[0] + da[1] * db[1]));
                    }
                }
            }
        };
        for &i in &self.rows {
            let jac = self.term.jacobian(phi, i as usize);
            block.clear();
            block.extend(
                jac.entries
                    .iter()
                    .filter_map(|&(v, d)| self.col_of[v as usize].map(|c| (c as usize, d))),
            );
            push_block(&block, jac.residual, &mut g, &mut trip);
        }
        for &(i, j, rho, w) in &self.edges {
            let (r, di, dj) = edge_residual(phi[i as usize], phi[j as usize], rho, w, self.k);
            block.clear();
            if let Some(c) = self.col_of[i as usize] {
                block.push((c as usize, [di, 0.0]));
            }
            if let Some(c) = self.col_of[j as usize] {
                block.push((c as usize, [dj, 0.0]));
            }
            push_block(&block, [r, 0.0], &mut g, &mut trip);
        }
        (trip, g)
    }
}

/// Minimizes E_ℓ + E_s over the angles of the `free` vertices, starting from `phi`.
pub fn solve(
    mesh: &Mesh,
    term: &HighlightTerm,
    phi: &[f64],
    free: &[u32],
    options: &LmOptions,
) -> Result<LmResult> {
    let g = term.geometry;
    let nv = g.num_vertices();
    let mut col_of = vec![None; nv];
    let mut free_sorted = free.to_vec();
    free_sorted.sort_unstable();
    free_sorted.dedup();
    for (c, &v) in free_sorted.iter().enumerate() {
        col_of[v as usize] = Some(c as u32);
    }
    // Rows: vertices whose residual depends on a free angle (itself or a stencil neighbour).
    let rows: Vec<u32> = (0..nv as u32)
        .filter(|&i| {
            term.target_q[i as usize].is_some()
                && (col_of[i as usize].is_some()
                    || g.stencil
                        .range(i as usize)
                        .any(|e| col_of[g.stencil.neighbor[e] as usize].is_some()))
        })
        .collect();
    let w = cotan_weights(mesh, &g.adjacency);
    let mut edges = Vec::new();
    if options.smoothness > 0.0 {
        for i in 0..nv {
            for s in g.adjacency.slots(i) {
                let j = g.adjacency.target(s);
                if i < j && (col_of[i].is_some() || col_of[j].is_some()) && w[s] > 0.0 {
                    edges.push((i as u32, j as u32, g.transport[s], options.smoothness * w[s]));
                }
            }
        }
    }
    let sys = System { term, col_of, free: free_sorted, rows, edges, k: term.symmetry.k() };
    let mut phi = phi.to_vec();
    let initial_energy = sys.energy(&phi);
    let n = sys.free.len();
    if n == 0 {
        return Ok(LmResult {
            phi,
            iterations: Vec::new(),
            stop: StopReason::NothingToSolve,
            initial_energy,
        });
    }
    let numerical = |m: String| Error::Numerical { stage: "Levenberg–Marquardt", message: m };
    let mut energy = initial_energy.0 + initial_energy.1;
    let mut pattern: Option<FixedPattern> = None;
    let mut lambda = f64::NAN;
    let mut nu = 2.0;
    let mut iterations = Vec::new();
    let mut stop = StopReason::IterationCap;
    'outer: for _ in 0..options.max_iterations {
        let t0 = Instant::now();
        let (trip, grad) = sys.normal_equations(&phi);
        let gmax = grad.iter().fold(0.0f64, |a, b| a.max(b.abs()));
        if gmax < options.gradient_tolerance {
            stop = StopReason::Gradient;
            break;
        }
        let mut diag = vec![0.0; n];
        for t in &trip {
            if t.row == t.col {
                diag[t.row] += t.val;
            }
        }
        let dmax = diag.iter().fold(0.0f64, |a, &b| a.max(b)).max(f64::MIN_POSITIVE);
        let dscale: Vec<f64> = diag.iter().map(|&d| d.max(1e-9 * dmax)).collect();
        if lambda.is_nan() {
            lambda = options.initial_damping;
        }
        if pattern.is_none() {
            pattern = Some(FixedPattern::new(n, &trip).map_err(numerical)?);
        }
        let pat = pattern.as_mut().expect("just built");
        pat.fill(&trip);
        let assembly = t0.elapsed().as_secs_f64();
        loop {
            let t1 = Instant::now();
            let symbolic = pat.symbolic.clone();
            let a = pat.damped(lambda, &dscale);
            let llt = Llt::try_new_with_symbolic(symbolic, a.as_ref(), Side::Lower)
                .map_err(|e| numerical(format!("{e:?}")))?;
            let mut rhs = Mat::<f64>::from_fn(n, 1, |c, _| -grad[c]);
            llt.solve_in_place(rhs.as_mut());
            let delta: Vec<f64> = (0..n).map(|c| rhs[(c, 0)]).collect();
            let solve_seconds = t1.elapsed().as_secs_f64();
            let mut trial = phi.clone();
            for (c, &v) in sys.free.iter().enumerate() {
                trial[v as usize] += delta[c];
            }
            let (eh, es) = sys.energy(&trial);
            let new_energy = eh + es;
            // Predicted decrease of the quadratic model: ½δᵀ(λDδ − g).
            let predicted: f64 = 0.5
                * (0..n).map(|c| delta[c] * (lambda * dscale[c] * delta[c] - grad[c])).sum::<f64>();
            let rho = if predicted > 0.0 { (energy - new_energy) / predicted } else { -1.0 };
            if new_energy.is_finite() && new_energy < energy && rho > 0.0 {
                let step_norm = delta.iter().fold(0.0f64, |a, b| a.max(b.abs()));
                let decrease = (energy - new_energy) / energy.max(f64::MIN_POSITIVE);
                phi = trial;
                energy = new_energy;
                iterations.push(Iteration {
                    highlight_energy: eh,
                    smoothness_energy: es,
                    damping: lambda,
                    step_norm,
                    assembly_seconds: assembly,
                    solve_seconds,
                });
                lambda *= (1.0f64 / 3.0).max(1.0 - (2.0 * rho - 1.0).powi(3));
                nu = 2.0;
                if decrease < options.relative_decrease {
                    stop = StopReason::RelativeDecrease;
                    break 'outer;
                }
                break;
            }
            lambda *= nu;
            nu *= 2.0;
            if lambda.is_nan() || lambda >= 1e16 {
                stop = StopReason::NoProgress;
                break 'outer;
            }
        }
    }
    Ok(LmResult { phi, iterations, stop, initial_energy })
}

/// The lower triangle of JᵀJ in a sparsity pattern fixed for the whole solve: the matrix and its
/// symbolic Cholesky analysis are built once, and each iteration refills the values in place
/// (each triplet's value slot is found once).
struct FixedPattern {
    matrix: SparseColMat<usize, f64>,
    slot: Vec<usize>,
    diag: Vec<usize>,
    base: Vec<f64>,
    symbolic: SymbolicLlt<usize>,
}

impl FixedPattern {
    fn new(n: usize, trip: &[Triplet<usize, usize, f64>]) -> std::result::Result<Self, String> {
        let mut all = trip.to_vec();
        all.extend((0..n).map(|c| Triplet::new(c, c, 0.0)));
        let matrix = SparseColMat::<usize, f64>::try_new_from_triplets(n, n, &all)
            .map_err(|e| format!("{e:?}"))?;
        let find = |r: usize, c: usize| -> usize {
            let sym = matrix.symbolic();
            let (start, end) = (sym.col_ptr()[c], sym.col_ptr()[c + 1]);
            start + sym.row_idx()[start..end].binary_search(&r).expect("entry in the pattern")
        };
        let slot = trip.iter().map(|t| find(t.row, t.col)).collect();
        let diag = (0..n).map(|c| find(c, c)).collect();
        let symbolic =
            SymbolicLlt::try_new(matrix.symbolic(), Side::Lower).map_err(|e| format!("{e:?}"))?;
        let base = vec![0.0; matrix.val().len()];
        Ok(FixedPattern { matrix, slot, diag, base, symbolic })
    }

    /// Refills JᵀJ from triplets in the same order as the ones the pattern was built from.
    fn fill(&mut self, trip: &[Triplet<usize, usize, f64>]) {
        debug_assert_eq!(trip.len(), self.slot.len());
        self.base.iter_mut().for_each(|v| *v = 0.0);
        for (t, &s) in trip.iter().zip(&self.slot) {
            self.base[s] += t.val;
        }
    }

    /// JᵀJ + λ diag(scale).
    fn damped(&mut self, lambda: f64, scale: &[f64]) -> &SparseColMat<usize, f64> {
        let vals = self.matrix.val_mut();
        vals.copy_from_slice(&self.base);
        for (c, &d) in self.diag.iter().enumerate() {
            vals[d] += lambda * scale[c];
        }
        &self.matrix
    }
}
