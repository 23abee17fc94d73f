//! `grainline edit`'s server against its safety rules (issue 16), each checked on a real server
//! started by the binary on `--port 0`, with raw HTTP over TCP (no client library that might
//! tidy a request up):
//!
//! - the first stdout line is `http://127.0.0.1:PORT/` with a real port;
//! - it listens on 127.0.0.1 only (127.0.0.2 and ::1, also this machine, are refused);
//! - a `Host` that is not its own (DNS rebinding), or none, gets a 4xx and no content;
//! - a write (`POST`) without its own `Origin`, with a cross-site `Sec-Fetch-Site` or not JSON
//!   is refused and changes nothing;
//! - only the embedded assets and the scene's own file are served: traversal in every
//!   spelling gets a 404 (or 400), never a file;
//! - malformed requests get a 4xx and the server keeps answering;
//! - SIGTERM and SIGINT end it within a second;
//! - after commits and an undo, the FIELD.json the server shows for its newest version is byte
//!   for byte the one `grainline run` writes for the saved scene.

use std::net::TcpStream;
use std::path::PathBuf;
use std::process::Command;
use std::time::{Duration, Instant};

use serde_json::Value;

#[path = "support/editor_http.rs"]
mod editor_http;
use editor_http::*;

#[test]
fn prints_its_url_and_listens_on_127_0_0_1_only() {
    let srv = start("bind");
    let (s, body) = get(srv.port, "/");
    assert_eq!(s, Some(200));
    assert!(body.contains("grainline edit"), "{body}");
    // Other addresses of this machine: another loopback address, and IPv6 loopback.
    for addr in ["127.0.0.2", "::1"] {
        let r = TcpStream::connect_timeout(
            &format!(
                "{}:{}",
                if addr.contains(':') { format!("[{addr}]") } else { addr.into() },
                srv.port
            )
            .parse()
            .unwrap(),
            Duration::from_secs(2),
        );
        assert!(r.is_err(), "{addr}:{} accepted a connection", srv.port);
    }
}

#[test]
fn refuses_a_host_that_is_not_its_own() {
    let srv = start("host");
    let p = srv.port;
    assert_eq!(get_with_host(p, "/api/info", &format!("localhost:{p}")).0, Some(200));
    for host in [
        format!("evil.example:{p}"),
        "evil.example".to_string(),
        format!("127.0.0.1:{}", p.wrapping_add(1)),
        format!("127.0.0.1.evil.example:{p}"),
        "127.0.0.1".to_string(),
    ] {
        let (s, body) = get_with_host(p, "/api/info", &host);
        assert_eq!(s, Some(403), "Host {host}: {body}");
        assert!(!body.contains("vertices"), "Host {host} got content: {body}");
        // Not the page either.
        assert!(!get_with_host(p, "/", &host).1.contains("<html"), "Host {host}");
    }
    // No Host at all (HTTP/1.0), and two of them.
    let (s, _) = raw(p, b"GET /api/info HTTP/1.0\r\n\r\n");
    assert!(matches!(s, Some(400..=499)), "{s:?}");
    let two = format!(
        "GET /api/info HTTP/1.1\r\nHost: 127.0.0.1:{p}\r\nHost: evil.example\r\nConnection: close\r\n\r\n"
    );
    assert!(matches!(raw(p, two.as_bytes()).0, Some(400..=499)));
}

#[test]
fn refuses_cross_origin_writes_and_takes_its_own() {
    let srv = start("origin");
    let p = srv.port;
    let v0 = state(p)["version"].as_u64().unwrap();
    let edit = r#"{"action": "commit", "edit": {"tool": "bend", "centre": {"point": [0, -30, 0]},
        "radius": 20, "strength": 0.5}}"#;
    let json = ("Content-Type", "application/json".to_string());
    let refused: Vec<Vec<(&str, String)>> = vec![
        vec![json.clone()],
        vec![("Origin", "http://evil.example".into()), json.clone()],
        vec![("Origin", format!("http://evil.example:{p}")), json.clone()],
        vec![("Origin", format!("https://127.0.0.1:{p}")), json.clone()],
        vec![("Origin", "null".into()), json.clone()],
        vec![
            ("Origin", format!("http://127.0.0.1:{p}")),
            ("Origin", "http://evil.example".into()),
            json.clone(),
        ],
        [own(p), vec![("Sec-Fetch-Site", "cross-site".into())]].concat(),
        vec![("Origin", format!("http://127.0.0.1:{p}")), ("Content-Type", "text/plain".into())],
        vec![("Origin", format!("http://127.0.0.1:{p}"))],
    ];
    for headers in &refused {
        for path in ["/api/edit", "/api/save", "/api/undo"] {
            let (s, body) = post(p, path, headers, edit);
            assert!(matches!(s, Some(403 | 415)), "{path} with {headers:?}: {s:?} {body}");
        }
    }
    // Nothing changed, nothing was written.
    assert_eq!(state(p)["version"].as_u64().unwrap(), v0);
    let file = std::fs::read_to_string(srv.dir.join("scene.json")).unwrap();
    assert!(!file.contains("bend"), "{file}");
    // The page's own write goes through (also with Sec-Fetch-Site: same-origin).
    let headers = [own(p), vec![("Sec-Fetch-Site", "same-origin".into())]].concat();
    let (s, body) = post(p, "/api/edit", &headers, edit);
    assert_eq!(s, Some(200), "{body}");
    let st = state(p);
    assert_eq!(st["version"].as_u64().unwrap(), v0 + 1);
    assert_eq!(st["edits"][0]["tool"], "bend");
    assert_eq!(st["dirty"], true);
    let (s, body) = post(p, "/api/save", &own(p), "{}");
    assert_eq!(s, Some(200), "{body}");
    let saved = std::fs::read_to_string(srv.dir.join("scene.json")).unwrap();
    let scene = grainline::scene::Scene::from_str(&saved, &srv.dir.join("scene.json")).unwrap();
    assert_eq!(scene.edits.len(), 1);
    assert_eq!(scene.edits[0].tool(), "bend");
}

