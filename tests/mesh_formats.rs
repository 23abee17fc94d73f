//! Issue 14, item 4: STL (binary and ASCII) and PLY (ASCII, binary little- and big-endian) as
//! input. Hand-written files with counts derived by hand, the same part in every format against
//! the OBJ loader, binary files written here byte by byte (independently of the reader), the
//! shared corpus converted to binary STL, and bad input: typed errors naming the file and the
//! element, never a panic.

mod common;

use std::path::{Path, PathBuf};

use grainline::mesh::load::{load_mesh, load_obj, LoadOptions, LoadedMesh, MeshFormat};
use grainline::mesh::Mesh;
use grainline::Error;

fn data(name: &str) -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("tests/data").join(name)
}

fn dir(name: &str) -> PathBuf {
    let d = std::env::temp_dir().join(format!("grainline-formats-{}-{name}", std::process::id()));
    let _ = std::fs::remove_dir_all(&d);
    std::fs::create_dir_all(&d).unwrap();
    d
}

fn load(p: &Path) -> LoadedMesh {
    load_mesh(p, &LoadOptions::default()).unwrap_or_else(|e| panic!("{}: {e}", p.display()))
}

/// The faces as position triples: geometry independent of vertex numbering.
fn triangles(m: &Mesh) -> Vec<[[f64; 3]; 3]> {
    m.faces.iter().map(|f| f.map(|v| m.positions[v as usize].into())).collect()
}

/// A binary STL written field by field: 80-byte header, u32 count, 50 bytes per triangle.
fn binary_stl(header: &[u8], tris: &[[[f32; 3]; 3]]) -> Vec<u8> {
    let mut b = vec![b' '; 80];
    b[..header.len()].copy_from_slice(header);
    b.extend_from_slice(&(tris.len() as u32).to_le_bytes());
    for t in tris {
        b.extend_from_slice(&[0u8; 12]); // facet normal, ignored by readers
        for v in t {
            for c in v {
                b.extend_from_slice(&c.to_le_bytes());
            }
        }
        b.extend_from_slice(&[0u8; 2]);
    }
    b
}

const TETRA: [[[f32; 3]; 3]; 4] = [
    [[0.0, 0.0, 0.0], [0.0, 1.0, 0.0], [1.0, 0.0, 0.0]],
    [[0.0, 0.0, 0.0], [1.0, 0.0, 0.0], [0.0, 0.0, 1.0]],
    [[0.0, 0.0, 0.0], [0.0, 0.0, 1.0], [0.0, 1.0, 0.0]],
    [[1.0, 0.0, 0.0], [0.0, 1.0, 0.0], [0.0, 0.0, 1.0]],
];

#[test]
fn item4_ascii_stl_tetrahedron_is_welded_to_four_vertices() {
    let m = load(&data("tetrahedron.stl"));
    assert_eq!(m.report.format, MeshFormat::Stl);
    // 4 facets × 3 unshared vertices = 12 in the file; 4 distinct positions (−0 equals 0).
    assert_eq!((m.report.file_vertices, m.report.welded_vertices), (12, 8));
    assert_eq!((m.mesh.num_vertices(), m.mesh.num_faces()), (4, 4));
    assert_eq!(m.report.face_index, vec![1, 2, 3, 4]);
    assert_eq!(m.report.face_line, vec![2, 9, 16, 23]);
    assert!(m.mesh.uv.is_none() && m.mesh.normals.is_none());
}

#[test]
fn item4_binary_stl_with_a_solid_header_is_read_as_binary() {
    let d = dir("solid-header");
    let p = d.join("tetra.stl");
    // The header starts with "solid" as many exporters write it; the size is 84 + 50·4.
    std::fs::write(&p, binary_stl(b"solid exported by a CAD system", &TETRA)).unwrap();
    let m = load(&p);
    assert_eq!((m.mesh.num_vertices(), m.mesh.num_faces()), (4, 4));
    assert_eq!(m.report.welded_vertices, 8);
    // Also under another extension: a binary STL is recognised by its size and bytes.
    let q = d.join("tetra.bin");
    std::fs::copy(&p, &q).unwrap();
    assert_eq!(load(&q).report.format, MeshFormat::Stl);
}

