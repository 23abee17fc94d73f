//! A brush on triangles larger than it (docs/math.md §12, "Between the vertices"): a flat panel
//! meshed as two triangles, as a CAD export meshes a flat face, takes a bend in its middle.
//!
//! Truth from outside the code: the panel is the plane z = 0 with its grain along x (its UVs),
//! lit by a directional light with no x component and seen by an eye at x = 0, so the half
//! vector's x component is ∝ −x / |eye − p| and the key highlight hᵀu = 0 is the line x = 0
//! exactly. The test reads FIELD.json and computes g = hᵀu itself from the positions: outside
//! the brush the solved highlight still crosses y = const at x = 0, inside it the bend has moved
//! it. A brush far smaller than the part (a slip of units) is still refused, naming the key.

use std::path::{Path, PathBuf};
use std::process::{Command, Output};

use nalgebra::Vector3;

fn dir(name: &str) -> PathBuf {
    let d = std::env::temp_dir().join(format!("grainline-large-tri-{}-{name}", std::process::id()));
    let _ = std::fs::remove_dir_all(&d);
    std::fs::create_dir_all(&d).unwrap();
    d
}

const PANEL: &str = "v -50 -30 0\nv 50 -30 0\nv 50 30 0\nv -50 30 0\n\
                     vt 0 0\nvt 1 0\nvt 1 1\nvt 0 1\nf 1/1 2/2 3/3\nf 1/1 3/3 4/4\n";
const EYE: [f64; 3] = [0.0, -20.0, 150.0];
const LIGHT: [f64; 3] = [0.0, -0.35, 1.0];

fn scene(d: &Path, radius: f64) -> PathBuf {
    std::fs::write(d.join("panel.obj"), PANEL).unwrap();
    let s = format!(
        r#"{{
  "units": "mm",
  "mesh": {{"path": "panel.obj"}},
  "field": {{"init": "uv", "symmetry": "line"}},
  "lights": [{{"type": "directional", "direction": {LIGHT:?}, "key": true}}],
  "view": {{"eye": {EYE:?}, "target": [0, 0, 0]}},
  "edits": [{{"tool": "bend", "centre": {{"point": [0, 0, 0]}}, "radius": {radius},
              "strength": 0.8, "direction": [1, 0, 0]}}]
}}"#
    );
    let p = d.join("scene.json");
    std::fs::write(&p, s).unwrap();
    p
}

fn optimize(sc: &Path, out: &Path, report: &Path) -> Output {
    Command::new(env!("CARGO_BIN_EXE_grainline"))
        .args(["--quiet", "optimize"])
        .arg(sc)
        .arg("--out")
        .arg(out)
        .arg("--report")
        .arg(report)
        .output()
        .unwrap()
}

fn vectors(v: &serde_json::Value, key: &str) -> Vec<Vector3<f64>> {
    v[key]
        .as_array()
        .unwrap_or_else(|| panic!("FIELD.json has no {key}"))
        .iter()
        .map(|p| {
            let c: Vec<f64> = p.as_array().unwrap().iter().map(|x| x.as_f64().unwrap()).collect();
            Vector3::new(c[0], c[1], c[2])
        })
        .collect()
}

/// g = hᵀu at a point, with h from the scene's light and eye (computed here, not read).
fn g(p: &Vector3<f64>, u: &Vector3<f64>) -> f64 {
    let l = Vector3::from(LIGHT).normalize();
    let v = (Vector3::from(EYE) - p).normalize();
    (l + v).normalize().dot(u)
}

