//! Issue 30: every input bounded, every message exact. One test per item, named after it.

use std::path::{Path, PathBuf};
use std::process::{Command, Output};

use grainline::generate;
use grainline::mesh::write::obj_string;

fn dir(name: &str) -> PathBuf {
    let d = std::env::temp_dir().join(format!("grainline-bounded-{}-{name}", std::process::id()));
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

/// A scene in `d` around a small vase of revolution, with `extra` (JSON members, each starting
/// with a comma; `"field": {"init": "uv"}` unless it has a `field`) and `lights` (a JSON
/// array).
fn scene_with(d: &Path, lights: &str, extra: &str) -> PathBuf {
    let mesh =
        generate::revolve(|t| (30.0 + 8.0 * (std::f64::consts::PI * t).sin(), 60.0 * t), 48, 24);
    std::fs::write(d.join("vase.obj"), obj_string(&mesh, "test vase")).unwrap();
    let field = if extra.contains(r#""field""#) { "" } else { r#", "field": {"init": "uv"}"# };
    let s = format!(
        r#"{{
  "mesh": "vase.obj",
  "lights": {lights},
  "view": {{"eye": [0, -200, 80], "target": [0, 0, 30]}}{field}{extra}
}}"#
    );
    let p = d.join("scene.json");
    std::fs::write(&p, s).unwrap();
    p
}

fn scene(d: &Path, extra: &str) -> PathBuf {
    scene_with(d, r#"[{"type": "directional", "direction": [0.3, -0.5, 1]}]"#, extra)
}

fn run(scene: &Path, out_dir: Option<&Path>) -> Output {
    let mut args = vec!["run".to_string(), scene.display().to_string(), "-q".into()];
    if let Some(o) = out_dir {
        args.extend(["--out-dir".into(), o.display().to_string()]);
    }
    let args: Vec<&str> = args.iter().map(String::as_str).collect();
    grainline(&args)
}

// Item 6: a relative output never leaves `--out-dir` (or the scene's directory).
#[test]
fn item_6_outputs_stay_inside_out_dir() {
    let d = dir("item6");
    let sd = d.join("scene");
    std::fs::create_dir_all(&sd).unwrap();
    let out = d.join("out");
    // Climbing out of --out-dir: refused naming the key, nothing written outside (or inside).
    let s = scene(&sd, r#", "render": {"output": "../../escape.png", "width": 64, "height": 48}"#);
    let o = run(&s, Some(&out));
    assert!(!o.status.success());
    let e = stderr(&o);
    assert!(e.contains("render.output") && e.contains("--out-dir"), "{e}");
    assert!(!d.join("escape.png").exists() && !std::env::temp_dir().join("escape.png").exists());
    // A `..` hidden behind a directory name still counts.
    let s = scene(&sd, r#", "field": {"init": "uv", "output": "a/../../field.json"}"#);
    let e = stderr(&run(&s, Some(&out)));
    assert!(e.contains("field.output") && e.contains("a/../../field.json"), "{e}");
    assert!(!d.join("field.json").exists());
    // Without --out-dir the scene's directory is the bound.
    let s = scene(&sd, r#", "field": {"init": "uv", "output": "../field.json"}"#);
    let e = stderr(&run(&s, None));
    assert!(e.contains("field.output") && e.contains("the scene file's directory"), "{e}");
    assert!(!d.join("field.json").exists());
    // Inside: written under --out-dir, `a/..` included.
    let s = scene(&sd, r#", "field": {"init": "uv", "output": "a/../field.json"}"#);
    let o = run(&s, Some(&out));
    assert!(o.status.success(), "{}", stderr(&o));
    assert!(out.join("field.json").exists());
    // Absolute paths stay allowed, wherever they point.
    let abs = d.join("elsewhere").join("field.json");
    let s = scene(&sd, &format!(r#", "field": {{"init": "uv", "output": {:?}}}"#, abs.display()));
    let o = run(&s, Some(&out));
    assert!(o.status.success(), "{}", stderr(&o));
    assert!(abs.exists());
    std::fs::remove_dir_all(&d).unwrap();
}

// Item 7: the examples name plain files, so `--out-dir out` writes out/NAME.svg, as the README
// says.
#[test]
fn item_7_examples_and_readme_agree_on_output_paths() {
    let root = Path::new(env!("CARGO_MANIFEST_DIR"));
    let mut seen = 0;
    for e in std::fs::read_dir(root.join("examples")).unwrap() {
        let scene = e.unwrap().path().join("scene.json");
        if !scene.exists() {
            continue;
        }
        let v: serde_json::Value =
            serde_json::from_str(&std::fs::read_to_string(&scene).unwrap()).unwrap();
        for key in [
            "/field/output",
            "/toolpaths/svg",
            "/toolpaths/gcode",
            "/toolpaths/strokes_json",
            "/render/output",
            "/render/linear",
            "/export/glb",
        ] {
            if let Some(p) = v.pointer(key).and_then(|p| p.as_str()) {
                assert!(
                    !p.contains('/'),
                    "{}: {key} is {p:?}, not a plain file name",
                    scene.display()
                );
                seen += 1;
            }
        }
    }
    assert!(seen >= 15, "only {seen} outputs in the examples");
    for doc in ["README.md", "examples/README.md", "docs/guide.md", "docs/scene.md"] {
        let text = std::fs::read_to_string(root.join(doc)).unwrap();
        assert!(!text.contains("out/out"), "{doc} still names out/out");
    }
    let readme = std::fs::read_to_string(root.join("README.md")).unwrap();
    assert!(readme.contains("--out-dir out") && readme.contains("`out/kettle.svg`"));
}

fn scene_error(text: &str) -> String {
    match grainline::scene::Scene::from_str(text, Path::new("scene.json")) {
        Ok(_) => panic!("accepted: {text}"),
        Err(e) => e.to_string(),
    }
}

const BASE: &str = r#""mesh": "part.obj", "view": {"eye": [0, -200, 80]}"#;

// Item 12: two key lights are refused, naming the second one's `key`.
#[test]
fn item_12_two_key_lights_are_refused() {
    let e = scene_error(&format!(
        r#"{{{BASE}, "lights": [
            {{"type": "directional", "direction": [0, 0, 1], "key": true}},
            {{"type": "directional", "direction": [1, 0, 1]}},
            {{"type": "point", "position": [0, 0, 500], "key": true}}]}}"#
    ));
    assert!(e.contains("lights[2].key") && e.contains("lights[0]"), "{e}");
    // One key light among several is fine.
    let ok = format!(
        r#"{{{BASE}, "lights": [{{"type": "directional", "direction": [0, 0, 1]}},
            {{"type": "point", "position": [0, 0, 500], "key": true}}]}}"#
    );
    grainline::scene::Scene::from_str(&ok, Path::new("scene.json")).unwrap();
}

// Item 8, first part: a point key light at the part's centre is refused at its position.
#[test]
fn item_8_point_key_light_at_the_centre_names_its_position() {
    let d = dir("item8-centre");
    scene(&d, "");
    let mesh =
        grainline::mesh::load::load_mesh(&d.join("vase.obj"), &Default::default()).unwrap().mesh;
    let c = grainline::highlight::lighting::centre_of(&mesh.positions);
    let lights = format!(
        r#"[{{"type": "directional", "direction": [0, 0, 1]}},
            {{"type": "point", "position": [{:?}, {:?}, {:?}], "key": true}}]"#,
        c.x, c.y, c.z
    );
    let s = scene_with(&d, &lights, "");
    let o = run(&s, Some(&d.join("out")));
    assert!(!o.status.success());
    let e = stderr(&o);
    assert!(e.contains("lights[1].position") && e.contains("centre"), "{e}");
    assert!(!e.contains("part centre: direction"), "{e}");
    std::fs::remove_dir_all(&d).unwrap();
}

