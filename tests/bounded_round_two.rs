//! Issue 46: every input bounded, round two. No write outside the out-dir (empty, `.` and
//! trailing-slash output keys refused naming the key), all-or-nothing runs, the scene file
//! checked like every other input (type and size, before it is read), budgets on edits, light
//! lists and SVG documents checked before the work, and messages in the scene's terms.
//! Every case runs in well under a second.

use std::path::{Path, PathBuf};
use std::process::{Command, Output};
use std::time::Instant;

use grainline::generate;
use grainline::mesh::write::obj_string;

fn dir(name: &str) -> PathBuf {
    let d = std::env::temp_dir().join(format!("grainline-bounded2-{}-{name}", std::process::id()));
    let _ = std::fs::remove_dir_all(&d);
    std::fs::create_dir_all(&d).unwrap();
    d
}

fn grainline(args: &[&str]) -> Output {
    Command::new(env!("CARGO_BIN_EXE_grainline")).args(args).output().unwrap()
}

fn stderr(o: &Output) -> String {
    String::from_utf8_lossy(&o.stderr).into_owned()
}

/// A small vase of revolution (UVs = angle, height) and a scene around it with `extra` (JSON
/// members, each starting with a comma).
fn scene(d: &Path, extra: &str) -> PathBuf {
    let mesh =
        generate::revolve(|t| (30.0 + 8.0 * (std::f64::consts::PI * t).sin(), 60.0 * t), 24, 12);
    std::fs::write(d.join("vase.obj"), obj_string(&mesh, "test vase")).unwrap();
    let s = format!(
        r#"{{
  "mesh": "vase.obj",
  "lights": [{{"type": "directional", "direction": [0.3, -0.5, 1]}}],
  "view": {{"eye": [0, -200, 80], "target": [0, 0, 30]}},
  "field": {{"init": "uv"}}{extra}
}}"#
    );
    let p = d.join("scene.json");
    std::fs::write(&p, s).unwrap();
    p
}

/// Every file under `d` (relative names), sorted, directories included (with a trailing `/`).
fn tree(d: &Path) -> Vec<String> {
    fn walk(base: &Path, d: &Path, out: &mut Vec<String>) {
        for e in std::fs::read_dir(d).unwrap() {
            let p = e.unwrap().path();
            let name = p.strip_prefix(base).unwrap().display().to_string();
            if p.is_dir() {
                out.push(format!("{name}/"));
                walk(base, &p, out);
            } else {
                out.push(name);
            }
        }
    }
    let mut v = Vec::new();
    walk(d, d, &mut v);
    v.sort();
    v
}

/// Runs `grainline run` on the scene, expecting a refusal within `secs` that mentions every
/// string of `wanted`; returns the message.
fn refused(args: &[&str], wanted: &[&str], secs: f64) -> String {
    let t = Instant::now();
    let o = grainline(args);
    let took = t.elapsed().as_secs_f64();
    let e = stderr(&o);
    assert_eq!(o.status.code(), Some(1), "{args:?}: {e}");
    assert!(!e.contains("panicked"), "{e}");
    for w in wanted {
        assert!(e.contains(w), "{args:?}: wanted {w:?} in: {e}");
    }
    assert!(!e.contains(":0:"), "a line 0: {e}");
    assert!(took < secs, "{args:?}: refused in {took:.2} s: {e}");
    e
}

// ---------------------------------------------------------------------------------------------
// 1. Every output path resolves inside the place the user named.

