//! Sparse Levenberg–Marquardt over the grain angles φ (the paper's §4.3).
//!
//! The unknowns are the angles of a chosen set of *free* vertices; all others stay fixed
//! (math.md §3: the data term alone is ill-posed, so the free set is an edit's support plus a
//! margin, and a weak smoothness term picks one solution). Each iteration assembles the stacked
//! residual r = [r_ℓ; r_s; r_κ; r_σ; r_lock] (math.md §4) and its analytic Jacobian J through one
//! residual-block abstraction (the private trait `Block`), solves
//!
//! ```text
//! (JᵀJ + λ D) δ = −Jᵀr,        D = diag(JᵀJ) (Marquardt scaling, floored)
//! ```
//!
//! by a sparse Cholesky factorization whose symbolic analysis (ordering, elimination tree) is
//! computed once and reused — every block writes its Jacobian entries in an order that depends
//! only on the mesh and the free set (hinges write zeros where inactive), so JᵀJ's pattern is
//! fixed — and updates λ by the gain ratio (Nielsen's rule). An accepted step never increases
//! the total energy.
//!
//! Optionally, each accepted step is followed by the paper's Laplacian smoothing pass on the
//! free vertices (math.md §5.9: φᵢ += (τ/k)·arg Σⱼ wᵢⱼ e^{ikΔᵢⱼ}, applied to all free vertices
//! at once), tried at τ = ½, ¼, ⅛ and kept only if it does not raise the total energy.

use std::time::Instant;

use faer::dyn_stack::{MemBuffer, MemStack};
use faer::linalg::cholesky::llt::factor::LltRegularization;
use faer::prelude::*;
use faer::sparse::linalg::cholesky::{
    factorize_symbolic_cholesky, CholeskySymbolicParams, SymbolicCholesky, SymmetricOrdering,
};
use faer::sparse::linalg::SupernodalThreshold;
use faer::sparse::{SparseColMat, Triplet};
use faer::{Conj, Par, Side};
use rayon::prelude::*;

use super::cg::{conjugate_gradient, JacobianProduct, JacobianRows};
pub use super::cg::{CG_FORCING, CG_MAX_ITERATIONS, CG_THRESHOLD};
use super::fabrication::{lock_residual, GradientHinge, HingeKind};
use super::highlight_term::HighlightTerm;
use super::smoothness::edge_residual;
use crate::geometry::laplacian::cotan_weights;
use crate::mesh::Mesh;
use crate::{Error, Result};

/// A hinge constraint for [`LmOptions`]: |x| ≤ bound with weight λ (see
/// [`super::fabrication`]).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct HingeOptions {
    /// The bound b > 0 (1/R for a turning radius R; s_max for splay).
    pub bound: f64,
    /// The weight λ ≥ 0.
    pub weight: f64,
}

/// Options of [`solve`]. All weights are absolute here; [`super::optimize()`] derives them from
/// the scene's relative settings.
#[derive(Clone, Debug)]
pub struct LmOptions {
    /// Weight λ_s of the smoothness energy (multiplies the cotangent weights).
    pub smoothness: f64,
    /// Iteration cap.
    pub max_iterations: usize,
    /// Stop when an accepted step lowers the energy by less than this fraction.
    pub relative_decrease: f64,
    /// Stop when ‖Jᵀr‖∞ falls to or below this.
    pub gradient_tolerance: f64,
    /// Initial damping λ, relative to diag(JᵀJ).
    pub initial_damping: f64,
    /// Turning-radius hinge on ūᵀ∇φ.
    pub turning: Option<HingeOptions>,
    /// Splay hinge on v̄ᵀ∇φ.
    pub splay: Option<HingeOptions>,
    /// Soft locks: (vertex, angle in its frame, weight λ_L); the residual is scaled by √(λ_L Aᵢ).
    pub soft_locks: Vec<(u32, f64, f64)>,
    /// Run the interleaved Laplacian smoothing pass after each accepted step.
    pub interleaved_smoothing: bool,
    /// How each damped system is solved.
    pub linear_solver: LinearSolver,
    /// The clamped cotangent weights of the mesh, one per adjacency slot, when the caller has
    /// them (several solves on one mesh share them); computed when `None`.
    pub cotan_weights: Option<std::sync::Arc<Vec<f64>>>,
}

