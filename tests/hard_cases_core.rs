//! Hard cases for the core: degenerate geometry must give finite outputs and typed errors,
//! never NaN, Inf or a panic.

mod common;
use common::shared_mesh;

use grainline::field::{compute_field, FieldFile, FieldOptions};
use grainline::generate::{self, Grid};
use grainline::geometry::{Geometry, GeometryOptions};
use grainline::highlight::tensor::tensor;
use grainline::highlight::{InitialField, Lighting, Symmetry, View};
use grainline::mesh::load::{load_obj, LoadOptions};
use grainline::mesh::Mesh;
use nalgebra::{Vector2, Vector3};

fn lighting() -> Lighting {
    Lighting::new(Vector3::new(0.4, 0.3, 1.0), View::Direction(Vector3::new(-0.3, 0.2, 1.0)))
        .unwrap()
}

/// Runs the whole field job and checks every output is finite; returns the result.
fn all_finite(
    mesh: &Mesh,
    init: InitialField,
    symmetry: Symmetry,
) -> grainline::field::FieldResult {
    let mut o = FieldOptions::new(lighting());
    o.init = init;
    o.symmetry = symmetry;
    let r = compute_field(mesh, &o).expect("field");
    FieldFile::new(mesh, "test", &o, &r).expect("every output finite");
    for i in 0..mesh.num_vertices() {
        let g = &r.geometry;
        assert!(g.weingarten[i].iter().all(|v| v.is_finite()), "W at {i}");
        assert!(r.highlight.gradient[i].iter().all(|v| v.is_finite()), "∇φ at {i}");
        assert!(g.areas[i] >= 0.0);
        let l = g.frames[i].to_local(&r.highlight.ell[i]);
        assert!(tensor(&l, 1e-3).iter().all(|v| v.is_finite()));
    }
    r
}

#[test]
fn h_equals_n_at_a_vertex() {
    // The light and view both along +z: at the top of a sphere h = n exactly.
    let mesh = generate::icosphere(1.0, 3);
    let mut o =
        FieldOptions::new(Lighting::new(Vector3::z(), View::Direction(Vector3::z())).unwrap());
    o.init = InitialField::World(Vector3::x());
    let r = compute_field(&mesh, &o).unwrap();
    let top = (0..mesh.num_vertices())
        .max_by(|&a, &b| mesh.positions[a].z.total_cmp(&mesh.positions[b].z))
        .unwrap();
    assert!(r.critical[top]);
    FieldFile::new(&mesh, "sphere", &o, &r).unwrap();
}

#[test]
fn flat_region_gives_zero_ell_and_an_isotropic_tensor() {
    let mesh = generate::plane(1.0, Grid::new(10, 10));
    let r = all_finite(&mesh, InitialField::World(Vector3::new(1.0, 0.5, 0.0)), Symmetry::Oriented);
    for (i, l) in r.highlight.ell.iter().enumerate() {
        assert!(l.norm() < 1e-12, "ℓ at {i}: {l}");
        let t = tensor(&Vector2::new(l.x, l.y), 1e-3);
        assert!((t - nalgebra::Matrix2::identity() * 0.5).norm() < 1e-6);
    }
}

#[test]
fn valence_3_and_valence_30() {
    // A 30-gon fan around a centre vertex, with an outer ring, and one triangle split 1-to-3
    // (a valence-3 vertex) in the outer ring.
    let n = 30;
    let mut pos = vec![Vector3::new(0.0, 0.0, 0.05)];
    for ring in 1..=2 {
        for k in 0..n {
            let a = std::f64::consts::TAU * k as f64 / n as f64 + 0.05 * ring as f64;
            let r = 0.3 * ring as f64;
            pos.push(Vector3::new(r * a.cos(), r * a.sin(), 0.05 - 0.2 * r * r));
        }
    }
    let mut faces = Vec::new();
    for k in 0..n as u32 {
        let (a, b) = (1 + k, 1 + (k + 1) % n as u32);
        faces.push([0, a, b]);
        let (c, d) = (a + n as u32, b + n as u32);
        faces.push([a, c, d]);
        faces.push([a, d, b]);
    }
    // Split the last triangle 1-to-3 at its centroid.
    let [a, b, c] = faces.pop().unwrap();
    let centroid = (pos[a as usize] + pos[b as usize] + pos[c as usize]) / 3.0;
    pos.push(centroid);
    let m = (pos.len() - 1) as u32;
    faces.extend([[a, b, m], [b, c, m], [c, a, m]]);
    let mesh = Mesh::from_triangles(pos, faces);
    let g = Geometry::compute(&mesh, &GeometryOptions::default());
    assert_eq!(g.adjacency.valence(0), 30);
    assert_eq!(g.adjacency.valence(m as usize), 3);
    // The centre is the apex of a paraboloid z = 0.05 − 0.2 r²: k1 = k2 = 0.4.
    assert!(
        (g.principal[0].k1 - 0.4).abs() < 0.02 && (g.principal[0].k2 - 0.4).abs() < 0.02,
        "{:?}",
        g.principal[0]
    );
    all_finite(&mesh, InitialField::Smooth, Symmetry::Line);
    all_finite(&mesh, InitialField::CurvatureMax, Symmetry::Line);
}

