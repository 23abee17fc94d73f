//! CAD parts as they are (docs/benchmarks.md, "CAD parts"): for every part, with
//! `field.init: "world"` and no edit, the share of the strokes' length within 1° of the world
//! direction projected onto each planar face of at least 5 % of the part's area, the share of
//! each such face's area that the glb carries flat (plane's normal within 1°, the grain as
//! tangent within 0.5°), the patches, and the layout's and the whole run's times; then a bend
//! and a drawn curve on the largest flat face, their fidelity (the report's) and the share of
//! the strokes more than two brush radii away that still run within 1° of the grain.
//!
//! ```text
//! cargo run --release --example bench_cad [-- --stl FILE UNITS]...
//! BENCH_SURFACES=off cargo run --release --example bench_cad   # the facets as they are
//! ```
//!
//! Parts: ../shared/meshes/cad (`GRAINLINE_SHARED` overrides ../shared), the parts of
//! `grainline::generate::cad` (written as binary STL), and any `--stl FILE UNITS`. The faces and
//! their grain are found from the STL alone (tests/support/cad_truth.rs). 2-core machine,
//! release build; the scenes run through the library's `pipeline::run`, as `grainline run`.
//! `BENCH_CAD_KEEP=1` keeps the scenes and their outputs (the directory is printed).

#[global_allocator]
static GLOBAL: mimalloc::MiMalloc = mimalloc::MiMalloc;

#[path = "../tests/support/cad_truth.rs"]
mod cad_truth;

use std::path::{Path, PathBuf};
use std::time::Instant;

use cad_truth::*;
use grainline::pipeline::run::{run, RunOptions};
use grainline::pipeline::Silent;
use grainline::scene::LoadedScene;

/// A world direction aligned with no face of the corpus.
const WORLD: P = [0.2, 1.0, 0.3];

struct Part {
    name: String,
    stl: PathBuf,
    units: String,
}

fn parts(out: &Path) -> Vec<Part> {
    let mut parts = Vec::new();
    let shared = std::env::var_os("GRAINLINE_SHARED")
        .map(PathBuf::from)
        .unwrap_or_else(|| PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("../shared"));
    for (file, units) in [
        ("box.STL", "in"),
        ("angle_block.STL", "in"),
        ("round.stl", "mm"),
        ("octagonal_pocket.stl", "m"),
        ("busted.STL", "mm"),
    ] {
        let stl = shared.join("meshes/cad").join(file);
        if stl.exists() {
            parts.push(Part { name: file.to_string(), stl, units: units.to_string() });
        } else {
            eprintln!("skipping {}: not found", stl.display());
        }
    }
    parts.extend(generated(out));
    let mut args = std::env::args().skip(1);
    while let Some(a) = args.next() {
        match (a.as_str(), args.next(), args.next()) {
            ("--stl", Some(f), Some(u)) => {
                let stl = PathBuf::from(&f);
                let name = stl.file_name().unwrap().to_string_lossy().to_string();
                parts.push(Part { name, stl, units: u });
            }
            _ => {
                eprintln!("usage: bench_cad [--stl FILE UNITS]...");
                std::process::exit(2);
            }
        }
    }
    parts
}

/// The generated CAD parts (`grainline::generate::cad`), written as binary STL under `out`.
fn generated(out: &Path) -> Vec<Part> {
    use grainline::generate::cad;
    let parts = [
        cad::housing(&Default::default()),
        cad::plate(&Default::default()),
        cad::bracket(&Default::default()),
        cad::turned(&Default::default()),
    ];
    parts
        .into_iter()
        .map(|p| {
            let p = p.expect("a generated part");
            let stl = out.join(format!("{}.stl", p.name));
            std::fs::write(&stl, p.stl_binary()).unwrap();
            Part { name: format!("generated {}", p.name), stl, units: p.units.as_str().to_string() }
        })
        .collect()
}

