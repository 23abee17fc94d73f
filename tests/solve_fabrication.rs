//! Fabrication energies (math.md §4): analytic Jacobians against central differences, and the
//! constraints holding after a solve on a plane, where ∇φ is known in closed form.

use grainline::generate::{self, Grid, GridPattern};
use grainline::geometry::{Geometry, GeometryOptions, GradientForm};
use grainline::highlight::Symmetry;
use grainline::mesh::Mesh;
use grainline::solve::fabrication::lock_residual;
use grainline::solve::{
    optimize, GradientHinge, HighlightTerm, HingeKind, SolverSettings, Splay, TurningRadius,
};
use nalgebra::Vector3;

fn hinge_check(kind: HingeKind, form: GradientForm, symmetry: Symmetry) {
    let mesh = generate::quadric_patch(
        [0.9, 0.3, -0.6],
        1.0,
        Grid { pattern: GridPattern::Jittered { amount: 0.2, seed: 7 }, ..Grid::new(9, 9) },
    );
    let g = Geometry::compute(&mesh, &GeometryOptions::default());
    let phi: Vec<f64> = mesh
        .positions
        .iter()
        .map(|p| 0.9 * p.x - 0.7 * p.y + 0.5 * (2.0 * p.x * p.y).sin())
        .collect();
    let mut hinge = GradientHinge { geometry: &g, symmetry, form, kind, bound: 1.0, weight: 3.0 };
    // A bound at the median |x|: about half the rows active.
    let mut xs: Vec<f64> = (0..phi.len()).map(|i| hinge.value(&phi, i).abs()).collect();
    xs.sort_by(f64::total_cmp);
    hinge.bound = xs[xs.len() / 2];
    let mut entries = Vec::new();
    let (mut active, mut worst) = (0, 0.0f64);
    for i in 0..phi.len() {
        let r = hinge.jacobian(&phi, i, &mut entries);
        assert_eq!(r, hinge.residual(&phi, i));
        let excess = hinge.value(&phi, i).abs() / hinge.bound - 1.0;
        if excess.abs() < 1e-4 {
            continue; // the kink: central differences straddle it
        }
        active += usize::from(excess > 0.0);
        let row_max = entries.iter().fold(0.0f64, |a, e| a.max(e.1.abs()));
        for &(j, d) in &entries {
            let step = 1e-6;
            let (mut p1, mut p2) = (phi.clone(), phi.clone());
            p1[j as usize] += step;
            p2[j as usize] -= step;
            let fd = (hinge.residual(&p1, i) - hinge.residual(&p2, i)) / (2.0 * step);
            let err = (fd - d).abs() / row_max.max(1e-12);
            worst = worst.max(err);
            assert!(err < 1e-6, "{kind:?} {form:?} {symmetry:?} row {i} col {j}: {d} vs fd {fd}");
            if excess < 0.0 {
                assert_eq!(d, 0.0, "inactive rows have zero entries");
            }
        }
    }
    assert!(active > 10, "{active} active rows");
    eprintln!("{kind:?} {form:?} {symmetry:?}: {active} active, worst relative error {worst:.1e}");
}

#[test]
fn hinge_jacobians_match_central_differences() {
    for kind in [HingeKind::Turning, HingeKind::Splay] {
        for form in [GradientForm::Angle, GradientForm::Sine] {
            for sym in [Symmetry::Oriented, Symmetry::Line] {
                hinge_check(kind, form, sym);
            }
        }
    }
}

#[test]
fn lock_residual_derivative_and_periodicity() {
    for k in [1u32, 2] {
        for &(phi, target) in &[(0.3, -0.4), (3.0, -3.0), (1.5, 1.5 + std::f64::consts::PI)] {
            let (r, d) = lock_residual(phi, target, 1.7, k);
            let h = 1e-6;
            let fd = (lock_residual(phi + h, target, 1.7, k).0
                - lock_residual(phi - h, target, 1.7, k).0)
                / (2.0 * h);
            assert!((fd - d).abs() < 1e-8, "k {k}: {d} vs {fd}");
            // |r| is periodic in 2π/k.
            let shifted = lock_residual(phi + std::f64::consts::TAU / k as f64, target, 1.7, k).0;
            assert!((shifted.abs() - r.abs()).abs() < 1e-12);
        }
    }
    // k = 2: a lock at φ̂ + π is satisfied.
    assert!(lock_residual(0.2 + std::f64::consts::PI, 0.2, 1.0, 2).0.abs() < 1e-12);
}

