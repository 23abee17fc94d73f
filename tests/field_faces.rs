//! Issue 33, item 3: FIELD.json (version 2) holds the faces of the mesh its field lives on,
//! after the patch split and the refinement inside the brushes, so a reader rebuilds the
//! triangles from the file alone; `--field` still reads version 1 (no faces).
//!
//! Truth from outside the code (as tests/hard_cases_large_triangles.rs): a flat panel meshed as
//! two triangles, the plane z = 0 with its grain along x, lit by a directional light with no x
//! component and seen by an eye at x = 0, so the key highlight hᵀu = 0 of the initial field is
//! the line x = 0. A bend of radius r, strength s and direction +x centred at the origin warps
//! it (docs/math.md §8, "Warps": on a plane the brush chart is (p − o)/r, W(x, y) = (x, y + s·d),
//! d = (1 − x² − y²)²/2) to the curve X = r·s·(1 − (Y/r)²)²/2. The test computes g = hᵀu itself
//! from FIELD.json's positions and grain on FIELD.json's faces (h from the scene's light and eye)
//! and finds that curve where the run report's fidelity says the edit landed.

use std::path::{Path, PathBuf};

mod common;

use common::{grainline, json_vectors, ok, read_json, scratch_dir};
use nalgebra::Vector3;

const PANEL: &str = "v -50 -30 0\nv 50 -30 0\nv 50 30 0\nv -50 30 0\n\
                     vt 0 0\nvt 1 0\nvt 1 1\nvt 0 1\nf 1/1 2/2 3/3\nf 1/1 3/3 4/4\n";
const EYE: [f64; 3] = [0.0, -20.0, 150.0];
const LIGHT: [f64; 3] = [0.0, -0.35, 1.0];
const RADIUS: f64 = 8.0;
const STRENGTH: f64 = 0.8;

/// The panel with a bend at its centre; `run` writes FIELD.json (`o/field.json`) and a small
/// preview (`o/run.png`).
fn panel_scene(d: &Path) -> PathBuf {
    std::fs::write(d.join("panel.obj"), PANEL).unwrap();
    let s = format!(
        r#"{{
  "units": "mm",
  "mesh": {{"path": "panel.obj"}},
  "field": {{"init": "uv", "symmetry": "line", "output": "o/field.json"}},
  "lights": [{{"type": "directional", "direction": {LIGHT:?}, "key": true}}],
  "view": {{"eye": {EYE:?}, "target": [0, 0, 0]}},
  "edits": [{{"tool": "bend", "centre": {{"point": [0, 0, 0]}}, "radius": {RADIUS},
              "strength": {STRENGTH}, "direction": [1, 0, 0]}}],
  "render": {{"width": 48, "height": 32, "output": "o/run.png"}}
}}"#
    );
    let p = d.join("scene.json");
    std::fs::write(&p, s).unwrap();
    p
}

/// FIELD.json's faces, each index checked to be in range and the corners distinct.
fn faces(v: &serde_json::Value, n: usize) -> Vec<[usize; 3]> {
    let a = v["faces"].as_array().expect("FIELD.json version 2 has `faces`");
    a.iter()
        .map(|f| {
            let f: Vec<usize> =
                f.as_array().unwrap().iter().map(|i| i.as_u64().unwrap() as usize).collect();
            assert_eq!(f.len(), 3, "a face is three indices: {f:?}");
            assert!(f.iter().all(|&i| i < n), "face {f:?} out of range ({n} vertices)");
            assert!(f[0] != f[1] && f[1] != f[2] && f[0] != f[2], "degenerate face {f:?}");
            [f[0], f[1], f[2]]
        })
        .collect()
}