#[test]
fn empty_dot_and_directory_output_keys_are_refused_naming_the_key_and_nothing_is_written() {
    let d = dir("keys");
    let cases: [(&str, &str, &str); 9] = [
        (r#", "export": {"maps": ""}"#, "export.maps", "is empty"),
        (r#", "render": {"width": 16, "height": 16, "output": "sub/"}"#, "render.output", "sub/"),
        (r#", "render": {"width": 16, "height": 16, "output": ""}"#, "render.output", "file"),
        (r#", "render": {"width": 16, "height": 16, "output": "."}"#, "render.output", "directory"),
        (r#", "toolpaths": {"svg": "a/..", "placement": {"width": 4}}"#, "toolpaths.svg", "a/.."),
        (r#", "toolpaths": {"gcode": "a/.", "placement": {"width": 4}}"#, "toolpaths.gcode", "a/."),
        (r#", "field": {"init": "uv", "output": "out/"}"#, "field.output", "out/"),
        (r#", "export": {"glb": "."}"#, "export.glb", "directory"),
        (
            r#", "render": {"width": 16, "height": 16, "output": "x.png", "linear": "l/"}"#,
            "render.linear",
            "l/",
        ),
    ];
    for (extra, key, what) in cases {
        let extra = extra.replace(r#", "field": {"init": "uv", "output": "out/"}"#, "");
        let sc = scene(&d, &extra);
        if key == "field.output" {
            let t = std::fs::read_to_string(&sc).unwrap().replace(
                r#""field": {"init": "uv"}"#,
                r#""field": {"init": "uv", "output": "out/"}"#,
            );
            std::fs::write(&sc, t).unwrap();
        }
        let out = d.join("o");
        let e = refused(
            &["--quiet", "run", sc.to_str().unwrap(), "--out-dir", out.to_str().unwrap()],
            &[key, what],
            5.0,
        );
        assert!(
            !out.exists(),
            "{key}: the failed run made {}: {:?} ({e})",
            out.display(),
            tree(&d)
        );
        assert_eq!(tree(&d), ["scene.json", "vase.obj"], "{key}: {e}");
    }
    // `.` and a trailing slash name the out-dir itself or a directory below it: the maps land
    // there, and nowhere else.
    for (maps, sub) in [(".", ""), ("m/", "m/")] {
        let d = dir(&format!("maps{}", sub.len()));
        let sc = scene(
            &d,
            &format!(r#", "export": {{"maps": "{maps}", "anisotropy_texture_size": 64}}"#),
        );
        let out = d.join("o");
        let o = grainline(&[
            "--quiet",
            "run",
            sc.to_str().unwrap(),
            "--out-dir",
            out.to_str().unwrap(),
        ]);
        assert!(o.status.success(), "{}", stderr(&o));
        let mut want = vec![
            format!("{sub}grain-angle.png"),
            format!("{sub}grain-direction.png"),
            "run-report.json".to_string(),
        ];
        if !sub.is_empty() {
            want.push(sub.to_string());
        }
        want.sort();
        assert_eq!(tree(&out), want);
        let _ = std::fs::remove_dir_all(&d);
    }
    std::fs::remove_dir_all(&d).unwrap();
}

#[test]
fn an_out_dir_that_is_a_file_is_named_as_such() {
    let d = dir("outfile");
    let sc = scene(&d, r#", "render": {"width": 16, "height": 16, "output": "x.png"}"#);
    std::fs::write(d.join("f"), b"a file").unwrap();
    let f = d.join("f");
    refused(
        &["--quiet", "run", sc.to_str().unwrap(), "--out-dir", f.to_str().unwrap()],
        &["--out-dir", "is a file, not a directory"],
        5.0,
    );
    assert_eq!(std::fs::read(&f).unwrap(), b"a file");
    std::fs::remove_dir_all(&d).unwrap();
}

// ---------------------------------------------------------------------------------------------
// 2. A run is all or nothing.

#[test]
fn a_run_failing_late_leaves_no_output_no_report_and_no_new_directory() {
    let d = dir("late");
    // The environment image passes the up-front checks but is not an image: the render fails
    // after the strokes were traced and staged.
    std::fs::write(d.join("env.hdr"), b"not an image").unwrap();
    let sc = scene(
        &d,
        r#", "toolpaths": {"svg": "new/v.svg", "gcode": "new/v.ngc", "placement": {"width": 4}},
        "render": {"width": 16, "height": 16, "output": "new/deeper/v.png"}"#,
    );
    let t = std::fs::read_to_string(&sc)
        .unwrap()
        .replace(r#""lights": ["#, r#""lights": [{"type": "environment", "file": "env.hdr"}, "#);
    std::fs::write(&sc, t).unwrap();
    let out = d.join("o");
    refused(
        &["--quiet", "run", sc.to_str().unwrap(), "--out-dir", out.to_str().unwrap()],
        &["env.hdr"],
        20.0,
    );
    assert!(!out.exists(), "{:?}", tree(&d));
    assert_eq!(tree(&d), ["env.hdr", "scene.json", "vase.obj"]);
    std::fs::remove_dir_all(&d).unwrap();
}

// ---------------------------------------------------------------------------------------------
// 3. The scene file is an input like every other: its type and size checked before it is read.

#[cfg(unix)]
#[test]
fn a_fifo_or_a_directory_as_the_scene_file_is_refused_without_blocking() {
    let d = dir("fifo");
    let fifo = d.join("scene.fifo");
    assert!(Command::new("mkfifo").arg(&fifo).status().unwrap().success());
    let f = fifo.to_str().unwrap();
    let dd = d.to_str().unwrap();
    for cmd in ["run", "trace", "render", "export", "optimize"] {
        let args: Vec<&str> = match cmd {
            "optimize" => vec!["--quiet", cmd, f, "--out", "x.json"],
            "export" => vec!["--quiet", cmd, f, "--glb", "x.glb"],
            _ => vec!["--quiet", cmd, f],
        };
        refused(&args, &["scene.fifo", "FIFO"], 5.0);
    }
    refused(&["--quiet", "run", "/dev/zero"], &["/dev/zero", "character device"], 5.0);
    refused(&["--quiet", "run", dd], &["directory"], 5.0);
    std::fs::remove_dir_all(&d).unwrap();
}

#[test]
fn a_huge_scene_or_svg_file_is_refused_from_its_size_unread() {
    let d = dir("huge");
    let big = d.join("big.json");
    // A sparse gigabyte: refused from its metadata, without reading a byte.
    std::fs::File::create(&big).unwrap().set_len(1 << 30).unwrap();
    refused(&["--quiet", "run", big.to_str().unwrap()], &["big.json", "1073741824 bytes"], 2.0);
    let svg = d.join("big.svg");
    std::fs::File::create(&svg).unwrap().set_len(1 << 30).unwrap();
    refused(
        &["--quiet", "panel", svg.to_str().unwrap(), "--out", d.join("p.obj").to_str().unwrap()],
        &["big.svg", "bytes"],
        2.0,
    );
    // A gigabyte of zeros named like a mesh: refused at its first line from its first bytes
    // (it was read whole, twice: 7 s and 1 GB of memory).
    let obj = d.join("big.obj");
    std::fs::File::create(&obj).unwrap().set_len(1 << 30).unwrap();
    let out = d.join("f.json");
    let field = ["--quiet", "field", obj.to_str().unwrap(), "--light", "0,0,1", "--view", "0,0,1"];
    let args = [&field[..], &["--out", out.to_str().unwrap()]].concat();
    refused(&args, &["big.obj:1:", "binary data"], 2.0);
    refused(&["--quiet", "inspect", obj.to_str().unwrap()], &["big.obj:1:", "binary data"], 2.0);
    // A control character in a trailing comment is not binary data: the file is read on.
    let text = format!("v 0 0 0 # \u{1}\n{}", "v 1 0 0\nv 0 1 0\nf 1 2 3\n".repeat(10));
    std::fs::write(&obj, text).unwrap();
    let o = grainline(&["--quiet", "inspect", obj.to_str().unwrap()]);
    assert!(o.status.success(), "{}", stderr(&o));
    std::fs::remove_dir_all(&d).unwrap();
}

// A triangle 10⁷⁴ units across (within the coordinate limit) whose field is not finite: the
// message names the mesh file.
#[test]
fn a_field_that_fails_on_a_vast_triangle_names_the_mesh() {
    let d = dir("vast");
    let obj = d.join("vast.obj");
    std::fs::write(&obj, "v 0 0 0\nv 1e74 0 0\nv 0 1e74 0\nf 1 2 3\n").unwrap();
    let out = d.join("f.json");
    let o = grainline(&[
        "--quiet",
        "field",
        obj.to_str().unwrap(),
        "--light",
        "0,0,1",
        "--view",
        "0,0,1",
        "--out",
        out.to_str().unwrap(),
    ]);
    let e = stderr(&o);
    if !o.status.success() {
        assert!(e.contains("vast.obj"), "{e}");
    }
    assert!(!out.exists() || o.status.success(), "{e}");
    std::fs::remove_dir_all(&d).unwrap();
}

// ---------------------------------------------------------------------------------------------
// 4. Budgets checked before the work.

#[test]
fn edit_counts_and_light_lists_are_refused_past_their_budgets_at_once() {
    let d = dir("counts");
    let bend =
        r#"{"tool": "bend", "centre": {"point": [0, -30, 30]}, "radius": 10, "strength": 0.3}"#;
    let edits = vec![bend; grainline::limits::MAX_EDITS + 1].join(",");
    let sc = scene(&d, &format!(r#", "edits": [{edits}]"#));
    refused(&["--quiet", "run", sc.to_str().unwrap()], &["edits", "1001 edits"], 2.0);
    let list = vec!["0"; 10_000].join(",");
    let sc = scene(
        &d,
        &format!(
            r#", "render": {{"width": 16, "height": 16, "output": "x.png",
            "effects": {{"highlight_curves": {{"lights": [{list}]}}}}}}"#
        ),
    );
    refused(
        &["--quiet", "run", sc.to_str().unwrap()],
        &["render.effects.highlight_curves.lights", "10000 lights"],
        2.0,
    );
    assert_eq!(tree(&d), ["scene.json", "vase.obj"]);
    std::fs::remove_dir_all(&d).unwrap();
}

fn panel(d: &Path, name: &str, svg: &str) -> (Output, f64) {
    let p = d.join(name);
    std::fs::write(&p, svg).unwrap();
    let t = Instant::now();
    let o = grainline(&[
        "--quiet",
        "panel",
        p.to_str().unwrap(),
        "--out",
        d.join("p.obj").to_str().unwrap(),
    ]);
    (o, t.elapsed().as_secs_f64())
}

#[test]
fn svg_nesting_element_counts_and_selectors_are_refused_before_usvg_reads_them() {
    let d = dir("svg");
    let head = r#"<svg xmlns="http://www.w3.org/2000/svg" width="100mm" height="100mm" viewBox="0 0 100 100">"#;
    // 10⁵ nested groups.
    let n = 100_000;
    let svg = format!(
        "{head}\n{}<rect width=\"10\" height=\"10\"/>{}</svg>",
        "<g>".repeat(n),
        "</g>".repeat(n)
    );
    let (o, took) = panel(&d, "deep.svg", &svg);
    let e = stderr(&o);
    assert!(!o.status.success() && e.contains("deep.svg:2:") && e.contains("nested"), "{e}");
    assert!(took < 2.0, "{took} s: {e}");
    // More elements than the budget.
    let svg = format!(
        "{head}\n{}</svg>",
        "<rect x=\"1\" y=\"1\" width=\"1\" height=\"1\"/>\n"
            .repeat(grainline::limits::MAX_SVG_ELEMENTS)
    );
    let (o, took) = panel(&d, "many.svg", &svg);
    let e = stderr(&o);
    let last = 1 + grainline::limits::MAX_SVG_ELEMENTS;
    assert!(!o.status.success() && e.contains(&format!("many.svg:{last}:")), "{e}");
    assert!(e.contains("elements"), "{e}");
    assert!(took < 2.0, "{took} s: {e}");
    // A selector whose matching grows exponentially with its combinators (395 bytes).
    let sel = vec!["g"; 100].join(" ");
    let svg = format!(
        "{head}\n<style>{sel} rect {{ fill: red }}</style>\n{}<rect width=\"10\" height=\"10\"/>{}</svg>",
        "<g>".repeat(60),
        "</g>".repeat(60)
    );
    let (o, took) = panel(&d, "css.svg", &svg);
    let e = stderr(&o);
    assert!(!o.status.success() && e.contains("css.svg:2:") && e.contains("selectors"), "{e}");
    assert!(took < 2.0, "{took} s: {e}");
    // A rect of 10³⁰ mm: beyond any sheet, refused before the triangulation.
    let svg = format!("{head}\n<rect width=\"1e30\" height=\"1e30\"/></svg>");
    let (o, took) = panel(&d, "vast.svg", &svg);
    let e = stderr(&o);
    assert!(!o.status.success() && e.contains("vast.svg:2:") && e.contains("MAX_PANEL"), "{e}");
    assert!(took < 2.0, "{took} s: {e}");
    // An ordinary style sheet is read.
    let svg = format!(
        "{head}\n<style>g rect {{ fill: red }} .a > .b ~ rect {{ fill: blue }}</style>\n<g><rect width=\"50\" height=\"50\"/></g></svg>"
    );
    let (o, _) = panel(&d, "ok.svg", &svg);
    assert!(o.status.success(), "{}", stderr(&o));
    std::fs::remove_dir_all(&d).unwrap();
}

// ---------------------------------------------------------------------------------------------
// 5. Messages name the key, in the scene's terms; printed paths have their control characters
// escaped.

#[test]
fn serde_wording_is_said_in_the_scene_s_terms() {
    let d = dir("words");
    let sc = d.join("s.json");
    let cases: [(&str, &[&str]); 5] = [
        ("[]", &["s.json", "the scene must be a JSON object"]),
        (
            r#"{"mesh": "x.obj", "view": {"eye": [0, -3, 1]}, "units": 5}"#,
            &["units: has the wrong type: expected one of `mm`"],
        ),
        (
            r#"{"mesh": "x.obj", "view": {"eye": [0, -3, 1, 4]}}"#,
            &["view.eye: holds more elements than it takes"],
        ),
        (
            r#"{"mesh": "x.obj", "view": {"eye": [0, -3, 1]}, "render": {"width": "wide", "output": "x.png"}}"#,
            &["render.width", "expected a whole number"],
        ),
        (r#"{"mesh": "x.obj", "view": []}"#, &["view: must be a JSON object"]),
    ];
    for (text, wanted) in cases {
        std::fs::write(&sc, text).unwrap();
        let e = refused(&["--quiet", "run", sc.to_str().unwrap()], wanted, 2.0);
        assert!(!e.contains("invalid length") && !e.contains("expected value"), "{e}");
        assert!(!e.contains("trailing characters") && !e.contains("u32"), "{e}");
    }
    std::fs::remove_dir_all(&d).unwrap();
}

#[test]
fn control_characters_in_printed_paths_are_escaped() {
    let d = dir("escape");
    let p = d.join("a\x1b[31mred.json");
    std::fs::write(&p, "{").unwrap();
    let o = grainline(&["--quiet", "run", p.to_str().unwrap()]);
    let e = stderr(&o);
    assert!(!o.status.success());
    assert!(!e.contains('\x1b'), "{e:?}");
    assert!(e.contains("a\\u{1b}[31mred.json"), "{e}");
    // A truncated scene names no `?` key.
    assert!(e.contains("red.json:1: EOF while parsing"), "{e}");
    std::fs::remove_dir_all(&d).unwrap();
}

/// A curve zigzagging over the whole vase with a small radius asks for its whole trace at
/// r/8: about 10⁷ new vertices. It is refused from the estimate before any split, naming the
/// edit, the estimate and `mesh.refine.max_vertices` (it used to be refined until the budget
/// stopped it, seconds later, naming the budget only), and nothing is written.
#[test]
fn a_zigzag_curve_refused_from_its_refinement_estimate_naming_the_edit() {
    let d = dir("zigzag");
    // 10⁴ points around the vase (R = 30 + 8 sin(πz/60)), z alternating 5 and 55 mm.
    let points: Vec<String> = (0..10_000)
        .map(|k| {
            let a = k as f64 * std::f64::consts::TAU / 10_000.0;
            let z: f64 = if k % 2 == 0 { 5.0 } else { 55.0 };
            let r = 30.0 + 8.0 * (std::f64::consts::PI * z / 60.0).sin();
            format!("[{:.4}, {:.4}, {z}]", r * a.cos(), r * a.sin())
        })
        .collect();
    let edit = format!(r#"{{"tool": "curve", "points": [[{}]], "radius": 0.5}}"#, points.join(","));
    let sc = scene(&d, &format!(r#", "edits": [{edit}]"#));
    let o = grainline(&["--quiet", "run", sc.to_str().unwrap()]);
    let e = stderr(&o);
    assert_eq!(o.status.code(), Some(1), "{e}");
    for w in
        ["edits[0]: refining the part for this curve would add about", "mesh.refine.max_vertices"]
    {
        assert!(e.contains(w), "wanted {w:?} in: {e}");
    }
    // The estimate, a·10ᵇ with b ≥ 6, is past the budget of 2 × 10⁶.
    let about = e.split("about ").nth(1).and_then(|s| s.split(' ').next()).unwrap();
    let estimate: f64 = about.parse().unwrap();
    assert!(estimate > 2e6, "{about}: {e}");
    assert_eq!(tree(&d), ["scene.json", "vase.obj"]);
    std::fs::remove_dir_all(&d).unwrap();
}
