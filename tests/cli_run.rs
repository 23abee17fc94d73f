//! `grainline run` end to end: only the stages a scene needs run, outputs are byte-identical
//! at one and two threads, stage times add up, bad scenes are named.

use std::path::{Path, PathBuf};
use std::process::{Command, Output};

use grainline::generate;
use grainline::mesh::write::obj_string;

fn dir(name: &str) -> PathBuf {
    let d = std::env::temp_dir().join(format!("grainline-cli-run-{}-{name}", std::process::id()));
    std::fs::create_dir_all(&d).unwrap();
    d
}

/// A small vase of revolution (UVs = angle, height) next to the scene.
fn write_part(d: &Path) {
    let mesh =
        generate::revolve(|t| (30.0 + 8.0 * (std::f64::consts::PI * t).sin(), 60.0 * t), 48, 24);
    std::fs::write(d.join("vase.obj"), obj_string(&mesh, "test vase")).unwrap();
}

fn scene(d: &Path, edits: &str, toolpaths: &str, render: &str) -> PathBuf {
    let s = format!(
        r#"{{
  "mesh": "vase.obj",
  "lights": [{{"type": "directional", "direction": [0.3, -0.5, 1]}}],
  "view": {{"eye": [0, -200, 80], "target": [0, 0, 30]}},
  "field": {{"init": "uv"}},
  "edits": {edits}{toolpaths}{render}
}}"#
    );
    let p = d.join("scene.json");
    std::fs::write(&p, s).unwrap();
    p
}

const BEND: &str =
    r#"[{"tool": "bend", "centre": {"point": [0, -36, 30]}, "radius": 15, "strength": 0.5}]"#;
const TOOLPATHS: &str = r#",
  "toolpaths": {"svg": "o/v.svg", "gcode": "o/v.ngc", "strokes_json": "o/v.json", "placement": {"width": 3}}"#;
const RENDER: &str = r#",
  "render": {"width": 96, "height": 96, "output": "o/v.png", "effects": {"strokes": {}}}"#;

fn run(args: &[&str]) -> Output {
    Command::new(env!("CARGO_BIN_EXE_grainline")).args(args).output().unwrap()
}

fn report(p: &Path) -> serde_json::Value {
    serde_json::from_slice(&std::fs::read(p).unwrap()).unwrap()
}

fn stage_names(r: &serde_json::Value) -> Vec<String> {
    r["stages"].as_array().unwrap().iter().map(|s| s["stage"].as_str().unwrap().into()).collect()
}