/// The linear solver of each damped step.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum LinearSolver {
    /// Direct below [`CG_THRESHOLD`] unknowns, conjugate gradients from there.
    #[default]
    Auto,
    /// Sparse Cholesky of JᵀJ + λD (symbolic analysis once per solve).
    Direct,
    /// Matrix-free Jacobi-preconditioned conjugate gradients on the Jacobian's rows, to a
    /// relative residual of at most [`CG_FORCING`] (an inexact Levenberg–Marquardt step; the gain
    /// ratio uses the model decrease of the step actually taken).
    ConjugateGradient,
}

impl Default for LmOptions {
    fn default() -> Self {
        LmOptions {
            smoothness: 1e-3,
            max_iterations: 50,
            relative_decrease: 1e-12,
            gradient_tolerance: 1e-12,
            initial_damping: 1e-4,
            turning: None,
            splay: None,
            soft_locks: Vec::new(),
            interleaved_smoothing: false,
            linear_solver: LinearSolver::Auto,
            cotan_weights: None,
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

/// The energy of each stacked term.
#[derive(Clone, Copy, Debug, Default, PartialEq, serde::Serialize)]
pub struct Energies {
    /// E_ℓ, the highlight energy (Eq. 8 repaired).
    pub highlight: f64,
    /// E_s, the smoothness energy.
    pub smoothness: f64,
    /// The turning-radius hinge.
    pub turning: f64,
    /// The splay hinge.
    pub splay: f64,
    /// The soft locks.
    pub locks: f64,
}

impl Energies {
    /// The sum of all terms.
    pub fn total(&self) -> f64 {
        self.highlight + self.smoothness + self.turning + self.splay + self.locks
    }

    fn add(&mut self, term: Term, e: f64) {
        match term {
            Term::Highlight => self.highlight += e,
            Term::Smoothness => self.smoothness += e,
            Term::Turning => self.turning += e,
            Term::Splay => self.splay += e,
            Term::Locks => self.locks += e,
        }
    }
}

/// One iteration's record.
#[derive(Clone, Debug, serde::Serialize)]
pub struct Iteration {
    /// The continuation stage (0 without continuation; see [`super::optimize()`]). The energy
    /// is monotone within a stage; each stage has its own smoothness weight.
    pub stage: usize,
    /// Every term's energy after the iteration (after its smoothing pass, if any).
    pub energies: Energies,
    /// Damping λ used for the accepted step.
    pub damping: f64,
    /// ‖δ‖∞ of the accepted step.
    pub step_norm: f64,
    /// Whether an interleaved smoothing pass was kept after the step.
    pub smoothed: bool,
    /// Seconds spent assembling residuals, Jacobian and normal equations.
    pub assembly_seconds: f64,
    /// Seconds spent in the damping, factorization, solve and trial energy of the accepted try
    /// (rejected tries are not counted, as in the paper's Fig. 12a).
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
    /// Energies before the first iteration.
    pub initial_energy: Energies,
}

#[derive(Clone, Copy, Debug)]
enum Term {
    Highlight,
    Smoothness,
    Turning,
    Splay,
    Locks,
}

/// Rows per parallel chunk. Chunks are fixed by the row order alone, and their results are
/// merged in chunk order, so the triplets, Jᵀr and the energies are bit-identical at any thread
/// count (and to a serial run).
const CHUNK: usize = 512;

/// Blocks of at most this many rows are assembled and summed on the calling thread (same
/// chunks, so the same sums): below it, waking the thread pool costs more than it saves
/// (perf on Fig. 12a's 656-vertex brush: 17 % of the time in the kernel's thread switches).
const SEQUENTIAL_ROWS: usize = 8 * CHUNK;

/// One chunk's contributions: the values of JᵀJ's lower-triangle products and (column, value)
/// terms of Jᵀr, in row order; the products' (row, column) positions only when the pattern is
/// being recorded (first iteration), since they do not change.
#[derive(Default)]
struct Local {
    vals: Vec<f64>,
    idx: Option<Vec<(u32, u32)>>,
    g: Vec<(usize, f64)>,
    block: Vec<(usize, [f64; 2])>,
    /// Matrix-free mode: the Jacobian's rows themselves instead of JᵀJ's products.
    rows: Option<JacobianRows>,
}

impl Local {
    /// Adds one row block: residual `r` and its entries `(vertex, ∂r/∂φ_vertex)`; entries of
    /// fixed vertices are dropped.
    #[inline]
    fn push(
        &mut self,
        col_of: &[Option<u32>],
        entries: impl Iterator<Item = (u32, [f64; 2])>,
        r: [f64; 2],
    ) {
        self.block.clear();
        self.block.extend(entries.filter_map(|(v, d)| col_of[v as usize].map(|c| (c as usize, d))));
        if let Some(rows) = &mut self.rows {
            if self.block.is_empty() {
                return;
            }
            for &(a, da) in &self.block {
                self.g.push((a, da[0] * r[0] + da[1] * r[1]));
                rows.col.push(a as u32);
                rows.d.push(da);
            }
            rows.ptr.push(rows.col.len() as u32);
            return;
        }
        for &(a, da) in &self.block {
            self.g.push((a, da[0] * r[0] + da[1] * r[1]));
            for &(b, db) in &self.block {
                if a >= b {
                    self.vals.push(da[0] * db[0] + da[1] * db[1]);
                    if let Some(idx) = &mut self.idx {
                        idx.push((a as u32, b as u32));
                    }
                }
            }
        }
    }
}

/// Accumulates Jᵀr and the lower triangle of JᵀJ from rows of up to two residual components.
struct Assembler<'a> {
    col_of: &'a [Option<u32>],
    g: Vec<f64>,
    vals: Vec<f64>,
    idx: Option<Vec<(u32, u32)>>,
    rows: Option<JacobianRows>,
}

impl Assembler<'_> {
    /// Assembles `row(item, push)` for every item, in parallel chunks merged in order.
    fn rows<T: Sync>(&mut self, items: &[T], row: impl Fn(&T, &mut Local, &[Option<u32>]) + Sync) {
        let col_of = self.col_of;
        let record = self.idx.is_some();
        let matrix_free = self.rows.is_some();
        let make = |chunk: &[T]| {
            let mut local = if matrix_free {
                Local {
                    rows: Some(JacobianRows {
                        ptr: vec![0],
                        col: Vec::with_capacity(8 * chunk.len()),
                        d: Vec::with_capacity(8 * chunk.len()),
                    }),
                    ..Local::default()
                }
            } else {
                Local {
                    vals: Vec::with_capacity(64 * chunk.len()),
                    idx: record.then(|| Vec::with_capacity(64 * chunk.len())),
                    ..Local::default()
                }
            };
            for it in chunk {
                row(it, &mut local, col_of);
            }
            local
        };
        // Small blocks run on the calling thread (see SEQUENTIAL_ROWS). Same chunks either
        // way, so the sums are identical.
        let locals: Vec<Local> = if items.len() <= SEQUENTIAL_ROWS {
            items.chunks(CHUNK).map(make).collect()
        } else {
            items.par_chunks(CHUNK).map(make).collect()
        };
        for local in locals {
            self.vals.extend_from_slice(&local.vals);
            if let (Some(all), Some(idx)) = (&mut self.idx, &local.idx) {
                all.extend_from_slice(idx);
            }
            if let (Some(all), Some(rows)) = (&mut self.rows, &local.rows) {
                all.append(rows);
            }
            for (c, v) in local.g {
                self.g[c] += v;
            }
        }
    }
}

/// Σ f(item) over `items`, in parallel chunks added in order (deterministic).
fn chunked_sum<T: Sync>(items: &[T], f: impl Fn(&T) -> f64 + Sync) -> f64 {
    let sum = |c: &[T]| c.iter().map(&f).sum::<f64>();
    let parts: Vec<f64> = if items.len() <= SEQUENTIAL_ROWS {
        items.chunks(CHUNK).map(sum).collect()
    } else {
        items.par_chunks(CHUNK).map(sum).collect()
    };
    parts.iter().sum()
}

/// One block of the stacked residual: its energy, and its rows assembled into the normal
/// equations. Rows must be pushed in an order and with entries that do not depend on φ.
trait Block: Sync {
    fn term(&self) -> Term;
    fn energy(&self, phi: &[f64]) -> f64;
    fn assemble(&self, phi: &[f64], acc: &mut Assembler);
}

struct HighlightBlock<'a> {
    term: &'a HighlightTerm<'a>,
    rows: Vec<u32>,
}