/// Runs `scene` from `dir`; returns the run report and the wall time.
fn run_scene(dir: &Path, scene: &serde_json::Value) -> (serde_json::Value, f64) {
    let path = dir.join("scene.json");
    std::fs::write(&path, serde_json::to_string_pretty(scene).unwrap()).unwrap();
    let report = dir.join("report.json");
    let start = Instant::now();
    let s = LoadedScene::read(&path).expect("scene");
    let options = RunOptions { out_dir: None, field: None, report: Some(report.clone()) };
    run(&s, &options, &Silent).unwrap_or_else(|e| panic!("{}: {e}", path.display()));
    let wall = start.elapsed().as_secs_f64();
    (serde_json::from_slice(&std::fs::read(&report).unwrap()).unwrap(), wall)
}

fn stage(report: &serde_json::Value, name: &str) -> f64 {
    report["stages"]
        .as_array()
        .unwrap()
        .iter()
        .filter(|s| s["stage"] == name)
        .map(|s| s["seconds"].as_f64().unwrap())
        .sum()
}

fn base_scene(part: &Part, d: f64, eye: P, target: P, light: P) -> serde_json::Value {
    // `BENCH_SURFACES=off` reads the facets as they are (`mesh.surfaces: "off"`), to compare.
    let surfaces = std::env::var("BENCH_SURFACES").unwrap_or_else(|_| "recognize".into());
    serde_json::json!({
        "mesh": {"path": part.stl, "allow_nonmanifold": true, "surfaces": surfaces},
        "units": part.units,
        "lights": [{"type": "directional", "direction": light}],
        "view": {"eye": eye, "target": target},
        "field": {"init": "world", "world": WORLD},
        "toolpaths": {"strokes_json": "strokes.json", "placement": {"width": d / 50.0}},
    })
}

fn pct(x: f64) -> String {
    if x.is_nan() {
        "–".to_string()
    } else {
        format!("{:.1} %", 100.0 * x)
    }
}

fn main() {
    let out = std::env::temp_dir().join(format!("grainline-bench-cad-{}", std::process::id()));
    std::fs::create_dir_all(&out).unwrap();
    let parts = parts(&out);
    println!("| part | V file | V split | patches | flat faces ≥ 5 % | strokes within 1° (worst face) | glb flat (worst face) | layout s | run s |");
    println!("|---|---|---|---|---|---|---|---|---|");
    let mut edit_rows = Vec::new();
    for part in &parts {
        let tris = read_stl(&part.stl);
        let d = diagonal(&tris);
        let faces = large_planar_faces(&tris, 0.05);
        let tol = 1e-4 * d;
        let dir = out.join(&part.name);
        std::fs::create_dir_all(&dir).unwrap();
        let c =
            tris.iter().flatten().fold([0.0; 3], |a, p| [a[0] + p[0], a[1] + p[1], a[2] + p[2]]);
        let c = c.map(|x| x / (3 * tris.len()) as f64);
        let mut scene =
            base_scene(part, d, [c[0] + d, c[1] - 2.0 * d, c[2] + 1.5 * d], c, [0.3, -0.5, 1.0]);
        scene["export"] = serde_json::json!({"glb": "part.glb"});
        let (report, wall) = run_scene(&dir, &scene);
        let straight = stroke_straightness(&dir.join("strokes.json"), &faces, WORLD, tol);
        let flat = glb_flatness(&dir.join("part.glb"), &faces, WORLD, tol);
        let worst = |v: &[(f64, f64)]| v.iter().map(|(t, g)| g / t).fold(f64::NAN, f64::min);
        let split = report["vertices"].as_u64().unwrap_or(0);
        let (vfile, patches) = match report["patches"].as_object() {
            Some(p) => (p["vertices_before"].as_u64().unwrap(), p["patches"].as_u64().unwrap()),
            None => (split, 1),
        };
        println!(
            "| {} ({}) | {vfile} | {split} | {patches} | {} | {} | {} | {:.2} | {:.2} |",
            part.name,
            part.units,
            faces.len(),
            pct(worst(&straight)),
            pct(worst(&flat)),
            stage(&report, "layout"),
            wall
        );
        if let Some(face) = faces.first() {
            for tool in ["bend", "curve"] {
                edit_rows.push(edit_row(part, &tris, face, tool, &out));
            }
        }
    }
    println!();
    println!("| part | edit on the largest flat face | r | within 0.05 r | p95 (× r) | singular before → after | landed | V refined | strokes > 2 r away within 1° | run s |");
    println!("|---|---|---|---|---|---|---|---|---|---|");
    for r in edit_rows {
        println!("{r}");
    }
    if std::env::var_os("BENCH_CAD_KEEP").is_some() {
        eprintln!("scenes and outputs kept in {}", out.display());
    } else {
        std::fs::remove_dir_all(&out).ok();
    }
}

