//! A drawn curve across a grain that turns along it (docs/math.md §9, "curve"): the hard case
//! of the curve tool's ring.
//!
//! The part is the flat sheet z = 0 (80 × 60 mm), lit by a directional light and seen by a near
//! eye, so the half vector h varies over it and is known in closed form. The grain before the
//! edit turns along y, at the angle α(y) = πy/30 + 0.3 from x̂ (a line field, half a turn every
//! 30 mm, without singularity): along a straight curve drawn at x = −10 from y = −25 to 25 it
//! turns by 300°, crossing its own highlights (u ⟂ h̄) and the lines u ∥ h̄ again and again. On
//! one side of each such crossing the grain lies on the other side of h̄ than any highlight
//! profile along the curve can have, so the grain must turn through u ∥ h̄ between the tube's
//! core and its edge; a blend of the position target ĝ never asks for that, and on the
//! corpus's teapot and rocker-arm it left singular pairs there (docs/benchmarks.md, sessions
//! 10–12).
//!
//! Truth from outside the code: the test computes g = hᵀu itself (h from the light and the eye),
//! extracts the solved highlight {g = 0} per triangle (corners aligned to the first), measures
//! the distance of the drawn curve to it, and counts singular triangles with the global angle of
//! the grain (the sheet is flat: no transport). The grain before the edit is the formula above.

use std::path::PathBuf;

use grainline::pipeline::optimize::optimize_stage;
use grainline::pipeline::{prepare, Silent, Stages};
use grainline::scene::LoadedScene;
use nalgebra::{Vector2, Vector3};

const EYE: [f64; 3] = [5.0, -60.0, 110.0];
const LIGHT: [f64; 3] = [0.0, -0.35, 1.0];
const RADIUS: f64 = 2.0;
const CURVE_X: f64 = -10.0;
const CURVE_Y: f64 = 25.0;

/// The grain's angle before the edit.
fn alpha(y: f64) -> f64 {
    std::f64::consts::PI * y / 30.0 + 0.3
}

