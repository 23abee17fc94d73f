//! Topology and UV charts on meshes whose answers are known by construction.

use std::path::PathBuf;

use grainline::mesh::load::{load_obj, LoadOptions};
use grainline::mesh::topology::Topology;
use grainline::mesh::uv_charts::UvCharts;
use grainline::mesh::{Mesh, VertexId};
use nalgebra::Vector3;

fn data(name: &str) -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("tests/data").join(name)
}

fn topo(name: &str) -> (Mesh, Topology) {
    let m = load_obj(&data(name), &LoadOptions::default()).unwrap().mesh;
    let t = Topology::new(&m).unwrap();
    (m, t)
}

/// An n × m torus grid (R = 2, r = 0.5), outward normals.
fn torus(n: u32, m: u32) -> Mesh {
    let mut p = Vec::new();
    for i in 0..n {
        for j in 0..m {
            let (u, v) = (
                i as f64 / n as f64 * std::f64::consts::TAU,
                j as f64 / m as f64 * std::f64::consts::TAU,
            );
            let w = 2.0 + 0.5 * v.cos();
            p.push(Vector3::new(w * u.cos(), w * u.sin(), 0.5 * v.sin()));
        }
    }
    let id = |i: u32, j: u32| (i % n) * m + (j % m);
    let mut f = Vec::new();
    for i in 0..n {
        for j in 0..m {
            f.push([id(i, j), id(i + 1, j), id(i + 1, j + 1)]);
            f.push([id(i, j), id(i + 1, j + 1), id(i, j + 1)]);
        }
    }
    Mesh::from_triangles(p, f)
}

#[test]
fn tetrahedron_is_a_sphere() {
    let (_, t) = topo("tetrahedron.obj");
    assert_eq!(t.euler_characteristic(), 2);
    assert_eq!(t.genus(), Some(0));
    assert_eq!(t.num_boundary_loops(), 0);
    assert_eq!(t.components().len(), 1);
    assert_eq!(t.num_edges(), 6);
    for v in 0..4 {
        let r = t.one_ring(VertexId(v));
        assert!(!r.open);
        assert_eq!(r.vertices.len(), 3);
        assert_eq!(r.faces.len(), 3);
    }
}

#[test]
fn torus_has_genus_one_and_ccw_rings() {
    let m = torus(12, 8);
    let t = Topology::new(&m).unwrap();
    assert_eq!(t.euler_characteristic(), 0);
    assert_eq!(t.genus(), Some(1));
    assert_eq!(t.num_boundary_loops(), 0);
    // Rings are counter-clockwise around the outward normal: consecutive neighbours (w, u)
    // give (w − v) × (u − v) along the normal, which on this torus points away from the
    // tube's core circle.
    for v in 0..m.num_vertices() {
        let p = m.positions[v];
        let core = Vector3::new(p.x, p.y, 0.0).normalize() * 2.0;
        let normal = p - core;
        let r = t.one_ring(VertexId(v as u32));
        assert_eq!(r.vertices.len(), 6);
        for k in 0..r.vertices.len() {
            let w = m.positions[r.vertices[k].index()] - p;
            let u = m.positions[r.vertices[(k + 1) % r.vertices.len()].index()] - p;
            assert!(w.cross(&u).dot(&normal) > 0.0, "vertex {v}");
        }
    }
}

#[test]
fn disk_has_one_loop_and_boundary_rings_start_on_the_boundary() {
    let (m, t) = topo("disk.obj");
    assert_eq!(t.euler_characteristic(), 1);
    assert_eq!(t.num_boundary_loops(), 1);
    assert_eq!(t.boundary_loop(0).len(), 6);
    assert_eq!(t.genus(), Some(0));
    assert_eq!(t.boundary_vertices().len(), 6);
    let r = t.one_ring(VertexId(0));
    assert!(!r.open && r.vertices.len() == 6);
    // Vertex 1 (file v 2): its ring is open, starts and ends at boundary neighbours,
    // and goes CCW around +z.
    let r = t.one_ring(VertexId(1));
    assert!(r.open);
    assert_eq!(r.vertices, &[VertexId(2), VertexId(0), VertexId(6)]);
    assert_eq!(r.faces.len(), 2);
    let p = |v: VertexId| m.positions[v.index()] - m.positions[1];
    assert!(p(r.vertices[0]).cross(&p(r.vertices[1])).z > 0.0);
}

#[test]
fn two_components_counted_apart() {
    let (_, t) = topo("two_objects.obj");
    assert_eq!(t.components().len(), 2);
    assert_eq!(t.euler_characteristic(), 2);
    assert_eq!(t.genus(), Some(0));
    assert!(t.components().iter().all(|c| c.boundary_loops == 1 && c.genus == Some(0)));
}

fn charts(name: &str) -> UvCharts {
    let (m, t) = topo(name);
    UvCharts::new(t.halfedges(), m.uv.as_ref().unwrap())
}

#[test]
fn cube_atlas_seams_and_charts() {
    let c = charts("cube_uv.obj");
    assert_eq!(c.charts().len(), 5);
    assert_eq!(c.num_seam_edges(), 11);
    assert_eq!(c.num_flipped_faces(), 0);
    assert!(c.charts().iter().all(|ch| !ch.mirrored));
    let faces: Vec<usize> = c.charts().iter().map(|ch| ch.faces).collect();
    assert_eq!(faces, vec![2, 4, 2, 2, 2]);
}

#[test]
fn mirrored_chart_detected() {
    let c = charts("cube_uv_mirrored.obj");
    assert_eq!(c.num_flipped_faces(), 2);
    let mirrored: Vec<usize> =
        c.charts().iter().filter(|ch| ch.mirrored).map(|ch| ch.faces).collect();
    assert_eq!(mirrored, vec![2]);
    assert_eq!(c.num_faces_against_chart(), 0);
}

#[test]
fn flipped_uv_triangle_detected() {
    let c = charts("uv_fold.obj");
    assert_eq!(c.charts().len(), 1);
    assert_eq!(c.num_seam_edges(), 0);
    assert_eq!(c.num_flipped_faces(), 1);
    assert_eq!(c.num_faces_against_chart(), 1);
    assert!(c.signed_area(grainline::mesh::FaceId(1)) < 0.0);
}
