//! Loading limits (issue 15): work linear in the file whatever the vertex valences (item 13),
//! coordinates whose squares overflow refused (item 14).

use std::io::Write;
use std::path::Path;

use grainline::mesh::halfedge::HalfEdges;
use grainline::mesh::load::{load_obj, LoadOptions};
use grainline::mesh::topology::Topology;

fn write(dir: &Path, name: &str, text: &str) -> std::path::PathBuf {
    let p = dir.join(name);
    std::fs::File::create(&p).unwrap().write_all(text.as_bytes()).unwrap();
    p
}

/// A fan of `n` triangles around vertex 1 spanning 3/4 of a turn (so it stays open).
fn fan_obj(n: usize) -> String {
    let mut s = String::from("v 0 0 0\n");
    for i in 0..=n {
        let t = 1.5 * std::f64::consts::PI * i as f64 / n as f64;
        s += &format!("v {} {} 0\n", t.cos(), t.sin());
    }
    for i in 0..n {
        s += &format!("f 1 {} {}\n", i + 2, i + 3);
    }
    s
}

/// Classification work bound of `HalfEdges::classify_steps`: 2·V + 9·H.
fn linear_bound(t: &Topology) -> u64 {
    let he = t.halfedges();
    2 * he.num_vertices() as u64 + 9 * he.num_halfedges() as u64
}

#[test]
fn item13_fan_of_200k_triangles_loads_in_linear_work() {
    let n = 200_000;
    let dir = tempfile::tempdir().unwrap();
    let path = write(dir.path(), "fan.obj", &fan_obj(n));
    let m = load_obj(&path, &LoadOptions::default()).unwrap().mesh;
    assert_eq!((m.num_vertices(), m.num_faces()), (n + 2, n));
    let t = Topology::new(&m).unwrap();
    // n + 1 spokes and n rim edges; one open disc: V − E + F = (n + 2) − (2n + 1) + n = 1.
    assert_eq!(t.num_edges(), 2 * n + 1);
    assert_eq!(t.euler_characteristic(), 1);
    assert_eq!(t.num_boundary_loops(), 1);
    assert_eq!(t.boundary_loop(0).len(), n + 2);
    // A scan of the centre's out-list per edge would take ~n² = 4·10¹⁰ steps.
    let steps = t.halfedges().classify_steps();
    assert!(steps > 0 && steps <= linear_bound(&t), "{steps} > {}", linear_bound(&t));
}

#[test]
fn item13_100k_copies_of_one_face_refused_naming_lines_in_linear_work() {
    let n = 100_000;
    let dir = tempfile::tempdir().unwrap();
    let text = format!("v 0 0 0\nv 1 0 0\nv 0 1 0\n{}", "f 1 2 3\n".repeat(n));
    let path = write(dir.path(), "rep.obj", &text);
    let e = load_obj(&path, &LoadOptions::default()).unwrap_err().to_string();
    assert!(e.contains("rep.obj"), "{e}");
    assert!(e.contains("shared by 100000 faces (line 4, line 5"), "{e}");
    assert!(e.len() < 400, "the message lists a few faces, not all: {} bytes", e.len());
    // Tolerated non-manifold edges are still refused past 64 faces (issue 30, item 1).
    let e = load_obj(&path, &LoadOptions::default().tolerant()).unwrap_err().to_string();
    assert!(e.contains("rep.obj") && e.contains("limits::MAX_EDGE_FACES"), "{e}");
    let he = HalfEdges::new(3, &vec![[0, 1, 2]; n]).unwrap();
    assert_eq!((he.num_edges(), he.widest_edge().map(|w| w.1)), (3, Some(n)));
    let steps = he.classify_steps();
    let bound = 2 * he.num_vertices() as u64 + 9 * he.num_halfedges() as u64;
    assert!(steps > 0 && steps <= bound, "{steps} > {bound}");
}

/// A right triangle with legs `c` along x and y, its far vertex on line 3.
fn big_triangle(c: &str) -> String {
    format!("# legs {c}\nv 0 0 0\nv {c} 0 0\nv 0 {c} 0\nf 1 2 3\n")
}

#[test]
fn item14_coordinates_whose_products_overflow_are_refused_naming_line_and_vertex() {
    let dir = tempfile::tempdir().unwrap();
    for c in ["1e308", "-1e308", "1e200", "1e160", "1e76"] {
        let path = write(dir.path(), "big.obj", &big_triangle(c));
        for opts in [LoadOptions::default(), LoadOptions::default().tolerant()] {
            let e = load_obj(&path, &opts).unwrap_err().to_string();
            // Vertex 2 (`v c 0 0`) is on line 3; the message names the bound, not a topology.
            assert!(e.contains("big.obj:3:") && e.contains("vertex 2 "), "{c}: {e}");
            assert!(e.contains("1e75"), "{c}: {e}");
            assert!(!e.contains("manifold") && !e.contains("zero area"), "{c}: {e}");
        }
    }
}

#[test]
fn item14_bound_accepts_1e75_with_its_exact_area_and_counts_the_scale() {
    let dir = tempfile::tempdir().unwrap();
    let path = write(dir.path(), "edge.obj", &big_triangle("1e75"));
    let m = load_obj(&path, &LoadOptions::default()).unwrap().mesh;
    // Area of the right triangle with legs 1e75: 5e149, finite.
    let a = m.area();
    assert!(a.is_finite() && (a / 5e149 - 1.0).abs() < 1e-12, "{a}");
    // The same file scaled by 10 exceeds the bound.
    let opts = LoadOptions { scale: 10.0, ..LoadOptions::default() };
    let e = load_obj(&path, &opts).unwrap_err().to_string();
    assert!(e.contains("edge.obj:3:") && e.contains("scale"), "{e}");
}
