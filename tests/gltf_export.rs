//! The glTF export checked by independent programs (issue 18):
//!
//! - the Khronos glTF-Validator (npm `gltf-validator`) reports 0 errors and 0 warnings on the
//!   export of every example (spot needs ../shared and is skipped with a message without it);
//! - three.js (GLTFLoader, MeshPhysicalMaterial anisotropy) in headless Chromium renders the
//!   kettle and the light example with the scene's camera and key light at 512²: its key
//!   highlight ridge lies within 1 px of grainline's own preview's, and the same render with
//!   `anisotropyRotation` turned by 90° lies beyond that bound (the test can fail);
//! - the anisotropy direction read back with the `gltf` crate (the `anisotropyTexture`'s RG at
//!   TEXCOORD_0 in the MikkTSpace frame of TANGENT, turned by `anisotropyRotation`) is
//!   perpendicular to the solved grain (FIELD.json of the same run) within 8° at ≥ 99 % of the
//!   vertices.
//!
//! tests/gltf-client/setup.sh installs what the clients need (`npm ci`; Debian's chromium when
//! /usr/bin/chromium is missing) on first use; a failed set-up fails the test, it never skips.

use std::collections::HashMap;
use std::path::{Path, PathBuf};
use std::process::Command;
use std::sync::OnceLock;

use serde_json::{json, Value};

#[allow(dead_code)]
#[path = "support/glb_texture.rs"]
mod glb_texture;
use glb_texture::read_texture;

const SIZE: usize = 512;
/// The bound on the ridge distance, pixels at 512² (issue 18 asked for 4 px; issue 33 for 1 px
/// with the grain carried by the `anisotropyTexture`).
const RIDGE_BOUND_PX: f64 = 1.0;

fn root() -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR"))
}

fn client() -> PathBuf {
    root().join("tests/gltf-client")
}

/// Runs setup.sh once for all tests of this binary; panics with its output when it fails.
fn setup() {
    static DONE: OnceLock<Result<(), String>> = OnceLock::new();
    let r = DONE.get_or_init(|| {
        let o = Command::new("bash")
            .arg(client().join("setup.sh"))
            .output()
            .map_err(|e| e.to_string())?;
        if o.status.success() {
            Ok(())
        } else {
            Err(format!(
                "{}{}",
                String::from_utf8_lossy(&o.stdout),
                String::from_utf8_lossy(&o.stderr)
            ))
        }
    });
    if let Err(e) = r {
        panic!("tests/gltf-client/setup.sh failed (it installs the glTF clients):\n{e}");
    }
}

/// A scene path made absolute against the example's directory.
fn absolute(base: &Path, p: &str) -> String {
    let q = Path::new(p);
    if q.is_absolute() { q.to_path_buf() } else { base.join(q) }.display().to_string()
}

/// The example's mesh file, or None (with a message) when it lies in an absent ../shared.
fn resolve_paths(name: &str, scene: &mut Value) -> Option<()> {
    let base = root().join("examples").join(name);
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
        // ../shared elsewhere: GRAINLINE_SHARED, as tests/example_scenes.rs.
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
    Some(())
}

/// The key light's index as the scene defines it (docs/render.md): the first directional or
/// point light with `"key": true`, else the first directional light.
fn key_light(scene: &Value) -> usize {
    let lights = scene["lights"].as_array().unwrap();
    let punctual = |l: &Value| l["type"] == "directional" || l["type"] == "point";
    lights
        .iter()
        .position(|l| punctual(l) && l["key"] == true)
        .or_else(|| lights.iter().position(|l| l["type"] == "directional"))
        .unwrap()
}

struct Exported {
    dir: PathBuf,
    glb: PathBuf,
    /// FIELD.json of the same run: positions and the solved grain.
    field: Value,
    report: Value,
    scene: Value,
}

