//! `grainline inspect` as a user runs it: the built binary on good and bad files.

use std::path::PathBuf;
use std::process::{Command, Output};

fn data(name: &str) -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("tests/data").join(name)
}

fn inspect(args: &[&str]) -> Output {
    Command::new(env!("CARGO_BIN_EXE_grainline")).arg("inspect").args(args).output().unwrap()
}

/// Non-zero exit, nothing on stdout, one error line naming the file (and the line, if given),
/// no panic.
fn fails_with_one_line(name: &str, line: Option<usize>) {
    let path = data(name);
    let out = inspect(&[path.to_str().unwrap()]);
    let err = String::from_utf8_lossy(&out.stderr);
    assert_eq!(out.status.code(), Some(1), "{name}: {err}");
    assert!(out.stdout.is_empty(), "{name}");
    assert!(!err.contains("panicked"), "{name}: {err}");
    assert_eq!(err.trim_end().lines().count(), 1, "{name}: {err}");
    assert!(err.contains(name), "{name}: {err}");
    if let Some(l) = line {
        assert!(err.contains(&format!("{name}:{l}:")), "{name}: {err}");
    }
}

#[test]
fn bad_files_fail_with_one_line() {
    fails_with_one_line("truncated.obj", Some(3));
    fails_with_one_line("nan.obj", Some(3));
    fails_with_one_line("out_of_range.obj", Some(5));
    fails_with_one_line("junk.obj", Some(3));
    fails_with_one_line("bad_number.obj", Some(3));
    fails_with_one_line("garbage.obj", Some(1));
    fails_with_one_line("empty.obj", None);
    fails_with_one_line("no_such_file.obj", None);
}

#[test]
fn directory_fails() {
    let out = inspect(&[data("").to_str().unwrap()]);
    assert_eq!(out.status.code(), Some(1));
    assert!(!String::from_utf8_lossy(&out.stderr).contains("panicked"));
}

#[test]
fn nonmanifold_mesh_is_reported_not_refused() {
    let out = inspect(&[data("fin.obj").to_str().unwrap(), "--json"]);
    assert!(out.status.success(), "{}", String::from_utf8_lossy(&out.stderr));
    let v: serde_json::Value = serde_json::from_slice(&out.stdout).unwrap();
    assert_eq!(v["problems"]["nonmanifold_edges"], 1);
    assert_eq!(v["genus"], serde_json::Value::Null);
}

#[test]
fn json_fields_on_a_cube_atlas() {
    let out = inspect(&[data("cube_uv_mirrored.obj").to_str().unwrap(), "--json", "--units", "cm"]);
    assert!(out.status.success());
    let v: serde_json::Value = serde_json::from_slice(&out.stdout).unwrap();
    assert_eq!(v["format_version"], 1);
    assert_eq!(v["units"], "cm");
    assert_eq!((v["vertices"].as_u64(), v["faces"].as_u64()), (Some(8), Some(12)));
    assert_eq!(v["euler_characteristic"], 2);
    assert_eq!(v["genus"], 0);
    assert_eq!(v["bounding_box"]["size"], serde_json::json!([1.0, 1.0, 1.0]));
    assert_eq!(v["uv"]["charts"], 5);
    assert_eq!(v["uv"]["seam_edges"], 11);
    assert_eq!(v["uv"]["flipped_faces"], 2);
    assert_eq!(v["uv"]["mirrored_charts"][0]["faces"], 2);
}

#[test]
fn text_output_names_units() {
    let out = inspect(&[data("disk.obj").to_str().unwrap()]);
    assert!(out.status.success());
    let s = String::from_utf8_lossy(&out.stdout);
    assert!(s.contains(" mm") && s.contains("1 loop(s)"), "{s}");
}