#[test]
fn serves_only_its_assets_and_the_scenes_file() {
    let srv = start("paths");
    let p = srv.port;
    std::fs::write(srv.dir.join("secret.txt"), "SECRET-CONTENT").unwrap();
    for path in [
        "/etc/passwd",
        "/../../../../etc/passwd",
        "/assets/../../../../etc/passwd",
        "/assets/..%2f..%2f..%2fetc%2fpasswd",
        "/%2e%2e/%2e%2e/%2e%2e/etc/passwd",
        "/files/../secret.txt",
        "/files/secret.txt",
        "/files/part.obj/../secret.txt",
        "/files/%2e%2e/secret.txt",
        "/secret.txt",
        "/assets/",
        "/assets/app.js/../../secret.txt",
        "/assets\\..\\secret.txt",
        "/files//etc/passwd",
        "/./secret.txt",
        "/Cargo.toml",
        "/src/main.rs",
    ] {
        let (s, body) = get(p, path);
        assert!(matches!(s, Some(400 | 404)), "{path}: {s:?}");
        assert!(!body.contains("root:") && !body.contains("SECRET"), "{path}: {body}");
    }
    // Absolute-form and authority-form targets, and a path without its slash.
    for target in [
        format!("http://127.0.0.1:{p}/"),
        "http://evil.example/".into(),
        "127.0.0.1".into(),
        "*".into(),
        "//etc/passwd".into(),
    ] {
        let (s, body) = get(p, &target);
        assert!(matches!(s, Some(400..=499)), "{target}: {s:?} {body}");
    }
    // The scene's own file, byte for byte, and the page's assets with their licence.
    let (s, body) = get(p, "/files/scene.json");
    assert_eq!(s, Some(200));
    assert_eq!(body, std::fs::read_to_string(srv.dir.join("scene.json")).unwrap());
    for (path, needle) in [
        ("/assets/app.js", "OrbitControls"),
        ("/assets/three.module.js", "Three.js Authors"),
        ("/assets/OrbitControls.js", "from './three.module.js'"),
        ("/assets/three-LICENSE.txt", "MIT"),
    ] {
        let (s, body) = get(p, path);
        assert_eq!(s, Some(200), "{path}");
        assert!(body.contains(needle), "{path} lacks {needle}");
    }
}