impl Block for HighlightBlock<'_> {
    fn term(&self) -> Term {
        Term::Highlight
    }
    fn energy(&self, phi: &[f64]) -> f64 {
        chunked_sum(&self.rows, |&i| {
            let r = self.term.residual(phi, i as usize);
            r[0] * r[0] + r[1] * r[1]
        })
    }
    fn assemble(&self, phi: &[f64], acc: &mut Assembler) {
        acc.rows(&self.rows, |&i, local, col_of| {
            let jac = self.term.jacobian(phi, i as usize);
            local.push(col_of, jac.entries.iter().copied(), jac.residual);
        });
    }
}

struct SmoothnessBlock {
    edges: Vec<(u32, u32, f64, f64)>, // (i, j, ρ_ij, λ_s w_ij), i < j, at least one free
    k: u32,
}

impl Block for SmoothnessBlock {
    fn term(&self) -> Term {
        Term::Smoothness
    }
    fn energy(&self, phi: &[f64]) -> f64 {
        chunked_sum(&self.edges, |&(i, j, rho, w)| {
            let r = edge_residual(phi[i as usize], phi[j as usize], rho, w, self.k).0;
            r * r
        })
    }
    fn assemble(&self, phi: &[f64], acc: &mut Assembler) {
        acc.rows(&self.edges, |&(i, j, rho, w), local, col_of| {
            let (r, di, dj) = edge_residual(phi[i as usize], phi[j as usize], rho, w, self.k);
            local.push(col_of, [(i, [di, 0.0]), (j, [dj, 0.0])].into_iter(), [r, 0.0]);
        });
    }
}

