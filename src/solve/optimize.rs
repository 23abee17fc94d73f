//! The optimizer's entry point: [`optimize`] turns a highlight term, a start field and an edit
//! support into an optimized field and a report (the paper's §4.3 with the fabrication energies
//! of math.md §4).
//!
//! 1. Locks are resolved ([`super::locks`]); hard-locked angles are set exactly and leave the
//!    unknowns.
//! 2. The free set is the support dilated by `margin_rings` rings (or every vertex with
//!    `whole_mesh`), minus the hard-locked vertices.
//! 3. The relative smoothness weight becomes absolute: λ_s × the surface area (the Dirichlet
//!    energy is scale-free, the highlight energy scales like an area).
//! 4. Levenberg–Marquardt ([`super::lm`]) runs on the stacked energy.
//! 5. The report lists the iterations, the constraint violations, the lock conflicts and the
//!    singularities of the result.

use serde::Serialize;

use super::branch::coherent_start;
use super::fabrication::{GradientHinge, HingeKind};
use super::face_hinge::{FaceTurningHinge, QUADRATURE};
use super::fill::harmonic_fill;
use super::highlight_term::HighlightTerm;
use super::lm::{
    energy_in, solve_in, Energies, HingeOptions, Iteration, LinearSolver, LmOptions, Region,
    SolveCache, StopReason,
};
use super::locks::{angle_difference, resolve_locks, LockConflict};
use super::settings::SolverSettings;
use crate::geometry::connection::wrap_angle;
use crate::geometry::laplacian::cotan_weights;
use crate::highlight::singularities::{singularities, Singularity};
use crate::mesh::Mesh;
use crate::{Error, Result};

/// A vertex violates a hinge when |x| exceeds its bound by more than this fraction.
pub const VIOLATION_TOLERANCE: f64 = 0.01;

/// How far the result is from the fabrication constraints.
#[derive(Clone, Debug, Default, PartialEq, Serialize)]
pub struct ConstraintViolations {
    /// Fraction of the surface area whose |ūᵀ∇φ| exceeds 1/R by more than 1 % (null without a
    /// turning-radius constraint).
    pub turning_area_fraction: Option<f64>,
    /// max R·|ūᵀ∇φ| over the surface (≤ 1 when the constraint holds everywhere).
    pub turning_max_ratio: Option<f64>,
    /// Fraction of the surface area whose |v̄ᵀ∇φ| exceeds s_max by more than 1 %.
    pub splay_area_fraction: Option<f64>,
    /// max |v̄ᵀ∇φ|/s_max over the surface.
    pub splay_max_ratio: Option<f64>,
    /// Largest deviation of a locked vertex from its lock angle (rad, modulo 2π/k; 0 without
    /// locks).
    pub max_lock_error: f64,
    /// Fraction of the surface area (a quarter of a triangle per quadrature point) where the
    /// streamlines of the field *as the tracer interpolates it* (`solve::face_hinge`, F1) turn
    /// tighter than R by more than 1 % (null without a turning-radius constraint).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub turning_triangle_area_fraction: Option<f64>,
    /// max R·|κ| at the triangles' quadrature points (F1).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub turning_triangle_max_ratio: Option<f64>,
    /// Fraction of the surface area where the divergence of the field as the tracer
    /// interpolates it (`solve::face_hinge`, F4) exceeds s_max by more than 1 % (null without
    /// a splay constraint).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub splay_triangle_area_fraction: Option<f64>,
    /// max |σ|/s_max at the triangles' quadrature points (F4).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub splay_triangle_max_ratio: Option<f64>,
}

/// A run from one start whose final energy is at most this fraction of its initial energy
/// has reached the exact fit; no other start is tried.
const NEGLIGIBLE_ENERGY: f64 = 1e-12;

/// One solve (all continuation stages) from one start.
struct Run {
    phi: Vec<f64>,
    iterations: Vec<Iteration>,
    initial: Option<Energies>,
    stop: StopReason,
}

impl Run {
    fn final_energy(&self) -> f64 {
        self.iterations
            .last()
            .map(|i| i.energies.total())
            .or(self.initial.map(|e| e.total()))
            .unwrap_or(0.0)
    }
}

