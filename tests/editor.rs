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
//!    measured on their pixels, along the drag, at several points along the highlight;
//! 6. the LIC toggle (key I): the texture it lays on the part (lic.png over lic-off.png, their
//!    ratio, which takes the shading out) is correlated along the key highlight's tangent and
//!    not across it, around the highlight near the middle of the view;
//! 7. the light tool (key L): a tangent dragged 60 px across the key highlight turns the key
//!    light, the highlight then runs through the pressed point (its curve within a few pixels,
//!    the pixels there brighter), and the gizmo shows the light the edit found.

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

/// The ratio of two screenshots' luminance where the first is neither too dark to divide by
/// nor saturated in either (`None` elsewhere).
fn ratio(on: &(Vec<f64>, usize, usize), off: &(Vec<f64>, usize, usize)) -> Vec<Option<f64>> {
    on.0.iter()
        .zip(&off.0)
        .map(|(&a, &b)| (b > 25.0 && b < 230.0 && a < 254.0).then(|| a / b))
        .collect()
}

/// The normalized autocorrelation of `img` (width `w`) at `lag` pixels along the unit `dir`,
/// over the valid pixels within `radius` of `c` whose lagged pixel is valid too.
fn autocorrelation(img: &[Option<f64>], w: usize, c: [f64; 2], dir: [f64; 2], lag: f64) -> f64 {
    let radius = 25.0;
    let at = |x: f64, y: f64| {
        let (x, y) = (x.round(), y.round());
        if x < 0.0 || y < 0.0 || x >= w as f64 || y as usize >= img.len() / w {
            return None;
        }
        img[y as usize * w + x as usize]
    };
    let mut pairs = Vec::new();
    let r = radius as i64;
    for dy in -r..=r {
        for dx in -r..=r {
            let (x, y) = (c[0] + dx as f64, c[1] + dy as f64);
            if (dx * dx + dy * dy) as f64 > radius * radius {
                continue;
            }
            if let (Some(a), Some(b)) = (at(x, y), at(x + lag * dir[0], y + lag * dir[1])) {
                pairs.push((a, b));
            }
        }
    }
    assert!(pairs.len() > 500, "only {} pixel pairs around {c:?}", pairs.len());
    let n = pairs.len() as f64;
    let (ma, mb) =
        (pairs.iter().map(|p| p.0).sum::<f64>() / n, pairs.iter().map(|p| p.1).sum::<f64>() / n);
    let cov: f64 = pairs.iter().map(|p| (p.0 - ma) * (p.1 - mb)).sum();
    let va: f64 = pairs.iter().map(|p| (p.0 - ma).powi(2)).sum();
    let vb: f64 = pairs.iter().map(|p| (p.1 - mb).powi(2)).sum();
    cov / (va * vb).sqrt()
}

/// The mean luminance of the 7 × 7 pixels around `p`.
fn patch_mean(img: &(Vec<f64>, usize, usize), p: [f64; 2]) -> f64 {
    let mut sum = 0.0;
    for dy in -3..=3 {
        for dx in -3..=3 {
            sum += sample(img, p[0] + f64::from(dx), p[1] + f64::from(dy));
        }
    }
    sum / 49.0
}

/// The angle between two directions, degrees.
fn angle_deg(a: &Value, b: &Value) -> f64 {
    let v = |x: &Value| [0, 1, 2].map(|k| x[k].as_f64().unwrap());
    let (a, b) = (v(a), v(b));
    let dot: f64 = (0..3).map(|k| a[k] * b[k]).sum();
    let n = |x: [f64; 3]| x.iter().map(|c| c * c).sum::<f64>().sqrt();
    (dot / (n(a) * n(b))).clamp(-1.0, 1.0).acos().to_degrees()
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
    // Vertices no stroke's brush reached (zero as-brushed grain) are shaded as bare metal: every
    // face corner at such a vertex is marked unbrushed, and none other.
    let (bare, corners) =
        (f["bare_vertices"].as_u64().unwrap(), f["unbrushed_corners"].as_u64().unwrap());
    assert!(corners >= bare && (bare == 0) == (corners == 0), "{f}");
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

    // The LIC: streaks along the key highlight, not across it (the shading divided out).
    let lic = &f["lic"];
    assert_eq!(lic["on"], true, "{lic}");
    assert!(lic["frames"].as_u64().unwrap() > 0, "no LIC pass was drawn: {lic}");
    let (on, off) = (luminance(&dir.join("lic.png")), luminance(&dir.join("lic-off.png")));
    let changed = on.0.iter().zip(&off.0).filter(|(a, b)| (*a - *b).abs() > 8.0).count();
    assert!(changed > 5000, "the LIC changed {changed} pixels");
    let r = ratio(&on, &off);
    let c = [lic["point"]["x"].as_f64().unwrap(), lic["point"]["y"].as_f64().unwrap()];
    let t = [lic["tangent"][0].as_f64().unwrap(), lic["tangent"][1].as_f64().unwrap()];
    // Two pixels apart along a streamline, two LIC values share most of their noise; across,
    // hardly any (the noise is white on the pixel grid, as the preview's).
    let along = autocorrelation(&r, on.1, c, t, 2.0);
    let across = autocorrelation(&r, on.1, c, [-t[1], t[0]], 2.0);
    eprintln!("LIC around the highlight at {c:?}: autocorrelation at 2 px {along:.2} along, {across:.2} across");
    assert!(along > 0.4 && across < 0.5 * along, "along {along:.2}, across {across:.2}");

    // The light tool: the key light turned, the highlight came through the pressed point.
    let lt = &f["light_tool"];
    assert_eq!(lt["last"]["tool"], "light", "{lt}");
    assert!(lt["tangent_drawn"].is_array(), "no tangent drawn while dragging: {lt}");
    let turned = angle_deg(&lt["key"], &lt["key_before"]);
    let (before, after) =
        (lt["nearest_before"].as_f64().unwrap(), lt["nearest_after"].as_f64().unwrap());
    let q = [lt["press"]["x"].as_f64().unwrap(), lt["press"]["y"].as_f64().unwrap()];
    let (lb, la) = (
        patch_mean(&luminance(&dir.join("light-tool-before.png")), q),
        patch_mean(&luminance(&dir.join("light-tool-after.png")), q),
    );
    eprintln!(
        "light tool at {q:?}: the key light turned {turned:.1}°; nearest highlight {before:.1} px \
         before, {after:.1} px after; luminance there {lb:.0} before, {la:.0} after"
    );
    assert!(turned > 2.0, "the key light turned {turned:.2}°");
    assert!(before > 20.0 && after < 5.0, "nearest highlight {before:.1} px → {after:.1} px");
    assert!(la > lb + 30.0, "the pressed point's luminance {lb:.0} → {la:.0}");
    // The gizmo shows the light the edit found.
    let key: Vec<String> =
        (0..3).map(|k| format!("{:.2}", lt["key"][k].as_f64().unwrap())).collect();
    assert_eq!(lt["gizmo"].as_str(), Some(key.join(", ").as_str()), "{lt}");
    assert!(lt["status"].as_str().unwrap().contains("light edit"), "{lt}");
}
