//! Recovery on spot (../shared/meshes/spot_triangulated.obj): a smooth field's own highlights as
//! targets, the field perturbed in a brush, the brush solved with the default settings and at
//! most 10 iterations (the bound: back to the true field within 1e-3 rad in ≤ 10
//! iterations).
//!
//! Experiments (docs/benchmarks.md) through environment variables: SPOT_SMOOTHNESS (relative
//! λ_s), SPOT_CENTRES (comma-separated vertices), SPOT_RADIUS (× bounding-box diagonal),
//! SPOT_CONT (continuation on), SPOT_HTV_TAU (row weights (hᵀv)²/((hᵀv)² + τ²) from the start
//! field), SPOT_DAMPING (initial LM damping), SPOT_MAXIT (iteration cap, default 10).

mod common;

use grainline::geometry::connection::wrap_angle;
use grainline::geometry::{Geometry, GeometryOptions, GradientForm};
use grainline::highlight::smoothest::{smoothest_field, SmoothestOptions};
use grainline::highlight::Symmetry;
use grainline::mesh::load::{load_obj, LoadOptions};
use grainline::mesh::Mesh;
use grainline::solve::{optimize, HighlightTerm, SolverSettings};
use nalgebra::Vector3;

fn env_f64(name: &str, default: f64) -> f64 {
    std::env::var(name).ok().and_then(|v| v.parse().ok()).unwrap_or(default)
}

struct Case {
    mesh: Mesh,
    g: Geometry,
    h: Vec<Vector3<f64>>,
}

fn load() -> Option<Case> {
    let path = common::shared_mesh("spot_triangulated.obj")?;
    let mesh = load_obj(&path, &LoadOptions::default()).unwrap().mesh;
    let g = Geometry::compute(&mesh, &GeometryOptions::default());
    let h = vec![Vector3::new(0.3, 0.4, 1.0).normalize(); mesh.num_vertices()];
    Some(Case { mesh, g, h })
}

fn term<'a>(c: &'a Case, phi: &[f64], sym: Symmetry) -> HighlightTerm<'a> {
    HighlightTerm::own_targets(&c.g, &c.h, sym, GradientForm::Angle, phi)
}

/// |hᵀv| at vertex i for the field φ.
fn htv(c: &Case, phi: &[f64], i: usize) -> f64 {
    let f = &c.g.frames[i];
    let u = f.direction(phi[i]);
    c.h[i].dot(&f.n.cross(&u)).abs()
}

