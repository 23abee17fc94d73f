//! The editor's acceptance test (issue 16): the page driven in headless Chromium like a
//! designer would, in one page load (tests/editor-client/drive.mjs, puppeteer-core and Debian's
//! chromium, installed by tests/editor-client/setup.sh — a failed set-up fails the test, it
//! never skips):
//!
//! 1. `grainline edit` on examples/kettle (its mesh, material, lights, view and bend edit; the
//!    toolpaths' files and the preview left out, `field.output` added so a run writes FIELD.json;
//!    `mesh.refine.edge` 0.1, so the kettle's 5 mm triangles are refined inside the 45 mm
//!    brushes and the page has to load the refined mesh when the drag ends);
//! 2. the page presses on the key highlight near the middle of the view with the bend tool and
//!    drags 40 px across it; once the edit is solved and shown, the FIELD.json of the version
//!    the page shows is fetched; Ctrl+S saves;
//! 3. `grainline run` on the saved scene writes FIELD.json: byte for byte the page's, on the
//!    mesh the page shows (its vertex count);
//! 4. with grain lines, strokes and as-brushed shading turned on by their keys, the page has
//!    the strokes of the committed field and shades the grain rebuilt from them, and the glTF
//!    export button writes scene.glb beside the scene; a drag on the key light gizmo turns the
//!    light the way it went (in the camera's frame);
//! 5. the screenshots before and after (kept under target/editor-acceptance/) show the
//!    highlight's ridge moved by at least 10 px where the brush was, in the drag's direction:
//!    measured on their pixels, along the drag, at several points along the highlight.

use std::io::{BufRead, BufReader};
use std::path::{Path, PathBuf};
use std::process::{Command, Stdio};

use serde_json::Value;

fn root() -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR"))
}

fn setup() {
    let o = Command::new("bash").arg(root().join("tests/editor-client/setup.sh")).output().unwrap();
    assert!(
        o.status.success(),
        "tests/editor-client/setup.sh failed (it installs puppeteer-core and chromium):\n{}{}",
        String::from_utf8_lossy(&o.stdout),
        String::from_utf8_lossy(&o.stderr)
    );
}

/// Luminance (sRGB-encoded values, 0–255) of a PNG, row-major, with its width and height.
fn luminance(path: &Path) -> (Vec<f64>, usize, usize) {
    let decoder = png::Decoder::new(std::io::BufReader::new(std::fs::File::open(path).unwrap()));
    let mut reader = decoder.read_info().unwrap();
    let mut buf = vec![0; reader.output_buffer_size().unwrap()];
    let info = reader.next_frame(&mut buf).unwrap();
    assert_eq!(info.bit_depth, png::BitDepth::Eight, "{}", path.display());
    let channels = match info.color_type {
        png::ColorType::Rgba => 4,
        png::ColorType::Rgb => 3,
        other => panic!("{}: colour type {other:?}", path.display()),
    };
    let (w, h) = (info.width as usize, info.height as usize);
    let mut lum = vec![0.0; w * h];
    for (i, l) in lum.iter_mut().enumerate() {
        let p = &buf[i * channels..i * channels + 3];
        *l = 0.2126 * f64::from(p[0]) + 0.7152 * f64::from(p[1]) + 0.0722 * f64::from(p[2]);
    }
    (lum, w, h)
}

/// Bilinear sample (0 outside).
fn sample(img: &(Vec<f64>, usize, usize), x: f64, y: f64) -> f64 {
    let (lum, w, h) = img;
    let (x0, y0) = (x.floor(), y.floor());
    if x0 < 0.0 || y0 < 0.0 || x0 + 1.0 >= *w as f64 || y0 + 1.0 >= *h as f64 {
        return 0.0;
    }
    let (fx, fy) = (x - x0, y - y0);
    let (i, j) = (x0 as usize, y0 as usize);
    let at = |i: usize, j: usize| lum[j * w + i];
    (1.0 - fy) * ((1.0 - fx) * at(i, j) + fx * at(i + 1, j))
        + fy * ((1.0 - fx) * at(i, j + 1) + fx * at(i + 1, j + 1))
}

