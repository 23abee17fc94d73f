//! Degenerate inputs of the optimizer: no targets, nothing to solve, an all-critical region
//! (h = n, where ℓ no longer depends on ∇φ), a k = 2 field stored with raw jumps of π, and
//! the interleaved smoothing pass with λ_s = 0.

use std::f64::consts::PI;

use grainline::generate::{self, Grid};
use grainline::geometry::connection::wrap_angle;
use grainline::geometry::{Geometry, GeometryOptions, GradientForm};
use grainline::highlight::Symmetry;
use grainline::mesh::Mesh;
use grainline::solve::{optimize, HighlightTerm, OptimizeReport, SolverSettings, StopReason};
use nalgebra::Vector3;

fn smooth_field(mesh: &Mesh, g: &Geometry) -> Vec<f64> {
    mesh.positions
        .iter()
        .zip(&g.frames)
        .map(|(p, f)| {
            f.angle_of(&Vector3::new((0.8 * p.y).cos(), (0.8 * p.y).sin() + 0.3 * p.x, 0.1))
        })
        .collect()
}

fn targets<'a>(
    g: &'a Geometry,
    h: &'a [Vector3<f64>],
    phi: &[f64],
    s: Symmetry,
) -> HighlightTerm<'a> {
    HighlightTerm::own_targets(g, h, s, GradientForm::Angle, phi)
}

fn sane(phi: &[f64], report: &OptimizeReport) {
    assert!(phi.iter().all(|p| p.is_finite()));
    serde_json::to_string(report).unwrap();
    let mut e = report.initial_energy.total();
    assert!(e.is_finite());
    for it in &report.iterations {
        assert!(it.energies.total().is_finite() && it.energies.total() <= e);
        e = it.energies.total();
    }
}

fn brush(mesh: &Mesh, centre: Vector3<f64>, radius: f64) -> Vec<bool> {
    mesh.positions.iter().map(|p| (p - centre).norm() < radius).collect()
}

#[test]
fn zero_targets() {
    let mesh = generate::quadric_patch([0.9, 0.2, -0.5], 1.0, Grid::new(12, 12));
    let g = Geometry::compute(&mesh, &GeometryOptions::default());
    let phi = smooth_field(&mesh, &g);
    let h = vec![Vector3::new(0.3, 0.4, 1.0).normalize(); phi.len()];
    let mut t = targets(&g, &h, &phi, Symmetry::Oriented);
    t.target_q = vec![None; phi.len()];
    let support = brush(&mesh, Vector3::zeros(), 0.5);
    // No energy at all: the gradient vanishes at once.
    let s0 = SolverSettings {
        smoothness: 0.0,
        interleaved_smoothing: Some(false),
        ..Default::default()
    };
    let r = optimize(&mesh, &t, &phi, &support, &s0).unwrap();
    sane(&r.phi, &r.report);
    assert_eq!(r.report.stop, StopReason::Gradient);
    for (a, b) in r.phi.iter().zip(&phi) {
        assert_eq!(*a, wrap_angle(*b));
    }
    // Smoothness only: it may only lower the Dirichlet energy.
    let r = optimize(&mesh, &t, &phi, &support, &SolverSettings::default()).unwrap();
    sane(&r.phi, &r.report);
    assert_eq!(r.report.initial_energy.highlight, 0.0);
}

#[test]
fn nothing_to_solve() {
    let mesh = generate::quadric_patch([0.9, 0.2, -0.5], 1.0, Grid::new(8, 8));
    let g = Geometry::compute(&mesh, &GeometryOptions::default());
    let phi = smooth_field(&mesh, &g);
    let h = vec![Vector3::new(0.3, 0.4, 1.0).normalize(); phi.len()];
    let t = targets(&g, &h, &phi, Symmetry::Line);
    let r = optimize(&mesh, &t, &phi, &vec![false; phi.len()], &SolverSettings::default()).unwrap();
    sane(&r.phi, &r.report);
    assert_eq!(
        (r.report.stop, r.report.unknowns, r.report.edited),
        (StopReason::NothingToSolve, 0, 0)
    );
    assert!(r.report.iterations.is_empty());
    // Every vertex hard-locked: nothing left either, and the locks hold.
    let s = SolverSettings {
        whole_mesh: true,
        constraints: grainline::solve::Constraints {
            locks: vec![grainline::solve::LockSpec {
                vertices: (0..phi.len() as u32).collect(),
                direction: Some([1.0, 0.0, 0.0]),
                ..Default::default()
            }],
            ..Default::default()
        },
        ..Default::default()
    };
    let r = optimize(&mesh, &t, &phi, &vec![true; phi.len()], &s).unwrap();
    sane(&r.phi, &r.report);
    assert_eq!(r.report.stop, StopReason::NothingToSolve);
    assert!(r.report.violations.max_lock_error < 1e-12);
    // Bad input is an error, not a panic.
    assert!(optimize(&mesh, &t, &phi[1..], &vec![false; phi.len()], &s).is_err());
    let mut nan = phi.clone();
    nan[3] = f64::NAN;
    assert!(optimize(&mesh, &t, &nan, &vec![false; phi.len()], &s).is_err());
}