/// The input OBJ's own triangles (fans of its `f` lines) and their total area.
fn obj_area(text: &str) -> f64 {
    let v: Vec<Vector3<f64>> = text
        .lines()
        .filter_map(|l| l.strip_prefix("v "))
        .map(|l| {
            let c: Vec<f64> = l.split_whitespace().map(|x| x.parse().unwrap()).collect();
            Vector3::new(c[0], c[1], c[2])
        })
        .collect();
    let corner = |s: &str| s.split('/').next().unwrap().parse::<usize>().unwrap() - 1;
    text.lines()
        .filter_map(|l| l.strip_prefix("f "))
        .map(|l| {
            let c: Vec<usize> = l.split_whitespace().map(corner).collect();
            (1..c.len() - 1)
                .map(|k| 0.5 * (v[c[k]] - v[c[0]]).cross(&(v[c[k + 1]] - v[c[0]])).norm())
                .sum::<f64>()
        })
        .sum()
}

/// Checks the triangles rebuilt from FIELD.json: their area is the part's, and each winds
/// counter-clockwise around the outward normals FIELD.json gives its corners.
fn check_triangles(pos: &[Vector3<f64>], normal: &[Vector3<f64>], tris: &[[usize; 3]], area: f64) {
    let mut total = 0.0;
    for t in tris {
        let cross = (pos[t[1]] - pos[t[0]]).cross(&(pos[t[2]] - pos[t[0]]));
        total += 0.5 * cross.norm();
        for &c in t {
            assert!(cross.dot(&normal[c]) > 0.0, "face {t:?} winds against its normals");
        }
    }
    assert!((total - area).abs() <= 1e-9 * area, "faces' area {total}, the part's {area}");
    // Every vertex lies on a face.
    let mut used = vec![false; pos.len()];
    tris.iter().flatten().for_each(|&c| used[c] = true);
    assert!(used.iter().all(|&u| u), "a vertex on no face");
}

/// g = hᵀu at a point, with h from the scene's light and eye (computed here, not read).
fn g(p: &Vector3<f64>, u: &Vector3<f64>) -> f64 {
    let l = Vector3::from(LIGHT).normalize();
    let v = (Vector3::from(EYE) - p).normalize();
    (l + v).normalize().dot(u)
}

/// The key highlight g = 0 of the line field `u`, one segment per face whose corners' signs
/// differ (g linear on the face; corners aligned to the first, as a line field's ±u).
fn highlight(
    pos: &[Vector3<f64>],
    u: &[Vector3<f64>],
    tris: &[[usize; 3]],
) -> Vec<[Vector3<f64>; 2]> {
    let mut segments = Vec::new();
    for t in tris {
        let ua = u[t[0]];
        let gs: Vec<f64> = t
            .iter()
            .map(|&c| g(&pos[c], &if u[c].dot(&ua) < 0.0 { -u[c] } else { u[c] }))
            .collect();
        let mut ends = Vec::new();
        for (i, j) in [(0, 1), (1, 2), (2, 0)] {
            if (gs[i] >= 0.0) != (gs[j] >= 0.0) {
                let s = gs[i] / (gs[i] - gs[j]);
                ends.push(pos[t[i]] + (pos[t[j]] - pos[t[i]]) * s);
            }
        }
        if ends.len() == 2 {
            segments.push([ends[0], ends[1]]);
        }
    }
    segments
}

fn distance_to_segment(p: &Vector3<f64>, [a, b]: &[Vector3<f64>; 2]) -> f64 {
    let d = b - a;
    let t = if d.norm_squared() > 0.0 {
        ((p - a).dot(&d) / d.norm_squared()).clamp(0.0, 1.0)
    } else {
        0.0
    };
    (p - (a + d * t)).norm()
}

/// The bend's target W(C0) on the panel, sampled along the chord: chart points (x, y) with
/// y = s·(1 − x²)²/2 and |W| < 0.85 (the samples the fidelity counts), as world points.
fn target() -> Vec<Vector3<f64>> {
    (-1000..=1000)
        .map(|k| k as f64 / 1000.0)
        .map(|x| (x, STRENGTH * (1.0 - x * x).powi(2) / 2.0))
        .filter(|(x, y)| (x * x + y * y).sqrt() < 0.85)
        .map(|(x, y)| Vector3::new(RADIUS * y, RADIUS * x, 0.0))
        .collect()
}

fn quantile(sorted: &[f64], q: f64) -> f64 {
    sorted[((q * sorted.len() as f64).ceil() as usize).clamp(1, sorted.len()) - 1]
}

