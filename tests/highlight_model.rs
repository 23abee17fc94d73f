//! The highlight model (Eq. 7), ∇φ (Eq. 10) and the connection against analytic truth.

use grainline::generate::{self, Grid, GridPattern};
use grainline::geometry::normals::corner_angle;
use grainline::geometry::{connection, Geometry, GeometryOptions, GradientForm};
use grainline::highlight::{self, initial_field, InitialField, Symmetry};
use grainline::mesh::Mesh;
use nalgebra::{Vector2, Vector3};

fn geom(mesh: &Mesh) -> Geometry {
    Geometry::compute(mesh, &GeometryOptions::default())
}

/// Eq. 7 for per-vertex world directions `dirs` (k = 1) under one half vector `h`.
fn field_of(
    mesh: &Mesh,
    g: &Geometry,
    dirs: &[Vector3<f64>],
    h: Vector3<f64>,
) -> highlight::HighlightField {
    let init = InitialField::Directions(dirs.to_vec());
    let phi = initial_field(mesh, g, &init, Symmetry::Oriented).unwrap().phi;
    let hs = vec![h; mesh.num_vertices()];
    highlight::highlight_field(g, &phi, Symmetry::Oriented, GradientForm::Angle, &hs)
}

/// Quadric height z = ½(c20 x² + 2 c11 xy + c02 y²) and its first derivatives.
fn quadric(c: [f64; 3], x: f64, y: f64) -> (f64, f64, f64) {
    (
        0.5 * (c[0] * x * x + 2.0 * c[1] * x * y + c[2] * y * y),
        c[0] * x + c[1] * y,
        c[1] * x + c[2] * y,
    )
}

/// The grain: the planar direction of angle θ = a x + b y, projected onto the tangent plane.
fn grain(c: [f64; 3], ab: (f64, f64), x: f64, y: f64) -> Vector3<f64> {
    let th = ab.0 * x + ab.1 * y;
    let (_, zx, zy) = quadric(c, x, y);
    let n = Vector3::new(-zx, -zy, 1.0).normalize();
    let w = Vector3::new(th.cos(), th.sin(), 0.0);
    (w - n * n.dot(&w)).normalize()
}

/// The exact ℓ = n × ∇_S(hᵀu) of the smooth surface and field (math.md §1), with the partial
/// derivatives of hᵀu taken by central differences of the analytic functions.
fn exact_ell(c: [f64; 3], ab: (f64, f64), h: &Vector3<f64>, x: f64, y: f64) -> Vector3<f64> {
    let f = |x: f64, y: f64| h.dot(&grain(c, ab, x, y));
    let e = 1e-5;
    let (fx, fy) =
        ((f(x + e, y) - f(x - e, y)) / (2.0 * e), (f(x, y + e) - f(x, y - e)) / (2.0 * e));
    let (_, zx, zy) = quadric(c, x, y);
    let (xx, xy) = (Vector3::new(1.0, 0.0, zx), Vector3::new(0.0, 1.0, zy));
    let g = nalgebra::Matrix2::new(xx.dot(&xx), xx.dot(&xy), xy.dot(&xx), xy.dot(&xy));
    let coef = g.try_inverse().unwrap() * Vector2::new(fx, fy);
    let grad = xx * coef.x + xy * coef.y;
    Vector3::new(-zx, -zy, 1.0).normalize().cross(&grad)
}

fn ell_on_patch(
    c: [f64; 3],
    ab: (f64, f64),
    h: Vector3<f64>,
    n: usize,
    pattern: GridPattern,
) -> (Mesh, Geometry, Vec<Vector3<f64>>) {
    let mesh = generate::quadric_patch(c, 0.5, Grid { pattern, ..Grid::new(n, n) });
    let g = geom(&mesh);
    let dirs: Vec<Vector3<f64>> = mesh.positions.iter().map(|p| grain(c, ab, p.x, p.y)).collect();
    let f = field_of(&mesh, &g, &dirs, h);
    (mesh, g, f.ell)
}

