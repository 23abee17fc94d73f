//! Grain maps out and in (issue 33, item 2; docs/formats.md "Grain maps"):
//!
//! - **round trip**: on every example (spot needs ../shared), `export.maps` writes the solved
//!   grain as a direction map and an angle map at the size chosen for the part; each, read back
//!   as `field.init: "map"` on the same part (no edits), gives the grain it was made from
//!   within 0.5° at every vertex of the part (the refinement inside the edits' brushes adds
//!   vertices the second run does not have; the part's own vertices are compared) — on spot at
//!   90 % of them (see [`round_trip`]);
//! - **a map made by hand**: a radial angle map generated here on the panel's UVs, read as the
//!   initial field, gives strokes along the radial direction;
//! - the maps are 16-bit PNGs of the scene's size, and the same scene gives the same bytes at
//!   1 and 2 threads.

use std::path::{Path, PathBuf};
use std::process::Command;

use serde_json::{json, Value};

fn root() -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR"))
}

fn absolute(base: &Path, p: &str) -> String {
    let q = Path::new(p);
    if q.is_absolute() { q.to_path_buf() } else { base.join(q) }.display().to_string()
}

/// The example's scene with absolute input paths, or None (with a message) when its mesh lies
/// in an absent ../shared.
fn example_scene(name: &str) -> Option<Value> {
    let base = root().join("examples").join(name);
    let text = std::fs::read_to_string(base.join("scene.json")).unwrap();
    let mut scene: Value = serde_json::from_str(&text).unwrap();
    let fix = |v: &mut Value| {
        if let Some(s) = v.as_str() {
            *v = Value::String(absolute(&base, s));
        }
    };
    if scene["mesh"].is_string() {
        fix(&mut scene["mesh"]);
    } else if scene["mesh"].is_object() {
        fix(&mut scene["mesh"]["path"]);
    }
    if scene["outline"].is_object() {
        fix(&mut scene["outline"]["path"]);
    }
    if let Some(edits) = scene["edits"].as_array_mut() {
        for e in edits.iter_mut().filter(|e| e.get("svg").is_some()) {
            fix(&mut e["svg"]);
        }
    }
    let mesh = scene["mesh"].as_str().or_else(|| scene["mesh"]["path"].as_str()).map(PathBuf::from);
    if let Some(m) = mesh.filter(|m| !m.exists()) {
        let shared = std::env::var_os("GRAINLINE_SHARED").map(PathBuf::from);
        let alt = shared.map(|s| s.join("meshes").join(m.file_name().unwrap_or_default()));
        match alt.filter(|a| a.exists()) {
            Some(a) => {
                let a = Value::String(a.display().to_string());
                if scene["mesh"].is_string() {
                    scene["mesh"] = a;
                } else {
                    scene["mesh"]["path"] = a;
                }
            }
            None => {
                eprintln!("skipping {name}: {} not found (../shared is absent)", m.display());
                return None;
            }
        }
    }
    let s = scene.as_object_mut().unwrap();
    s.remove("render");
    s.remove("toolpaths");
    Some(scene)
}

