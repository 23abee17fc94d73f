//! The analytic Jacobian of the highlight residual against central differences (math.md §3).

use grainline::generate::{self, Grid, GridPattern};
use grainline::geometry::{Geometry, GeometryOptions, GradientForm};
use grainline::highlight::tensor::q;
use grainline::highlight::Symmetry;
use grainline::solve::HighlightTerm;
use nalgebra::{Vector2, Vector3};

fn check(form: GradientForm, symmetry: Symmetry) {
    let mesh = generate::quadric_patch(
        [0.9, 0.3, -0.6],
        1.0,
        Grid { pattern: GridPattern::Jittered { amount: 0.2, seed: 4 }, ..Grid::new(9, 9) },
    );
    let g = Geometry::compute(&mesh, &GeometryOptions::default());
    let n = mesh.num_vertices();
    let h = vec![Vector3::new(0.2, 0.5, 1.0).normalize(); n];
    let phi: Vec<f64> = mesh
        .positions
        .iter()
        .map(|p| 0.4 * p.x - 0.3 * p.y + 0.2 * (2.0 * p.x * p.y).sin())
        .collect();
    let target_q =
        (0..n).map(|i| Some(q(&Vector2::new((i as f64).cos(), (i as f64).sin()), 0.0))).collect();
    let term = HighlightTerm {
        geometry: &g,
        h: &h,
        symmetry,
        form,
        epsilon: 0.05,
        target_q,
        weight: vec![1.0; n],
        target_g: vec![None; n],
    };
    let mut worst: f64 = 0.0;
    for i in 0..n {
        let jac = term.jacobian(&phi, i);
        assert_eq!(jac.residual, term.residual(&phi, i));
        let row_max = jac.entries.iter().flat_map(|e| e.1).fold(0.0f64, |a, b| a.max(b.abs()));
        for &(j, d) in &jac.entries {
            let step = 1e-6;
            let (mut p1, mut p2) = (phi.clone(), phi.clone());
            p1[j as usize] += step;
            p2[j as usize] -= step;
            let (r1, r2) = (term.residual(&p1, i), term.residual(&p2, i));
            for c in 0..2 {
                let fd = (r1[c] - r2[c]) / (2.0 * step);
                // Relative to the row's largest entry: central differences carry an absolute
                // error of about 1e-11 here, which tiny entries cannot resolve relatively.
                let err = (fd - d[c]).abs() / row_max.max(1e-12);
                worst = worst.max(err);
                assert!(
                    err < 1e-6,
                    "{form:?} {symmetry:?} row {i} col {j} comp {c}: analytic {} vs fd {fd}",
                    d[c]
                );
            }
        }
        // No other column influences row i.
        let cols: Vec<u32> = jac.entries.iter().map(|e| e.0).collect();
        let outside = (0..n as u32).find(|c| !cols.contains(c) && (*c as usize) % 7 == i % 7);
        if let Some(c) = outside {
            let mut p1 = phi.clone();
            p1[c as usize] += 1e-3;
            assert_eq!(
                term.residual(&p1, i),
                term.residual(&phi, i),
                "row {i} depends on column {c}"
            );
        }
    }
    eprintln!("{form:?} {symmetry:?}: worst relative Jacobian error {worst:.2e}");
}

#[test]
fn jacobian_matches_central_differences() {
    for form in [GradientForm::Sine, GradientForm::Angle] {
        for sym in [Symmetry::Oriented, Symmetry::Line] {
            check(form, sym);
        }
    }
}

#[test]
fn residual_energy_is_the_tensor_distance() {
    // Σ|rᵢ|² = Σ Aᵢ‖L(ℓᵢ) − L*ᵢ‖²_F at ε = 0.
    let mesh = generate::torus(2.0, 0.7, 24, 12);
    let g = Geometry::compute(&mesh, &GeometryOptions::default());
    let n = mesh.num_vertices();
    let h = vec![Vector3::new(0.1, 0.3, 1.0).normalize(); n];
    let phi: Vec<f64> = mesh.positions.iter().map(|p| p.x.atan2(p.y)).collect();
    let targets: Vec<Vector2<f64>> =
        (0..n).map(|i| Vector2::new(1.0, 0.1 * i as f64).normalize()).collect();
    let term = HighlightTerm {
        geometry: &g,
        h: &h,
        symmetry: Symmetry::Line,
        form: GradientForm::Angle,
        epsilon: 0.0,
        target_q: targets.iter().map(|t| Some(q(t, 0.0))).collect(),
        weight: vec![1.0; n],
        target_g: vec![None; n],
    };
    let (mut e_res, mut e_tensor) = (0.0, 0.0);
    for (i, t) in targets.iter().enumerate() {
        let r = term.residual(&phi, i);
        e_res += r[0] * r[0] + r[1] * r[1];
        let l = term.ell_bar(&phi, i);
        let big_l = l * l.transpose() / l.norm_squared();
        e_tensor += g.areas[i] * (big_l - t * t.transpose()).norm_squared();
    }
    assert!((e_res - e_tensor).abs() < 1e-10 * e_tensor, "{e_res} vs {e_tensor}");
}