#[test]
fn all_critical_region() {
    // h = n at every vertex: hᵀv = 0, ℓ = R W ū depends on φ pointwise only (math.md §3), and on
    // a plane ℓ ≡ 0.
    for mesh in [
        generate::plane(1.0, Grid::new(10, 10)),
        generate::quadric_patch([0.9, 0.2, -0.5], 1.0, Grid::new(12, 12)),
    ] {
        let g = Geometry::compute(&mesh, &GeometryOptions::default());
        let phi = smooth_field(&mesh, &g);
        let h: Vec<Vector3<f64>> = g.frames.iter().map(|f| f.n).collect();
        for sym in [Symmetry::Oriented, Symmetry::Line] {
            let t = targets(&g, &h, &phi, sym);
            let mut start = phi.clone();
            let support = brush(&mesh, Vector3::zeros(), 0.5);
            for (i, s) in support.iter().enumerate() {
                if *s {
                    start[i] += 0.3;
                }
            }
            for smoothness in [0.0, 1e-4] {
                let s = SolverSettings { smoothness, ..Default::default() };
                let r = optimize(&mesh, &t, &start, &support, &s).unwrap();
                sane(&r.phi, &r.report);
            }
        }
    }
}

#[test]
fn k2_field_with_raw_jumps_of_pi_recovers() {
    let mesh = generate::quadric_patch([0.9, 0.2, -0.5], 1.0, Grid::new(30, 30));
    let g = Geometry::compute(&mesh, &GeometryOptions::default());
    // A line field around the ±π/2 wrap, stored with a raw jump of π at every other vertex.
    let phi_true: Vec<f64> = smooth_field(&mesh, &g)
        .iter()
        .enumerate()
        .map(|(i, p)| p + PI / 2.0 + if i % 2 == 0 { PI } else { 0.0 })
        .collect();
    let h = vec![Vector3::new(0.3, 0.4, 1.0).normalize(); phi_true.len()];
    let t = targets(&g, &h, &phi_true, Symmetry::Line);
    let centre = Vector3::new(0.1, -0.1, 0.0);
    let support = brush(&mesh, centre, 0.45);
    let mut phi = phi_true.clone();
    for (i, s) in support.iter().enumerate() {
        if *s {
            let d = (mesh.positions[i] - centre).norm() / 0.45;
            phi[i] += 0.3 * (1.0 - d * d).powi(2);
        }
    }
    let s = SolverSettings { margin_rings: 0, ..Default::default() };
    let r = optimize(&mesh, &t, &phi, &support, &s).unwrap();
    sane(&r.phi, &r.report);
    let worst = (0..phi.len())
        .filter(|&i| support[i])
        .map(|i| (wrap_angle(2.0 * (r.phi[i] - phi_true[i])) / 2.0).abs())
        .fold(0.0, f64::max);
    eprintln!(
        "k = 2 with raw π jumps: {} iterations, worst {worst:.2e} rad",
        r.report.iterations.len()
    );
    assert!(worst < 1e-3 && r.report.iterations.len() <= 10, "{worst}");
}

#[test]
fn interleaved_smoothing_keeps_the_energy_monotone() {
    let mesh = generate::quadric_patch([0.9, 0.2, -0.5], 1.0, Grid::new(20, 20));
    let g = Geometry::compute(&mesh, &GeometryOptions::default());
    let phi_true = smooth_field(&mesh, &g);
    let h = vec![Vector3::new(0.3, 0.4, 1.0).normalize(); phi_true.len()];
    let t = targets(&g, &h, &phi_true, Symmetry::Oriented);
    let support = brush(&mesh, Vector3::zeros(), 0.6);
    let phi: Vec<f64> = phi_true
        .iter()
        .enumerate()
        .map(|(i, p)| p + if support[i] { 0.4 * (7.0 * mesh.positions[i].x).sin() } else { 0.0 })
        .collect();
    let s = SolverSettings { smoothness: 0.0, ..Default::default() };
    let r = optimize(&mesh, &t, &phi, &support, &s).unwrap();
    assert!(r.report.interleaved_smoothing);
    sane(&r.phi, &r.report);
    let kept = r.report.iterations.iter().filter(|i| i.smoothed).count();
    eprintln!("smoothing passes kept: {kept} of {}", r.report.iterations.len());
    assert!(
        r.report.iterations.last().unwrap().energies.total()
            < 0.1 * r.report.initial_energy.total()
    );
}

