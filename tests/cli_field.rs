//! `grainline field` end to end: outputs, bad input, atomic writes.

use std::path::PathBuf;
use std::process::{Command, Output};

fn data(name: &str) -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("tests/data").join(name)
}

fn tmp(name: &str) -> PathBuf {
    let d = std::env::temp_dir().join(format!("grainline-cli-field-{}", std::process::id()));
    std::fs::create_dir_all(&d).unwrap();
    d.join(name)
}

fn field(args: &[&str]) -> Output {
    Command::new(env!("CARGO_BIN_EXE_grainline"))
        .arg("field")
        .arg("--quiet")
        .args(args)
        .output()
        .unwrap()
}

#[test]
fn writes_a_complete_field_file() {
    let out = tmp("tet.json");
    let o = field(&[
        data("tetrahedron.obj").to_str().unwrap(),
        "--light",
        "0.2,0.3,1",
        "--view",
        "0,0,1",
        "--init",
        "world:1,0,0",
        "--out",
        out.to_str().unwrap(),
    ]);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let v: serde_json::Value = serde_json::from_slice(&std::fs::read(&out).unwrap()).unwrap();
    let n = v["meta"]["vertices"].as_u64().unwrap() as usize;
    assert_eq!(n, 4);
    for key in ["position", "normal", "u", "ell", "k1", "k2", "area", "critical"] {
        assert_eq!(v[key].as_array().unwrap().len(), n, "{key}");
    }
    assert_eq!(v["meta"]["units"], "mm");
    // u is unit and tangent.
    for i in 0..n {
        let u: Vec<f64> =
            v["u"][i].as_array().unwrap().iter().map(|x| x.as_f64().unwrap()).collect();
        let nn: Vec<f64> =
            v["normal"][i].as_array().unwrap().iter().map(|x| x.as_f64().unwrap()).collect();
        let dot: f64 = u.iter().zip(&nn).map(|(a, b)| a * b).sum();
        let len: f64 = u.iter().map(|a| a * a).sum::<f64>().sqrt();
        assert!(dot.abs() < 1e-12 && (len - 1.0).abs() < 1e-12);
    }
    // The file reads back through the library's own checked reader.
    grainline::field::FieldFile::read(&out).unwrap();
}

#[test]
fn same_input_same_bytes_whatever_the_thread_count() {
    let kettle = PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("examples/data/kettle.obj");
    for (mesh, init) in [(data("cube_uv.obj"), "uv"), (kettle, "smooth")] {
        let (a, b) = (tmp(&format!("t1-{init}.json")), tmp(&format!("t2-{init}.json")));
        for (out, threads) in [(&a, "1"), (&b, "2")] {
            let args = [
                "--threads",
                threads,
                "field",
                "--quiet",
                mesh.to_str().unwrap(),
                "--light",
                "1,1,1",
                "--eye",
                "300,200,500",
                "--init",
                init,
                "--symmetric",
                "--out",
                out.to_str().unwrap(),
            ];
            let o = Command::new(env!("CARGO_BIN_EXE_grainline")).args(args).output().unwrap();
            assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
        }
        assert_eq!(std::fs::read(&a).unwrap(), std::fs::read(&b).unwrap(), "{init}");
    }
}

#[test]
fn bad_input_fails_cleanly_and_writes_nothing() {
    let out = tmp("never.json");
    let quad = data("quad.obj");
    let q = quad.to_str().unwrap();
    let o_ = out.to_str().unwrap();
    let (nan, tet) = (data("nan.obj"), data("tetrahedron.obj"));
    let (nan, tet) = (nan.to_str().unwrap(), tet.to_str().unwrap());
    let cases: Vec<(Vec<&str>, &str)> = vec![
        (vec![nan, "--light", "0,0,1", "--view", "0,0,1", "--out", o_], "nan.obj"),
        (vec![q, "--light", "0,0,0", "--view", "0,0,1", "--out", o_], "light"),
        (vec![q, "--light", "0,0,1,4", "--view", "0,0,1", "--out", o_], "light"),
        (vec![q, "--light", "0,0,1", "--view", "nan,0,1", "--out", o_], "view"),
        (vec![q, "--light", "0,0,1", "--view", "0,0,1", "--init", "sideways", "--out", o_], "init"),
        (
            vec!["/nonexistent/mesh.obj", "--light", "0,0,1", "--view", "0,0,1", "--out", o_],
            "mesh.obj",
        ),
        (
            vec![
                q,
                "--light",
                "0,0,1",
                "--view",
                "0,0,1",
                "--directions",
                "/nonexistent/d.json",
                "--out",
                o_,
            ],
            "d.json",
        ),
        (vec![tet, "--light", "0,0,1", "--view", "0,0,1", "--init", "uv", "--out", o_], "UV"),
    ];
    for (args, needle) in cases {
        let o = field(&args);
        let err = String::from_utf8_lossy(&o.stderr);
        assert_eq!(o.status.code(), Some(1), "{args:?}: {err}");
        assert!(err.contains(needle), "{args:?}: {err}");
        assert!(!err.contains("panicked"), "{err}");
        assert_eq!(err.trim().lines().count(), 1, "one line: {err}");
        assert!(!out.exists(), "{args:?} left an output file");
    }
}

#[test]
fn directions_file_errors_name_the_vertex_and_line() {
    let mesh = data("quad.obj");
    let dir = tmp("dirs.json");
    let out = tmp("dirs-out.json");
    let run = |contents: &str| {
        std::fs::write(&dir, contents).unwrap();
        let (m, d, o) = (mesh.to_str().unwrap(), dir.to_str().unwrap(), out.to_str().unwrap());
        let args = [m, "--light", "0,0,1", "--view", "0,0,1", "--directions", d, "--out", o];
        let o = field(&args);
        assert!(!o.status.success());
        String::from_utf8_lossy(&o.stderr).into_owned()
    };
    // quad.obj: 4 vertices in the z = 0 plane; vertex 2's direction is along the normal.
    let err = run("{\"u\": [[1,0,0],[1,0,0],\n[0,0,1],[1,0,0]]}");
    assert!(err.contains("vertex 2"), "{err}");
    let err = run("{\"u\": [[1,0,0],\n[1,0,0],\n[1,0 0]]}");
    assert!(err.contains("dirs.json:3"), "{err}");
    assert!(!out.exists());
}