/// The start of the solve (see [`SolverSettings::harmonic_start`]).
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize)]
#[serde(rename_all = "kebab-case")]
pub enum StartChoice {
    /// The given field (after the hard locks).
    Given,
    /// The connection-harmonic fill of the free region ([`super::fill::harmonic_fill`]), whose
    /// energy was lower.
    HarmonicFill,
    /// The position energy's branch-coherent start ([`super::branch::coherent_start`]).
    CoherentBranch,
}

/// What [`optimize`] did.
#[derive(Clone, Debug, Serialize)]
pub struct OptimizeReport {
    /// Accepted iterations, each with every term's energy, λ, step norm and timings.
    pub iterations: Vec<Iteration>,
    /// Energies of the start field (after applying the hard locks).
    pub initial_energy: Energies,
    /// Why the solver stopped.
    pub stop: StopReason,
    /// Vertices in the edit support.
    pub edited: usize,
    /// Unknowns (free angles).
    pub unknowns: usize,
    /// Hard-locked vertices.
    pub hard_locked: usize,
    /// Soft-locked vertices.
    pub soft_locked: usize,
    /// The absolute smoothness weight used (λ_s × surface area).
    pub smoothness_weight: f64,
    /// Whether the interleaved smoothing pass ran.
    pub interleaved_smoothing: bool,
    /// Which start the kept solve began from.
    pub start: StartChoice,
    /// The total energy of the given field (after the hard locks), whichever start was kept:
    /// the solve lowered the energy from it to the last iteration's (or `initial_energy`'s,
    /// when the kept start needed no iteration).
    pub given_energy: f64,
    /// How many starts were solved from (1 to 3; a later one only when the earlier did not
    /// reach a negligible energy).
    pub starts_tried: usize,
    /// Constraint violations of the result.
    pub violations: ConstraintViolations,
    /// Vertices where locks disagree, with the angles asked for and the one used.
    pub conflicting_locks: Vec<LockConflict>,
    /// Vertices where a lock's direction has no tangential part (lock skipped).
    pub degenerate_lock_vertices: Vec<u32>,
    /// Singular faces of the result.
    pub singularities: Vec<Singularity>,
}

/// The optimized field and its report.
#[derive(Clone, Debug)]
pub struct OptimizeResult {
    /// φ per vertex (in the geometry's frames, wrapped to (−π, π]).
    pub phi: Vec<f64>,
    /// What happened.
    pub report: OptimizeReport,
}

/// How many times longer than the support's longest inner edge an edge may be and still free
/// its far end as a margin vertex ([`dilate`]).
pub const MARGIN_EDGE_FACTOR: f64 = 4.0;

/// The vertices within `rings` graph steps of a `true` entry of `support`, each step along an
/// edge at most [`MARGIN_EDGE_FACTOR`] times the longest edge between two support vertices
///. A margin is a few rings *near* the brush: a CAD face's
/// sliver or strip joins a refined brush to a vertex across the face, whose grain — and the
/// grain of every triangle it spans — the solve would otherwise turn. On a mesh whose edges
/// are of one size this is the plain ring dilation.
pub fn dilate(mesh: &Mesh, term: &HighlightTerm, support: &[bool], rings: u32) -> Vec<bool> {
    let adj = &term.geometry.adjacency;
    let p = &mesh.positions;
    let mut longest: f64 = 0.0;
    for v in (0..support.len()).filter(|&v| support[v]) {
        for &j in adj.neighbors(v) {
            if support[j as usize] {
                longest = longest.max((p[j as usize] - p[v]).norm());
            }
        }
    }
    // A support of one vertex has no inner edge: its ring is the margin, whatever its length.
    let reach = if longest > 0.0 { MARGIN_EDGE_FACTOR * longest } else { f64::INFINITY };
    let mut inside = support.to_vec();
    let mut frontier: Vec<u32> =
        (0..support.len() as u32).filter(|&v| support[v as usize]).collect();
    for _ in 0..rings {
        let mut next = Vec::new();
        for &v in &frontier {
            for &j in adj.neighbors(v as usize) {
                if !inside[j as usize] && (p[j as usize] - p[v as usize]).norm() <= reach {
                    inside[j as usize] = true;
                    next.push(j);
                }
            }
        }
        next.sort_unstable();
        frontier = next;
    }
    inside
}

