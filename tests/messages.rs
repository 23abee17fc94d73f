//! Issue 15, item 15: messages. Errors raised while running keep the scene key path, a Z floor
//! violation is reported under `z_floor`, no Rust debug text leaks, long element lists are cut
//! short, numbers print with sensible precision, and a scene's hint names the scene key.

use std::path::{Path, PathBuf};
use std::process::{Command, Output};

use grainline::generate;
use grainline::mesh::write::obj_string;

fn dir(name: &str) -> PathBuf {
    let d = std::env::temp_dir().join(format!("grainline-messages-{}-{name}", std::process::id()));
    let _ = std::fs::remove_dir_all(&d);
    std::fs::create_dir_all(&d).unwrap();
    d
}

fn grainline(args: &[&str]) -> Output {
    Command::new(env!("CARGO_BIN_EXE_grainline")).args(args).output().unwrap()
}

/// The one error line of a failed run.
fn error_of(o: &Output) -> String {
    assert!(!o.status.success(), "expected a failure");
    let e = String::from_utf8_lossy(&o.stderr).trim().to_string();
    assert_eq!(e.lines().count(), 1, "one line: {e}");
    assert!(!e.contains("panicked"), "{e}");
    e
}

/// No Rust debug text: `Some(…)`, `None`, variant names in braces, faer / spade enum names.
fn assert_no_debug_text(e: &str) {
    for bad in ["Some(", "None", "{ index", "NonPositivePivot", "TooLarge", "Numeric(", "Geodesic"]
    {
        assert!(!e.contains(bad), "debug text {bad:?} in: {e}");
    }
}

fn scene(d: &Path, mesh: &str, lights: &str, extra: &str) -> PathBuf {
    if mesh == "vase.obj" {
        let m = generate::revolve(
            |t| (30.0 + 8.0 * (std::f64::consts::PI * t).sin(), 60.0 * t),
            48,
            24,
        );
        std::fs::write(d.join("vase.obj"), obj_string(&m, "test vase")).unwrap();
    }
    let s = format!(
        r#"{{
  "mesh": "{mesh}",
  "lights": {lights},
  "view": {{"eye": [0, -200, 80], "target": [0, 0, 30]}},
  "field": {{"init": "uv"}}{extra}
}}"#
    );
    let p = d.join("scene.json");
    std::fs::write(&p, s).unwrap();
    p
}

const LIGHT: &str = r#"[{"type": "directional", "direction": [0.3, -0.5, 1]}]"#;

#[test]
fn item15_errors_found_while_tracing_keep_the_toolpaths_prefix() {
    let d = dir("prefix");
    let cases = [
        // Flat passes at Z 0 and travel at Z −1.
        (r#""gcode_options": {"safe_z": -1}"#, "toolpaths.gcode_options.safe_z"),
        // Surface following on a vase tilts far more than 0.001°.
        (
            r#""plan": {"z_mode": {"mode": "surface_following", "max_tilt_deg": 0.001,
                "on_tilt": "error"}}"#,
            "toolpaths.plan.z_mode.max_tilt_deg",
        ),
        // A Z floor above the cutting height: reported under its own key.
        (r#""gcode_options": {"z_floor": 1}"#, "toolpaths.gcode_options.z_floor"),
    ];
    for (opts, key) in cases {
        let extra = format!(
            r#", "toolpaths": {{"gcode": "o/v.ngc", "placement": {{"width": 4}}, {opts}}}"#
        );
        let sc = scene(&d, "vase.obj", LIGHT, &extra);
        let e = error_of(&grainline(&["--quiet", "run", sc.to_str().unwrap()]));
        assert!(e.contains(&format!("{}: {key}: ", sc.display())), "want {key} in: {e}");
        assert_no_debug_text(&e);
        if key.ends_with("z_floor") {
            assert!(e.contains("below the Z floor") && e.contains("(stroke "), "{e}");
            assert!(!e.contains("envelope"), "{e}");
        }
        assert!(!d.join("o").exists());
    }
    std::fs::remove_dir_all(&d).unwrap();
}

/// An OBJ whose edge (1, 2) is shared by `n` triangles.
fn fan_of_fins(n: usize) -> String {
    let mut s = String::from("v 0 0 0\nv 1 0 0\n");
    for k in 0..n {
        let a = k as f64 * std::f64::consts::TAU / n as f64;
        s.push_str(&format!("v 0.5 {} {}\n", a.cos(), a.sin()));
    }
    for k in 0..n {
        s.push_str(&format!("f 1 2 {}\n", k + 3));
    }
    s
}