struct HingeBlock<'a> {
    hinge: GradientHinge<'a>,
    rows: Vec<u32>,
}

impl Block for HingeBlock<'_> {
    fn term(&self) -> Term {
        match self.hinge.kind {
            HingeKind::Turning => Term::Turning,
            HingeKind::Splay => Term::Splay,
        }
    }
    fn energy(&self, phi: &[f64]) -> f64 {
        chunked_sum(&self.rows, |&i| {
            let r = self.hinge.residual(phi, i as usize);
            r * r
        })
    }
    fn assemble(&self, phi: &[f64], acc: &mut Assembler) {
        acc.rows(&self.rows, |&i, local, col_of| {
            let mut entries = Vec::with_capacity(16);
            let r = self.hinge.jacobian(phi, i as usize, &mut entries);
            local.push(col_of, entries.iter().map(|&(v, d)| (v, [d, 0.0])), [r, 0.0]);
        });
    }
}

struct LockBlock {
    locks: Vec<(u32, f64, f64)>, // (vertex, angle, √(λ A))
    k: u32,
}

impl Block for LockBlock {
    fn term(&self) -> Term {
        Term::Locks
    }
    fn energy(&self, phi: &[f64]) -> f64 {
        chunked_sum(&self.locks, |&(i, a, s)| {
            let r = lock_residual(phi[i as usize], a, s, self.k).0;
            r * r
        })
    }
    fn assemble(&self, phi: &[f64], acc: &mut Assembler) {
        acc.rows(&self.locks, |&(i, a, s), local, col_of| {
            let (r, d) = lock_residual(phi[i as usize], a, s, self.k);
            local.push(col_of, std::iter::once((i, [d, 0.0])), [r, 0.0]);
        });
    }
}

/// JᵀJ's lower-triangle product values, their positions (when recorded) and Jᵀr.
type NormalEquations = (Vec<f64>, Option<Vec<(u32, u32)>>, Vec<f64>);