#[test]
fn lu_eq1_at_the_origin() {
    // Lu et al.'s Eq. 1 (math.md §1): u = e_x at the origin, ∇φ = (a, b), h = (0, s, c) ⇒
    // ℓ = (−(b s + c11 c), a s + c20 c, 0).
    let c = [0.9, 0.35, -0.6];
    let ab = (0.7, -0.4);
    let th: f64 = 0.6;
    let h = Vector3::new(0.0, th.sin(), th.cos());
    let lu =
        Vector3::new(-(ab.1 * th.sin() + c[1] * th.cos()), ab.0 * th.sin() + c[0] * th.cos(), 0.0);
    let mut last = f64::INFINITY;
    for n in [16, 32, 64] {
        let (mesh, _, ell) = ell_on_patch(c, ab, h, n, GridPattern::Regular);
        let o = mesh.positions.iter().position(|p| p.x.abs() < 1e-12 && p.y.abs() < 1e-12).unwrap();
        let err = (ell[o] - lu).norm() / lu.norm();
        eprintln!("n={n}: ℓ at origin {:?}, Lu {:?}, rel err {err:.2e}", ell[o], lu);
        assert!(err < last);
        last = err;
    }
    assert!(last < 2e-3);
}

fn angle_between_lines(a: &Vector3<f64>, b: &Vector3<f64>) -> f64 {
    (a.cross(b).norm()).atan2(a.dot(b).abs())
}

#[test]
fn ell_matches_the_smooth_surface_at_interior_vertices_and_converges() {
    let c = [0.8, -0.3, 0.5];
    let ab = (0.9, 0.5);
    let h = Vector3::new(0.3, 0.4, 1.0).normalize();
    for pattern in [
        GridPattern::Regular,
        GridPattern::CrissCross,
        GridPattern::Jittered { amount: 0.2, seed: 3 },
    ] {
        let mut maxes = Vec::new();
        for n in [16, 32, 64] {
            let (mesh, g, ell) = ell_on_patch(c, ab, h, n, pattern);
            let mut max_deg = 0.0f64;
            let mut rms = 0.0;
            let mut count = 0.0;
            for i in (0..mesh.num_vertices()).filter(|&i| !g.adjacency.is_boundary_vertex(i)) {
                let p = mesh.positions[i];
                let truth = exact_ell(c, ab, &h, p.x, p.y);
                let deg = angle_between_lines(&ell[i], &truth).to_degrees();
                max_deg = max_deg.max(deg);
                rms += deg * deg;
                count += 1.0;
            }
            let rms = (rms / count).sqrt();
            eprintln!("{pattern:?} n={n}: max {max_deg:.3}°, rms {rms:.4}°");
            maxes.push(rms);
        }
        assert!(maxes[2] < maxes[1] && maxes[1] < maxes[0], "{pattern:?}: {maxes:?}");
        assert!(maxes[2] < 0.5, "{pattern:?}: rms {}°", maxes[2]);
        eprintln!("{pattern:?}: observed order {:.2}", (maxes[1] / maxes[2]).log2());
    }
}

#[test]
fn gradient_is_exact_for_a_linear_angle_on_a_plane() {
    for pattern in [
        GridPattern::Regular,
        GridPattern::CrissCross,
        GridPattern::Jittered { amount: 0.3, seed: 11 },
    ] {
        let mesh = generate::plane(1.0, Grid { pattern, ..Grid::new(12, 9) });
        let g = geom(&mesh);
        let (a, b) = (0.8, -1.3);
        for k in [1u32, 2] {
            // φ is measured from each frame's t; on a plane every frame has t = x.
            let phi: Vec<f64> = mesh.positions.iter().map(|p| a * p.x + b * p.y).collect();
            let grad = g.stencil.gradient(&phi, k, GradientForm::Angle);
            for (i, gr) in grad.iter().enumerate() {
                assert!(
                    (gr - Vector2::new(a, b)).norm() < 1e-11,
                    "{pattern:?} k={k} vertex {i}: {gr}"
                );
            }
        }
    }
}

