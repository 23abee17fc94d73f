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