#[test]
fn full_scene_writes_every_output_byte_identically_at_1_and_2_threads() {
    let d = dir("full");
    write_part(&d);
    let sc = scene(&d, BEND, TOOLPATHS, RENDER);
    let mut bytes = Vec::new();
    let mut brushed = Vec::new();
    for t in ["1", "2"] {
        let out = d.join(format!("t{t}"));
        let o = run(&[
            "--quiet",
            "--threads",
            t,
            "run",
            sc.to_str().unwrap(),
            "--out-dir",
            out.to_str().unwrap(),
        ]);
        assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
        let files: Vec<Vec<u8>> = ["o/v.svg", "o/v.ngc", "o/v.json", "o/v.png"]
            .iter()
            .map(|f| std::fs::read(out.join(f)).unwrap())
            .collect();
        assert!(files.iter().all(|f| !f.is_empty()));
        let r = report(&out.join("run-report.json"));
        // `brush width` runs exactly when an edit lands as designed but not as brushed.
        let lost = r["as_brushed"]["carrying_width"].as_array().is_some_and(|c| !c.is_empty());
        let mut want = vec!["load", "refine", "field", "edits", "solve", "toolpaths"];
        want.extend(["as-brushed", "as-brushed fidelity"]);
        want.extend(lost.then_some("brush width"));
        want.extend(["write toolpaths", "render", "write render"]);
        assert_eq!(stage_names(&r), want);
        // The stage times add up to the wall time (within 5 %).
        let sum: f64 =
            r["stages"].as_array().unwrap().iter().map(|s| s["seconds"].as_f64().unwrap()).sum();
        let wall = r["wall_seconds"].as_f64().unwrap();
        assert!((wall - sum).abs() <= 0.05 * wall + 1e-3, "stages {sum} s, wall {wall} s");
        // On Linux each stage says the process's peak resident memory while it ran (MB): at
        // least what the part and its field hold, at most the machine.
        if cfg!(target_os = "linux") {
            for st in r["stages"].as_array().unwrap() {
                let mb = st["peak_rss_mb"].as_f64().unwrap_or(0.0);
                assert!(mb > 1.0 && mb < 1e6, "{st}");
            }
        }
        assert!(r["toolpaths"]["job"]["stroke_count"].as_u64().unwrap() > 5);
        // The cycle time (issue 31): in the report and, to one decimal, in the program header.
        let cycle = r["toolpaths"]["job"]["cycle_time_s"].as_f64().unwrap();
        let head = format!("(cycle time: {cycle:.1} s at rapid 5000 mm/min");
        let ngc = String::from_utf8_lossy(&files[1]);
        assert!(cycle > 0.0 && ngc.lines().any(|l| l.starts_with(&head)), "{cycle} s");
        // The solve ran: iterations, or a start that satisfies the targets as it is — the
        // position energy's branch-coherent start, or the given field when the tools' designed
        // grain meets every position row already (the coherent start keeps it).
        let solver = &r["optimize"]["solver"];
        let met = solver["initial_energy"]["position"].as_f64().unwrap()
            <= 1e-12 * solver["unknowns"].as_f64().unwrap();
        assert!(
            !solver["iterations"].as_array().unwrap().is_empty()
                || solver["start"] == "coherent-branch"
                || (solver["start"] == "given" && met),
            "{solver}"
        );
        assert!(solver["given_energy"].as_f64().unwrap() > 0.0);
        bytes.push(files);
        // The edit measured as brushed (no times in it): the same at any thread count.
        assert!(r["as_brushed"]["fidelity"][0]["as_brushed"]["samples"].as_u64() > Some(0));
        brushed.push(r["as_brushed"].to_string());
    }
    assert!(bytes[0] == bytes[1], "outputs differ between --threads 1 and 2");
    assert_eq!(brushed[0], brushed[1], "the as-brushed figures differ between --threads 1 and 2");
}

#[test]
fn a_scene_computes_only_what_it_asks_for() {
    let d = dir("minimal");
    write_part(&d);
    // No edits, no toolpaths, no render: only load and field.
    let sc = scene(&d, "[]", "", "");
    let rep = d.join("r.json");
    let o = run(&["--quiet", "run", sc.to_str().unwrap(), "--report", rep.to_str().unwrap()]);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let r = report(&rep);
    assert_eq!(stage_names(&r), ["load", "field"]);
    assert!(r["optimize"].is_null() && r["toolpaths"].is_null() && r["render"].is_null());
    // A render without stroke effects traces no strokes; with toolpaths but no edits, no solve.
    let sc = scene(
        &d,
        "[]",
        "",
        r#",
  "render": {"width": 64, "height": 64, "output": "o/m.png"}"#,
    );
    let o = run(&["--quiet", "run", sc.to_str().unwrap(), "--report", rep.to_str().unwrap()]);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let r = report(&rep);
    assert_eq!(stage_names(&r), ["load", "field", "render", "write render"]);
    assert_eq!(r["plan"]["trace"], false);
    let sc = scene(&d, "[]", TOOLPATHS, "");
    let o = run(&["--quiet", "run", sc.to_str().unwrap(), "--report", rep.to_str().unwrap()]);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    assert_eq!(stage_names(&report(&rep)), ["load", "field", "toolpaths", "write toolpaths"]);
}