/// Runs `grainline run` on the example with `export.glb` and `field.output`, and, with
/// `preview`, grainline's preview at 512² under the key light alone (no other light, no diffuse
/// term, no LIC or overlays, linear PFM).
fn export_example(name: &str, preview: bool) -> Option<Exported> {
    let text =
        std::fs::read_to_string(root().join("examples").join(name).join("scene.json")).unwrap();
    let mut scene: Value = serde_json::from_str(&text).unwrap();
    resolve_paths(name, &mut scene)?;
    let dir = std::env::temp_dir().join(format!("grainline-gltf-{name}-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let s = scene.as_object_mut().unwrap();
    s.remove("toolpaths");
    s.remove("render");
    s.insert("export".into(), json!({ "glb": dir.join("part.glb") }));
    scene["field"]["output"] = json!(dir.join("field.json"));
    if preview {
        let key = key_light(&scene);
        let k = scene["lights"][key].clone();
        scene["lights"] = json!([k]);
        scene["material"]["diffuse"] = json!([0, 0, 0]);
        scene["render"] = json!({
            "width": SIZE, "height": SIZE, "supersample": 1, "tone_map": "none",
            "output": dir.join("preview.png"), "linear": dir.join("preview.pfm"),
            "effects": { "shading": true }
        });
    }
    let scene_path = dir.join("scene.json");
    std::fs::write(&scene_path, serde_json::to_string_pretty(&scene).unwrap()).unwrap();
    let o = Command::new(env!("CARGO_BIN_EXE_grainline"))
        .args(["--quiet", "run"])
        .arg(&scene_path)
        .arg("--report")
        .arg(dir.join("report.json"))
        .output()
        .unwrap();
    assert!(o.status.success(), "{name}: {}", String::from_utf8_lossy(&o.stderr));
    let read = |f: &str| -> Value {
        serde_json::from_slice(&std::fs::read(dir.join(f)).unwrap()).unwrap()
    };
    Some(Exported {
        glb: dir.join("part.glb"),
        field: read("field.json"),
        report: read("report.json"),
        scene,
        dir,
    })
}

/// (a) glTF-Validator: 0 errors, 0 warnings.
fn validate(name: &str, glb: &Path) {
    setup();
    let o = Command::new("node").arg(client().join("validate.mjs")).arg(glb).output().unwrap();
    let out = String::from_utf8_lossy(&o.stdout);
    assert!(
        o.status.success(),
        "{name}: validate.mjs failed: {out}{}",
        String::from_utf8_lossy(&o.stderr)
    );
    let r: Value = serde_json::from_str(out.trim()).unwrap();
    eprintln!(
        "{name}: glTF-Validator {}: {} errors, {} warnings, {} infos, {} hints {}",
        r["validator"], r["errors"], r["warnings"], r["infos"], r["hints"], r["messages"]
    );
    assert_eq!(r["errors"], 0, "{name}: {}", r["messages"]);
    assert_eq!(r["warnings"], 0, "{name}: {}", r["messages"]);
}

/// (c) The anisotropy direction as a viewer reads it — the `anisotropyTexture`'s RG sampled at
/// TEXCOORD_0, in the frame (T, B = w·(N × T)), turned by `anisotropyRotation` — read back with
/// the `gltf` crate, against the solved grain u of FIELD.json: |d·u| ≤ sin 8° at ≥ 99 % of the
/// glTF vertices. The same with the texture's angle mirrored (B taken as N × T whatever w) is
/// reported. Returns the fraction.
fn check_direction(name: &str, x: &Exported) -> f64 {
    let bytes = std::fs::read(&x.glb).unwrap();
    let g = gltf::Gltf::from_slice(&bytes).unwrap();
    let blob = g.blob.as_deref().unwrap();
    // The rotation from the JSON chunk (the extension is not in the gltf crate's typed API).
    let json_len = u32::from_le_bytes(bytes[12..16].try_into().unwrap()) as usize;
    let doc: Value = serde_json::from_slice(&bytes[20..20 + json_len]).unwrap();
    let ext = &doc["materials"][0]["extensions"]["KHR_materials_anisotropy"];
    let rot = ext["anisotropyRotation"].as_f64().unwrap_or(0.0);
    assert_eq!(rot, 0.0, "{name}: {ext}");
    assert!(ext["anisotropyStrength"].as_f64().unwrap() > 0.1, "{name}: {ext}");
    let tex_info = &ext["anisotropyTexture"];
    assert_eq!(tex_info["texCoord"].as_u64().unwrap_or(0), 0, "{name}: {ext}");
    let texture = read_texture(&doc, blob, tex_info["index"].as_u64().unwrap() as usize);
    let mesh = g.meshes().next().unwrap();
    let prim = mesh.primitives().next().unwrap();
    assert_eq!(prim.mode(), gltf::mesh::Mode::Triangles);
    let reader = prim.reader(|_| Some(blob));
    let p: Vec<[f32; 3]> = reader.read_positions().unwrap().collect();
    let n: Vec<[f32; 3]> = reader.read_normals().unwrap().collect();
    let t: Vec<[f32; 4]> = reader.read_tangents().unwrap().collect();
    let uv: Vec<[f32; 2]> = reader.read_tex_coords(0).unwrap().into_f32().collect();
    let idx: Vec<u32> = reader.read_indices().unwrap().into_u32().collect();
    assert_eq!(idx.len() % 3, 0);
    assert!(idx.iter().all(|&i| (i as usize) < p.len()));
    // Mesh vertices by their f32 position (the export writes positions as f32).
    let key = |q: [f32; 3]| q.map(f32::to_bits);
    let mut by_pos: HashMap<[u32; 3], Vec<usize>> = HashMap::new();
    let pos = x.field["position"].as_array().unwrap();
    let u = x.field["u"].as_array().unwrap();
    let v3 = |v: &Value| [0, 1, 2].map(|k| v[k].as_f64().unwrap());
    for (i, q) in pos.iter().enumerate() {
        by_pos.entry(key(v3(q).map(|c| c as f32))).or_default().push(i);
    }
    let sin8 = 8f64.to_radians().sin();
    let (mut good, mut good_mirrored) = (0, 0);
    for k in 0..p.len() {
        let nn = n[k].map(f64::from);
        let tt = [t[k][0], t[k][1], t[k][2]].map(f64::from);
        let w = f64::from(t[k][3]);
        assert!(w == 1.0 || w == -1.0, "{name}: tangent w {w}");
        let b = [
            nn[1] * tt[2] - nn[2] * tt[1],
            nn[2] * tt[0] - nn[0] * tt[2],
            nn[0] * tt[1] - nn[1] * tt[0],
        ];
        let [dx, dy] = texture.sample(uv[k].map(f64::from));
        let a = dy.atan2(dx) + rot;
        let d = [0, 1, 2].map(|c| a.cos() * tt[c] + a.sin() * w * b[c]);
        let dm = [0, 1, 2].map(|c| a.cos() * tt[c] + a.sin() * b[c]);
        let verts =
            by_pos.get(&key(p[k])).unwrap_or_else(|| panic!("{name}: vertex {k} not in the mesh"));
        let across = |d: [f64; 3]| {
            verts.iter().any(|&i| {
                let uu = v3(&u[i]);
                let dot: f64 = (0..3).map(|c| d[c] * uu[c]).sum();
                let nd = d.iter().map(|c| c * c).sum::<f64>().sqrt();
                let nu = uu.iter().map(|c| c * c).sum::<f64>().sqrt();
                nu > 0.0 && dot.abs() <= sin8 * nd * nu
            })
        };
        good += usize::from(across(d));
        good_mirrored += usize::from(across(dm));
    }
    let frac = good as f64 / p.len() as f64;
    eprintln!(
        "{name}: anisotropy direction (texture at TEXCOORD_0 in the MikkTSpace frame) ⟂ grain \
         within 8° at {:.3} % of {} vertices ({:.3} % with B = N × T whatever w)",
        100.0 * frac,
        p.len(),
        100.0 * good_mirrored as f64 / p.len() as f64
    );
    // Around a singular face (k = 2, the report's `isolated_faces`: oriented on its own) the
    // texels of neighbouring faces carry opposite signs of one line, which a bilinear sample
    // at the face's corners averages away: its three corners are not counted against the bound.
    let isolated = x.report["export"]["isolated_faces"].as_u64().unwrap() as usize;
    let missed = p.len() - good;
    assert!(
        missed as f64 <= 0.01 * p.len() as f64 + 3.0 * isolated as f64,
        "{name}: only {:.2} % of the vertices ({isolated} isolated faces)",
        100.0 * frac
    );
    frac
}

/// Luminance and a coverage mask of a 512² image.
struct Image {
    lum: Vec<f64>,
}

fn luminance(r: f64, g: f64, b: f64) -> f64 {
    0.2126 * r + 0.7152 * g + 0.0722 * b
}

/// The raw RGBA f32 of render.mjs (rows top to bottom): luminance and alpha > ½ as the mask.
fn read_three(path: &Path) -> (Image, Vec<bool>) {
    let b = std::fs::read(path).unwrap();
    assert_eq!(b.len(), SIZE * SIZE * 16, "{}", path.display());
    let f = |i: usize| f64::from(f32::from_le_bytes(b[4 * i..4 * i + 4].try_into().unwrap()));
    let lum = (0..SIZE * SIZE).map(|p| luminance(f(4 * p), f(4 * p + 1), f(4 * p + 2))).collect();
    let mask = (0..SIZE * SIZE).map(|p| f(4 * p + 3) > 0.5).collect();
    (Image { lum }, mask)
}

/// grainline's PFM (bottom-to-top rows, decoded here by hand: "PF\nW H\n-1.0\n" + f32 LE RGB).
fn read_pfm(path: &Path) -> Image {
    let b = std::fs::read(path).unwrap();
    let mut nl = 0;
    let mut start = 0;
    for (i, &c) in b.iter().enumerate() {
        if c == b'\n' {
            nl += 1;
            if nl == 3 {
                start = i + 1;
                break;
            }
        }
    }
    let header = String::from_utf8_lossy(&b[..start]).to_string();
    assert!(
        header.starts_with("PF\n")
            && header.contains(&format!("{SIZE} {SIZE}"))
            && header.contains("-1"),
        "{header}"
    );
    assert_eq!(b.len() - start, SIZE * SIZE * 12);
    let f = |i: usize| {
        f64::from(f32::from_le_bytes(b[start + 4 * i..start + 4 * i + 4].try_into().unwrap()))
    };
    let mut lum = vec![0.0; SIZE * SIZE];
    for y in 0..SIZE {
        let row = SIZE - 1 - y; // PFM rows run bottom to top
        for x in 0..SIZE {
            let p = row * SIZE + x;
            lum[y * SIZE + x] = luminance(f(3 * p), f(3 * p + 1), f(3 * p + 2));
        }
    }
    Image { lum }
}

/// The key highlight's ridge: in every row and every column crossing the highlight (its
/// maximum at least a quarter of the image's), the brightest pixel inside the part's mask.
fn ridge(img: &Image, mask: &[bool]) -> Vec<(f64, f64)> {
    let l = |x: usize, y: usize| if mask[y * SIZE + x] { img.lum[y * SIZE + x] } else { 0.0 };
    let top = (0..SIZE * SIZE).map(|p| if mask[p] { img.lum[p] } else { 0.0 }).fold(0.0, f64::max);
    let mut pts = Vec::new();
    if top <= 0.0 {
        return pts;
    }
    for y in 0..SIZE {
        let (x, v) =
            (0..SIZE).map(|x| (x, l(x, y))).fold((0, -1.0), |a, b| if b.1 > a.1 { b } else { a });
        if v >= 0.25 * top {
            pts.push((x as f64, y as f64));
        }
    }
    for x in 0..SIZE {
        let (y, v) =
            (0..SIZE).map(|y| (y, l(x, y))).fold((0, -1.0), |a, b| if b.1 > a.1 { b } else { a });
        if v >= 0.25 * top && !pts.contains(&(x as f64, y as f64)) {
            pts.push((x as f64, y as f64));
        }
    }
    pts
}

/// Symmetric mean chamfer distance: the larger of the two mean nearest-point distances.
fn ridge_distance(a: &[(f64, f64)], b: &[(f64, f64)]) -> f64 {
    let mean_nearest = |p: &[(f64, f64)], q: &[(f64, f64)]| {
        p.iter()
            .map(|&(x, y)| {
                q.iter()
                    .map(|&(u, v)| ((x - u).powi(2) + (y - v).powi(2)).sqrt())
                    .fold(f64::MAX, f64::min)
            })
            .sum::<f64>()
            / p.len().max(1) as f64
    };
    if a.is_empty() || b.is_empty() {
        return f64::INFINITY;
    }
    mean_nearest(a, b).max(mean_nearest(b, a))
}

/// (b) three.js against the preview: the ridge within the bound, and beyond it with the
/// anisotropy direction turned by 90°. Returns (distance, distance turned).
fn check_three(name: &str, x: &Exported) -> (f64, f64) {
    setup();
    let key = &x.scene["lights"][0];
    // A light edit moves the key light: the run report has where to.
    let dir = x.report["optimize"]["key_light"]
        .as_array()
        .cloned()
        .unwrap_or_else(|| key["direction"].as_array().unwrap().clone());
    let view = &x.scene["view"];
    let job = json!({
        "glb": x.glb, "width": SIZE, "height": SIZE,
        "camera": { "eye": view["eye"], "target": view.get("target").cloned().unwrap_or(json!([0, 0, 0])),
                    "up": view.get("up").cloned().unwrap_or(json!([0, 0, 1])),
                    "fov_deg": view.get("fov_deg").cloned().unwrap_or(json!(35)) },
        "light": { "direction": dir, "irradiance": key.get("irradiance").cloned().unwrap_or(json!(1)) },
        "renders": [
            { "rotate_anisotropy_deg": 0, "raw": x.dir.join("three.f32"), "png": x.dir.join("three.png") },
            { "rotate_anisotropy_deg": 90, "raw": x.dir.join("three-turned.f32"), "png": x.dir.join("three-turned.png") }
        ]
    });
    let job_path = x.dir.join("job.json");
    std::fs::write(&job_path, job.to_string()).unwrap();
    let o = Command::new("node").arg(client().join("render.mjs")).arg(&job_path).output().unwrap();
    assert!(
        o.status.success(),
        "{name}: render.mjs failed:\n{}{}",
        String::from_utf8_lossy(&o.stdout),
        String::from_utf8_lossy(&o.stderr)
    );
    let stdout = String::from_utf8_lossy(&o.stdout).to_string();
    eprintln!("{name}: three.js: {}", stdout.trim());
    check_view(name, &serde_json::from_str::<Value>(stdout.trim()).unwrap()["info"], key);
    let (three, mask) = read_three(&x.dir.join("three.f32"));
    let (turned, _) = read_three(&x.dir.join("three-turned.f32"));
    let preview = read_pfm(&x.dir.join("preview.pfm"));
    // Not a black or empty image: the part covers ≥ 5 % of the frame, and the highlight is a
    // ridge (its peak ≥ 10× the part's median luminance) of ≥ 50 pixels in both renders.
    let covered = mask.iter().filter(|&&m| m).count();
    assert!(covered > SIZE * SIZE / 20, "{name}: the part covers {covered} pixels");
    for (what, img) in [("three.js", &three), ("preview", &preview)] {
        let mut v: Vec<f64> = (0..SIZE * SIZE).filter(|&p| mask[p]).map(|p| img.lum[p]).collect();
        v.sort_by(f64::total_cmp);
        let (median, peak) = (v[v.len() / 2], v[v.len() - 1]);
        assert!(
            peak > 0.0 && peak >= 10.0 * median,
            "{name}: {what} has no highlight (peak {peak}, median {median})"
        );
    }
    let (r3, rp, rt) = (ridge(&three, &mask), ridge(&preview, &mask), ridge(&turned, &mask));
    assert!(
        r3.len() >= 50 && rp.len() >= 50,
        "{name}: ridges of {} and {} pixels",
        r3.len(),
        rp.len()
    );
    let d = ridge_distance(&r3, &rp);
    let d_turned = ridge_distance(&rt, &rp);
    eprintln!(
        "{name}: key highlight ridge, three.js vs preview at {SIZE}²: {d:.2} px ({} / {} ridge pixels); \
         anisotropy turned by 90°: {d_turned:.2} px",
        r3.len(),
        rp.len()
    );
    assert!(d <= RIDGE_BOUND_PX, "{name}: ridge {d:.2} px from the preview's");
    assert!(
        d_turned > RIDGE_BOUND_PX,
        "{name}: turning the anisotropy by 90° left the ridge within {d_turned:.2} px: the check cannot tell"
    );
    if let Some(out) = std::env::var_os("GRAINLINE_GLTF_FIGURES") {
        // docs/img: the preview and the three.js render side by side (docs/guide.md).
        let out = PathBuf::from(out);
        std::fs::create_dir_all(&out).unwrap();
        std::fs::copy(x.dir.join("preview.png"), out.join(format!("gltf-{name}-preview.png")))
            .unwrap();
        std::fs::copy(x.dir.join("three.png"), out.join(format!("gltf-{name}-three.png"))).unwrap();
    }
    (d, d_turned)
}

/// The file's camera and key light, as three.js loaded them (world coordinates: metres, +Y up),
/// against the scene's, turned by the same node transform: same eye, forward, up (orthogonalized)
/// and field of view; the light towards the (possibly moved) key light with its irradiance.
fn check_view(name: &str, info: &Value, key: &Value) {
    let v = |x: &Value| [0, 1, 2].map(|k| x[k].as_f64().unwrap());
    let dist = |a: [f64; 3], b: [f64; 3]| (0..3).map(|k| (a[k] - b[k]).powi(2)).sum::<f64>().sqrt();
    let (fc, ex) = (&info["file_camera"], &info["expected"]);
    assert!(fc.is_object(), "{name}: the file has no camera: {info}");
    let eye = v(&ex["eye"]);
    let scale = eye.iter().map(|c| c * c).sum::<f64>().sqrt();
    assert!(dist(v(&fc["eye"]), eye) < 1e-5 * scale, "{name}: camera {fc} vs {ex}");
    let f = v(&ex["forward"]);
    assert!(dist(v(&fc["forward"]), f) < 1e-5, "{name}: camera {fc} vs {ex}");
    let u = v(&ex["up"]);
    let uf: f64 = (0..3).map(|k| u[k] * f[k]).sum();
    let w = [0, 1, 2].map(|k| u[k] - uf * f[k]);
    let n = w.iter().map(|c| c * c).sum::<f64>().sqrt();
    assert!(dist(v(&fc["up"]), w.map(|c| c / n)) < 1e-5, "{name}: camera {fc} vs {ex}");
    assert!((fc["fov_deg"].as_f64().unwrap() - ex["fov_deg"].as_f64().unwrap()).abs() < 1e-6);
    let fl = &info["file_light"];
    assert!(fl.is_object() && fl["count"] == 1, "{name}: the file has no single key light: {info}");
    assert!(dist(v(&fl["towards"]), v(&ex["light"])) < 1e-5, "{name}: light {fl} vs {ex}");
    let e = key.get("irradiance").and_then(Value::as_f64).unwrap_or(1.0);
    assert!((fl["intensity"].as_f64().unwrap() - e).abs() < 1e-9, "{name}: light {fl}");
}

fn example(name: &str, three: bool) {
    let Some(x) = export_example(name, three) else { return };
    let e = &x.report["export"];
    assert!(e["vertices"].as_u64().unwrap() >= e["mesh_vertices"].as_u64().unwrap());
    eprintln!("{name}: export {e}");
    validate(name, &x.glb);
    check_direction(name, &x);
    if three {
        check_three(name, &x);
    }
    std::fs::remove_dir_all(&x.dir).ok();
}

#[test]
fn kettle() {
    example("kettle", true);
}

/// GGX with aluminium, and a light edit (the key light moves).
#[test]
fn light() {
    example("light", true);
}

#[test]
fn dome() {
    example("dome", false);
}

#[test]
fn panel() {
    example("panel", false);
}

#[test]
fn spot() {
    example("spot", false);
}

/// The strokes node: LINES whose points lie on the part, and a valid file (kettle, its
/// toolpaths section).
#[test]
fn strokes_node() {
    let dir = std::env::temp_dir().join(format!("grainline-gltf-strokes-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let glb = dir.join("kettle.glb");
    let o = Command::new(env!("CARGO_BIN_EXE_grainline"))
        .args(["--quiet", "export"])
        .arg(root().join("examples/kettle/scene.json"))
        .arg("--glb")
        .arg(&glb)
        .args(["--strokes", "--as-brushed", "--report"])
        .arg(dir.join("r.json"))
        .output()
        .unwrap();
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let r: Value = serde_json::from_slice(&std::fs::read(dir.join("r.json")).unwrap()).unwrap();
    assert!(r["export"]["strokes"].as_u64().unwrap() > 10, "{}", r["export"]);
    assert!(r["plan"]["as_brushed"] == true && r["plan"]["trace"] == true);
    let bytes = std::fs::read(&glb).unwrap();
    let g = gltf::Gltf::from_slice(&bytes).unwrap();
    let blob = g.blob.as_deref().unwrap();
    let lines = g.meshes().nth(1).expect("a second mesh").primitives().next().unwrap();
    assert_eq!(lines.mode(), gltf::mesh::Mode::Lines);
    let pts: Vec<[f32; 3]> = lines.reader(|_| Some(blob)).read_positions().unwrap().collect();
    let surface: Vec<[f32; 3]> = g
        .meshes()
        .next()
        .unwrap()
        .primitives()
        .next()
        .unwrap()
        .reader(|_| Some(blob))
        .read_positions()
        .unwrap()
        .collect();
    // Every 50th stroke point lies within 6 mm of a vertex of the part (strokes are traced on
    // the surface; the kettle's edges are about that long).
    for p in pts.iter().step_by(50) {
        let d = surface
            .iter()
            .map(|q| (0..3).map(|k| (p[k] - q[k]).powi(2)).sum::<f32>().sqrt())
            .fold(f32::MAX, f32::min);
        assert!(d < 6.0, "stroke point {p:?} is {d} mm from the part");
    }
    validate("kettle with strokes", &glb);
    std::fs::remove_dir_all(&dir).ok();
}

/// Bad requests are refused naming the flag or the scene key: no output path, and strokes
/// asked for without a `toolpaths` section.
#[test]
fn errors_name_the_key() {
    let dir = std::env::temp_dir().join(format!("grainline-gltf-errors-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let run = |args: &[&str], scene: &Path| {
        let o = Command::new(env!("CARGO_BIN_EXE_grainline"))
            .args(["--quiet", "export"])
            .arg(scene)
            .args(args)
            .output()
            .unwrap();
        assert!(!o.status.success());
        String::from_utf8_lossy(&o.stderr).to_string()
    };
    let kettle = root().join("examples/kettle/scene.json");
    let e = run(&[], &kettle);
    assert!(e.contains("--glb"), "{e}");
    let text = std::fs::read_to_string(&kettle).unwrap();
    let mut scene: Value = serde_json::from_str(&text).unwrap();
    scene.as_object_mut().unwrap().remove("toolpaths");
    scene["mesh"] = json!(root().join("examples/data/kettle.obj"));
    let p = dir.join("scene.json");
    std::fs::write(&p, scene.to_string()).unwrap();
    let glb = dir.join("x.glb").display().to_string();
    let e = run(&["--glb", &glb, "--strokes"], &p);
    assert!(e.contains("export.strokes") && e.contains("toolpaths"), "{e}");
    assert!(!dir.join("x.glb").exists());
    std::fs::remove_dir_all(&dir).ok();
}
