//! Loading and validating OBJ files: small hand-made files under tests/data whose contents are
//! known by construction.

use std::path::PathBuf;

use grainline::mesh::load::{load_obj, DegeneratePolicy, LoadOptions, LoadedMesh};
use grainline::mesh::Units;
use grainline::Error;

fn data(name: &str) -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("tests/data").join(name)
}

fn load(name: &str) -> grainline::Result<LoadedMesh> {
    load_obj(&data(name), &LoadOptions::default())
}

fn err(name: &str) -> Error {
    match load(name) {
        Ok(_) => panic!("{name} should not load"),
        Err(e) => e,
    }
}

/// The message is one line and names the file.
fn one_line(e: &Error, name: &str) -> String {
    let s = e.to_string();
    assert!(!s.contains('\n'), "multi-line message: {s}");
    assert!(s.contains(name), "message does not name {name}: {s}");
    s
}

#[test]
fn quad_is_triangulated_with_uv_and_normals() {
    let m = load("quad.obj").unwrap();
    assert_eq!(m.mesh.num_vertices(), 4);
    assert_eq!(m.mesh.faces, vec![[0, 1, 2], [0, 2, 3]]);
    let uv = m.mesh.uv.as_ref().unwrap();
    assert_eq!(uv.face(1)[2], nalgebra::Vector2::new(0.0, 1.0));
    let n = m.mesh.normals.as_ref().unwrap();
    assert_eq!(n.values.len(), 1);
    assert_eq!(n.corners, vec![[0, 0, 0], [0, 0, 0]]);
    assert_eq!(m.report.polygons_split, 1);
    assert!((m.mesh.area() - 1.0).abs() < 1e-12);
    assert_eq!(m.report.face_line, vec![11, 11]);
}

#[test]
fn pentagon_fan_and_unreferenced_vertices_keep_file_order() {
    let m = load("pentagon_unreferenced.obj").unwrap();
    assert_eq!(m.mesh.num_vertices(), 5);
    assert_eq!(m.mesh.faces, vec![[0, 1, 2], [0, 2, 3], [0, 3, 4]]);
    assert_eq!(m.report.unreferenced_vertices, 2);
    assert_eq!(m.report.file_vertices, 7);
    assert_eq!(m.report.source_vertex, vec![2, 3, 4, 5, 6]);
    assert!((m.mesh.positions[0].x - 1.0).abs() < 1e-6);
}

#[test]
fn two_objects_merged_or_picked() {
    let all = load("two_objects.obj").unwrap();
    assert_eq!(all.mesh.num_faces(), 2);
    assert_eq!(all.report.objects, vec!["first", "second"]);
    let opts = LoadOptions { object: Some("second".into()), ..Default::default() };
    let second = load_obj(&data("two_objects.obj"), &opts).unwrap();
    assert_eq!(second.mesh.num_faces(), 1);
    assert_eq!(second.mesh.positions[0].x, 5.0);
    assert_eq!(second.report.source_vertex, vec![4, 5, 6]);
    assert_eq!(second.report.unreferenced_vertices, 3);
    let opts = LoadOptions { object: Some("third".into()), ..Default::default() };
    let e = load_obj(&data("two_objects.obj"), &opts).unwrap_err();
    assert!(matches!(e, Error::ObjectNotFound { .. }));
    let s = one_line(&e, "two_objects.obj");
    assert!(s.contains("first, second"), "{s}");
}

#[test]
fn units_and_scale() {
    let opts = LoadOptions { units: Units::Cm, scale: 2.5, ..Default::default() };
    let m = load_obj(&data("tetrahedron.obj"), &opts).unwrap();
    assert_eq!(m.mesh.units, Units::Cm);
    assert_eq!(m.mesh.positions[1].x, 2.5);
    let bad = LoadOptions { scale: f64::NAN, ..Default::default() };
    assert!(matches!(load_obj(&data("tetrahedron.obj"), &bad), Err(Error::InvalidArgument { .. })));
}

#[test]
fn nonmanifold_edge_is_refused_naming_it() {
    let e = err("fin.obj");
    assert!(matches!(e, Error::NonManifold { .. }), "{e}");
    let s = one_line(&e, "fin.obj");
    assert!(s.contains("vertices 1 and 2") && s.contains("line 6"), "{s}");
    let opts = LoadOptions { allow_nonmanifold: true, ..Default::default() };
    let m = load_obj(&data("fin.obj"), &opts).unwrap();
    assert_eq!(m.report.nonmanifold_edges, 1);
}

#[test]
fn nonmanifold_vertex_is_refused_naming_it() {
    let e = err("bowtie.obj");
    assert!(matches!(e, Error::NonManifold { .. }), "{e}");
    assert!(one_line(&e, "bowtie.obj").contains("vertex 1"));
    let opts = LoadOptions { allow_nonmanifold: true, ..Default::default() };
    let m = load_obj(&data("bowtie.obj"), &opts).unwrap();
    assert_eq!(m.report.nonmanifold_vertices, 1);
}

#[test]
fn inconsistent_orientation_names_the_face_pair() {
    let e = err("flipped_face.obj");
    assert!(matches!(e, Error::InconsistentOrientation { .. }), "{e}");
    let s = one_line(&e, "flipped_face.obj");
    assert!(s.contains("line 5 and line 6") && s.contains("vertex 2 to vertex 3"), "{s}");
}

#[test]
fn nan_coordinate_names_its_line() {
    let e = err("nan.obj");
    assert!(matches!(e, Error::NonFinite { line: 3, .. }), "{e}");
    assert!(one_line(&e, "nan.obj").contains("nan.obj:3:"));
}

#[test]
fn index_out_of_range_names_its_line() {
    let e = err("out_of_range.obj");
    assert!(matches!(e, Error::IndexOutOfRange { line: 5, .. }), "{e}");
    assert!(one_line(&e, "out_of_range.obj").contains("v 9"));
}

