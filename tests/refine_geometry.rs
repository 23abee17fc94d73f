//! The refined part's shape, from outside the code: refinement inside a brush must not make
//! the surface bumpy. Its new vertices sit on the Phong point of their edge, and their
//! curvature (jet fits on the refined mesh, as the field computes it) is compared with the
//! analytic curvature of the sphere and of the cylinder the coarse mesh samples.

use grainline::generate;
use grainline::geometry::{Geometry, GeometryOptions};
use grainline::mesh::refine::{refine, RefineOptions};
use grainline::mesh::Mesh;

/// Refines every face of `mesh` to edges ≤ `edge`; returns the refined mesh and its count of
/// original vertices.
fn refined(mesh: &Mesh, edge: f64) -> (Mesh, usize) {
    let target = vec![edge; mesh.num_faces()];
    let r = refine(mesh, &target, &RefineOptions::default()).unwrap();
    assert!(r.levels >= 2, "{} levels", r.levels);
    (r.mesh, mesh.num_vertices())
}

/// The largest relative error of k1 and k2 against `truth` over the new vertices (those at
/// index ≥ `first`) that `keep` selects.
fn curvature_error(
    mesh: &Mesh,
    first: usize,
    truth: (f64, f64),
    keep: impl Fn(usize) -> bool,
) -> f64 {
    let g = Geometry::compute(mesh, &GeometryOptions::default());
    let scale = truth.0.abs().max(truth.1.abs());
    (first..mesh.num_vertices())
        .filter(|&i| keep(i))
        .map(|i| {
            let p = &g.principal[i];
            ((p.k1 - truth.0).abs().max((p.k2 - truth.1).abs())) / scale
        })
        .fold(0.0, f64::max)
}

/// Edges of a subdivision-2 icosphere span about 18°; the midpoint of such a chord is 1.2 % of
/// the radius inside the sphere. Two levels of splitting must keep every new vertex within
/// 0.1 % of the sphere (the Phong point with shape factor 1/2 is exact to second order: R cos θ
/// (1 + ½ sin² θ) = R (1 − 3θ⁴/8 + …)) and its curvature within 10 % of 1/R.
#[test]
fn refining_a_sphere_keeps_it_round() {
    let r = 2.0;
    let coarse = generate::icosphere(r, 2);
    let edge = coarse
        .faces
        .iter()
        .map(|f| (coarse.positions[f[0] as usize] - coarse.positions[f[1] as usize]).norm())
        .fold(0.0, f64::max);
    let (mesh, first) = refined(&coarse, edge / 3.5);
    let radial = (first..mesh.num_vertices())
        .map(|i| (mesh.positions[i].norm() - r).abs() / r)
        .fold(0.0, f64::max);
    let k = curvature_error(&mesh, first, (1.0 / r, 1.0 / r), |_| true);
    eprintln!(
        "sphere: {} new vertices, radial {radial:.2e}, curvature {k:.3}",
        mesh.num_vertices() - first
    );
    assert!(radial < 1e-3, "a new vertex is {radial:.2e} R off the sphere");
    assert!(k < 0.10, "curvature off by {k:.3} of 1/R");
}

/// A cylinder of radius 1 with 24 segments around: the refined vertices keep their distance
/// to the axis and the curvature (1/R, 0), away from the open ends.
#[test]
fn refining_a_cylinder_keeps_it_round() {
    let (r, h) = (1.0, 2.0);
    let coarse = generate::cylinder(r, h, 24, 8);
    let (mesh, first) = refined(&coarse, 0.07);
    let z = |i: usize| mesh.positions[i].z;
    let (lo, hi) = (0..first)
        .map(z)
        .fold((f64::INFINITY, f64::NEG_INFINITY), |(a, b), v| (a.min(v), b.max(v)));
    let inner = |i: usize| z(i) > lo + 0.3 * (hi - lo) && z(i) < hi - 0.3 * (hi - lo);
    let radial = (first..mesh.num_vertices())
        .map(|i| (mesh.positions[i].xy().norm() - r).abs() / r)
        .fold(0.0, f64::max);
    let k = curvature_error(&mesh, first, (1.0 / r, 0.0), inner);
    eprintln!("cylinder: radial {radial:.2e}, curvature {k:.3}");
    assert!(radial < 1e-3, "a new vertex is {radial:.2e} R off the cylinder");
    assert!(k < 0.10, "curvature off by {k:.3} of 1/R");
}

/// A CAD-like puck's top: a flat disc of radius 35 at z = 20 meshed as a fan of 96 slivers
/// from its centre, meeting a quarter-round fillet of radius 5 (8 rings) down to the wall.
fn puck() -> Mesh {
    let (r, h, fr, nseg) = (40.0, 20.0, 5.0, 96usize);
    let mut prof = vec![(r, 0.0), (r, h - fr)];
    for k in 1..=8 {
        let a = std::f64::consts::FRAC_PI_2 * k as f64 / 8.0;
        prof.push((r - fr + fr * a.cos(), h - fr + fr * a.sin()));
    }
    let mut pos = Vec::new();
    let mut rings = Vec::new();
    for &(rr, z) in &prof {
        let mut ring = Vec::new();
        for i in 0..nseg {
            let ph = 2.0 * std::f64::consts::PI * i as f64 / nseg as f64;
            ring.push(pos.len() as u32);
            pos.push(nalgebra::Vector3::new(rr * ph.cos(), rr * ph.sin(), z));
        }
        rings.push(ring);
    }
    let mut faces = Vec::new();
    for w in rings.windows(2) {
        let (p, q) = (&w[0], &w[1]);
        for i in 0..nseg {
            let j = (i + 1) % nseg;
            faces.push([p[i], p[j], q[j]]);
            faces.push([p[i], q[j], q[i]]);
        }
    }
    let c = pos.len() as u32;
    pos.push(nalgebra::Vector3::new(0.0, 0.0, h));
    let top = rings.last().unwrap();
    for i in 0..nseg {
        faces.push([top[i], top[(i + 1) % nseg], c]);
    }
    Mesh::from_triangles(pos, faces)
}