/// A plane with the field of circles around (0, −1.3): ∇φ = (x − x₀)^⊥/r², so the streamlines'
/// geodesic curvature is exactly 1/r, from 1/0.3 near the bottom to 0.4 at the top corners.
fn circles(mesh: &Mesh, g: &Geometry) -> Vec<f64> {
    mesh.positions
        .iter()
        .zip(&g.frames)
        .map(|(p, f)| {
            let d = Vector3::new(p.x, p.y + 1.3, 0.0);
            f.angle_of(&Vector3::new(-d.y, d.x, 0.0))
        })
        .collect()
}

fn plane_term<'a>(
    g: &'a Geometry,
    h: &'a [Vector3<f64>],
    phi: &[f64],
    symmetry: Symmetry,
) -> HighlightTerm<'a> {
    HighlightTerm::own_targets(g, h, symmetry, GradientForm::Angle, phi)
}

fn monotone(report: &grainline::solve::OptimizeReport) {
    let mut e = report.initial_energy.total();
    for it in &report.iterations {
        assert!(it.energies.total() <= e, "energy rose: {e} -> {}", it.energies.total());
        e = it.energies.total();
    }
}

#[test]
fn turning_radius_holds_after_the_solve() {
    let mesh = generate::plane(1.0, Grid::new(24, 24));
    let g = Geometry::compute(&mesh, &GeometryOptions::default());
    let phi = circles(&mesh, &g);
    let h = vec![Vector3::new(0.3, 0.4, 1.0).normalize(); phi.len()];
    for sym in [Symmetry::Oriented, Symmetry::Line] {
        let term = plane_term(&g, &h, &phi, sym);
        let radius = 1.0;
        let before = (0..phi.len())
            .map(|i| {
                let u = g.frames[i].direction(phi[i]);
                let _ = u;
                GradientHinge {
                    geometry: &g,
                    symmetry: sym,
                    form: GradientForm::Angle,
                    kind: HingeKind::Turning,
                    bound: 1.0 / radius,
                    weight: 1.0,
                }
                .value(&phi, i)
                .abs()
            })
            .fold(0.0, f64::max);
        assert!(before > 2.5, "the start bends tightly: max κ_g {before}");
        let settings = SolverSettings {
            whole_mesh: true,
            max_iterations: 200,
            constraints: grainline::solve::Constraints {
                turning_radius: Some(TurningRadius { radius, weight: 1e4 }),
                ..Default::default()
            },
            ..Default::default()
        };
        let r = optimize(&mesh, &term, &phi, &vec![false; phi.len()], &settings).unwrap();
        let v = &r.report.violations;
        eprintln!(
            "{sym:?}: max R·κ_g {before:.2} -> {:.4}, violating area {:.4}, {} iterations, stop {:?}, energies {:?}",
            v.turning_max_ratio.unwrap(),
            v.turning_area_fraction.unwrap(),
            r.report.iterations.len(),
            r.report.stop,
            r.report.iterations.last().map(|i| i.energies)
        );
        assert!(v.turning_max_ratio.unwrap() <= 1.05, "{v:?}");
        assert!(r.phi.iter().all(|p| p.is_finite()));
        monotone(&r.report);
    }
}

#[test]
fn splay_holds_after_the_solve() {
    // A source field u = (x − x₀)/r: div u = 1/r, large near the source below the plane.
    let mesh = generate::plane(1.0, Grid::new(24, 24));
    let g = Geometry::compute(&mesh, &GeometryOptions::default());
    let phi: Vec<f64> = mesh
        .positions
        .iter()
        .zip(&g.frames)
        .map(|(p, f)| f.angle_of(&Vector3::new(p.x, p.y + 1.3, 0.0)))
        .collect();
    let h = vec![Vector3::new(0.3, 0.4, 1.0).normalize(); phi.len()];
    let term = plane_term(&g, &h, &phi, Symmetry::Oriented);
    let settings = SolverSettings {
        whole_mesh: true,
        max_iterations: 200,
        constraints: grainline::solve::Constraints {
            splay: Some(Splay { max: 1.0, weight: 1e4 }),
            ..Default::default()
        },
        ..Default::default()
    };
    let r = optimize(&mesh, &term, &phi, &vec![false; phi.len()], &settings).unwrap();
    let v = &r.report.violations;
    eprintln!(
        "splay: max ratio {:.4}, violating area {:.4}, {} iterations",
        v.splay_max_ratio.unwrap(),
        v.splay_area_fraction.unwrap(),
        r.report.iterations.len()
    );
    assert!(v.splay_max_ratio.unwrap() <= 1.05, "{v:?}");
    monotone(&r.report);
}
