//! Sparse Levenberg–Marquardt over the grain angles φ (the paper's §4.3).
//!
//! The unknowns are the angles of a chosen set of *free* vertices; all others stay fixed
//! (math.md §3: the data term alone is ill-posed, so the free set is an edit's support plus a
//! margin, and a weak smoothness term picks one solution). Each iteration assembles the stacked
//! residual r = [r_ℓ; r_s; r_κ; r_σ; r_lock] (math.md §4) and its analytic Jacobian J through one
//! residual-block abstraction (the private trait `Block`, in the submodule `blocks`), solves
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

use super::cg::{conjugate_gradient, NormalMatrix};
pub use super::cg::{CG_FORCING, CG_MAX_ITERATIONS, CG_THRESHOLD};
use super::highlight_term::HighlightTerm;
use super::pattern::DirectSystem;
pub use super::pattern::SolveCache;
use crate::geometry::laplacian::cotan_weights;
use crate::mesh::Mesh;
use crate::{Error, Result};

mod blocks;

pub use blocks::Region;
use blocks::{build_system, Assembler, System};

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
    /// Turning-radius hinge inside the triangles (`super::face_hinge`): `bound` is 1/R′ with
    /// R′ = R/(1 − margin). Its energy is added to the turning term.
    pub turning_faces: Option<HingeOptions>,
    /// Splay hinge inside the triangles (`super::face_hinge`, F4): `bound` is s_max·(1 −
    /// margin). Its energy is added to the splay term.
    pub splay_faces: Option<HingeOptions>,
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
    /// Jacobi-preconditioned conjugate gradients on JᵀJ assembled in a fixed pattern, to a
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
            turning_faces: None,
            splay_faces: None,
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

impl std::fmt::Display for StopReason {
    /// The name the reports use (`relative-decrease`, `gradient`, `iteration-cap`,
    /// `no-progress`, `nothing-to-solve`).
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str(match self {
            StopReason::RelativeDecrease => "relative-decrease",
            StopReason::Gradient => "gradient",
            StopReason::IterationCap => "iteration-cap",
            StopReason::NoProgress => "no-progress",
            StopReason::NothingToSolve => "nothing-to-solve",
        })
    }
}

