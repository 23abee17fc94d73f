//! `solve_cached` (the direct path's pattern, ordering and symbolic analysis kept between
//! solves) gives the same bits as independent `solve` calls, whether the cached analysis fits
//! the next solve (same free set) or not (another free set), and still recovers a known field.

use grainline::generate::{self, Grid};
use grainline::geometry::connection::wrap_angle;
use grainline::geometry::{Geometry, GeometryOptions, GradientForm};
use grainline::highlight::Symmetry;
use grainline::solve::{solve, solve_cached, HighlightTerm, LmOptions, SolveCache};
use nalgebra::Vector3;

#[test]
fn cached_solves_equal_fresh_ones() {
    let mesh = generate::quadric_patch([0.9, 0.2, -0.5], 1.0, Grid::new(30, 30));
    let g = Geometry::compute(&mesh, &GeometryOptions::default());
    let n = mesh.num_vertices();
    let h = vec![Vector3::new(0.3, 0.4, 1.0).normalize(); n];
    let phi_true: Vec<f64> = (0..n)
        .map(|i| {
            let p = mesh.positions[i];
            g.frames[i].angle_of(&Vector3::new(
                (0.8 * p.y).cos(),
                (0.8 * p.y).sin() + 0.3 * p.x,
                0.1,
            ))
        })
        .collect();
    let term = HighlightTerm::own_targets(&g, &h, Symmetry::Line, GradientForm::Angle, &phi_true);
    let brush = |centre: Vector3<f64>, radius: f64| -> (Vec<u32>, Vec<f64>) {
        let free: Vec<u32> = (0..n as u32)
            .filter(|&i| (mesh.positions[i as usize] - centre).norm() < radius)
            .collect();
        let mut phi = phi_true.clone();
        for &i in &free {
            let d = (mesh.positions[i as usize] - centre).norm() / radius;
            phi[i as usize] += 0.3 * (1.0 - d * d).powi(2);
        }
        (free, phi)
    };
    let (free_a, phi_a) = brush(Vector3::new(0.1, -0.1, 0.0), 0.45);
    let (free_b, phi_b) = brush(Vector3::new(-0.2, 0.2, 0.0), 0.3);
    assert!(free_a.len() > 100 && free_b.len() > 40 && free_a != free_b);
    let opts = LmOptions { smoothness: 1e-4, ..Default::default() };
    let heavier = LmOptions { smoothness: 1e-2, ..opts.clone() };
    let fresh_a = solve(&mesh, &term, &phi_a, &free_a, &opts).unwrap();
    let fresh_b = solve(&mesh, &term, &phi_b, &free_b, &opts).unwrap();
    let fresh_a2 = solve(&mesh, &term, &phi_a, &free_a, &heavier).unwrap();
    let mut cache = SolveCache::default();
    // Built, rebuilt for another free set, rebuilt, then reused with another weight.
    let sequence = [
        (&phi_a, &free_a, &opts, &fresh_a),
        (&phi_b, &free_b, &opts, &fresh_b),
        (&phi_a, &free_a, &opts, &fresh_a),
        (&phi_a, &free_a, &heavier, &fresh_a2),
        (&phi_a, &free_a, &opts, &fresh_a),
    ];
    for (step, (phi, free, o, fresh)) in sequence.iter().enumerate() {
        let r = solve_cached(&mesh, &term, phi, free, o, &mut cache).unwrap();
        let same = r.phi.iter().zip(&fresh.phi).all(|(a, b)| a.to_bits() == b.to_bits());
        assert!(same, "step {step}: the cached solve differs from a fresh one");
        assert_eq!(r.iterations.len(), fresh.iterations.len(), "step {step}");
    }
    // And the result is the true field (the brush is recovered to 1e-3 rad).
    let worst = free_a
        .iter()
        .map(|&i| (wrap_angle(2.0 * (fresh_a.phi[i as usize] - phi_true[i as usize])) / 2.0).abs())
        .fold(0.0, f64::max);
    assert!(worst < 1e-3, "worst error {worst}");
}