#[test]
fn field_json_of_a_refined_part_rebuilds_its_triangles_and_its_highlight_issue_33() {
    let d = scratch_dir("field-faces", "refined");
    let sc = panel_scene(&d);
    let rep = d.join("report.json");
    ok(&grainline(&["--quiet", "run", sc.to_str().unwrap(), "--report", rep.to_str().unwrap()]));
    let (field, report) = (read_json(&d.join("o/field.json")), read_json(&rep));
    assert_eq!(field["version"], 3);
    let pos = json_vectors(&field, "position");
    let (normal, u) = (json_vectors(&field, "normal"), json_vectors(&field, "u"));
    let tris = faces(&field, pos.len());
    // The part was refined inside the brush: the faces are the refined mesh's, as the report
    // counts them.
    let added = report["optimize"]["refinement"]["vertices_added"].as_u64().unwrap();
    assert!(added > 100, "{}", report["optimize"]["refinement"]);
    assert_eq!(pos.len() as u64, report["vertices"].as_u64().unwrap());
    assert_eq!(tris.len() as u64, report["faces"].as_u64().unwrap());
    assert!(tris.len() > 2);
    check_triangles(&pos, &normal, &tris, obj_area(PANEL));

    // The key highlight of the solved field, on FIELD.json's own triangles.
    let c1 = highlight(&pos, &u, &tris);
    assert!(!c1.is_empty());
    let fid = &report["optimize"]["fidelity"][0];
    assert_eq!(fid["landed"], true, "{fid}");
    let mut dist: Vec<f64> = target()
        .iter()
        .map(|p| c1.iter().map(|s| distance_to_segment(p, s)).fold(f64::INFINITY, f64::min))
        .map(|d| (d / RADIUS).min(2.0))
        .collect();
    dist.sort_by(f64::total_cmp);
    let within = dist.iter().filter(|&&d| d <= 0.05).count() as f64 / dist.len() as f64;
    let (median, p95) = (quantile(&dist, 0.5), quantile(&dist, 0.95));
    let figure = |k: &str| fid[k].as_f64().unwrap();
    eprintln!("rebuilt: within {within} median {median} p95 {p95}; report: {fid}");
    // The report's figures, found again from the file alone.
    assert!((within - figure("within")).abs() <= 0.02, "within {within}: {fid}");
    assert!((median - figure("median")).abs() <= 0.01, "median {median}: {fid}");
    assert!((p95 - figure("p95")).abs() <= 0.02, "p95 {p95}: {fid}");
    // At the brush's centre the highlight moved to x = r·s/2 (3.2 mm), across the row y = 0.
    let centre: Vec<f64> = c1
        .iter()
        .filter(|[a, b]| (a.y <= 0.0) != (b.y <= 0.0) && a.x.abs() < RADIUS)
        .map(|[a, b]| a.x + (b.x - a.x) * a.y / (a.y - b.y))
        .collect();
    assert_eq!(centre.len(), 1, "{centre:?}");
    assert!((centre[0] - RADIUS * STRENGTH / 2.0).abs() < 0.05 * RADIUS, "{centre:?}");
    std::fs::remove_dir_all(&d).ok();
}