#[test]
fn truncated_lines_name_their_line() {
    assert!(matches!(err("truncated.obj"), Error::Parse { line: 3, .. }));
    assert!(matches!(err("truncated_face.obj"), Error::Parse { line: 4, .. }));
    let e = err("junk.obj");
    assert!(matches!(e, Error::Parse { line: 3, .. }), "{e}");
    let e = err("bad_number.obj");
    assert!(matches!(e, Error::Parse { line: 3, .. }), "{e}");
    one_line(&e, "bad_number.obj");
}

/// Issue 46: `v x y z r g b [a]` (scan exports) and `v x y z w` load with the right
/// positions whichever reader reads the numbers; other counts, a `w` of zero or not finite and
/// a colour that is not a number are refused naming the file, the line and what was found.
#[test]
fn vertex_colours_and_weights_load_and_bad_counts_name_their_line() {
    use grainline::mesh::load::{load_obj_with, ObjParser};
    use nalgebra::Vector3;
    for parser in [ObjParser::Auto, ObjParser::Tobj, ObjParser::Parallel] {
        let m = load_obj_with(&data("vertex_colours.obj"), &LoadOptions::default(), parser)
            .unwrap_or_else(|e| panic!("{parser:?}: {e}"));
        let want = [[0.0, 0.0, 0.0], [2.0, 0.0, 0.0], [0.0, 2.0, 0.0], [0.0, 0.0, 1.0]];
        let want: Vec<Vector3<f64>> = want.iter().map(|&p| Vector3::from(p)).collect();
        assert_eq!(m.mesh.positions, want, "{parser:?}");
        assert_eq!(m.mesh.faces.len(), 4);
    }
    let dir = std::env::temp_dir().join(format!("grainline-colours-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    for (line, wanted) in [
        ("v 0 1 0 1 0", "vertex with 5 numbers; a vertex takes 3 (x y z), 4 (x y z w)"),
        ("v 0 1 0 1 0 0 1 1", "vertex with 8 numbers"),
        ("v 0 1", "vertex with 2 numbers; a vertex takes 3 (x y z), 4 (x y z w) or 6 to 7"),
        ("v 0 1 0 0.5 red 0", "bad number \"red\""),
        ("v 0 1 0 0", "vertex weight w is zero"),
        ("v 0 1 0 inf", "vertex weight w is inf"),
        ("v 0 1 0 NaN", "vertex weight w is NaN"),
    ] {
        let p = dir.join("bad.obj");
        std::fs::write(&p, format!("v 0 0 0\nv 1 0 0\n{line}\nf 1 2 3\n")).unwrap();
        for parser in [ObjParser::Tobj, ObjParser::Parallel] {
            let e = load_obj_with(&p, &LoadOptions::default(), parser).unwrap_err();
            assert!(matches!(e, Error::Parse { line: 3, .. }), "{line}: {e}");
            let s = one_line(&e, "bad.obj");
            assert!(s.contains("bad.obj:3:") && s.contains(wanted), "{line}: {s}");
        }
    }
    std::fs::remove_dir_all(&dir).unwrap();
}

#[test]
fn binary_garbage_missing_file_directory_and_empty_file() {
    let e = err("garbage.obj");
    assert!(matches!(e, Error::Parse { line: 1, .. }), "{e}");
    one_line(&e, "garbage.obj");
    let e = err("no_such_file.obj");
    assert!(matches!(e, Error::Io { .. }));
    one_line(&e, "no_such_file.obj");
    let e = load_obj(&data(""), &LoadOptions::default()).unwrap_err();
    assert!(matches!(e, Error::Io { .. }), "{e}");
    let e = err("empty.obj");
    assert!(matches!(e, Error::EmptyMesh { .. }), "{e}");
    one_line(&e, "empty.obj");
}

#[test]
fn degenerate_faces_dropped_or_refused() {
    let m = load("degenerate.obj").unwrap();
    assert_eq!(m.mesh.num_faces(), 1);
    assert_eq!(m.report.dropped_degenerate_faces, 1);
    // Vertex 4 was only used by the dropped face.
    assert_eq!(m.report.unreferenced_vertices, 1);
    let opts = LoadOptions { degenerate: DegeneratePolicy::Error, ..Default::default() };
    let e = load_obj(&data("degenerate.obj"), &opts).unwrap_err();
    assert!(matches!(e, Error::DegenerateFaces { .. }));
    assert!(one_line(&e, "degenerate.obj").contains("line 6"));
}

#[test]
fn welding_maps_to_the_first_occurrence() {
    let dir = std::env::temp_dir().join(format!("grainline-weld-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let p = dir.join("split.obj");
    // Two triangles sharing the edge (2, 3) through duplicates 4 ≈ 3 and 5 = 2.
    let text = "v 0 0 0\nv 1 0 0\nv 0 1 0\nv 0 1.0000001 0\nv 1 0 0\nv 1 1 0\nf 1 2 3\nf 5 6 4\n";
    std::fs::write(&p, text).unwrap();
    let plain = load_obj(&p, &LoadOptions::default()).unwrap();
    assert_eq!(plain.mesh.num_vertices(), 6);
    let opts = LoadOptions { weld: Some(1e-5), ..Default::default() };
    let w = load_obj(&p, &opts).unwrap();
    assert_eq!(w.mesh.num_vertices(), 4);
    assert_eq!(w.report.welded_vertices, 2);
    assert_eq!(w.report.source_vertex, vec![1, 2, 3, 6]);
    assert_eq!(w.mesh.faces, vec![[0, 1, 2], [1, 3, 2]]);
    std::fs::remove_dir_all(&dir).unwrap();
}