// Item 8: the solver's smoothness and turning radius are bounded, named when refused, and
// huge numbers and paths are printed short.
#[test]
fn item_8_bounded_solver_numbers_and_short_messages() {
    let lights = r#""lights": [{"type": "directional", "direction": [0, 0, 1]}]"#;
    let e = scene_error(&format!(r#"{{{BASE}, {lights}, "solver": {{"smoothness": 1e300}}}}"#));
    assert!(
        e.contains("solver.smoothness") && e.contains("1e300") && e.contains("1000000]"),
        "{e}"
    );
    assert!(e.len() < 200, "{e}");
    let e = scene_error(&format!(
        r#"{{{BASE}, {lights},
            "solver": {{"constraints": {{"turning_radius": {{"radius": 1e300}}}}}}}}"#
    ));
    assert!(
        e.contains("solver.constraints.turning_radius.radius") && e.contains("≤ 1000000000"),
        "{e}"
    );
    assert!(e.contains("1e300") && e.len() < 200, "{e}");
    // The solve's iteration cap is bounded too (each iteration is a factorization).
    let e =
        scene_error(&format!(r#"{{{BASE}, {lights}, "solver": {{"max_iterations": 1000001}}}}"#));
    assert!(
        e.contains("solver.max_iterations") && e.contains("[1, 1000]") && e.contains("1000001"),
        "{e}"
    );
    // At the documented limits: accepted.
    let ok = format!(
        r#"{{{BASE}, {lights}, "solver": {{"smoothness": 1e6,
            "constraints": {{"turning_radius": {{"radius": 1e9}}}}}}}}"#
    );
    grainline::scene::Scene::from_str(&ok, Path::new("scene.json")).unwrap();
    // An output path past 4096 bytes: refused naming the key, echoed shortened.
    let d = dir("item8-path");
    let long = "x/".repeat(50_000) + "a.svg";
    let s = scene(&d, &format!(r#", "field": {{"init": "uv", "output": "{long}"}}"#));
    let o = run(&s, Some(&d.join("out")));
    assert!(!o.status.success());
    let e = stderr(&o);
    assert!(e.contains("field.output") && e.contains("4096") && e.contains("100005 bytes"), "{e}");
    assert!(e.len() < 1000, "{} bytes of stderr", e.len());
    std::fs::remove_dir_all(&d).unwrap();
}

// Item 4: at most 64 lights and 10⁵ points per curve edit, refused naming the key.
#[test]
fn item_4_lights_and_curve_points_are_bounded() {
    use grainline::limits::{MAX_CURVE_POINTS, MAX_LIGHTS};
    let light = r#"{"type": "directional", "direction": [0, 0, 1]}"#;
    let lights = |n: usize| vec![light; n].join(", ");
    let e = scene_error(&format!(r#"{{{BASE}, "lights": [{}]}}"#, lights(MAX_LIGHTS + 1)));
    assert!(e.contains("lights:") && e.contains("65 lights") && e.contains("64"), "{e}");
    let ok = format!(r#"{{{BASE}, "lights": [{}]}}"#, lights(MAX_LIGHTS));
    grainline::scene::Scene::from_str(&ok, Path::new("scene.json")).unwrap();
    let curve = |n: usize| {
        let pts: Vec<String> = (0..n).map(|i| format!("[{}, 0.5]", i as f64 / n as f64)).collect();
        format!(
            r#"{{{BASE}, "lights": [{light}],
                "edits": [{{"tool": "curve", "uv": [[{}]], "radius": 2}}]}}"#,
            pts.join(", ")
        )
    };
    let e = scene_error(&curve(MAX_CURVE_POINTS + 1));
    assert!(e.contains("edits[0]") && e.contains("uv") && e.contains("100000"), "{e}");
    grainline::scene::Scene::from_str(&curve(MAX_CURVE_POINTS), Path::new("scene.json")).unwrap();
}

/// `grainline ARGS`, killed (and the test failed) if it runs past 30 s.
fn grainline_within_30s(args: &[&str]) -> Output {
    let mut child = Command::new(env!("CARGO_BIN_EXE_grainline"))
        .args(args)
        .stdout(std::process::Stdio::piped())
        .stderr(std::process::Stdio::piped())
        .spawn()
        .unwrap();
    let started = std::time::Instant::now();
    while child.try_wait().unwrap().is_none() {
        if started.elapsed().as_secs() > 30 {
            child.kill().ok();
            child.wait().ok();
            panic!("grainline {args:?} blocked");
        }
        std::thread::sleep(std::time::Duration::from_millis(50));
    }
    child.wait_with_output().unwrap()
}

// Item 3: a FIFO given as the mesh is refused at once, naming the file, instead of blocking.
#[cfg(unix)]
#[test]
fn item_3_fifo_mesh_is_refused_without_blocking() {
    let d = dir("item3");
    let fifo = d.join("part.obj");
    let ok = Command::new("mkfifo").arg(&fifo).status().unwrap().success();
    assert!(ok, "mkfifo failed");
    // The library refuses it from its metadata (on a thread: a regression would block).
    let (tx, rx) = std::sync::mpsc::channel();
    let f2 = fifo.clone();
    std::thread::spawn(move || {
        let r = grainline::mesh::load::load_mesh(&f2, &Default::default());
        tx.send(r.err().map(|e| e.to_string())).ok();
    });
    let e = rx.recv_timeout(std::time::Duration::from_secs(30)).expect("load_mesh blocked");
    let e = e.expect("a FIFO loaded as a mesh");
    assert!(e.contains("part.obj") && e.contains("FIFO"), "{e}");
    // `inspect`, `field` and a scene's mesh: each refused, naming the file.
    let f = fifo.display().to_string();
    let out = d.join("f.json").display().to_string();
    std::fs::write(
        d.join("scene.json"),
        r#"{"mesh": "part.obj", "view": {"eye": [0, -200, 80]},
            "lights": [{"type": "directional", "direction": [0, 0, 1]}]}"#,
    )
    .unwrap();
    let scene = d.join("scene.json").display().to_string();
    let out_dir = d.join("out").display().to_string();
    for args in [
        vec!["inspect", &f],
        vec!["field", &f, "--light", "0,0,1", "--view", "0,-1,0", "--out", &out],
        vec!["run", &scene, "--out-dir", &out_dir],
    ] {
        let o = grainline_within_30s(&args);
        assert!(!o.status.success());
        let e = stderr(&o);
        assert!(e.contains("part.obj") && e.contains("FIFO"), "{args:?}: {e}");
    }
    std::fs::remove_dir_all(&d).unwrap();
}

/// An OBJ of three vertices and `n` lines of `f 1 2 3`.
fn repeated_faces(n: usize) -> String {
    format!("v 0 0 0\nv 1 0 0\nv 0 1 0\n{}", "f 1 2 3\n".repeat(n))
}

// Item 1: `inspect` on one face repeated N times (or one polygon of N corners over three
// vertices) compared the faces along an edge pairwise: N² work. An edge joins at most 64 faces
// (limits::MAX_EDGE_FACES) and a face lists at most 10⁶ corners (limits::MAX_POLYGON_CORNERS),
// refused naming the file (and the line) even where non-manifold edges are tolerated.
#[test]
fn item_1_inspect_is_linear_in_repeated_faces() {
    use grainline::limits::{MAX_EDGE_FACES, MAX_POLYGON_CORNERS};
    let d = dir("item1");
    let p = d.join("rep.obj");
    let path = p.display().to_string();
    let out = d.join("f.json").display().to_string();
    let field = ["field", &path, "--allow-nonmanifold", "--light", "0,0,1", "--view", "0,-1,0"];
    let field: Vec<&str> = field.into_iter().chain(["--out", &out]).collect();
    // At the budget: inspected, the edges reported as non-manifold.
    std::fs::write(&p, repeated_faces(MAX_EDGE_FACES)).unwrap();
    let o = grainline(&["inspect", &path]);
    assert!(o.status.success(), "{}", stderr(&o));
    let text = String::from_utf8_lossy(&o.stdout);
    assert!(text.contains("3 edges, 64 triangles"), "{text}");
    // One past it, and 10⁵ past it: refused, naming the file, the budget and a few lines.
    for n in [MAX_EDGE_FACES + 1, 100_000] {
        std::fs::write(&p, repeated_faces(n)).unwrap();
        for args in [vec!["inspect", &path], field.clone()] {
            let o = grainline(&args);
            assert!(!o.status.success(), "{args:?}");
            let e = stderr(&o);
            assert!(e.contains("rep.obj") && e.contains("limits::MAX_EDGE_FACES"), "{e}");
            assert!(e.contains(&format!("shared by {n} faces (line 4, line 5")), "{e}");
            assert!(e.len() < 400, "{e}");
        }
    }
    // A face line one corner past the budget: refused at its line, before it is split.
    let corners = vec!["1 2 3"; MAX_POLYGON_CORNERS / 3 + 1].join(" ");
    std::fs::write(&p, format!("v 0 0 0\nv 1 0 0\nv 0 1 0\nf {corners}\n")).unwrap();
    let o = grainline(&["inspect", &path]);
    let e = stderr(&o);
    assert!(e.contains("rep.obj:4:") && e.contains("limits::MAX_POLYGON_CORNERS"), "{e}");
    std::fs::remove_dir_all(&d).unwrap();
}

/// An OBJ of one convex polygon of `n` corners on the unit circle (split into a fan).
fn polygon(n: usize) -> String {
    let mut s = String::new();
    for i in 0..n {
        let t = std::f64::consts::TAU * i as f64 / n as f64;
        s += &format!("v {} {} {}\n", t.cos(), t.sin(), 0.1 * t.cos() * t.sin());
    }
    let corners: Vec<String> = (1..=n).map(|i| i.to_string()).collect();
    s + "f " + &corners.join(" ") + "\n"
}

// Item 2: every rim vertex of a fan (a polygon of n corners is split into one) gathered the
// hub's n neighbours into its 2-ring for the jet fit and ∇φ: n² work. Rings past the 1-ring
// do not pass through a vertex of more than 128 neighbours and stop at 512 vertices
// (docs/math.md §5.6, "Bounded rings"); the work is counted, not timed.
#[test]
fn item_2_field_is_linear_on_one_huge_polygon_and_fans() {
    use grainline::geometry::rings::{gather_ring, MAX_RING_POINTS, MAX_RING_VALENCE};
    use grainline::mesh::Adjacency;
    let n = 20_000;
    // A fan of n triangles around vertex 0: the rings of all vertices hold O(n) vertices in all.
    let faces: Vec<[u32; 3]> = (0..n as u32).map(|k| [0, k + 1, k + 2]).collect();
    let adj = Adjacency::from_faces(n + 2, &faces);
    let (mut ring, mut scratch) = (Vec::new(), Vec::new());
    for depth in 2..=4 {
        let total: usize = (0..n + 2)
            .map(|i| {
                gather_ring(&adj, i, depth, &mut ring, &mut scratch);
                assert!(i == 0 || ring.len() <= MAX_RING_POINTS);
                ring.len()
            })
            .sum();
        // The hub's own ring is its n neighbours; each rim vertex's runs along the rim.
        assert!(total <= n + 1 + (2 * depth + 1) * (n + 1), "depth {depth}: {total}");
    }
    // A vertex of at most MAX_RING_VALENCE neighbours is still passed through: a fan of 128.
    let faces: Vec<[u32; 3]> =
        (0..MAX_RING_VALENCE as u32 - 1).map(|k| [0, k + 1, k + 2]).collect();
    let adj = Adjacency::from_faces(MAX_RING_VALENCE + 1, &faces);
    gather_ring(&adj, 1, 2, &mut ring, &mut scratch);
    assert_eq!(ring.len(), MAX_RING_VALENCE, "the plain 2-ring: all of the hub's neighbours");
    // `field` on one polygon of 20,000 corners computes a field for every vertex.
    let d = dir("item2");
    let p = d.join("polygon.obj");
    std::fs::write(&p, polygon(n)).unwrap();
    let out = d.join("f.json");
    let (path, out_s) = (p.display().to_string(), out.display().to_string());
    let args = ["--quiet", "field", &path, "--light", "0.3,0.2,1", "--view", "0,-1,1"];
    let o = grainline(&[&args[..], &["--out", &out_s]].concat());
    assert!(o.status.success(), "{}", stderr(&o));
    let field: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(&out).unwrap()).unwrap();
    assert_eq!(field["u"].as_array().map(Vec::len), Some(n));
    std::fs::remove_dir_all(&d).unwrap();
}