#[test]
fn malformed_requests_get_a_4xx_and_the_server_goes_on() {
    let srv = start("malformed");
    let p = srv.port;
    let bad: Vec<Vec<u8>> = vec![
        b"\x00\x01\x02garbage\r\n\r\n".to_vec(),
        b"GET\r\n\r\n".to_vec(),
        format!("BREW / HTTP/1.1\r\nHost: 127.0.0.1:{p}\r\nConnection: close\r\n\r\n").into_bytes(),
        format!("DELETE /api/state HTTP/1.1\r\nHost: 127.0.0.1:{p}\r\nConnection: close\r\n\r\n")
            .into_bytes(),
        format!("GET / HTTP/1.1\r\nHost: 127.0.0.1:{p}\r\nBroken header line\r\n\r\n").into_bytes(),
        format!(
            "POST /api/edit HTTP/1.1\r\nHost: 127.0.0.1:{p}\r\nOrigin: http://127.0.0.1:{p}\r\n\
             Content-Type: application/json\r\nContent-Length: 99999999\r\nConnection: close\r\n\r\n{{"
        )
        .into_bytes(),
        format!("GET /{} HTTP/1.1\r\nHost: 127.0.0.1:{p}\r\nConnection: close\r\n\r\n", "a".repeat(5000))
            .into_bytes(),
    ];
    for rq in &bad {
        let (s, _) = raw(p, rq);
        // A 4xx, or the connection closed without an answer (no status at all); never 2xx/5xx.
        assert!(
            s.is_none() || matches!(s, Some(400..=499)),
            "{:?}: {s:?}",
            String::from_utf8_lossy(rq)
        );
        assert_eq!(get(p, "/api/info").0, Some(200), "after {:?}", String::from_utf8_lossy(rq));
    }
    // Bad JSON, bad edits, bad queries: 400 with a message naming the problem.
    for (body, needle) in [
        ("{", "request"),
        ("[]", "request"),
        (r#"{"action": "commit"}"#, "action"),
        (r#"{"action": "jump", "edit": null}"#, "action"),
        (r#"{"action": "commit", "extra": 1}"#, "extra"),
        (r#"{"action": "commit", "edit": {"tool": "bend", "radius": 5}}"#, "centre"),
        (
            r#"{"action": "commit", "edit": {"tool": "bend", "centre": {"point": [0,0,0]}, "radius": 5, "radious": 3}}"#,
            "radious",
        ),
        (
            r#"{"action": "commit", "edit": {"tool": "bend", "centre": {"point": [0,0,0]}, "radius": -5}}"#,
            "radius",
        ),
        (
            r#"{"action": "commit", "edit": {"tool": "bend", "centre": {"point": [0,0,0]}, "radius": 5, "strength": 9}}"#,
            "strength",
        ),
        (
            r#"{"action": "commit", "edit": {"tool": "bend", "centre": {"vertex": 99999999}, "radius": 5}}"#,
            "vertex",
        ),
        (
            r#"{"action": "commit", "edit": {"tool": "curve", "svg": "/etc/passwd", "radius": 5}}"#,
            "svg",
        ),
        (
            r#"{"action": "commit", "edit": {"tool": "move_light", "light": [0, 0, 1]}}"#,
            "move_light",
        ),
    ] {
        let (s, r) = post(p, "/api/edit", &own(p), body);
        assert_eq!(s, Some(400), "{body}: {r}");
        assert!(r.contains(needle), "{body}: {r} does not name {needle}");
    }
    assert_eq!(post(p, "/api/undo", &own(p), "{}").0, Some(400));
    assert_eq!(get(p, "/api/state?after=x").0, Some(400));
    assert_eq!(get(p, "/api/grain?version=123456").0, Some(409));
    assert_eq!(state(p)["edits"].as_array().unwrap().len(), 0);
}

fn ends_on(signal: &str, code: i32) {
    let mut srv = start(&format!("signal-{signal}"));
    // Serving (the page answers) and idle.
    assert_eq!(get(srv.port, "/api/info").0, Some(200));
    let ok = Command::new("kill")
        .args([&format!("-{signal}"), &srv.child.id().to_string()])
        .status()
        .unwrap();
    assert!(ok.success());
    let t = Instant::now();
    let status = loop {
        if let Some(s) = srv.child.try_wait().unwrap() {
            break s;
        }
        assert!(t.elapsed() < Duration::from_secs(1), "still running 1 s after SIG{signal}");
        std::thread::sleep(Duration::from_millis(10));
    };
    assert_eq!(status.code(), Some(code));
}

#[test]
fn sigterm_and_sigint_end_it_within_a_second() {
    ends_on("TERM", 143);
    ends_on("INT", 130);
}

/// Waits (bounded) until the newest version is solved; returns it.
#[test]
fn saved_scene_reproduces_the_shown_field_byte_for_byte() {
    let srv = start("save");
    let p = srv.port;
    let commit = |edit: &str| {
        let (s, b) =
            post(p, "/api/edit", &own(p), &format!(r#"{{"action": "commit", "edit": {edit}}}"#));
        assert_eq!(s, Some(200), "{edit}: {b}");
    };
    commit(
        r#"{"tool": "bend", "centre": {"point": [0, -30, 5]}, "radius": 25, "strength": 0.7, "direction": [1, 0, 0.2]}"#,
    );
    commit(r#"{"tool": "stencil", "centre": {"point": [25, -20, -20]}, "radius": 12}"#);
    commit(
        r#"{"tool": "expand", "centre": {"point": [-20, -20, 20]}, "radius": 15, "strength": 0.5}"#,
    );
    assert_eq!(post(p, "/api/undo", &own(p), "{}").0, Some(200));
    let v = solved(p);
    let (s, shown) = get(p, &format!("/api/field.json?version={v}"));
    assert_eq!(s, Some(200));
    std::fs::write(srv.dir.join("shown.json"), &shown).unwrap();
    let scene = save_and_run(&srv);
    let saved = std::fs::read_to_string(&scene).unwrap();
    let parsed = grainline::scene::Scene::from_str(&saved, &scene).unwrap();
    let tools: Vec<&str> = parsed.edits.iter().map(|e| e.tool()).collect();
    assert_eq!(tools, ["bend", "stencil"]);
    let ran = std::fs::read_to_string(srv.dir.join("field.json")).unwrap();
    assert!(ran.contains("phi_before"), "not an optimized field");
    assert!(ran == shown, "run: {} bytes, shown: {} bytes", ran.len(), shown.len());
}

/// The little-endian `u32` at byte `k` of `b`.
fn u32_at(b: &[u8], k: usize) -> u32 {
    u32::from_le_bytes(b[k..k + 4].try_into().unwrap())
}

/// Drags a bend (two previews), commits it, saves; returns the vertex counts of the grain
/// during the drag and after the commit, the committed grain's part id, and whether `grainline
/// run` on the saved scene wrote the FIELD.json the server showed byte for byte.
fn drag_commit_save_run(srv: &Server) -> (u32, u32, u32, bool) {
    let p = srv.port;
    let bend = |s: f64| {
        format!(
            r#"{{"tool": "bend", "centre": {{"point": [0, -30, 5]}}, "radius": 25, "strength": {s}, "direction": [1, 0, 0.2]}}"#
        )
    };
    let send = |action: &str, edit: &str| {
        let body = format!(r#"{{"action": "{action}", "edit": {edit}}}"#);
        let (s, b) = post(p, "/api/edit", &own(p), &body);
        assert_eq!(s, Some(200), "{body}: {b}");
    };
    let grain = |v: u64| {
        let (s, g) = get_bytes(p, &format!("/api/grain?version={v}"));
        assert_eq!(s, Some(200));
        (u32_at(&g, 0), u32_at(&g, 12))
    };
    send("preview", &bend(0.3));
    send("preview", &bend(0.6));
    let (dragged, _) = grain(solved(p));
    send("commit", &bend(0.7));
    let v = solved(p);
    let (committed, part) = grain(v);
    // The page loads the committed grain's mesh: its vertex count is the grain's.
    let (s, mesh) = get_bytes(p, &format!("/api/mesh?part={part}"));
    assert_eq!(s, Some(200));
    assert_eq!(u32_at(&mesh, 0), committed);
    let (s, shown) = get_bytes(p, &format!("/api/field.json?version={v}"));
    assert_eq!(s, Some(200));
    save_and_run(srv);
    let ran = std::fs::read(srv.dir.join("field.json")).unwrap();
    let field: Value = serde_json::from_slice(&ran).unwrap();
    assert_eq!(field["u"].as_array().unwrap().len(), committed as usize);
    (dragged, committed, part, ran == shown)
}

/// Issue 16 with refinement (issue 13): on a part coarse enough for the brush to be refined,
/// the drag is solved on the part as loaded and the committed bend on the part refined inside
/// its brush, as `grainline run` refines it; the saved scene reproduces the shown FIELD.json.
#[test]
fn a_bend_on_a_coarse_part_is_refined_when_committed_and_the_run_reproduces_it() {
    let srv = start("refine");
    let coarse = 32 * 9; // the cylinder's vertices: 32 around, 9 rings
    let (s, mesh) = get_bytes(srv.port, "/api/mesh");
    assert_eq!(s, Some(200));
    assert_eq!(u32_at(&mesh, 0), coarse);
    let (dragged, committed, part, same) = drag_commit_save_run(&srv);
    assert_eq!(dragged, coarse, "a drag step is solved on the part as loaded");
    assert!(committed > coarse, "the committed bend was not refined: {committed} vertices");
    assert_ne!(part, 0);
    assert!(same, "the run's FIELD.json differs from the one shown");
    assert_eq!(get(srv.port, "/api/mesh?part=99").0, Some(404));
    // Undo: back on the part as loaded; redo: the same brushes, so the refinement kept for
    // them is shown again (not made anew, which would number a new part).
    let p = srv.port;
    let part_now = || {
        let (s, g) = get_bytes(p, &format!("/api/grain?version={}", solved(p)));
        assert_eq!(s, Some(200));
        (u32_at(&g, 0), u32_at(&g, 12))
    };
    assert_eq!(post(p, "/api/undo", &own(p), "{}").0, Some(200));
    assert_eq!(part_now(), (coarse, 0));
    assert_eq!(post(p, "/api/redo", &own(p), "{}").0, Some(200));
    assert_eq!(part_now(), (committed, part));
}

/// `mesh.refine.mode: "none"`: nothing is refined, and the run still reproduces the field.
#[test]
fn with_refinement_off_the_committed_bend_stays_on_the_part_as_loaded() {
    let scene = SCENE.replace(
        r#""mesh": "part.obj""#,
        r#""mesh": {"path": "part.obj", "refine": {"mode": "none"}}"#,
    );
    let srv = start_with("norefine", &scene);
    let (dragged, committed, part, same) = drag_commit_save_run(&srv);
    assert_eq!((dragged, committed, part), (32 * 9, 32 * 9, 0));
    assert!(same, "the run's FIELD.json differs from the one shown");
}

/// Issue 16, export: after a committed bend, `POST /api/export` writes the SVG and the G-code
/// the scene names, byte for byte the files `grainline run` writes for the saved scene, and a
/// glTF binary beside the scene file (the scene names none): magic `glTF`, version 2, the
/// header's length the file's. A scene without UVs or a `toolpaths` section is told the key.
#[test]
fn export_writes_what_the_run_of_the_saved_scene_writes() {
    let scene = SCENE.replace(
        r#""field": {"#,
        r#""toolpaths": {"svg": "strokes.svg", "gcode": "strokes.ngc"}, "field": {"#,
    );
    let srv = start_with("export", &scene);
    let p = srv.port;
    let bend = r#"{"tool": "bend", "centre": {"point": [0, -30, 5]}, "radius": 25, "strength": 0.7, "direction": [1, 0, 0.2]}"#;
    let (s, b) =
        post(p, "/api/edit", &own(p), &format!(r#"{{"action": "commit", "edit": {bend}}}"#));
    assert_eq!(s, Some(200), "{b}");
    let export = |what: &str| {
        let (s, b) = post(p, "/api/export", &own(p), &format!(r#"{{"what": "{what}"}}"#));
        assert_eq!(s, Some(200), "{what}: {b}");
        let v: Value = serde_json::from_str(&b).unwrap();
        let path = PathBuf::from(v["written"].as_str().unwrap());
        (path.clone(), std::fs::read(&path).unwrap())
    };
    let (svg_path, svg) = export("svg");
    let (gcode_path, gcode) = export("gcode");
    assert_eq!(svg_path, srv.dir.join("strokes.svg"));
    assert_eq!(gcode_path, srv.dir.join("strokes.ngc"));
    assert!(svg.starts_with(b"<?xml") || svg.starts_with(b"<svg"), "not an SVG");
    let (glb_path, glb) = export("glb");
    assert_eq!(glb_path, srv.dir.join("scene.glb"));
    assert_eq!(&glb[0..4], b"glTF");
    assert_eq!(u32_at(&glb, 4), 2);
    assert_eq!(u32_at(&glb, 8) as usize, glb.len());
    // A cross-origin export is refused like every write; an unknown kind is a 400.
    let (s, _) = post(p, "/api/export", &[own(p)[1].clone()], r#"{"what": "svg"}"#);
    assert_eq!(s, Some(403));
    assert_eq!(post(p, "/api/export", &own(p), r#"{"what": "obj"}"#).0, Some(400));
    // The saved scene's run writes the same bytes.
    std::fs::remove_file(&svg_path).unwrap();
    std::fs::remove_file(&gcode_path).unwrap();
    save_and_run(&srv);
    assert!(std::fs::read(&svg_path).unwrap() == svg, "the run's SVG differs from the export");
    assert!(std::fs::read(&gcode_path).unwrap() == gcode, "the run's G-code differs");
    // The strokes shown are the run's: as many, on the part (radius 30), and the as-brushed
    // grain a unit vector (or zero) per vertex of the committed part.
    let report: Value =
        serde_json::from_slice(&std::fs::read(srv.dir.join("run-report.json")).unwrap()).unwrap();
    let run_strokes = report["toolpaths"]["job"]["stroke_count"].as_u64().unwrap();
    let v = solved(p);
    let (s, b) = get_bytes(p, &format!("/api/strokes?version={v}"));
    assert_eq!(s, Some(200));
    let (n_strokes, n_points, n_vertices) = (u32_at(&b, 0), u32_at(&b, 4), u32_at(&b, 8));
    assert!(n_strokes > 0);
    assert_eq!(u64::from(n_strokes), run_strokes);
    assert_eq!(u64::from(n_vertices), report["vertices"].as_u64().unwrap());
    let f32_at = |k: usize| f32::from_le_bytes(b[k..k + 4].try_into().unwrap());
    let points = 16 + 4 * n_strokes as usize;
    let lengths: u32 = (0..n_strokes as usize).map(|i| u32_at(&b, 16 + 4 * i)).sum();
    assert_eq!(lengths, n_points);
    assert_eq!(b.len(), points + 12 * (n_points + n_vertices) as usize);
    for i in 0..n_points as usize {
        let q = [0, 1, 2].map(|c| f64::from(f32_at(points + 12 * i + 4 * c)));
        let r = q[0].hypot(q[1]);
        assert!((r - 30.0).abs() < 0.5, "stroke point {i} at radius {r}");
    }
    let brushed = points + 12 * n_points as usize;
    let mut units = 0;
    for i in 0..n_vertices as usize {
        let u = [0, 1, 2].map(|c| f64::from(f32_at(brushed + 12 * i + 4 * c)));
        let norm = (u[0] * u[0] + u[1] * u[1] + u[2] * u[2]).sqrt();
        assert!(norm < 1e-6 || (norm - 1.0).abs() < 1e-4, "as-brushed u at {i}: {norm}");
        units += usize::from(norm > 0.5);
    }
    assert!(units > n_vertices as usize / 2, "{units} of {n_vertices} vertices brushed");
}

/// A part without UVs and a scene without `toolpaths`: the export says which key to add and
/// writes nothing; the glTF binary, which needs no layout, is written.
#[test]
fn export_without_a_layout_names_the_key_to_add() {
    let scene = SCENE.replace(r#""init": "uv""#, r#""init": "smooth""#);
    let dir = scene_dir_with("export-nouv", &scene);
    let mut cylinder = grainline::generate::cylinder(30.0, 80.0, 32, 8);
    cylinder.uv = None;
    std::fs::write(dir.join("part.obj"), grainline::mesh::write::obj_string(&cylinder, "t"))
        .unwrap();
    let srv = start_in(dir);
    let p = srv.port;
    let (s, b) = post(p, "/api/export", &own(p), r#"{"what": "gcode"}"#);
    assert_eq!(s, Some(400), "{b}");
    assert!(b.contains("toolpaths") && b.contains("UV"), "{b}");
    assert!(!srv.dir.join("scene.ngc").exists());
    let v = solved(p);
    let (s, b) = get(p, &format!("/api/strokes?version={v}"));
    assert_eq!(s, Some(400), "{b}");
    assert!(b.contains("toolpaths"), "{b}");
    let (s, b) = post(p, "/api/export", &own(p), r#"{"what": "glb"}"#);
    assert_eq!(s, Some(200), "{b}");
    assert!(srv.dir.join("scene.glb").exists());
}

/// Issue 16, the light gizmo: `POST /api/light` turns the key light as a scene change; the
/// field shown after a bend under the new light is byte for byte the one `grainline run`
/// writes for the saved scene, whose `lights` hold the new direction; undo brings the light
/// as read back; a zero direction is refused.
#[test]
fn a_key_light_set_on_the_page_is_saved_and_the_run_reproduces_the_field() {
    let srv = start("light");
    let p = srv.port;
    let bend = r#"{"tool": "bend", "centre": {"point": [0, -30, 5]}, "radius": 25, "strength": 0.7, "direction": [1, 0, 0.2]}"#;
    let (s, b) =
        post(p, "/api/edit", &own(p), &format!(r#"{{"action": "commit", "edit": {bend}}}"#));
    assert_eq!(s, Some(200), "{b}");
    let before = solved(p);
    let (_, under_old) = get(p, &format!("/api/field.json?version={before}"));
    assert_eq!(post(p, "/api/light", &own(p), r#"{"direction": [0, 0, 0]}"#).0, Some(400));
    let (s, _) = post(p, "/api/light", &[own(p)[1].clone()], r#"{"direction": [0.6, -0.8, 0]}"#);
    assert_eq!(s, Some(403));
    let (s, b) = post(p, "/api/light", &own(p), r#"{"direction": [1.2, -1.6, 2]}"#);
    assert_eq!(s, Some(200), "{b}");
    let v = solved(p);
    let st = state(p);
    let l: Vec<f64> = st["light"].as_array().unwrap().iter().map(|c| c.as_f64().unwrap()).collect();
    let n = (1.2f64 * 1.2 + 1.6 * 1.6 + 4.0).sqrt();
    assert!((l[0] - 1.2 / n).abs() < 1e-12 && (l[2] - 2.0 / n).abs() < 1e-12, "{l:?}");
    assert_eq!(st["dirty"], true);
    let (s, shown) = get(p, &format!("/api/field.json?version={v}"));
    assert_eq!(s, Some(200));
    assert!(shown != under_old, "the field did not change with the light");
    let scene = save_and_run(&srv);
    let saved: Value = serde_json::from_str(&std::fs::read_to_string(&scene).unwrap()).unwrap();
    let d: Vec<f64> = saved["lights"][0]["direction"]
        .as_array()
        .unwrap()
        .iter()
        .map(|c| c.as_f64().unwrap())
        .collect();
    assert_eq!(d, l);
    assert_eq!(saved["edits"].as_array().unwrap().len(), 1);
    let ran = std::fs::read_to_string(srv.dir.join("field.json")).unwrap();
    assert!(ran == shown, "run: {} bytes, shown: {} bytes", ran.len(), shown.len());
    // Undo: the light as read, the field as before it turned.
    assert_eq!(post(p, "/api/undo", &own(p), "{}").0, Some(200));
    let v = solved(p);
    assert!(state(p)["light"].is_null());
    let (_, back) = get(p, &format!("/api/field.json?version={v}"));
    assert!(back == under_old, "undo did not bring the old light's field back");
}

/// The `Threads:` and `VmRSS:` (kB) of a process, from /proc.
fn threads_and_rss(pid: u32) -> (usize, usize) {
    let status = std::fs::read_to_string(format!("/proc/{pid}/status")).unwrap_or_default();
    let field = |name: &str| {
        status
            .lines()
            .find_map(|l| l.strip_prefix(name))
            .and_then(|v| v.split_whitespace().next().and_then(|n| n.parse().ok()))
            .unwrap_or(0)
    };
    (field("Threads:"), field("VmRSS:"))
}

// Issue 30, item 5: 200 partial connections (half a request, then silence) kept 211 threads
// alive and grew the editor from 71 to 259 MB. At most 32 connections are handled at once
// (more get a 503 at once), a request's head must arrive within 10 s, and then the server
// answers as before.
#[test]
fn issue30_item5_partial_connections_are_bounded() {
    use std::io::{Read, Write};
    let srv = start("partial");
    let p = srv.port;
    assert_eq!(get(p, "/api/info").0, Some(200));
    let pid = srv.child.id();
    let (threads0, rss0) = threads_and_rss(pid);
    let mut stalled = Vec::new();
    for _ in 0..200 {
        let mut s = TcpStream::connect(("127.0.0.1", p)).unwrap();
        let _ =
            s.write_all(format!("GET /api/info HTTP/1.1\r\nHost: 127.0.0.1:{p}\r\nX-").as_bytes());
        stalled.push(s);
    }
    std::thread::sleep(Duration::from_millis(500));
    let (threads, rss) = threads_and_rss(pid);
    assert!(threads <= threads0 + 34, "{threads0} threads before, {threads} with 200 stalled");
    assert!(rss < rss0 + 40_000, "{rss0} kB before, {rss} kB with 200 stalled");
    // The ones beyond the bound were answered 503 and closed.
    let mut busy = 0;
    for s in &mut stalled {
        s.set_read_timeout(Some(Duration::from_millis(20))).unwrap();
        let mut b = [0u8; 12];
        if matches!(s.read(&mut b), Ok(12) if b.starts_with(b"HTTP/1.1 503")) {
            busy += 1;
        }
    }
    assert!(busy >= 200 - 32, "{busy} connections answered 503");
    // After the head's time limit the stalled ones are closed (408), and requests are served.
    let t = Instant::now();
    loop {
        if get(p, "/api/info").0 == Some(200) {
            break;
        }
        assert!(t.elapsed() < Duration::from_secs(15), "still busy after {:?}", t.elapsed());
        std::thread::sleep(Duration::from_millis(250));
    }
    drop(stalled);
    std::thread::sleep(Duration::from_millis(300));
    let (threads, _) = threads_and_rss(pid);
    assert!(threads <= threads0 + 2, "{threads0} threads before, {threads} after");
}

// Issue 30, item 5: `/api/save` with a garbage body saved anyway; a bend of radius 1e30 and a
// key light the scene file refuses were accepted and saved. Each is a 400 naming what is wrong,
// with the scene file's own checks, and nothing is saved.
#[test]
fn issue30_item5_api_refuses_what_the_scene_file_refuses() {
    // The eye straight above the part: a key light of [0, 0, -1] points straight away from it.
    let text = SCENE.replace(r#""eye": [0, -300, 0]"#, r#""eye": [0, 0, 300], "up": [0, 1, 0]"#);
    let srv = start_with("refuse", &text);
    let p = srv.port;
    let scene = srv.dir.join("scene.json");
    let before = std::fs::read(&scene).unwrap();
    for body in ["garbage", "[]", r#"{"path": "/tmp/x.json"}"#] {
        let (s, r) = post(p, "/api/save", &own(p), body);
        assert_eq!(s, Some(400), "{body}: {r}");
        assert!(r.contains("/api/save takes {}"), "{body}: {r}");
    }
    let bend = r#"{"action": "commit", "edit": {"tool": "bend", "centre": {"point": [30, 0, 0]}, "radius": 1e30}}"#;
    let (s, r) = post(p, "/api/edit", &own(p), bend);
    assert_eq!(s, Some(400), "{r}");
    assert!(r.contains("radius") && r.contains("1e30") && r.contains("MAX_EDIT_RADIUS"), "{r}");
    let (s, r) = post(p, "/api/light", &own(p), r#"{"direction": [0, 0, -1]}"#);
    assert_eq!(s, Some(400), "{r}");
    assert!(r.contains("lights[0].direction"), "{r}");
    // The scene file says the same of the same values.
    let path = std::path::Path::new("s.json");
    let light = text.replace("[0.3, -0.5, 1]", "[0, 0, -1]");
    let e = grainline::scene::Scene::from_str(&light, path).unwrap_err().to_string();
    assert!(e.contains("lights[0].direction"), "{e}");
    let edit = r#", "edits": [{"tool": "bend", "centre": {"point": [30, 0, 0]}, "radius": 1e30}]}"#;
    let plain = format!(
        r#"{{"mesh": "part.obj", "view": {{"eye": [0, 0, 300], "up": [0, 1, 0]}},
            "lights": [{{"type": "directional", "direction": [0.3, -0.5, 1]}}]{edit}"#
    );
    let e = grainline::scene::Scene::from_str(&plain, path).unwrap_err().to_string();
    assert!(e.contains("edits[0].radius") && e.contains("MAX_EDIT_RADIUS"), "{e}");
    assert_eq!(std::fs::read(&scene).unwrap(), before, "nothing was saved");
    assert_eq!(state(p)["edits"].as_array().unwrap().len(), 0);
}

// Issue 46, item 3: a curve preview of 60k points used to run for over a minute and reach
// 5.3 GB. The refinement a curve would ask for is estimated when the request arrives, with
// the estimate `grainline run` makes before any split: past `mesh.refine.max_vertices` the
// preview (and the commit) is a 400 at once naming the edit and the budget, and nothing
// changes.
#[test]
fn issue46_an_over_budget_curve_preview_is_refused_at_once() {
    let text = SCENE.replace(
        r#""mesh": "part.obj""#,
        r#""mesh": {"path": "part.obj", "refine": {"max_vertices": 5000}}"#,
    );
    let srv = start_with("overbudget", &text);
    let p = srv.port;
    solved(p);
    let before = state(p);
    // A zigzag over the cylinder's side (r = 30, z in [-40, 40]), 20k points, r = 0.5 mm.
    let points: Vec<String> = (0..20_000)
        .map(|i| {
            let a = std::f64::consts::TAU * i as f64 / 20_000.0;
            let z = if i % 2 == 0 { -30 } else { 30 };
            format!("[{:.2},{:.2},{z}]", 30.0 * a.cos(), 30.0 * a.sin())
        })
        .collect();
    let edit = format!(r#"{{"tool": "curve", "points": [[{}]], "radius": 0.5}}"#, points.join(","));
    for action in ["preview", "commit"] {
        let body = format!(r#"{{"action": "{action}", "edit": {edit}}}"#);
        let t = Instant::now();
        let (s, r) = post(p, "/api/edit", &own(p), &body);
        let took = t.elapsed();
        assert_eq!(s, Some(400), "{action}: {r}");
        assert!(
            r.contains("edits[0]") && r.contains("mesh.refine.max_vertices") && r.contains("5000"),
            "{action}: {r}"
        );
        // Refused from an estimate (the refinement would take minutes); 2 s of slack for a
        // loaded machine.
        assert!(took < Duration::from_secs(3), "{action} took {took:?}");
    }
    let after = state(p);
    for key in ["version", "edits", "previewing", "undo"] {
        assert_eq!(after[key], before[key], "{key}");
    }
}

// Issue 46, item 3: the handler kept computing after its client left, holding its connection
// slot. An export (a whole run of the committed edits) whose client closes the connection is
// cancelled: its work stops at the next check point, its threads end (the slot is free), no
// file and no temporary is written, the session is as it was, and the next request is
// answered at once. Each check point inside the request pauses 1 s (a testing aid,
// `GRAINLINE_TEST_CHECKPOINT_PAUSE_MS`), so the export takes at least 2 s unless cancelled,
// and one that went on to its end would leave its file.
#[test]
fn issue46_work_for_a_client_that_left_is_cancelled() {
    use std::io::Write;
    let env = [(grainline::cancel::CHECKPOINT_PAUSE_ENV, "1000")];
    let srv = start_in_env(scene_dir_with("cancel", SCENE), &env);
    let p = srv.port;
    let pid = srv.child.id();
    let v = solved(p);
    let before = state(p);
    let (threads0, _) = threads_and_rss(pid);
    let body = r#"{"what": "glb"}"#;
    let mut s = TcpStream::connect(("127.0.0.1", p)).unwrap();
    let rq = format!(
        "POST /api/export HTTP/1.1\r\nHost: 127.0.0.1:{p}\r\nOrigin: http://127.0.0.1:{p}\r\n\
         Content-Type: application/json\r\nContent-Length: {}\r\n\r\n{body}",
        body.len()
    );
    s.write_all(rq.as_bytes()).unwrap();
    // The export is under way (its connection's thread and its work's)...
    std::thread::sleep(Duration::from_millis(300));
    assert!(threads_and_rss(pid).0 > threads0, "the export is not running");
    // ... when its client leaves.
    drop(s);
    let t = Instant::now();
    while threads_and_rss(pid).0 > threads0 {
        assert!(t.elapsed() < Duration::from_secs(30), "the export's threads still run");
        std::thread::sleep(Duration::from_millis(50));
    }
    let t = Instant::now();
    assert_eq!(get(p, "/api/info").0, Some(200));
    assert!(t.elapsed() < Duration::from_secs(5), "answered after {:?}", t.elapsed());
    // The export wrote nothing: it was cancelled, not finished unseen.
    std::thread::sleep(Duration::from_millis(2500));
    let files: Vec<String> = std::fs::read_dir(&srv.dir)
        .unwrap()
        .map(|e| e.unwrap().file_name().to_string_lossy().into_owned())
        .collect();
    assert!(!files.iter().any(|f| f.ends_with(".glb") || f.ends_with(".tmp")), "{files:?}");
    let after = state(p);
    for key in ["version", "solved_version", "edits", "error"] {
        assert_eq!(after[key], before[key], "{key}");
    }
    assert_eq!(after["version"].as_u64(), Some(v));
    // The same export, waited for, is written: the session was left as it was.
    let (status, r) = post(p, "/api/export", &own(p), body);
    assert_eq!(status, Some(200), "{r}");
    assert!(srv.dir.join("scene.glb").exists(), "{r}");
}

// Issue 46, item 3: a solve made stale by a change ran to its end before the newer version
// was solved. A bend committed and undone at once is dropped at the solver's next check point:
// the state is solved again long before that bend's solve could have ended. Check points
// pause 300 ms (`GRAINLINE_TEST_CHECKPOINT_PAUSE_MS`): a commit's solve (refinement levels,
// stages, edits, iterations, fidelity) takes seconds, its cancellation one pause.
#[test]
fn issue46_a_stale_solve_is_cancelled() {
    let env = [(grainline::cancel::CHECKPOINT_PAUSE_ENV, "300")];
    let srv = start_in_env(scene_dir_with("stale", SCENE), &env);
    let p = srv.port;
    solved(p);
    let bend = |x: i32| {
        format!(
            r#"{{"action": "commit", "edit": {{"tool": "bend", "centre": {{"point": [{x}, 0, 0]}},
                "radius": 20, "strength": 0.6}}}}"#
        )
    };
    // A commit solved to its end: how long a solve takes.
    let t = Instant::now();
    assert_eq!(post(p, "/api/edit", &own(p), &bend(30)).0, Some(200));
    solved(p);
    let full = t.elapsed().as_secs_f64();
    assert_eq!(post(p, "/api/undo", &own(p), "{}").0, Some(200));
    solved(p);
    let before = state(p);
    // Another bend (another refinement), undone at once.
    assert_eq!(post(p, "/api/edit", &own(p), &bend(-30)).0, Some(200));
    let t = Instant::now();
    assert_eq!(post(p, "/api/undo", &own(p), "{}").0, Some(200));
    let v = solved(p);
    let took = t.elapsed().as_secs_f64();
    let after = state(p);
    assert_eq!(after["solved_version"].as_u64(), Some(v));
    assert_eq!(after["edits"], before["edits"]);
    assert!(after["error"].is_null(), "{}", after["error"]);
    assert!(after["dropped"].as_u64() > before["dropped"].as_u64(), "{after}");
    assert!(took < 0.5 * full, "solved again after {took:.1} s; a solve takes {full:.1} s");
}
