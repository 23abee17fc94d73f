//! Issue 15, item 12: bounded work. Every input-dependent cost is estimated before the work
//! starts and refused past its documented budget (src/limits.rs, docs/scene.md "Limits"),
//! naming the scene key (or CLI flag), the estimate and the budget. Each test asks for work
//! far beyond the budget: it can only pass quickly if the refusal comes first.

use std::cell::RefCell;
use std::path::{Path, PathBuf};
use std::process::{Command, Output};

use grainline::generate;
use grainline::mesh::write::obj_string;
use grainline::pipeline::{prepare, Observer, Stages};
use grainline::scene::{LoadedScene, Scene};

fn dir(name: &str) -> PathBuf {
    let d = std::env::temp_dir().join(format!("grainline-budgets-{}-{name}", std::process::id()));
    let _ = std::fs::remove_dir_all(&d);
    std::fs::create_dir_all(&d).unwrap();
    d
}

fn grainline(args: &[&str]) -> Output {
    Command::new(env!("CARGO_BIN_EXE_grainline")).args(args).output().unwrap()
}

fn error_of(o: &Output) -> String {
    assert!(!o.status.success(), "expected a failure");
    let e = String::from_utf8_lossy(&o.stderr).trim().to_string();
    assert_eq!(e.lines().count(), 1, "one line: {e}");
    assert!(!e.contains("panicked"), "{e}");
    e
}

/// A vase of revolution (radius 30–38 mm, 60 mm tall: about 1.3 × 10⁴ mm²) with UVs.
fn vase(d: &Path) {
    let m =
        generate::revolve(|t| (30.0 + 8.0 * (std::f64::consts::PI * t).sin(), 60.0 * t), 48, 24);
    std::fs::write(d.join("vase.obj"), obj_string(&m, "test vase")).unwrap();
}

fn scene_text(part: &str, extra: &str) -> String {
    format!(
        r#"{{
  {part},
  "lights": [{{"type": "directional", "direction": [0.3, -0.5, 1]}}],
  "view": {{"eye": [0, -200, 80], "target": [0, 0, 30]}},
  "field": {{"init": "uv"}}{extra}
}}"#
    )
}

/// Records the stages `prepare` starts.
#[derive(Default)]
struct Record(RefCell<Vec<String>>);

impl Observer for Record {
    fn stage(&self, name: &str) {
        self.0.borrow_mut().push(name.to_string());
    }
}

/// Prepares the scene at `path`; returns its error and the stages started.
fn prepare_error(path: &Path) -> (String, Vec<String>) {
    let s = LoadedScene::read(path).unwrap();
    let rec = Record::default();
    let mut stages = Stages::new(&rec);
    let e = match prepare(&s, &mut stages) {
        Ok(_) => panic!("prepare accepted {}", path.display()),
        Err(e) => s.wrap(e).to_string(),
    };
    drop(stages);
    (e, rec.0.into_inner())
}