// Item 8, the rest: `lead_in`, `lead_out`, `ramp_height`, `overtravel` and `contact_depth` are
// at most 10⁶ scene units, refused when the scene is read naming their key, printed short (1e300
// used to print a 300-digit number and blame `gcode_options.safe_z`).
#[test]
fn item_8_leads_and_ramps_are_bounded_and_named() {
    let d = dir("item8b");
    for key in ["lead_in", "lead_out", "ramp_height", "overtravel", "contact_depth"] {
        let plan = format!(r#", "toolpaths": {{"gcode": "x.ngc", "plan": {{"{key}": 1e300}}}}"#);
        let o = run(&scene(&d, &plan), Some(&d.join("out")));
        assert!(!o.status.success(), "{key}");
        let e = stderr(&o);
        assert!(e.contains(&format!("toolpaths.plan.{key}")) && e.contains("got 1e300"), "{e}");
        assert!(!e.contains("safe_z") && e.len() < 300, "{e}");
        assert!(!d.join("out").join("x.ngc").exists());
    }
    std::fs::remove_dir_all(&d).unwrap();
}

// Item 9: each failure names the key that caused it.
#[test]
fn item_9_messages_name_the_key_that_caused_them() {
    let d = dir("item9");
    let out = d.join("out");
    let err = |extra: &str| {
        let o = run(&scene(&d, extra), Some(&out));
        assert!(!o.status.success(), "{extra}");
        stderr(&o)
    };
    let mesh_err = |mesh: &str| {
        let s = scene(&d, "");
        let text = std::fs::read_to_string(&s).unwrap().replace(r#""vase.obj""#, mesh);
        std::fs::write(&s, text).unwrap();
        stderr(&run(&s, Some(&out)))
    };
    let e = mesh_err(r#"{"path": "vase.obj", "scale": 1e-300}"#);
    assert!(e.contains("mesh.scale") && e.contains("1e-300"), "{e}");
    let e = mesh_err(r#"{"path": "vase.obj", "weld": 1e30}"#);
    assert!(e.contains("zero area") && e.contains("mesh.weld") && e.contains("1e30"), "{e}");
    let e = err(r#", "toolpaths": {"svg": "x.svg", "placement": {"test_ratio": 1e-12}}"#);
    assert!(e.contains("placement.test_ratio") && !e.contains("placement.width:"), "{e}");
    let e = err(r#", "toolpaths": {"svg": "x.svg", "placement": {"trace": {"max_step": 1e-9}}}"#);
    assert!(e.contains("trace.max_step") && e.contains("got 1e-9"), "{e}");
    let edit = r#"{"tool": "bend", "centre": {"point": [0, -30, 30], "bogus": 1}, "radius": 20}"#;
    let e = err(&format!(r#", "edits": [{edit}]"#));
    assert!(e.contains("edits[0]") && e.contains("unknown field `bogus`"), "{e}");
    // A UTF-8 byte-order mark is read past.
    let s = scene(&d, "");
    let text = std::fs::read_to_string(&s).unwrap();
    std::fs::write(&s, format!("\u{feff}{text}")).unwrap();
    let o = run(&s, Some(&out));
    assert!(o.status.success(), "{}", stderr(&o));
    // An environment light pointing at a mesh: "not an image", without a line 0.
    let lights = r#"[{"type": "directional", "direction": [0.3, -0.5, 1], "key": true},
                     {"type": "environment", "file": "vase.obj"}]"#;
    let render = r#", "render": {"width": 32, "height": 24, "output": "x.png"}"#;
    let o = run(&scene_with(&d, lights, render), Some(&out));
    let e = stderr(&o);
    assert!(e.contains("vase.obj: not an image") && !e.contains(":0:"), "{e}");
    std::fs::remove_dir_all(&d).unwrap();
}

/// One ASCII STL triangle with the given line end.
fn ascii_stl(eol: &str) -> String {
    let lines = [
        "solid t",
        "facet normal 0 0 1",
        "outer loop",
        "vertex 0 0 0",
        "vertex 1 0 0",
        "vertex 0 1 0",
        "endloop",
        "endfacet",
        "endsolid t",
    ];
    lines.join(eol) + eol
}

fn load(p: &Path) -> grainline::Result<grainline::mesh::load::LoadedMesh> {
    grainline::mesh::load::load_mesh(p, &Default::default())
}

fn load_err(p: &Path) -> String {
    load(p).expect_err("refused").to_string()
}

// Item 10: an ASCII STL with CR line ends ("without facets") or a UTF-8 BOM ("binary STL
// truncated … 1818521189 triangles") loads; a mesh named `.txt` is read by its content or
// refused naming the file and the extensions read ("empty mesh"); an ASCII PLY vertex line
// of 2 values is reported at its vertex element and line (it was blamed on a face element);
// a face of area 5e37 is not called zero-area, and large faces stay finite downstream.
#[test]
fn item_10_meshes_line_ends_bom_extension_ply_lines_and_large_faces() {
    use grainline::mesh::load::MeshFormat;
    let d = dir("item10");
    let w = |name: &str, bytes: &[u8]| {
        let p = d.join(name);
        std::fs::write(&p, bytes).unwrap();
        p
    };
    for (name, text) in [
        ("crlf.stl", ascii_stl("\r\n")),
        ("cr.stl", ascii_stl("\r")),
        ("bom.stl", format!("\u{feff}{}", ascii_stl("\n"))),
        ("bomcr.stl", format!("\u{feff}{}", ascii_stl("\r"))),
        ("stl.txt", ascii_stl("\r\n")),
    ] {
        let m = load(&w(name, text.as_bytes())).unwrap_or_else(|e| panic!("{name}: {e}"));
        assert_eq!((m.report.format, m.mesh.num_faces()), (MeshFormat::Stl, 1), "{name}");
    }
    // Line numbers count lone CRs: a bad keyword on line 4.
    let bad = ascii_stl("\r").replacen("vertex 0 0 0", "vertux 0 0 0", 1);
    let e = load_err(&w("badcr.stl", bad.as_bytes()));
    assert!(e.contains("badcr.stl:4:"), "{e}");
    // By content: an OBJ, a binary STL and a PLY named .txt; anything else refused.
    let m = load(&w("obj.txt", b"v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\n")).unwrap();
    assert_eq!(m.report.format, MeshFormat::Obj);
    let tri = generate::plane(1.0, generate::Grid::new(1, 1));
    let mut stl = vec![0u8; 80];
    stl.extend((tri.faces.len() as u32).to_le_bytes());
    for f in &tri.faces {
        stl.extend([0u8; 12]);
        for &v in f {
            for k in 0..3 {
                stl.extend((tri.positions[v as usize][k] as f32).to_le_bytes());
            }
        }
        stl.extend([0u8; 2]);
    }
    let m = load(&w("binary.txt", &stl)).unwrap();
    assert_eq!((m.report.format, m.mesh.num_faces()), (MeshFormat::Stl, 2));
    for (name, bytes) in
        [("notes.txt", &b"hello, world\n"[..]), ("empty.txt", b""), ("noext", b"\x01\x02")]
    {
        let e = load_err(&w(name, bytes));
        assert!(
            e.contains(name) && e.contains(".obj, .stl, .ply") && !e.contains("empty mesh"),
            "{e}"
        );
    }
    // An ASCII PLY vertex line of 2 values: its element and its line (12), not a face's.
    let ply = "ply\nformat ascii 1.0\nelement vertex 3\nproperty float x\nproperty float y\n\
               property float z\nelement face 1\nproperty list uchar int vertex_indices\n\
               end_header\n0 0 0\n1 0 0\n0 1\n3 0 1 2\n";
    let e = load_err(&w("two.ply", ply.as_bytes()));
    assert!(
        e.contains("two.ply:12:") && e.contains("vertex element 2") && !e.contains("face"),
        "{e}"
    );
    let e = load_err(&w("four.ply", ply.replace("\n0 1\n", "\n0 1 0 7\n").as_bytes()));
    assert!(e.contains("four.ply:12:") && e.contains("vertex element 2"), "{e}");
    // A needle of area 5e37 within the coordinate bound: a sliver, not a zero-area face.
    let e = load_err(&w("needle.obj", b"v 0 0 0\nv 1e75 0 0\nv 0 1e-37 0\nf 1 2 3\n"));
    assert!(e.contains("needle.obj") && e.contains("sliver") && e.contains("5e37"), "{e}");
    assert!(!e.contains("zero area"), "{e}");
    // Faces of area ~5e37 (and of ~1e148) load whole and give a finite field.
    for s in [1e19, 1e74] {
        let mut part = generate::quadric_patch([0.4, 0.0, -0.4], 1.0, generate::Grid::new(8, 8));
        part.positions.iter_mut().for_each(|p| *p *= s);
        let m = load(&w("large.obj", obj_exact(&part).as_bytes())).unwrap();
        assert_eq!(m.report.dropped_degenerate_faces, 0, "{s}");
        let field = finite_field(&m.mesh);
        assert!(field, "{s}: a non-finite value in the field");
    }
    // A part 1e-150 across: refused naming the bound (its curvatures would overflow).
    let mut tiny = generate::plane(1.0, generate::Grid::new(4, 4));
    tiny.positions.iter_mut().for_each(|p| *p *= 1e-150);
    let e = load_err(&w("tiny.obj", obj_exact(&tiny).as_bytes()));
    assert!(e.contains("tiny.obj") && e.contains("limits::MIN_PART_SIZE"), "{e}");
    std::fs::remove_dir_all(&d).unwrap();
}

/// An OBJ of a mesh's positions (exact, in exponent form) and faces.
fn obj_exact(mesh: &grainline::mesh::Mesh) -> String {
    let v = mesh.positions.iter().map(|p| format!("v {:e} {:e} {:e}\n", p.x, p.y, p.z));
    let f = mesh.faces.iter().map(|f| format!("f {} {} {}\n", f[0] + 1, f[1] + 1, f[2] + 1));
    v.chain(f).collect()
}

/// Whether the initial field and ℓ of a mesh are finite everywhere.
fn finite_field(mesh: &grainline::mesh::Mesh) -> bool {
    use grainline::field::{compute_field, FieldOptions};
    use grainline::highlight::{Lighting, View};
    let light = nalgebra::Vector3::new(0.3, 0.2, 1.0);
    let lighting = Lighting::new(light, View::Direction(nalgebra::Vector3::new(0.0, 0.1, 1.0)));
    let field = compute_field(mesh, &FieldOptions::new(lighting.unwrap())).unwrap();
    let ell = field.highlight.ell.iter().all(|l| l.iter().all(|x| x.is_finite()));
    ell && field.phi.iter().all(|x| x.is_finite())
}

/// An SVG document 100 × 100 mm (viewBox in mm) holding `body`, with the root's `viewBox`.
fn svg_doc(view_box: &str, body: &str) -> String {
    format!(
        "<svg xmlns=\"http://www.w3.org/2000/svg\" width=\"100mm\" height=\"100mm\" \
         viewBox=\"{view_box}\">\n{body}\n</svg>\n"
    )
}

fn svg_err(d: &Path, file: &str, text: &str) -> String {
    let p = d.join(file);
    std::fs::write(&p, text).unwrap();
    let opts = grainline::panel::PanelOptions::default();
    grainline::panel::panel_from_svg(&p, &opts).expect_err("refused").to_string()
}

// Item 11: SVG outlines. `viewBox="0 0 0 0"` ("is not four numbers"), a path syntax error
// ("subpath 1 is open"), coordinates of 1e39 (`FILE:0: no closed outline`), `scale(NaN)`
// (accepted), and a 200,000-point circle written with 6 decimals (refused as self-crossing).
#[test]
fn item_11_svg_outlines_view_box_syntax_bounds_transforms_and_fine_circles() {
    let d = dir("item11");
    let rect = r#"<rect x="10" y="10" width="50" height="40"/>"#;
    let e = svg_err(&d, "vb.svg", &svg_doc("0 0 0 0", rect));
    assert!(e.contains("vb.svg:1:") && e.contains("zero width and height"), "{e}");
    let e = svg_err(&d, "vbw.svg", &svg_doc("0 0 0 100", rect));
    assert!(e.contains("zero width") && !e.contains("four numbers"), "{e}");
    let path = r#"<path d="M 10 10 L 50 10 L 50 x50 L 10 50 Z"/>"#;
    let e = svg_err(&d, "syntax.svg", &svg_doc("0 0 100 100", path));
    assert!(e.contains("syntax.svg:2:") && e.contains("syntax error"), "{e}");
    assert!(e.contains("position 22") && e.contains("x50") && !e.contains("open"), "{e}");
    for (body, attr) in [
        (r#"<path d="M 1e39 10 L 50 10 L 50 50 Z"/>"#, "d:"),
        (r#"<polygon points="10,10 1e39,10 50,50"/>"#, "points:"),
        (r#"<rect x="10" y="10" width="1e39" height="5"/>"#, "width:"),
    ] {
        let e = svg_err(&d, "big.svg", &svg_doc("0 0 100 100", body));
        assert!(e.contains("big.svg:2:") && e.contains(attr) && e.contains("1e39"), "{e}");
        assert!(e.contains("limits::MAX_SVG_NUMBER") && !e.contains(":0:"), "{e}");
    }
    for t in ["scale(NaN)", "scale(0)", "translate(1e39 0)", "rotate(oops)"] {
        let body = format!(r#"<g id="part" transform="{t}">{rect}</g>"#);
        let e = svg_err(&d, "t.svg", &svg_doc("0 0 100 100", &body));
        assert!(
            e.contains("t.svg:2: g element") && e.contains(&format!("transform=\"{t}\"")),
            "{e}"
        );
    }
    // A circle of 200,000 points at 6 decimals, at several radii (the smallest has repeated
    // points once rounded): one simple loop, checked and meshed in well under a second each
    // (the check is timed in src/panel/mod.rs).
    for r in [0.03, 1.0, 40.0] {
        let n = 200_000;
        let pts: Vec<String> = (0..n)
            .map(|i| {
                let t = std::f64::consts::TAU * i as f64 / n as f64;
                format!("{:.6},{:.6}", 50.0 + r * t.cos(), 50.0 + r * t.sin())
            })
            .collect();
        let body = format!(r#"<path d="M{} Z"/>"#, pts.join(" L"));
        let p = d.join("circle.svg");
        std::fs::write(&p, svg_doc("0 0 100 100", &body)).unwrap();
        let loops =
            grainline::panel::read_svg_loops(&std::fs::read_to_string(&p).unwrap(), &p, 0.01)
                .unwrap();
        assert_eq!(loops.len(), 1);
        let opts = grainline::panel::PanelOptions { min_angle_deg: 0.0, ..Default::default() };
        let res = grainline::panel::mesh_loops(&loops, &p, &opts);
        assert!(res.is_ok(), "r = {r}: {}", res.err().unwrap());
    }
    std::fs::remove_dir_all(&d).unwrap();
}

// Item 1, found again by the load benchmark (docs/benchmarks.md): a file of 4 MB or more is read
// by the parallel scanner, which let a face of exactly 10⁶ + 1 corners through (its last corner
// ends at the line's end, where the budget was not checked).
#[test]
fn item_1_parallel_reader_refuses_a_face_one_corner_past_the_budget() {
    use grainline::limits::MAX_POLYGON_CORNERS;
    use grainline::mesh::load::PARALLEL_MIN_BYTES;
    let d = dir("item1p");
    let p = d.join("big.obj");
    let mut s = "v 0.000000 0.000000 0.000000\n".repeat(PARALLEL_MIN_BYTES / 29 + 1);
    s += "v 0 0 0\nv 1 0 0\nv 0 1 0\nf";
    let n = s.matches('v').count();
    let (a, b, c) = (n - 2, n - 1, n);
    for k in 0..=MAX_POLYGON_CORNERS {
        s += &format!(" {}", [a, b, c][k % 3]);
    }
    s += "\n";
    std::fs::write(&p, &s).unwrap();
    let e = load_err(&p);
    assert!(e.contains("big.obj:") && e.contains("limits::MAX_POLYGON_CORNERS"), "{e}");
    std::fs::remove_dir_all(&d).unwrap();
}