/// Edges of 0.5 asked on the faces of a band across the puck's top (and its fillet there).
fn band_across_the_top(m: &Mesh) -> Vec<f64> {
    m.faces
        .iter()
        .map(|f| {
            let c =
                f.iter().map(|&v| m.positions[v as usize]).sum::<nalgebra::Vector3<f64>>() / 3.0;
            if c.z > 14.0 && c.x.abs() < 30.0 && (c.y - 10.0).abs() < 4.0 {
                0.5
            } else {
                f64::INFINITY
            }
        })
        .collect()
}

/// A band across the puck's flat top refined to edges of 0.5: every new vertex inside the
/// disc stays on its plane z = 20 (Phong points from the rim's normals, which lean towards the
/// fillet, lifted them by up to 0.21 — a bump along every split sliver that the preview
/// showed as streaks), and the new vertices on the fillet stay on its quarter circle within
/// 60 % of its chords' sagitta (the rim's normals, shared by the disc and the fillet, lean
/// by half a fillet step: Phong points are no better than the normals).
#[test]
fn refining_a_flat_face_keeps_it_flat() {
    let m = puck();
    let target = band_across_the_top(&m);
    let r = refine(&m, &target, &RefineOptions::default()).unwrap();
    let first = m.num_vertices();
    // Inside the disc, away from its rim (whose chords' midpoints sit at r = 35 cos 1.9°).
    let inside = (first..r.mesh.num_vertices()).filter(|&i| r.mesh.positions[i].xy().norm() < 34.9);
    let (mut count, mut off) = (0, 0.0f64);
    for i in inside {
        count += 1;
        off = off.max((r.mesh.positions[i].z - 20.0).abs());
    }
    // The fillet: the distance to its centre circle (radius 35 at z = 15) is 5.
    let fillet = (first..r.mesh.num_vertices())
        .map(|i| r.mesh.positions[i])
        .filter(|p| p.z > 15.0 + 1e-9 && p.xy().norm() > 35.0 + 1e-9)
        .map(|p| ((p.xy().norm() - 35.0).hypot(p.z - 15.0) - 5.0).abs())
        .fold(0.0, f64::max);
    eprintln!("flat top: {count} new vertices, the farthest {off:.2e} off the plane; fillet {fillet:.2e} off its circle");
    assert!(count > 1000);
    assert!(off < 1e-9, "a new vertex of the flat top is {off} off its plane");
    // The fillet's chords span 11.25°: sagitta 5 (1 − cos 5.6°) = 0.024.
    assert!(fillet < 0.6 * 0.024, "a new fillet vertex is {fillet} off the fillet");
}

/// The puck's flat top shades as a plane up to its rim, before and after refinement: every
/// vertex of the top, the rim circle included, has the plane's normal exactly (the fillet meets
/// the top tangentially, so the rim's true normal is the plane's; the jet-refined weighted
/// average leaned it 0.5° towards the fillet as loaded, and up to 4.9° at the rim's new vertices
/// after refinement, where the preview of a curve on the top showed radial wedges).
/// The fillet's own vertices keep normals strictly between the plane's and the wall's.
#[test]
fn a_flat_face_meeting_a_fillet_has_the_planes_normal_up_to_its_rim() {
    let m = puck();
    let target = band_across_the_top(&m);
    let refined = refine(&m, &target, &RefineOptions::default()).unwrap().mesh;
    for (name, mesh) in [("as loaded", &m), ("refined", &refined)] {
        let g = Geometry::compute(mesh, &GeometryOptions::default());
        let (mut top, mut rim, mut fillet) = (0.0f64, 0.0f64, (f64::INFINITY, 0.0f64));
        for (i, p) in mesh.positions.iter().enumerate() {
            let tilt = g.normal(i).z.clamp(-1.0, 1.0).acos().to_degrees();
            if (p.z - 20.0).abs() < 1e-9 {
                if p.xy().norm() < 35.0 - 1e-6 {
                    top = top.max(tilt);
                } else {
                    rim = rim.max(tilt);
                }
            } else if p.z > 15.5 {
                fillet = (fillet.0.min(tilt), fillet.1.max(tilt));
            }
        }
        eprintln!(
            "{name}: top {top:.2e}°, rim {rim:.2e}°, fillet {:.1}–{:.1}°",
            fillet.0, fillet.1
        );
        assert!(top < 1e-6 && rim < 1e-6, "{name}: the top leans {top}°, its rim {rim}°");
        assert!(fillet.0 > 1.0 && fillet.1 < 85.0, "{name}: fillet normals {fillet:?}");
    }
}
