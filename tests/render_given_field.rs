//! Issue 33, item 4: `grainline render SCENE --field FIELD.json` draws the LIC of the field it
//! shows (it drew the initial field's ℓ under the given field's shading).
//!
//! A panel with a bend (tests/hard_cases_large_triangles.rs' part): `run` writes FIELD.json and
//! a preview with the LIC; `render --field` of that FIELD.json gives the same PNG byte for byte.
//! The LIC texture is also measured, to show the comparison sees it: rendered with the LIC at
//! strength 0.5 and at 0 (no LIC), their ratio is a monotone function of the texture alone
//! (docs/render.md, "resolve": c·((1 − s) + 2s·lic)). The field shown and the initial field
//! (FIELD.json's `u_before`) give different textures inside the brush, where the bend turned ℓ,
//! and the same far from it.

use std::path::{Path, PathBuf};
use std::process::{Command, Output};

fn dir(name: &str) -> PathBuf {
    let d =
        std::env::temp_dir().join(format!("grainline-render-given-{}-{name}", std::process::id()));
    let _ = std::fs::remove_dir_all(&d);
    std::fs::create_dir_all(&d).unwrap();
    d
}

fn grainline(args: &[&str]) -> Output {
    let o = Command::new(env!("CARGO_BIN_EXE_grainline")).args(args).output().unwrap();
    assert!(o.status.success(), "{args:?}: {}", String::from_utf8_lossy(&o.stderr));
    o
}

const PANEL: &str = "v -50 -30 0\nv 50 -30 0\nv 50 30 0\nv -50 30 0\n\
                     vt 0 0\nvt 1 0\nvt 1 1\nvt 0 1\nf 1/1 2/2 3/3\nf 1/1 3/3 4/4\n";
const W: usize = 160;
const H: usize = 120;
/// The brush's radius on screen: 8 mm seen 151 mm away with a 15° field of view over 120 px.
const BRUSH_PX: f64 = 8.0 / (151.0 * 0.131_652_5) * 60.0;

/// The panel with a bend at the centre of the view, the LIC at `strength`.
fn scene(d: &Path, name: &str, strength: f64) -> PathBuf {
    std::fs::write(d.join("panel.obj"), PANEL).unwrap();
    let s = format!(
        r#"{{
  "units": "mm",
  "mesh": {{"path": "panel.obj"}},
  "field": {{"init": "uv", "symmetry": "line", "output": "o/field.json"}},
  "lights": [{{"type": "directional", "direction": [0, -0.35, 1], "key": true}}],
  "view": {{"eye": [0, -20, 150], "target": [0, 0, 0], "fov_deg": 15}},
  "edits": [{{"tool": "bend", "centre": {{"point": [0, 0, 0]}}, "radius": 8,
              "strength": 0.8, "direction": [1, 0, 0]}}],
  "render": {{"width": {W}, "height": {H}, "output": "o/run.png",
              "effects": {{"lic": {{"strength": {strength}, "length_px": 8}}}}}}
}}"#
    );
    let p = d.join(name);
    std::fs::write(&p, s).unwrap();
    p
}

fn render(sc: &Path, field: &Path, png: &Path) -> Vec<u8> {
    let (sc, field, out) = (sc.to_str().unwrap(), field.to_str().unwrap(), png.to_str().unwrap());
    grainline(&["--quiet", "render", sc, "--field", field, "--out", out]);
    std::fs::read(png).unwrap()
}

/// The green channel per pixel.
fn green(png: &[u8]) -> Vec<f64> {
    let p = tiny_skia::Pixmap::decode_png(png).unwrap();
    assert_eq!((p.width() as usize, p.height() as usize), (W, H));
    p.pixels().iter().map(|c| c.green() as f64).collect()
}

/// The LIC texture, up to a monotone map: the image with the LIC over the image without, where
/// the latter is bright enough to tell (`None` elsewhere).
fn texture(with: &[u8], without: &[u8]) -> Vec<Option<f64>> {
    green(with).iter().zip(green(without)).map(|(&a, b)| (b >= 24.0).then(|| a / b)).collect()
}

/// Mean |a − b| over the pixels both textures hold, inside and outside `r` px of the centre.
fn differences(a: &[Option<f64>], b: &[Option<f64>], r: f64) -> (f64, f64, usize) {
    let (mut inside, mut outside) = ((0.0, 0), (0.0, 0));
    for (k, (a, b)) in a.iter().zip(b).enumerate() {
        let (Some(a), Some(b)) = (a, b) else { continue };
        let (x, y) = ((k % W) as f64 + 0.5 - W as f64 / 2.0, (k / W) as f64 + 0.5 - H as f64 / 2.0);
        let d = (x * x + y * y).sqrt();
        if d < r {
            inside = (inside.0 + (a - b).abs(), inside.1 + 1);
        } else if d > 2.0 * r {
            outside = (outside.0 + (a - b).abs(), outside.1 + 1);
        }
    }
    (inside.0 / inside.1.max(1) as f64, outside.0 / outside.1.max(1) as f64, inside.1)
}

#[test]
fn render_of_a_given_field_draws_that_fields_lic_issue_33() {
    let d = dir("lic");
    let sc = scene(&d, "scene.json", 0.5);
    grainline(&["--quiet", "run", sc.to_str().unwrap()]);
    let field = d.join("o/field.json");
    let run_png = std::fs::read(d.join("o/run.png")).unwrap();
    // The acceptance: the same PNG, byte for byte.
    let given = render(&sc, &field, &d.join("given.png"));
    assert!(given == run_png, "render --field differs from run's preview");

    // The measure: the LIC textures of the field shown and of the initial field.
    let plain_sc = scene(&d, "plain.json", 0.0);
    let given_plain = render(&plain_sc, &field, &d.join("given-plain.png"));
    let mut initial: serde_json::Value =
        serde_json::from_slice(&std::fs::read(&field).unwrap()).unwrap();
    initial["u"] = initial["u_before"].clone();
    let initial_field = d.join("initial.json");
    std::fs::write(&initial_field, serde_json::to_vec(&initial).unwrap()).unwrap();
    let initial_lic = render(&sc, &initial_field, &d.join("initial.png"));
    let initial_plain = render(&plain_sc, &initial_field, &d.join("initial-plain.png"));
    let shown = texture(&given, &given_plain);
    let before = texture(&initial_lic, &initial_plain);
    let (inside, outside, count) = differences(&shown, &before, BRUSH_PX);
    eprintln!("LIC change: {inside} inside the brush ({count} px), {outside} far from it");
    assert!(count > 200, "{count} pixels inside the brush");
    assert!(inside > 0.05 && inside > 4.0 * outside, "{inside} inside, {outside} outside");
    std::fs::remove_dir_all(&d).ok();
}