#[test]
fn item4_stl_weld_tolerance_is_the_obj_one() {
    let d = dir("weld-tol");
    let mut t = TETRA;
    t[3][2] = [0.0, 0.0, 1.001]; // one corner off by 1e-3
    let p = d.join("t.stl");
    std::fs::write(&p, binary_stl(b"", &t)).unwrap();
    // Exact weld: the stray corner stays a vertex of its own (5 vertices, an open mesh).
    let exact = load_mesh(&p, &LoadOptions::default().tolerant()).unwrap();
    assert_eq!(exact.mesh.num_vertices(), 5);
    // --weld 0.01 (the OBJ option) joins it.
    let opts = LoadOptions { weld: Some(0.01), ..LoadOptions::default() };
    let welded = load_mesh(&p, &opts).unwrap();
    assert_eq!((welded.mesh.num_vertices(), welded.report.welded_vertices), (4, 8));
}

#[test]
fn item4_ply_ascii_reads_polygons_uvs_and_normals() {
    let m = load(&data("tetrahedron.ply"));
    assert_eq!(m.report.format, MeshFormat::Ply);
    assert_eq!((m.mesh.num_vertices(), m.mesh.num_faces(), m.report.welded_vertices), (4, 4, 0));
    assert_eq!(m.report.face_line, vec![15, 16, 17, 18]);

    let q = load(&data("square_uv.ply"));
    // One quad split into (0 1 2), (0 2 3); the edge element and the colour are skipped.
    assert_eq!(q.mesh.faces, vec![[0, 1, 2], [0, 2, 3]]);
    assert_eq!(q.report.polygons_split, 1);
    let uv = q.mesh.uv.as_ref().expect("s t become UVs");
    let got: Vec<[f64; 2]> = (0..2).flat_map(|f| uv.face(f)).map(|t| t.into()).collect();
    let want = [[0.0, 0.0], [1.0, 0.0], [1.0, 0.5], [0.0, 0.0], [1.0, 0.5], [0.0, 0.5]];
    assert_eq!(got, want);
    let n = q.mesh.normals.as_ref().expect("nx ny nz become normals");
    assert!(n.values.iter().all(|v| v == &nalgebra::Vector3::z()));
}

/// A binary PLY written field by field: float x y z, uchar red (skipped), float u v when
/// `with_uv`; faces as `uchar` count + `int` indices; an `edge` element after them.
fn binary_ply(big: bool, with_uv: bool, pos: &[[f32; 3]], faces: &[Vec<i32>]) -> Vec<u8> {
    let enc = if big { "binary_big_endian" } else { "binary_little_endian" };
    let uvp = if with_uv { "property float u\nproperty float v\n" } else { "" };
    let mut b = format!(
        "ply\nformat {enc} 1.0\nelement vertex {}\nproperty float x\nproperty float y\n\
         property float z\nproperty uchar red\n{uvp}element face {}\n\
         property list uchar int vertex_indices\nelement edge 1\nproperty short a\n\
         property short b\nend_header\n",
        pos.len(),
        faces.len()
    )
    .into_bytes();
    let f32b = |x: f32| if big { x.to_be_bytes() } else { x.to_le_bytes() };
    for p in pos {
        for &c in p {
            b.extend_from_slice(&f32b(c));
        }
        b.push(7);
        if with_uv {
            b.extend_from_slice(&f32b(p[0] * 0.5));
            b.extend_from_slice(&f32b(p[1] * 0.5));
        }
    }
    for f in faces {
        b.push(f.len() as u8);
        for &i in f {
            b.extend_from_slice(&if big { i.to_be_bytes() } else { i.to_le_bytes() });
        }
    }
    b.extend_from_slice(&[0, 1, 0, 2]);
    b
}

const TETRA_V: [[f32; 3]; 4] = [[0.0, 0.0, 0.0], [1.0, 0.0, 0.0], [0.0, 1.0, 0.0], [0.0, 0.0, 1.0]];

fn tetra_faces() -> Vec<Vec<i32>> {
    vec![vec![0, 2, 1], vec![0, 1, 3], vec![0, 3, 2], vec![1, 2, 3]]
}

