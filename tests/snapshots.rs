//! Format guards: insta snapshots of the SVG, the G-code and the run report's stable fields for
//! two small scenes. The numbers inside are checked against analytic truth elsewhere (toolpaths
//! tests: spacing, circles, LinuxCNC and vpype acceptance; cli_run: stages); these snapshots
//! only catch unintended format changes. Update with `INSTA_UPDATE=always cargo test --test
//! snapshots` after checking the diff.

use std::path::{Path, PathBuf};
use std::process::Command;

use grainline::generate;
use grainline::mesh::write::obj_string;

fn run_scene(
    name: &str,
    mesh: grainline::mesh::Mesh,
    extra: &str,
) -> (String, String, serde_json::Value) {
    let d = std::env::temp_dir().join(format!("grainline-snap-{}-{name}", std::process::id()));
    std::fs::create_dir_all(&d).unwrap();
    std::fs::write(d.join("part.obj"), obj_string(&mesh, name)).unwrap();
    let scene = format!(
        r#"{{
  "mesh": "part.obj",
  "lights": [{{"type": "directional", "direction": [0.3, -0.5, 1]}}],
  "view": {{"eye": [0, -200, 80], "target": [0, 0, 0], "model": "distant"}},
  "field": {{"init": "uv"}},
  "toolpaths": {{"svg": "o.svg", "gcode": "o.ngc", "placement": {{"width": 6}}}}{extra}
}}"#
    );
    let p: PathBuf = d.join("scene.json");
    std::fs::write(&p, scene).unwrap();
    let o = Command::new(env!("CARGO_BIN_EXE_grainline"))
        .args(["--quiet", "run"])
        .arg(&p)
        .output()
        .unwrap();
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let read = |f: &str| std::fs::read_to_string(d.join(f)).unwrap();
    let report: serde_json::Value = serde_json::from_str(&read("run-report.json")).unwrap();
    let out = (read("o.svg"), read("o.ngc"), report);
    std::fs::remove_dir_all(&d).ok();
    out
}

/// The report without times, paths and floating-point figures: its shape and counts.
fn stable(r: &serde_json::Value) -> serde_json::Value {
    let t = &r["toolpaths"]["job"];
    serde_json::json!({
        "format": r["format"],
        "version": r["version"],
        "units": r["units"],
        "plan": r["plan"],
        "stages": r["stages"].as_array().unwrap().iter().map(|s| s["stage"].clone()).collect::<Vec<_>>(),
        "vertices": r["vertices"],
        "faces": r["faces"],
        "strokes": t["stroke_count"],
        "passes": t["pass_count"],
        "stop_reasons": t["stop_reasons"],
        "outputs": r["outputs"].as_array().unwrap().iter()
            .map(|o| Path::new(o.as_str().unwrap()).file_name().unwrap().to_string_lossy().into_owned())
            .collect::<Vec<_>>(),
    })
}

#[test]
fn flat_plate_with_uv_in_mm() {
    let mut mesh = generate::plane(30.0, generate::Grid::new(6, 4));
    // UV = XY in mm, as a panel from an outline.
    if let Some(uv) = mesh.uv.as_mut() {
        for c in uv.values.iter_mut() {
            *c = nalgebra::Vector2::new(60.0 * c.x - 30.0, 60.0 * c.y - 30.0);
        }
    }
    let (svg, gcode, report) = run_scene("plate", mesh, "");
    insta::assert_snapshot!("plate_svg", svg);
    insta::assert_snapshot!("plate_gcode", gcode);
    insta::assert_snapshot!(
        "plate_report",
        serde_json::to_string_pretty(&stable(&report)).unwrap()
    );
}

#[test]
fn small_vase_with_a_bend() {
    let mesh =
        generate::revolve(|t| (20.0 + 5.0 * (std::f64::consts::PI * t).sin(), 40.0 * t), 24, 10);
    let (svg, gcode, report) = run_scene(
        "vase",
        mesh,
        r#",
  "edits": [{"tool": "bend", "centre": {"point": [0, -24, 20]}, "radius": 10, "strength": 0.5}]"#,
    );
    insta::assert_snapshot!("vase_svg", svg);
    insta::assert_snapshot!("vase_gcode", gcode);
    insta::assert_snapshot!("vase_report", serde_json::to_string_pretty(&stable(&report)).unwrap());
}
