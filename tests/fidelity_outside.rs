//! Issue 32, item 3: the run report's `fidelity` is the figure a reader computes from FIELD.json
//! and the scene alone, on a noisy scan.
//!
//! The part is an ellipsoid 100 × 84 × 72 mm scanned with uniform radial noise of ±0.45 mm at
//! about 0.9 mm spacing (RMS 0.26 mm, 0.29 of the spacing; `field.noise: "auto"` fits the
//! normals over a ball). A bend and an expand (strength 0.8, radius 6 and 7 % of the diagonal)
//! are centred on the key highlight and push across it; a drawn S-curve (radius 2 % of the
//! diagonal) crosses it. Each runs through `grainline run`, and this file measures the edit
//! again from FIELD.json (positions, faces, normals, `u`, `u_before`) and the scene (light,
//! eye, the edit), by docs/math.md §10 written out here, without grainline's fidelity code:
//!
//! - g = hᵀu per vertex, h = (l + v)/|l + v| from the scene's light and eye; per face the zero
//!   segment of the linear g (line field: corners aligned to the first).
//! - Warps: the brush's coordinates are the tangent plane at the centre (normal: FIELD.json's at
//!   the nearest vertex; +y the edit's direction), in units of r — on this part, whose radius of
//!   curvature is 3–5 brush radii, within 0.01 r of the geodesic polar coordinates the tool
//!   works in. C0 (from `u_before`) is mapped by the warp W, sampled every 0.01 and kept within
//!   0.85 of the centre; a sample is within when a C1 segment (from `u`, with an end in the unit
//!   disk) is within 0.05.
//! - Curve: samples every 0.01 r along the drawn polyline, less one radius at each end; the
//!   distance to a C1 segment in the plane of its face.
//!
//! The report and this measure agree within 0.05 in share for each edit. With the chart that
//! added the noise's height to every step (before issue 32, item 3) the bend's report said
//! 100 % where this measure finds 83 % (at ±0.5 mm: 46 %): the chart was 5–8 % larger than the
//! surface, so the highlight moved that much less on the part than in the chart.

use std::path::{Path, PathBuf};

mod common;

use common::{grainline, json_vectors, ok, read_json, scratch_dir};
use nalgebra::{SVector, Vector2, Vector3};

type V2 = Vector2<f64>;
type V3 = Vector3<f64>;

/// Semi-axes of the scanned ellipsoid, mm.
const AXES: [f64; 3] = [50.0, 42.0, 36.0];
/// Half-width of the uniform radial noise, mm.
const NOISE: f64 = 0.45;
const LIGHT: [f64; 3] = [0.25, -1.0, 0.2];
const EYE: [f64; 3] = [0.0, -400.0, 0.0];
const STRENGTH: f64 = 0.8;
/// Tolerance and compare radius of the measure, units of r.
const TOLERANCE: f64 = 0.05;
const COMPARE: f64 = 0.85;

/// The noisy ellipsoid: an icosphere of 6 subdivisions (40 962 vertices) stretched to `AXES`,
/// each vertex moved along its radius by a fixed LCG's draw in ±`NOISE`.
fn noisy_ellipsoid_obj() -> String {
    let mut m = grainline::generate::icosphere(1.0, 6);
    let mut s = 0x2545_f491_4f6c_dd1du64;
    for p in &mut m.positions {
        s = s.wrapping_mul(6364136223846793005).wrapping_add(1442695040888963407);
        let r = (s >> 11) as f64 / (1u64 << 53) as f64;
        let q = V3::new(p.x * AXES[0], p.y * AXES[1], p.z * AXES[2]);
        *p = q + q.normalize() * NOISE * (2.0 * r - 1.0);
    }
    grainline::mesh::write::obj_string(&m, "noisy ellipsoid")
}

/// The point of the smooth ellipsoid in the direction of azimuth `a` (from −y towards +x) and
/// elevation `b`.
fn on_ellipsoid(a: f64, b: f64) -> V3 {
    let d = V3::new(a.sin() * b.cos(), -a.cos() * b.cos(), b.sin());
    let k = (0..3).map(|i| (d[i] / AXES[i]).powi(2)).sum::<f64>().sqrt();
    d / k
}

