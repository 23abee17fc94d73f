//! Curvature, normals and areas against analytic surfaces.

use grainline::generate::{self, Grid, GridPattern};
use grainline::geometry::{Geometry, GeometryOptions};
use nalgebra::Vector3;

fn geom(mesh: &grainline::mesh::Mesh) -> Geometry {
    Geometry::compute(mesh, &GeometryOptions::default())
}

/// Max and RMS relative error of k1 over the vertices selected by `keep`.
fn errors(
    g: &Geometry,
    truth: impl Fn(usize) -> (f64, f64),
    keep: impl Fn(usize) -> bool,
) -> (f64, f64, f64) {
    let (mut max1, mut max2, mut sum, mut n) = (0.0f64, 0.0f64, 0.0, 0.0);
    for i in (0..g.num_vertices()).filter(|&i| keep(i)) {
        let (k1, k2) = truth(i);
        let scale = k1.abs().max(k2.abs());
        let e1 = (g.principal[i].k1 - k1).abs() / scale;
        let e2 = (g.principal[i].k2 - k2).abs() / scale;
        max1 = max1.max(e1);
        max2 = max2.max(e2);
        sum += e1 * e1;
        n += 1.0;
    }
    (max1, max2, (sum / n).sqrt())
}

#[test]
fn torus_128x32_k1_error_is_well_under_libigl() {
    // libigl's principal_curvature (radius 2) has a 3.5 % k1 error here (issue 2); aim ≤ 1.75 %.
    let (big_r, r) = (2.0, 0.5);
    let mesh = generate::torus(big_r, r, 128, 32);
    let g = geom(&mesh);
    let (max1, max2, rms) =
        errors(&g, |i| generate::torus_curvatures(big_r, r, &mesh.positions[i]), |_| true);
    eprintln!("torus 128x32: k1 max rel err {max1:.4}, k2 max {max2:.4}, k1 rms {rms:.5}");
    assert!(max1 < 0.0175, "k1 max relative error {max1}");
}

#[test]
fn sphere_curvature_positive_and_converging() {
    let mut last = f64::INFINITY;
    for sub in [2, 3, 4, 5] {
        let r = 1.7;
        let mesh = generate::icosphere(r, sub);
        let g = geom(&mesh);
        let (m1, m2, _) = errors(&g, |_| (1.0 / r, 1.0 / r), |_| true);
        let err = m1.max(m2);
        eprintln!("icosphere {sub}: max rel err {err:.3e}");
        for i in 0..g.num_vertices() {
            assert!(g.normal(i).dot(&mesh.positions[i]) > 0.0, "outward normal");
            assert!(g.principal[i].k2 > 0.0, "sphere with outward normals: k > 0");
        }
        assert!(err < last, "error must fall with refinement");
        last = err;
    }
    assert!(last < 2e-3);
}

#[test]
fn cylinder_curvature_interior() {
    let (r, h) = (0.8, 2.0);
    let mut last = f64::INFINITY;
    for n in [24, 48, 96] {
        let mesh = generate::cylinder(r, h, n, n / 2);
        let g = geom(&mesh);
        let interior = |i: usize| !g.adjacency.is_boundary_vertex(i);
        let (m1, m2, _) = errors(&g, |_| (1.0 / r, 0.0), interior);
        let (b1, b2, _) = errors(&g, |_| (1.0 / r, 0.0), |i| !interior(i));
        eprintln!("cylinder {n}: interior {m1:.2e} {m2:.2e}, boundary {b1:.2e} {b2:.2e}");
        assert!(m1.max(m2) < last);
        last = m1.max(m2);
        assert!(b1.max(b2) < 0.1, "boundary vertices use the 2-ring and stay close");
    }
}

/// Analytic Weingarten map of z = ½xᵀCx at (x, y), in a frame of the tangent plane: returns
/// the principal curvatures (k1 ≥ k2, eigenvalues of −W for the upward normal).
fn quadric_principal(c: [f64; 3], x: f64, y: f64) -> (f64, f64) {
    let (zx, zy) = (c[0] * x + c[1] * y, c[1] * x + c[2] * y);
    let (zxx, zxy, zyy) = (c[0], c[1], c[2]);
    let w = (1.0 + zx * zx + zy * zy).sqrt();
    // First and second fundamental forms (second w.r.t. the upward normal).
    let (e, f, gg) = (1.0 + zx * zx, zx * zy, 1.0 + zy * zy);
    let (l, m, n) = (zxx / w, zxy / w, zyy / w);
    let k_mean = (e * n - 2.0 * f * m + gg * l) / (2.0 * (e * gg - f * f));
    let k_gauss = (l * n - m * m) / (e * gg - f * f);
    let d = (k_mean * k_mean - k_gauss).max(0.0).sqrt();
    // W = II (sign of math.md), principal curvatures of −W:
    (-k_mean + d, -k_mean - d)
}