#[test]
fn item15_a_nonmanifold_edge_lists_a_few_faces_and_names_the_right_switch() {
    let d = dir("fins");
    std::fs::write(d.join("fins.obj"), fan_of_fins(2000)).unwrap();
    let mesh = d.join("fins.obj");
    let out = d.join("f.json");
    let e = error_of(&grainline(&[
        "--quiet",
        "field",
        mesh.to_str().unwrap(),
        "--light",
        "0,0,1",
        "--view",
        "0,-1,0",
        "--out",
        out.to_str().unwrap(),
    ]));
    assert!(e.contains("shared by 2000 faces"), "{e}");
    assert!(e.contains("… and 1996 more"), "{e}");
    assert!(e.len() < 400, "{} bytes: {e}", e.len());
    assert!(e.contains("--allow-nonmanifold"), "{e}");
    // Inside a scene the switch is the key `mesh.allow_nonmanifold`.
    let sc = scene(&d, "fins.obj", LIGHT, "");
    let e = error_of(&grainline(&["--quiet", "run", sc.to_str().unwrap()]));
    assert!(e.contains("mesh.allow_nonmanifold") && !e.contains("--allow"), "{e}");
    assert!(e.len() < 400, "{e}");
    std::fs::remove_dir_all(&d).unwrap();
}

#[test]
fn item15_numbers_print_with_sensible_precision() {
    let d = dir("numbers");
    // A light direction whose length underflows: named by its key, printed in exponent form.
    let tiny = r#"[{"type": "directional", "direction": [1e-200, 0, 0]}]"#;
    let sc = scene(&d, "vase.obj", tiny, "");
    let e = error_of(&grainline(&["--quiet", "run", sc.to_str().unwrap()]));
    assert!(e.contains("lights[0].direction") && e.contains("1e-200"), "{e}");
    assert!(e.len() < 300, "{} bytes: {e}", e.len());
    // Setting errors print the value as written, not 300 digits.
    let sc = scene(
        &d,
        "vase.obj",
        LIGHT,
        r#", "render": {"width": 8, "height": 8, "output": "a.png", "exposure": 1e300}"#,
    );
    let e = error_of(&grainline(&["--quiet", "run", sc.to_str().unwrap()]));
    assert!(e.len() < 300, "{} bytes: {e}", e.len());
    // The CLI's direction check too.
    let mesh = d.join("vase.obj");
    let e = error_of(&grainline(&[
        "--quiet",
        "field",
        mesh.to_str().unwrap(),
        "--light",
        "1e-300,0,0",
        "--view",
        "0,-1,0",
        "--out",
        d.join("f.json").to_str().unwrap(),
    ]));
    assert!(e.contains("1e-300") && e.len() < 200, "{e}");
    std::fs::remove_dir_all(&d).unwrap();
}

#[test]
fn item15_no_debug_text_in_messages_or_files() {
    let d = dir("debug");
    // An empty support names its metric in words.
    let extra = r#", "edits": [{"tool": "bend", "centre": {"point": [0, -36, 30]}, "radius": 1e-9,
        "strength": 0.5}]"#;
    let sc = scene(&d, "vase.obj", LIGHT, extra);
    let e = error_of(&grainline(&["--quiet", "run", sc.to_str().unwrap()]));
    assert!(e.contains("edits[0]") && e.contains("geodesic distance"), "{e}");
    assert!(e.contains("within 1e-9 of"), "{e}");
    assert_no_debug_text(&e);
    // A panel without --max-edge: its OBJ header says "unlimited", not `None`.
    let svg = d.join("p.svg");
    std::fs::write(
        &svg,
        "<svg xmlns='http://www.w3.org/2000/svg' width='10mm' height='10mm' viewBox='0 0 10 10'>\
         <path d='M0 0 H10 V10 H0 Z'/></svg>",
    )
    .unwrap();
    let obj = d.join("p.obj");
    let o = grainline(&["--quiet", "panel", svg.to_str().unwrap(), "--out", obj.to_str().unwrap()]);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let text = std::fs::read_to_string(&obj).unwrap();
    let header: Vec<&str> = text.lines().filter(|l| l.starts_with('#')).collect();
    assert!(header.iter().any(|l| l.contains("max edge unlimited")), "{header:?}");
    assert!(header.iter().all(|l| !l.contains("None")), "{header:?}");
    std::fs::remove_dir_all(&d).unwrap();
}

#[test]
fn item15_toolpath_errors_print_strokes_without_option_text() {
    use grainline_toolpaths::ToolpathError;
    let floor =
        ToolpathError::BelowFloor { z: -0.5, floor: 0.0, by: 0.5, unit: "mm", stroke: Some(0) };
    let travel = ToolpathError::OutsideEnvelope {
        axis: 'X',
        value: 200.0,
        min: 0.0,
        max: 160.0,
        by: 40.0,
        unit: "mm",
        stroke: None,
    };
    let (a, b) = (floor.to_string(), travel.to_string());
    assert!(a.ends_with("(stroke 0)"), "{a}");
    assert!(b.contains("travel") && !b.contains("None") && !b.contains("Some("), "{b}");
    assert_no_debug_text(&a);
    assert_no_debug_text(&b);
    // Through the scene mapping: the floor under its own key.
    let e = grainline::scene::toolpaths::toolpath_error(floor);
    assert!(e.to_string().starts_with("gcode_options.z_floor: Z = -0.5"), "{e}");
}