/// What a reader takes from FIELD.json.
struct Field {
    pos: Vec<V3>,
    faces: Vec<[usize; 3]>,
    normal: Vec<V3>,
    u: Vec<V3>,
    u_before: Vec<V3>,
}

fn read_field(p: &Path) -> Field {
    let v = read_json(p);
    let index = |i: &serde_json::Value| i.as_u64().unwrap() as usize;
    let faces = v["faces"].as_array().expect("FIELD.json version 2 has faces");
    let faces = faces
        .iter()
        .map(|f| {
            let f = f.as_array().unwrap();
            [index(&f[0]), index(&f[1]), index(&f[2])]
        })
        .collect();
    let u = json_vectors(&v, "u");
    let u_before =
        if v.get("u_before").is_some() { json_vectors(&v, "u_before") } else { u.clone() };
    Field {
        pos: json_vectors(&v, "position"),
        faces,
        normal: json_vectors(&v, "normal"),
        u,
        u_before,
    }
}

/// The half vector at p from the scene's light and eye.
fn half(p: &V3) -> V3 {
    (V3::from(LIGHT).normalize() + (V3::from(EYE) - p).normalize()).normalize()
}

/// The key highlight of the line field `u` on `faces`: (face, segment) where g = hᵀu, linear on
/// the face with its corners aligned to the first, changes sign.
fn highlight(f: &Field, u: &[V3], faces: &[usize]) -> Vec<(usize, [V3; 2])> {
    let mut out = Vec::new();
    for &k in faces {
        let t = f.faces[k];
        let ua = u[t[0]];
        let g = t.map(|c| half(&f.pos[c]).dot(&if u[c].dot(&ua) < 0.0 { -u[c] } else { u[c] }));
        let mut ends = Vec::new();
        for (i, j) in [(0, 1), (1, 2), (2, 0)] {
            if (g[i] >= 0.0) != (g[j] >= 0.0) {
                let s = g[i] / (g[i] - g[j]);
                ends.push(f.pos[t[i]] + (f.pos[t[j]] - f.pos[t[i]]) * s);
            }
        }
        if ends.len() == 2 {
            out.push((k, [ends[0], ends[1]]));
        }
    }
    out
}

/// Distance from p to the segment ab, in the plane or in space.
fn distance<const D: usize>(p: &SVector<f64, D>, a: &SVector<f64, D>, b: &SVector<f64, D>) -> f64 {
    let d = b - a;
    let t = if d.norm_squared() > 0.0 {
        ((p - a).dot(&d) / d.norm_squared()).clamp(0.0, 1.0)
    } else {
        0.0
    };
    (p - (a + d * t)).norm()
}

/// The warps of docs/math.md §8: bend d = w/2, expand d = w·g(y)/2, w = (1 − x² − y²)².
fn warp(tool: &str, p: V2) -> V2 {
    let w = (1.0 - p.norm_squared()).max(0.0).powi(2);
    let d = match tool {
        "bend" => w / 2.0,
        _ => w * p.y.sin() / (p.y.sin().powi(2) + 0.02f64.powi(2)).powf(0.25) / 2.0,
    };
    V2::new(p.x, p.y + STRENGTH * d)
}

/// Points every `spacing` of arc length along the chains `lines` (the first at spacing/2, the
/// phase carried from piece to piece).
fn resample(lines: &[Vec<V2>], spacing: f64) -> Vec<V2> {
    let (mut out, mut next) = (Vec::new(), 0.5 * spacing);
    for w in lines.iter().flat_map(|l| l.windows(2)) {
        let len = (w[1] - w[0]).norm();
        while next <= len {
            out.push(w[0] + (w[1] - w[0]) * (next / len));
            next += spacing;
        }
        next -= len;
    }
    out
}

