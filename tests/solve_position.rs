//! The position energy (docs/math.md §9): its Jacobian against central differences, and edits
//! that land where they ask on a flat sheet seen by a near eye — the case where Eq. 7's ℓ
//! vanishes and the paper's energy has no gradient. The truth is analytic: on the plane z = 0
//! the half vector is known in closed form, so the original highlight C₀ (g = hᵀx̂ = 0 for the
//! grain u = x̂) is found by bisection on the exact g, and its image under the warp W (or the
//! drawn line) is where the solved highlight must cross the mesh's rows.

use grainline::edit::{apply_edits, Edit, EditInput, EditOptions};
use grainline::field::{compute_field, FieldOptions, FieldResult};
use grainline::generate;
use grainline::highlight::{InitialField, Lighting, Symmetry, View};
use grainline::mesh::Mesh;
use grainline::solve::{optimize, HighlightEnergy, HighlightTerm, SolverSettings};
use nalgebra::Vector3;

const LIGHT: [f64; 3] = [0.2, -0.4, 1.0];
const EYE: [f64; 3] = [0.0, -200.0, 300.0];

/// A 200 × 200 mm sheet, 2.5 mm grid, grain along x (its UVs), line field or not.
fn sheet(symmetry: Symmetry) -> (Mesh, FieldOptions, FieldResult) {
    let mesh = generate::plane(100.0, generate::Grid::new(80, 80));
    let lighting = Lighting::new(Vector3::from(LIGHT), View::Eye(Vector3::from(EYE))).unwrap();
    let mut options = FieldOptions::new(lighting);
    options.init = InitialField::Uv;
    options.symmetry = symmetry;
    let field = compute_field(&mesh, &options).unwrap();
    (mesh, options, field)
}

/// The exact g = hᵀx̂ on the plane z = 0 at (x, y).
fn exact_g(x: f64, y: f64) -> f64 {
    let p = Vector3::new(x, y, 0.0);
    let wo = (Vector3::from(EYE) - p).normalize();
    (Vector3::from(LIGHT).normalize() + wo).normalize().x
}

/// The root of `f` in [a, b] by bisection (f(a), f(b) of opposite signs).
fn bisect(f: impl Fn(f64) -> f64, mut a: f64, mut b: f64) -> f64 {
    let fa = f(a);
    assert!(fa * f(b) < 0.0, "no sign change in [{a}, {b}]");
    for _ in 0..100 {
        let m = 0.5 * (a + b);
        if (f(m) > 0.0) == (fa > 0.0) {
            a = m;
        } else {
            b = m;
        }
    }
    0.5 * (a + b)
}

/// Where the zero set of g = hᵀu of `phi` crosses the mesh row y = `row`, nearest to `near`
/// (linear interpolation between neighbouring row vertices, line-field signs aligned).
fn crossing(mesh: &Mesh, field: &FieldResult, phi: &[f64], row: f64, near: f64) -> f64 {
    let mut vs: Vec<usize> =
        (0..mesh.num_vertices()).filter(|&i| (mesh.positions[i].y - row).abs() < 1e-9).collect();
    vs.sort_by(|&a, &b| mesh.positions[a].x.total_cmp(&mesh.positions[b].x));
    let u = |i: usize| field.geometry.frames[i].direction(phi[i]);
    let mut best: Option<f64> = None;
    for w in vs.windows(2) {
        let (a, b) = (w[0], w[1]);
        let (ua, mut ub) = (u(a), u(b));
        if ua.dot(&ub) < 0.0 {
            ub = -ub;
        }
        let (ga, gb) = (field.h[a].dot(&ua), field.h[b].dot(&ub));
        if ga * gb <= 0.0 && ga != gb {
            let t = ga / (ga - gb);
            let x = mesh.positions[a].x + t * (mesh.positions[b].x - mesh.positions[a].x);
            if best.is_none_or(|c| (x - near).abs() < (c - near).abs()) {
                best = Some(x);
            }
        }
    }
    best.expect("the row has a highlight crossing")
}

fn solve(
    mesh: &Mesh,
    options: &FieldOptions,
    field: &FieldResult,
    phi: &[f64],
    edits: &[Edit],
    energy: HighlightEnergy,
) -> (Vec<f64>, grainline::solve::OptimizeReport) {
    let g = &field.geometry;
    let input = EditInput {
        mesh,
        geometry: g,
        phi,
        lighting: &options.lighting,
        h: &field.h,
        symmetry: options.symmetry,
        gradient_form: options.gradient_form,
    };
    let er = apply_edits(&input, edits, &EditOptions::default()).unwrap();
    let norms: Vec<f64> = field.highlight.m.iter().map(|m| m.norm()).collect();
    let eps = grainline::highlight::tensor::default_epsilon(&norms).max(1e-9);
    let term = er.highlight_term(g, options.symmetry, options.gradient_form, energy, eps);
    let settings = SolverSettings { highlight_energy: energy, ..SolverSettings::default() };
    let out = optimize(mesh, &term, &er.phi, &er.support, &settings).unwrap();
    (out.phi, out.report)
}