#[test]
fn gradient_is_frame_independent_and_ell_too() {
    let mesh = generate::torus(2.0, 0.7, 48, 20);
    let h = Vector3::new(0.2, -0.5, 1.0).normalize();
    let dirs: Vec<Vector3<f64>> =
        mesh.positions.iter().map(|p| Vector3::new(-p.y, p.x, 0.3 * p.z)).collect();
    let mut ells = Vec::new();
    for seed in [None, Some(1u64), Some(99)] {
        let g = Geometry::compute(
            &mesh,
            &GeometryOptions { frame_twist_seed: seed, ..Default::default() },
        );
        let f = field_of(&mesh, &g, &dirs, h);
        ells.push(f.ell);
    }
    for e in &ells[1..] {
        for (i, (a, b)) in ells[0].iter().zip(e).enumerate() {
            assert!((a - b).norm() < 1e-9 * (1.0 + a.norm()), "vertex {i}: {a} vs {b}");
        }
    }
}

#[test]
fn scaling_scales_w_and_gradient_and_keeps_ell_direction() {
    let base = generate::torus(2.0, 0.6, 40, 16);
    let h = Vector3::new(0.1, 0.3, 1.0).normalize();
    let dirs: Vec<Vector3<f64>> =
        base.positions.iter().map(|p| Vector3::new(1.0, 0.2 * p.x, 0.1)).collect();
    let run = |s: f64| {
        let mut m = base.clone();
        m.scale(s);
        let g = geom(&m);
        let f = field_of(&m, &g, &dirs, h);
        (g, f)
    };
    let (g1, f1) = run(1.0);
    for s in [1e-4, 1e4] {
        let (gs, fs) = run(s);
        for i in 0..g1.num_vertices() {
            assert!(
                (gs.weingarten[i] * s - g1.weingarten[i]).norm()
                    < 1e-8 * (1.0 + g1.weingarten[i].norm())
            );
            assert!(
                (fs.gradient[i] * s - f1.gradient[i]).norm() < 1e-8 * (1.0 + f1.gradient[i].norm())
            );
            let (a, b) = (fs.ell[i] * s, f1.ell[i]);
            assert!((a - b).norm() < 1e-8 * (1.0 + b.norm()), "vertex {i} at scale {s}");
        }
    }
}

#[test]
fn face_normal_holonomy_equals_the_angle_defect_exactly() {
    // Carrying a vector around the loop of face normals of a vertex star by minimal rotations
    // turns it by the area of the star's Gauss image: the angle defect.
    let mesh = generate::icosphere(1.0, 1);
    let vf = grainline::geometry::VertexFaces::new(&mesh);
    let fnorm = grainline::geometry::normals::face_normals(&mesh);
    let g = geom(&mesh);
    for v in 0..mesh.num_vertices() {
        // Order the faces around v by walking shared edges.
        let mut faces: Vec<usize> = vf.of(v).iter().map(|&(f, _)| f as usize).collect();
        let mut ordered = vec![faces.remove(0)];
        while !faces.is_empty() {
            let last = mesh.faces[*ordered.last().unwrap()];
            let c = last.iter().position(|&x| x as usize == v).unwrap();
            let next_vertex = last[(c + 2) % 3]; // the edge v → prev is shared with the next face
            let k = faces.iter().position(|&f| mesh.faces[f].contains(&next_vertex)).unwrap();
            ordered.push(faces.remove(k));
        }
        let defect: f64 = std::f64::consts::TAU
            - vf.of(v)
                .iter()
                .map(|&(f, c)| {
                    let p = mesh.face_positions(f as usize);
                    let c = c as usize;
                    corner_angle(&p[c], &p[(c + 1) % 3], &p[(c + 2) % 3])
                })
                .sum::<f64>();
        let n0 = fnorm[ordered[0]];
        let w0 = (mesh.positions[mesh.faces[ordered[0]][0] as usize]
            - mesh.positions[mesh.faces[ordered[0]][1] as usize])
            .normalize();
        let mut w = w0;
        for k in 0..ordered.len() {
            let (a, b) = (fnorm[ordered[k]], fnorm[ordered[(k + 1) % ordered.len()]]);
            w = connection::minimal_rotation(&w, &a, &b);
        }
        let turned = n0.dot(&w0.cross(&w)).atan2(w0.dot(&w));
        assert!((turned.abs() - defect.abs()).abs() < 1e-12, "vertex {v}: {turned} vs {defect}");
        // The vertex-ring version (what the solver uses) agrees to the discretization order.
        let _ = &g;
    }
}