#[test]
fn item4_the_same_part_in_obj_stl_and_ply_has_the_same_geometry() {
    let d = dir("same-part");
    let obj = load_obj(&data("tetrahedron.obj"), &LoadOptions::default()).unwrap().mesh;
    let want = triangles(&obj);
    let bin_stl = d.join("t.stl");
    std::fs::write(&bin_stl, binary_stl(b"", &TETRA)).unwrap();
    let mut paths = vec![data("tetrahedron.stl"), bin_stl, data("tetrahedron.ply")];
    for (big, uv) in [(false, false), (true, false), (false, true), (true, true)] {
        let p = d.join(format!("t-{big}-{uv}.ply"));
        std::fs::write(&p, binary_ply(big, uv, &TETRA_V, &tetra_faces())).unwrap();
        paths.push(p);
    }
    for p in &paths {
        let m = load(p);
        assert_eq!(triangles(&m.mesh), want, "{}", p.display());
        assert_eq!(m.mesh.num_vertices(), obj.num_vertices(), "{}", p.display());
    }
    // The binary PLY with u v: UV = half of (x, y) at every corner, as written.
    let m = load(&paths[5]);
    let uv = m.mesh.uv.as_ref().expect("u v");
    for f in 0..m.mesh.num_faces() {
        for (k, t) in uv.face(f).iter().enumerate() {
            let p = m.mesh.positions[m.mesh.faces[f][k] as usize];
            assert_eq!((t.x, t.y), (p.x * 0.5, p.y * 0.5));
        }
    }
}

#[test]
fn item4_every_shared_mesh_reads_back_from_binary_stl_with_the_obj_counts() {
    let names = [
        "blub_quadrangulated.obj",
        "fandisk.obj",
        "oloid4096_tri.obj",
        "paper-crumpled2.obj",
        "rocker-arm.obj",
        "spot_triangulated.obj",
        "stanford-bunny.obj",
        "teapot.obj",
    ];
    let d = dir("corpus");
    for name in names {
        let Some(path) = common::shared_mesh(name) else { return };
        // The OBJ welded exactly, as the STL reader welds (a no-op for a well-formed OBJ).
        let opts = LoadOptions { weld: Some(0.0), ..LoadOptions::default() }.tolerant();
        let obj = load_obj(&path, &opts).unwrap().mesh;
        // STL stores f32: distinct OBJ positions must stay distinct in f32 for the counts to
        // agree; count the distinct rounded positions independently.
        let mut keys: Vec<[u32; 3]> = obj
            .positions
            .iter()
            .map(|p| [p.x, p.y, p.z].map(|c| (c as f32 + 0.0).to_bits()))
            .collect();
        keys.sort_unstable();
        keys.dedup();
        let tris: Vec<[[f32; 3]; 3]> = obj
            .faces
            .iter()
            .map(|f| f.map(|v| obj.positions[v as usize].map(|c| c as f32).into()))
            .collect();
        let p = d.join(name.replace(".obj", ".stl"));
        std::fs::write(&p, binary_stl(b"solid converted for a test", &tris)).unwrap();
        let stl = load_mesh(&p, &LoadOptions::default().tolerant()).unwrap();
        assert_eq!(stl.report.file_vertices, 3 * obj.num_faces(), "{name}");
        assert_eq!(stl.mesh.num_vertices(), keys.len(), "{name}: distinct f32 positions");
        assert_eq!(stl.mesh.num_vertices(), obj.num_vertices(), "{name}: vertices");
        assert_eq!(
            stl.mesh.num_faces() + stl.report.dropped_degenerate_faces,
            obj.num_faces(),
            "{name}: faces"
        );
        assert_eq!(stl.report.dropped_degenerate_faces, 0, "{name}: no face collapses in f32");
        let _ = std::fs::remove_file(&p);
    }
}

// ---- bad input ----------------------------------------------------------------------------

fn error(p: &Path) -> Error {
    match load_mesh(p, &LoadOptions::default()) {
        Ok(_) => panic!("{}: expected an error", p.display()),
        Err(e) => e,
    }
}

fn write(d: &Path, name: &str, bytes: &[u8]) -> PathBuf {
    let p = d.join(name);
    std::fs::write(&p, bytes).unwrap();
    p
}

/// One line, naming the file, with every expected fragment.
fn says(e: &Error, p: &Path, parts: &[&str]) {
    let s = e.to_string();
    assert_eq!(s.lines().count(), 1, "{s}");
    assert!(s.contains(&p.display().to_string()), "names the file: {s}");
    for part in parts {
        assert!(s.contains(part), "{part:?} in: {s}");
    }
}