/// What a caller that solves many times on one mesh lends [`optimize_with`] (the editor's drag
/// steps, issue 16). None of it changes the field the solve finds.
#[derive(Clone, Debug)]
pub struct OptimizeReuse {
    /// The mesh's cotangent weights ([`cotan_weights`]), computed once.
    pub cotan_weights: Option<std::sync::Arc<Vec<f64>>>,
    /// Whether the whole-mesh figures of the report are measured: the constraint violations
    /// and the singularities (false: left empty, for a report made later on the same field).
    pub whole_mesh_report: bool,
    /// The gradient stencil's users ([`crate::geometry::GradientStencil::users`]), made once:
    /// the solve's set-up then visits the free vertices and their neighbours, not the part.
    pub stencil_users: Option<std::sync::Arc<crate::geometry::gradient::StencilUsers>>,
    /// The part's [`surface_area`], summed once.
    pub surface_area: Option<f64>,
}

/// The surface area the relative smoothness weight is scaled by: the sum of the vertex areas
/// that are finite and positive.
pub fn surface_area(g: &crate::geometry::Geometry) -> f64 {
    g.areas.iter().filter(|a| a.is_finite() && **a > 0.0).sum()
}

impl Default for OptimizeReuse {
    fn default() -> Self {
        OptimizeReuse {
            cotan_weights: None,
            whole_mesh_report: true,
            stencil_users: None,
            surface_area: None,
        }
    }
}

/// Optimizes the field `phi` (angles in `term.geometry`'s frames) against `term`, freeing the
/// edit `support` (one flag per vertex) dilated by the settings' margin.
pub fn optimize(
    mesh: &Mesh,
    term: &HighlightTerm,
    phi: &[f64],
    support: &[bool],
    settings: &SolverSettings,
) -> Result<OptimizeResult> {
    optimize_with(mesh, term, phi, support, settings, &OptimizeReuse::default())
}

/// [`optimize`] with what `reuse` lends: the same field, bit for bit, and the same report but
/// for the whole-mesh figures when `reuse.whole_mesh_report` is false.
pub fn optimize_with(
    mesh: &Mesh,
    term: &HighlightTerm,
    phi: &[f64],
    support: &[bool],
    settings: &SolverSettings,
    reuse: &OptimizeReuse,
) -> Result<OptimizeResult> {
    settings.validate()?;
    check_inputs(mesh, term, phi, support)?;
    let g = term.geometry;
    let nv = g.num_vertices();
    let k = term.symmetry.k();
    let c = &settings.constraints;
    let locks = resolve_locks(mesh, g, &c.locks, k, c.conflict_tolerance, "constraints.locks")?;
    let mut start = phi.to_vec();
    let mut free = if settings.whole_mesh {
        vec![true; nv]
    } else {
        dilate(mesh, term, support, settings.margin_rings)
    };
    for &(v, a) in &locks.hard {
        start[v as usize] = a;
        free[v as usize] = false;
    }
    let free_list: Vec<u32> = (0..nv as u32).filter(|&v| free[v as usize]).collect();
    let options = lm_options(mesh, term, settings, &locks, reuse);
    let w = options.cotan_weights.clone().expect("set by lm_options");
    let region = Region::new(g, &free_list, &w, reuse.stencil_users.as_deref());
    let stages: Vec<f64> = if settings.continuation && settings.smoothness > 0.0 {
        vec![1000.0, 100.0, 10.0, 1.0]
    } else {
        vec![1.0]
    };
    let solves = Solves {
        mesh,
        term,
        free_list: &free_list,
        region: &region,
        options: &options,
        settings,
        stages,
        // One cache for every solve below: they share the free set, so the direct path's
        // pattern, ordering and symbolic analysis are built once (rebuilt only if a stage's
        // blocks differ).
        cache: std::cell::RefCell::new(SolveCache::default()),
    };
    let (candidates, given_energy) = solves.candidates(start)?;
    let (start_choice, run, starts_tried) = solves.best_run(candidates, given_energy)?;
    let Run { phi: mut out, iterations, initial: initial_energy, stop } = run;
    let initial_energy = initial_energy.unwrap_or_default();
    for p in out.iter_mut() {
        *p = wrap_angle(*p);
    }
    let violations = if reuse.whole_mesh_report {
        violations(mesh, term, settings, &locks, &out)
    } else {
        ConstraintViolations::default()
    };
    let report = OptimizeReport {
        iterations,
        initial_energy,
        stop,
        edited: support.iter().filter(|&&s| s).count(),
        unknowns: free_list.len(),
        hard_locked: locks.hard.len(),
        soft_locked: locks.soft.len(),
        smoothness_weight: options.smoothness,
        interleaved_smoothing: options.interleaved_smoothing,
        start: start_choice,
        given_energy,
        starts_tried,
        violations,
        conflicting_locks: locks.conflicts,
        degenerate_lock_vertices: locks.degenerate,
        singularities: if reuse.whole_mesh_report {
            singularities(mesh, g, &out, k)
        } else {
            Vec::new()
        },
    };
    Ok(OptimizeResult { phi: out, report })
}

