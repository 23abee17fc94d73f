//! Levenberg–Marquardt recovers a known field from its own highlight targets (math.md §3).

use grainline::generate::{self, Grid};
use grainline::geometry::connection::wrap_angle;
use grainline::geometry::{Geometry, GeometryOptions, GradientForm};
use grainline::highlight::Symmetry;
use grainline::mesh::Mesh;
use grainline::solve::{solve, HighlightTerm, LinearSolver, LmOptions};
use nalgebra::Vector3;

/// The true field's world direction: turning slowly with position.
fn world(p: &Vector3<f64>) -> Vector3<f64> {
    Vector3::new((0.8 * p.y).cos(), (0.8 * p.y).sin() + 0.3 * p.x, 0.1)
}

/// The true field in each frame: [`world`] projected onto the tangent planes. It is smooth
/// only where the projection keeps a good part of its length; where `world` is normal to the
/// surface it is singular and recovery is ill-posed, so brushes are kept away from there.
fn true_field(mesh: &Mesh, g: &Geometry) -> Vec<f64> {
    (0..mesh.num_vertices()).map(|i| g.frames[i].angle_of(&world(&mesh.positions[i]))).collect()
}

/// Fraction of `world`'s length left after projection onto the tangent plane of vertex `i`.
fn tangential_fraction(mesh: &Mesh, g: &Geometry, i: usize) -> f64 {
    let w = world(&mesh.positions[i]);
    let n = g.frames[i].n;
    (w - n * n.dot(&w)).norm() / w.norm()
}

fn recover(mesh: &Mesh, symmetry: Symmetry, centre: Vector3<f64>, radius: f64) {
    recover_with(mesh, symmetry, centre, radius, LinearSolver::Auto);
}

fn recover_with(
    mesh: &Mesh,
    symmetry: Symmetry,
    centre: Vector3<f64>,
    radius: f64,
    linear_solver: LinearSolver,
) {
    let g = Geometry::compute(mesh, &GeometryOptions::default());
    let n = mesh.num_vertices();
    let h = vec![Vector3::new(0.3, 0.4, 1.0).normalize(); n];
    let phi_true = true_field(mesh, &g);
    let term = HighlightTerm::own_targets(&g, &h, symmetry, GradientForm::Angle, &phi_true);
    let brush: Vec<u32> =
        (0..n as u32).filter(|&i| (mesh.positions[i as usize] - centre).norm() < radius).collect();
    assert!(brush.len() > 20);
    let mut phi = phi_true.clone();
    for &i in &brush {
        let d = (mesh.positions[i as usize] - centre).norm() / radius;
        phi[i as usize] += 0.3 * (1.0 - d * d).powi(2);
    }
    let opts = LmOptions { smoothness: 1e-4, linear_solver, ..Default::default() };
    let r = solve(mesh, &term, &phi, &brush, &opts).unwrap();
    let k = symmetry.k() as f64;
    let worst = brush
        .iter()
        .map(|&i| (wrap_angle(k * (r.phi[i as usize] - phi_true[i as usize])) / k).abs())
        .fold(0.0, f64::max);
    let energies: Vec<f64> = std::iter::once(r.initial_energy.total())
        .chain(r.iterations.iter().map(|it| it.energies.total()))
        .collect();
    eprintln!("{symmetry:?}: {} free, {} iterations, stop {:?}, worst error {worst:.2e} rad, energies {:?}", brush.len(), r.iterations.len(), r.stop, energies);
    for w in energies.windows(2) {
        assert!(w[1] <= w[0], "accepted steps never increase the energy");
    }
    let to_1e3 = r.iterations.len();
    assert!(worst < 1e-3, "worst error {worst}");
    assert!(to_1e3 <= 10, "{to_1e3} iterations");
}

#[test]
fn recovers_a_perturbed_field_on_a_quadric_patch() {
    let mesh = generate::quadric_patch([0.9, 0.2, -0.5], 1.0, Grid::new(30, 30));
    for sym in [Symmetry::Oriented, Symmetry::Line] {
        recover(&mesh, sym, Vector3::new(0.1, -0.1, 0.0), 0.45);
    }
}

/// The inexact matrix-free step (conjugate gradients, used from 20k unknowns) recovers the
/// field as the direct one does: same tolerance, same iteration bound.
#[test]
fn conjugate_gradient_steps_recover_too() {
    let mesh = generate::quadric_patch([0.9, 0.2, -0.5], 1.0, Grid::new(30, 30));
    for sym in [Symmetry::Oriented, Symmetry::Line] {
        recover_with(
            &mesh,
            sym,
            Vector3::new(0.1, -0.1, 0.0),
            0.45,
            LinearSolver::ConjugateGradient,
        );
    }
}