#[test]
fn item4_bad_binary_stl_gives_typed_errors() {
    let d = dir("bad-binary-stl");
    let good = binary_stl(b"solid x", &TETRA);
    // Truncated inside triangle 2 (84 + 50 + 20 bytes).
    let p = write(&d, "trunc.stl", &good[..154]);
    let e = error(&p);
    assert!(matches!(e, Error::BinaryFile { offset: 80, .. }), "{e:?}");
    says(
        &e,
        &p,
        &["truncated", "announces 4 triangles", "room for 1 triangle", "incomplete triangle 2"],
    );
    // A count far beyond the file: refused from the size, nothing allocated for it.
    let mut absurd = good.clone();
    absurd[80..84].copy_from_slice(&u32::MAX.to_le_bytes());
    absurd[..5].copy_from_slice(b"xxxxx");
    let p = write(&d, "absurd.stl", &absurd);
    says(&error(&p), &p, &["announces 4294967295 triangles"]);
    // NaN in triangle 3, vertex 2: byte 84 + 2·50 + 12 + 12.
    let mut t = TETRA;
    t[2][1][0] = f32::NAN;
    let p = write(&d, "nan.stl", &binary_stl(b"", &t));
    let e = error(&p);
    assert!(matches!(e, Error::BinaryFile { offset: 208, .. }), "{e:?}");
    says(&e, &p, &["triangle 3: vertex 2 has a non-finite"]);
    // Too short for a header and not ASCII.
    let p = write(&d, "short.stl", b"\x00\x01\x02");
    says(&error(&p), &p, &["too short for a binary STL"]);
    // Zero triangles.
    let p = write(&d, "empty.stl", &binary_stl(b"", &[]));
    assert!(matches!(error(&p), Error::EmptyMesh { .. }));
    // Two triangles on one edge with a third: non-manifold, named by triangle and position.
    let fin = [TETRA[0], TETRA[1], [[0.0, 0.0, 0.0], [1.0, 0.0, 0.0], [0.0, -1.0, 0.0]]];
    let p = write(&d, "fin.stl", &binary_stl(b"", &fin));
    let e = error(&p);
    assert!(matches!(e, Error::NonManifold { .. }), "{e:?}");
    says(&e, &p, &["non-manifold edge", "(0, 0, 0)", "(1, 0, 0)", "triangle 1", "triangle 2"]);
    assert!(e.to_string().contains("triangle 3"), "{e}");
}

#[test]
fn item4_bad_ascii_stl_gives_typed_errors_with_lines() {
    let d = dir("bad-ascii-stl");
    let text = std::fs::read_to_string(data("tetrahedron.stl")).unwrap();
    // Truncated in facet 2.
    let cut: String = text.lines().take(12).map(|l| format!("{l}\n")).collect();
    let p = write(&d, "trunc.stl", cut.as_bytes());
    let e = error(&p);
    assert!(matches!(e, Error::Parse { line: 13, .. }), "{e:?}");
    says(&e, &p, &["unexpected end of file in facet 2"]);
    // A vertex with two coordinates: the next keyword is not a number.
    let p =
        write(&d, "short-vertex.stl", text.replacen("vertex 0 1 0", "vertex 0 1", 1).as_bytes());
    let e = error(&p);
    assert!(matches!(e, Error::Parse { line: 6, .. }), "{e:?}");
    says(&e, &p, &["expected a number (vertex 2) in facet 1", "\"vertex\""]);
    // NaN, on its line.
    let p = write(&d, "nan.stl", text.replacen("vertex 1 0 0", "vertex nan 0 0", 1).as_bytes());
    let e = error(&p);
    assert!(matches!(e, Error::NonFinite { line: 6, .. }), "{e:?}");
    says(&e, &p, &["facet 1: vertex 3 has a non-finite"]);
    // A coordinate beyond the bound.
    let p = write(&d, "huge.stl", text.replacen("vertex 1 0 0", "vertex 1e300 0 0", 1).as_bytes());
    says(&error(&p), &p, &["beyond ±1e75"]);
    // A facet of two vertices.
    let two = text.replacen("      vertex 1 0 0\n", "", 1);
    let p = write(&d, "two.stl", two.as_bytes());
    says(&error(&p), &p, &["facet 1 has 2 vertices"]);
}