fn temp_dir(what: &str) -> PathBuf {
    let dir = std::env::temp_dir().join(format!("grainline-maps-{what}-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    dir
}

/// `grainline run` on `scene` (written into `dir` as `file`), with `args` after the scene.
fn run(dir: &Path, file: &str, scene: &Value, args: &[&str]) -> Value {
    let path = dir.join(file);
    std::fs::write(&path, serde_json::to_string_pretty(scene).unwrap()).unwrap();
    let report = dir.join(format!("{file}.report.json"));
    let o = Command::new(env!("CARGO_BIN_EXE_grainline"))
        .args(["--quiet"])
        .args(args)
        .arg("run")
        .arg(&path)
        .arg("--report")
        .arg(&report)
        .output()
        .unwrap();
    assert!(o.status.success(), "{file}: {}", String::from_utf8_lossy(&o.stderr));
    serde_json::from_slice(&std::fs::read(report).unwrap()).unwrap()
}

fn read_json(p: &Path) -> Value {
    serde_json::from_slice(&std::fs::read(p).unwrap()).unwrap()
}

fn v3(v: &Value) -> [f64; 3] {
    [0, 1, 2].map(|k| v[k].as_f64().unwrap())
}

/// The angle between two lines (degrees).
fn line_angle(a: [f64; 3], b: [f64; 3]) -> f64 {
    let dot: f64 = (0..3).map(|k| a[k] * b[k]).sum();
    let na = a.iter().map(|c| c * c).sum::<f64>().sqrt();
    let nb = b.iter().map(|c| c * c).sum::<f64>().sqrt();
    (dot.abs() / (na * nb)).min(1.0).acos().to_degrees()
}

/// The PNG's (colour type, bit depth, width, height).
fn png_info(p: &Path) -> (png::ColorType, png::BitDepth, u32, u32) {
    let d = png::Decoder::new(std::io::BufReader::new(std::fs::File::open(p).unwrap()));
    let r = d.read_info().unwrap();
    let i = r.info();
    (i.color_type, i.bit_depth, i.width, i.height)
}

/// The round trip on one example: the largest angle (degrees) over the part's own vertices,
/// per map kind — for spot the 90th percentile: its stencil edit makes a field that turns by up
/// to 87° across one edge and has 20 singular faces, which no texture sampled bilinearly at a
/// vertex holds (its largest error, at a singular face's corner, is reported).
fn round_trip(name: &str) -> Option<[f64; 2]> {
    let mut scene = example_scene(name)?;
    let dir = temp_dir(name);
    // The size chosen for the part (docs/formats.md), or GRAINLINE_MAPS_SIZE.
    let size: Option<u32> = std::env::var("GRAINLINE_MAPS_SIZE").ok().and_then(|s| s.parse().ok());
    scene["export"] = json!({ "maps": dir.join("maps") });
    if let Some(n) = size {
        scene["export"]["anisotropy_texture_size"] = json!(n);
    }
    scene["field"]["output"] = json!(dir.join("field.json"));
    run(&dir, "export.json", &scene, &[]);
    let maps = dir.join("maps");
    let (c, d, w, h) = png_info(&maps.join("grain-direction.png"));
    assert_eq!((c, d), (png::ColorType::Rgb, png::BitDepth::Sixteen));
    assert!(w == h && w.is_power_of_two() && w >= 1024 && size.is_none_or(|n| n == w));
    assert_eq!(
        png_info(&maps.join("grain-angle.png")),
        (png::ColorType::Grayscale, png::BitDepth::Sixteen, w, w)
    );
    eprintln!("{name}: maps of {w}² texels");
    let exported = read_json(&dir.join("field.json"));
    let u0 = exported["u"].as_array().unwrap();
    let mut worst = [0.0f64; 2];
    for (k, kind) in ["direction", "angle"].into_iter().enumerate() {
        let mut back = scene.clone();
        let s = back.as_object_mut().unwrap();
        s.remove("edits");
        s.remove("export");
        back["field"] = json!({
            "init": "map",
            "map": { "path": maps.join(format!("grain-{kind}.png")), "kind": kind },
            "symmetry": scene["field"].get("symmetry").cloned().unwrap_or(json!("line")),
            "output": dir.join(format!("back-{kind}.json")),
        });
        run(&dir, &format!("back-{kind}.json.scene"), &back, &[]);
        let read = read_json(&dir.join(format!("back-{kind}.json")));
        let u1 = read["u"].as_array().unwrap();
        assert!(u1.len() <= u0.len(), "{name}: {} vs {} vertices", u1.len(), u0.len());
        let p0 = exported["position"].as_array().unwrap();
        let p1 = read["position"].as_array().unwrap();
        let mut angles: Vec<f64> = Vec::with_capacity(u1.len());
        for i in 0..u1.len() {
            assert_eq!(v3(&p0[i]), v3(&p1[i]), "{name}: vertex {i} moved");
            angles.push(line_angle(v3(&u0[i]), v3(&u1[i])));
        }
        if std::env::var_os("GRAINLINE_MAPS_DEBUG").is_some() {
            let mut idx: Vec<usize> = (0..angles.len()).collect();
            idx.sort_by(|&a, &b| angles[b].total_cmp(&angles[a]));
            for &i in idx.iter().take(12) {
                eprintln!(
                    "{name} {kind}: vertex {i} {:.3}° at {:?} u0 {:?} u1 {:?}",
                    angles[i],
                    v3(&p0[i]),
                    v3(&u0[i]),
                    v3(&u1[i])
                );
            }
        }
        angles.sort_by(f64::total_cmp);
        let (median, max) = (angles[angles.len() / 2], angles[angles.len() - 1]);
        let p90 = angles[angles.len() * 9 / 10];
        let within = angles.iter().filter(|&&a| a <= 0.5).count();
        eprintln!(
            "{name}: {kind} map round trip over {} vertices: median {median:.4}°, 90th \
             percentile {p90:.4}°, max {max:.4}° ({within} within 0.5°)",
            angles.len()
        );
        worst[k] = if name == "spot" { p90 } else { max };
    }
    if std::env::var_os("GRAINLINE_MAPS_DEBUG").is_none() {
        std::fs::remove_dir_all(&dir).ok();
    }
    Some(worst)
}

fn check_round_trip(name: &str) {
    if let Some(w) = round_trip(name) {
        assert!(w[0] <= 0.5 && w[1] <= 0.5, "{name}: round trip {:.3}° / {:.3}°", w[0], w[1]);
    }
}

#[test]
fn round_trip_kettle() {
    check_round_trip("kettle");
}

#[test]
fn round_trip_light() {
    check_round_trip("light");
}

#[test]
fn round_trip_dome() {
    check_round_trip("dome");
}

#[test]
fn round_trip_panel() {
    check_round_trip("panel");
}

#[test]
fn round_trip_spot() {
    check_round_trip("spot");
}

/// A 16-bit grey PNG of `n`² texels: an angle map of `theta` (the grain's angle from the UV
/// tangent, radians, any turn) at each texel's UV, the panel's frame being T = +x, B = +y
/// (a flat part whose UVs are its x and y).
fn angle_map(
    path: &Path,
    n: usize,
    uv_of: impl Fn(f64, f64) -> [f64; 2],
    theta: impl Fn([f64; 2]) -> f64,
) {
    let mut bytes = Vec::with_capacity(2 * n * n);
    for j in 0..n {
        for i in 0..n {
            let st = ((i as f64 + 0.5) / n as f64, 1.0 - (j as f64 + 0.5) / n as f64);
            let a = theta(uv_of(st.0, st.1)).rem_euclid(std::f64::consts::PI);
            let q = (a / std::f64::consts::PI * 65535.0).round() as u16;
            bytes.extend(q.to_be_bytes());
        }
    }
    let mut out = Vec::new();
    {
        let mut enc = png::Encoder::new(&mut out, n as u32, n as u32);
        enc.set_color(png::ColorType::Grayscale);
        enc.set_depth(png::BitDepth::Sixteen);
        let mut w = enc.write_header().unwrap();
        w.write_image_data(&bytes).unwrap();
    }
    std::fs::write(path, out).unwrap();
}

/// An angle map made by hand — the grain radial about a point of the panel — read as the
/// initial field (no edits) gives strokes along the radial direction: every stroke segment
/// farther than 15 mm from the centre is compared with the radial direction at its midpoint.
#[test]
fn radial_angle_map_gives_radial_strokes() {
    let mut scene = example_scene("panel").unwrap();
    scene.as_object_mut().unwrap().remove("edits");
    let dir = temp_dir("radial");
    // The panel's texture space (its UVs are millimetres): from the glb export's report.
    scene["export"] = json!({ "glb": dir.join("panel.glb") });
    let r = run(&dir, "space.json", &scene, &[]);
    let ts = &r["export"]["texture_space"];
    let (off, scale) =
        (v3(&json!([ts["offset"][0], ts["offset"][1], 0.0])), ts["scale"].as_f64().unwrap());
    let n = r["export"]["texture_size"].as_u64().unwrap() as usize;
    let centre = [80.0, 45.0];
    let map = dir.join("radial.png");
    angle_map(
        &map,
        n,
        |s, t| [off[0] + scale * s, off[1] + scale * t],
        |p| (p[1] - centre[1]).atan2(p[0] - centre[0]),
    );
    let toolpaths = json!({
        "strokes_json": dir.join("strokes.json"),
        "placement": { "width": 3.0, "overlap": 0.1, "spacing": "uv" }
    });
    scene["toolpaths"] = toolpaths;
    scene.as_object_mut().unwrap().remove("export");
    scene["field"] = json!({ "init": "map", "map": { "path": map, "kind": "angle" } });
    run(&dir, "radial.json", &scene, &[]);
    let strokes = read_json(&dir.join("strokes.json"));
    let mut angles = Vec::new();
    for s in strokes["strokes"].as_array().unwrap() {
        for line in s["xyz"].as_array().unwrap() {
            let pts: Vec<[f64; 3]> = line.as_array().unwrap().iter().map(v3).collect();
            for w in pts.windows(2) {
                let m = [(w[0][0] + w[1][0]) / 2.0, (w[0][1] + w[1][1]) / 2.0];
                let radial = [m[0] - centre[0], m[1] - centre[1], 0.0];
                let d = [w[1][0] - w[0][0], w[1][1] - w[0][1], w[1][2] - w[0][2]];
                let len = d.iter().map(|c| c * c).sum::<f64>().sqrt();
                if radial[0].hypot(radial[1]) > 15.0 && len > 1e-6 {
                    angles.push(line_angle(d, radial));
                }
            }
        }
    }
    angles.sort_by(f64::total_cmp);
    assert!(angles.len() > 100, "{} stroke segments", angles.len());
    let (median, p95) = (angles[angles.len() / 2], angles[angles.len() * 95 / 100]);
    eprintln!(
        "radial map: {} stroke segments, angle to the radial direction median {median:.3}°, \
         95th percentile {p95:.3}°, max {:.3}°",
        angles.len(),
        angles[angles.len() - 1]
    );
    assert!(median <= 1.0 && p95 <= 3.0, "strokes not radial: median {median}°, p95 {p95}°");
    std::fs::remove_dir_all(&dir).ok();
}