fn dir() -> PathBuf {
    let d = std::env::temp_dir().join(format!("grainline-curve-ring-{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&d);
    std::fs::create_dir_all(&d).unwrap();
    d
}

/// The sheet as a grid of 1 mm cells, and the grain before the edit at its vertices.
fn sheet(d: &std::path::Path) -> PathBuf {
    let (nx, ny) = (80, 60);
    let mut obj = String::new();
    let mut u = Vec::new();
    for j in 0..=ny {
        for i in 0..=nx {
            let (x, y) = (-40.0 + i as f64, -30.0 + j as f64);
            obj += &format!("v {x} {y} 0\n");
            u.push([alpha(y).cos(), alpha(y).sin(), 0.0]);
        }
    }
    for j in 0..ny {
        for i in 0..nx {
            let a = j * (nx + 1) + i + 1;
            let (b, c, e) = (a + 1, a + nx + 2, a + nx + 1);
            obj += &format!("f {a} {b} {c}\nf {a} {c} {e}\n");
        }
    }
    std::fs::write(d.join("sheet.obj"), obj).unwrap();
    std::fs::write(d.join("before.json"), serde_json::json!({ "u": u }).to_string()).unwrap();
    let points: Vec<[f64; 3]> =
        (0..=50).map(|k| [CURVE_X, -CURVE_Y + k as f64 * 2.0 * CURVE_Y / 50.0, 0.0]).collect();
    let scene = serde_json::json!({
        "units": "mm",
        "mesh": { "path": "sheet.obj" },
        "field": { "init": "directions", "directions": "before.json", "symmetry": "line" },
        "lights": [{ "type": "directional", "direction": LIGHT, "key": true }],
        "view": { "eye": EYE, "target": [0, 0, 0] },
        "edits": [{ "tool": "curve", "points": [points], "radius": RADIUS }],
    });
    let p = d.join("scene.json");
    std::fs::write(&p, serde_json::to_string_pretty(&scene).unwrap()).unwrap();
    p
}

/// h̄ at a point of the sheet (its tangent part: the sheet's normal is ẑ).
fn h_bar(p: &Vector3<f64>) -> Vector2<f64> {
    let l = Vector3::from(LIGHT).normalize();
    let v = (Vector3::from(EYE) - p).normalize();
    let h = (l + v).normalize();
    Vector2::new(h.x, h.y)
}

/// The zero set of g = h̄ᵀu over the faces: one segment per face whose aligned corners change
/// sign.
fn highlight(
    pos: &[Vector3<f64>],
    u: &[Vector2<f64>],
    faces: &[[u32; 3]],
) -> Vec<[Vector2<f64>; 2]> {
    let mut out = Vec::new();
    for f in faces {
        let c = f.map(|v| v as usize);
        let a = u[c[0]];
        let g: Vec<f64> = c
            .iter()
            .map(|&v| {
                let w = if u[v].dot(&a) < 0.0 { -u[v] } else { u[v] };
                h_bar(&pos[v]).dot(&w)
            })
            .collect();
        let mut ends = Vec::new();
        for e in 0..3 {
            let (i, j) = (e, (e + 1) % 3);
            if (g[i] >= 0.0) != (g[j] >= 0.0) {
                let t = g[i] / (g[i] - g[j]);
                let p = pos[c[i]] + (pos[c[j]] - pos[c[i]]) * t;
                ends.push(Vector2::new(p.x, p.y));
            }
        }
        if ends.len() == 2 {
            out.push([ends[0], ends[1]]);
        }
    }
    out
}

fn distance_to_segment(p: &Vector2<f64>, s: &[Vector2<f64>; 2]) -> f64 {
    let e = s[1] - s[0];
    let t = if e.norm_squared() > 0.0 {
        ((p - s[0]).dot(&e) / e.norm_squared()).clamp(0.0, 1.0)
    } else {
        0.0
    };
    (s[0] + e * t - p).norm()
}

/// Faces whose line-field index is not 0: the sum over the edges of the angle change wrapped
/// to (−π/2, π/2] is a non-zero multiple of π.
fn singular(angles: &[f64], faces: &[[u32; 3]]) -> Vec<usize> {
    let pi = std::f64::consts::PI;
    let wrap = |x: f64| x - pi * (x / pi).round();
    faces
        .iter()
        .enumerate()
        .filter(|(_, f)| {
            let s: f64 =
                (0..3).map(|e| wrap(angles[f[(e + 1) % 3] as usize] - angles[f[e] as usize])).sum();
            (s / pi).round() != 0.0
        })
        .map(|(k, _)| k)
        .collect()
}

#[test]
fn a_curve_across_a_turning_grain_lands_without_singular_triangles() {
    let d = dir();
    let scene = LoadedScene::read(&sheet(&d)).expect("scene");
    let p = prepare(&scene, &mut Stages::new(&Silent)).expect("prepare");
    let o = optimize_stage(&scene, &p, &mut Stages::new(&Silent)).expect("optimize");
    let (mesh, g) = (&p.mesh, &p.field.geometry);
    let pos = &mesh.positions;
    let faces = &mesh.faces;
    assert!(pos.iter().all(|q| q.z == 0.0), "the refined sheet left the plane");
    let to2 = |w: &Vector3<f64>| Vector2::new(w.x, w.y);
    let after: Vec<Vector2<f64>> = g.directions_of(&o.phi).iter().map(to2).collect();
    let before: Vec<Vector2<f64>> =
        pos.iter().map(|q| Vector2::new(alpha(q.y).cos(), alpha(q.y).sin())).collect();
    assert!(after
        .iter()
        .all(|w| w.x.is_finite() && w.y.is_finite() && (w.norm() - 1.0).abs() < 1e-9));

    // The case is what it claims: along the curve the grain before the edit crosses its own
    // highlight (ĝ₀ changes sign) and the lines u ∥ h̄ (|ĝ₀| passes 1) several times each.
    let along: Vec<f64> = (0..=500)
        .map(|k| {
            let q = Vector3::new(CURVE_X, -CURVE_Y + k as f64 * 0.1, 0.0);
            let (a, hb) = (alpha(q.y), h_bar(&q));
            (Vector2::new(a.cos(), a.sin()).dot(&hb) / hb.norm()).clamp(-1.0, 1.0).acos()
        })
        .collect();
    let crossings =
        |level: f64| along.windows(2).filter(|w| (w[0] < level) != (w[1] < level)).count();
    let half = std::f64::consts::FRAC_PI_2;
    assert!(
        crossings(half) >= 1,
        "the grain before crosses its highlight {} times",
        crossings(half)
    );
    assert!(crossings(0.3) + crossings(std::f64::consts::PI - 0.3) >= 2, "no turn through u ∥ h̄");

    // The solved key highlight lies on the drawn curve (less one radius at each end).
    let c1 = highlight(pos, &after, faces);
    assert!(!c1.is_empty(), "no highlight after the edit");
    let mut dist: Vec<f64> = (0..=400)
        .map(|k| {
            Vector2::new(CURVE_X, -CURVE_Y + RADIUS + k as f64 * (2.0 * (CURVE_Y - RADIUS)) / 400.0)
        })
        .map(|q| {
            c1.iter().map(|s| distance_to_segment(&q, s)).fold(f64::INFINITY, f64::min) / RADIUS
        })
        .collect();
    dist.sort_by(f64::total_cmp);
    let within = dist.iter().filter(|x| **x <= 0.05).count() as f64 / dist.len() as f64;
    let p95 = dist[(0.95 * (dist.len() - 1) as f64).round() as usize];
    assert!(within >= 0.9 && p95 <= 0.1, "within {:.1} %, p95 {p95:.3} r", 100.0 * within);

    // No singular triangle inside the tube, before (the formula's grain has none) or after.
    let tube: Vec<usize> = (0..faces.len())
        .filter(|&f| {
            faces[f].iter().all(|&v| {
                let q = pos[v as usize];
                let dy = (q.y.abs() - CURVE_Y).max(0.0);
                (q.x - CURVE_X).hypot(dy) < RADIUS
            })
        })
        .collect();
    assert!(tube.len() > 1000, "{} faces in the tube", tube.len());
    let angles = |w: &[Vector2<f64>]| w.iter().map(|w| w.y.atan2(w.x)).collect::<Vec<f64>>();
    let inside = |s: Vec<usize>| s.into_iter().filter(|f| tube.binary_search(f).is_ok()).count();
    assert_eq!(inside(singular(&angles(&before), faces)), 0, "the grain before has a singularity");
    assert_eq!(inside(singular(&angles(&after), faces)), 0, "the edit added singular triangles");
    // None anywhere else either, and the grain outside the tube is the grain before.
    assert_eq!(singular(&angles(&after), faces).len(), 0, "singular triangles outside the tube");
    for (k, q) in pos.iter().enumerate() {
        let dy = (q.y.abs() - CURVE_Y).max(0.0);
        if (q.x - CURVE_X).hypot(dy) > RADIUS + 1.5 {
            assert!(after[k].dot(&before[k]).abs() > 1.0 - 1e-9, "vertex {k} at {q:?} turned");
        }
    }

    // The run report says the same.
    let f = &o.report.fidelity[0];
    assert!(f.landed, "the report says it missed: {f:?}");
    assert_eq!((f.singular_before, f.singular_after), (0, 0));
    let _ = std::fs::remove_dir_all(&d);
}