#[test]
fn position_rows_match_central_differences() {
    let (_, _, field) = sheet(Symmetry::Line);
    let n = field.phi.len();
    let targets: Vec<Option<f64>> =
        (0..n).map(|i| Some(((i * 7919) % 1000) as f64 / 500.0 - 1.0)).collect();
    let term = HighlightTerm {
        geometry: &field.geometry,
        h: &field.h,
        symmetry: Symmetry::Line,
        form: Default::default(),
        epsilon: 0.0,
        target_q: vec![None; n],
        weight: vec![1.3; n],
        target_g: targets,
        h_gradient: None,
    };
    let mut phi: Vec<f64> = (0..n).map(|i| field.phi[i] + 0.37 * (i as f64).sin()).collect();
    let step = 1e-6;
    let mut worst: f64 = 0.0;
    for i in (0..n).step_by(97) {
        let (_, d) = term.position_row(&phi, i);
        let p0 = phi[i];
        phi[i] = p0 + step;
        let rp = term.position_row(&phi, i).0;
        phi[i] = p0 - step;
        let rm = term.position_row(&phi, i).0;
        phi[i] = p0;
        let fd = (rp - rm) / (2.0 * step);
        worst = worst.max((d - fd).abs() / fd.abs().max(1e-3));
    }
    assert!(worst < 1e-7, "relative error {worst:e}");
}

#[test]
fn a_bend_on_a_flat_sheet_seen_by_a_near_eye_lands_on_the_warped_highlight() {
    let (mesh, options, field) = sheet(Symmetry::Line);
    // C₀ on the row y = 0 from the exact g, checked against the mesh's own extraction.
    let x0 = bisect(|x| exact_g(x, 0.0), 0.0, 100.0);
    let measured = crossing(&mesh, &field, &field.phi, 0.0, x0);
    assert!((measured - x0).abs() < 0.05, "C₀ at {measured}, exact {x0}");
    let (r, s) = (30.0, 0.8);
    let bend: Edit = serde_json::from_value(serde_json::json!({
        "tool": "bend", "centre": {"point": [x0, 0.0, 0.0]}, "radius": r, "strength": s,
        "direction": [1.0, 0.0, 0.0], "metric": "euclidean"
    }))
    .unwrap();
    let (phi, report) = solve(
        &mesh,
        &options,
        &field,
        &field.phi,
        std::slice::from_ref(&bend),
        HighlightEnergy::Position,
    );
    assert_ne!(report.stop, grainline::solve::StopReason::IterationCap);
    assert!(report.iterations.len() <= 15, "{} iterations", report.iterations.len());
    for w in report.iterations.windows(2) {
        assert!(w[1].energies.total() <= w[0].energies.total());
    }
    // On the brush's own rows the warp moves C₀ along x by s·d(x_b, y_b)·r, d = w/2.
    for row in [-15.0, -7.5, 0.0, 7.5, 15.0] {
        let c0 = bisect(|x| exact_g(x, row), 0.0, 100.0);
        // Planar coordinates: +y_b = world +x, x_b = world −y (x_b = y_b × n with n = +z... the
        // fall-off is symmetric in x_b, so its sign does not matter).
        let yb0 = (c0 - x0) / r;
        let xb = row / r;
        let target = x0
            + r * {
                // W(x_b, y_b0) = y_b0 + s (1 − x_b² − y_b0²)²/2 on the chord x_b.
                let q = 1.0 - xb * xb - yb0 * yb0;
                yb0 + s * 0.5 * q * q
            };
        let got = crossing(&mesh, &field, &phi, row, target);
        assert!(
            (got - target).abs() < 0.05 * r,
            "row {row}: highlight at x = {got:.3}, W(C₀) at {target:.3} (C₀ at {c0:.3})"
        );
    }
    // Eq. 7 alone vanishes for a constant grain on a plane; with the near eye's term (∇h)ᵀu
    // (docs/math.md §2.1) the tensor energy has a gradient too, and its solve moves the
    // highlight towards W(C₀) (by more than a tenth of the radius).
    let (phi_t, _) = solve(&mesh, &options, &field, &field.phi, &[bend], HighlightEnergy::Tensor);
    let got = crossing(&mesh, &field, &phi_t, 0.0, x0);
    assert!((got - x0).abs() > 0.1 * r, "tensor: {got} vs C₀ {x0}");
}

#[test]
fn a_drawn_line_gets_the_highlight_on_it_whatever_the_line_field_signs() {
    let (mesh, options, field) = sheet(Symmetry::Line);
    let x_line = 40.0;
    let r = 15.0;
    let curve: Edit = serde_json::from_value(serde_json::json!({
        "tool": "curve", "points": [[[x_line, -45.0, 0.0], [x_line, 45.0, 0.0]]], "radius": r
    }))
    .unwrap();
    // The same start with the grain's sign flipped at a third of the vertices: a line field
    // does not see the sign, and neither may the result.
    let flipped: Vec<f64> = field
        .phi
        .iter()
        .enumerate()
        .map(|(i, &p)| if (i * 2654435761) % 3 == 0 { p + std::f64::consts::PI } else { p })
        .collect();
    for start in [&field.phi, &flipped] {
        let (phi, report) = solve(
            &mesh,
            &options,
            &field,
            start,
            std::slice::from_ref(&curve),
            HighlightEnergy::Position,
        );
        assert_ne!(report.stop, grainline::solve::StopReason::IterationCap);
        for row in [-30.0, -15.0, 0.0, 15.0, 30.0] {
            let got = crossing(&mesh, &field, &phi, row, x_line);
            assert!((got - x_line).abs() < 0.05 * r, "row {row}: highlight at {got}");
        }
        // No singularity inside the tube: the target forces none.
        let inside = report
            .singularities
            .iter()
            .filter(|s| (s.position[0] - x_line).abs() < r && s.position[1].abs() < 45.0)
            .count();
        assert_eq!(inside, 0, "{:?}", report.singularities);
    }
}