/// An OBJ of unit squares, square `i` at x = 2i in 3D (so each is its own chart), two
/// triangles each, with UV square `[lo, lo + 1]²`; a mirrored square has its u reversed
/// (both triangles flipped).
fn squares_obj(name: &str, squares: &[([f64; 2], bool)]) -> PathBuf {
    use std::fmt::Write;
    let mut s = String::new();
    for (i, &([u0, v0], mirrored)) in squares.iter().enumerate() {
        let x = 2.0 * i as f64;
        for (dx, dy) in [(0.0, 0.0), (1.0, 0.0), (1.0, 1.0), (0.0, 1.0)] {
            let _ = writeln!(s, "v {} {dy} 0", x + dx);
            let du = if mirrored { 1.0 - dx } else { dx };
            let _ = writeln!(s, "vt {} {}", u0 + du, v0 + dy);
        }
        let b = 4 * i + 1;
        let _ = writeln!(s, "f {b}/{b} {}/{} {}/{}", b + 1, b + 1, b + 2, b + 2);
        let _ = writeln!(s, "f {b}/{b} {}/{} {}/{}", b + 2, b + 2, b + 3, b + 3);
    }
    let path =
        std::env::temp_dir().join(format!("grainline-inspect-{}-{name}.obj", std::process::id()));
    std::fs::write(&path, s).unwrap();
    path
}

fn inspect_json(path: &std::path::Path) -> serde_json::Value {
    let out = inspect(&[path.to_str().unwrap(), "--json"]);
    assert!(out.status.success(), "{}", String::from_utf8_lossy(&out.stderr));
    serde_json::from_slice(&out.stdout).unwrap()
}

#[test]
fn overlapping_and_mirrored_charts_are_reported() {
    // A mirrored square over the middle of another: they share the UV square [0.5, 1]².
    let p = squares_obj("mirrored_overlap", &[([0.0, 0.0], false), ([0.5, 0.5], true)]);
    let v = inspect_json(&p);
    assert_eq!(v["uv"]["charts"], 2);
    assert_eq!(v["uv"]["overlapping_charts"], serde_json::json!([[0, 1]]));
    assert_eq!(v["uv"]["overlapping_chart_pairs"], 1);
    assert_eq!(v["uv"]["flipped_faces"], 2);
    assert_eq!(v["uv"]["mirrored_chart_count"], 1);
    assert_eq!(v["uv"]["charts_with_flipped_faces"], 1);
    assert_eq!(v["uv"]["mirrored_charts"][0]["chart"], 1);
    let out = inspect(&[p.to_str().unwrap()]);
    let text = String::from_utf8_lossy(&out.stdout);
    assert!(text.contains("overlapping charts: 1 pair(s) — #0 and #1"), "{text}");
    assert!(text.contains("mirrored charts: 1 — #1 (2 faces)"), "{text}");
    let _ = std::fs::remove_file(&p);

    // Squares 0 and 1 share only the corner [0.9, 1]², where no triangle's centroid lies in
    // the other chart; square 2 is far away.
    let p = squares_obj(
        "corner_overlap",
        &[([0.0, 0.0], false), ([0.9, 0.9], false), ([5.0, 5.0], false)],
    );
    let v = inspect_json(&p);
    assert_eq!(v["uv"]["charts"], 3);
    assert_eq!(v["uv"]["overlapping_charts"], serde_json::json!([[0, 1]]));
    assert_eq!(v["uv"]["mirrored_chart_count"], 0);
    assert_eq!(v["uv"]["charts_with_flipped_faces"], 0);
    let _ = std::fs::remove_file(&p);
}

#[test]
fn charts_packed_edge_to_edge_do_not_overlap() {
    // Square 1 touches square 0 along u = 1, square 2 (mirrored) along v = 1; they share
    // edges in UV but no interior point.
    let p = squares_obj("packed", &[([0.0, 0.0], false), ([1.0, 0.0], false), ([0.0, 1.0], true)]);
    let v = inspect_json(&p);
    assert_eq!(v["uv"]["charts"], 3);
    assert_eq!(v["uv"]["overlapping_charts"], serde_json::json!([]));
    assert_eq!(v["uv"]["overlapping_chart_pairs"], 0);
    assert_eq!(v["uv"]["mirrored_chart_count"], 1);
    let out = inspect(&[p.to_str().unwrap()]);
    assert!(String::from_utf8_lossy(&out.stdout).contains("overlapping charts: none"));
    let _ = std::fs::remove_file(&p);
    // The cube atlas of tests/data packs its charts edge to edge as well.
    let v = inspect_json(&data("cube_uv_mirrored.obj"));
    assert_eq!(v["uv"]["overlapping_chart_pairs"], 0);
}
