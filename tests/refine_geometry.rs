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