#[test]
fn quadric_patches_converge_on_every_pattern() {
    let c = [0.8, 0.3, -0.5];
    for pattern in [
        GridPattern::Regular,
        GridPattern::CrissCross,
        GridPattern::Jittered { amount: 0.25, seed: 7 },
    ] {
        let mut errs = Vec::new();
        for n in [16, 32, 64] {
            let mesh = generate::quadric_patch(c, 1.0, Grid { pattern, ..Grid::new(n, n) });
            let g = geom(&mesh);
            let (m1, m2, rms) = errors(
                &g,
                |i| quadric_principal(c, mesh.positions[i].x, mesh.positions[i].y),
                |i| !g.adjacency.is_boundary_vertex(i),
            );
            errs.push(rms);
            eprintln!("{pattern:?} n={n}: max {m1:.2e} {m2:.2e} rms {rms:.2e}");
        }
        let order = (errs[1] / errs[2]).log2();
        eprintln!("{pattern:?}: observed order {order:.2}");
        assert!(errs[2] < errs[1] && errs[1] < errs[0], "{pattern:?}: {errs:?}");
        assert!(order > 0.8, "{pattern:?}: order {order}");
    }
}

#[test]
fn weingarten_is_symmetric_and_areas_sum_to_the_surface_area() {
    for mesh in [
        generate::torus(2.0, 0.5, 64, 16),
        generate::icosphere(1.0, 3),
        generate::cylinder(1.0, 1.0, 32, 8),
    ] {
        let g = geom(&mesh);
        for w in &g.weingarten {
            assert_eq!(w[(0, 1)], w[(1, 0)]);
        }
        let total: f64 = g.areas.iter().sum();
        assert!((total - mesh.area()).abs() < 1e-12 * mesh.area());
    }
    // And the mesh area converges to the analytic one.
    let (big_r, r) = (2.0, 0.5);
    let exact = 4.0 * std::f64::consts::PI.powi(2) * big_r * r;
    let a1 = (generate::torus(big_r, r, 64, 16).area() - exact).abs();
    let a2 = (generate::torus(big_r, r, 128, 32).area() - exact).abs();
    assert!(a2 < a1 / 3.5, "second-order convergence of the area: {a1} {a2}");
}

#[test]
fn normals_point_outward_on_the_torus() {
    let (big_r, r) = (2.0, 0.5);
    let mesh = generate::torus(big_r, r, 64, 16);
    let g = geom(&mesh);
    for (i, p) in mesh.positions.iter().enumerate() {
        let ring_centre = Vector3::new(p.x, p.y, 0.0).normalize() * big_r;
        let exact = (p - ring_centre).normalize();
        assert!(g.normal(i).dot(&exact) > 0.9999, "vertex {i}");
    }
}