#[test]
fn boundary_corners_with_two_neighbours() {
    // Grid corners where the quad diagonal does not touch have exactly two neighbours.
    let mesh = generate::quadric_patch([0.5, 0.1, -0.3], 1.0, Grid::new(6, 6));
    let g = Geometry::compute(&mesh, &GeometryOptions::default());
    let two: Vec<usize> =
        (0..mesh.num_vertices()).filter(|&i| g.adjacency.valence(i) == 2).collect();
    assert!(!two.is_empty());
    for &i in &two {
        assert!(g.adjacency.is_boundary_vertex(i));
    }
    all_finite(&mesh, InitialField::Uv, Symmetry::Oriented);
}

#[test]
fn tiny_and_huge_scales() {
    for s in [1e-4, 1e4] {
        let mut mesh = generate::torus(2.0, 0.5, 48, 16);
        mesh.scale(s);
        let r = all_finite(&mesh, InitialField::Smooth, Symmetry::Line);
        let g = &r.geometry;
        // The minor-circle curvature is 2/s everywhere (within the 48×16 discretization error).
        let worst = g.principal.iter().map(|p| (p.k1 * s - 2.0).abs() / 2.0).fold(0.0, f64::max);
        assert!(worst < 0.04, "scale {s}: k1 relative error {worst}");
        let mut eye_mesh = mesh.clone();
        eye_mesh.scale(1.0);
        let mut o = FieldOptions::new(
            Lighting::new(Vector3::z(), View::Eye(Vector3::new(0.0, 0.0, 10.0 * s))).unwrap(),
        );
        o.init = InitialField::Uv;
        let r = compute_field(&eye_mesh, &o).unwrap();
        FieldFile::new(&eye_mesh, "t", &o, &r).unwrap();
    }
}

#[test]
fn isolated_vertex_and_zero_area_face_in_memory() {
    // Not through the loader (which drops both): the geometry itself must cope.
    let mut mesh = generate::plane(1.0, Grid::new(4, 4));
    mesh.uv = None;
    mesh.positions.push(Vector3::new(5.0, 5.0, 5.0)); // isolated
    let a = mesh.faces[0][0];
    mesh.faces.push([a, a, mesh.faces[0][1]]); // zero area, repeated index
    let g = Geometry::compute(&mesh, &GeometryOptions::default());
    assert_eq!(g.diagnostics.fallback_normals, 1);
    assert_eq!(g.diagnostics.empty_gradient_stencils, 1);
    all_finite(&mesh, InitialField::World(Vector3::x()), Symmetry::Oriented);
    all_finite(&mesh, InitialField::Smooth, Symmetry::Oriented);
}

#[test]
fn world_direction_along_the_normal_falls_back() {
    let mesh = generate::icosphere(1.0, 2);
    let r = all_finite(&mesh, InitialField::World(Vector3::z()), Symmetry::Oriented);
    // The two poles have z ∥ n: both take the second direction (x, the axis least aligned with
    // z, projected), so none needs the neighbours' fallback.
    assert!(r.fallback_vertices.is_empty(), "{:?}", r.fallback_vertices);
    let g = Geometry::compute(&mesh, &GeometryOptions::default());
    let poles: Vec<usize> =
        (0..mesh.num_vertices()).filter(|&i| g.frames[i].n.z.abs() > 0.9999).collect();
    assert_eq!(poles.len(), 2);
    for i in poles {
        let u = g.frames[i].direction(r.phi[i]);
        assert!(u.x.abs() > 0.9999, "pole {i}: u {u:?}");
    }
}