#[test]
fn item4_bad_ply_gives_typed_errors() {
    let d = dir("bad-ply");
    let text = std::fs::read_to_string(data("tetrahedron.ply")).unwrap();
    // An absurd count: refused from the header, before anything is allocated for it.
    let p = write(
        &d,
        "absurd.ply",
        text.replace("element vertex 4", "element vertex 2000000000").as_bytes(),
    );
    let e = error(&p);
    assert!(matches!(e, Error::Parse { line: 4, .. }), "{e:?}");
    says(&e, &p, &["\"vertex\" with 2000000000 entries", "truncated file, or a wrong count"]);
    let p = write(
        &d,
        "over.ply",
        text.replace("element vertex 4", "element vertex 99999999999").as_bytes(),
    );
    says(&error(&p), &p, &["more than the 3000000000"]);
    // A face index out of range, on its line.
    let p = write(&d, "index.ply", text.replace("3 1 2 3", "3 1 2 4").as_bytes());
    let e = error(&p);
    assert!(matches!(e, Error::IndexOutOfRange { line: 18, .. }), "{e:?}");
    says(&e, &p, &["face element 3: vertex index 2 is 4; the file has 4 vertices"]);
    // NaN.
    let p = write(&d, "nan.ply", text.replacen("1 0 0", "1 nan 0", 1).as_bytes());
    says(&error(&p), &p, &["vertex element 1 has a non-finite"]);
    // A count larger than the data: the last face is missing.
    let p = write(&d, "short.ply", text.replace("3 1 2 3\n", "").as_bytes());
    says(&error(&p), &p, &["face element 3", "missing (truncated file?)"]);
    // More data than the counts say.
    let p = write(&d, "long.ply", format!("{text}3 0 1 2\n").as_bytes());
    says(&error(&p), &p, &["after the last element"]);
    // A face of two vertices, a bad header line, a missing coordinate property.
    let p = write(&d, "two.ply", text.replace("3 0 3 2", "2 0 3").as_bytes());
    says(&error(&p), &p, &["face element 2 has 2 vertex indices"]);
    let p =
        write(&d, "header.ply", text.replace("property float y", "property flaot y").as_bytes());
    says(&error(&p), &p, &["unknown property type \"flaot\""]);
    let p = write(&d, "noz.ply", text.replace("property float z\n", "").as_bytes());
    says(&error(&p), &p, &["no property \"z\""]);
    // Binary: truncated inside a face, and an index out of range, named by element and byte.
    let good = binary_ply(false, false, &TETRA_V, &tetra_faces());
    let p = write(&d, "trunc.ply", &good[..good.len() - 12]);
    let e = error(&p);
    assert!(matches!(e, Error::BinaryFile { .. }), "{e:?}");
    says(&e, &p, &["face element 3", "truncated file"]);
    let mut faces = tetra_faces();
    faces[1][2] = -1;
    let p = write(&d, "neg.ply", &binary_ply(true, false, &TETRA_V, &faces));
    says(&error(&p), &p, &["face element 1: vertex index 2 is negative or too large"]);
    // The face count of a binary file far beyond its bytes.
    let end = good.windows(11).position(|w| w == b"end_header\n").unwrap();
    let head = String::from_utf8(good[..end].to_vec()).unwrap();
    let mut absurd = head.replace("element face 4", "element face 900000000").into_bytes();
    absurd.extend_from_slice(&good[end..]);
    let p = write(&d, "absurd-bin.ply", &absurd);
    says(&error(&p), &p, &["\"face\" with 900000000 entries"]);
}

#[test]
fn item4_cli_reads_stl_and_ply_and_names_the_file_in_errors() {
    let d = dir("cli");
    let p = write(&d, "t.stl", &binary_stl(b"solid t", &TETRA));
    let out = std::process::Command::new(env!("CARGO_BIN_EXE_grainline"))
        .args(["inspect", "--json"])
        .arg(&p)
        .output()
        .unwrap();
    assert!(out.status.success(), "{}", String::from_utf8_lossy(&out.stderr));
    let v: serde_json::Value = serde_json::from_slice(&out.stdout).unwrap();
    assert_eq!((v["format"].as_str(), v["vertices"].as_u64()), (Some("stl"), Some(4)));
    assert_eq!(v["problems"]["welded_vertices"], 8);
    // The smallest angle of the tetrahedron: 45° (its faces are right isosceles and
    // equilateral triangles), so no slivers; its 6 edges all have dihedral angles > 40°.
    assert!((v["quality"]["min_angle_deg"].as_f64().unwrap() - 45.0).abs() < 1e-9);
    assert_eq!(v["quality"]["slivers"], 0);
    assert_eq!(v["quality"]["crease_edges"], 6);
    let bad = write(&d, "bad.ply", b"ply\nformat ascii 1.0\nelement vertex 1\nproperty float x\n");
    let out = std::process::Command::new(env!("CARGO_BIN_EXE_grainline"))
        .arg("inspect")
        .arg(&bad)
        .output()
        .unwrap();
    let e = String::from_utf8_lossy(&out.stderr);
    assert_eq!(out.status.code(), Some(1));
    assert_eq!(e.trim_end().lines().count(), 1, "{e}");
    assert!(e.contains(&format!("{}:5:", bad.display())) && e.contains("no `end_header`"), "{e}");
    assert!(!e.contains("panicked"), "{e}");
}