/// A warp's share within tolerance and its sample count, measured in the tangent plane at the
/// centre.
fn outside_warp(f: &Field, tool: &str, centre: &V3, radius: f64, direction: &V3) -> (f64, usize) {
    let nearest = (0..f.pos.len())
        .min_by(|&a, &b| (f.pos[a] - centre).norm().total_cmp(&(f.pos[b] - centre).norm()))
        .unwrap();
    let n0 = f.normal[nearest];
    let ey = (direction - n0 * n0.dot(direction)).normalize();
    let ex = ey.cross(&n0);
    let plane = |p: &V3| V2::new(ex.dot(&(p - centre)), ey.dot(&(p - centre))) / radius;
    let faces: Vec<usize> = (0..f.faces.len())
        .filter(|&k| f.faces[k].iter().any(|&c| (f.pos[c] - centre).norm() < 1.1 * radius))
        .filter(|&k| f.faces[k].iter().map(|&c| f.normal[c]).sum::<V3>().dot(&n0) > 0.0)
        .collect();
    let c1: Vec<[V2; 2]> = highlight(f, &f.u, &faces)
        .iter()
        .map(|(_, s)| [plane(&s[0]), plane(&s[1])])
        .filter(|s| s[0].norm() <= 1.0 || s[1].norm() <= 1.0)
        .collect();
    // W(C0): each C0 segment subdivided finely before the warp.
    let warped: Vec<Vec<V2>> = highlight(f, &f.u_before, &faces)
        .iter()
        .map(|(_, s)| {
            let (a, b) = (plane(&s[0]), plane(&s[1]));
            let n = ((b - a).norm() / 0.001).ceil().max(1.0) as usize;
            (0..=n).map(|k| warp(tool, a + (b - a) * (k as f64 / n as f64))).collect()
        })
        .collect();
    let samples: Vec<V2> =
        resample(&warped, 0.01).into_iter().filter(|p| p.norm() < COMPARE).collect();
    let within = samples
        .iter()
        .filter(|p| c1.iter().any(|s| distance(p, &s[0], &s[1]) <= TOLERANCE))
        .count();
    (within as f64 / samples.len().max(1) as f64, samples.len())
}

/// A curve's share within tolerance and its sample count: distances in the plane of C1's face.
fn outside_curve(f: &Field, line: &[V3], radius: f64) -> (f64, usize) {
    let near = |p: &V3| line.windows(2).any(|w| distance(p, &w[0], &w[1]) < radius);
    let faces: Vec<usize> =
        (0..f.faces.len()).filter(|&k| f.faces[k].iter().any(|&c| near(&f.pos[c]))).collect();
    let c1: Vec<([V3; 2], V3)> = highlight(f, &f.u, &faces)
        .into_iter()
        .map(|(k, s)| {
            let p = f.faces[k].map(|c| f.pos[c]);
            (s, (p[1] - p[0]).cross(&(p[2] - p[0])).normalize())
        })
        .collect();
    let total: f64 = line.windows(2).map(|w| (w[1] - w[0]).norm()).sum();
    let spacing = 0.01 * radius;
    let samples: Vec<V3> = (0..)
        .map(|k| (k as f64 + 0.5) * spacing)
        .take_while(|&s| s <= total)
        .filter(|&s| s >= radius && s <= total - radius)
        .map(|s| {
            let mut at = 0.0;
            for w in line.windows(2) {
                let len = (w[1] - w[0]).norm();
                if at + len >= s && len > 0.0 {
                    return w[0] + (w[1] - w[0]) * ((s - at) / len);
                }
                at += len;
            }
            line[line.len() - 1]
        })
        .collect();
    let in_plane = |p: &V3, (s, n): &([V3; 2], V3)| {
        let q = p - n * (p - s[0]).dot(n);
        distance(&q, &s[0], &s[1])
    };
    let within =
        samples.iter().filter(|p| c1.iter().any(|c| in_plane(p, c) <= TOLERANCE * radius)).count();
    (within as f64 / samples.len().max(1) as f64, samples.len())
}