#[test]
fn light_opposite_the_view() {
    let mesh = generate::icosphere(1.0, 2);
    let mut o =
        FieldOptions::new(Lighting::new(Vector3::x(), View::Direction(-Vector3::x())).unwrap());
    o.init = InitialField::Smooth;
    let r = compute_field(&mesh, &o).unwrap();
    FieldFile::new(&mesh, "t", &o, &r).unwrap();
    assert!(r.h.iter().all(|h| (h.norm() - 1.0).abs() < 1e-12));
}

#[test]
fn bad_directions_are_typed_errors() {
    let mesh = generate::icosphere(1.0, 1);
    let g = Geometry::compute(&mesh, &GeometryOptions::default());
    let mut d: Vec<Vector3<f64>> = mesh.positions.iter().map(|_| Vector3::x()).collect();
    d[3] = mesh.positions[3]; // along the normal
    let e = grainline::highlight::initial_field(
        &mesh,
        &g,
        &InitialField::Directions(d),
        Symmetry::Oriented,
    )
    .unwrap_err();
    assert!(e.to_string().contains("vertex 3"), "{e}");
    let e = grainline::highlight::initial_field(&mesh, &g, &InitialField::Uv, Symmetry::Oriented)
        .unwrap_err();
    assert!(e.to_string().contains("no UV"), "{e}");
}

fn shared(name: &str, options: LoadOptions) -> Option<Mesh> {
    let path = shared_mesh(name)?;
    Some(load_obj(&path, &options).unwrap_or_else(|e| panic!("{name}: {e}")).mesh)
}

#[test]
fn oloid_slivers() {
    let Some(mesh) = shared("oloid4096_tri.obj", LoadOptions::default().tolerant()) else { return };
    let r = all_finite(&mesh, InitialField::Smooth, Symmetry::Line);
    // The oloid is developable: K = k1 k2 ≈ 0 away from its two edge circles.
    let g = &r.geometry;
    let small_k2 = g
        .principal
        .iter()
        .filter(|p| p.k1.abs().min(p.k2.abs()) < 0.1 * p.k1.abs().max(p.k2.abs()) + 1e-9)
        .count();
    eprintln!(
        "oloid: {small_k2}/{} vertices with one near-zero principal curvature",
        mesh.num_vertices()
    );
    all_finite(&mesh, InitialField::CurvatureMin, Symmetry::Line);
}

#[test]
fn teapot_and_bunny_duplicates_and_isolated_vertices() {
    if let Some(mesh) = shared("teapot.obj", LoadOptions::default().tolerant()) {
        all_finite(&mesh, InitialField::World(Vector3::new(0.0, 1.0, 0.0)), Symmetry::Line);
    }
    if let Some(mesh) =
        shared("teapot.obj", LoadOptions { weld: Some(1e-6), ..LoadOptions::default().tolerant() })
    {
        all_finite(&mesh, InitialField::Smooth, Symmetry::Oriented);
    }
    if let Some(mesh) = shared("stanford-bunny.obj", LoadOptions::default().tolerant()) {
        all_finite(&mesh, InitialField::CurvatureMin, Symmetry::Line);
    }
}