/// The checks of [`optimize_with`]'s input sizes and angles.
fn check_inputs(mesh: &Mesh, term: &HighlightTerm, phi: &[f64], support: &[bool]) -> Result<()> {
    let nv = term.geometry.num_vertices();
    if mesh.num_vertices() != nv {
        return Err(Error::invalid_arg(
            "mesh",
            format!("{} vertices, the geometry has {nv}", mesh.num_vertices()),
        ));
    }
    if phi.len() != nv || support.len() != nv {
        return Err(Error::invalid_arg(
            "phi",
            format!("{} angles and {} support flags for {nv} vertices", phi.len(), support.len()),
        ));
    }
    if let Some(i) = phi.iter().position(|p| !p.is_finite()) {
        return Err(Error::invalid_arg("phi", format!("angle of vertex {i} is not finite")));
    }
    Ok(())
}

/// The absolute weights and hinges of the solves of [`optimize_with`], from the settings
/// (relative to the mesh's area) and the resolved locks.
fn lm_options(
    mesh: &Mesh,
    term: &HighlightTerm,
    settings: &SolverSettings,
    locks: &super::locks::ResolvedLocks,
    reuse: &OptimizeReuse,
) -> LmOptions {
    let g = term.geometry;
    let c = &settings.constraints;
    let area = reuse.surface_area.unwrap_or_else(|| surface_area(g));
    LmOptions {
        smoothness: settings.smoothness * area,
        max_iterations: settings.max_iterations,
        relative_decrease: settings.relative_decrease,
        gradient_tolerance: settings.gradient_tolerance,
        initial_damping: settings.initial_damping,
        turning: c
            .turning_radius
            .as_ref()
            .map(|t| HingeOptions { bound: 1.0 / t.radius, weight: t.weight }),
        splay: c.splay.as_ref().map(|s| HingeOptions { bound: s.max, weight: s.weight }),
        turning_faces: c.turning_radius.as_ref().and_then(|t| {
            let f = c.turning_in_triangles.clone().unwrap_or_default();
            f.enabled.then(|| HingeOptions {
                bound: (1.0 - f.margin) / t.radius,
                weight: f.weight.unwrap_or(t.weight),
            })
        }),
        splay_faces: c.splay.as_ref().and_then(|sp| {
            let f = c.splay_in_triangles.clone().unwrap_or_default();
            f.enabled.then(|| HingeOptions {
                bound: sp.max * (1.0 - f.margin),
                weight: f.weight.unwrap_or(sp.weight),
            })
        }),
        soft_locks: locks.soft.clone(),
        interleaved_smoothing: settings.smoothing_pass(),
        linear_solver: LinearSolver::Auto,
        cotan_weights: Some(match &reuse.cotan_weights {
            Some(w) if w.len() == g.adjacency.num_slots() => w.clone(),
            _ => std::sync::Arc::new(cotan_weights(mesh, &g.adjacency)),
        }),
    }
}

/// The starts to run, in order: each start's kind and angles.
type Candidates = Vec<(StartChoice, Vec<f64>)>;