/// A brush of `radius` whose ball of 1.5 × radius keeps the true field farthest from singular.
fn smooth_brush_centre(mesh: &Mesh, radius: f64) -> Vector3<f64> {
    let g = Geometry::compute(mesh, &GeometryOptions::default());
    let best = (0..mesh.num_vertices())
        .step_by(37)
        .map(|c| {
            let worst = (0..mesh.num_vertices())
                .filter(|&i| (mesh.positions[i] - mesh.positions[c]).norm() < 1.5 * radius)
                .map(|i| tangential_fraction(mesh, &g, i))
                .fold(1.0, f64::min);
            (worst, c)
        })
        .max_by(|a, b| a.0.total_cmp(&b.0).then(b.1.cmp(&a.1)))
        .unwrap();
    mesh.positions[best.1]
}

#[test]
fn recovers_on_a_sphere() {
    let mesh = generate::icosphere(1.0, 4);
    let centre = smooth_brush_centre(&mesh, 0.3);
    for sym in [Symmetry::Oriented, Symmetry::Line] {
        recover(&mesh, sym, centre, 0.3);
    }
}

/// The harmonic fill (`solve::fill`) of an axial field on a cylinder: the axial field is parallel
/// (the discrete transport between two tangent planes of a cylinder is a rotation about its
/// axis), so it is the exact minimizer of the connection Dirichlet energy with its own boundary
/// values, whatever the start inside — for k = 1, and for k = 2 with the fixed vertices' signs
/// flipped at random (a line field does not see them).
#[test]
fn harmonic_fill_restores_a_parallel_field() {
    use grainline::geometry::laplacian::cotan_weights;
    use grainline::solve::fill::harmonic_fill;
    let mesh = generate::cylinder(1.0, 2.0, 48, 24);
    let g = Geometry::compute(&mesh, &GeometryOptions::default());
    let n = mesh.num_vertices();
    let axial: Vec<f64> =
        (0..n).map(|i| g.frames[i].angle_of(&Vector3::new(0.0, 0.0, 1.0))).collect();
    let free: Vec<u32> =
        (0..n as u32).filter(|&i| mesh.positions[i as usize].z.abs() < 0.5).collect();
    assert!(free.len() > 100);
    let w = cotan_weights(&mesh, &g.adjacency);
    for k in [1u32, 2] {
        let start: Vec<f64> = (0..n)
            .map(|i| {
                let scramble = if free.binary_search(&(i as u32)).is_ok() {
                    1.3 * (7.1 * i as f64).sin()
                } else if k == 2 && i % 3 == 0 {
                    std::f64::consts::PI
                } else {
                    0.0
                };
                axial[i] + scramble
            })
            .collect();
        let fill = harmonic_fill(&g, &w, &start, &free, k).expect("factorizable");
        let kf = k as f64;
        for &i in &free {
            let e = wrap_angle(kf * (fill[i as usize] - axial[i as usize])) / kf;
            assert!(e.abs() < 1e-9, "k = {k}, vertex {i}: error {e}");
        }
        for i in (0..n).filter(|i| free.binary_search(&(*i as u32)).is_err()) {
            assert_eq!(fill[i], start[i], "fixed vertex {i} moved");
        }
    }
}

/// The conjugate-gradient path gives the same bits at 1, 2 and 3 threads, on a torus large
/// enough that the assembled JᵀJ, its products and the dot products run over several parallel
/// chunks, with the turning-radius hinge assembled too.
#[test]
fn conjugate_gradient_steps_are_the_same_at_any_thread_count() {
    let mesh = generate::torus(2.0, 0.7, 200, 100);
    let g = Geometry::compute(&mesh, &GeometryOptions::default());
    let n = mesh.num_vertices();
    assert!(n > 16_384 + 2048, "{n} vertices: too few for several chunks");
    let h = vec![Vector3::new(0.3, 0.4, 1.0).normalize(); n];
    let phi_true = true_field(&mesh, &g);
    let term = HighlightTerm::own_targets(&g, &h, Symmetry::Line, GradientForm::Angle, &phi_true);
    let phi: Vec<f64> =
        (0..n).map(|i| phi_true[i] + 0.2 * (3.0 * mesh.positions[i].x).sin()).collect();
    let free: Vec<u32> = (0..n as u32).collect();
    let opts = LmOptions {
        smoothness: 1e-4,
        max_iterations: 2,
        turning: Some(grainline::solve::HingeOptions { bound: 2.0, weight: 1.0 }),
        linear_solver: LinearSolver::ConjugateGradient,
        ..Default::default()
    };
    let run = |threads: usize| {
        let pool = rayon::ThreadPoolBuilder::new().num_threads(threads).build().unwrap();
        pool.install(|| solve(&mesh, &term, &phi, &free, &opts).unwrap())
    };
    let one = run(1);
    assert_eq!(one.iterations.len(), 2);
    assert!(one.iterations[1].energies.total() < one.initial_energy.total());
    for threads in [2, 3] {
        let other = run(threads);
        assert!(
            one.phi.iter().zip(&other.phi).all(|(a, b)| a.to_bits() == b.to_bits()),
            "{threads} threads"
        );
    }
}