#[test]
fn field_json_of_a_part_cut_into_patches_holds_the_copies_faces() {
    // A cube is cut along its twelve sharp edges into six patches: its faces name the copies.
    let d = scratch_dir("field-faces", "patches");
    let cube = PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("tests/data/cube_uv.obj");
    let text = std::fs::read_to_string(&cube).unwrap();
    std::fs::write(d.join("cube.obj"), &text).unwrap();
    let sc = d.join("scene.json");
    std::fs::write(
        &sc,
        r#"{"mesh": "cube.obj", "field": {"init": "uv", "output": "field.json"},
            "lights": [{"type": "directional", "direction": [0.3, -0.5, 1]}],
            "view": {"eye": [3, -4, 5], "target": [0.5, 0.5, 0.5]}}"#,
    )
    .unwrap();
    ok(&grainline(&["--quiet", "run", sc.to_str().unwrap()]));
    let field = read_json(&d.join("field.json"));
    let pos = json_vectors(&field, "position");
    let copies = field["patch_copies"].as_array().expect("the cube was split").len();
    assert_eq!(pos.len(), 8 + copies);
    let tris = faces(&field, pos.len());
    assert_eq!(tris.len(), 12);
    assert!(tris.iter().flatten().any(|&c| c >= 8), "no face names a copy");
    let normal = json_vectors(&field, "normal");
    check_triangles(&pos, &normal, &tris, obj_area(&text));
    // Each patch is flat: a face's corners carry its own normal.
    for t in &tris {
        let n = (pos[t[1]] - pos[t[0]]).cross(&(pos[t[2]] - pos[t[0]])).normalize();
        assert!(t.iter().all(|&c| normal[c].dot(&n) > 0.999), "{t:?}");
    }
    // `grainline field` writes the loaded mesh's faces too.
    let out = d.join("plain.json");
    ok(&grainline(&[
        "--quiet",
        "field",
        cube.to_str().unwrap(),
        "--light",
        "0.3,-0.5,1",
        "--view",
        "0,-1,0.5",
        "--out",
        out.to_str().unwrap(),
    ]));
    let plain = read_json(&out);
    assert_eq!(plain["version"], 3);
    assert_eq!(faces(&plain, 8).len(), 12);
    std::fs::remove_dir_all(&d).ok();
}

#[test]
fn field_option_reads_version_1_and_checks_version_2s_faces() {
    let d = scratch_dir("field-faces", "versions");
    let sc = panel_scene(&d);
    ok(&grainline(&["--quiet", "run", sc.to_str().unwrap()]));
    let v2 = read_json(&d.join("o/field.json"));
    let render = |field: &Path, png: &str| {
        grainline(&[
            "--quiet",
            "render",
            sc.to_str().unwrap(),
            "--field",
            field.to_str().unwrap(),
            "--out",
            d.join(png).to_str().unwrap(),
        ])
    };
    let write = |name: &str, v: &serde_json::Value| {
        let p = d.join(name);
        std::fs::write(&p, serde_json::to_vec(v).unwrap()).unwrap();
        p
    };
    // A version-1 file (no faces) reads, and shows what its version-2 original shows.
    let mut v1 = v2.clone();
    v1.as_object_mut().unwrap().remove("faces");
    v1["version"] = 1.into();
    let v1 = write("v1.json", &v1);
    ok(&render(&d.join("o/field.json"), "v2.png"));
    ok(&render(&v1, "v1.png"));
    assert!(std::fs::read(d.join("v1.png")).unwrap() == std::fs::read(d.join("v2.png")).unwrap());
    // So does a version-2 file (no `meta.diagnostics.fidelity`, which version 3 added).
    let mut older = v2.clone();
    older["meta"]["diagnostics"].as_object_mut().unwrap().remove("fidelity");
    older["version"] = 2.into();
    let older = write("older.json", &older);
    ok(&render(&older, "older.png"));
    assert!(
        std::fs::read(d.join("older.png")).unwrap() == std::fs::read(d.join("v2.png")).unwrap()
    );
    // Version 2 without faces, a face out of range, an unknown version: refused, naming the
    // file and the key.
    let mut no_faces = v2.clone();
    no_faces.as_object_mut().unwrap().remove("faces");
    let mut out_of_range = v2.clone();
    let n = v2["position"].as_array().unwrap().len();
    out_of_range["faces"][3] = serde_json::json!([0, 1, n]);
    let mut v4 = v2.clone();
    v4["version"] = 4.into();
    for (name, v, want) in [
        ("no-faces.json", no_faces, "version 3 needs `faces`".to_string()),
        ("range.json", out_of_range, format!("faces[3] names vertex {n}")),
        ("v4.json", v4, "version is 4".to_string()),
    ] {
        let p = write(name, &v);
        let o = render(&p, "bad.png");
        assert!(!o.status.success());
        let e = String::from_utf8_lossy(&o.stderr);
        assert!(e.contains(name) && e.contains(&want), "{e}");
    }
    std::fs::remove_dir_all(&d).ok();
}