/// The energy of each stacked term.
#[derive(Clone, Copy, Debug, Default, PartialEq, serde::Serialize)]
pub struct Energies {
    /// E_ℓ, the highlight energy (Eq. 8 repaired).
    pub highlight: f64,
    /// E_g, the position energy (the highlight where the edits ask; `solve::position_term`).
    pub position: f64,
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
        self.highlight + self.position + self.smoothness + self.turning + self.splay + self.locks
    }

    fn add(&mut self, term: Term, e: f64) {
        match term {
            Term::Highlight => self.highlight += e,
            Term::Position => self.position += e,
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
    /// Seconds spent before the tries: JᵀJ refilled from the Jacobian's rows (and, in the
    /// first iteration, the rows assembled and the pattern, ordering and symbolic analysis
    /// built, unless cached); on the conjugate-gradient path, JᵀJ refilled in its pattern (built
    /// in the first iteration).
    pub assembly_seconds: f64,
    /// Seconds spent in the damping, factorization, solve and trial point of the accepted try
    /// (rejected tries are not counted, as in the paper's Fig. 12a). The trial point's rows
    /// and Jᵀr are assembled with its energy, and serve the next iteration.
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
    Position,
    Smoothness,
    Turning,
    Splay,
    Locks,
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
    solve_cached(mesh, term, phi, free, options, &mut SolveCache::default())
}

/// [`solve`], reusing the direct path's pattern, ordering and symbolic analysis from `cache`
/// when this solve's Jacobian has the same structure as the one they were built for (several
/// solves over one free set: continuation stages, several starts), and leaving this solve's in
/// it. The result is the same as [`solve`]'s.
pub fn solve_cached(
    mesh: &Mesh,
    term: &HighlightTerm,
    phi: &[f64],
    free: &[u32],
    options: &LmOptions,
    cache: &mut SolveCache,
) -> Result<LmResult> {
    check_sizes(term, phi)?;
    let w = weights(mesh, term, options);
    let region = Region::new(term.geometry, free, &w, None);
    solve_in(mesh, term, phi, &region, options, cache)
}

/// The cotangent weights `options` lend, or the mesh's.
fn weights(mesh: &Mesh, term: &HighlightTerm, options: &LmOptions) -> std::sync::Arc<Vec<f64>> {
    let g = term.geometry;
    match &options.cotan_weights {
        Some(w) if w.len() == g.adjacency.num_slots() => w.clone(),
        _ => std::sync::Arc::new(cotan_weights(mesh, &g.adjacency)),
    }
}

/// The energies of `phi` over the free vertices of `region`: the initial energies
/// [`solve_in`] reports, the same bits, without assembling the Jacobian or copying `phi`.
pub fn energy_in(
    mesh: &Mesh,
    term: &HighlightTerm,
    phi: &[f64],
    region: &Region,
    options: &LmOptions,
) -> Result<Energies> {
    check_sizes(term, phi)?;
    let w = weights(mesh, term, options);
    let e = build_system(mesh, term, region, options, &w).energy(phi);
    if !e.total().is_finite() {
        return Err(numerical(format!("the initial energy is not finite: {e:?}")));
    }
    Ok(e)
}

/// The sizes of `phi` and of `term`'s targets against the geometry's vertices.
fn check_sizes(term: &HighlightTerm, phi: &[f64]) -> Result<()> {
    let nv = term.geometry.num_vertices();
    if phi.len() != nv
        || term.target_q.len() != nv
        || term.weight.len() != nv
        || term.target_g.len() != nv
    {
        return Err(Error::invalid_arg(
            "phi",
            format!("{} angles, {} targets for {nv} vertices", phi.len(), term.target_q.len()),
        ));
    }
    Ok(())
}

/// [`solve_cached`] over the free vertices of `region`, made with the cotangent weights
/// `options` lend ([`Region::new`]): the same result as [`solve_cached`]'s for those vertices.
pub fn solve_in(
    mesh: &Mesh,
    term: &HighlightTerm,
    phi: &[f64],
    region: &Region,
    options: &LmOptions,
    cache: &mut SolveCache,
) -> Result<LmResult> {
    check_sizes(term, phi)?;
    let w = weights(mesh, term, options);
    let sys = build_system(mesh, term, region, options, &w);
    let phi = phi.to_vec();
    let n = sys.free.len();
    // The first iteration's rows, assembled here: their energies are the initial ones (the
    // same bits as `System::energy`), so the start's residuals are evaluated once. The time is
    // the first iteration's.
    let t0 = Instant::now();
    let mut acc = Assembler::new(sys.col_of, n);
    let initial_energy = if n == 0 { sys.energy(&phi) } else { sys.assemble(&phi, &mut acc) };
    let first_assembly = t0.elapsed().as_secs_f64();
    if !initial_energy.total().is_finite() {
        return Err(numerical(format!("the initial energy is not finite: {initial_energy:?}")));
    }
    if n == 0 {
        return Ok(LmResult {
            phi,
            iterations: Vec::new(),
            stop: StopReason::NothingToSolve,
            initial_energy,
        });
    }
    let matrix_free = match options.linear_solver {
        LinearSolver::Direct => false,
        LinearSolver::ConjugateGradient => true,
        LinearSolver::Auto => n >= CG_THRESHOLD,
    };
    // The direct path's pattern: the cached one if it fits (checked in the first assembly).
    let direct: Option<DirectSystem> = if matrix_free { None } else { cache.direct.take() };
    let mut lm = Lm {
        sys: &sys,
        term,
        w: &w,
        options,
        n,
        matrix_free,
        phi,
        energy: initial_energy.total(),
        direct,
        checked: false,
        acc,
        next: Assembler::new(sys.col_of, n),
        assembled: true,
        first_assembly,
        product: None,
        first_gradient: None,
        lambda: options.initial_damping,
        nu: 2.0,
        iterations: Vec::new(),
        delta: vec![0.0; n],
        saved: vec![0.0; n],
    };
    let stop = lm.run()?;
    if lm.direct.is_some() {
        cache.direct = lm.direct;
    }
    Ok(LmResult { phi: lm.phi, iterations: lm.iterations, stop, initial_energy })
}

/// A numerical failure of the Levenberg–Marquardt solve.
fn numerical(m: String) -> Error {
    Error::Numerical { stage: "Levenberg–Marquardt", message: m }
}

/// The Levenberg–Marquardt iterations of [`solve_cached`]: the system, the angles `phi`, the
/// damping and the buffers kept from one iteration to the next.
///
/// `acc` holds the rows and Jᵀr at φ; each try assembles the trial point into `next` (its
/// energies are the trial energy), and an accepted try's `next` becomes the next iteration's
/// `acc` — so each accepted iteration evaluates its residuals once.
struct Lm<'s, 'a> {
    sys: &'s System<'a>,
    term: &'s HighlightTerm<'s>,
    w: &'s [f64],
    options: &'s LmOptions,
    /// Number of free angles.
    n: usize,
    /// The conjugate-gradient path (else the direct one).
    matrix_free: bool,
    phi: Vec<f64>,
    /// The total energy at `phi`.
    energy: f64,
    /// The direct path's pattern (built or checked in the first assembly: `checked`).
    direct: Option<DirectSystem>,
    checked: bool,
    acc: Assembler<'s>,
    next: Assembler<'s>,
    /// Whether `acc` holds the rows at `phi` already.
    assembled: bool,
    /// Seconds of the rows assembled before the first iteration (counted in its assembly).
    first_assembly: f64,
    /// JᵀJ of the conjugate-gradient path.
    product: Option<NormalMatrix>,
    first_gradient: Option<f64>,
    lambda: f64,
    nu: f64,
    iterations: Vec<Iteration>,
    delta: Vec<f64>,
    saved: Vec<f64>,
}

/// What [`Lm::linearize`] gives the tries of one iteration.
struct Linearization {
    /// The diagonal of JᵀJ.
    diag: Vec<f64>,
    /// The damping's scale: the diagonal, floored.
    dscale: Vec<f64>,
    /// The conjugate-gradient forcing term.
    forcing: f64,
}

/// The outcome of one try.
enum Try {
    /// Accepted; iterate on.
    Accepted,
    /// Accepted with too small a relative decrease: stop.
    Converged,
    /// Rejected; the damping raised, try again.
    Rejected,
    /// Rejected with the damping out of range: stop.
    NoProgress,
}

impl Lm<'_, '_> {
    /// Iterates until a stop criterion or the iteration cap; why it stopped.
    fn run(&mut self) -> Result<StopReason> {
        let mut stop = StopReason::IterationCap;
        'outer: for _ in 0..self.options.max_iterations {
            crate::cancel::checkpoint("solve")?;
            let t0 = Instant::now();
            if !self.assembled {
                self.sys.assemble(&self.phi, &mut self.acc);
            }
            let gmax = self.acc.g.iter().fold(0.0f64, |a, b| a.max(b.abs()));
            if gmax.is_nan() || gmax <= self.options.gradient_tolerance {
                stop = StopReason::Gradient;
                break;
            }
            let lin = self.linearize()?;
            let assembly = t0.elapsed().as_secs_f64() + std::mem::take(&mut self.first_assembly);
            loop {
                let t1 = Instant::now();
                let predicted = self.step(&lin)?;
                match self.try_step(predicted, assembly, t1) {
                    Try::Accepted => break,
                    Try::Converged => {
                        stop = StopReason::RelativeDecrease;
                        break 'outer;
                    }
                    Try::Rejected => {}
                    Try::NoProgress => {
                        stop = StopReason::NoProgress;
                        break 'outer;
                    }
                }
            }
            if self.assembled {
                std::mem::swap(&mut self.acc, &mut self.next);
            }
        }
        Ok(stop)
    }

    /// JᵀJ refilled from the rows in `acc` (its pattern built or checked first), its
    /// diagonal, the damping's scale and the forcing term.
    fn linearize(&mut self) -> Result<Linearization> {
        let n = self.n;
        let acc = &self.acc;
        let diag = if self.matrix_free {
            if !self.product.as_ref().is_some_and(|m| m.matches(&acc.rows, n)) {
                self.product = Some(NormalMatrix::new(&acc.rows, n));
            }
            let m = self.product.as_mut().expect("built above");
            m.fill(&acc.rows);
            m.diagonal().to_vec()
        } else {
            if !self.checked {
                self.checked = true;
                if !self.direct.as_ref().is_some_and(|d| d.matches(&acc.rows, n)) {
                    self.direct = Some(DirectSystem::new(&acc.rows, n).map_err(numerical)?);
                }
            }
            let ds = self.direct.as_mut().expect("built above");
            ds.fill(&acc.rows);
            ds.diagonal()
        };
        let grad = &acc.g;
        let gnorm = grad.iter().map(|g| g * g).sum::<f64>().sqrt();
        let g0 = *self.first_gradient.get_or_insert(gnorm);
        let forcing = CG_FORCING.min(gnorm / g0.max(f64::MIN_POSITIVE));
        let dmax = diag.iter().fold(0.0f64, |a, &b| a.max(b)).max(1e-300);
        let dscale: Vec<f64> = diag.iter().map(|&d| d.max(1e-9 * dmax)).collect();
        Ok(Linearization { diag, dscale, forcing })
    }

    /// The damped step into `delta` at the current λ; its predicted decrease.
    fn step(&mut self, lin: &Linearization) -> Result<f64> {
        let (n, lambda, grad) = (self.n, self.lambda, &self.acc.g);
        let (diag, dscale, forcing) = (&lin.diag, &lin.dscale, lin.forcing);
        let delta = &mut self.delta;
        Ok(if let Some(product) = &self.product {
            let shift: Vec<f64> = dscale.iter().map(|&d| lambda * d).collect();
            let precond: Vec<f64> = diag.iter().zip(&shift).map(|(d, s)| d + s).collect();
            let b: Vec<f64> = grad.iter().map(|g| -g).collect();
            *delta = conjugate_gradient(product, &shift, &precond, &b, forcing).0;
            // Predicted decrease of the Gauss–Newton model for an inexact step, on the
            // scale of the direct branch's ½δᵀ(λDδ − g): ½(−2gᵀδ − δᵀJᵀJδ).
            let mut jtj = vec![0.0; n];
            product.apply(delta, None, &mut jtj);
            0.5 * (0..n).map(|c| -2.0 * grad[c] * delta[c] - delta[c] * jtj[c]).sum::<f64>()
        } else {
            let ds = self.direct.as_mut().expect("built in the assembly");
            for (d, g) in delta.iter_mut().zip(grad) {
                *d = -g;
            }
            ds.solve_damped(lambda, dscale, delta).map_err(numerical)?;
            // Predicted decrease of the quadratic model: ½δᵀ(λDδ − g).
            0.5 * (0..n).map(|c| delta[c] * (lambda * dscale[c] * delta[c] - grad[c])).sum::<f64>()
        })
    }

    /// Tries `phi + delta`: kept (recorded, λ lowered) if it lowers the energy and the model
    /// agrees, else undone (λ raised).
    fn try_step(&mut self, predicted: f64, assembly: f64, t1: Instant) -> Try {
        let (sys, energy, lambda) = (self.sys, self.energy, self.lambda);
        // The trial point in place (the free angles saved to undo a rejected try).
        for (c, &v) in sys.free.iter().enumerate() {
            self.saved[c] = self.phi[v as usize];
            self.phi[v as usize] += self.delta[c];
        }
        let mut new = sys.assemble(&self.phi, &mut self.next);
        let new_energy = new.total();
        let rho = if predicted > 0.0 { (energy - new_energy) / predicted } else { -1.0 };
        if new_energy.is_finite() && new_energy < energy && rho > 0.0 {
            let step_norm = self.delta.iter().fold(0.0f64, |a, b| a.max(b.abs()));
            let mut after = new_energy;
            let mut smoothed = false;
            self.assembled = true;
            if let Some((s, es)) = self.smoothed(after) {
                self.phi = s;
                new = es;
                after = es.total();
                smoothed = true;
                self.assembled = false;
            }
            let decrease = (energy - after) / energy.max(f64::MIN_POSITIVE);
            self.energy = after;
            self.iterations.push(Iteration {
                stage: 0,
                energies: new,
                damping: lambda,
                step_norm,
                smoothed,
                assembly_seconds: assembly,
                solve_seconds: t1.elapsed().as_secs_f64(),
            });
            self.lambda *= (1.0f64 / 3.0).max(1.0 - (2.0 * rho - 1.0).powi(3));
            self.nu = 2.0;
            if decrease < self.options.relative_decrease {
                return Try::Converged;
            }
            return Try::Accepted;
        }
        for (c, &v) in sys.free.iter().enumerate() {
            self.phi[v as usize] = self.saved[c];
        }
        self.lambda *= self.nu;
        self.nu *= 2.0;
        if self.lambda.is_nan() || self.lambda >= 1e16 {
            return Try::NoProgress;
        }
        Try::Rejected
    }

    /// With interleaved smoothing: the first smoothing pass (τ = ½, ¼, ⅛) of `phi` whose
    /// energy is finite and at most `after`, and its energies.
    fn smoothed(&self, after: f64) -> Option<(Vec<f64>, Energies)> {
        if self.options.interleaved_smoothing {
            for tau in [0.5, 0.25, 0.125] {
                let s = smoothing_pass(&self.phi, self.sys.free, self.term, self.w, tau);
                let es = self.sys.energy(&s);
                if es.total().is_finite() && es.total() <= after {
                    return Some((s, es));
                }
            }
        }
        None
    }
}