/// What the solves of [`optimize_with`] share: the free vertices, the options, the
/// continuation stages' smoothness factors and the direct path's cache.
struct Solves<'a> {
    mesh: &'a Mesh,
    term: &'a HighlightTerm<'a>,
    free_list: &'a [u32],
    region: &'a Region,
    options: &'a LmOptions,
    settings: &'a SolverSettings,
    stages: Vec<f64>,
    cache: std::cell::RefCell<SolveCache>,
}

impl Solves<'_> {
    /// One run: every continuation stage from `start`.
    fn run_from(&self, start: Vec<f64>) -> Result<Run> {
        let (stages, options, cache) = (&self.stages, self.options, &self.cache);
        let mut run = Run {
            phi: start,
            iterations: Vec::new(),
            initial: None,
            stop: StopReason::IterationCap,
        };
        for (stage, factor) in stages.iter().enumerate() {
            let last = stage + 1 == stages.len();
            let left = self.settings.max_iterations.saturating_sub(run.iterations.len());
            let opts = LmOptions {
                smoothness: factor * options.smoothness,
                max_iterations: if last { left } else { left.min(5) },
                ..options.clone()
            };
            let lm = solve_in(
                self.mesh,
                self.term,
                &run.phi,
                self.region,
                &opts,
                &mut cache.borrow_mut(),
            )?;
            run.initial.get_or_insert(lm.initial_energy);
            run.iterations.extend(lm.iterations.into_iter().map(|mut it| {
                it.stage = stage;
                it
            }));
            run.phi = lm.phi;
            run.stop = lm.stop;
        }
        Ok(run)
    }

    /// The energy of `phi` over the free set (a solve's initial energy, the same bits).
    fn energy(&self, phi: &[f64]) -> Result<f64> {
        Ok(energy_in(self.mesh, self.term, phi, self.region, self.options)?.total())
    }

    /// The starts to run, in order, and the given start's energy.
    fn candidates(&self, start: Vec<f64>) -> Result<(Candidates, f64)> {
        let (term, free_list, options, settings) =
            (self.term, self.free_list, self.options, self.settings);
        let g = term.geometry;
        let k = term.symmetry.k();
        // Candidate starts: the given field and, when asked, the harmonic fill; the one of lower
        // energy first. The second runs only if the first does not reach (near) zero energy, and
        // the run with the lower final energy is kept.
        let mut candidates = vec![(StartChoice::Given, start)];
        if settings.harmonic_start && !settings.whole_mesh && !free_list.is_empty() {
            let w = options.cotan_weights.clone().expect("set above");
            if let Some(fill) = harmonic_fill(g, &w, &candidates[0].1, free_list, k) {
                let e_given = self.energy(&candidates[0].1)?;
                let e_fill = self.energy(&fill)?;
                let fill = (StartChoice::HarmonicFill, fill);
                if e_fill < e_given {
                    candidates.insert(0, fill);
                } else {
                    candidates.push(fill);
                }
            }
        }
        // The position energy's branch-coherent start (`super::branch`) goes first: it satisfies
        // every position row, and the other starts can reach the same (zero) energy on mixed
        // branches, which misplace the highlight. It is kept when its solve ends at a negligible
        // energy relative to the given start's.
        let given = candidates.iter().find(|(c, _)| *c == StartChoice::Given).expect("given");
        let given_energy = self.energy(&given.1)?;
        if let Some(coherent) = coherent_start(term, &given.1, free_list) {
            candidates.insert(0, (StartChoice::CoherentBranch, coherent));
        }
        Ok((candidates, given_energy))
    }

    /// Runs the `candidates` in order until one ends at a negligible energy; the run of the
    /// lowest final energy, its start, and the number of starts run.
    fn best_run(
        &self,
        candidates: Candidates,
        given_energy: f64,
    ) -> Result<(StartChoice, Run, usize)> {
        let (term, g) = (self.term, self.term.geometry);
        // The energy of a unit residual on every free row, Σ wᵢAᵢ: a run that ends below a
        // negligible fraction of it has met its rows to round-off, however small the start's own
        // energy was (an edit's designed grain starts the solve near zero energy).
        let unit_energy: f64 = self
            .free_list
            .iter()
            .map(|&v| (term.weight[v as usize] * g.areas[v as usize]).max(0.0))
            .filter(|e| e.is_finite())
            .sum();
        let mut best: Option<(StartChoice, Run)> = None;
        let mut starts_tried = 0;
        for (choice, start) in candidates {
            let run = self.run_from(start)?;
            starts_tried += 1;
            let e0 = run.initial.map_or(0.0, |e| e.total());
            let e1 = run.final_energy();
            let coherent = choice == StartChoice::CoherentBranch;
            if best.as_ref().is_none_or(|(_, b)| e1 < b.final_energy()) {
                best = Some((choice, run));
            }
            let scale = if coherent { given_energy.max(e0) } else { e0 };
            if e1 <= NEGLIGIBLE_ENERGY * scale || e1 <= NEGLIGIBLE_ENERGY * unit_energy {
                break;
            }
        }
        let (start_choice, run) = best.expect("at least the given start");
        Ok((start_choice, run, starts_tried))
    }
}