/// A scan's noise: a sphere of radius 50 (a subdivision-5 icosphere, edges of about 2) whose
/// vertices are moved along the radius by up to ±0.2, pseudo-randomly. The 1-ring fit follows
/// the noise (p95 normals off by 4.9°, curvature by 960 %); `fit_radius` of a few edges
/// averages it out. Truth from outside: the radial normal and k = 1/50.
#[test]
fn a_fit_over_a_ball_averages_a_scans_noise_out() {
    let r = 50.0;
    let mut mesh = generate::icosphere(r, 5);
    let mut s = 12345u64;
    for p in mesh.positions.iter_mut() {
        s = s.wrapping_mul(6364136223846793005).wrapping_add(1442695040888963407);
        let u = (s >> 11) as f64 / (1u64 << 53) as f64 * 2.0 - 1.0;
        *p *= 1.0 + 0.2 * u / r;
    }
    let truth = |g: &Geometry| -> (f64, f64) {
        let (mut normal, mut curvature) = (Vec::new(), Vec::new());
        for i in 0..g.num_vertices() {
            let want = mesh.positions[i].normalize();
            normal.push(g.normal(i).dot(&want).clamp(-1.0, 1.0).acos().to_degrees());
            let p = &g.principal[i];
            curvature.push((p.k1 - 1.0 / r).abs().max((p.k2 - 1.0 / r).abs()) * r);
        }
        let p95 = |v: &mut Vec<f64>| {
            v.sort_by(f64::total_cmp);
            v[v.len() * 95 / 100]
        };
        (p95(&mut normal), p95(&mut curvature))
    };
    let ring = truth(&geom(&mesh));
    // Least squares over more points: the errors fall as the ball grows (curvature about as
    // 1/ρ²), and at ρ = 10 (five edges) the normals are within half a degree.
    let mut last = ring;
    for rho in [6.0, 10.0, 15.0] {
        let b = truth(&Geometry::compute(
            &mesh,
            &GeometryOptions { fit_radius: Some(rho), ..Default::default() },
        ));
        eprintln!(
            "noisy sphere, p95: 1-ring normal {:.2}°, curvature {:.0} %; ball of {rho}: normal {:.2}°, curvature {:.0} %",
            ring.0,
            100.0 * ring.1,
            b.0,
            100.0 * b.1
        );
        assert!(b.0 < last.0 && b.1 < last.1, "ball of {rho}: {b:?} after {last:?}");
        if rho == 10.0 {
            assert!(b.0 < 0.5 && b.1 < 0.05 * ring.1, "ball of 10: {b:?} vs the ring's {ring:?}");
        }
        last = b;
    }
    assert!(ring.0 > 2.0 && ring.1 > 2.0, "the noise should show in the 1-ring fit: {ring:?}");
}

/// On a clean sphere the ball fit is as accurate as the ring's: a quadric over a ball of radius
/// ρ is off by O(ρ²/R²).
#[test]
fn a_fit_over_a_ball_keeps_a_clean_sphere() {
    let r = 50.0;
    let mesh = generate::icosphere(r, 5);
    let g =
        Geometry::compute(&mesh, &GeometryOptions { fit_radius: Some(6.0), ..Default::default() });
    let (m1, m2, _) = errors(&g, |_| (1.0 / r, 1.0 / r), |_| true);
    eprintln!("clean sphere, ball of 6: max relative curvature error {:.2e}", m1.max(m2));
    assert!(m1.max(m2) < 0.02);
}

/// A mesher's micro-feature: a vertex whose six faces are a tiny corner (here a crinkled fan
/// 0.03 across, tilted 27°) inside a flat surface of unit edges. Its 1-ring fit is the fan's
/// tilt; its 2-ring is the surface's, and the fit takes it (MIN_RING_SHARE).
#[test]
fn a_micro_feature_s_vertex_takes_the_surface_s_normal() {
    // Ring `k` of `n` at radius r on the plane z = tilt · x, crinkled by ±crinkle · r.
    let ring = |r: f64, k: usize, n: usize, tilt: f64, crinkle: f64| {
        let a = std::f64::consts::TAU * k as f64 / n as f64;
        let sign = if k.is_multiple_of(2) { 1.0 } else { -1.0 };
        Vector3::new(r * a.cos(), r * a.sin(), tilt * r * a.cos() + sign * crinkle * r)
    };
    let mut pos = vec![Vector3::zeros()];
    pos.extend((0..6).map(|k| ring(0.03, k, 6, 0.5, 0.2)));
    pos.extend((0..6).map(|k| ring(1.0, k, 6, 0.0, 0.0)));
    pos.extend((0..12).map(|k| ring(2.0, k, 12, 0.0, 0.0)));
    let (tiny, r1, r2) = (1u32, 7u32, 13u32);
    let mut faces = Vec::new();
    for k in 0..6u32 {
        let j = (k + 1) % 6;
        faces.push([0, tiny + k, tiny + j]);
        faces.push([tiny + k, r1 + k, r1 + j]);
        faces.push([tiny + k, r1 + j, tiny + j]);
        faces.push([r1 + k, r2 + 2 * k, r2 + 2 * k + 1]);
        faces.push([r1 + k, r2 + 2 * k + 1, r1 + j]);
        faces.push([r1 + j, r2 + 2 * k + 1, r2 + (2 * k + 2) % 12]);
    }
    let mesh = grainline::mesh::Mesh::from_triangles(pos, faces);
    let g = geom(&mesh);
    let tilt = g.normal(0).angle(&Vector3::z()).to_degrees();
    assert!(tilt < 3.0, "the micro-feature's normal is {tilt:.1}° off the surface's");
}