struct System<'a> {
    col_of: Vec<Option<u32>>,
    free: Vec<u32>,
    blocks: Vec<Box<dyn Block + 'a>>,
}

impl System<'_> {
    fn energy(&self, phi: &[f64]) -> Energies {
        let mut e = Energies::default();
        for b in &self.blocks {
            e.add(b.term(), b.energy(phi));
        }
        e
    }

    /// The lower triangle of JᵀJ as a list of product values (in an order that depends only on
    /// the mesh and the free set, so the pattern is fixed across iterations), their (row,
    /// column) positions if `record`, and Jᵀr. `capacity` pre-sizes the value list.
    fn normal_equations(&self, phi: &[f64], record: bool, capacity: usize) -> NormalEquations {
        let mut acc = Assembler {
            col_of: &self.col_of,
            g: vec![0.0; self.free.len()],
            vals: Vec::with_capacity(capacity),
            idx: record.then(Vec::new),
            rows: None,
        };
        for b in &self.blocks {
            b.assemble(phi, &mut acc);
        }
        (acc.vals, acc.idx, acc.g)
    }

    /// The Jacobian's rows (matrix-free mode) and Jᵀr.
    fn jacobian_rows(&self, phi: &[f64]) -> (JacobianRows, Vec<f64>) {
        let mut acc = Assembler {
            col_of: &self.col_of,
            g: vec![0.0; self.free.len()],
            vals: Vec::new(),
            idx: None,
            rows: Some(JacobianRows { ptr: vec![0], ..Default::default() }),
        };
        for b in &self.blocks {
            b.assemble(phi, &mut acc);
        }
        (acc.rows.expect("matrix-free mode"), acc.g)
    }
}

/// The free-vertex part of the paper's smoothing pass: φᵢ += (τ/k)·arg Σⱼ wᵢⱼ e^{ikΔᵢⱼ} for
/// every free i, all computed from the same φ (so the pass is order-independent).
fn smoothing_pass(
    phi: &[f64],
    free: &[u32],
    term: &HighlightTerm,
    w: &[f64],
    tau: f64,
) -> Vec<f64> {
    let g = term.geometry;
    let kf = term.symmetry.k() as f64;
    let mut out = phi.to_vec();
    for &i in free {
        let i = i as usize;
        let (mut c, mut s, mut wsum) = (0.0, 0.0, 0.0);
        for slot in g.adjacency.slots(i) {
            let j = g.adjacency.target(slot);
            let a = kf * (phi[j] + g.transport[slot] - phi[i]);
            c += w[slot] * a.cos();
            s += w[slot] * a.sin();
            wsum += w[slot];
        }
        if c.hypot(s) > 1e-12 * wsum {
            out[i] += tau * s.atan2(c) / kf;
        }
    }
    out
}