/// The constraint violations of the field `out` over the whole mesh.
fn violations(
    mesh: &Mesh,
    term: &HighlightTerm,
    settings: &SolverSettings,
    locks: &super::locks::ResolvedLocks,
    out: &[f64],
) -> ConstraintViolations {
    let g = term.geometry;
    let nv = g.num_vertices();
    let k = term.symmetry.k();
    let c = &settings.constraints;
    let violation = |kind: HingeKind, bound: f64| {
        let hinge = GradientHinge {
            geometry: g,
            symmetry: term.symmetry,
            form: term.form,
            kind,
            bound,
            weight: 0.0,
        };
        let (mut bad, mut total, mut worst) = (0.0, 0.0, 0.0f64);
        for i in 0..nv {
            let ratio = hinge.value(out, i).abs() / bound;
            let a = g.areas[i].max(0.0);
            total += a;
            if ratio > 1.0 + VIOLATION_TOLERANCE {
                bad += a;
            }
            worst = worst.max(ratio);
        }
        (if total > 0.0 { bad / total } else { 0.0 }, worst)
    };
    let mut violations = ConstraintViolations::default();
    if let Some(t) = &c.turning_radius {
        let (f, m) = violation(HingeKind::Turning, 1.0 / t.radius);
        violations.turning_area_fraction = Some(f);
        violations.turning_max_ratio = Some(m);
    }
    // The same figures inside the triangles, on the field as the tracer interpolates it.
    let frames = FaceTurningHinge::frames(mesh);
    let triangle_violation = |kind: HingeKind, bound: f64| {
        let hinge = FaceTurningHinge {
            geometry: g,
            symmetry: term.symmetry,
            faces: frames.clone(),
            kind,
            radius: 1.0 / bound,
            weight: 0.0,
        };
        let (mut bad, mut total, mut worst) = (0.0, 0.0, 0.0f64);
        for (f, frame) in hinge.faces.iter().enumerate() {
            for q in 0..QUADRATURE.len() {
                let a = frame.area / QUADRATURE.len() as f64;
                total += a;
                if let Some(x) = hinge.curvature(out, f, q) {
                    let ratio = x.abs() / bound;
                    if ratio > 1.0 + VIOLATION_TOLERANCE {
                        bad += a;
                    }
                    worst = worst.max(ratio);
                }
            }
        }
        (if total > 0.0 { bad / total } else { 0.0 }, worst)
    };
    if let Some(t) = &c.turning_radius {
        let (f, m) = triangle_violation(HingeKind::Turning, 1.0 / t.radius);
        violations.turning_triangle_area_fraction = Some(f);
        violations.turning_triangle_max_ratio = Some(m);
    }
    if let Some(sp) = &c.splay {
        let (f, m) = triangle_violation(HingeKind::Splay, sp.max);
        violations.splay_triangle_area_fraction = Some(f);
        violations.splay_triangle_max_ratio = Some(m);
    }
    if let Some(s) = &c.splay {
        let (f, m) = violation(HingeKind::Splay, s.max);
        violations.splay_area_fraction = Some(f);
        violations.splay_max_ratio = Some(m);
    }
    violations.max_lock_error = locks
        .hard
        .iter()
        .map(|&(v, a)| (v, a))
        .chain(locks.soft.iter().map(|&(v, a, _)| (v, a)))
        .map(|(v, a)| angle_difference(out[v as usize], a, k).abs())
        .fold(0.0, f64::max);
    violations
}