/// A bend or a drawn curve at the deepest point of `face`, seen so that the key highlight
/// passes there; its table row.
fn edit_row(part: &Part, tris: &[[P; 3]], face: &PlanarFace, tool: &str, out: &Path) -> String {
    let d = diagonal(tris);
    let (p0, clearance) = face.deep_point();
    let r = (0.04 * d).min(0.6 * clearance);
    let n = face.normal;
    let u = face.world_grain(WORLD);
    let EditSite { light: l, eye, push, curve } = edit_site(p0, n, u, r, d);
    let mut scene = base_scene(part, d, eye, p0, l);
    scene["toolpaths"]["placement"]["width"] = serde_json::json!(r / 6.0);
    scene["edits"] = match tool {
        "bend" => serde_json::json!([{"tool": "bend", "centre": {"point": p0}, "radius": r,
                                       "strength": 0.8, "direction": push}]),
        _ => serde_json::json!([{"tool": "curve", "points": [curve], "radius": r / 3.0}]),
    };
    let dir = out.join(format!("{}-{tool}", part.name));
    std::fs::create_dir_all(&dir).unwrap();
    let (report, wall) = run_scene(&dir, &scene);
    let f = &report["optimize"]["fidelity"][0];
    // Strokes on the face more than 2 r from the brush (its centre, or the drawn curve).
    let far = |p: P| match tool {
        "bend" => norm(sub(p, p0)) > 2.0 * r,
        _ => curve.windows(2).all(|s| segment_distance(p, s[0], s[1]) > 2.0 * r),
    };
    let (total, good) = far_straightness(&dir.join("strokes.json"), face, u, 1e-4 * d, far);
    let refined = report["optimize"]["refinement"]["vertices_added"].as_u64().unwrap_or(0);
    format!(
        "| {} | {tool} | {:.3} | {} | {:.3} | {} → {} | {} | +{refined} | {} | {wall:.2} |",
        part.name,
        r,
        pct(f["within"].as_f64().unwrap_or(f64::NAN)),
        f["p95"].as_f64().unwrap_or(f64::NAN),
        f["singular_before"],
        f["singular_after"],
        f["landed"],
        pct(good / total),
    )
}

/// (length, length within 1° of `u`) of the stroke segments on `face` whose both ends pass
/// `keep`.
fn far_straightness(
    strokes: &Path,
    face: &PlanarFace,
    u: P,
    tol: f64,
    keep: impl Fn(P) -> bool,
) -> (f64, f64) {
    let s: serde_json::Value = serde_json::from_slice(&std::fs::read(strokes).unwrap()).unwrap();
    let v3 = |v: &serde_json::Value| [0, 1, 2].map(|k| v[k].as_f64().unwrap());
    let (mut total, mut good) = (0.0, 0.0);
    for stroke in s["strokes"].as_array().unwrap() {
        for piece in stroke["xyz"].as_array().unwrap() {
            let xyz: Vec<P> = piece.as_array().unwrap().iter().map(v3).collect();
            for seg in xyz.windows(2) {
                let dseg = sub(seg[1], seg[0]);
                let len = norm(dseg);
                let m = [0, 1, 2].map(|c| 0.5 * (seg[0][c] + seg[1][c]));
                if len > 0.0 && keep(seg[0]) && keep(seg[1]) && face.contains(m, tol) {
                    total += len;
                    if angle_deg(dseg, u, true) < 1.0 {
                        good += len;
                    }
                }
            }
        }
    }
    (total, good)
}