/// The ridge (brightest point) along the line `p + s·across`, s in [−reach, reach] px, after a
/// 3 px box filter along the line: its s and its luminance.
fn ridge(img: &(Vec<f64>, usize, usize), p: [f64; 2], across: [f64; 2], reach: f64) -> (f64, f64) {
    let step = 0.5;
    let n = (2.0 * reach / step) as usize + 1;
    let s_of = |k: usize| -reach + k as f64 * step;
    let raw: Vec<f64> = (0..n)
        .map(|k| sample(img, p[0] + s_of(k) * across[0], p[1] + s_of(k) * across[1]))
        .collect();
    let mut best = (0.0, f64::NEG_INFINITY);
    for k in 3..n.saturating_sub(3) {
        let v = raw[k - 3..=k + 3].iter().sum::<f64>() / 7.0;
        if v > best.1 {
            best = (s_of(k), v);
        }
    }
    best
}

#[test]
fn drag_a_bend_on_the_kettle_save_and_run_reproduce_the_field() {
    setup();
    let dir = root().join("target/editor-acceptance");
    let _ = std::fs::remove_dir_all(&dir);
    std::fs::create_dir_all(&dir).unwrap();
    // The kettle example, its mesh by absolute path, writing only FIELD.json when run.
    let mut scene: Value = serde_json::from_str(
        &std::fs::read_to_string(root().join("examples/kettle/scene.json")).unwrap(),
    )
    .unwrap();
    scene["mesh"] = serde_json::json!({
        "path": root().join("examples/data/kettle.obj").display().to_string(),
        "refine": { "edge": 0.1 },
    });
    let obj = scene.as_object_mut().unwrap();
    // The kettle's toolpaths section without its files: the page traces its strokes with it.
    if let Some(t) = obj.get_mut("toolpaths").and_then(Value::as_object_mut) {
        t.remove("svg");
        t.remove("gcode");
    }
    obj.remove("render");
    scene["field"]["output"] = Value::String("field.json".into());
    let scene_path = dir.join("scene.json");
    std::fs::write(&scene_path, serde_json::to_string_pretty(&scene).unwrap()).unwrap();
    let own_edits = scene["edits"].as_array().unwrap().len();

    let mut editor = Command::new(env!("CARGO_BIN_EXE_grainline"))
        .args(["--quiet", "edit", "--port", "0"])
        .arg(&scene_path)
        .stdout(Stdio::piped())
        .stderr(Stdio::inherit())
        .spawn()
        .unwrap();
    let mut url = String::new();
    BufReader::new(editor.stdout.take().unwrap()).read_line(&mut url).unwrap();
    let url = url.trim().to_string();
    assert!(url.starts_with("http://127.0.0.1:") && url.ends_with('/'), "{url}");
    let job = serde_json::json!({
        "url": url, "out_dir": dir, "width": 1000, "height": 700, "drag_px": 40,
    });
    std::fs::write(dir.join("job.json"), job.to_string()).unwrap();
    let o = Command::new("node")
        .arg(root().join("tests/editor-client/drive.mjs"))
        .arg(dir.join("job.json"))
        .output()
        .unwrap();
    let _ = editor.kill();
    let _ = editor.wait();
    assert!(
        o.status.success(),
        "drive.mjs failed:\n{}{}",
        String::from_utf8_lossy(&o.stdout),
        String::from_utf8_lossy(&o.stderr)
    );
    eprintln!("drive.mjs: {}", String::from_utf8_lossy(&o.stdout).trim());
    let result: Value =
        serde_json::from_str(&std::fs::read_to_string(dir.join("result.json")).unwrap()).unwrap();

    // The saved scene: the kettle's own edit, then the page's bend, as the page committed it.
    let saved = std::fs::read_to_string(&scene_path).unwrap();
    let parsed = grainline::scene::Scene::from_str(&saved, &scene_path).unwrap();
    assert_eq!(parsed.edits.len(), own_edits + 1, "{saved}");
    let last: grainline::edit::Edit = serde_json::from_value(result["last"].clone()).unwrap();
    assert_eq!(parsed.edits[own_edits], last);
    let grainline::edit::Edit::Bend(bend) = &last else { panic!("not a bend: {last:?}") };
    assert!(bend.strength > 0.0 && bend.direction.is_some(), "{bend:?}");

    // The toggles: strokes traced for the committed field, grain lines drawn, the as-brushed
    // grain shaded; the glTF export button wrote a GLB beside the scene file.
    let f = &result["features"];
    assert_eq!(f["toggles"], serde_json::json!([true, true, true]), "{f}");
    assert!(f["strokes_error"].is_null(), "{f}");
    assert!(f["strokes"].as_u64().unwrap() > 10, "{f}");
    assert!(f["grain_segments"].as_u64().unwrap() > 1000, "{f}");
    assert_eq!(f["shading"], "as-brushed", "{f}");
    assert_eq!(f["exported"].as_str().map(PathBuf::from), Some(dir.join("scene.glb")), "{f}");
    let glb = std::fs::read(dir.join("scene.glb")).unwrap();
    assert_eq!(&glb[..4], b"glTF");

    // The gizmo's drag, up and right from its centre (0.48 of its radius each way): the light
    // points that way in the camera's frame, x = y = 0.48 and z = √(1 − 2·0.48²).
    let l = &f["light"];
    let (r, u, b) =
        (l["right"].as_f64().unwrap(), l["up"].as_f64().unwrap(), l["back"].as_f64().unwrap());
    assert!((r - 0.48).abs() < 0.05 && (u - 0.48).abs() < 0.05, "{l}");
    assert!((b - (1.0f64 - 2.0 * 0.48 * 0.48).sqrt()).abs() < 0.05, "{l}");
    assert_eq!(l["dirty"], true, "{l}");

    // `grainline run` on the saved scene: FIELD.json byte for byte the page's.
    let run = Command::new(env!("CARGO_BIN_EXE_grainline"))
        .args(["--quiet", "run"])
        .arg(&scene_path)
        .output()
        .unwrap();
    assert!(run.status.success(), "{}", String::from_utf8_lossy(&run.stderr));
    let ran = std::fs::read(dir.join("field.json")).unwrap();
    let shown = std::fs::read(dir.join("page-field.json")).unwrap();
    assert!(ran.len() > 1000, "{}", ran.len());
    // Refined inside the brushes, and shown on that mesh.
    let field: Value = serde_json::from_slice(&ran).unwrap();
    let n = field["u"].as_array().unwrap().len();
    assert!(n > 4704, "the kettle (4,704 vertices) was not refined: {n}");
    assert_eq!(result["vertices"].as_u64(), Some(n as u64), "the page shows another mesh");
    assert!(
        ran == shown,
        "FIELD.json of the run ({} bytes) differs from the page's ({} bytes)",
        ran.len(),
        shown.len()
    );

    // The ridge moved where the brush was: along the drag, at points along the highlight.
    let before = luminance(&dir.join("before.png"));
    let after = luminance(&dir.join("after.png"));
    let press = [result["press"]["x"].as_f64().unwrap(), result["press"]["y"].as_f64().unwrap()];
    let across = [result["across"][0].as_f64().unwrap(), result["across"][1].as_f64().unwrap()];
    let tangent = [-across[1], across[0]];
    let mut shifts = Vec::new();
    for k in -5..=5 {
        let o = 2.0 * f64::from(k);
        let p = [press[0] + o * tangent[0], press[1] + o * tangent[1]];
        let (sb, lb) = ridge(&before, p, across, 70.0);
        let (sa, la) = ridge(&after, p, across, 70.0);
        // A highlight, not the dark body: well above the part's own shade.
        assert!(lb > 80.0 && la > 80.0, "no ridge at offset {o}: {lb:.0} / {la:.0}");
        eprintln!("offset {o:+.0} px: ridge at {sb:+.1} px before, {sa:+.1} px after");
        shifts.push(sa - sb);
    }
    shifts.sort_by(f64::total_cmp);
    let median = shifts[shifts.len() / 2];
    eprintln!("ridge shift along the drag: median {median:.1} px (drag 40 px)");
    assert!(
        median >= 10.0,
        "the ridge moved {median:.1} px along the drag (need ≥ 10): {shifts:?}"
    );
}