#[test]
fn spot_mirrored_uv_chart() {
    let Some(mesh) = shared("spot_triangulated.obj", LoadOptions::default()) else { return };
    let r = all_finite(&mesh, InitialField::Uv, Symmetry::Oriented);
    // Inside a chart the UV field is smooth: along edges whose two ends are off the seams (all
    // corners of the vertex share one UV), neighbouring directions differ by little, on the
    // mirrored chart too.
    let u = r.geometry.directions_of(&r.phi);
    let uv = mesh.uv.as_ref().unwrap();
    let mut vertex_uv: Vec<Option<u32>> = vec![None; mesh.num_vertices()];
    let mut on_seam = vec![false; mesh.num_vertices()];
    for (tri, corners) in mesh.faces.iter().zip(&uv.corners) {
        for (&v, &t) in tri.iter().zip(corners) {
            let v = v as usize;
            match vertex_uv[v] {
                None => vertex_uv[v] = Some(t),
                Some(x) if x != t => on_seam[v] = true,
                _ => {}
            }
        }
    }
    let mut angles = Vec::new();
    for tri in &mesh.faces {
        for k in 0..3 {
            let (a, b) = (tri[k] as usize, tri[(k + 1) % 3] as usize);
            if !on_seam[a] && !on_seam[b] {
                angles.push(u[a].angle(&u[b]).to_degrees());
            }
        }
    }
    angles.sort_by(f64::total_cmp);
    let (median, p99) = (angles[angles.len() / 2], angles[angles.len() * 99 / 100]);
    eprintln!("spot: neighbouring UV directions inside charts: median {median:.2}°, p99 {p99:.1}°");
    // The faces themselves differ by a median 4.9° and p99 44° across shared edges (the UV map
    // of spot is coarse); a chart turned over would put many pairs near 180°.
    assert!(median < 10.0 && p99 < 60.0);
    assert!(r.fallback_vertices.is_empty());
}

#[test]
fn every_shared_mesh_gives_finite_fields() {
    for name in ["blub_quadrangulated.obj", "fandisk.obj", "rocker-arm.obj", "paper-crumpled2.obj"]
    {
        if let Some(mesh) = shared(name, LoadOptions::default().tolerant()) {
            let init = if mesh.uv.is_some() { InitialField::Uv } else { InitialField::Smooth };
            all_finite(&mesh, init, Symmetry::Line);
        }
    }
}

/// A doubly curved panel whose UV map folds at x = 0 (u = |x|, one UV per vertex, as a mirrored
/// half of a symmetric part is often mapped): the faces on either side of the fold share its
/// UVs, but their ∂p/∂u point along +x and −x. As a line the grain is x̂ on both sides and on
/// the fold; summed as vectors the fold's directions cancelled and it took whatever was left —
/// on a symmetric part, exactly where the key highlight lies. Truth from outside: ∂p/∂x =
/// (1, 0, x/200) of the surface z = x²/400 + y²/600, which ∂p/∂u is up to sign, and no singular
/// triangle anywhere.
#[test]
fn a_mirrored_uv_fold_keeps_a_line_fields_grain() {
    let (nx, ny) = (40usize, 24usize);
    let mut pos = Vec::new();
    let mut tex = Vec::new();
    for j in 0..=ny {
        for i in 0..=nx {
            let (x, y) =
                (-80.0 + 160.0 * i as f64 / nx as f64, -50.0 + 100.0 * j as f64 / ny as f64);
            pos.push(Vector3::new(x, y, x * x / 400.0 + y * y / 600.0));
            tex.push(Vector2::new(x.abs() / 80.0, (y + 50.0) / 100.0));
        }
    }
    let mut faces = Vec::new();
    for j in 0..ny {
        for i in 0..nx {
            let a = (j * (nx + 1) + i) as u32;
            let (b, c, d) = (a + 1, a + nx as u32 + 2, a + nx as u32 + 1);
            faces.push([a, b, c]);
            faces.push([a, c, d]);
        }
    }
    let mut mesh = Mesh::from_triangles(pos, faces.clone());
    mesh.uv = Some(grainline::mesh::CornerAttribute { values: tex, corners: faces });
    let r = all_finite(&mesh, InitialField::Uv, Symmetry::Line);
    let u = r.geometry.directions_of(&r.phi);
    let (mut worst, mut fold): (f64, f64) = (0.0, 0.0);
    for (i, ui) in u.iter().enumerate() {
        let x = mesh.positions[i].x;
        let want = Vector3::new(1.0, 0.0, x / 200.0).normalize();
        let off = ui.dot(&want).abs().clamp(0.0, 1.0).acos().to_degrees();
        worst = worst.max(off);
        if x == 0.0 {
            fold = fold.max(off);
        }
    }
    eprintln!("mirrored fold: the grain is within {worst:.2}° of ∂p/∂x ({fold:.2}° on the fold)");
    assert!(worst < 1.0 && fold < 1.0, "the grain turns {worst}° off ∂p/∂x ({fold}° on the fold)");
    let sing = grainline::solve::singularities(&mesh, &r.geometry, &r.phi, 2);
    assert!(sing.is_empty(), "{} singular triangles", sing.len());
}