/// Minimizes the stacked energy over the angles of the `free` vertices, starting from `phi`.
pub fn solve(
    mesh: &Mesh,
    term: &HighlightTerm,
    phi: &[f64],
    free: &[u32],
    options: &LmOptions,
) -> Result<LmResult> {
    let g = term.geometry;
    let nv = g.num_vertices();
    if phi.len() != nv || term.target_q.len() != nv || term.weight.len() != nv {
        return Err(Error::invalid_arg(
            "phi",
            format!("{} angles, {} targets for {nv} vertices", phi.len(), term.target_q.len()),
        ));
    }
    let mut col_of = vec![None; nv];
    let mut free_sorted: Vec<u32> = free.iter().copied().filter(|&v| (v as usize) < nv).collect();
    free_sorted.sort_unstable();
    free_sorted.dedup();
    for (c, &v) in free_sorted.iter().enumerate() {
        col_of[v as usize] = Some(c as u32);
    }
    // Vertices whose Eq. 10 stencil touches a free angle (itself or a neighbour).
    let touched: Vec<u32> = (0..nv as u32)
        .filter(|&i| {
            col_of[i as usize].is_some()
                || g.stencil
                    .range(i as usize)
                    .any(|e| col_of[g.stencil.neighbor[e] as usize].is_some())
        })
        .collect();
    let k = term.symmetry.k();
    let w = match &options.cotan_weights {
        Some(w) if w.len() == g.adjacency.num_slots() => w.clone(),
        _ => std::sync::Arc::new(cotan_weights(mesh, &g.adjacency)),
    };
    let mut blocks: Vec<Box<dyn Block>> = Vec::new();
    let rows = touched.iter().copied().filter(|&i| term.target_q[i as usize].is_some()).collect();
    blocks.push(Box::new(HighlightBlock { term, rows }));
    if options.smoothness > 0.0 {
        let mut edges = Vec::new();
        for i in 0..nv {
            for s in g.adjacency.slots(i) {
                let j = g.adjacency.target(s);
                if i < j && (col_of[i].is_some() || col_of[j].is_some()) && w[s] > 0.0 {
                    edges.push((i as u32, j as u32, g.transport[s], options.smoothness * w[s]));
                }
            }
        }
        blocks.push(Box::new(SmoothnessBlock { edges, k }));
    }
    for (opt, kind) in [(options.turning, HingeKind::Turning), (options.splay, HingeKind::Splay)] {
        if let Some(h) = opt {
            if h.weight > 0.0 && h.bound > 0.0 && h.bound.is_finite() {
                let hinge = GradientHinge {
                    geometry: g,
                    symmetry: term.symmetry,
                    form: term.form,
                    kind,
                    bound: h.bound,
                    weight: h.weight,
                };
                blocks.push(Box::new(HingeBlock { hinge, rows: touched.clone() }));
            }
        }
    }
    let locks: Vec<(u32, f64, f64)> = options
        .soft_locks
        .iter()
        .filter(|l| (l.0 as usize) < nv && col_of[l.0 as usize].is_some() && l.2 > 0.0)
        .map(|&(v, a, wl)| (v, a, (wl * g.areas[v as usize]).max(0.0).sqrt()))
        .collect();
    if !locks.is_empty() {
        blocks.push(Box::new(LockBlock { locks, k }));
    }
    let sys = System { col_of, free: free_sorted, blocks };
    let mut phi = phi.to_vec();
    let initial_energy = sys.energy(&phi);
    let numerical = |m: String| Error::Numerical { stage: "Levenberg–Marquardt", message: m };
    if !initial_energy.total().is_finite() {
        return Err(numerical(format!("the initial energy is not finite: {initial_energy:?}")));
    }
    let n = sys.free.len();
    if n == 0 {
        return Ok(LmResult {
            phi,
            iterations: Vec::new(),
            stop: StopReason::NothingToSolve,
            initial_energy,
        });
    }
    let mut energy = initial_energy.total();
    let mut pattern: Option<FixedPattern> = None;
    let matrix_free = match options.linear_solver {
        LinearSolver::Direct => false,
        LinearSolver::ConjugateGradient => true,
        LinearSolver::Auto => n >= CG_THRESHOLD,
    };
    let mut product: Option<JacobianProduct> = None;
    let mut first_gradient: Option<f64> = None;
    let mut lambda = options.initial_damping;
    let mut nu = 2.0;
    let mut iterations = Vec::new();
    let mut stop = StopReason::IterationCap;
    'outer: for _ in 0..options.max_iterations {
        let t0 = Instant::now();
        let (grad, diag) = if matrix_free {
            let (rows, grad) = sys.jacobian_rows(&phi);
            let diag = rows.diagonal(n);
            product = Some(JacobianProduct::new(rows, n));
            (grad, diag)
        } else {
            let capacity = pattern.as_ref().map_or(0, |p| p.slot.len());
            let (vals, idx, grad) = sys.normal_equations(&phi, pattern.is_none(), capacity);
            let gmax = grad.iter().fold(0.0f64, |a, b| a.max(b.abs()));
            if gmax.is_nan() || gmax <= options.gradient_tolerance {
                stop = StopReason::Gradient;
                break;
            }
            if pattern.is_none() {
                let idx = idx.expect("recorded when there is no pattern");
                pattern = Some(FixedPattern::new(n, &idx).map_err(numerical)?);
            }
            let pat = pattern.as_mut().expect("just built");
            pat.fill(&vals);
            (grad, pat.diagonal())
        };
        let gmax = grad.iter().fold(0.0f64, |a, b| a.max(b.abs()));
        if gmax.is_nan() || gmax <= options.gradient_tolerance {
            stop = StopReason::Gradient;
            break;
        }
        let gnorm = grad.iter().map(|g| g * g).sum::<f64>().sqrt();
        let g0 = *first_gradient.get_or_insert(gnorm);
        let forcing = CG_FORCING.min(gnorm / g0.max(f64::MIN_POSITIVE));
        let dmax = diag.iter().fold(0.0f64, |a, &b| a.max(b)).max(1e-300);
        let dscale: Vec<f64> = diag.iter().map(|&d| d.max(1e-9 * dmax)).collect();
        let assembly = t0.elapsed().as_secs_f64();
        loop {
            let t1 = Instant::now();
            let (delta, predicted) = if let Some(product) = &product {
                let shift: Vec<f64> = dscale.iter().map(|&d| lambda * d).collect();
                let precond: Vec<f64> = diag.iter().zip(&shift).map(|(d, s)| d + s).collect();
                let b: Vec<f64> = grad.iter().map(|g| -g).collect();
                let (delta, _) = conjugate_gradient(product, &shift, &precond, &b, forcing);
                // Predicted decrease of the Gauss–Newton model for an inexact step, on the
                // scale of the direct branch's ½δᵀ(λDδ − g): ½(−2gᵀδ − δᵀJᵀJδ).
                let mut jtj = vec![0.0; n];
                product.apply(&delta, &vec![0.0; n], &mut Vec::new(), &mut jtj);
                let pred = 0.5
                    * (0..n).map(|c| -2.0 * grad[c] * delta[c] - delta[c] * jtj[c]).sum::<f64>();
                (delta, pred)
            } else {
                let pat = pattern.as_mut().expect("built in the assembly");
                let mut rhs = Mat::<f64>::from_fn(n, 1, |c, _| -grad[c]);
                pat.solve_damped(lambda, &dscale, rhs.as_mut()).map_err(numerical)?;
                let delta: Vec<f64> = (0..n).map(|c| rhs[(c, 0)]).collect();
                // Predicted decrease of the quadratic model: ½δᵀ(λDδ − g).
                let pred: f64 = 0.5
                    * (0..n)
                        .map(|c| delta[c] * (lambda * dscale[c] * delta[c] - grad[c]))
                        .sum::<f64>();
                (delta, pred)
            };
            let mut trial = phi.clone();
            for (c, &v) in sys.free.iter().enumerate() {
                trial[v as usize] += delta[c];
            }
            let mut new = sys.energy(&trial);
            let new_energy = new.total();
            let rho = if predicted > 0.0 { (energy - new_energy) / predicted } else { -1.0 };
            if new_energy.is_finite() && new_energy < energy && rho > 0.0 {
                let step_norm = delta.iter().fold(0.0f64, |a, b| a.max(b.abs()));
                let mut after = new_energy;
                phi = trial;
                let mut smoothed = false;
                if options.interleaved_smoothing {
                    for tau in [0.5, 0.25, 0.125] {
                        let s = smoothing_pass(&phi, &sys.free, term, &w, tau);
                        let es = sys.energy(&s);
                        if es.total().is_finite() && es.total() <= after {
                            phi = s;
                            new = es;
                            after = es.total();
                            smoothed = true;
                            break;
                        }
                    }
                }
                let decrease = (energy - after) / energy.max(f64::MIN_POSITIVE);
                energy = after;
                iterations.push(Iteration {
                    stage: 0,
                    energies: new,
                    damping: lambda,
                    step_norm,
                    smoothed,
                    assembly_seconds: assembly,
                    solve_seconds: t1.elapsed().as_secs_f64(),
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
/// (each triplet's value slot is found once). The factor's values and the factorization's
/// workspace are allocated once too; each damping try refactorizes in place, sequentially (so
/// the result does not depend on the thread count).
struct FixedPattern {
    matrix: SparseColMat<usize, f64>,
    slot: Vec<usize>,
    diag: Vec<usize>,
    base: Vec<f64>,
    symbolic: SymbolicCholesky<usize>,
    l_values: Vec<f64>,
    workspace: MemBuffer,
}

impl FixedPattern {
    fn new(n: usize, idx: &[(u32, u32)]) -> std::result::Result<Self, String> {
        let mut all: Vec<Triplet<usize, usize, f64>> =
            idx.iter().map(|&(r, c)| Triplet::new(r as usize, c as usize, 0.0)).collect();
        all.extend((0..n).map(|c| Triplet::new(c, c, 0.0)));
        let matrix = SparseColMat::<usize, f64>::try_new_from_triplets(n, n, &all)
            .map_err(|e| format!("{e:?}"))?;
        let find = |r: usize, c: usize| -> usize {
            let sym = matrix.symbolic();
            let (start, end) = (sym.col_ptr()[c], sym.col_ptr()[c + 1]);
            start + sym.row_idx()[start..end].binary_search(&r).expect("entry in the pattern")
        };
        let slot = idx.iter().map(|&(r, c)| find(r as usize, c as usize)).collect();
        let diag = (0..n).map(|c| find(c, c)).collect();
        let symbolic = factorize_symbolic_cholesky(
            matrix.symbolic(),
            Side::Lower,
            SymmetricOrdering::Amd,
            // Supernodal even where faer's flop-ratio heuristic picks the simplicial
            // (up-looking) factorization: on the 2-ring pattern of a brush of 200–700 vertices
            // it took the numeric factorization from ~1.0 to ~0.6 ms (bench_solver, Fig. 12a).
            CholeskySymbolicParams {
                supernodal_flop_ratio_threshold: SupernodalThreshold::FORCE_SUPERNODAL,
                ..Default::default()
            },
        )
        .map_err(|e| format!("{e:?}"))?;
        let base = vec![0.0; matrix.val().len()];
        let l_values = vec![0.0; symbolic.len_val()];

        let workspace = MemBuffer::try_new(
            symbolic
                .factorize_numeric_llt_scratch::<f64>(Par::Seq, Default::default())
                .or(symbolic.solve_in_place_scratch::<f64>(1, Par::Seq)),
        )
        .map_err(|e| format!("{e:?}"))?;
        Ok(FixedPattern { matrix, slot, diag, base, symbolic, l_values, workspace })
    }

    /// Refills JᵀJ from product values in the same order as the positions the pattern was built
    /// from (summed in that fixed order, so deterministic).
    fn fill(&mut self, vals: &[f64]) {
        debug_assert_eq!(vals.len(), self.slot.len());
        self.base.iter_mut().for_each(|v| *v = 0.0);
        for (&v, &s) in vals.iter().zip(&self.slot) {
            self.base[s] += v;
        }
    }

    /// diag(JᵀJ) of the last fill.
    fn diagonal(&self) -> Vec<f64> {
        self.diag.iter().map(|&d| self.base[d]).collect()
    }

    /// Solves (JᵀJ + λ diag(scale)) x = rhs in place: refills the damped matrix and its
    /// Cholesky factor (symbolic analysis reused).
    fn solve_damped(
        &mut self,
        lambda: f64,
        scale: &[f64],
        rhs: MatMut<'_, f64>,
    ) -> std::result::Result<(), String> {
        let vals = self.matrix.val_mut();
        vals.copy_from_slice(&self.base);
        for (c, &d) in self.diag.iter().enumerate() {
            vals[d] += lambda * scale[c];
        }
        let stack = MemStack::new(&mut self.workspace);
        let llt = self
            .symbolic
            .factorize_numeric_llt(
                &mut self.l_values,
                self.matrix.as_ref(),
                Side::Lower,
                LltRegularization::default(),
                Par::Seq,
                stack,
                Default::default(),
            )
            .map_err(|e| format!("{e:?}"))?;
        llt.solve_in_place_with_conj(Conj::No, rhs, Par::Seq, MemStack::new(&mut self.workspace));
        Ok(())
    }
}