#[test]
fn vertex_ring_holonomy_converges_to_the_enclosed_curvature() {
    // Σ over the 1-ring loop of transports ≈ the Gaussian curvature enclosed (sphere: area / r²).
    let mut last = f64::INFINITY;
    for sub in [2, 3, 4] {
        let mesh = generate::icosphere(1.0, sub);
        let g = geom(&mesh);
        let mut worst: f64 = 0.0;
        for v in (0..mesh.num_vertices()).step_by(7) {
            let ring = ordered_ring(&mesh, v);
            let mut hol = 0.0;
            for k in 0..ring.len() {
                let (a, b) = (ring[k], ring[(k + 1) % ring.len()]);
                // transport from a to b: φ_b-frame angle = φ_a-frame angle + ρ_ba
                hol += g.transport[g.adjacency.slot(b, a as u32).unwrap()];
            }
            let hol = connection::wrap_angle(hol);
            // enclosed area of the spherical polygon of the ring ≈ Σ areas of the star faces
            let star: f64 = ring
                .iter()
                .enumerate()
                .map(|(k, &a)| {
                    let b = ring[(k + 1) % ring.len()];
                    0.5 * (mesh.positions[a] - mesh.positions[v])
                        .cross(&(mesh.positions[b] - mesh.positions[v]))
                        .norm()
                })
                .sum();
            worst = worst.max((hol.abs() - star).abs() / star);
        }
        eprintln!("icosphere {sub}: worst relative holonomy error {worst:.3e}");
        assert!(worst < last);
        last = worst;
    }
    assert!(last < 0.05);
}

fn ordered_ring(mesh: &Mesh, v: usize) -> Vec<usize> {
    let star: Vec<[u32; 3]> =
        mesh.faces.iter().filter(|f| f.contains(&(v as u32))).copied().collect();
    let rot = |f: &[u32; 3]| {
        let c = f.iter().position(|&x| x as usize == v).unwrap();
        (f[(c + 1) % 3] as usize, f[(c + 2) % 3] as usize)
    };
    let mut ring = vec![rot(&star[0]).0];
    while ring.len() < star.len() {
        let last = *ring.last().unwrap();
        let next = star.iter().map(rot).find(|&(a, _)| a == last).unwrap().1;
        ring.push(next);
    }
    ring
}

#[test]
fn smoothest_field_on_a_plane_is_constant() {
    let mesh = generate::plane(
        1.0,
        Grid { pattern: GridPattern::Jittered { amount: 0.2, seed: 5 }, ..Grid::new(20, 20) },
    );
    let g = geom(&mesh);
    for sym in [Symmetry::Oriented, Symmetry::Line] {
        let r = highlight::smoothest::smoothest_field(&mesh, &g, sym, &Default::default()).unwrap();
        let k = sym.k() as f64;
        for p in &r.phi {
            let d = connection::wrap_angle(k * (p - r.phi[0]));
            assert!(d.abs() < 1e-6, "{sym:?}: {d}");
        }
        assert!(r.eigenvalue.abs() < 1e-6, "{}", r.eigenvalue);
    }
}

#[test]
fn smoothest_field_on_a_sphere_is_smooth_but_not_constant() {
    let mesh = generate::icosphere(1.0, 3);
    let g = geom(&mesh);
    let r = highlight::smoothest::smoothest_field(&mesh, &g, Symmetry::Line, &Default::default())
        .unwrap();
    // A sphere admits no parallel field: λ > 0, but of the order of the curvature, not of h⁻².
    assert!(r.eigenvalue > 0.1 && r.eigenvalue < 10.0, "{}", r.eigenvalue);
    assert!(r.phi.iter().all(|p| p.is_finite()));
}

#[test]
fn critical_points_where_h_meets_n() {
    let mesh = generate::icosphere(1.0, 3);
    let g = geom(&mesh);
    let h = vec![Vector3::z(); mesh.num_vertices()];
    let crit = highlight::critical::critical_points(&h, g.frames.iter().map(|f| f.n), 0.9995);
    let top = (0..mesh.num_vertices())
        .max_by(|&a, &b| mesh.positions[a].z.total_cmp(&mesh.positions[b].z))
        .unwrap();
    assert!(crit[top]);
    assert_eq!(crit.iter().filter(|&&c| c).count(), 1);
}