/// A bounded turn removes the windings of its target and adds none (docs/math.md §10): on a
/// curved patch with a regular field, a target rotation with a ±½ pair (the rotation that
/// would put two singular faces there) comes back as a real rotation whose field is as regular
/// as the one turned, every edge within the bound, most vertices on their target; a target with
/// a lone ½ (a rim around a net winding) is refused.
#[test]
fn a_bounded_turn_adds_no_singularity_and_keeps_its_target_away_from_the_pair() {
    use grainline::solve::singularities::face_index;
    use grainline::solve::turn::{bounded_turn, TurnInput, TurnOptions};
    let mesh = generate::quadric_patch([0.3, 0.1, -0.2], 1.0, Grid::new(40, 40));
    let g = Geometry::compute(&mesh, &GeometryOptions::default());
    let n = mesh.num_vertices();
    let phi: Vec<f64> =
        (0..n).map(|i| g.frames[i].angle_of(&Vector3::new(1.0, 0.2, 0.0))).collect();
    let p = |i: usize| mesh.positions[i];
    let arg = |i: usize, c: (f64, f64)| (p(i).y - c.1).atan2(p(i).x - c.0);
    let (a, b) = ((-0.26, 0.11), (0.24, -0.09));
    let pair: Vec<f64> = (0..n).map(|i| 0.4 + 0.5 * (arg(i, a) - arg(i, b))).collect();
    let free: Vec<u32> = (0..n as u32)
        .filter(|&i| p(i as usize).x.abs() < 0.8 && p(i as usize).y.abs() < 0.8)
        .collect();
    let weight = vec![1.0; free.len()];
    let singular =
        |f: &[f64]| (0..mesh.num_faces()).filter(|&t| face_index(&mesh, &g, f, t, 2) != 0).count();
    assert_eq!(singular(&phi), 0);
    let direct: Vec<f64> = (0..n).map(|i| phi[i] + pair[i]).collect();
    assert_eq!(singular(&direct), 2, "the target winds around the pair");
    let options = TurnOptions { bound: 0.8, smoothness: 0.0 };
    let input = TurnInput { phi: &phi, target: &pair, free: &free, weight: &weight, k: 2 };
    let turn = bounded_turn(&g, &input, &options).expect("a pair's rim closes");
    // Δ on the free vertices, the target (lifted near 0) elsewhere.
    let mut delta: Vec<f64> = pair.iter().map(|&t| wrap_angle(2.0 * t) / 2.0).collect();
    for (&v, d) in free.iter().zip(&turn) {
        delta[v as usize] = *d;
    }
    let turned: Vec<f64> = (0..n).map(|i| phi[i] + delta[i]).collect();
    assert_eq!(singular(&turned), 0, "a bounded turn adds no singular face");
    let adj = &g.adjacency;
    let beta = 0.8 * std::f64::consts::FRAC_PI_2;
    for &v in &free {
        let i = v as usize;
        for s in adj.slots(i) {
            let j = adj.target(s);
            let d = wrap_angle(2.0 * (phi[j] + g.transport[s] - phi[i])) / 2.0;
            // The rim's lift is not returned: there the turn is read mod π.
            let mut turn = d + delta[j] - delta[i];
            if free.binary_search(&(j as u32)).is_err() {
                turn = wrap_angle(2.0 * turn) / 2.0;
            }
            assert!(turn.abs() <= beta + 1e-9, "edge {i}–{j} over the bound");
        }
    }
    let kept = free
        .iter()
        .filter(|&&v| (wrap_angle(2.0 * (delta[v as usize] - pair[v as usize])) / 2.0).abs() < 1e-3)
        .count();
    assert!(kept as f64 >= 0.8 * free.len() as f64, "{kept} of {} on their target", free.len());
    let lone: Vec<f64> = (0..n).map(|i| 0.5 * arg(i, a)).collect();
    let input = TurnInput { target: &lone, ..input };
    assert!(bounded_turn(&g, &input, &options).is_none(), "a lone ½ has no bounded turn");
}