#[test]
fn bad_sections_are_named_and_nothing_is_written() {
    let d = dir("bad");
    write_part(&d);
    for (toolpaths, needle) in [
        (r#", "toolpaths": {"svg": "o/x.svg", "placement": {"widht": 3}}"#, "toolpaths.placement"),
        (
            r#", "toolpaths": {"svg": "o/x.svg", "placement": {"width": -3}}"#,
            "toolpaths.placement.width",
        ),
        (r#", "render": {"width": 0, "output": "o/x.png"}"#, "render.width"),
    ] {
        let sc = scene(&d, "[]", toolpaths, "");
        let o = run(&["--quiet", "run", sc.to_str().unwrap()]);
        let err = String::from_utf8_lossy(&o.stderr);
        assert_eq!(o.status.code(), Some(1), "{toolpaths}: {err}");
        assert!(err.contains(needle), "{toolpaths}: {err}");
        assert!(!d.join("o").exists(), "nothing written after a failure");
    }
}

/// G-code refusals raised while running name the scene key path (`toolpaths.…`), and
/// nothing is written; an empty program is refused unless `allow_empty`, which the run
/// report then warns about.
#[test]
fn gcode_errors_name_the_scene_key_path() {
    let d = dir("gcode-keys");
    write_part(&d);
    let tp = |gcode: &str, plan: &str| {
        format!(
            r#", "toolpaths": {{"svg": "o/x.svg", "gcode": "o/x.ngc", "placement": {{"width": 4}},
                "plan": {{{plan}}}, "gcode_options": {{{gcode}}}}}"#
        )
    };
    let tilt = r#""z_mode": {"mode": "surface_following", "max_tilt_deg": 5, "on_tilt": "skip"}"#;
    for (toolpaths, needle) in [
        (tp(r#""safe_z": 0.5"#, ""), "toolpaths.gcode_options.safe_z: 0.5 mm prints as Z0.500"),
        (tp(r#""z_floor": 1"#, ""), "toolpaths.gcode_options.z_floor: Z = 0 mm (as printed)"),
        (
            tp(r#""spindle": {"snippet": {"on": "M3", "off": "M5\nM2"}}"#, ""),
            "toolpaths.gcode_options.spindle.snippet.off: line 2 `M2`",
        ),
        (tp(r#""feed": 0.01"#, ""), "toolpaths.gcode_options.feed: 0.01 mm/min prints as F0.0"),
        (tp(r#""safe_z": 100"#, tilt), "toolpaths.gcode: the G-code program would have no passes"),
        (
            tp(r#""safe_z": 100"#, &tilt.replace("skip", "error")),
            "toolpaths.plan.z_mode.max_tilt_deg: stroke",
        ),
    ] {
        let sc = scene(&d, "[]", &toolpaths, "");
        let o = run(&["--quiet", "run", sc.to_str().unwrap()]);
        let err = String::from_utf8_lossy(&o.stderr);
        assert_eq!(o.status.code(), Some(1), "{toolpaths}: {err}");
        assert!(err.contains(needle), "{toolpaths}: {err}");
        assert!(!d.join("o").exists(), "nothing written after a failure");
    }
    let sc = scene(&d, "[]", &tp(r#""safe_z": 100, "allow_empty": true"#, tilt), "");
    let o = run(&["--quiet", "run", sc.to_str().unwrap()]);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let r = report(&d.join("run-report.json"));
    let w = r["toolpaths"]["job"]["warnings"][0].as_str().unwrap();
    assert!(w.contains("no passes") && w.contains("allow_empty"), "{w}");
    let g = std::fs::read_to_string(d.join("o/x.ngc")).unwrap();
    assert!(!g.lines().any(|l| l.starts_with("G1 ")), "{g}");
}

/// A scene in inches: the G-code is in mm (G21) with every length converted, and the
/// `gcode_options` lengths are read in inches.
#[test]
fn gcode_units_in_scene_prints_millimetres() {
    let d = dir("gcode-in");
    write_part(&d);
    let sc = scene(
        &d,
        "[]",
        r#", "toolpaths": {"gcode": "o/x.ngc", "placement": {"width": 4},
              "gcode_options": {"safe_z": 0.2, "clearance": 0.1, "feed": 40, "plunge_feed": 10,
                                "envelope": {"min": [-1000, -1000, -1], "max": [1000, 1000, 1]}}}"#,
        "",
    );
    let text =
        std::fs::read_to_string(&sc).unwrap().replacen("{\n", "{\n  \"units\": \"in\",\n", 1);
    std::fs::write(&sc, text).unwrap();
    let o = run(&["--quiet", "run", sc.to_str().unwrap()]);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let g = std::fs::read_to_string(d.join("o/x.ngc")).unwrap();
    assert!(g.contains("units: mm, G21; lengths converted from in x25.4"), "{g}");
    assert!(g.contains("G0 Z5.080\n") && g.contains(" F1016.0\n") && g.contains(" F254.0\n"));
    assert!(!g.contains("G20"));
    // An envelope ending at X = 1 in is far too small for the ≈ 200 in wide layout.
    let text = std::fs::read_to_string(&sc).unwrap().replace("[1000, 1000, 1]", "[1, 1000, 1]");
    std::fs::write(&sc, text).unwrap();
    let o = run(&["--quiet", "run", sc.to_str().unwrap()]);
    let err = String::from_utf8_lossy(&o.stderr);
    assert!(
        err.contains("toolpaths.gcode_options.envelope: X = ") && err.contains(" in by "),
        "{err}"
    );
}

#[test]
fn trace_writes_the_strokes_of_a_given_field_and_flags_override_the_scene() {
    let d = dir("trace");
    write_part(&d);
    let sc = scene(&d, BEND, TOOLPATHS, "");
    let field = d.join("f.json");
    let o = run(&["--quiet", "optimize", sc.to_str().unwrap(), "--out", field.to_str().unwrap()]);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let (svg, rep) = (d.join("given.svg"), d.join("trace.json"));
    let o = run(&[
        "--quiet",
        "trace",
        sc.to_str().unwrap(),
        "--field",
        field.to_str().unwrap(),
        "--svg",
        svg.to_str().unwrap(),
        "--report",
        rep.to_str().unwrap(),
    ]);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    assert!(std::fs::read_to_string(&svg).unwrap().contains("<svg"));
    let r = report(&rep);
    // The field came from the file: no edits and no solve ran (the part is refined inside
    // the scene's brush as the optimize run that wrote the field refined it).
    assert_eq!(
        stage_names(&r),
        ["load", "refine", "field", "read field", "toolpaths", "write toolpaths"]
    );
    // The same strokes as the scene's own solve (the FIELD.json holds that solve's grain).
    let o = run(&[
        "--quiet",
        "trace",
        sc.to_str().unwrap(),
        "--svg",
        d.join("own.svg").to_str().unwrap(),
    ]);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let a = std::fs::read_to_string(&svg).unwrap();
    let b = std::fs::read_to_string(d.join("own.svg")).unwrap();
    assert!(a == b, "the FIELD.json round trip changed the strokes");
    // Nothing to write is an error.
    let bare = scene(&d, "[]", "", "");
    let o = run(&["--quiet", "trace", bare.to_str().unwrap()]);
    assert_eq!(o.status.code(), Some(1));
    assert!(String::from_utf8_lossy(&o.stderr).contains("nothing to write"));
}

/// `grainline render`: the preview alone. `--out` and `--linear` override the scene; the
/// strokes are traced for the strokes overlay but no toolpath file is written; the PFM holds
/// width × height × 3 finite floats; a missing scene is a one-line error naming it.
#[test]
fn render_command_writes_only_the_preview() {
    let d = dir("render");
    write_part(&d);
    let s = scene(&d, "[]", TOOLPATHS, RENDER);
    let (png, pfm, rep) = (d.join("alt/p.png"), d.join("alt/p.pfm"), d.join("alt/rep.json"));
    let args = [
        "--quiet",
        "render",
        s.to_str().unwrap(),
        "--out",
        png.to_str().unwrap(),
        "--linear",
        pfm.to_str().unwrap(),
        "--report",
        rep.to_str().unwrap(),
    ];
    let out = run(&args);
    assert!(out.status.success(), "{}", String::from_utf8_lossy(&out.stderr));
    assert!(png.exists() && pfm.exists());
    for f in ["o/v.svg", "o/v.ngc", "o/v.json", "o/v.png"] {
        assert!(!d.join(f).exists(), "{f} written by `render`");
    }
    let r = report(&rep);
    assert_eq!(
        stage_names(&r),
        ["load", "field", "toolpaths", "write toolpaths", "render", "write render"]
    );
    assert_eq!(r["outputs"].as_array().unwrap().len(), 2, "{}", r["outputs"]);
    assert!(r["toolpaths"]["job"]["stroke_count"].as_u64().unwrap() > 0);
    // PFM: "PF\n96 96\n-1.0\n" then 96·96·3 little-endian f32.
    let bytes = std::fs::read(&pfm).unwrap();
    let header_end = bytes.iter().enumerate().filter(|(_, &b)| b == b'\n').nth(2).unwrap().0 + 1;
    let header = String::from_utf8_lossy(&bytes[..header_end]);
    assert!(header.starts_with("PF\n96 96\n-"), "{header}");
    let data = &bytes[header_end..];
    assert_eq!(data.len(), 96 * 96 * 3 * 4);
    assert!(data.chunks(4).all(|c| f32::from_le_bytes([c[0], c[1], c[2], c[3]]).is_finite()));

    let missing = d.join("missing.json");
    let out = run(&["--quiet", "render", missing.to_str().unwrap()]);
    assert!(!out.status.success());
    let err = String::from_utf8_lossy(&out.stderr);
    assert_eq!(err.lines().count(), 1, "{err}");
    assert!(err.contains("missing.json"), "{err}");
    assert_eq!(err.matches("os error").count(), 1, "cause printed twice: {err}");
}

#[test]
fn a_field_of_the_unrefined_part_is_traced_on_its_own_triangles() {
    // The vase's bend is finer than its triangles, so `optimize` refines the part inside the
    // brush; a FIELD.json written with `mesh.refine.mode: "none"` (or before refinement
    // existed) has the part's own vertex count and must still trace with the default scene.
    let d = dir("unrefined");
    write_part(&d);
    let sc = scene(&d, BEND, TOOLPATHS, "");
    let refined = d.join("refined.json");
    let o = run(&["--quiet", "optimize", sc.to_str().unwrap(), "--out", refined.to_str().unwrap()]);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let text = std::fs::read_to_string(&sc).unwrap();
    let own_sc = d.join("own.json");
    std::fs::write(
        &own_sc,
        text.replace(
            r#""mesh": "vase.obj""#,
            r#""mesh": {"path": "vase.obj", "refine": {"mode": "none"}}"#,
        ),
    )
    .unwrap();
    let own = d.join("own-field.json");
    let o = run(&["--quiet", "optimize", own_sc.to_str().unwrap(), "--out", own.to_str().unwrap()]);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let count = |p: &Path| report(p)["u"].as_array().unwrap().len();
    let obj_vertices = std::fs::read_to_string(d.join("vase.obj"))
        .unwrap()
        .lines()
        .filter(|l| l.starts_with("v "))
        .count();
    assert_eq!(count(&own), obj_vertices, "mode none keeps the part's vertices");
    assert!(count(&refined) > obj_vertices, "the default refines inside the brush");
    for field in [&own, &refined] {
        let rep = d.join("trace-report.json");
        let _ = std::fs::remove_file(&rep);
        let svg = d.join("t.svg");
        let _ = std::fs::remove_file(&svg);
        let o = run(&[
            "--quiet",
            "trace",
            sc.to_str().unwrap(),
            "--field",
            field.to_str().unwrap(),
            "--svg",
            svg.to_str().unwrap(),
            "--report",
            rep.to_str().unwrap(),
        ]);
        assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
        assert_eq!(report(&rep)["vertices"].as_u64().unwrap() as usize, count(field));
    }
}