fn scene(d: &Path, edits: &str, out: &str) -> PathBuf {
    let s = format!(
        r#"{{
  "units": "mm",
  "mesh": "scan.obj",
  "field": {{"init": "world", "world": [0, 0, 1], "symmetry": "line", "output": "{out}"}},
  "lights": [{{"type": "directional", "direction": {LIGHT:?}, "key": true}}],
  "view": {{"eye": {EYE:?}, "target": [0, 0, 0]}},
  "edits": {edits}
}}"#
    );
    let p = d.join(format!("{out}.scene.json"));
    std::fs::write(&p, s).unwrap();
    p
}

/// Runs the scene with `edits`; the report's first fidelity entry and FIELD.json.
fn run(d: &Path, name: &str, edits: &str) -> (serde_json::Value, Field) {
    let out = format!("{name}.json");
    let rep = d.join(format!("{name}.report.json"));
    let sc = scene(d, edits, &out);
    ok(&grainline(&["--quiet", "run", sc.to_str().unwrap(), "--report", rep.to_str().unwrap()]));
    let report = read_json(&rep);
    assert!(report["noise"]["fit_radius"].is_number(), "the scan is noisy: {}", report["noise"]);
    (report["optimize"]["fidelity"][0].clone(), read_field(&d.join(out)))
}

/// The midpoint of the initial key highlight's segment nearest `near`.
fn on_c0(f: &Field, near: &V3) -> V3 {
    let all: Vec<usize> = (0..f.faces.len()).collect();
    highlight(f, &f.u, &all)
        .iter()
        .map(|(_, s)| (s[0] + s[1]) / 2.0)
        .min_by(|a, b| (a - near).norm().total_cmp(&(b - near).norm()))
        .unwrap()
}

fn compare(tool: &str, fid: &serde_json::Value, (outside, samples): (f64, usize)) {
    let within = fid["within"].as_f64().unwrap();
    eprintln!(
        "{tool}: report {within:.3} ({} samples), outside {outside:.3} ({samples})",
        fid["samples"]
    );
    assert!(samples > 100, "{tool}: {samples} samples");
    assert!((within - outside).abs() <= 0.05, "{tool}: report {within}, outside {outside}: {fid}");
}

#[test]
fn the_report_agrees_with_a_measure_from_field_json_on_a_noisy_scan() {
    let d = scratch_dir("fidelity-outside", "ellipsoid");
    std::fs::write(d.join("scan.obj"), noisy_ellipsoid_obj()).unwrap();
    ok(&grainline(&["--quiet", "run", scene(&d, "[]", "initial.json").to_str().unwrap()]));
    let initial = read_field(&d.join("initial.json"));
    let diag = 2.0 * V3::from(AXES).norm();
    // Bend and expand: centred on the key highlight (about the equator of the front, seen and
    // lit from −y), pushing across it (+z).
    for (tool, share, azimuth) in [("bend", 0.06, -0.5), ("expand", 0.07, 0.5)] {
        let c = on_c0(&initial, &on_ellipsoid(azimuth, 0.0));
        let radius = share * diag;
        let edits = format!(
            r#"[{{"tool": "{tool}", "centre": {{"point": [{}, {}, {}]}}, "radius": {radius},
                 "strength": {STRENGTH}, "direction": [0, 0, 1]}}]"#,
            c.x, c.y, c.z
        );
        let (fid, field) = run(&d, tool, &edits);
        compare(tool, &fid, outside_warp(&field, tool, &c, radius, &V3::z()));
    }
    // The S-curve: from the highlight up, across it and down to it again.
    let radius = 0.02 * diag;
    let line: Vec<V3> = (0..=60)
        .map(|k| k as f64 / 60.0)
        .map(|t| on_ellipsoid(-0.6 + 0.8 * t, 0.12 * (std::f64::consts::TAU * t).sin()))
        .collect();
    let points: Vec<String> = line.iter().map(|p| format!("[{}, {}, {}]", p.x, p.y, p.z)).collect();
    let edits = format!(
        r#"[{{"tool": "curve", "points": [[{}]], "radius": {radius}}}]"#,
        points.join(", ")
    );
    let (fid, field) = run(&d, "curve", &edits);
    compare("curve", &fid, outside_curve(&field, &line, radius));
    std::fs::remove_dir_all(&d).ok();
}