#[test]
fn brushes_recover_the_true_field() {
    let Some(c) = load() else { return };
    let n = c.mesh.num_vertices();
    let (lo, hi) = c.mesh.positions.iter().fold(
        (Vector3::repeat(f64::INFINITY), Vector3::repeat(f64::NEG_INFINITY)),
        |(lo, hi), p| (lo.inf(p), hi.sup(p)),
    );
    let radius = env_f64("SPOT_RADIUS", 0.1) * (hi - lo).norm();
    let smoothness = env_f64("SPOT_SMOOTHNESS", SolverSettings::default().smoothness);
    let centres: Vec<usize> = std::env::var("SPOT_CENTRES")
        .ok()
        .map(|s| s.split(',').map(|x| x.parse().unwrap()).collect())
        .unwrap_or(vec![250, 500, 750, 1000, 1250, 1500, 1750, 2000, 2250, 2500, 2750]);
    let mut failures = Vec::new();
    let (mut total, mut recovered) = (0, 0);
    // Brushes where the data term's ODE is far from degenerate (min |hᵀv| ≥ 0.1 over the brush,
    // math.md §3) and that did not recover: must stay empty.
    let mut well_posed_failures = Vec::new();
    for sym in [Symmetry::Oriented, Symmetry::Line] {
        let phi_true =
            smoothest_field(&c.mesh, &c.g, sym, &SmoothestOptions::default()).unwrap().phi;
        let t = term(&c, &phi_true, sym);
        let k = sym.k() as f64;
        for &centre in &centres {
            let p0 = c.mesh.positions[centre];
            let support: Vec<bool> =
                c.mesh.positions.iter().map(|p| (p - p0).norm() < radius).collect();
            let mut phi = phi_true.clone();
            for i in 0..n {
                if support[i] {
                    let d = (c.mesh.positions[i] - p0).norm() / radius;
                    phi[i] += 0.3 * (1.0 - d * d).powi(2);
                }
            }
            let mut t = t.clone();
            if let Ok(tau) = std::env::var("SPOT_HTV_TAU") {
                let tau: f64 = tau.parse().unwrap();
                for i in 0..n {
                    let x = htv(&c, &phi, i);
                    t.weight[i] = x * x / (x * x + tau * tau);
                }
            }
            let s = SolverSettings {
                smoothness,
                margin_rings: 0,
                continuation: std::env::var("SPOT_CONT").is_ok(),
                initial_damping: env_f64("SPOT_DAMPING", SolverSettings::default().initial_damping),
                max_iterations: env_f64("SPOT_MAXIT", 10.0) as usize,
                ..Default::default()
            };
            let r = optimize(&c.mesh, &t, &phi, &support, &s).unwrap();
            let (mut worst, mut at) = (0.0f64, 0);
            for i in (0..n).filter(|&i| support[i]) {
                let e = (wrap_angle(k * (r.phi[i] - phi_true[i])) / k).abs();
                if e > worst {
                    (worst, at) = (e, i);
                }
            }
            let min_htv =
                (0..n).filter(|&i| support[i]).map(|i| htv(&c, &phi_true, i)).fold(1.0, f64::min);
            let its = r.report.iterations.len();
            eprintln!(
                "{sym:?} centre {centre}: {} free, start {:?}, {its} it, stop {:?}, worst {worst:.2e} at {at} (|hᵀv| there {:.3}, min in brush {min_htv:.3}), E {:.2e} -> {:.2e}",
                r.report.unknowns,
                r.report.start,
                r.report.stop,
                htv(&c, &phi_true, at),
                r.report.initial_energy.total(),
                r.report.iterations.last().map_or(f64::NAN, |i| i.energies.total()),
            );
            assert!(r.phi.iter().all(|p| p.is_finite()));
            let mut e = r.report.initial_energy.total();
            for it in &r.report.iterations {
                assert!(it.stage > 0 || it.energies.total() <= e, "energy rose");
                e = it.energies.total();
            }
            total += 1;
            if worst < 1e-3 {
                recovered += 1;
            } else {
                failures.push((sym, centre, worst, its));
                if min_htv >= 0.1 {
                    well_posed_failures.push((sym, centre, worst));
                }
            }
        }
    }
    eprintln!("recovered {recovered} of {total} within the iteration cap; not: {failures:?}");
    // Not every brush recovers: where the data ODE degenerates (hᵀv ≈ 0 inside the brush,
    // math.md §3) the data term has other minima (docs/benchmarks.md lists them). Every brush
    // away from that degeneracy must recover, and the overall rate of the default settings
    // (16 of 22 within 10 iterations since the harmonic-fill start; 11 of 22 within 20 before)
    // is guarded against regressions.
    let experiment = [
        "SPOT_SMOOTHNESS",
        "SPOT_CENTRES",
        "SPOT_CONT",
        "SPOT_HTV_TAU",
        "SPOT_RADIUS",
        "SPOT_DAMPING",
        "SPOT_MAXIT",
    ]
    .iter()
    .any(|v| std::env::var(v).is_ok());
    if !experiment {
        assert!(
            well_posed_failures.is_empty(),
            "well-posed brushes failed: {well_posed_failures:?}"
        );
        assert!(recovered >= 16, "{recovered} of {total} brushes recovered");
    }
}

/// Unoriented angle (degrees) between two highlight tangents in frame coordinates.
fn line_angle_deg(a: &nalgebra::Vector2<f64>, b: &nalgebra::Vector2<f64>) -> f64 {
    let d = a.y.atan2(a.x) - b.y.atan2(b.x);
    (wrap_angle(2.0 * d) / 2.0).abs().to_degrees()
}

#[test]
fn every_vertex_free_still_fits_the_tangents() {
    let Some(c) = load() else { return };
    let n = c.mesh.num_vertices();
    for sym in [Symmetry::Oriented, Symmetry::Line] {
        let phi_true =
            smoothest_field(&c.mesh, &c.g, sym, &SmoothestOptions::default()).unwrap().phi;
        let t = term(&c, &phi_true, sym);
        let p0 = c.mesh.positions[1000];
        let phi: Vec<f64> = (0..n)
            .map(|i| phi_true[i] + 0.3 * (-(c.mesh.positions[i] - p0).norm_squared() / 0.05).exp())
            .collect();
        let s = SolverSettings { whole_mesh: true, ..Default::default() };
        let r = optimize(&c.mesh, &t, &phi, &vec![false; n], &s).unwrap();
        let mut errs: Vec<f64> = (0..n)
            .filter_map(|i| {
                let want = t.ell_bar(&phi_true, i);
                (want.norm() > 10.0 * t.epsilon)
                    .then(|| line_angle_deg(&t.ell_bar(&r.phi, i), &want))
            })
            .collect();
        errs.sort_by(f64::total_cmp);
        let (median, p90) = (errs[errs.len() / 2], errs[errs.len() * 9 / 10]);
        eprintln!(
            "{sym:?} whole mesh: {} iterations, stop {:?}, tangent error median {median:.4}°, p90 {p90:.3}°, max {:.2}° over {} vertices",
            r.report.iterations.len(),
            r.report.stop,
            errs[errs.len() - 1],
            errs.len()
        );
        assert!(median <= 0.1, "median {median}°");
    }
}