#[test]
fn item12_a_fine_brush_is_refused_when_the_part_is_loaded_before_the_field() {
    let d = dir("brush");
    vase(&d);
    // Area ≈ 1.3e4 mm²: a 0.01 mm brush is ~1.3e6 mm of strokes sampled every 0.0025 mm,
    // ~5e8 samples (budget 2e7); overlap 0.999999 of a 4 mm brush the same.
    let cases = [
        (r#""placement": {"width": 0.01}"#, "toolpaths.placement.width"),
        (r#""placement": {"width": 4, "overlap": 0.999999}"#, "toolpaths.placement.overlap"),
        (
            r#""placement": {"width": 2, "trace": {"max_step": 1e-5}}"#,
            "toolpaths.placement.trace.max_step",
        ),
    ];
    for (placement, key) in cases {
        let extra = format!(r#", "toolpaths": {{"svg": "o/v.svg", {placement}}}"#);
        let p = d.join("scene.json");
        std::fs::write(&p, scene_text(r#""mesh": "vase.obj""#, &extra)).unwrap();
        let (e, stages) = prepare_error(&p);
        assert!(e.contains(&format!("{key}: ")), "want {key} in: {e}");
        assert!(e.contains("samples, beyond the budget of 2e7 samples"), "{e}");
        // Loaded, then refused: the field (the first costly stage) never started.
        assert_eq!(stages, ["load"], "{e}");
        // Through the CLI: one line, nothing written.
        let o = grainline(&["--quiet", "run", p.to_str().unwrap()]);
        let e = error_of(&o);
        assert!(e.contains(&format!("{key}: placing strokes ")), "{e}");
        assert!(!d.join("o").exists());
    }
    // The default brush on the same part is well within the budget.
    let p = d.join("scene.json");
    let extra = r#", "toolpaths": {"svg": "o/v.svg", "placement": {"width": 4}}"#;
    std::fs::write(&p, scene_text(r#""mesh": "vase.obj""#, extra)).unwrap();
    let s = LoadedScene::read(&p).unwrap();
    assert!(prepare(&s, &mut Stages::new(&grainline::pipeline::Silent)).is_ok());
    std::fs::remove_dir_all(&d).unwrap();
}

#[test]
fn item12_a_fine_brush_is_refused_by_the_toolpaths_crate_itself() {
    use grainline_toolpaths::{generate, Directions, FieldMesh, JobOptions, PlacementOptions};
    use grainline_toolpaths::{Symmetry, ToolpathError};
    // A 1000 × 1000 mm sheet: a 0.001 mm brush is 1e9 mm of strokes, 4e12 samples.
    let uv = vec![[0.0, 0.0], [1000.0, 0.0], [1000.0, 1000.0], [0.0, 1000.0]];
    let mesh = FieldMesh::new(
        uv,
        vec![[0, 1, 2], [0, 2, 3]],
        Directions::Angles(vec![0.0; 4]),
        Symmetry::Line,
    );
    let opts = JobOptions { placement: PlacementOptions::new(1e-3, 0.0), ..Default::default() };
    let e = generate(mesh, &opts).unwrap_err();
    assert!(matches!(e, ToolpathError::Budget { key: "placement.width", .. }), "{e:?}");
    // 1e6 / (1e-3 · 2.5e-4) = 4e12.
    assert!(e.to_string().contains("sampled every 2.500e-4 mm over 1000000 mm²"), "{e}");
    assert!(e.to_string().contains("4.00e12 samples"), "{e}");
}

#[test]
fn item12_neighbours_past_the_budget_are_refused_when_the_scene_is_read() {
    let text = scene_text(
        r#""mesh": "vase.obj""#,
        r#", "toolpaths": {"svg": "v.svg", "plan": {"order": {"neighbours": 4294967295}}}"#,
    );
    let e = Scene::from_str(&text, Path::new("s.json")).unwrap_err().to_string();
    assert!(e.starts_with("s.json: toolpaths.plan.order.neighbours: 4294967295 "), "{e}");
    assert!(e.contains("at most 256"), "{e}");
    let ok = text.replace("4294967295", "256");
    assert!(Scene::from_str(&ok, Path::new("s.json")).is_ok());
}

const RECT: &str = r#"<svg xmlns="http://www.w3.org/2000/svg" width="100mm" height="50mm"
  viewBox="0 0 100 50"><rect x="0" y="0" width="100" height="50"/></svg>"#;

#[test]
fn item12_a_tiny_outline_max_edge_is_refused_before_meshing() {
    let d = dir("outline");
    std::fs::write(d.join("rect.svg"), RECT).unwrap();
    // 5000 mm² at 1e-3 mm: 5000 / (½ · √3/4 · 1e-6) ≈ 2.3e10 triangles (budget 4e6).
    let p = d.join("scene.json");
    let part = r#""outline": {"path": "rect.svg", "max_edge": 0.001}"#;
    std::fs::write(&p, scene_text(part, "")).unwrap();
    let (e, stages) = prepare_error(&p);
    assert!(e.contains("outline.max_edge: 0.001 mm on an outline of 5000 mm²"), "{e}");
    assert!(e.contains("2.31e10 triangles, beyond the budget of 4e6"), "{e}");
    assert_eq!(stages, ["load"]);
    // `grainline panel --max-edge 0.01`: 2.3e8 triangles; refused naming the flag.
    let out = d.join("p.obj");
    let o = grainline(&[
        "--quiet",
        "panel",
        d.join("rect.svg").to_str().unwrap(),
        "--out",
        out.to_str().unwrap(),
        "--max-edge",
        "0.01",
    ]);
    let e = error_of(&o);
    assert!(e.contains("--max-edge") && e.contains("2.31e8 triangles"), "{e}");
    // The shortest edge within the budget: √(4.7 · 5000 / 4e6) ≈ 0.077 mm.
    assert!(e.contains("(at least 0.077 mm here)"), "{e}");
    assert!(!out.exists());
    // At 0.1 mm (2.3e6 triangles estimated) the budget is not the limit.
    let loops = grainline::panel::read_svg_loops(RECT, Path::new("rect.svg"), 0.01).unwrap();
    let est = grainline::panel::estimate(&loops, Some(0.1));
    assert!(
        (est.triangles - (5000.0 / (0.5 * 3f64.sqrt() / 4.0 * 0.01) + 3000.0 + 4.0)).abs() < 1.0
    );
    std::fs::remove_dir_all(&d).unwrap();
}

#[test]
fn item12_render_memory_is_estimated_and_refused_when_the_scene_is_read() {
    // The largest render the sample bound allows (4096² at supersample 2 = 2²⁶ samples) with
    // LIC, the gap map and the as-brushed side by side: per sample 16 + 12 + 2·16 + 12 + 32
    // + 8 = 112 B, per pixel 2·34 + 4 = 72 B: 8.125 GiB (budget 4 GiB).
    let fx = r#""effects": {"lic": {}, "gap": {}, "as_brushed": {}}"#;
    let size = r#""width": 4096, "height": 4096, "supersample": 2"#;
    let render = format!(r#", "toolpaths": {{"svg": "v.svg"}}, "render": {{{size}, {fx}}}"#);
    let text = scene_text(r#""mesh": "vase.obj""#, &render);
    let e = Scene::from_str(&text, Path::new("s.json")).unwrap_err().to_string();
    assert!(
        e.starts_with("s.json: render: width × height × supersample² = 4096 × 4096 × 2²"),
        "{e}"
    );
    assert!(e.contains("GiB (112 bytes per sample and 72 per pixel"), "{e}");
    assert!(e.contains("beyond the budget of 4.00 GiB"), "{e}");
    // Plain shading at the same size: 16 + 12 + 16 + 8 = 52 B per sample and 34 per pixel,
    // 3.78 GiB: accepted.
    let plain = scene_text(r#""mesh": "vase.obj""#, &format!(r#", "render": {{{size}}}"#));
    let s = Scene::from_str(&plain, Path::new("s.json")).unwrap();
    let r = s.render.as_ref().unwrap();
    assert_eq!(r.memory_estimate(), (1u64 << 26) * 52 + (1u64 << 24) * 34);
}