/// Where the highlight of the field `u` crosses the row y ≈ `y` (|Δy| < `band`): the mean x of
/// the vertex pairs along the row, at most `gap` apart, whose g changes sign, each crossing
/// interpolated linearly, and of the vertices where g is 0.
fn crossing(pos: &[Vector3<f64>], u: &[Vector3<f64>], y: f64, band: f64, gap: f64) -> Option<f64> {
    let mut row: Vec<usize> = (0..pos.len()).filter(|&i| (pos[i].y - y).abs() < band).collect();
    row.sort_by(|&a, &b| pos[a].x.total_cmp(&pos[b].x));
    let mut xs = Vec::new();
    for w in row.windows(2) {
        let (a, b) = (w[0], w[1]);
        // A line field: align the second grain to the first before comparing signs.
        let ub = if u[a].dot(&u[b]) < 0.0 { -u[b] } else { u[b] };
        let (ga, gb) = (g(&pos[a], &u[a]), g(&pos[b], &ub));
        if ga * gb < 0.0 && (pos[b].x - pos[a].x) < gap {
            xs.push(pos[a].x + (pos[b].x - pos[a].x) * ga / (ga - gb));
        }
    }
    // A vertex exactly on the highlight (the refinement puts midpoints on x = 0).
    xs.extend(row.iter().filter(|&&i| g(&pos[i], &u[i]).abs() < 1e-12).map(|&i| pos[i].x));
    (!xs.is_empty()).then(|| xs.iter().sum::<f64>() / xs.len() as f64)
}

#[test]
fn a_bend_between_the_vertices_of_two_triangles_refines_them_and_lands() {
    let d = dir("lands");
    let sc = scene(&d, 8.0);
    let (out, rep) = (d.join("field.json"), d.join("report.json"));
    let o = optimize(&sc, &out, &rep);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let report: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(&rep).unwrap()).unwrap();
    let refinement = &report["refinement"];
    assert!(refinement["vertices_added"].as_u64().unwrap() > 100, "{refinement}");
    let fid = &report["fidelity"][0];
    assert_eq!(fid["landed"], true, "{fid}");
    assert!(fid["within"].as_f64().unwrap() >= 0.9, "{fid}");
    assert_eq!(fid["singular_after"], 0, "{fid}");

    let field: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(&out).unwrap()).unwrap();
    let pos = vectors(&field, "position");
    let (u, before) = (vectors(&field, "u"), vectors(&field, "u_before"));
    assert!(pos.iter().chain(&u).chain(&before).all(|p| p.iter().all(|c| c.is_finite())));
    // The brush holds vertices now (edges of r/3 inside it).
    let inside = pos.iter().filter(|p| p.norm() < 8.0).count();
    assert!(inside >= 20, "{inside} vertices inside the brush");
    // Before the edit: the highlight is x = 0 on every row that has vertices.
    let band = 1.0;
    let x0 = crossing(&pos, &before, 0.0, band, 5.0).expect("a highlight crosses y = 0 before");
    assert!(x0.abs() < 0.3, "before the edit the highlight crosses y = 0 at x = {x0}");
    // After: unchanged outside the brush — along the panel's edges y = ±30, whose consecutive
    // vertices share an edge (g is linear along it, however far apart they are: the panel is
    // refined near the brush only) — and moved across inside it.
    for y in [-30.0, 30.0] {
        let x = crossing(&pos, &u, y, 1e-9, f64::INFINITY)
            .expect("a highlight crosses the panel's edge");
        assert!(x.abs() < 0.5, "outside the brush (y = {y}) the highlight moved to x = {x}");
    }
    let x1 = crossing(&pos, &u, 0.0, band, 5.0).expect("a highlight crosses y = 0 after");
    assert!(x1.abs() > 0.8, "the bend did not move the highlight at the centre: x = {x1}");
}

#[test]
fn a_brush_far_smaller_than_the_part_between_its_vertices_is_refused() {
    let d = dir("refused");
    // 0.2 mm on a 117 mm panel: below 0.5 % of the diagonal.
    let sc = scene(&d, 0.2);
    let (out, rep) = (d.join("field.json"), d.join("report.json"));
    let o = optimize(&sc, &out, &rep);
    assert!(!o.status.success());
    let err = String::from_utf8_lossy(&o.stderr);
    assert!(err.contains("edits[0].radius") && err.contains("holds no vertex"), "{err}");
    assert!(!out.exists() && !rep.exists(), "a refused run writes nothing");
}