#[test]
fn byte_identical_at_any_thread_count() {
    let mesh = generate::quadric_patch([0.9, 0.2, -0.5], 1.0, Grid::new(20, 20));
    let run = |threads: usize| {
        let pool = rayon::ThreadPoolBuilder::new().num_threads(threads).build().unwrap();
        pool.install(|| {
            let g = Geometry::compute(&mesh, &GeometryOptions::default());
            let phi_true = smooth_field(&mesh, &g);
            let h = vec![Vector3::new(0.3, 0.4, 1.0).normalize(); phi_true.len()];
            let t = targets(&g, &h, &phi_true, Symmetry::Line);
            let support = brush(&mesh, Vector3::zeros(), 0.5);
            let phi: Vec<f64> = phi_true
                .iter()
                .enumerate()
                .map(|(i, p)| p + if support[i] { 0.2 } else { 0.0 })
                .collect();
            let s = SolverSettings {
                constraints: grainline::solve::Constraints {
                    turning_radius: Some(grainline::solve::TurningRadius {
                        radius: 1.0,
                        weight: 10.0,
                    }),
                    ..Default::default()
                },
                ..Default::default()
            };
            optimize(&mesh, &t, &phi, &support, &s).unwrap().phi
        })
    };
    let (a, b) = (run(1), run(2));
    assert!(a.iter().zip(&b).all(|(x, y)| x.to_bits() == y.to_bits()));
}

/// The matrix-free conjugate-gradient step (parallel products in fixed chunks) on a mesh large
/// enough to split every pass into several chunks: bit-identical at 1 and 2 threads.
#[test]
fn conjugate_gradient_is_byte_identical_at_any_thread_count() {
    use grainline::solve::{solve, HighlightTerm, LinearSolver, LmOptions};
    let mesh = generate::quadric_patch([0.9, 0.2, -0.5], 1.0, Grid::new(110, 110));
    let g = Geometry::compute(&mesh, &GeometryOptions::default());
    let phi_true = smooth_field(&mesh, &g);
    let h = vec![Vector3::new(0.3, 0.4, 1.0).normalize(); phi_true.len()];
    let t: HighlightTerm = targets(&g, &h, &phi_true, Symmetry::Line);
    let phi: Vec<f64> = phi_true
        .iter()
        .enumerate()
        .map(|(i, p)| p + 0.2 * (5.0 * mesh.positions[i].x).sin())
        .collect();
    let free: Vec<u32> = (0..phi.len() as u32).collect();
    let opts = LmOptions {
        smoothness: 1e-6,
        max_iterations: 3,
        linear_solver: LinearSolver::ConjugateGradient,
        ..Default::default()
    };
    let run = |threads: usize| {
        let pool = rayon::ThreadPoolBuilder::new().num_threads(threads).build().unwrap();
        pool.install(|| solve(&mesh, &t, &phi, &free, &opts).unwrap())
    };
    let (a, b) = (run(1), run(2));
    assert!(!a.iterations.is_empty());
    assert!(a.phi.iter().zip(&b.phi).all(|(x, y)| x.to_bits() == y.to_bits()));
    let e = |r: &grainline::solve::LmResult| r.iterations.last().unwrap().energies.total();
    assert!(e(&a) < a.initial_energy.total());
    assert_eq!(e(&a).to_bits(), e(&b).to_bits());
}

/// A bounded turn on degenerate input (docs/math.md §10): no free vertex, zero weights, a
/// target that is not a number, a free region with no rim, a zero-area face inside — each gives
/// a finite answer or none, never a panic.
#[test]
fn bounded_turns_of_degenerate_input() {
    use grainline::solve::turn::{bounded_turn, TurnInput, TurnOptions};
    let mut mesh = generate::plane(1.0, Grid::new(12, 12));
    // Collapse one interior vertex onto its neighbour: two zero-area faces.
    let (a, b) = (6 * 13 + 6, 6 * 13 + 7);
    mesh.positions[a] = mesh.positions[b];
    let g = Geometry::compute(&mesh, &GeometryOptions::default());
    let n = mesh.num_vertices();
    let phi = vec![0.3; n];
    let target: Vec<f64> = (0..n).map(|i| 0.2 * mesh.positions[i].x).collect();
    let inner: Vec<u32> = (0..n as u32)
        .filter(|&i| {
            mesh.positions[i as usize].x.abs() < 0.7 && mesh.positions[i as usize].y.abs() < 0.7
        })
        .collect();
    let options = TurnOptions { bound: 0.8, smoothness: 0.0 };
    let check = |free: &[u32], weight: &[f64], target: &[f64]| {
        let input = TurnInput { phi: &phi, target, free, weight, k: 2 };
        let out = bounded_turn(&g, &input, &options);
        if let Some(d) = &out {
            assert_eq!(d.len(), free.len());
            assert!(d.iter().all(|x| x.is_finite()));
        }
        out
    };
    assert_eq!(check(&[], &[], &target).map(|d| d.len()), Some(0), "nothing to turn");
    let ones = vec![1.0; inner.len()];
    let zeros = vec![0.0; inner.len()];
    assert!(check(&inner, &ones, &target).is_some(), "with the zero-area faces");
    assert!(check(&inner, &zeros, &target).is_some(), "zero weights: the rim decides");
    let mut nan = target.clone();
    nan[inner[3] as usize] = f64::NAN;
    assert!(check(&inner, &ones, &nan).is_none(), "a target that is not a number");
    let all: Vec<u32> = (0..n as u32).collect();
    assert!(check(&all, &vec![1.0; n], &target).is_none(), "no rim to hold");
}
